"""What a report restates: the derivation of one mechanism as neutral data (sympy expressions,
labels and names), taken from an :class:`~symkin.kinematics.analysis.Analysis` once.

The LaTeX report prints these pieces and derives nothing itself: the structure matrices, the
plate data and Δz of every hinge, J, J* and the positions (4.7), the hinge models' formulas, the
loop equations (5.1)/(5.3) with the signed hinges of each loop, the dyads, the first-order system
A δ = −Φ Δz, and for every point its path, whether the loops move it, its rigid position, its
paper-level deviation (4.8) and the link turns the other levels add; with the `loaded` level,
the plates' stiffness and the reduced equilibrium's unknowns, rows, hinge forces and plate
frames (docs/physics.md, "`loaded`: Newton on the reduced equilibrium").
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import sympy as sp

from ..core import vectors as V
from ..core.vectors import Vec
from ..graph.structure import Structure
from ..kinematics.analysis import Analysis
from ..kinematics.dyads import RigidSolution
from ..kinematics.loop_equations import LoopEquations, loop_equations
from ..kinematics.positions import HingeGeometry, paper_matrices, paper_positions
from ..model import hinges as hinge_models
from ..model import special
from ..model.entries import Load
from ..model.hinges import PLATE_LENGTH, PRBM_PRESETS, THETA
from ..physics.stiffness import PlateStiffness, plate_stiffness


@dataclass(frozen=True, eq=False)
class PointStatement:
    """One characteristic point: where it sits and how each level moves it."""

    name: str
    link: int  # label of its link
    at: Vec  # as-fabricated position
    path: tuple[int, ...]  # hinge labels of the direct path [s_0, s_link]
    moved: bool  # a hinge on the path is not an input: the loops move it
    rigid: Vec  # rigid position Σ Rot(φ_i) W_i
    paper: Vec  # ΔR at level paper (4.8)
    turns: tuple[tuple[int, Vec, sp.Expr, sp.Expr], ...]  # (link i, W_i, δφ_i, φ_i), δφ_i ≠ 0


@dataclass(frozen=True, eq=False)
class LoopStatement:
    """The fundamental loop of one chord."""

    chord: int
    hinges: tuple[int, ...]  # labels of the loop's hinges
    links: tuple[int, ...]  # labels of the links it passes
    signs: tuple[tuple[int, int], ...]  # (b, Φ_cb) for the loop's hinges: Φ_c Δz = Σ Φ_cb Δz_b
    weights: dict[int, Vec]  # V^c_i: the rigid part of (5.3) is Σ Rot(φ_i) V^c_i
    equations: LoopEquations  # (5.1), the scalar pair, squared and solved forms


@dataclass(frozen=True, eq=False)
class ModelStatement:
    """A hinge model as the report states it, with the hinges that use it."""

    model: str
    description: str
    hinges: tuple[int, ...]
    generic: tuple[sp.Expr, sp.Expr, sp.Expr, sp.Expr] | None  # f, g, Δf, Δg over l (γ, c_θ)
    elementary: dict[str, sp.Expr]  # "f", "g": the same without kernels, where that exists
    prbm: tuple[tuple[int, sp.Expr, sp.Expr], ...]  # (hinge, γ, c_θ) of prbm hinges
    kernels: tuple[type, ...]  # the stable kernels its formulas use


@dataclass(frozen=True, eq=False)
class LoadedStatement:
    """The `loaded` level's reduced equilibrium (docs/physics.md) as the report states it: its
    unknowns and rows, each hinge's end force in the chord loads and each plate's mid-frame."""

    plates: tuple[tuple[int, PlateStiffness], ...]  # (hinge label, its plate's EI, EA, κGA, l)
    loads: tuple[Load, ...]
    chord_loads: dict[int, tuple[sp.Symbol, sp.Symbol, sp.Symbol]]  # chord c: n_cx, n_cy, μ_c
    balanced: tuple[int, ...]  # the non-input tree hinges: a moment balance row each
    related: tuple[int, ...]  # the non-input chords: a moment relation row each
    forces: tuple[tuple[int, Vec], ...]  # (a, n_a): link M's force on hinge a, in the n_c
    frames: tuple[tuple[int, sp.Expr], ...]  # (a, β_a): every plate's mid-frame angle
    offset: bool  # a rigid pin sits off its plate's midpoint (pin = "prbm")


@dataclass(frozen=True, eq=False)
class Derivation:
    """The symbolic derivation of one mechanism, for the points and levels of a plan."""

    structure: Structure
    theta: dict[int, sp.Symbol]  # θ_a by hinge label
    delta: dict[int, sp.Symbol]  # δ_a by hinge label
    deltas: tuple[sp.Symbol, ...]  # the unknown δ, in the order of the linear system
    variable: sp.Symbol  # θ of the hinge models' f(θ), g(θ)
    inputs: tuple[int, ...]  # input hinge labels
    unknowns: tuple[int, ...]  # non-input hinge labels
    hinges: dict[int, HingeGeometry]
    plates: dict[int, dict[str, sp.Expr]]  # c_{i±a}, α±, q*, l of every hinge
    phi: tuple[sp.Expr, ...]  # φ_i of links 0..n: Σ q_b over the direct path
    delta_phi: tuple[sp.Expr, ...]  # δφ_i of links 0..n: Σ σ_b δ_b over the direct path
    J: sp.Matrix  # (4.3) over abstract c_{i,a}
    Jstar: sp.Matrix  # (4.4) over abstract z_a
    R: sp.Matrix  # (4.7)
    models: tuple[ModelStatement, ...]
    loops: tuple[LoopStatement, ...]
    rigid: RigidSolution
    linear: tuple[sp.Matrix, sp.Matrix] | None  # (A, r) when some point is moved by the loops
    points: tuple[PointStatement, ...]
    loaded: LoadedStatement | None = None


def derivation(
    analysis: Analysis,
    points: Sequence[str],
    moved: frozenset[str],
    loaded: bool = False,
) -> Derivation:
    """The statement of `analysis` for the named points (`moved`: those the loops move), with
    the `loaded` level's reduced equilibrium when `loaded`."""
    an, kin, s = analysis, analysis.kin, analysis.structure
    J, Jstar = paper_matrices(s)
    return Derivation(
        structure=s,
        theta=dict(kin.theta),
        delta=dict(kin.delta),
        deltas=an.deltas,
        variable=THETA,
        inputs=kin.inputs,
        unknowns=kin.unknowns,
        hinges=dict(kin.hinges),
        plates={a: kin.plate_data(a) for a in range(1, s.m + 1)},
        phi=tuple(kin.phi(i) for i in range(s.n + 1)),
        delta_phi=tuple(an.delta_phi(i) for i in range(s.n + 1)),
        J=J,
        Jstar=Jstar,
        R=paper_positions(s),
        models=_models(an),
        loops=_loops(an),
        rigid=an.rigid,
        linear=an.linear_system if an.deltas and moved else None,
        points=tuple(_point(an, name, name in moved) for name in points),
        loaded=_loaded(an) if loaded else None,
    )


def _loaded(an: Analysis) -> LoadedStatement:
    kin, s = an.kin, an.structure
    mech = an.mechanism
    stiffness = plate_stiffness(mech, "loaded")
    chords = tuple(range(s.n + 1, s.m + 1))
    chord_loads = {
        c: (
            sp.Symbol(f"n_{c}x", real=True),
            sp.Symbol(f"n_{c}y", real=True),
            sp.Symbol(f"mu_{c}", real=True),
        )
        for c in chords
    }
    # the forces on every moving link: its loads and the chord plates' reactions (link M of
    # chord c exerts n_c on the plate, so the plate pushes M by -n_c and P by +n_c)
    on_link: dict[int, Vec] = dict.fromkeys(range(s.n + 1), V.ZERO)
    for load in mech.loads:
        i = s.links.index(load.link)
        on_link[i] = V.add(on_link[i], tuple(load.force))
    for c, (nx, ny, _) in chord_loads.items():
        h = kin.hinges[c]
        on_link[h.M] = V.sub(on_link[h.M], (nx, ny))
        on_link[h.P] = V.add(on_link[h.P], (nx, ny))
    forces = []
    for a in range(1, s.m + 1):
        if a in chord_loads:
            forces.append((a, chord_loads[a][:2]))
            continue
        # a tree hinge carries what acts on the links beyond it (pose-independent statics)
        beyond = [i for i in range(1, s.n + 1) if a in s.tree_path(i)]
        total = V.add(*(on_link[i] for i in beyond)) if beyond else V.ZERO
        forces.append((a, V.scale(kin.hinges[a].sign, total)))
    plates = tuple(
        (a, stiffness[h.name]) for a, h in sorted(kin.hinges.items()) if h.name in stiffness
    )
    frames = []
    for a, _ in plates:
        h = kin.hinges[a]
        delta = kin.delta[a] if a in kin.unknowns else sp.S.Zero
        frames.append((a, kin.phi(h.P) + an.delta_phi(h.P) + h.angle + (kin.theta[a] + delta) / 2))
    return LoadedStatement(
        plates=plates,
        loads=tuple(mech.loads),
        chord_loads=chord_loads,
        balanced=tuple(a for a in kin.unknowns if a <= s.n),
        related=tuple(c for c in chords if c in kin.unknowns),
        forces=tuple(forces),
        frames=tuple(frames),
        offset=any(kin.hinges[a].midpoint is not None for a, _ in plates),
    )


def _point(an: Analysis, name: str, moved: bool) -> PointStatement:
    kin = an.kin
    point = an.mechanism.point(name)
    k = an.link[point.link]
    turns = tuple(
        (i, w, an.delta_phi(i), kin.phi(i))
        for i, w in kin.weights(k, point.at).items()
        if an.delta_phi(i) != 0
    )
    return PointStatement(
        name,
        k,
        point.at,
        an.structure.tree_path(k),
        moved,
        an.point_rigid(name),
        an.point_deviation(name, "paper"),
        turns,
    )


def _loops(an: Analysis) -> tuple[LoopStatement, ...]:
    s = an.structure
    out = []
    for eq in loop_equations(an.kin):
        c = eq.chord
        hinges = s.loop_hinges(c)
        row = s.loops[c - s.n - 1]
        links = sorted({s.i_plus[b - 1] for b in hinges} | {s.i_minus[b - 1] for b in hinges})
        out.append(
            LoopStatement(
                c,
                hinges,
                tuple(links),
                tuple((b, int(row[b - 1])) for b in range(1, s.m + 1) if row[b - 1]),
                an.kin.loop_weights(c),
                eq,
            )
        )
    return tuple(out)


def _models(an: Analysis) -> tuple[ModelStatement, ...]:
    kin = an.kin
    used: dict[str, list[int]] = {}
    for a in range(1, an.structure.m + 1):
        used.setdefault(kin.hinges[a].hinge.model, []).append(a)
    out = []
    for model in sorted(used, key=lambda m: min(used[m])):
        hinges = tuple(used[model])
        generic = _generic_functions(model)
        elementary = {}
        if generic is not None:
            exprs = list(generic)
            for key, e in zip(("f", "g"), generic[:2]):
                if _has_kernel(e) and model != "elastica_force":
                    plain = special.expand_special(e)
                    if not _has_kernel(plain) and not plain.has(*special.ELASTICA_FUNCTIONS):
                        elementary[key] = plain
        else:
            exprs = [kin.hinges[a].df for a in hinges] + [kin.hinges[a].dg for a in hinges]
        prbm = ()
        if model == "prbm":
            force = PRBM_PRESETS["force"]
            prbm = tuple(
                (
                    a,
                    sp.sympify(kin.hinges[a].hinge.param("gamma", force["gamma"])),
                    sp.sympify(kin.hinges[a].hinge.param("c_theta", force["c_theta"])),
                )
                for a in hinges
            )
        kernels = sorted(
            {
                type(f)
                for e in exprs
                for f in sp.sympify(e).atoms(sp.Function)
                if isinstance(f, special.StableKernel)
            },
            key=lambda c: c.__name__,
        )
        out.append(
            ModelStatement(
                model,
                hinge_models.MODELS[model].description,
                hinges,
                generic,
                elementary,
                prbm,
                tuple(kernels),
            )
        )
    return tuple(out)


class _Generic:
    """A stand-in hinge with symbolic plate length and model parameters, for the formulas."""

    def __init__(self, model: str, params: dict) -> None:
        self.model = model
        self.name = model
        self.length = PLATE_LENGTH
        self._params = params

    def param(self, key: str, default: object = None) -> object:
        return self._params.get(key, default)


def _generic_functions(model: str) -> tuple | None:
    """f, g, Δf, Δg of a model over a symbolic plate length (and γ, c_θ); None for the models
    whose functions are the hinge's own (table, expr)."""
    if model in ("table", "expr"):
        return None
    params = {}
    if model == "prbm":
        params = {
            "gamma": sp.Symbol("gamma", positive=True),
            "c_theta": sp.Symbol("c_theta", positive=True),
        }
    plate = hinge_models.plate_functions(_Generic(model, params))
    return plate.f, plate.g, plate.df, plate.dg


def _has_kernel(expr: sp.Expr) -> bool:
    return any(special.is_special(f) for f in sp.sympify(expr).atoms(sp.Function))
