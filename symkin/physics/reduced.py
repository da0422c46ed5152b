"""The reduced equilibrium of a compliant mechanism: Newton on the compliant-minus-rigid angles of
the non-input hinges and, per loop, the chord plate's end load (docs/physics.md, "The Newton
level"). The `loaded` level's solver (symkin.studies.physical.loaded runs it in mpmath),
evaluated through sympy's lambdify in float64 (numpy kernels) or mpmath.

Unknowns x (scaled, so every component is O(θ) or O(load/F)): δ_a / (l_min/L) of every
non-input hinge, n_c/F and μ_c/(F L) of every chord c (the force and moment link M exerts on
the chord plate at M's clamp); L the largest distance between hinge centres, l_min the shortest
plate, F = max EI/(l L). Residuals: the `exact` level's loop closure in δ-form, each plate's end
displacement its circular arc plus the plate relation (symkin.physics.plate_relation) under its
current end force, less the rigid pin's own path (a pin = "prbm" pin off the plate's midpoint
adds (l - 2d) sin(θ/2) across the arc's chord, d its distance from M's clamp); the moment
balance, at the current pose, of the links beyond every non-input tree hinge about M's clamp of
its plate; the moment relation of every chord plate that is not an input (an input chord's μ is
its actuator's reaction plus the plate's moment, as an input tree hinge has no balance row). The
forces in tree hinges follow from the loads and the chord forces by statics (pose-independent,
linear).

Two segments (`segments=2`, Ma & Chen's chained beam-constraint model with two links): each
plate is two half plates joined at a section turned by ψ = θ/2 + η, η one more unknown per plate
(after the chords'), each half with the plate relation under the plate's force, and one more
residual per plate, the joint's moment balance. The halves see a quarter of the plate's load
index: where the plate comes near its buckling load, one relation's truncation is too coarse.

Solve: Newton from x = 0 at load factor 1; where a step would turn a hinge by more than 0.2 rad,
or the Jacobian's determinant changes sign, continuation along the inputs and loads scaled
together from the as-fabricated pose. Refusal (the answer is not given): a plate's compression
at 90 % of its sway buckling load, or the truncation estimate 3 e24² above 1 % (e24: the
largest relative change of a point's deviation when the quartic terms are dropped, relative to
the point's deviation but at least a tenth of the largest one and 1e-13 L, by one Newton
step with the Jacobian of the last step that converged, a step below tol from the solution; its
determinant's sign is also the acceptance's: the generated drivers keep its LU and evaluate
nothing more at the solution).
"""

from __future__ import annotations

import copy
import math
import threading
from collections.abc import Callable, Mapping
from contextlib import suppress
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
import sympy as sp

from ..core import vectors as V
from ..core.settings import EPS64, SOLVER
from ..kinematics.positions import Kinematics
from ..model.derivatives import jacobian
from ..model.expressions import substitute
from ..model.lambdified import NO_DOCSTRING, lambdify
from ..model.sections import RelationTerms
from ..model.special import arck, mpmath_namespace, sinr
from .plate_relation import energy, notch_energy, notch_relation, relation
from .reduced_rates import _red_implicit, _red_inputs_x, _red_relation
from .reduced_solver import _red_equilibrium, _red_sway, _red_verdict
from .stiffness import plate_stiffness

#: The level's Newton, continuation and refusals (docs/numerics.md, "The solver table"): the
#: generated drivers' too; the shared solver takes them at float64's ε (System).
RULES = SOLVER.loaded
#: How a refusal by the estimate begins (the caller may chain two half plates then).
TRUNCATION = "truncation estimate"


@dataclass
class Answer:
    """The solution at one configuration, or why there is none (`refused` names the rule)."""

    deviations: dict[str, tuple[float, float]]
    x: np.ndarray
    iterations: int
    steps: int  # continuation steps (1: plain Newton)
    estimate: float  # est_factor e24²
    p_over_pcr: float  # the worst plate's compression over its sway buckling load
    refused: str = ""
    segments: int = 1  # half plates chained per plate (2: one plate relation was not enough)
    # by hinge name: the force (frame axes, N) and the moment (about M's clamp, CCW, N·u, u the
    # file's length unit) link M exerts on the plate (a pin: on the pin) at its M end
    hinge_loads: dict[str, tuple[float, float, float]] = field(default_factory=dict)
    energy: float = math.nan  # the plates' elastic energy, N·u (the plate relation's)
    # by hinge name: compliant minus rigid hinge angle (rad; zero on the inputs)
    angle_deviations: dict[str, float] = field(default_factory=dict)
    # the rigid hinge angles (by label) it was solved at, and the solver (for what `loaded`
    # reports beyond the deviations, symkin.physics.reduced_reported)
    theta: dict[int, float] = field(default_factory=dict)
    solver: Reduced | None = field(default=None, repr=False, compare=False)
    # by actuator name: the stroke the rigid reference is at (file unit; set by the caller)
    strokes: dict[str, float] = field(default_factory=dict)
    # why the reference stayed short of the stroke a force actuator produced, which no pose of
    # the rigid linkage reaches (docs/physics.md, "Beyond the rigid reach"; set by the caller)
    unreached: str = ""


#: The plate functions of symkin.physics.plate_relation, lambdified, by (key, lambdify's module
#: names): Reduced._plate_fn.
_PLATE_FNS: dict[tuple, Callable] = {}
_PLATE_LOCK = threading.Lock()


class Reduced:
    """The reduced equilibrium of one mechanism at fixed parameter values, as sympy expressions
    of the unknowns x, the rigid hinge angles and the load factor, lambdified on demand."""

    def __init__(
        self,
        kin: Kinematics,
        values: Mapping[sp.Symbol, sp.Expr],
        modules: list | Callable[[], list] | None = None,
        segments: int = 1,
        symbolic: bool = False,
    ) -> None:
        """`values`: the file's parameters; `modules`: lambdify's (default mpmath with symkin's
        special functions; the numpy backend's float64 namespace gives float code; a callable is
        called after each derivation); `segments`: 1, or 2 to chain two half plates per plate
        (their joint's rotation an unknown, docs/physics.md) where one is not accurate enough.
        `symbolic`: the expressions keep the file's parameters as symbols (generated code reads
        them at run time, symkin.codegen.loaded); the scales L, l_min and F, which only
        condition Newton, stay numbers at `values`."""
        if segments not in (1, 2):
            raise ValueError("segments must be 1 or 2")
        self.segments = segments
        self.kin = kin
        st = kin.structure
        mech = kin.mechanism
        # the namespace is taken after each derivation: the kernels it creates are in it
        self.modules = modules or (lambda: [mpmath_namespace(), "mpmath"])
        self._values_subs = dict(values)

        value = self.value

        def num(e) -> sp.Expr:
            return sp.sympify(e) if symbolic else value(e)

        self.symbolic = symbolic

        # a notch's plate: EI₀ = l/∫dx/EI, EA and κGA of the same end compliances, and its
        # relation's terms (model.sections.RelationTerms): numbers, in generated code too
        stiff = plate_stiffness(mech, "loaded", notches=True)
        self.n, self.m = st.n, st.m
        self.hinges = kin.hinges
        self.paths = {i: st.tree_path(i) for i in range(st.n + 1)}
        self.unknowns = list(kin.unknowns)  # the actuators' surrogates are appended below
        self.chords = list(range(st.n + 1, st.m + 1))
        self.beyond = {a: [i for i in range(1, st.n + 1) if a in self.paths[i]] for a in self.paths}
        # numbers of every hinge
        self.plate = {}
        centres = {}
        for a, h in self.hinges.items():
            centres[a] = tuple(num(v) for v in h.centre)
            if h.hinge.is_plate:
                # l - 2d, d the rigid pin's distance from M's clamp: nonzero where pin = "prbm"
                # puts it off the midpoint, from whose pin the relation's arc is measured
                offset = sp.S.Zero
                if h.midpoint is not None:
                    offset = num(2 * V.dot(V.sub(h.centre, h.midpoint), h.u))
                s = stiff[h.name]
                terms = s.section.relation_terms(self._values_subs)
                if terms is None:
                    EI, EA, kGA = num(s.EI), num(s.EA), num(s.kGA)
                else:  # the section's integrals by quadrature, the correction in them
                    c = s.section.compliance_numbers(self._values_subs)
                    EI, EA, kGA = (value(s.length / v) for v in (c.theta_M, c.x_N, c.y_V))
                length = num(h.length)
                reissner = s.stretches
                self.plate[a] = {
                    "EI": EI,
                    "l": length,
                    "ea": EI / (EA * length**2) if reissner else sp.S.Zero,
                    "es": EI / (kGA * length**2) if reissner else sp.S.Zero,
                    "alpha": num(h.angle),
                    "offset": offset,
                    "terms": terms,
                }
        self.centres = centres
        label = {name: i for i, name in enumerate(st.links)}
        scale = mech.unit_scale
        self.loads = [
            (
                label[ld.link],
                tuple(num(v) for v in ld.at),
                tuple(num(v) for v in ld.force),
                num(ld.moment / scale),
            )
            for ld in mech.loads
        ]
        self.points = {p.name: (label[p.link], tuple(num(v) for v in p.at)) for p in mech.points}
        # the actuators (docs/physics.md, "Actuators at loaded"): a stroke is one
        # more unknown, its force along d at its point, and one more row, its point's deviation
        # along d zero (the rigid reference meets the stroke); a force is a dead load t F d,
        # F an argument after the rigid angles. Their surrogate hinges are not held.
        hinge_label = {h.name: a for a, h in self.hinges.items()}
        self.acts = [
            (
                act.name,
                label[act.link],
                tuple(num(v) for v in act.at),
                tuple(num(v) for v in act.direction),
                act.drive,
            )
            for act in mech.actuators
        ]
        # a stroke's series spring k (N per file unit; None: ideal): its row then reads
        # d·ΔX(a) = −f/k, the compliant point short of the commanded stroke by f/k
        self.springs = [None if act.spring is None else num(act.spring) for act in mech.actuators]
        # (a structure's force actuators have none: docs/levels.md, "Structures")
        surrogates = {hinge_label[act.surrogate] for act in mech.actuators if act.surrogate}
        self.strokes = [k for k, act in enumerate(self.acts) if act[4] == "stroke"]
        self.forces = [act[0] for act in self.acts if act[4] == "force"]
        self.fa = [sp.Symbol(f"fa_{k}", real=True) for k in range(len(self.forces))]
        # a structure's strokes (docs/levels.md, "Structures"): its rigid reference stays as
        # fabricated, so the row holds the point's deviation along d at the commanded stroke,
        # an argument after the forces (the continuation scales it with the inputs)
        self.placed = [act[0] for act in self.acts if act[4] == "stroke" and mech.is_structure]
        self.sa = [sp.Symbol(f"sa_{k}", real=True) for k in range(len(self.placed))]
        self.clamp_m = {}
        for a, h in self.hinges.items():
            self.clamp_m[a] = tuple(num(v) for v in h.clamp(h.M)) if a in self.plate else centres[a]
        cs = [tuple(float(value(v)) for v in c) for c in centres.values()]
        # a lone hinge (a cantilever) has no spacing: its plate's length sets the scale (1e-300
        # scaled its surrogate's turn by 5e300, past float64 in the generated code)
        self.L = max([math.dist(a, b) for a in cs for b in cs], default=0.0) or max(
            [float(value(d["l"])) for d in self.plate.values()] + [1e-300]
        )
        self.lmin = min([float(value(d["l"])) for d in self.plate.values()], default=self.L)
        self.F = max(
            [float(value(d["EI"] / (d["l"] * self.L))) for d in self.plate.values()] or [1.0]
        )
        self.unknowns += sorted(surrogates)
        nu = len(self.unknowns)
        # per plate and segment: (hinge, segment, EI, length, ε_a, ε_s) of the half plates
        self.segs = [
            (a, j, d["EI"], d["l"] / segments, d["ea"] * segments**2, d["es"] * segments**2)
            for a, d in sorted(self.plate.items())
            for j in range(segments)
        ]
        # each segment's relation terms (None: the uniform plate's relation)
        self.terms = [self.plate[a]["terms"] for a, *_ in self.segs]
        self.notched = any(t is not None for t in self.terms)
        if self.notched and segments == 2:
            raise ValueError("a notch is not chained from two half plates (its halves differ)")
        joints = len(self.plate) if segments == 2 else 0
        self.size = nu + 3 * len(self.chords) + len(self.strokes) + joints
        self.scale = np.concatenate(
            [
                np.full(nu, self.lmin / self.L),
                np.tile([self.F, self.F, self.F * self.L], len(self.chords)),
                np.full(len(self.strokes), self.F),  # the stroke actuators' forces, N
                np.ones(joints),  # η: the joint's rotation beyond half the plate's, rad
            ]
        )
        self.x = sp.symbols(f"x_0:{self.size}", real=True)
        self.th = {a: sp.Symbol(f"th_{a}", real=True) for a in self.hinges}
        self.t = sp.Symbol("t", real=True)
        # the reported quantities' parameters (symkin.physics.reduced_reported), zero at the
        # solution: each input hinge's compliant angle beyond its rigid one, and a virtual load
        # (F_x, F_y, M; N and N·u) at every point
        # and each actuator's value beyond the given one (a stroke, a force)
        self.inputs = [
            a for a in sorted(self.hinges) if self.hinges[a].is_input and a not in surrogates
        ]
        self.held = set(self.inputs)
        self.extra = (
            [sp.Symbol(f"din_{a}", real=True) for a in self.inputs]
            + [sp.Symbol(f"dact_{k}", real=True) for k in range(len(self.acts))]
            + [
                sp.Symbol(f"{c}_{k}", real=True)
                for k in range(len(self.points))
                for c in ("vfx", "vfy", "vm")
            ]
        )
        self._fns: dict = {}
        # the last _eval: (its key, its result); Newton asks the residual and then the Jacobian
        # at the same point
        self._evaluated: tuple | None = None

    def value(self, e) -> sp.Float:
        """`e` at the file's parameter values, a 30-digit Float."""
        return sp.Float(sp.N(substitute(e, self._values_subs), 30), 30)

    # -- the equations -------------------------------------------------------------------------
    @cached_property
    def _s(self) -> dict:
        """Every intermediate quantity as a sympy expression of (x, th, t) and the plates'
        outputs, symbols `out[a]` = (along, across, omega) (the chain rule takes their
        derivatives from the plate relation's, docs/physics.md)."""
        return self._state(False)

    @cached_property
    def _se(self) -> dict:
        """:attr:`_s` with the reported quantities' parameters `extra` in it."""
        return self._state(True)

    def _state(self, extended: bool) -> dict:
        nu = len(self.unknowns)
        X = [xi * sp.Float(float(s), 17) for xi, s in zip(self.x, self.scale)]
        delta = dict.fromkeys(self.hinges, sp.S.Zero)
        for k, a in enumerate(self.unknowns):
            delta[a] = X[k]
        # (link, at, force, moment, factor): the file's loads scale with t
        loads = [(link, at, force, moment, self.t) for link, at, force, moment in self.loads]
        # the actuators' forces along their lines (stroke: an unknown; force: t F)
        act_force = [
            X[nu + 3 * len(self.chords) + self.strokes.index(k)]
            if act[4] == "stroke"
            else self.t * self.fa[self.forces.index(act[0])]
            for k, act in enumerate(self.acts)
        ]
        dact = [sp.S.Zero] * len(self.acts)
        if extended:
            for k, a in enumerate(self.inputs):
                delta[a] = self.extra[k]
            dact = list(self.extra[len(self.inputs) : len(self.inputs) + len(self.acts)])
            for k, act in enumerate(self.acts):
                if act[4] == "force":
                    act_force[k] += dact[k]
            virtual = self.extra[len(self.inputs) + len(self.acts) :]
            for k, name in enumerate(sorted(self.points)):
                link, at = self.points[name]
                fx, fy, m = virtual[3 * k : 3 * k + 3]
                loads.append((link, at, (fx, fy), m, sp.S.One))
        for (_, link, at, d, _), f in zip(self.acts, act_force):
            loads.append((link, at, (f * d[0], f * d[1]), sp.S.Zero, sp.S.One))
        chord = {
            c: (X[nu + 3 * j], X[nu + 3 * j + 1], X[nu + 3 * j + 2])
            for j, c in enumerate(self.chords)
        }
        sign = {a: h.sign for a, h in self.hinges.items()}
        phi = {i: sp.Add(*(sign[b] * self.th[b] for b in self.paths[i])) for i in self.paths}
        dphi = {i: sp.Add(*(sign[b] * delta[b] for b in self.paths[i])) for i in self.paths}
        # forces on links: the loads (times t) and the chord plates' reactions
        on_link = {i: [sp.S.Zero, sp.S.Zero] for i in self.paths}
        for link, _, force, _, factor in loads:
            on_link[link][0] += factor * force[0]
            on_link[link][1] += factor * force[1]
        for c, (nx, ny, _) in chord.items():
            h = self.hinges[c]
            on_link[h.M] = [on_link[h.M][0] - nx, on_link[h.M][1] - ny]
            on_link[h.P] = [on_link[h.P][0] + nx, on_link[h.P][1] + ny]
        n = {}
        for a in range(1, self.n + 1):
            fx = sp.Add(*(on_link[i][0] for i in self.beyond[a]))
            fy = sp.Add(*(on_link[i][1] for i in self.beyond[a]))
            n[a] = (sign[a] * fx, sign[a] * fy)
        for c, (nx, ny, _) in chord.items():
            n[c] = (nx, ny)
        dz, mom, pf, out, joint = {}, {}, {}, {}, {}
        first_eta = nu + 3 * len(self.chords) + len(self.strokes)
        for a, h in self.hinges.items():
            if a not in self.plate:
                dz[a], mom[a] = V.ZERO, sp.S.Zero
                continue
            d = self.plate[a]
            tc = self.th[a] + delta[a]
            frame = phi[h.P] + dphi[h.P] + d["alpha"] + tc / 2
            for j in range(self.segments):
                out[a, j] = sp.symbols(f"along_{a}_{j} across_{a}_{j} omega_{a}_{j}", real=True)
            if self.segments == 1:
                k = d["l"] ** 2 / d["EI"]
                p, f = V.rot(-frame, (n[a][0] * k, n[a][1] * k))
                along, across, omega = out[a, 0]
                u = tc / 2
                # M's clamp beyond the rigid pin's path: the arc's chord beyond the midpoint
                # pin's, and the relation's correction
                local = (d["l"] * (u * u * arck(u) + along), d["l"] * across)
                mom[a] = omega * d["EI"] / d["l"]
                pf[a, 0] = (tc, p, f)
            else:
                local, mom[a], joint[a] = self._chain(
                    d, tc, X[first_eta + sorted(self.plate).index(a)], frame, n[a], pf, out, a
                )
            # a pin off the midpoint (pin = "prbm", d from M's clamp): the two pins' paths
            # differ by (l/2 - d)(1 - e^{iθ}), in the mid-frame (0, (l - 2d) sin(θ/2))
            local = (local[0], local[1] + d["offset"] * sp.sin(tc / 2))
            dz[a] = V.rot(frame, local)
        return {
            "delta": delta,
            "chord": chord,
            "phi": phi,
            "dphi": dphi,
            "n": n,
            "dz": dz,
            "mom": mom,
            "pf": pf,
            "out": out,
            "joint": joint,
            "loads": loads,
            "act_force": act_force,
            "dact": dact,
        }

    def _chain(self, d: dict, tc, eta, frame, n, pf: dict, out: dict, a: int):
        """Two half plates h = l/2 joined at a section turned by ψ = θ/2 + η from P's clamp:
        M's clamp beyond the midpoint pin's path in the plate's mid-frame (cancellation-free:
        h (2 sin²(θ/4) - 2 sin²(η/2), sin η) plus each half's own arc and relation), the moment
        at M's end and the joint's moment balance (half 1's end moment = half 2's plus n's
        moment about the joint)."""
        h = d["l"] / 2
        k = h**2 / d["EI"]
        psi = tc / 2 + eta
        # the halves' mid-frames from the plate's: ψ/2 - θ/2 and ψ/2
        turns = (eta / 2 - tc / 4, tc / 4 + eta / 2)
        rots = (psi, tc - psi)
        local = (
            h * (2 * sp.sin(tc / 4) ** 2 - 2 * sp.sin(eta / 2) ** 2),
            h * sp.sin(eta),
        )
        ends = []
        for j in range(2):
            p, f = V.rot(-(frame + turns[j]), (n[0] * k, n[1] * k))
            pf[a, j] = (rots[j], p, f)
            along, across, omega = out[a, j]
            u = rots[j] / 2
            local = V.add(local, V.rot(turns[j], (h * (u * u * arck(u) + along), h * across)))
            ends.append(omega * d["EI"] / h)
        along, across, _ = out[a, 1]
        u = rots[1] / 2
        r2 = V.rot(frame + turns[1], (h * (sinr(0)(u) + along), h * across))
        return local, ends[1], ends[0] - ends[1] - V.cross(r2, n)

    def _weights(self, link: int, point) -> dict:
        out, previous = {}, (sp.S.Zero, sp.S.Zero)
        path = self.paths[link]
        for i, b in zip((0,) + path, path):
            out[i] = V.sub(self.centres[b], previous)
            previous = self.centres[b]
        out[link] = V.sub(point, previous)
        return out

    def _path_dz(self, s: dict, link: int):
        terms = [V.scale(self.hinges[b].sign, s["dz"][b]) for b in self.paths[link]]
        return V.add(*terms) if terms else V.ZERO

    def _position(self, s: dict, link: int, point):
        """Current position of a point fixed in `link` (full: it is a moment arm)."""
        rigid = [
            V.rot(s["phi"][i] + s["dphi"][i], w) for i, w in self._weights(link, point).items()
        ]
        return V.add(*rigid, self._path_dz(s, link))

    def _deviation(self, s: dict, link: int, point):
        """Compliant minus rigid position, cancellation-free."""
        parts = [
            V.rot(s["phi"][i], V.rot_minus_identity(s["dphi"][i], w))
            for i, w in self._weights(link, point).items()
        ]
        return V.add(*parts, self._path_dz(s, link))

    def _rows(self, s: dict) -> list[sp.Expr]:
        st = self.kin.structure
        rows = []
        for c in self.chords:
            row = st.loops[c - self.n - 1]
            rows.append(
                sp.Add(
                    *(
                        int(row[b - 1]) * self.hinges[b].sign * s["delta"][b]
                        for b in range(1, self.m + 1)
                        if row[b - 1]
                    )
                )
            )
            lw = self.kin.loop_weights(c)
            parts = []
            for i, w in lw.items():
                if not self.symbolic:
                    w = tuple(self.value(v) for v in w)
                parts.append(V.rot(s["phi"][i], V.rot_minus_identity(s["dphi"][i], w)))
            for b in range(1, self.m + 1):
                if row[b - 1]:
                    parts.append(V.scale(int(row[b - 1]) * self.hinges[b].sign, s["dz"][b]))
            ox, oy = V.add(*parts)
            rows += [ox / self.lmin, oy / self.lmin]
        unit = self.F * self.L
        for a in range(1, self.n + 1):
            if a not in self.held:
                rows.append(self._balance(s, a) / unit)
        for c, (_, _, mu) in s["chord"].items():
            # an input chord's actuator takes up whatever moment the plate does not: μ is its
            # reaction (plate plus actuator), no relation
            if c not in self.held:
                rows.append((mu - s["mom"][c]) / unit)
        for k in self.strokes:
            # the stroke: the point of action's deviation along d is zero (beyond `dact`); a
            # structure's, the commanded stroke (its reference as fabricated)
            name, link, at, d, _ = self.acts[k]
            lost = sp.S.Zero if self.springs[k] is None else s["act_force"][k] / self.springs[k]
            lost -= self.sa[self.placed.index(name)] if name in self.placed else sp.S.Zero
            rows.append((V.dot(d, self._deviation(s, link, at)) - s["dact"][k] + lost) / self.lmin)
        for a in sorted(s["joint"]):
            rows.append(s["joint"][a] / unit)
        return rows

    def _balance(self, s: dict, a: int) -> sp.Expr:
        """The plate's moment at M's clamp of tree hinge `a` less that of the loads and chord
        loads on the links beyond it (about the clamp): zero at a non-input hinge, the moment
        its actuator exerts on link M at an input."""
        h = self.hinges[a]
        xm = self._position(s, h.M, self.clamp_m[a])
        total = []
        for link, at, force, moment, factor in s["loads"]:
            if link in self.beyond[a]:
                arm = V.sub(self._position(s, link, at), xm)
                total.append(factor * (V.cross(arm, force) + moment))
        for c, (nx, ny, mu) in s["chord"].items():
            hc = self.hinges[c]
            xcm = self._position(s, hc.M, self.clamp_m[c])
            if hc.M in self.beyond[a]:
                total.append(V.cross(V.sub(xcm, xm), (-nx, -ny)) - mu)
            if hc.P in self.beyond[a]:
                total.append(V.cross(V.sub(xcm, xm), (nx, ny)) + mu)
        return s["mom"][a] - h.sign * sp.Add(*total)

    def _clamp_p(self, a: int):
        h = self.hinges[a]
        if self.symbolic:
            return h.clamp(h.P)
        return tuple(self.value(v) for v in h.clamp(h.P))

    def _reported(self, s: dict) -> list[sp.Expr]:
        """Every input's actuator moment on link M (N·u: a tree hinge's moment balance, an input
        chord's plate moment less μ), every actuator's force (stroke) or stroke beyond the rigid
        reference's (force), then every point's deviation and its link's rotation beyond the
        rigid (x, y, φ), sorted by name."""
        out = []
        for a in self.inputs:
            if a <= self.n:
                out.append(self._balance(s, a))
            else:
                out.append(s["mom"][a] - s["chord"][a][2])
        for k, (_, link, at, d, drive) in enumerate(self.acts):
            # a stroke's force, a force's stroke beyond the rigid reference's
            if drive == "stroke":
                out.append(s["act_force"][k])
            else:
                out.append(V.dot(d, self._deviation(s, link, at)))
        for name in sorted(self.points):
            link, at = self.points[name]
            out += [*self._deviation(s, link, at), s["dphi"][link]]
        return out

    def reported(self, x, theta, t: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
        """`_reported`'s values at the solution x and their total derivatives by the parameters
        `extra` (implicit-function theorem: dx/dp = −J⁻¹ dR/dp, the plate relation's outputs
        through the chain rule)."""
        args, _, dins, outs, parts = self._eval(x, theta, t)
        zero = [0.0] * len(self.extra)
        dr, dins_p, ys, dy_x, dy_p, dy_o = self._fn("report")(*args, outs + zero)
        q, n, k, o = len(self.extra), self.size, len(ys), len(outs)
        dr = np.array(dr, dtype=float).reshape(n, q)
        dins_p = np.array(dins_p, dtype=float).reshape(o, q)
        ys = np.array(ys, dtype=float)
        dy_x = np.array(dy_x, dtype=float).reshape(k, n)
        dy_p = np.array(dy_p, dtype=float).reshape(k, q)
        dy_o = np.array(dy_o, dtype=float).reshape(k, o)
        jac, jo = np.zeros((0, 0)), np.zeros((0, o))
        if n:
            _, jo = self._fn("jac")(*args, outs)
            jo = np.array(jo, dtype=float).reshape(n, o)
            jac = self.jacobian(x, theta, t)
        # a batch of one (symkin.physics.reduced_rates); a singular J raises
        block = _red_relation([d.ravel() for d in parts], None, 1)
        dins_x = _red_inputs_x(dins, n, len(parts), 1, 3)
        one = [m[None] for m in (jac, jo)]
        rest = [m[None] for m in (dr, dins_p, dy_x, dy_o, dy_p)]
        return ys, _red_implicit(*one, block, dins_x, *rest, each=False)[0]

    def clamps(self, x, theta, t: float = 1.0) -> dict[int, tuple[float, ...]]:
        """Every plate's P clamp (x, y), M clamp (x, y) and link P's rotation, compliant."""
        args, _, _, outs, _ = self._eval(x, theta, t)
        v = [float(u) for u in self._fn("clamps")(*args, outs)]
        return {a: tuple(v[5 * k : 5 * k + 5]) for k, a in enumerate(sorted(self.plate))}

    def twin(self, key: str, modules: Callable[[], list] | list) -> Reduced:
        """This derivation lambdified into other `modules`, kept under `key`: the buckling
        search's many solves run on the float64 kernels, the derivation shared."""
        twins = self.__dict__.setdefault("_twins", {})
        if key not in twins:
            other = copy.copy(self)
            other.modules, other._fns, other._evaluated = modules, {}, None
            other.__dict__.pop("_twins", None)
            twins[key] = other
        return twins[key]

    def located(self, name: str) -> tuple[int, tuple]:
        """(link, position as fabricated) of a point, an actuator's hidden one ("@name") too."""
        if name in self.points:
            return self.points[name]
        _, link, at, _, _ = next(a for a in self.acts if f"@{a[0]}" == name)
        return link, at

    # -- numbers -------------------------------------------------------------------------------
    @property
    def given(self) -> list[str]:
        """The actuators whose values the functions take after the rigid angles, by name: the
        force actuators' forces (N), then a structure's strokes (file unit)."""
        return self.forces + self.placed

    @property
    def given_symbols(self) -> list[sp.Symbol]:
        """:attr:`given`'s symbols."""
        return self.fa + self.sa

    def angles(self, theta: Mapping) -> list:
        """The functions' second argument: the rigid hinge angles by label, then the values of
        :attr:`given` by name (`theta` holds both)."""
        return [theta[a] for a in sorted(self.hinges)] + [theta[n] for n in self.given]

    def _angles(self, theta) -> list:
        """`angles(theta)`, or theta itself where it is that list already (the shared solver's
        configurations, System)."""
        return theta if isinstance(theta, list) else self.angles(theta)

    def _modules(self) -> list:
        """lambdify's modules, taken now: a callable's namespace holds the kernels derived so
        far."""
        return self.modules() if callable(self.modules) else self.modules

    def _lambdify(self, exprs: list, extra: list | None = None):
        thetas = [self.th[a] for a in sorted(self.hinges)] + self.given_symbols
        args = [list(self.x), thetas, self.t]
        if extra is not None:
            args.append(extra)
        # a callable gives the modules after the derivation: kernels it created are in them
        modules = self._modules()
        return lambdify(args, exprs, modules)

    def _fn(self, key: str):
        """The lambdified function `key`: "plates" (x, th, t) -> (θ_c, p, f) of every plate and
        their x-derivatives; "res", "jac" (x, th, t, outputs) -> residual, ∂/∂x at fixed plate
        outputs and ∂/∂outputs; "dev" -> the points' deviations;
        "loads" -> every hinge's (n_x, n_y, moment) at its M end; "energy" (θ, p, f, ε_a, ε_s)
        -> one plate's elastic energy (EI/l); "plate4", "plate2" (θ, p, f, ε_a, ε_s) -> the
        plate relation and its 9 partials."""
        if key in self._fns:
            return self._fns[key]
        s = self._s
        outs = [v for a, j, *_ in self.segs for v in s["out"][a, j]]
        if key == "plates":
            ins = sp.Matrix([v for a, j, *_ in self.segs for v in s["pf"][a, j]])
            fn = self._lambdify([list(ins), list(jacobian(ins, self.x))])
        elif key in ("res", "jac"):
            rows = sp.Matrix(self._rows(s))
            if key == "res":
                fn = self._lambdify(list(rows), outs)
            else:
                parts = [list(jacobian(rows, self.x)), list(jacobian(rows, outs))]
                fn = self._lambdify(parts, outs)
        elif key == "dev":
            exprs = [
                c
                for name, (link, at) in sorted(self.points.items())
                for c in self._deviation(s, link, at)
            ]
            # then each actuator's point's deviation along its line of action, and x, y
            for _, link, at, d, _ in self.acts:
                dev = self._deviation(s, link, at)
                exprs += [V.dot(d, dev), *dev]
            fn = self._lambdify(exprs, outs)
        elif key == "loads":
            exprs = [v for a in sorted(self.hinges) for v in (*s["n"][a], s["mom"][a])]
            fn = self._lambdify(exprs, outs)
        elif key == "report":
            se = self._se
            rows = sp.Matrix(self._rows(se))
            ins = sp.Matrix([v for a, j, *_ in self.segs for v in se["pf"][a, j]])
            ys = sp.Matrix(self._reported(se))
            parts = [
                list(jacobian(rows, self.extra)),
                list(jacobian(ins, self.extra)),
                list(ys),
                list(jacobian(ys, self.x)),
                list(jacobian(ys, self.extra)),
                list(jacobian(ys, outs)),
            ]
            fn = self._lambdify(parts, outs + self.extra)
        elif key == "clamps":
            exprs = []
            for a in sorted(self.plate):
                h = self.hinges[a]
                exprs += [
                    *self._position(s, h.P, tuple(self._clamp_p(a))),
                    *self._position(s, h.M, self.clamp_m[a]),
                    s["phi"][h.P] + s["dphi"][h.P],
                ]
            fn = self._lambdify(exprs, outs)
        elif key in ("energy", "plate4", "plate2"):
            fn = self._plate_fn(key)
        else:  # pragma: no cover
            raise KeyError(key)
        self._fns[key] = fn
        return fn

    def plate_fn(self, key: str, k: int):
        """Segment k's "energy" or relation ("plate4", "plate2"): the uniform plate's, shared
        (:meth:`_fn`), or its notch's (:meth:`_plate_fn` with its terms)."""
        terms = self.terms[k]
        return self._fn(key) if terms is None else self._plate_fn(key, terms)

    def _plate_fn(self, key: str, terms: RelationTerms | None = None):
        """One plate's "energy" or relation ("plate4", "plate2"), lambdified: no mechanism's
        data is in them (a notch's: its section's terms), so each is derived once per process
        and lambdify's modules (symkin's namespaces are named by the module they complete:
        "mpmath", "math")."""
        modules = self._modules()
        tag = (key, tuple(m for m in modules if isinstance(m, str)), terms)
        with _PLATE_LOCK:
            fn = _PLATE_FNS.get(tag)
            if fn is not None:
                return fn
            th, p, f, ea, es = sp.symbols("theta p f e_a e_s", real=True)
            if key == "energy":
                exprs = (
                    energy(th, p, f, ea, es)
                    if terms is None
                    else notch_energy(th, p, f, ea, es, terms)
                )
            else:
                order = int(key[-1])
                rel = (
                    relation(th, p, f, ea, es, order)
                    if terms is None
                    else notch_relation(th, p, f, ea, es, terms, order)
                )
                vals = [rel.along, rel.across, rel.omega]
                exprs = vals + [sp.diff(v, w) for v in vals for w in (th, p, f)]
            # taken after the derivation, as _lambdify's: the kernels it created are in them
            modules = self._modules()
            fn = _PLATE_FNS[tag] = sp.lambdify(
                [th, p, f, ea, es], exprs, modules=modules, cse=key != "energy", **NO_DOCSTRING
            )
            return fn

    def _eval(self, x, theta: Mapping[int, float], t: float, order: int = 4, jac: bool = False):
        """Plate inputs, outputs and (with `jac`) the chain rule's pieces at (x, θ, t); the last
        point's kept (read only by the callers)."""
        args = (list(map(float, x)), self._angles(theta), t)
        key = (tuple(args[0]), tuple(args[1]), t, order)
        last = self._evaluated  # one read: another thread may replace it
        if last is not None and last[0] == key:
            return last[1]
        ins, dins = self._fn("plates")(*args)
        outs, parts = [], []
        for k, (_, _, _, _, ea, es) in enumerate(self.segs):
            plate = self.plate_fn(f"plate{order}", k)
            v = plate(*(float(u) for u in ins[3 * k : 3 * k + 3]), float(ea), float(es))
            outs += [float(u) for u in v[:3]]
            parts.append(np.array(v[3:], dtype=float).reshape(3, 3))
        result = args, np.array(ins, dtype=float), np.array(dins, dtype=float), outs, parts
        self._evaluated = key, result
        return result

    def residual(self, x, theta, t, order: int = 4) -> np.ndarray:
        args, _, _, outs, _ = self._eval(x, theta, t, order)
        return np.array(self._fn("res")(*args, outs), dtype=float)

    def jacobian(self, x, theta, t) -> np.ndarray:
        """dR/dx = ∂R/∂x + ∂R/∂outputs · ∂outputs/∂(θ_c, p, f) · ∂(θ_c, p, f)/∂x."""
        args, _, dins, outs, parts = self._eval(x, theta, t)
        jx, jo = self._fn("jac")(*args, outs)
        jx = np.array(jx, dtype=float).reshape(self.size, self.size)
        if not parts:
            return jx
        jo = np.array(jo, dtype=float).reshape(self.size, len(outs))
        block = np.zeros((len(outs), len(outs)))
        for k, d in enumerate(parts):
            block[3 * k : 3 * k + 3, 3 * k : 3 * k + 3] = d
        return jx + jo @ block @ dins.reshape(len(outs), self.size)

    def deviations(self, x, theta, order: int = 4) -> dict[str, tuple[float, float]]:
        args, _, _, outs, _ = self._eval(x, theta, 1.0, order)
        v = np.array(self._fn("dev")(*args, outs), dtype=float)
        return {name: (v[2 * k], v[2 * k + 1]) for k, name in enumerate(sorted(self.points))}

    def along(self, x, theta) -> dict[str, float]:
        """Every actuator's point's deviation along its line of action (file unit), by name."""
        return {name: v[0] for name, v in self._acted(x, theta).items()}

    def acted(self, x, theta) -> dict[str, tuple[float, float]]:
        """Every actuator's point's deviation (x, y; file unit), by actuator name."""
        return {name: (v[1], v[2]) for name, v in self._acted(x, theta).items()}

    def _acted(self, x, theta) -> dict[str, tuple[float, float, float]]:
        args, _, _, outs, _ = self._eval(x, theta, 1.0)
        v = [float(u) for u in self._fn("dev")(*args, outs)[2 * len(self.points) :]]
        return {act[0]: tuple(v[3 * k : 3 * k + 3]) for k, act in enumerate(self.acts)}

    # -- solving: symkin.physics.reduced_solver, the generated numpy modules' solver too ---------
    @property
    def system(self) -> System:
        """This equilibrium as the shared solver's system (float64 arithmetic, its ε), with the
        rules RULES holds now."""
        return System(self)

    def solve(self, rigid: Callable[[float], Mapping[int, float]]) -> Answer:
        """The equilibrium at the inputs; `rigid(s)` gives the rigid hinge angles (by label) at
        the inputs scaled by s (1: the configuration asked for, 0: as fabricated). Newton from
        x = 0 at load factor 1, continuation where it fails, the refusals: the shared solver's
        (symkin.physics.reduced_solver: _red_equilibrium, _red_verdict)."""
        theta = rigid(1.0)
        sy = self.system
        with np.errstate(all="ignore"):  # NaN where an evaluation failed: a failed step
            x, jac, ok, steps, total = _red_equilibrium(
                sy, sy.column(theta), [], lambda k: lambda s: self.angles(rigid(s))
            )
        if not ok[0]:
            return Answer(
                {}, x[:, 0], int(total[0]), int(steps[0]), math.nan, math.nan, "no convergence"
            )
        answer = self._answer(x, theta, jac, int(total[0]), int(steps[0]))
        answer.theta, answer.solver = dict(theta), self
        return answer

    def compression(self, x, theta, t: float) -> float:
        """The worst plate's compression over its sway buckling load (its p̃ over −π²) at
        (x, θ, t), from the plates' inputs alone (no relation: past buckling too)."""
        args = (list(map(float, x)), self._angles(theta), t)
        ins = self._fn("plates")(*args)[0]
        worst = 0.0
        for k, (_, _, _, _, ea, es) in enumerate(self.segs):
            # a half plate's p: the plate's over segments²; ε_a − ε_s in sympy, as before; a
            # notch's relation has its poles at α p̃ and β p̃ = −π² (model.sections)
            terms = self.terms[k]
            factor = 1.0 if terms is None else max(terms.alpha, terms.beta)
            w = _red_sway(float(ins[3 * k + 1]), float(ea - es), 0.0, self.segments) * factor
            worst = max(worst, w)
        return worst

    def _answer(self, x, theta, jac, total: int, steps: int) -> Answer:
        """The deviations at the solution x ((n, 1)) with jac its last Newton step's J ((1, n,
        n)), the worst plate's compression and the truncation estimate, refused where either is
        too large (_red_verdict)."""
        sy = self.system
        with np.errstate(all="ignore"):
            dev, worst, estimate, status = _red_verdict(sy, x, sy.column(theta), [], jac)
        worst_p, estimate = float(worst[0]), float(estimate[0])
        refused = ""
        if status[0] == 1:
            refused = f"a plate at {worst_p:.0%} of its sway buckling load"
            if worst_p < RULES.p_limit:
                refused = "a deviation that is not finite"
        elif status[0] == 4:
            refused = f"{TRUNCATION} {estimate:.2%}"
        x = x[:, 0]
        names = sorted(self.points)
        deviations = {name: (dev[2 * k, 0], dev[2 * k + 1, 0]) for k, name in enumerate(names)}
        loads, work = self._loads(x, theta)
        angles = {
            self.hinges[a].name: float(x[k] * self.scale[k]) for k, a in enumerate(self.unknowns)
        }
        return Answer(
            deviations,
            x,
            total,
            steps,
            estimate,
            worst_p,
            refused,
            segments=self.segments,
            hinge_loads=loads,
            energy=work,
            angle_deviations={h.name: angles.get(h.name, 0.0) for h in self.hinges.values()},
        )

    @property
    def length(self) -> float:
        """The mechanism's size: the largest distance between hinge centres, at least the
        shortest plate (a cross-spring pivot's hinges share their centre)."""
        return max(self.L, self.lmin)

    def _loads(self, x, theta) -> tuple[dict[str, tuple[float, float, float]], float]:
        """Every hinge's end load at the solution x (tree hinges: statics of the loads and the
        chord forces; moments: the plate relation's ω EI/l) and the plates' elastic energy, the
        sum of each (half) plate's U + p X + f Y (symkin.physics.plate_relation.energy)."""
        args, ins, _, outs, _ = self._eval(x, theta, 1.0)
        v = [float(u) for u in self._fn("loads")(*args, outs)]
        loads = {
            self.hinges[a].name: (v[3 * k], v[3 * k + 1], v[3 * k + 2])
            for k, a in enumerate(sorted(self.hinges))
        }
        work = math.fsum(
            float(
                self.plate_fn("energy", k)(
                    *(float(u) for u in ins[3 * k : 3 * k + 3]), float(ea), float(es)
                )
            )
            * float(ei / length)
            for k, (_, _, ei, length, ea, es) in enumerate(self.segs)
        )
        return loads, work


#: What a lambdified evaluation raises where the shared solver reads NaN: a singular matrix, a
#: plate past its buckling load (the kernels' DomainError), an overflow.
_FAILURES = (np.linalg.LinAlgError, ValueError, ZeroDivisionError, OverflowError)


class System:
    """A Reduced as symkin.physics.reduced_solver's system: each configuration of a batch (x's
    columns, theta a list of (b,) arrays of `Reduced.angles`) evaluated alone by the lambdified
    functions, in float64 (the rules at its ε); NaN where an evaluation raises."""

    def __init__(self, red: Reduced) -> None:
        self.red = red
        self.size, self.scale, self.count = red.size, red.scale, red.segments
        labels = sorted(red.hinges)
        self.t = _Rules(
            RULES.rules(EPS64),
            unknowns=len(red.unknowns),
            unknown_index=[labels.index(a) for a in red.unknowns],
            forces=len(red.forces),
            loads=bool(red.loads or red.forces),  # t enters the equations
            length=red.length,
        )

    def column(self, theta: Mapping) -> list[np.ndarray]:
        """One configuration's theta (by label, and the forces by name) as the solver's."""
        return [np.array([v]) for v in self.red.angles(theta)]

    def _each(self, x, theta, t):
        for k in range(x.shape[1]):
            yield k, x[:, k], [float(v[k]) for v in theta], float(t[k] if np.ndim(t) else t)

    def system(self, x, theta, p, t) -> tuple[np.ndarray, np.ndarray]:
        n, b = self.size, x.shape[1]
        res, jac = np.full((n, b), np.nan), np.full((b, n, n), np.nan)
        for k, xk, angles, tk in self._each(x, theta, t):
            try:
                r, j = self.red.residual(xk, angles, tk), self.red.jacobian(xk, angles, tk)
            except _FAILURES:
                continue
            res[:, k], jac[k] = r, j
        return res, jac

    def residual(self, x, theta, p, t) -> np.ndarray:
        res = np.full((self.size, x.shape[1]), np.nan)
        for k, xk, angles, tk in self._each(x, theta, t):
            with suppress(*_FAILURES):
                res[:, k] = self.red.residual(xk, angles, tk)
        return res

    def compression(self, x, theta, p, t) -> np.ndarray:
        worst = np.full(x.shape[1], np.nan)
        for k, xk, angles, tk in self._each(x, theta, t):
            with suppress(*_FAILURES):
                worst[k] = self.red.compression(xk, angles, tk)
        return worst

    def _deviation(self, x, theta, order: int) -> np.ndarray:
        dev = np.full((2 * len(self.red.points), x.shape[1]), np.nan)
        for k, xk, angles, _ in self._each(x, theta, 1.0):
            with suppress(*_FAILURES):
                found = self.red.deviations(xk, angles, order)
                dev[:, k] = [c for name in sorted(found) for c in found[name]]
        return dev

    def measure(self, x, theta, p) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        res = np.full((self.size, x.shape[1]), np.nan)
        for k, xk, angles, _ in self._each(x, theta, 1.0):
            with suppress(*_FAILURES):
                res[:, k] = self.red.residual(xk, angles, 1.0, 2)
        return self._deviation(x, theta, 4), self.compression(x, theta, p, 1.0), res

    def deviation2(self, x, theta, p) -> np.ndarray:
        return self._deviation(x, theta, 2)


class _Rules:
    """The solver's rules (SOLVER.loaded.rules at an ε) and the system's sizes, as attributes."""

    def __init__(self, rules: Mapping[str, float | int], **more) -> None:
        self.__dict__.update(rules, **more)
