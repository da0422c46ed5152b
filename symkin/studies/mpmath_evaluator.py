"""The `sympy` backend's solver: the derivation of one Analysis evaluated with mpmath at any
working precision (docs/levels.md). The rigid angles from the closed-form dyads (or Newton with
continuation from the as-fabricated pose), δ from the linear system A δ = −Φ Δz
(`first_order`) or Newton on the exact closure from there (`exact`) — the Newton, its stopping
rule and the continuation are symkin.kinematics.loop_newton's, which the generated numpy modules
run too, here in mpmath numbers (MPMATH) — then the point positions,
deviations and link rotations; every configuration checked against the winding rule, the
plates' limits and the redundant loops (symkin.core.settings). Its sensitivities are
symkin.studies.mpmath_sensitivity's, its physical levels symkin.studies.physical's."""

from __future__ import annotations

import math
import weakref
from collections.abc import Mapping
from dataclasses import dataclass

import mpmath
import numpy
import sympy as sp

from ..core import levels
from ..core.errors import AssemblyError
from ..core.settings import SOLVER
from ..kinematics.analysis import Analysis
from ..kinematics.loop_newton import _continuation, _newton_solve, _Rule
from ..model.lambdified import mpmath_function
from ..physics import reduced_sensitivity
from .configuration import Configuration
from .results import LinkResult

_EVALUATORS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def evaluator_of(analysis: Analysis) -> MpmathEvaluator:
    """The mpmath evaluator of `analysis`, kept as long as the analysis (its lambdas are cached)."""
    solver = _EVALUATORS.get(analysis)
    if solver is None:
        solver = _EVALUATORS[analysis] = MpmathEvaluator(analysis)
    return solver


class MpmathEvaluator:
    """The derivation of one Analysis evaluated with mpmath; lambdified functions cached by key."""

    def __init__(self, analysis: Analysis) -> None:
        self.an = analysis
        self.kin = analysis.kin
        self.mechanism = analysis.mechanism
        self._lambdas: dict[str, object] = {}
        self.loaded_terms: reduced_sensitivity.LoadedSensitivity | None = None

    def fn(self, key: str, exprs, args) -> object:
        """Lambdified (mpmath) function, cached per key."""
        if key not in self._lambdas:
            self._lambdas[key] = mpmath_function(args, exprs)
        return self._lambdas[key]

    def values(
        self, config: Configuration, dps: int, level: levels.Level | None = None
    ) -> dict[str, tuple]:
        """Point name -> (rigid (x, y), deviation (dx, dy)) as mpmath numbers at `dps` digits
        (for references that need more than doubles, e.g. central differences), at `level`
        (by default the configuration's)."""
        with mpmath.workdps(dps):
            return self.point_values(self.state(config, dps, level))

    def state(self, config: Configuration, dps: int, level: levels.Level | None = None) -> State:
        """The solved configuration at `level`, by default its own (call inside
        mpmath.workdps(dps))."""
        an = self.an
        row = config.level if level is None else level
        given = config.angles
        exact_params = config.params
        pvals = [mpmath.mpf(sp.N(exact_params[s], dps + 5)) for s in an.params]
        ivals = {a: mpmath.mpf(sp.N(v, dps + 5)) for a, v in given.items()}
        theta, dyads = self.rigid_angles(pvals, ivals)
        self._check_limits(theta, ivals)
        delta = self._deltas(row, pvals, theta)
        self._check_limits({a: theta[a] + delta.get(a, 0) for a in theta}, ivals)
        return State(row.name, exact_params, pvals, ivals, theta, delta, dyads)

    def arguments(self, state: State) -> tuple[list, list]:
        """The symbols of the derivation (parameters, θ, δ) and their values in `state`."""
        an = self.an
        args = [*an.params, *an.thetas, *an.deltas]
        values = [
            *state.pvals,
            *(state.theta[a] for a in sorted(state.theta)),
            *(state.delta.get(a, mpmath.mpf(0)) for a in self.kin.unknowns),
        ]
        return args, values

    def point_values(self, state: State) -> dict[str, tuple]:
        an = self.an
        args, values = self.arguments(state)
        out = {}
        for p in an.points:
            rig = self.fn(f"rigid:{p.name}", list(an.point_rigid(p.name)), args)(*values)
            dev = self.fn(
                f"{state.level}:{p.name}", list(an.point_deviation(p.name, state.level)), args
            )(*values)
            out[p.name] = ((rig[0], rig[1]), (dev[0], dev[1]))
        return out

    def links(self, an: Analysis, level: str, prefix: str, args: list, values: list) -> dict:
        """Every link's rigid rotation, compliant rotation and deviation at `level` (the
        deviation from δ itself), `args` the symbols of `an` and `values` theirs."""
        s = an.structure
        rot = self.fn(
            f"{prefix}links:{level}",
            [an.link_rotation(i) for i in range(s.n + 1)]
            + [an.link_deviation(i, level) for i in range(s.n + 1)],
            args,
        )(*values)
        links = {}
        for i in range(s.n + 1):
            rigid, dev = wrap(rot[i]), rot[s.n + 1 + i]
            links[s.links[i]] = LinkResult(float(rigid), float(rigid + dev), float(dev))
        return links

    def turned_surrogates(
        self, links: dict[str, LinkResult], angle_deviations: Mapping[str, float]
    ) -> dict[str, LinkResult]:
        """`links` with the actuators' surrogates turned too (they are not held at the
        physical levels): each link's deviation the sum of its direct path's angle deviations
        (by hinge name), the surrogates' included."""
        kin, s = self.kin, self.an.structure
        out = dict(links)
        for i in range(s.n + 1):
            dev = math.fsum(
                kin.hinges[b].sign * angle_deviations[kin.hinges[b].name] for b in s.tree_path(i)
            )
            rigid = links[s.links[i]].rigid
            out[s.links[i]] = LinkResult(rigid, rigid + dev, dev)
        return out

    def dyad_states(self, config: Configuration) -> tuple[dict, ...]:
        """Branch and toggle margin of every dyad of the rigid solution at `config`'s inputs."""
        given, exact_params = config.angles, config.params
        with mpmath.workdps(30):
            pvals = [mpmath.mpf(sp.N(exact_params[s], 35)) for s in self.an.params]
            ivals = {a: mpmath.mpf(sp.N(v, 35)) for a, v in given.items()}
            return tuple(self.rigid_angles(pvals, ivals)[1])

    def rigid_angles(self, pvals: list, ivals: dict) -> tuple[dict, list]:
        """Rigid hinge angles θ^r (file orientation) for the given inputs, and dyad states."""
        an, kin, sol = self.an, self.kin, self.an.rigid
        env = dict(zip(an.params, pvals))
        env.update({kin.theta[a]: v for a, v in ivals.items()})
        dyads = []
        if not sol.closed_form:
            theta = self._rigid_newton(pvals, ivals)
            self._check_winding(pvals, theta, ivals)
            theta = self._polish(pvals, theta)
            self._check_consistency("rigid", pvals, theta)
            return theta, dyads
        for symbol, expr in sol.assignments:
            fn = self.fn(f"assign:{symbol.name}", expr, sorted(expr.free_symbols, key=str))
            env[symbol] = fn(*(env[s] for s in sorted(expr.free_symbols, key=str)))
            dyad = next((d for d in sol.dyads if d.reach == symbol), None)
            if dyad is not None and env[symbol] < 0:
                raise self._cannot_close(dyad, ivals)
        for d in sol.dyads:
            dyads.append(
                {
                    "hinges": [kin.hinges[a].name for a in d.hinges],
                    "loop": kin.hinges[d.chord].name,
                    "branch": d.branch,
                    "toggle_margin": float(env[d.margin]),
                }
            )
        phi = {}
        for link, expr in sol.phi.items():
            fn = self.fn(f"phi:{link}", expr, sorted(expr.free_symbols, key=str))
            phi[link] = fn(*(env[s] for s in sorted(expr.free_symbols, key=str)))
        theta = dict(ivals)
        for a in kin.unknowns:
            h = kin.hinges[a]
            # an angle whose inputs are all zero is exactly zero (the formulas round to noise)
            rest = all(ivals[b] == 0 for b in sol.depends[a])
            theta[a] = mpmath.mpf(0) if rest else wrap(phi[h.M] - phi[h.P])
        self._check_winding(pvals, theta, ivals)
        theta = self._polish(pvals, theta)
        self._check_consistency("rigid", pvals, theta)
        return theta, dyads

    def _polish(self, pvals: list, theta: dict) -> dict:
        """Rule 2 of symkin.core.settings, as the generated evaluators run it (the shared Newton,
        symkin.kinematics.loop_newton): Newton on the rigid closure from the rigid start until a
        step is at most `converged` times the largest unknown angle (or stalls), at most
        `polish` steps. The closed form's and the continuation's absolute 10^-40 would be no
        relative accuracy for an input of 1e-100; each step squares the error. A singular step
        (an exact toggle) keeps the angles as they are (settings, rule 2)."""
        unknowns = self.kin.unknowns
        tol = SOLVER.mpmath(mpmath.mp.dps)
        if not unknowns or tol.polish == 0:
            return theta
        labels = sorted(theta)
        x, _, _ = _newton_solve(
            MPMATH,
            self._rigid_system(pvals),
            [theta[a] for a in labels],
            [labels.index(a) for a in unknowns],
            numpy.True_,
            _Rule(*SOLVER.loop_rules(tol)["polish"]),
        )
        return dict(zip(labels, x))

    def _rigid_system(self, pvals: list):
        """The rigid closure at the parameters `pvals` as the shared Newton's system: the hinge
        angles (label order) -> the residual, then ∂/∂θ of the unknowns row-major (A of the
        first-order system: the same structure)."""
        an = self.an
        args = [*an.params, *an.thetas]
        f = self.fn("rigid_residual", list(an.rigid_residual), args)
        jac = self.fn("rigid_jacobian", an.linear_system[0].tolist(), args)

        def system(theta: list) -> list:
            return [*f(*pvals, *theta), *(v for row in jac(*pvals, *theta) for v in row)]

        return system

    def _check_winding(self, pvals: list, theta: dict, ivals: dict) -> None:
        """The winding rule of symkin.core.settings: every loop's angle sum below
        SOLVER.winding (the angular rows solved; a dropped one is checked with the others)."""
        an, kin = self.an, self.kin
        if not kin.unknowns:
            return
        f = self.fn("rigid_residual", list(an.rigid_residual), [*an.params, *an.thetas])
        rows = f(*pvals, *(theta[a] for a in sorted(theta)))
        for k in an.angular_rows:
            c = an.row_chord(an.rows[k])
            if not abs(rows[k]) < SOLVER.winding:
                at = ", ".join(
                    f"{kin.hinges[b].name}={float(v):g}" for b, v in sorted(ivals.items())
                )
                raise AssemblyError(
                    f"{self.mechanism.path}: at {at} a hinge of the loop of "
                    f"'{kin.hinges[c].name}' ({an.structure.loop_text(c)}) would have turned "
                    "through more than half a turn on the way from the as-fabricated pose (its "
                    "angles sum to 2*pi, not 0): a plate cannot bend that far"
                )

    def _at(self, theta: dict) -> str:
        """'F1=0.01, ...': the inputs of a configuration, for messages."""
        kin = self.kin
        return ", ".join(f"{kin.hinges[a].name}={float(theta[a]):g}" for a in kin.inputs)

    def _check_consistency(
        self, form: str, pvals: list, theta: dict, delta: dict | None = None, level: str = ""
    ) -> None:
        """Redundant loops (symkin.core.settings, step 4): every dropped closure row of `form`
        ('rigid', 'first_order', 'exact') vanishes at the solution to SOLVER's `consistent`
        times the size of its terms, else the loops contradict each other here (exit 3)."""
        an = self.an
        if not an.redundant:
            return
        residual, size = an.consistency(form)
        args = [*an.params, *an.thetas] + ([] if form == "rigid" else [*an.deltas])
        values = [*pvals, *(theta[a] for a in sorted(theta))]
        if form != "rigid":
            values += [delta[a] for a in self.kin.unknowns]
        out = self.fn(f"consistency:{form}", [*residual, *size], args)(*values)
        tol = SOLVER.mpmath(mpmath.mp.dps).consistent
        d = len(an.dropped)
        for k, row in enumerate(an.dropped):
            if abs(out[k]) <= tol * out[d + k]:
                continue
            c = an.row_chord(row)
            what = ("angular", "x", "y")[row % 3]
            where = (
                f"the redundant loop of '{self.kin.hinges[c].name}' ({an.structure.loop_text(c)})"
            )
            off = (
                f"its {what} closure is off by {float(out[k]):.3g} "
                f"(its terms {float(out[d + k]):.3g})"
            )
            if form == "rigid":
                raise AssemblyError(
                    f"{self.mechanism.path}: at {self._at(theta)} {where} cannot close with the "
                    f"other loops: {off}; the rigid linkage locks here (its constraints are "
                    "redundant in the as-fabricated pose only)"
                )
            raise AssemblyError(
                f"{self.mechanism.path}: at {self._at(theta)} the plates do not close {where} "
                f"at level {level}: {off}; a kinematic level bends each plate by its model "
                "alone, which cannot also close a redundant loop (the physical level "
                "equilibrium shares the deformation among the loops)"
            )

    def _worst_loop(self, form: str, pvals: list, theta: dict, delta: dict | None = None) -> str:
        """The loop whose solved closure row is furthest from zero, relative to the size of its
        terms: "the loop of 'S2' (F1 + S1 - S2 - F2)", for a message."""
        an = self.an
        residual, size = an.closure_terms(form, an.rows)
        args = [*an.params, *an.thetas] + ([] if form == "rigid" else [*an.deltas])
        values = [*pvals, *(theta[a] for a in sorted(theta))]
        if form != "rigid":
            values += [delta[a] for a in self.kin.unknowns]
        out = self.fn(f"terms:{form}", [*residual, *size], args)(*values)
        k = len(an.rows)

        def ratio(i: int):
            r, t = abs(out[i]), out[k + i]
            if not mpmath.isfinite(r):
                return mpmath.inf
            return r / t if t else (mpmath.inf if r else 0)

        worst = max(range(k), key=ratio)
        c = an.row_chord(an.rows[worst])
        return f"the loop of '{self.kin.hinges[c].name}' ({an.structure.loop_text(c)})"

    def _check_limits(self, theta: dict, ivals: dict) -> None:
        """No plate is driven past its bound: its model's limit (elastica_force: π/2) or π."""
        for a, h in self.kin.hinges.items():
            if h.limit is not None and not abs(theta[a]) < mpmath.mpf(sp.N(h.limit, 30)):
                at = ", ".join(
                    f"{self.kin.hinges[b].name}={float(v):g}" for b, v in sorted(ivals.items())
                )
                why = (
                    "a plate cannot bend through more than half a turn"
                    if h.limit == sp.pi
                    else f"beyond its model '{h.hinge.model}', which holds for |theta| < "
                    f"{float(sp.N(h.limit)):.6g} rad"
                )
                raise AssemblyError(
                    f"{self.mechanism.path}: at {at} the hinge '{h.name}' would bend to "
                    f"{float(theta[a]):.6g} rad: {why}"
                )

    def _cannot_close(self, dyad, ivals) -> AssemblyError:
        kin = self.kin
        at = ", ".join(f"{kin.hinges[a].name}={float(v):g}" for a, v in sorted(ivals.items()))
        return AssemblyError(
            f"{self.mechanism.path}: the loop of hinge '{kin.hinges[dyad.chord].name}' "
            f"({self.an.structure.loop_text(dyad.chord)}) cannot close at {at}: the dyad "
            f"{'-'.join(kin.hinges[a].name for a in dyad.hinges)} is beyond its toggle position "
            "(outside the assembly range)"
        )

    def _rigid_newton(self, pvals: list, ivals: dict) -> dict:
        """Rigid angles by Newton with continuation from the as-fabricated pose (no closed
        form: a group is not a dyad), the shared Newton's (symkin.kinematics.loop_newton)."""
        kin = self.kin
        labels = sorted({*ivals, *kin.unknowns})
        theta = [ivals.get(a, mpmath.mpf(0)) for a in labels]
        inputs = [(labels.index(a), v) for a, v in ivals.items()]
        staged: list = []

        def stage(t: float) -> None:
            staged.append(mpmath.mpf(t))
            for i, v in inputs:
                theta[i] = v * staged[-1]

        theta, ok = _continuation(
            MPMATH,
            stage,
            self._rigid_system(pvals),
            theta,
            [labels.index(a) for a in kin.unknowns],
            numpy.True_,
            _Rule(*SOLVER.loop_rules(SOLVER.mpmath(mpmath.mp.dps))["rigid"]),
            float(max([abs(v) for v in ivals.values()] + [0])),
            SOLVER.continuation_step,
        )
        if not ok:
            t = staged[-1]
            at = ", ".join(
                f"{kin.hinges[a].name}={float(v * t):g}" for a, v in sorted(ivals.items())
            )
            where = dict(zip(labels, theta))
            raise AssemblyError(
                f"{self.mechanism.path}: the rigid loops cannot close at {at}: "
                f"{self._worst_loop('rigid', pvals, where)} does not converge in "
                f"{SOLVER.rigid_iterations} Newton steps (outside the assembly range or "
                "at a toggle position)"
            )
        return dict(zip(labels, theta))  # tracked continuously: the limits see |theta| > pi

    def _deltas(self, level: levels.Level, pvals: list, theta: dict) -> dict:
        """δ of the non-input hinges: zero (paper), linear (first_order) or Newton (exact), by
        the stopping rule of symkin.core.settings (3); redundant loops checked (4)."""
        an = self.an
        if not level.needs_delta or not an.deltas:
            return {}
        args = [*an.params, *an.thetas]
        values = [*pvals, *(theta[a] for a in sorted(theta))]
        a_lin, r_lin = an.linear_system
        A = mpmath.matrix(self.fn("lin_A", a_lin.tolist(), args)(*values))
        r = mpmath.matrix(self.fn("lin_r", list(r_lin), args)(*values))
        try:
            d = -mpmath.lu_solve(A, r)
        except ZeroDivisionError:
            raise AssemblyError(
                f"{self.mechanism.path}: the mechanism is at a toggle position "
                "(singular loop Jacobian) for these inputs"
            ) from None
        unknowns = self.kin.unknowns
        delta = {a: d[k] for k, a in enumerate(unknowns)}
        if level.name == "first_order":
            self._check_consistency("first_order", pvals, theta, delta, level.name)
            return delta
        scale = self.fn("scale", list(an.closure_scale), args)(*values)
        args_d = [*args, *an.deltas]
        f = self.fn("residual", list(an.residual), args_d)
        jac = self.fn("jacobian", an.jacobian.tolist(), args_d)

        def system(x: list) -> list:
            return [*f(*values, *x), *(v for row in jac(*values, *x) for v in row)]

        x, ok, stopped = _newton_solve(
            MPMATH,
            system,
            [delta[a] for a in unknowns],
            range(len(unknowns)),
            numpy.True_,
            _Rule(*SOLVER.loop_rules(SOLVER.mpmath(mpmath.mp.dps))["exact"]),
            scale=scale,
        )
        delta = dict(zip(unknowns, x))
        if not ok:
            raise AssemblyError(
                f"{self.mechanism.path}: singular compliant loop Jacobian "
                "(toggle position) for these inputs"
            )
        if not stopped:
            raise AssemblyError(
                f"{self.mechanism.path}: at {self._at(theta)} the compliant closure did not "
                f"converge in {SOLVER.exact_iterations} Newton steps: "
                f"{self._worst_loop('exact', pvals, theta, delta)} stays furthest from closing"
            )
        self._check_consistency("exact", pvals, theta, delta, level.name)
        return delta


@dataclass(frozen=True)
class State:
    """One configuration solved in mpmath: parameter and input values, θ and δ."""

    level: str
    exact_params: dict
    pvals: list
    inputs: dict
    theta: dict
    delta: dict
    dyads: list


def wrap(angle):
    """Angle wrapped into (-π, π]: hinge angles are rotations from the as-fabricated pose."""
    two_pi = 2 * mpmath.pi
    return angle - two_pi * mpmath.nint(angle / two_pi)


class _Mpmath:
    """The arithmetic of the shared Newton (symkin.kinematics.loop_newton) for one
    configuration in mpmath numbers at the working precision: mpmath's LU solve, masks
    numpy.bool_."""

    @staticmethod
    def solve(a: list, b: list, ok) -> tuple[list, object]:
        k = len(b)
        if not ok:
            return [mpmath.mpf(0)] * k, numpy.False_
        try:
            x = mpmath.lu_solve(
                mpmath.matrix([a[i * k : i * k + k] for i in range(k)]), mpmath.matrix(b)
            )
        except ZeroDivisionError:  # singular
            return [mpmath.mpf(0)] * k, numpy.False_
        out = [x[i] for i in range(k)]
        return out, numpy.bool_(all(mpmath.isfinite(v) for v in out))

    @staticmethod
    def where(mask, a, b):
        return a if mask else b

    @staticmethod
    def largest(values: list):
        sizes = [abs(v) for v in values]
        return mpmath.nan if any(mpmath.isnan(v) for v in sizes) else max(sizes)

    @staticmethod
    def full(ok, value):
        return mpmath.mpf(value)


MPMATH = _Mpmath()
