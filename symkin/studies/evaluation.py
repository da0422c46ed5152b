"""One configuration evaluated (`symkin eval`): the derivation with mpmath, or the generated code.

The `sympy` backend evaluates the expressions of :class:`~symkin.analysis.Analysis` with mpmath
at `dps` digits (40 by default), so its float64 results are correctly rounded references for the
generated evaluators: the rigid angles from the closed-form dyads (or Newton with continuation
from the as-fabricated pose), δ from the linear system A δ = −Φ Δz (`first_order`) or Newton on
the exact closure from there (`exact`), then the point positions and deviations (docs/levels.md).
The `numpy` and `c` backends run the generated evaluators; when one of them cannot assemble a
configuration, the mpmath evaluation is asked why, so every backend fails with the same exit code
(3) and the same message naming the loop (docs/cli.md).
"""

from __future__ import annotations

import dataclasses
import functools
import math
import weakref
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field

import mpmath
import numpy as np
import sympy as sp
from sympy.printing.pycode import MpmathPrinter

from ..codegen import pipeline, plan_cache
from ..codegen.backends.numpy.kernels import float64_namespace
from ..core import levels
from ..core.errors import AssemblyError, InputError, suggest
from ..core.recent import Recent
from ..core.settings import SOLVER
from ..kinematics.analysis import Analysis
from ..model import expressions, special
from ..model.lambdified import printer_settings
from ..model.mechanism import Mechanism, check_values
from ..model.precedence import FastPrecedence
from ..physics import equilibrium as physical_equilibrium
from ..physics import model_error as physical_model_error
from ..physics import reduced, reduced_reported, reduced_sensitivity
from ..physics.result import ActuatorLoad, HingeLoad, InputLoad, PlateStress

#: The mpmath evaluation of the derivation, then the generated-code backends (their registry).
BACKENDS = ("sympy", *pipeline.BACKENDS)


@dataclass(frozen=True)
class PointResult:
    rigid: tuple[float, float]
    compliant: tuple[float, float]
    deviation: tuple[float, float]

    @property
    def norm(self) -> float:
        """|ΔR|, the length of the deviation."""
        return math.hypot(*self.deviation)


Pair = tuple[float, float]


@dataclass(frozen=True)
class Sensitivity:
    """Total derivatives at one configuration (docs/sensitivity.md): per point, per parameter
    (file order) or input hinge, the derivative of (x, y) of the deviation and of the rigid
    position. A parameter whose default reads others carries them along."""

    deviation: dict[str, dict[str, Pair]]  # P -> parameter -> d(dx, dy)/dp
    deviation_inputs: dict[str, dict[str, Pair]]  # P -> input hinge -> d(dx, dy)/dθ
    rigid: dict[str, dict[str, Pair]]  # P -> parameter -> d(x, y)/dp, rigid
    rigid_inputs: dict[str, dict[str, Pair]]

    def as_json(self) -> dict:
        """The keys `eval --sensitivity --json` adds (docs/cli.md)."""

        def lists(table: dict) -> dict:
            return {p: {k: list(v) for k, v in row.items()} for p, row in table.items()}

        return {
            "sensitivity": lists(self.deviation),
            "sensitivity_inputs": lists(self.deviation_inputs),
            "rigid_sensitivity": lists(self.rigid),
            "rigid_sensitivity_inputs": lists(self.rigid_inputs),
        }

    @classmethod
    def from_columns(
        cls, points: Sequence[str], params: Sequence[str], inputs: Sequence[str], deviation, rigid
    ) -> Sensitivity:
        """From arrays indexed [point][variable][component], variables = params then inputs."""
        n = len(params)

        def table(data, names, offset) -> dict:
            return {
                p: {
                    v: (float(data[i][offset + k][0]), float(data[i][offset + k][1]))
                    for k, v in enumerate(names)
                }
                for i, p in enumerate(points)
            }

        return cls(
            table(deviation, params, 0),
            table(deviation, inputs, n),
            table(rigid, params, 0),
            table(rigid, inputs, n),
        )


@dataclass(frozen=True)
class LinkResult:
    """A link's rotation from the as-fabricated pose (radians): rigid (wrapped to (−π, π]),
    compliant = rigid + deviation, and the deviation itself, computed from δ directly."""

    rigid: float
    compliant: float
    deviation: float


@dataclass(frozen=True)
class Evaluation:
    """One configuration evaluated at one level (the `eval --json` of docs/cli.md via
    :meth:`as_json`)."""

    level: str
    backend: str
    inputs: dict[str, float]
    angles_rigid: dict[str, float]
    angles_compliant: dict[str, float]
    points: dict[str, PointResult]
    dyads: tuple[dict, ...] = field(default=())
    params: dict[str, float] = field(default_factory=dict)  # every parameter's value used
    overrides: tuple[str, ...] = ()  # the ones given with --param
    links: dict[str, LinkResult] = field(default_factory=dict)  # every link's rotation
    sensitivity: Sensitivity | None = None  # with eval --sensitivity
    # The physical levels (docs/physics.md): each plate's end load, the elastic energy (J) and,
    # at `equilibrium`, the solver's estimate of the deviations' largest relative error.
    hinges: dict[str, HingeLoad] = field(default_factory=dict)
    energy: float | None = None
    error_estimate: float | None = None
    # At `equilibrium` (docs/physics.md, "What equilibrium reports"): every input's actuator
    # moment and stiffness, every point's 3×3 tangent stiffness with the inputs held (None: held
    # rigidly), every plate's largest stress, and with loads their first buckling factor
    # (math.inf: none up to physics.equilibrium.BUCKLING_LIMIT) and the hinge that buckles.
    actuation: dict[str, InputLoad] = field(default_factory=dict)
    # every actuator's stroke, force and dF/ds (docs/physics.md)
    actuators: dict[str, ActuatorLoad] = field(default_factory=dict)
    stiffness: dict[str, list | None] = field(default_factory=dict)
    plates: dict[str, PlateStress] = field(default_factory=dict)
    buckling: float | None = None
    buckling_hinge: str | None = None
    units: str = "m"  # the file's length unit (the stiffness's unit)
    # The physical levels' model error per point (docs/physics.md, "Model error"): relative to
    # |ΔR|, an estimate of the level's beam theory against a continuum, and its parts.
    model_error: dict[str, float] = field(default_factory=dict)
    model_error_parts: dict[str, dict[str, float]] = field(default_factory=dict)

    def as_json(self) -> dict:
        """The `eval --json` document (docs/cli.md; the physical levels' keys: docs/physics.md)."""
        extra = self.sensitivity.as_json() if self.sensitivity is not None else {}
        physical = {}
        if levels.get(self.level).needs_stiffness:
            physical = {
                "hinges": {
                    name: {"moment": h.moment, "force": list(h.force)}
                    for name, h in self.hinges.items()
                },
                "energy": self.energy,
            }
            if self.error_estimate is not None:
                physical["error_estimate"] = self.error_estimate
            if self.actuation:
                physical["inputs"] = {
                    name: {"angle": a.angle, "moment": a.moment, "stiffness": a.stiffness}
                    for name, a in self.actuation.items()
                }
            if self.actuators:
                physical["actuators"] = {
                    name: {"stroke": a.stroke, "force": a.force, "stiffness": a.stiffness}
                    for name, a in self.actuators.items()
                }
            if self.stiffness:
                physical["stiffness"] = dict(self.stiffness)
            if self.plates:
                physical["plates"] = {
                    name: {"stress": p.stress, "strain": p.strain, "safety": p.safety}
                    for name, p in self.plates.items()
                }
            if self.buckling is not None:
                # JSON has no infinity: null is "none up to the factor searched"
                physical["buckling"] = self.buckling if math.isfinite(self.buckling) else None
        return {
            "level": self.level,
            "backend": self.backend,
            "inputs": dict(self.inputs),
            "params": dict(self.params),
            "angles": {"rigid": dict(self.angles_rigid), "compliant": dict(self.angles_compliant)},
            "points": {
                name: {
                    "rigid": list(p.rigid),
                    "compliant": list(p.compliant),
                    "deviation": list(p.deviation),
                    "norm": p.norm,
                }
                | ({"model_error": self.model_error[name]} if name in self.model_error else {})
                for name, p in self.points.items()
            },
            "links": {
                name: {"rigid": r.rigid, "compliant": r.compliant, "deviation": r.deviation}
                for name, r in self.links.items()
            },
            "dyads": [dict(d) for d in self.dyads],
            **extra,
        } | physical


def evaluate(
    analysis: Analysis,
    inputs: Mapping[str, object],
    level: str = levels.DEFAULT,
    params: Mapping[str, object] | None = None,
    backend: str = "sympy",
    dps: int = 40,
    sensitivity: bool = False,
) -> Evaluation:
    """Evaluate one configuration at `level` through `backend` (sympy: mpmath at `dps` digits);
    with `sensitivity`, also the derivatives by every parameter and input
    (docs/sensitivity.md)."""
    if sensitivity and not levels.get(level).sensitivity:
        having = [lv.name for lv in levels.LEVELS if lv.generated and lv.sensitivity]
        raise InputError(
            f"the {level} level has no sensitivities",
            file=analysis.mechanism.path,
            entry="--sensitivity",
            hint="ask for them at " + ", ".join(having) + " (docs/sensitivity.md)",
        )
    if analysis.mechanism.actuators:
        return _actuated(analysis, inputs, level, params, backend, dps, sensitivity)
    return _evaluate(analysis, inputs, level, params, backend, dps, sensitivity)


def _evaluate(
    analysis: Analysis,
    inputs: Mapping[str, object],
    level: str,
    params: Mapping[str, object] | None,
    backend: str,
    dps: int,
    sensitivity: bool,
) -> Evaluation:
    """:func:`evaluate` with every input a hinge angle (the actuators' surrogates included)."""
    if backend == "sympy":
        if level in levels.LOADED:
            return loaded(analysis, inputs, params, dps, sensitivity)
        if level == "equilibrium":
            return equilibrium(analysis, inputs, params)
        return _mpmath_evaluator(analysis).evaluate(inputs, level, params, dps, sensitivity)
    if backend in pipeline.REGISTRY:
        return _generated(analysis, inputs, level, params, backend, sensitivity)
    raise InputError(
        f"unknown backend '{backend}'", entry="--backend", hint="backends: " + ", ".join(BACKENDS)
    )


# -- actuators (docs/levels.md, "Actuators") ---------------------------------------------------


def actuator_values(mech: Mechanism, inputs: Mapping[str, object]) -> dict[str, sp.Expr]:
    """The exact value of every input the user gives (input hinges and actuators, by name):
    each given once, nothing else."""
    names = mech.drives
    for key in inputs:
        if key not in names:
            raise InputError(
                f"'{key}' is not an input (an input hinge or an actuator)",
                file=mech.path,
                entry="--input",
                hint=(suggest(key, names) + "; " if suggest(key, names) else "")
                + "inputs: "
                + ", ".join(names),
            )
    missing = [n for n in names if n not in inputs]
    if missing:
        raise InputError(
            f"no value for the input(s) {', '.join(missing)}",
            file=mech.path,
            entry="--input",
            hint="give every input, e.g. --input " + " --input ".join(f"{n}=0.1" for n in missing),
        )
    return {k: exact_value(v, f"--input {k}", mech.path) for k, v in inputs.items()}


def check_actuated_level(mech: Mechanism, level: str, backend: str, sensitivity: bool) -> None:
    """Refuse (exit 2, naming the actuator) what the actuators do not drive yet: a force at a
    kinematic level (it needs a physical one), force actuators in the generated backends but at
    loaded (numpy and C), the C's sensitivities at loaded with force actuators."""
    if not mech.actuators:
        return
    first = mech.actuators[0]
    entry = f"[[actuator]] '{first.name}'"
    forces = [a for a in mech.actuators if a.drive == "force"]
    if forces and not levels.get(level).needs_stiffness:
        raise InputError(
            f"the actuator '{forces[0].name}' drives by force, which needs a physical level "
            f"(the {level} level has no stiffness)",
            file=mech.path,
            entry=f"[[actuator]] '{forces[0].name}'",
            hint='ask for --level loaded or --level equilibrium, or make it drive = "stroke"',
        )
    if level in levels.LOADED and sensitivity and backend == "c" and forces:
        raise InputError(
            f"the generated C evaluators have no {level} sensitivities with force actuators "
            f"yet (actuator '{forces[0].name}')",
            file=mech.path,
            entry=f"[[actuator]] '{forces[0].name}'",
            hint="use --backend numpy",
        )
    # the generated evaluators take a force at loaded alone (the physical level they generate)
    if backend not in ("sympy", *pipeline.REGISTRY) or (
        backend != "sympy" and forces and level not in levels.LOADED
    ):
        raise InputError(
            f"the generated {backend} evaluators do not take "
            + ("force actuators" if forces else "actuators")
            + f" yet (actuator '{(forces or [first])[0].name}')",
            file=mech.path,
            entry=entry,
            hint="use --backend sympy"
            + (" or numpy" if not forces or level in levels.LOADED else ""),
        )


def _actuated(
    analysis: Analysis,
    inputs: Mapping[str, object],
    level: str,
    params: Mapping[str, object] | None,
    backend: str,
    dps: int,
    sensitivity: bool,
) -> Evaluation:
    """One configuration of a mechanism driven by stroke actuators (docs/levels.md,
    "Actuators"): the rigid linkage and the compliant mechanism each at the strokes. Each
    actuator's surrogate hinge takes the angle at which the rigid point of action has moved by
    the stroke along the line of action, and, separately, the (compliant) angle at which the
    compliant point has; the deviation is compliant - rigid, each taken at its own angle."""
    mech = analysis.mechanism
    check_actuated_level(mech, level, backend, sensitivity)
    if backend != "sympy":  # the generated module solves the strokes itself
        return _generated(analysis, inputs, level, params, backend, sensitivity)
    if level == "equilibrium":
        return equilibrium(analysis, inputs, params)
    if level in levels.LOADED:
        return loaded(analysis, inputs, params, dps, sensitivity)
    given = actuator_values(mech, inputs)
    hinges = {k: v for k, v in given.items() if k not in {a.name for a in mech.actuators}}
    strokes = [given[a.name] for a in mech.actuators]
    solver = _mpmath_evaluator(analysis)
    rigid = _stroke_angles(solver, mech, hinges, strokes, level, params, dps, compliant=False)
    compliant = _stroke_angles(
        solver, mech, hinges, strokes, level, params, dps, compliant=True, start=rigid
    )

    def run(angles, with_rates=sensitivity):
        state = dict(hinges) | {s: mpmath.nstr(v, dps + 10) for s, v in angles.items()}
        return _evaluate(analysis, state, level, params, backend, dps, with_rates)

    ev_r, ev_c = run(rigid), run(compliant)
    rates = None
    if sensitivity:
        rest = run(dict.fromkeys(rigid, mpmath.mpf(0)))
        rates = _stroke_sensitivity(mech, params, ev_r, ev_c, rest)
    hidden = {a.point for a in mech.actuators}
    points = {}
    for name, c in ev_c.points.items():
        if name in hidden:
            continue
        r = ev_r.points[name]
        # compliant - rigid, each at its own surrogate angles: the rigid shift between the two
        # angles plus the deviation at the compliant ones
        dev = tuple(c.rigid[i] - r.rigid[i] + c.deviation[i] for i in range(2))
        points[name] = PointResult(r.rigid, c.compliant, dev)
    links = {
        name: LinkResult(
            ev_r.links[name].rigid,
            c.compliant,
            c.rigid - ev_r.links[name].rigid + c.deviation,
        )
        for name, c in ev_c.links.items()
    }
    return dataclasses.replace(
        ev_c,
        inputs={k: float(sp.N(v, 20)) for k, v in given.items()},
        angles_rigid=dict(ev_r.angles_rigid),
        points=points,
        links=links,
        dyads=ev_r.dyads,
        sensitivity=rates,
    )


def _stroke_sensitivity(
    mech: Mechanism,
    params: Mapping[str, object] | None,
    ev_r: Evaluation,
    ev_c: Evaluation,
    rest: Evaluation,
) -> Sensitivity:
    """The derivatives with actuators (docs/sensitivity.md, "Actuators"): each surrogate angle
    v solves g(v, y) = d(y).(X(v, y) - X0(y)) - s = 0 (X the point of action, rigid or rigid +
    deviation, X0 as fabricated), so dv/dy = -(dg/dv)^-1 dg/dy for every parameter, input
    hinge and stroke y; the derivatives at fixed kinematic inputs are the evaluations' own, at
    the rigid pose (ev_r), the compliant one (ev_c) and as fabricated (rest)."""
    assert ev_r.sensitivity and ev_c.sensitivity and rest.sensitivity
    acts = mech.actuators
    names = [p.name for p in mech.parameters]
    hinges = [h for h in mech.drives if h not in {a.name for a in acts}]
    surrogates = [a.surrogate for a in acts]
    k = len(acts)

    def rate(ev: Evaluation, point: str, y: str, compliant: bool) -> np.ndarray:
        """d(X)/dy at fixed kinematic inputs, X rigid (+ deviation when compliant)."""
        sens = ev.sensitivity
        assert sens is not None
        table = "params" if y in names else "inputs"
        rig = (sens.rigid if table == "params" else sens.rigid_inputs)[point][y]
        out = np.array(rig, dtype=float)
        if compliant:
            dev = (sens.deviation if table == "params" else sens.deviation_inputs)[point][y]
            out = out + np.array(dev, dtype=float)
        return out

    # the lines of action and their rates by the parameters (a direction may read them):
    # central differences of the direction alone at 30 digits, its defaults re-evaluated
    values = parameter_values(mech, params)

    def directions(at: Mapping[sp.Symbol, sp.Expr]) -> list[np.ndarray]:
        out = []
        for a in acts:
            d = [sp.N(c.xreplace(at), 30) for c in a.direction]
            out.append(np.array([float(c) for c in d]))
        return out

    d0 = directions(values)
    dd: dict[str, list[np.ndarray]] = {}
    for par in mech.parameters:
        if not any(c.free_symbols for a in acts for c in a.direction):
            dd[par.name] = [np.zeros(2) for _ in acts]
            continue
        h = sp.Float(10, 30) ** -12 * max(1, abs(sp.N(values[par.symbol], 30)))
        shifted = {q.name: values[q.symbol] for q in mech.parameters if q is not par}
        up = directions(parameter_values(mech, shifted | {par.name: values[par.symbol] + h}))
        down = directions(parameter_values(mech, shifted | {par.name: values[par.symbol] - h}))
        dd[par.name] = [(u - w) / (2 * float(h)) for u, w in zip(up, down)]
    variables = names + hinges + [a.name for a in acts]

    def surrogate_rates(ev: Evaluation, compliant: bool) -> np.ndarray:
        """dv/dy, k x variables."""
        jac = np.array(
            [
                [d0[i] @ rate(ev, a.point, v, compliant) for v in surrogates]
                for i, a in enumerate(acts)
            ]
        )
        rhs = np.zeros((k, len(variables)))
        for i, a in enumerate(acts):
            pts = ev.points.get(a.point) if a.point in ev.points else None
            for j, y in enumerate(variables):
                if y in names:
                    moved = rate(ev, a.point, y, compliant) - rate(rest, a.point, y, False)
                    g = d0[i] @ moved
                    if pts is not None:
                        offset = np.array(pts.compliant if compliant else pts.rigid, dtype=float)
                        offset = offset - np.array(rest.points[a.point].rigid, dtype=float)
                        g += dd[y][i] @ offset
                elif y in hinges:
                    g = d0[i] @ rate(ev, a.point, y, compliant)
                else:
                    g = -float(y == a.name)
                rhs[i, j] = -g
        return np.linalg.solve(jac, rhs)

    rate_r, rate_c = surrogate_rates(ev_r, False), surrogate_rates(ev_c, True)
    shown = [p for p in ev_c.points if p not in {a.point for a in acts}]
    dev: dict[str, dict[str, Pair]] = {}
    rig: dict[str, dict[str, Pair]] = {}
    for point in shown:
        dev[point], rig[point] = {}, {}
        for j, y in enumerate(variables):
            stroke = j >= len(names) + len(hinges)
            r = np.zeros(2) if stroke else rate(ev_r, point, y, False)
            c = np.zeros(2) if stroke else rate(ev_c, point, y, True)
            for i, v in enumerate(surrogates):
                r = r + rate(ev_r, point, v, False) * rate_r[i, j]
                c = c + rate(ev_c, point, v, True) * rate_c[i, j]
            rig[point][y] = (float(r[0]), float(r[1]))
            dev[point][y] = (float(c[0] - r[0]), float(c[1] - r[1]))

    def split(table: dict, params_: bool) -> dict:
        return {
            p: {y: v for y, v in row.items() if (y in names) == params_} for p, row in table.items()
        }

    return Sensitivity(split(dev, True), split(dev, False), split(rig, True), split(rig, False))


def _stroke_jacobian(residual, angles: dict, r: list, step) -> mpmath.matrix | None:
    """The strokes' Jacobian by the surrogate angles: central differences, one-sided where a
    step crosses a toggle (the linkage does not assemble there); None where neither side
    assembles."""
    jac = mpmath.matrix(len(r), len(angles))
    for j, n in enumerate(angles):
        sides = []
        for sign in (1, -1):
            try:
                sides.append(residual(angles | {n: angles[n] + sign * step}))
            except AssemblyError:
                sides.append(None)
        plus, minus = sides
        for i in range(len(r)):
            if plus is not None and minus is not None:
                jac[i, j] = (plus[i] - minus[i]) / (2 * step)
            elif plus is not None or minus is not None:
                jac[i, j] = (
                    (plus[i] - r[i]) / step if plus is not None else (r[i] - minus[i]) / step
                )
            else:
                return None
    return jac


def _stroke_angles(
    solver: _Mpmath,
    mech: Mechanism,
    hinges: Mapping[str, sp.Expr],
    strokes: Sequence[sp.Expr],
    level: str,
    params: Mapping[str, object] | None,
    dps: int,
    compliant: bool,
    start: Mapping[str, mpmath.mpf] | None = None,
) -> dict[str, mpmath.mpf]:
    """The surrogate hinges' angles at which the actuators' points have moved by `strokes`
    along their lines of action: in the rigid linkage, or (`compliant`) in the compliant
    mechanism at `level`. Newton's method on the k × k system, its Jacobian by central
    differences at `dps` digits (the strokes are smooth in the angles away from a toggle)."""
    names = [a.surrogate for a in mech.actuators]
    with mpmath.workdps(dps + 10):
        target = [mpmath.mpf(sp.N(s, dps + 10)) for s in strokes]
        values = parameter_values(mech, params)
        at = [
            [mpmath.mpf(sp.N(c.xreplace(values), dps + 10)) for c in a.at] for a in mech.actuators
        ]
        scale = max(
            [abs(c) for xy in at for c in xy] + [abs(t) for t in target] + [SOLVER.strokes.floor]
        )
        angles = dict(start) if start else dict.fromkeys(names, mpmath.mpf(0))
        # the surrogate angles reach the evaluators as input values, which hold a double's
        # 16 digits: the strokes are met to 1e-15 of the mechanism's size
        tol = scale * mpmath.mpf(10) ** max(
            SOLVER.strokes.mpmath_digits_lost - dps, -SOLVER.strokes.mpmath_float_digits
        )
        step = mpmath.mpf(10) ** -SOLVER.strokes.mpmath_step_digits

        def residual(trial: Mapping[str, mpmath.mpf]) -> list:
            state = dict(hinges) | {n: mpmath.nstr(trial[n], dps + 10) for n in names}
            found = solver.values(state, level if compliant else "paper", params, dps + 10)
            out = []
            for a, xy, s in zip(mech.actuators, at, target):
                rig, dev = found[a.point]
                pos = [rig[i] + (dev[i] if compliant else 0) for i in range(2)]
                d = [mpmath.mpf(sp.N(c.xreplace(values), dps + 10)) for c in a.direction]
                out.append(d[0] * (pos[0] - xy[0]) + d[1] * (pos[1] - xy[1]) - s)
            return out

        r = residual(angles)
        for _ in range(SOLVER.strokes.mpmath_iterations):
            size = max(abs(x) for x in r)
            if size <= tol:
                return angles
            jac = _stroke_jacobian(residual, angles, r, step)
            try:
                delta = None if jac is None else mpmath.lu_solve(jac, mpmath.matrix(r))
            except ZeroDivisionError:
                delta = None
            if delta is None or not all(mpmath.isfinite(x) for x in delta):
                break
            # damped: a full step may leave the assembly range (past a dyad's toggle) or
            # grow the residual far from the solution; halve it until it does neither
            for _ in range(SOLVER.strokes.halvings):
                trial = {n: angles[n] - delta[j] for j, n in enumerate(names)}
                try:
                    found = residual(trial)
                except AssemblyError:
                    found = None
                if found is not None and max(abs(x) for x in found) < size:
                    break
                delta = delta * SOLVER.strokes.cut
            else:
                break
            angles, r = trial, found
    raise AssemblyError(
        f"{mech.path}: no pose of the "
        + ("compliant mechanism" if compliant else "rigid linkage")
        + " reaches the strokes "
        + ", ".join(f"{a.name}={float(sp.N(s, 20)):g}" for a, s in zip(mech.actuators, strokes))
        + " (the surrogate hinges "
        + ", ".join(names)
        + " found no solution: past a toggle or the linkage's reach)"
    )


def loaded(
    analysis: Analysis,
    inputs: Mapping[str, object],
    params: Mapping[str, object] | None = None,
    dps: int = 40,
    sensitivity: bool = False,
) -> Evaluation:
    """The `loaded` level (docs/physics.md): the reduced equilibrium in mpmath, reported on the
    rigid linkage solved at `dps` digits; with `sensitivity`, its derivatives by every parameter
    and input (docs/sensitivity.md)."""
    return _mpmath_evaluator(analysis).loaded(inputs, params, dps, sensitivity)


def equilibrium(
    analysis: Analysis,
    inputs: Mapping[str, object],
    params: Mapping[str, object] | None = None,
    extra_digits: int = 0,
) -> Evaluation:
    """The `equilibrium` level (docs/physics.md): the plates as geometrically exact beams (each
    hinge's `beam`), solved numerically to its own error estimate; `extra_digits` raises the
    working precision (to check it)."""
    return _mpmath_evaluator(analysis).equilibrium(inputs, params, extra_digits)


#: The reduced-equilibrium solvers already derived, by analysis (and by its content,
#: plan_cache.in_memory), then by (parameters, backend, segments).
_REDUCED: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def _float_modules() -> list:
    """lambdify's modules for float64 code with symkin's kernels (taken after a derivation)."""
    return [float64_namespace(), "math"]


def reduced_equilibrium(
    analysis: Analysis,
    inputs: Mapping[str, object],
    params: Mapping[str, object] | None = None,
    backend: str = "numpy",
    segments: int | None = None,
) -> reduced.Answer:
    """The reduced equilibrium (symkin.physics.reduced, the `loaded` level's solver) at one
    configuration: `backend` "numpy" (the numpy backend's float64 kernels) or
    "sympy" (mpmath); `segments` 1 or 2 half plates per plate, by default 1 and 2 where the
    truncation estimate refuses one. The derivation is kept per analysis, parameter values,
    backend and segments."""
    if backend not in ("numpy", "sympy"):
        raise InputError(f"unknown backend '{backend}'", hint="backends: numpy, sympy")
    mech = analysis.mechanism
    exact_params = parameter_values(mech, params)
    solvers = _REDUCED.get(analysis)
    if solvers is None:
        # an analysis of the same file (mechanism, points, hinge models) shares them
        solvers = _REDUCED[analysis] = plan_cache.in_memory(
            analysis, {"for": "reduced_equilibrium"}, dict, dict
        )

    def solver(count: int) -> reduced.Reduced:
        values = tuple(sorted((str(k), str(v)) for k, v in exact_params.items()))
        key = (values, backend, count)
        if key not in solvers:
            modules = _float_modules if backend == "numpy" else None
            other = solvers.get((values, "sympy" if backend == "numpy" else "numpy", count))
            if other is not None:  # the other backend's derivation, lambdified anew
                modules = modules or (lambda: [special.mpmath_namespace(), "mpmath"])
                solvers[key] = other.twin(backend, modules)
            else:
                solvers[key] = reduced.Reduced(analysis.kin, exact_params, modules, count)
        return solvers[key]

    ev = _mpmath_evaluator(analysis)
    hinges: Mapping[str, object] = inputs
    strokes: dict[str, object] = {}
    forces: dict[str, float] = {}
    if mech.actuators:
        drives = actuator_values(mech, inputs)
        hinges = {k: v for k, v in drives.items() if k not in {a.name for a in mech.actuators}}
        for a in mech.actuators:
            if a.drive == "stroke":
                strokes[a.name] = drives[a.name]
            else:  # first against the as-fabricated pose, then at the stroke it produced
                strokes[a.name], forces[a.name] = 0, float(sp.N(drives[a.name], 20))

    def run(strokes: Mapping[str, object]) -> reduced.Answer:
        @functools.cache
        def rigid(scale: float) -> dict:
            given = {k: scale * float(v) for k, v in hinges.items()}
            if mech.actuators:
                found = _stroke_angles(
                    ev,
                    mech,
                    given,
                    [scale * sp.N(sp.sympify(strokes[a.name]), 25) for a in mech.actuators],
                    "paper",
                    params,
                    20,
                    compliant=False,
                )
                given |= {n: mpmath.nstr(v, 25) for n, v in found.items()}
            angles = input_values(analysis, given)
            with mpmath.workdps(30):
                pvals = [mpmath.mpf(sp.N(exact_params[s], 35)) for s in analysis.params]
                ivals = {a: mpmath.mpf(sp.N(v, 35)) for a, v in angles.items()}
                theta, _ = ev._rigid_angles(pvals, ivals)
            return {a: float(v) for a, v in theta.items()} | forces

        answer = solver(segments or 1).solve(rigid)
        if segments is None and answer.refused.startswith(reduced.TRUNCATION):
            answer = solver(2).solve(rigid)
        answer.strokes = {n: float(sp.N(sp.sympify(v), 20)) for n, v in strokes.items()}
        return answer

    answer = run(strokes)
    # a force actuator: the rigid reference at the stroke the force produced (the compliant
    # mechanism's pose does not depend on the reference; one more solve expresses it against
    # the new one, whose point of action then has no deviation along d)
    for _ in range(SOLVER.strokes.reference_rounds):
        if not forces or answer.refused:
            break
        assert answer.solver is not None
        along = {
            n: v for n, v in answer.solver.along(answer.x, answer.theta).items() if n in forces
        }
        if max(abs(v) for v in along.values()) <= SOLVER.strokes.reference * answer.solver.L:
            break
        strokes = strokes | {n: answer.strokes[n] + v for n, v in along.items()}
        answer = run(strokes)
    return answer


#: The Evaluation fields `loaded` reports beyond the deviations (docs/physics.md).
_REPORTED = ("actuation", "actuators", "stiffness", "plates", "buckling")


def _reported_fields(answer: reduced.Answer, scale: float) -> dict:
    """`loaded`'s input moments and stiffness, point stiffness, plate stress and buckling factor
    as Evaluation fields (symkin.physics.reduced_reported); the buckling search's solves in
    float64 (an mpmath one is seconds per solve)."""
    assert answer.solver is not None
    search = answer.solver.twin("float64", _float_modules)
    rep = reduced_reported.report(answer, scale, search=search)
    hidden = {a.point for a in answer.solver.kin.mechanism.actuators}
    return {
        "actuation": rep.inputs,
        "actuators": rep.actuators,
        "stiffness": {n: k for n, k in rep.stiffness.items() if n not in hidden},
        "plates": {  # in the file's order, as equilibrium's
            h.name: rep.plates[h.name]
            for h in answer.solver.kin.mechanism.hinges
            if h.name in rep.plates
        },
        "buckling": rep.buckling,
    }


def with_model_error(
    result: Evaluation, mechanism: Mechanism, values: Mapping[sp.Symbol, sp.Expr]
) -> Evaluation:
    """`result`, at a physical level, with its model error per point
    (symkin.physics.model_error; docs/physics.md): `values` the exact parameter values."""
    found = physical_model_error.estimate(
        mechanism,
        values,
        result.level,
        physical_model_error.level_stretches(mechanism, result.level),
        {name: link.compliant for name, link in result.links.items()},
        result.angles_compliant,
        result.hinges,
        {name: p.deviation for name, p in result.points.items()},
    )
    return dataclasses.replace(result, model_error=found.total, model_error_parts=found.parts)


# -- values from the user -----------------------------------------------------------------------


def exact_value(value: object, entry: str, file: str) -> sp.Expr:
    """An input or parameter value (number, whitelisted expression string, or an exact sympy
    number symkin made itself) as an exact number."""
    try:
        if isinstance(value, sp.Rational | sp.Float):
            expr = value
        elif isinstance(value, str):
            expr = expressions.parse(value, {})
        else:
            expr = expressions.number(value)  # type: ignore[arg-type]
    except expressions.ExpressionError as exc:
        raise InputError(
            str(exc), file=file, entry=entry, hint="give a number or an expression such as 10*deg"
        ) from None
    if not (expr.is_real and expr.is_finite):
        raise InputError(f"{value!r} is not a finite real number", file=file, entry=entry)
    try:
        size = abs(expressions.numeric(expr, {}))
    except expressions.NotReal:
        raise InputError(
            f"{value!r} is not a finite real number",
            file=file,
            entry=entry,
            hint="give a number or an expression such as 10*deg",
        ) from None
    if size > expressions.FLOAT64_MAX:
        raise InputError(
            f"{value!r} is beyond a float64 (|value| < 1.8e308)",
            file=file,
            entry=entry,
            hint="give a value the generated code can hold",
        )
    return expr


def parameter_values(
    mechanism: Mechanism, overrides: Mapping[str, object] | None = None
) -> dict[sp.Symbol, sp.Expr]:
    """Exact values of every parameter: overrides, then defaults re-evaluated in file order."""
    overrides = dict(overrides or {})
    known = {p.name for p in mechanism.parameters}
    for key in overrides:
        if key not in known:
            raise InputError(
                f"unknown parameter '{key}'",
                file=mechanism.path,
                entry="--param",
                hint="parameters: " + (", ".join(sorted(known)) or "none"),
            )
    values: dict[sp.Symbol, sp.Expr] = {}
    changed = False
    for p in mechanism.parameters:
        raw = overrides.get(p.name)
        if raw is not None:
            values[p.symbol] = exact_value(raw, f"--param {p.name}", mechanism.path)
            changed = True
        elif not changed:
            values[p.symbol] = p.value
        else:
            # A default re-evaluated with overridden values: numerically (60 digits), so an
            # override can never make sympy build a huge exact number (e.g. l**n, n = 1e9).
            try:
                value = sp.Float(expressions.numeric(p.expr, values), expressions.NUMERIC_DPS)
            except expressions.NotReal:
                value = sp.nan
            if not (value.is_real and value.is_finite) or abs(value) > expressions.FLOAT64_MAX:
                raise InputError(
                    f"parameter '{p.name}' = {p.expr} evaluates to {value} with the overrides",
                    file=mechanism.path,
                    entry="--param",
                    hint="choose override values that keep it finite",
                )
            values[p.symbol] = value
    if changed:
        check_values(mechanism, values, "--param")
    return values


def parameter_floats(mechanism: Mechanism, values: Mapping[sp.Symbol, sp.Expr]) -> dict[str, float]:
    """Parameter values by name, as the doubles the generated evaluators receive."""
    return {p.name: float(sp.N(values[p.symbol], 20)) for p in mechanism.parameters}


def input_values(analysis: Analysis, inputs: Mapping[str, object]) -> dict[int, sp.Expr]:
    """Exact input angles by hinge label; every input hinge, and nothing else, must be given."""
    kin, mech = analysis.kin, analysis.mechanism
    names = {kin.hinges[a].name: a for a in kin.inputs}
    for key in inputs:
        if key not in names:
            raise InputError(
                f"'{key}' is not an input hinge",
                file=mech.path,
                entry="--input",
                hint="inputs: " + ", ".join(names),
            )
    missing = [n for n in names if n not in inputs]
    if missing:
        raise InputError(
            f"no value for the input(s) {', '.join(missing)}",
            file=mech.path,
            entry="--input",
            hint="give every input, e.g. --input " + " --input ".join(f"{n}=0.1" for n in missing),
        )
    values = {names[k]: exact_value(v, f"--input {k}", mech.path) for k, v in inputs.items()}
    for a, value in values.items():
        if (sp.Abs(value) - sp.pi).is_positive:
            name = kin.hinges[a].name
            same = ""
            if abs(value) < 1e6:
                wrapped = value - 2 * sp.pi * sp.floor(value / (2 * sp.pi) + sp.Rational(1, 2))
                same = f"; the same pose is {name}={float(sp.N(wrapped, 20)):.9g}"
            raise AssemblyError(
                f"{mech.path}: --input {name}={float(sp.N(value, 20)):.9g} rad: an input is "
                f"the rotation of its plate from the as-fabricated pose, |angle| <= pi"
                f"{same}"
            )
    return values


def check_fabricated_pose(analysis: Analysis) -> None:
    """Refuse (exit 2) input hinges that do not determine the pose: in the as-fabricated pose
    (θ = 0, where every loop closes by construction) the rigid loop Jacobian A must be regular;
    a singular A leaves some non-input hinges free, so no evaluation can succeed."""
    kin = analysis.kin
    if not kin.unknowns:
        return
    at_rest = dict.fromkeys(analysis.thetas, 0)
    rows = analysis.linear_system[0].xreplace(at_rest).subs(analysis.mechanism.defaults).tolist()
    with mpmath.workdps(30):
        a = mpmath.matrix([[mpmath.mpf(sp.N(e, 35)) for e in row] for row in rows])
        for i in range(a.rows):  # angular rows are pure numbers, positional lengths
            scale = max(abs(a[i, j]) for j in range(a.cols))
            for j in range(a.cols):
                a[i, j] = a[i, j] / scale if scale else a[i, j]
        # A float64 SVD settles every well-conditioned case (rounding moves the singular values
        # by ~1e-16 of the largest); only a nearly singular A needs the 30-digit one, which
        # costs seconds on a 60 x 60 system (a ladder of 20 loops).
        sigma64 = np.linalg.svd(np.array(a.tolist(), dtype=float), compute_uv=False)
        if sigma64.size and sigma64[-1] > 1e-8 * sigma64[0]:
            return
        _, sigma, vt = mpmath.svd_r(a)
        k = min(range(len(sigma)), key=lambda i: sigma[i])
        if sigma[k] > mpmath.mpf(10) ** -20 * max(sigma):
            return
        free = [
            kin.hinges[a_].name
            for j, a_ in enumerate(kin.unknowns)
            if abs(vt[k, j]) > mpmath.mpf(10) ** -10
        ]
    inputs = ", ".join(analysis.mechanism.inputs)
    raise InputError(
        f"the input hinges {inputs} do not determine the pose: in the as-fabricated pose the "
        f"loops leave {', '.join(free)} free to move (singular loop Jacobian)",
        file=analysis.mechanism.path,
        entry="input",
        hint=f"mark other hinges as inputs, e.g. one of {', '.join(free)} instead of one of "
        f"{inputs}",
    )


# -- the sympy backend: mpmath ---------------------------------------------------------------------

_EVALUATORS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


class _ArgumentPrinter(FastPrecedence, MpmathPrinter):
    """lambdify's MpmathPrinter that prints each argument symbol by its position (_a0, _a1, ...).

    A parameter may share its name with an internal symbol (a class apart: other assumptions),
    so arguments are told apart by the symbol, not its name; printing them so costs nothing,
    where renaming them in the expression first (lambdify's dummify, or an xreplace) re-walks
    every expression: minutes on a ladder of 20 loops."""

    def __init__(self, names: Mapping[sp.Symbol, str], settings: dict) -> None:
        super().__init__(settings)
        self._names = names

    def _print_Symbol(self, expr: sp.Symbol) -> str:
        name = self._names.get(expr)
        return name if name is not None else super()._print_Symbol(expr)


#: The last mpmath functions printed, by their arguments and expressions: analyses of other
#: files share many (a mechanism with one plate stiffer has the same kinematics).
_FUNCTIONS: Recent[tuple, Callable] = Recent(256)


def _frozen(exprs) -> object:
    return tuple(_frozen(e) for e in exprs) if isinstance(exprs, list | tuple) else exprs


def mpmath_function(args: Sequence[sp.Symbol], exprs) -> Callable:
    """`exprs` (an expression or nested lists of them) as a Python function of `args`
    evaluated with mpmath and symkin's special functions; printed once per arguments and
    expressions (the last 256 kept)."""
    key = (tuple(args), _frozen(exprs))
    try:
        hash(key)
    except TypeError:  # e.g. a mutable matrix among them: printed every time
        return _mpmath_function(args, exprs)
    return _FUNCTIONS.get_or_make(key, lambda: _mpmath_function(args, exprs))


def _mpmath_function(args: Sequence[sp.Symbol], exprs) -> Callable:
    """`exprs` (an expression or nested lists of them) as a Python function of `args`
    evaluated with mpmath and symkin's special functions.

    What sympy.lambdify(args, exprs, modules=[mpmath_namespace(), "mpmath"]) gives, without its
    walks of every expression (dummifying, implemented-function lookup, the docstring), which
    cost more than the printing on large mechanisms. No CSE: every row is evaluated as written,
    so its rounding is what the stopping rule of symkin.core.settings (3b) was measured on."""
    names = {s: f"_a{k}" for k, s in enumerate(args)}
    namespace = {**vars(mpmath), **special.mpmath_namespace()}
    printer = _ArgumentPrinter(names, printer_settings({k: k for k in special.mpmath_namespace()}))

    def flat(e) -> list:
        return [v for x in e for v in flat(x)] if isinstance(e, list | tuple) else [e]

    def nest(e, values):
        if isinstance(e, list | tuple):
            return [nest(x, values) for x in e]
        return next(values)

    leaves = [sp.sympify(e) for e in flat(exprs)]
    shaped = nest(exprs, iter([printer.doprint(v) for v in leaves]))

    def text(e) -> str:
        return "[" + ", ".join(text(x) for x in e) + "]" if isinstance(e, list) else e

    source = f"def _f({', '.join(names.values())}):\n    return {text(shaped)}"
    local: dict = {}
    # the source is printed from sympy expressions whose every argument is renamed _aK, so no
    # name from a mechanism file reaches it (lambdify execs its source the same way)
    exec(compile(source, "<symkin-mpmath>", "exec"), namespace, local)
    return local["_f"]


def _mpmath_evaluator(analysis: Analysis) -> _Mpmath:
    """The mpmath evaluator of `analysis`, kept as long as the analysis (its lambdas are cached)."""
    solver = _EVALUATORS.get(analysis)
    if solver is None:
        solver = _EVALUATORS[analysis] = _Mpmath(analysis)
    return solver


class _Mpmath:
    """The derivation of one Analysis evaluated with mpmath; lambdified functions cached by key."""

    def __init__(self, analysis: Analysis) -> None:
        self.an = analysis
        self.kin = analysis.kin
        self.mechanism = analysis.mechanism
        self._lambdas: dict[str, object] = {}
        self._loaded_terms: reduced_sensitivity.LoadedSensitivity | None = None

    def _fn(self, key: str, exprs, args) -> object:
        """Lambdified (mpmath) function, cached per key."""
        if key not in self._lambdas:
            self._lambdas[key] = mpmath_function(args, exprs)
        return self._lambdas[key]

    def evaluate(
        self,
        inputs: Mapping[str, object],
        level: str,
        params: Mapping[str, object] | None,
        dps: int,
        sensitivity: bool = False,
    ) -> Evaluation:
        an = self.an
        with mpmath.workdps(dps):
            state = self.state(inputs, level, params, dps)
            points = {}
            for name, (rig, dev) in self._point_values(state).items():
                points[name] = PointResult(
                    (float(rig[0]), float(rig[1])),
                    (float(rig[0] + dev[0]), float(rig[1] + dev[1])),
                    (float(dev[0]), float(dev[1])),
                )
            theta, delta, ivals = state.theta, state.delta, state.inputs
            args, values = self._arguments(state)
            links = self._links(an, level, "", args, values)
            names = {a: self.kin.hinges[a].name for a in self.kin.hinges}
            return Evaluation(
                level=level,
                backend="sympy",
                inputs={names[a]: float(ivals[a]) for a in sorted(ivals)},
                angles_rigid={names[a]: float(theta[a]) for a in sorted(theta)},
                angles_compliant={
                    names[a]: float(theta[a] + delta.get(a, 0)) for a in sorted(theta)
                },
                points=points,
                dyads=tuple(state.dyads),
                params=parameter_floats(self.mechanism, state.exact_params),
                overrides=tuple(params or ()),
                links=links,
                sensitivity=self._sensitivity(state) if sensitivity else None,
            )

    def values(
        self,
        inputs: Mapping[str, object],
        level: str,
        params: Mapping[str, object] | None,
        dps: int,
    ) -> dict[str, tuple]:
        """Point name -> (rigid (x, y), deviation (dx, dy)) as mpmath numbers at `dps` digits
        (for references that need more than doubles, e.g. central differences)."""
        with mpmath.workdps(dps):
            return self._point_values(self.state(inputs, level, params, dps))

    def state(
        self,
        inputs: Mapping[str, object],
        level: str,
        params: Mapping[str, object] | None,
        dps: int,
    ) -> _State:
        """The solved configuration (call inside mpmath.workdps(dps))."""
        an = self.an
        levels.get(level)
        given = input_values(an, inputs)
        exact_params = parameter_values(self.mechanism, params)
        pvals = [mpmath.mpf(sp.N(exact_params[s], dps + 5)) for s in an.params]
        ivals = {a: mpmath.mpf(sp.N(v, dps + 5)) for a, v in given.items()}
        theta, dyads = self._rigid_angles(pvals, ivals)
        self._check_limits(theta, ivals)
        delta = self._deltas(level, pvals, theta)
        self._check_limits({a: theta[a] + delta.get(a, 0) for a in theta}, ivals)
        return _State(level, exact_params, pvals, ivals, theta, delta, dyads)

    def _arguments(self, state: _State) -> tuple[list, list]:
        """The symbols of the derivation (parameters, θ, δ) and their values in `state`."""
        an = self.an
        args = [*an.params, *an.thetas, *an.deltas]
        values = [
            *state.pvals,
            *(state.theta[a] for a in sorted(state.theta)),
            *(state.delta.get(a, mpmath.mpf(0)) for a in self.kin.unknowns),
        ]
        return args, values

    def _point_values(self, state: _State) -> dict[str, tuple]:
        an = self.an
        args, values = self._arguments(state)
        out = {}
        for p in an.points:
            rig = self._fn(f"rigid:{p.name}", list(an.point_rigid(p.name)), args)(*values)
            dev = self._fn(
                f"{state.level}:{p.name}", list(an.point_deviation(p.name, state.level)), args
            )(*values)
            out[p.name] = ((rig[0], rig[1]), (dev[0], dev[1]))
        return out

    def _sensitivity(self, state: _State, answer: reduced.Answer | None = None) -> Sensitivity:
        """Total derivatives by the implicit-function theorem on the closures
        (symkin.sensitivity), in mpmath; at `loaded`, on its reduced equilibrium (`answer`)."""
        from ..kinematics import sensitivity

        an, kin = self.an, self.kin
        if not an.points:
            return Sensitivity({}, {}, {}, {})
        terms = sensitivity.of(an)
        args, values = self._arguments(state)
        level = state.level

        def matrix(key: str, expr: sp.Matrix):
            if not expr.rows or not expr.cols:
                return mpmath.zeros(expr.rows, expr.cols)
            return mpmath.matrix(self._fn(f"sens:{key}", expr.tolist(), args)(*values))

        def solve(m, rhs):
            try:
                cols = [mpmath.lu_solve(m, rhs.column(j)) for j in range(rhs.cols)]
            except ZeroDivisionError:
                raise AssemblyError(
                    f"{self.mechanism.path}: the mechanism is at a toggle "
                    "position (singular loop Jacobian) for these inputs"
                ) from None
            out = mpmath.zeros(rhs.rows, rhs.cols)
            for j, col in enumerate(cols):
                for i in range(rhs.rows):
                    out[i, j] = col[i]
            return out

        k, nv = len(kin.unknowns), len(terms.variables)
        theta_v = mpmath.zeros(k, nv)
        rigid_stage = terms.rigid_stage
        if rigid_stage is not None:
            theta_v = -solve(matrix("A", rigid_stage.jacobian), matrix("Gv", rigid_stage.variables))
        rig = terms.rigid
        total_r = matrix("Rv", rig.variables) + (matrix("Rt", rig.theta) * theta_v if k else 0)
        if level in levels.LOADED:
            # the reduced equilibrium's (symkin.physics.reduced_sensitivity), in float64 as its
            # solution
            assert answer is not None
            total_d = mpmath.matrix(self._loaded_rates(state, answer, theta_v).tolist())
        else:
            total_d = self._level_rates(state, terms, matrix, solve, theta_v)
        chain = self._fn(
            "sens:chain",
            sensitivity.parameter_chain(
                [p.expr for p in self.mechanism.parameters], an.params
            ).tolist(),
            args,
        )(*values)
        n_p = len(an.params)
        inputs = [kin.hinges[a].name for a in kin.inputs]
        by_strokes = bool(self.mechanism.actuators) and level in levels.LOADED
        if by_strokes:
            # by the strokes instead of the surrogates' angles (at `loaded`; the kinematic
            # levels' are carried over by _stroke_sensitivity, which reads the surrogates')
            assert answer is not None
            forces = len(answer.solver.forces) if answer.solver else 0
            if forces:  # the rigid positions do not read the forces
                total_r = total_r.T.tolist() + [[0] * total_r.rows for _ in range(forces)]
                total_r = mpmath.matrix(total_r).T
            to_drives = self._stroke_columns(state, total_r, total_d, answer)
            total_d, total_r = total_d * to_drives, total_r * to_drives
            inputs, nv = list(self.mechanism.drives), to_drives.cols

        def per_point(m) -> list:
            cols = [
                [(m[2 * i, j], m[2 * i + 1, j]) for i in range(len(an.points))] for j in range(nv)
            ]
            cols[:n_p] = sensitivity.total(cols[:n_p], chain)
            return [[cols[j][i] for j in range(nv)] for i in range(len(an.points))]

        names = [p.name for p in an.points]
        found = Sensitivity.from_columns(
            names,
            [p.name for p in self.mechanism.parameters],
            inputs,
            per_point(total_d),
            per_point(total_r),
        )
        if not by_strokes:
            return found
        hidden = {a.point for a in self.mechanism.actuators}
        return Sensitivity(
            *(
                {p: row for p, row in table.items() if p not in hidden}
                for table in vars(found).values()
            )
        )

    def _stroke_columns(self, state: _State, total_r, total_d, answer: reduced.Answer):
        """d(parameters, kinematic inputs, forces)/d(parameters, drives) at `loaded`
        (docs/sensitivity.md, "Actuators"): each actuator's surrogate angle θ_v of the rigid
        reference solves, for a stroke, g = d·(X_a(θ) − a) − s = 0 (the rigid linkage at the
        stroke) and, for a force, c = d·ΔX_a = 0 (the reference at the stroke the force
        produced), so dθ_v/dy = −(∂(g, c)/∂θ_v)⁻¹ ∂(g, c)/∂y for every parameter (partial: the
        chain follows), input hinge, stroke and force y. `total_r` and `total_d` the rigid
        positions' and the deviations' rates by (parameters, kinematic inputs, forces), the
        actuators' hidden points among them."""
        an, kin, mech = self.an, self.kin, self.mechanism
        red = answer.solver
        assert red is not None
        acts = mech.actuators
        n_p, k, n_in = len(an.params), len(acts), len(kin.inputs)
        labels = {h.name: a for a, h in kin.hinges.items()}
        drives = list(mech.drives)
        hinges = [n for n in drives if n not in {a.name for a in acts}]
        user = {name: n_p + j for j, name in enumerate(drives)}
        row = {p.name: 2 * i for i, p in enumerate(an.points)}
        column = {a: n_p + j for j, a in enumerate(kin.inputs)}
        column |= {name: n_p + n_in + j for j, name in enumerate(red.forces)}
        params = list(an.params)
        args = [*an.params, *an.thetas]
        at = [*state.pvals, *(state.theta[a] for a in sorted(state.theta))]
        acted = red.acted(answer.x, answer.theta)
        out = mpmath.zeros(n_p + n_in + len(red.forces), n_p + len(drives))
        for c in range(n_p):
            out[c, c] = 1
        for name in hinges:
            out[column[labels[name]], user[name]] = 1
        for name in red.forces:
            out[column[name], user[name]] = 1
        jac, rhs = mpmath.zeros(k, k), mpmath.zeros(k, n_p + len(drives))
        for i, act in enumerate(acts):
            exprs = [*act.direction, *act.at]
            exprs += [sp.diff(e, q) for e in exprs for q in params]
            got = self._fn(f"stroke:{act.name}", exprs, params)(*state.pvals)
            d, a0 = got[:2], got[2:4]
            dd = [[got[4 + m * n_p + c] for c in range(n_p)] for m in range(2)]
            da = [[got[4 + (2 + m) * n_p + c] for c in range(n_p)] for m in range(2)]
            r = row[act.point]
            stroke = act.drive == "stroke"
            table = total_r if stroke else total_d

            def along(col: int, d=d, r=r, table=table):
                return d[0] * table[r, col] + d[1] * table[r + 1, col]

            for j, other in enumerate(acts):
                jac[i, j] = along(column[labels[other.surrogate]])
            for name in hinges:
                rhs[i, user[name]] = along(column[labels[name]])
            if stroke:  # g: the rigid point's stroke
                x = self._fn(f"rigid(theta):{act.point}", list(an.point_rigid(act.point)), args)(
                    *at
                )
                offset = [x[0] - a0[0], x[1] - a0[1]]
                for c in range(n_p):
                    rhs[i, c] = along(c) - d[0] * da[0][c] - d[1] * da[1][c]
                rhs[i, user[act.name]] = -1
            else:  # c: the point's deviation along d
                offset = list(acted[act.name])
                for c in range(n_p):
                    rhs[i, c] = along(c)
                for name in red.forces:
                    rhs[i, user[name]] = along(column[name])
            for c in range(n_p):  # a line of action that reads the parameters turns with them
                rhs[i, c] += dd[0][c] * offset[0] + dd[1][c] * offset[1]
        rates = -(jac**-1) * rhs
        for j, act in enumerate(acts):
            for c in range(rhs.cols):
                out[column[labels[act.surrogate]], c] = rates[j, c]
        return out

    def _level_rates(self, state: _State, terms, matrix, solve, theta_v):
        """dΔR/dv at a kinematic level (partial by the parameters: no chain yet)."""
        level, k = state.level, len(self.kin.unknowns)
        part = terms.partials(level)
        total_d = matrix(f"{level}:Dv", part.variables)
        if k:
            total_d += matrix(f"{level}:Dt", part.theta) * theta_v
            stage = terms.stage(level)
            if stage is not None:
                rhs = (
                    matrix(f"{level}:Ev", stage.variables)
                    + matrix(f"{level}:Et", stage.theta) * theta_v
                )
                delta_v = -solve(matrix(f"{level}:M", stage.jacobian), rhs)
                total_d += matrix(f"{level}:Dd", part.delta) * delta_v
        return total_d

    def _loaded_rates(self, state: _State, answer: reduced.Answer, theta_v) -> np.ndarray:
        """dΔR/dv at `loaded` from its solution (symkin.physics.reduced_sensitivity)."""
        an, kin = self.an, self.kin
        if self._loaded_terms is None:
            # float64 kernels: the solution is float64 (as the solver's, symkin.physics.reduced)
            self._loaded_terms = reduced_sensitivity.LoadedSensitivity(
                an, lambda: [float64_namespace(), "math"]
            )
        red = answer.solver
        assert red is not None
        npar = len(an.params)
        theta_u = np.array(theta_v.tolist(), dtype=float).reshape(len(kin.unknowns), -1)
        rates = reduced_sensitivity.theta_rates(an, theta_u, npar, kin.inputs)
        if red.forces:  # the force actuators' forces: arguments beside θ, a column each
            m, nv, nf = rates.shape[0], rates.shape[1], len(red.forces)
            wider = np.zeros((m + nf, nv + nf))
            wider[:m, :nv], wider[m:, nv:] = rates, np.eye(nf)
            rates = wider
        return self._loaded_terms.rates(
            answer.x,
            red.scale,
            answer.segments,
            answer.theta,
            [float(v) for v in state.pvals],
            rates,
        )

    def loaded(
        self,
        inputs: Mapping[str, object],
        params: Mapping[str, object] | None,
        dps: int,
        sensitivity: bool = False,
    ) -> Evaluation:
        """The `loaded` level (docs/physics.md): the reduced equilibrium (symkin.physics.reduced)
        in mpmath, its deviations, angle deviations, hinge loads and energy put on the rigid
        linkage solved at `dps` digits; a configuration it refuses (no convergence, a plate
        near buckling, the truncation estimate with two half plates) is exit 3."""
        an, mech = self.an, self.mechanism
        if an.redundant and not any(h.beam == "reissner" for h in mech.hinges if h.is_plate):
            # as at equilibrium: inextensible plates leave a redundant loop's self-stress
            # undetermined (the relation's quartic terms alone would fix it, meaninglessly)
            raise AssemblyError(
                f"{mech.path}: the loaded level cannot solve this redundant mechanism "
                f"({len(an.dropped)} redundant closure constraint(s)): its plates are "
                "inextensible elastica, which leave the forces the redundant loops carry along "
                'the plates undetermined; give them beam = "reissner" (docs/levels.md)'
            )
        answer = reduced_equilibrium(an, inputs, params, backend="sympy")
        if answer.refused:
            raise AssemblyError(
                f"{mech.path}: the loaded level refuses this configuration: {answer.refused} "
                "(docs/physics.md); ask for --level equilibrium"
            )
        exact_params = parameter_values(mech, params)
        names = {a: h.name for a, h in self.kin.hinges.items()}
        hidden = {a.point for a in mech.actuators}
        acting: dict[str, sp.Expr] = {}
        if mech.actuators:
            # the rigid linkage at the strokes (a force actuator's: the one it produced)
            drives = actuator_values(mech, inputs)
            acting = {a.name: drives[a.name] for a in mech.actuators}
            hinge_inputs = {k: v for k, v in drives.items() if k not in acting}
            found = _stroke_angles(
                self,
                mech,
                hinge_inputs,
                [sp.Float(answer.strokes[a.name], 17) for a in mech.actuators],
                "paper",
                params,
                dps,
                compliant=False,
            )
            given = input_values(
                an, dict(hinge_inputs) | {n: mpmath.nstr(v, dps + 5) for n, v in found.items()}
            )
        else:
            given = input_values(an, inputs)
        args = [*an.params, *an.thetas]
        with mpmath.workdps(dps):
            pvals = [mpmath.mpf(sp.N(exact_params[s], dps + 5)) for s in an.params]
            ivals = {a: mpmath.mpf(sp.N(v, dps + 5)) for a, v in given.items()}
            theta, dyads = self._rigid_angles(pvals, ivals)
            at = [*pvals, *(theta[a] for a in sorted(theta))]
            points = {}
            for p in an.points:
                if p.name in hidden:
                    continue
                rig = self._fn(f"rigid(theta):{p.name}", list(an.point_rigid(p.name)), args)(*at)
                dev = answer.deviations[p.name]
                points[p.name] = PointResult(
                    (float(rig[0]), float(rig[1])),
                    (float(rig[0] + dev[0]), float(rig[1] + dev[1])),
                    (float(dev[0]), float(dev[1])),
                )
            # the links' rotations: the rigid one from the rigid angles, the deviation from the
            # solution's angle deviations, as at equilibrium
            deltas = [mpmath.mpf(answer.angle_deviations[names[a]]) for a in self.kin.unknowns]
            links = self._links(an, "exact", "equilibrium:", [*args, *an.deltas], at + deltas)
            if mech.actuators:
                links = self._turned_surrogates(links, answer.angle_deviations)
            scale = mpmath.mpf(sp.N(mech.unit_scale, dps))
            hinges = {
                names[a]: HingeLoad(
                    (answer.hinge_loads[names[a]][0], answer.hinge_loads[names[a]][1]),
                    float(answer.hinge_loads[names[a]][2] * scale),
                )
                for a in sorted(names)
            }
            result = Evaluation(
                level="loaded",
                backend="sympy",
                inputs={names[a]: float(ivals[a]) for a in sorted(ivals) if names[a] in mech.drives}
                | {n: float(sp.N(v, 20)) for n, v in acting.items()},
                angles_rigid={names[a]: float(theta[a]) for a in sorted(theta)},
                angles_compliant={
                    names[a]: float(theta[a] + answer.angle_deviations[names[a]])
                    for a in sorted(theta)
                },
                points=points,
                dyads=tuple(dyads),
                params=parameter_floats(mech, exact_params),
                overrides=tuple(params or ()),
                hinges=hinges,
                energy=float(answer.energy * scale),
                links=links,
                units=mech.units,
                **_reported_fields(answer, float(scale)),
            )
            if sensitivity:
                state = _State("loaded", exact_params, pvals, ivals, theta, {}, dyads)
                result = dataclasses.replace(result, sensitivity=self._sensitivity(state, answer))
        return with_model_error(result, mech, exact_params)

    def _links(self, an: Analysis, level: str, prefix: str, args: list, values: list) -> dict:
        """Every link's rigid rotation, compliant rotation and deviation at `level` (the
        deviation from δ itself), `args` the symbols of `an` and `values` theirs."""
        s = an.structure
        rot = self._fn(
            f"{prefix}links:{level}",
            [an.link_rotation(i) for i in range(s.n + 1)]
            + [an.link_deviation(i, level) for i in range(s.n + 1)],
            args,
        )(*values)
        links = {}
        for i in range(s.n + 1):
            rigid, dev = _wrap(rot[i]), rot[s.n + 1 + i]
            links[s.links[i]] = LinkResult(float(rigid), float(rigid + dev), float(dev))
        return links

    def _turned_surrogates(
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

    def _multipliers(self, a_t: list, q: list) -> list:
        """μ of A^T μ = Q at the rigid pose (the loop's chord forces and moments)."""
        try:
            return list(mpmath.lu_solve(mpmath.matrix(a_t), mpmath.matrix(q)))
        except ZeroDivisionError:
            raise AssemblyError(
                f"{self.mechanism.path}: the mechanism is at a toggle position "
                "(singular loop Jacobian) for these inputs"
            ) from None

    def equilibrium(
        self,
        inputs: Mapping[str, object],
        params: Mapping[str, object] | None,
        extra_digits: int = 0,
    ) -> Evaluation:
        """The `equilibrium` level (symkin.physics.equilibrium), against this rigid linkage."""
        an, mech = self.an, self.mechanism
        names = {a: h.name for a, h in self.kin.hinges.items()}
        labels = {n: a for a, n in names.items()}
        driven = {a.name for a in mech.actuators}
        if mech.actuators:
            drives = actuator_values(mech, inputs)
            given = {labels[n]: v for n, v in drives.items() if n not in driven}
            acting = {n: v for n, v in drives.items() if n in driven}
        else:
            given, acting = input_values(an, inputs), {}
        exact_params = parameter_values(self.mechanism, params)
        args = [*an.params, *an.thetas]

        def rigid(dps: int, strokes: Mapping[str, object]) -> tuple[dict, dict]:
            """Rigid hinge angles and point positions at `dps` digits (exit 3 out of range), the
            actuators at `strokes` (docs/levels.md, "Actuators")."""
            surrogates = {}
            if mech.actuators:
                found = _stroke_angles(
                    self,
                    mech,
                    {names[a]: v for a, v in given.items()},
                    [sp.N(sp.sympify(strokes[a.name]), dps + 5) for a in mech.actuators],
                    "paper",
                    params,
                    dps,
                    compliant=False,
                )
                surrogates = {labels[n]: v for n, v in found.items()}
            with mpmath.workdps(dps):
                pvals = [mpmath.mpf(sp.N(exact_params[s], dps + 5)) for s in an.params]
                ivals = {a: mpmath.mpf(sp.N(v, dps + 5)) for a, v in given.items()}
                ivals |= {a: mpmath.mpf(v) for a, v in surrogates.items()}
                theta, _ = self._rigid_angles(pvals, ivals)
                at = [*pvals, *(theta[a] for a in sorted(theta))]
                return (
                    {names[a]: v for a, v in theta.items()},
                    {
                        p.name: self._fn(
                            f"rigid(theta):{p.name}", list(an.point_rigid(p.name)), args
                        )(*at)
                        for p in an.points
                    },
                )

        try:
            res = physical_equilibrium.solve(
                self.mechanism,
                exact_params,
                {names[a]: v for a, v in given.items()} | acting,
                rigid,
                extra_digits,
            )
        except np.linalg.LinAlgError:
            if not an.redundant:
                raise
            # Inextensible plates cannot share a redundant loop's force along themselves: the
            # split is undetermined and the equilibrium equations singular (docs/levels.md).
            raise AssemblyError(
                f"{self.mechanism.path}: the equilibrium level cannot solve this redundant "
                f"mechanism ({len(an.dropped)} redundant closure constraint(s)): its plates "
                "are inextensible elastica, which leave the forces the redundant loops carry "
                "along the plates undetermined (a singular system)"
            ) from None
        buckling = None
        if self.mechanism.loads or any(a.drive == "force" for a in mech.actuators):
            buckling = physical_equilibrium.buckling_factor(
                self.mechanism, exact_params, {names[a]: v for a, v in given.items()} | acting
            )
        order = [names[a] for a in sorted(names)]
        with mpmath.workdps(20):
            # The links' rotations: the rigid one from the rigid angles, the deviation from the
            # solution's angle deviations (docs/physics.md).
            values = [
                *(mpmath.mpf(sp.N(exact_params[s], 25)) for s in an.params),
                *(mpmath.mpf(res.angles_rigid[names[a]]) for a in sorted(names)),
                *(mpmath.mpf(res.angle_deviations[names[a]]) for a in self.kin.unknowns),
            ]
            links = self._links(an, "exact", "equilibrium:", [*args, *an.deltas], values)
            if mech.actuators:
                links = self._turned_surrogates(links, res.angle_deviations)
        result = Evaluation(
            level="equilibrium",
            backend="sympy",
            inputs={names[a]: float(sp.N(given[a], 20)) for a in sorted(given)}
            | {n: float(sp.N(v, 20)) for n, v in acting.items()},
            angles_rigid={n: res.angles_rigid[n] for n in order},
            angles_compliant={n: res.angles_compliant[n] for n in order},
            points={
                n: PointResult(*res.points[n])
                for n in res.points
                if n not in {a.point for a in mech.actuators}
            },
            # the rigid linkage's dyads: with actuators, at its surrogates' angles
            dyads=self.dyad_states(
                {n: res.angles_rigid[n] for n in mech.inputs} if mech.actuators else inputs,
                params,
            ),
            params=parameter_floats(self.mechanism, exact_params),
            overrides=tuple(params or ()),
            hinges={n: res.hinges[n] for n in order},
            energy=res.energy,
            error_estimate=res.error_estimate,
            links=links,
            actuation=res.inputs,
            actuators=res.actuators,
            stiffness={
                n: k for n, k in res.stiffness.items() if n not in {a.point for a in mech.actuators}
            },
            plates={h.name: res.plates[h.name] for h in mech.hinges if h.name in res.plates},
            buckling=None if buckling is None else buckling.factor,
            buckling_hinge=None if buckling is None else buckling.hinge,
            units=self.mechanism.units,
        )
        return with_model_error(result, self.mechanism, exact_params)

    def dyad_states(
        self, inputs: Mapping[str, object], params: Mapping[str, object] | None = None
    ) -> tuple[dict, ...]:
        """Branch and toggle margin of every dyad of the rigid solution at these inputs."""
        given = input_values(self.an, inputs)
        exact_params = parameter_values(self.mechanism, params)
        with mpmath.workdps(30):
            pvals = [mpmath.mpf(sp.N(exact_params[s], 35)) for s in self.an.params]
            ivals = {a: mpmath.mpf(sp.N(v, 35)) for a, v in given.items()}
            return tuple(self._rigid_angles(pvals, ivals)[1])

    def _rigid_angles(self, pvals: list, ivals: dict) -> tuple[dict, list]:
        """Rigid hinge angles θ^r (file orientation) for the given inputs, and dyad states."""
        an, kin, sol = self.an, self.kin, self.an.rigid
        env = dict(zip(an.params, pvals))
        env.update({kin.theta[a]: v for a, v in ivals.items()})
        dyads = []
        if not sol.closed_form:
            theta = self._rigid_newton(pvals, ivals)
            self._check_winding(pvals, theta, ivals)
            self._check_consistency("rigid", pvals, theta)
            return theta, dyads
        for symbol, expr in sol.assignments:
            fn = self._fn(f"assign:{symbol.name}", expr, sorted(expr.free_symbols, key=str))
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
            fn = self._fn(f"phi:{link}", expr, sorted(expr.free_symbols, key=str))
            phi[link] = fn(*(env[s] for s in sorted(expr.free_symbols, key=str)))
        theta = dict(ivals)
        for a in kin.unknowns:
            h = kin.hinges[a]
            # an angle whose inputs are all zero is exactly zero (the formulas round to noise)
            rest = all(ivals[b] == 0 for b in sol.depends[a])
            theta[a] = mpmath.mpf(0) if rest else _wrap(phi[h.M] - phi[h.P])
        self._check_winding(pvals, theta, ivals)
        self._check_consistency("rigid", pvals, theta)
        return theta, dyads

    def _check_winding(self, pvals: list, theta: dict, ivals: dict) -> None:
        """The winding rule of symkin.core.settings: every loop's angle sum below
        SOLVER.winding (the angular rows solved; a dropped one is checked with the others)."""
        an, kin = self.an, self.kin
        if not kin.unknowns:
            return
        f = self._fn("rigid_residual", list(an.rigid_residual), [*an.params, *an.thetas])
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
        out = self._fn(f"consistency:{form}", [*residual, *size], args)(*values)
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
        out = self._fn(f"terms:{form}", [*residual, *size], args)(*values)
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
        form: a group is not a dyad)."""
        an, kin = self.an, self.kin
        args = [*an.params, *an.thetas]
        f = self._fn("rigid_residual", list(an.rigid_residual), args)
        # ∂/∂θ of the rigid closure is A of the first-order system (the same structure).
        jac = self._fn("rigid_jacobian", an.linear_system[0].tolist(), args)
        steps = SOLVER.continuation_steps(max([abs(v) for v in ivals.values()] + [0]))
        x = {a: mpmath.mpf(0) for a in kin.unknowns}
        for step in range(1, steps + 1):
            t = mpmath.mpf(step) / steps
            theta = {**{a: v * t for a, v in ivals.items()}, **x}
            x = self._newton(f, jac, pvals, theta, kin.unknowns)
            if x is None:
                at = ", ".join(
                    f"{kin.hinges[a].name}={float(v * t):g}" for a, v in sorted(ivals.items())
                )
                raise AssemblyError(
                    f"{self.mechanism.path}: the rigid loops cannot close at {at}: "
                    f"{self._worst_loop('rigid', pvals, theta)} does not converge in "
                    f"{SOLVER.rigid_iterations} Newton steps (outside the assembly range or "
                    "at a toggle position)"
                )
        return {**ivals, **x}  # tracked continuously: the limits see |theta| > pi

    def _newton(self, f, jac, pvals: list, theta: dict, unknowns: Sequence[int]) -> dict | None:
        """Newton iteration on the θ of `unknowns`; None when it does not converge."""
        x = mpmath.matrix([theta[a] for a in unknowns])
        tol = SOLVER.mpmath(mpmath.mp.dps).rigid
        for _ in range(SOLVER.rigid_iterations):
            values = [*pvals, *(theta[a] for a in sorted(theta))]
            try:
                step = mpmath.lu_solve(mpmath.matrix(jac(*values)), mpmath.matrix(f(*values)))
            except ZeroDivisionError:
                return None
            x = x - step
            for k, a in enumerate(unknowns):
                theta[a] = x[k]
            if mpmath.norm(step, mpmath.inf) <= tol:
                return {a: x[k] for k, a in enumerate(unknowns)}
        return None

    def _deltas(self, level: str, pvals: list, theta: dict) -> dict:
        """δ of the non-input hinges: zero (paper), linear (first_order) or Newton (exact), by
        the stopping rule of symkin.core.settings (3); redundant loops checked (4)."""
        an = self.an
        if not levels.get(level).needs_delta or not an.deltas:
            return {}
        args = [*an.params, *an.thetas]
        values = [*pvals, *(theta[a] for a in sorted(theta))]
        a_lin, r_lin = an.linear_system
        A = mpmath.matrix(self._fn("lin_A", a_lin.tolist(), args)(*values))
        r = mpmath.matrix(self._fn("lin_r", list(r_lin), args)(*values))
        try:
            d = -mpmath.lu_solve(A, r)
        except ZeroDivisionError:
            raise AssemblyError(
                f"{self.mechanism.path}: the mechanism is at a toggle position "
                "(singular loop Jacobian) for these inputs"
            ) from None
        unknowns = self.kin.unknowns
        delta = {a: d[k] for k, a in enumerate(unknowns)}
        if level == "first_order":
            self._check_consistency("first_order", pvals, theta, delta, level)
            return delta
        scale = self._fn("scale", list(an.closure_scale), args)(*values)
        args_d = [*args, *an.deltas]
        f = self._fn("residual", list(an.residual), args_d)
        jac = self._fn("jacobian", an.jacobian.tolist(), args_d)
        x = mpmath.matrix([delta[a] for a in unknowns])
        tol = SOLVER.mpmath(mpmath.mp.dps)
        k = len(unknowns)
        previous = None
        for _ in range(SOLVER.exact_iterations):
            vals = [*values, *x]
            res, jm = mpmath.matrix(f(*vals)), mpmath.matrix(jac(*vals))
            # (3b): the residual at the rounding level of its terms
            floor = all(
                abs(res[i])
                <= tol.residual
                * (scale[i] + mpmath.fsum(abs(jm[i, j]) * abs(x[j]) for j in range(k)))
                for i in range(k)
            )
            try:
                step = mpmath.lu_solve(jm, res)
            except ZeroDivisionError:
                raise AssemblyError(
                    f"{self.mechanism.path}: singular compliant loop Jacobian "
                    "(toggle position) for these inputs"
                ) from None
            x = x - step
            size, change = mpmath.norm(x, mpmath.inf), mpmath.norm(step, mpmath.inf)
            if (
                change <= tol.converged * size
                or floor
                or (
                    previous is not None
                    and change >= SOLVER.stall_ratio * previous
                    and change <= tol.stalled * size
                )
            ):
                delta = {a: x[j] for j, a in enumerate(unknowns)}
                self._check_consistency("exact", pvals, theta, delta, level)
                return delta
            previous = change
        last = {a: x[j] for j, a in enumerate(unknowns)}
        raise AssemblyError(
            f"{self.mechanism.path}: at {self._at(theta)} the compliant closure did not "
            f"converge in {SOLVER.exact_iterations} Newton steps: "
            f"{self._worst_loop('exact', pvals, theta, last)} stays furthest from closing"
        )


@dataclass(frozen=True)
class _State:
    """One configuration solved in mpmath: parameter and input values, θ and δ."""

    level: str
    exact_params: dict
    pvals: list
    inputs: dict
    theta: dict
    delta: dict
    dyads: list


def _wrap(angle):
    """Angle wrapped into (-π, π]: hinge angles are rotations from the as-fabricated pose."""
    two_pi = 2 * mpmath.pi
    return angle - two_pi * mpmath.nint(angle / two_pi)


# -- the numpy and c backends: the generated evaluators --------------------------------------------


def _generated(
    analysis: Analysis,
    inputs: Mapping[str, object],
    level: str,
    params: Mapping[str, object] | None,
    backend: str,
    sensitivity: bool = False,
) -> Evaluation:
    """One configuration through a generated-code `backend` (symkin.codegen.pipeline); with
    `sensitivity`, its generated sensitivity function too."""
    if not levels.get(level).generated:
        raise InputError(
            f"level '{level}' has no generated evaluator",
            entry="--backend",
            hint="evaluate it with --backend sympy",
        )
    kin, mech = analysis.kin, analysis.mechanism
    if mech.actuators:
        drives = actuator_values(mech, inputs)
        names = list(mech.drives)
        x = [float(sp.N(drives[n], 20)) for n in names]
    else:
        given = input_values(analysis, inputs)
        names = [kin.hinges[a].name for a in kin.inputs]
        x = [float(sp.N(given[a], 20)) for a in kin.inputs]
    pvals = parameter_values(analysis.mechanism, params)
    pfloat = [float(sp.N(pvals[s], 20)) for s in analysis.params]
    # a plan derived with sensitivities or more levels serves (the same values); else the
    # kinematic levels are derived without the physical ones (the reduced equilibrium's
    # routines are most of a plan's derivation)
    scope = None
    if not levels.get(level).needs_stiffness:
        scope = [lv.name for lv in levels.LEVELS if lv.generated and not lv.needs_stiffness]
    p = pipeline.plan_covering(analysis, level, sensitivity=sensitivity, levels=scope)
    ev = pipeline.evaluator(p, backend, analysis.mechanism.path)
    row, shape = pipeline.backend(backend), pipeline.Shape.of(p)
    hinges, pnames = shape.hinges, shape.params
    sens = None
    status, out, angles, rot = row.pose(ev, shape, x, pfloat, level)
    if status == 3:
        raise InputError(f"the {backend} evaluator rejected the arguments", entry="--input")
    if status == 0 and sensitivity:
        rows = row.sensitivity_rows(ev, shape, np.array([x]), pfloat, level)
        status = int(rows[0][0])
        sens = Sensitivity.from_columns(shape.points, pnames, names, rows[2][0], rows[3][0])
    if status:
        _explain(analysis, inputs, level, params, sensitivity)
    points = {
        n: PointResult(
            (out[6 * i], out[6 * i + 1]),
            (out[6 * i + 2], out[6 * i + 3]),
            (out[6 * i + 4], out[6 * i + 5]),
        )
        for i, n in enumerate(shape.points)
    }
    m = len(hinges)
    rigid = dict(zip(hinges, angles[:m]))
    compliant = dict(zip(hinges, angles[m:]))
    links = {n: LinkResult(*rot[3 * i : 3 * i + 3]) for i, n in enumerate(p.reported_links)}
    order = {kin.hinges[a].name: a for a in kin.hinges}
    extra = {}
    if levels.get(level).needs_stiffness:
        # The plates' loads and energy are not in the generated evaluators' output: the
        # derivation gives them, as it gives the dyad states (docs/physics.md).
        physical = loaded(analysis, inputs, params)
        extra = {"hinges": physical.hinges, "energy": physical.energy, "units": mech.units}
        extra |= {k: getattr(physical, k) for k in _REPORTED}
    result = Evaluation(
        level=level,
        backend=backend,
        inputs=dict(zip(names, x)),
        angles_rigid={h: rigid[h] for h in sorted(rigid, key=order.get)},
        angles_compliant={h: compliant[h] for h in sorted(compliant, key=order.get)},
        points=points,
        dyads=_mpmath_evaluator(analysis).dyad_states(
            {n: rigid[n] for n in mech.inputs} if mech.actuators else inputs, params
        ),
        params=parameter_floats(analysis.mechanism, pvals),
        overrides=tuple(params or ()),
        links=links,
        sensitivity=sens,
        **extra,
    )
    if levels.get(level).needs_stiffness:
        return with_model_error(result, analysis.mechanism, pvals)
    return result


def _explain(analysis: Analysis, inputs, level, params, sensitivity: bool = False) -> None:
    """Raise the sympy backend's error for a configuration a generated evaluator refused."""
    evaluate(analysis, inputs, level, params, sensitivity=sensitivity)
    raise AssemblyError(
        f"{analysis.mechanism.path}: the generated evaluator could not solve this "
        "configuration (no convergence in float64), although the 40-digit "
        "derivation can"
    )


def fixed_angles(mech: Mechanism, fixed: Mapping[str, object] | None) -> dict[str, sp.Expr]:
    """Input name -> exact angle of the inputs `fixed` holds (numbers or expressions such as
    'pi/8'); names that are not inputs are bad input (exit 2)."""
    held = {}
    for name, value in (fixed or {}).items():
        if name not in mech.inputs:
            raise InputError(
                f"'{name}' is not an input hinge",
                file=mech.path,
                entry="--fix",
                hint="inputs: " + ", ".join(mech.inputs),
            )
        held[name] = exact_value(value, "--fix", mech.path)
    return held
