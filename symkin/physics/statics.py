"""The `loaded` level's derivation (docs/physics.md): plate end loads from the statics
of the pin linkage, each plate's force compliance added to its circular arc, loops closed exactly.

All sympy, in the symbols the kinematic levels use (theta_a: rigid hinge angles, delta_a: their
compliant corrections, the parameters) and three more families, each a named intermediate:

1. Statics of the rigid pin linkage at the rigid pose, with a torsional spring k_a in every plate
   and the file's dead loads: virtual work over the non-input hinge angles with the loop closure
   as constraint gives A^T μ = Q, where A is the rigid loop Jacobian (the matrix of the
   first-order level) and Q_a = −k_a θ_a + s_a Σ_loads [(X − R_a) × F + M] the generalized forces
   (R_a the pin, s_a the paper orientation, the loads on the links beyond hinge a). The
   multipliers `mu_k` (angular, x, y per loop) are the moment and force the loop's chord
   transmits: the pin force on i+(c) is −μ, on i−(c) +μ. The spring is EI/l (`mu0_k`, a first
   pass) and then EI/l·rotation(p) with the axial load index p = N l²/EI of that first pass
   (`mu_k`): a plate in tension takes more moment to bend (symkin.physics.beamcolumn).
2. Hinge forces n_a (what link M exerts on the plate at its M end, frame axes): a chord's from its
   μ, a tree hinge's from the balance of the links beyond it (the loads and chord forces on them).
3. Per plate the components (N, V) of n_a along and across its mid-direction R(θ_a/2)u (in P's
   plate frame), p = N l²/EI, f = V l²/EI, and its end displacement beyond the circular arc, the
   named `compliance_x_a`, `compliance_y_a` = R(θ_a/2)·(−l [θ_a² (bending(p) − 1/24)
   + f² bowing(p)], l f shear(p)) in P's plate frame: the beam-column (linear beam theory with
   the axial force kept, series in p) in the plate's mid-frame, where by symmetry θ moves M's
   clamp only along the chord and V only across it. At p → 0 this is the first-order correction
   R(θ/2)·(0, V l³/(12 EI)). Then the loops are closed exactly by the `exact` level's Newton on δ,
   the compliance held at its rigid-pose value.

The plates are inextensible, as at the `equilibrium` level; `extensible=True` adds the axial
stretch N l/EA along the chord (docs/physics.md: about (t/l)² of the force correction).
"""

from __future__ import annotations

import dataclasses
import weakref
from dataclasses import dataclass
from functools import cached_property

import sympy as sp

from ..core import vectors as V
from ..graph.structure import Structure
from ..kinematics.analysis import Analysis
from ..model.hinges import plate_functions
from .beamcolumn import series
from .stiffness import PlateStiffness, plate_stiffness


@dataclass(frozen=True)
class PlateLoad:
    """One hinge's loads at the rigid pose: force n (frame axes), its components (N, V) along and
    across the plate's mid-direction, the load indices p = N l²/EI and f = V l²/EI (plates only),
    the compliance symbols and their expressions."""

    label: int
    force: V.Vec
    axial: sp.Expr
    shear: sp.Expr
    p: sp.Expr | None = None
    f: sp.Expr | None = None
    compliance: tuple[sp.Symbol, sp.Symbol] | None = None
    displacement: V.Vec | None = None


class LoadedDerivation:
    """The `loaded` level of a structure: statics, plate loads and the loaded loop closure.

    `beam_column=False` gives the first-order level (springs EI/l, compliance V l³/(12 EI));
    `extensible=True` adds the axial stretch N l/EA."""

    def __init__(
        self, structure: Structure, points=None, beam_column: bool = True, extensible: bool = False
    ) -> None:
        self.structure = structure
        self.mechanism = mech = structure.mechanism
        self.beam_column = beam_column
        self.extensible = extensible
        self.series = series()
        self.stiffness: dict[str, PlateStiffness] = plate_stiffness(mech, "loaded")
        label = {name: a for a, name in enumerate(structure.hinges, start=1)}
        self.compliance = {
            label[h.name]: (
                sp.Symbol(f"compliance_x_{label[h.name]}", real=True),
                sp.Symbol(f"compliance_y_{label[h.name]}", real=True),
            )
            for h in mech.hinges
            if h.is_plate
        }

        def plate(hinge):
            """The physical plate: circular arc (pure moment) plus its force compliance."""
            if not hinge.is_plate:
                return plate_functions(hinge)
            pf = plate_functions(hinge, shape="circular_arc")
            ex, ey = self.compliance[label[hinge.name]]
            return dataclasses.replace(pf, f=pf.f + ex, g=pf.g + ey, df=pf.df + ex, dg=pf.dg + ey)

        #: The loaded closure: the exact level's equations with the plates of `plate`.
        self.analysis = Analysis(structure, points, plate)
        self.kin = self.analysis.kin
        loops = 3 * len(self.kin.chords)
        self.mu = tuple(sp.Symbol(f"mu_{k}", real=True) for k in range(1, loops + 1))
        self.mu0 = (
            tuple(sp.Symbol(f"mu0_{k}", real=True) for k in range(1, loops + 1))
            if beam_column
            else ()
        )
        # The closure's constants (multipliers, compliance) count as parameters of its analysis,
        # so the exact level's evaluation runs on it unchanged.
        self.analysis.params = (
            *self.analysis.params,
            *self.mu0,
            *self.mu,
            *(c for a in sorted(self.compliance) for c in self.compliance[a]),
        )

    # -- 1. statics --------------------------------------------------------------------------------
    def generalized_forces(self, springs: dict[int, sp.Expr]) -> sp.Matrix:
        """Q over the non-input hinge angles: −k_a θ_a plus the loads' moments about the pin."""
        kin, s = self.kin, self.structure
        scale = self.mechanism.unit_scale
        link = {name: i for i, name in enumerate(s.links)}
        rows = []
        for a in kin.unknowns:
            h = kin.hinges[a]
            q = -springs.get(a, 0) * kin.theta[a]
            pivot = kin.rigid_position(h.P, h.centre)
            for load in self.mechanism.loads:
                j = link[load.link]
                if a in s.tree_path(j):
                    arm = V.sub(kin.rigid_position(j, load.at), pivot)
                    q += h.sign * (V.cross(arm, load.force) + load.moment / scale)
            rows.append(q)
        return sp.Matrix(rows)

    def _springs(self, loads: dict[int, PlateLoad] | None) -> dict[int, sp.Expr]:
        """k_a = EI/l, times rotation(p) of the given first-pass loads."""
        out = {}
        for a, h in self.kin.hinges.items():
            stiff = self.stiffness.get(h.name)
            if stiff is not None:
                factor = 1 if loads is None else self.series.value("rotation", loads[a].p)
                out[a] = stiff.EI / stiff.length * factor
        return out

    @cached_property
    def first_statics(self) -> tuple[sp.Matrix, sp.Matrix]:
        """(A^T, Q) with springs EI/l, solved for `mu0` (the beam-column's first pass)."""
        a_matrix, _ = self.analysis.linear_system
        return a_matrix.T, self.generalized_forces(self._springs(None))

    @cached_property
    def statics(self) -> tuple[sp.Matrix, sp.Matrix]:
        """(A^T, Q) solved for `mu`: springs EI/l·rotation(p) with p from `mu0` (beam-column),
        or EI/l (first order). A is the rigid loop Jacobian of the first-order level."""
        if not self.beam_column:
            return self.first_statics
        first = self._loads(self.mu0)
        return self.first_statics[0], self.generalized_forces(self._springs(first))

    # -- 2. hinge forces ---------------------------------------------------------------------------
    def _loads(self, mu: tuple[sp.Symbol, ...]) -> dict[int, PlateLoad]:
        """n_a, (N, V) and p, f of every hinge with the multipliers `mu`, at the rigid pose."""
        kin, s = self.kin, self.structure
        link = {name: i for i, name in enumerate(s.links)}

        def chord_force(c: int) -> V.Vec:
            k = 3 * (c - s.n - 1)
            return mu[k + 1], mu[k + 2]

        on_link: dict[int, list[V.Vec]] = {i: [] for i in range(s.n + 1)}
        for load in self.mechanism.loads:
            on_link[link[load.link]].append(load.force)
        for c in kin.chords:
            on_link[s.i_plus[c - 1]].append(V.scale(-1, chord_force(c)))
            on_link[s.i_minus[c - 1]].append(chord_force(c))
        out = {}
        for a, h in kin.hinges.items():
            if a in kin.chords:
                force = V.scale(-h.sign, chord_force(a))
            else:
                beyond = [i for i in range(1, s.n + 1) if a in s.tree_path(i)]
                force = V.scale(h.sign, V.add(*(f for i in beyond for f in on_link[i])))
            mid = V.unit(kin.phi(h.P) + h.angle + kin.theta[a] / 2)
            axial, shear = V.dot(force, mid), V.dot(force, V.perp(mid))
            stiff = self.stiffness.get(h.name)
            if stiff is None:
                out[a] = PlateLoad(a, force, axial, shear)
            else:
                index = stiff.length**2 / stiff.EI
                out[a] = PlateLoad(a, force, axial, shear, axial * index, shear * index)
        return out

    @cached_property
    def plate_loads(self) -> dict[int, PlateLoad]:
        """The loads with `mu`, and each plate's displacement beyond its arc (the compliance)."""
        out = {}
        bc = self.series
        for a, load in self._loads(self.mu).items():
            comp = self.compliance.get(a)
            if comp is None:
                out[a] = load
                continue
            stiff = self.stiffness[self.kin.hinges[a].name]
            l, theta = stiff.length, self.kin.theta[a]
            if self.beam_column:
                along = -l * (
                    theta**2 * bc.value("bending", load.p, first=1)
                    + load.f**2 * bc.value("bowing", load.p)
                )
                across = l * load.f * bc.value("shear", load.p)
            else:
                along, across = sp.Integer(0), l * load.f / 12
            if self.extensible:
                along += load.axial * l / stiff.EA
            out[a] = dataclasses.replace(
                load, compliance=comp, displacement=V.rot(theta / 2, (along, across))
            )
        return out

    # -- results -----------------------------------------------------------------------------------
    def _compliant_angle(self, a: int) -> sp.Expr:
        kin = self.kin
        return kin.theta[a] + (kin.delta[a] if a in kin.unknowns else 0)

    def end_moment(self, a: int) -> sp.Expr:
        """Moment link M exerts on the plate at its M end (N·u): EI/l (θ rotation(p)
        − f coupling(p)) at the compliant angle θ (first order: EI θ/l − V l/2)."""
        stiff = self.stiffness.get(self.kin.hinges[a].name)
        if stiff is None:
            return sp.Integer(0)
        load, theta = self.plate_loads[a], self._compliant_angle(a)
        if not self.beam_column:
            return stiff.EI * theta / stiff.length - load.shear * stiff.length / 2
        bc = self.series
        return (
            stiff.EI
            / stiff.length
            * (theta * bc.value("rotation", load.p) - load.f * bc.value("coupling", load.p))
        )

    def energy(self, a: int) -> sp.Expr:
        """Elastic energy of plate a (N·u): EI/l (θ² strain_bending(p) + f² strain_shear(p)),
        plus N² l/(2 EA) when extensible (first order: EI θ²/(2l) + V² l³/(24 EI))."""
        stiff = self.stiffness.get(self.kin.hinges[a].name)
        if stiff is None:
            return sp.Integer(0)
        load, theta = self.plate_loads[a], self._compliant_angle(a)
        p = load.p if self.beam_column else sp.Integer(0)
        bc = self.series
        out = (
            stiff.EI
            / stiff.length
            * (theta**2 * bc.value("strain_bending", p) + load.f**2 * bc.value("strain_shear", p))
        )
        if self.extensible:
            out += load.axial**2 * stiff.length / (2 * stiff.EA)
        return out


_DERIVATIONS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def loaded_derivation(
    analysis: Analysis, beam_column: bool = True, extensible: bool = False
) -> LoadedDerivation:
    """The LoadedDerivation of an analysis's structure and points, derived once per analysis
    and options (the mpmath evaluation and the plan of the generated code share it)."""
    cache = _DERIVATIONS.setdefault(analysis, {})
    key = (beam_column, extensible)
    if key not in cache:
        cache[key] = LoadedDerivation(
            analysis.structure, [p.name for p in analysis.points], beam_column, extensible
        )
    return cache[key]
