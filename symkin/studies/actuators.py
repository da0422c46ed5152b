"""Actuators (docs/levels.md, "Actuators"): what they drive at which level and backend, the
surrogate hinges' angles that reach their strokes (the shared stroke solve,
symkin.studies.stroke_solver, in mpmath), and the derivatives by the strokes
(docs/sensitivity.md, "Actuators"). The physical levels' actuators are
symkin.studies.physical's; the dispatch over a driven mechanism is symkin.studies.evaluation's."""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import mpmath
import numpy as np
import sympy as sp

from ..core import backends, levels
from ..core.errors import AssemblyError, InputError
from ..core.settings import SOLVER
from ..model.mechanism import Mechanism
from .configuration import Configuration, parameter_values
from .mpmath_evaluator import MpmathEvaluator
from .results import Evaluation, Pair, Sensitivity
from .stroke_solver import _stroke_solve


class ReachError(AssemblyError):
    """No pose of the rigid linkage (or of the compliant mechanism) reaches the strokes: exit 3,
    unless a force actuator drove the compliant mechanism there (docs/physics.md, "Beyond the
    rigid reach"), where the level reports the compliant pose with no deviation."""


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
    caps = backends.get(backend)
    if level in levels.LOADED and sensitivity and forces and level not in caps.force_sensitivities:
        others = backends.having(generated=True, force_sensitivities=level)
        raise InputError(
            f"the generated {caps.title} evaluators have no {level} sensitivities with force "
            f"actuators yet (actuator '{forces[0].name}')",
            file=mech.path,
            entry=f"[[actuator]] '{forces[0].name}'",
            hint="use --backend " + " or ".join(others),
        )
    # the generated evaluators take a force at loaded alone (the physical level they generate)
    # (stroke actuators at a level the backend does not hold: the level's own check refuses)
    if (forces and level not in caps.forces) or (
        not forces and level in caps.levels and level not in caps.actuators
    ):
        others = backends.having(**{"forces" if forces else "actuators": level})
        raise InputError(
            f"the generated {caps.title} evaluators do not take "
            + ("force actuators" if forces else "actuators")
            + f" yet (actuator '{(forces or [first])[0].name}')",
            file=mech.path,
            entry=entry,
            hint="use --backend " + " or ".join(others),
        )


def stroke_sensitivity(
    config: Configuration,
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
    mech = config.mechanism
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
    values = config.params

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


def stroke_angles(
    solver: MpmathEvaluator,
    config: Configuration,
    strokes: Sequence[sp.Expr],
    dps: int,
    compliant: bool,
    start: Mapping[str, mpmath.mpf] | None = None,
) -> dict[str, mpmath.mpf]:
    """The surrogate hinges' angles at which the actuators' points have moved by `strokes`
    along their lines of action, the input hinges beside them at `config`'s angles: in the
    rigid linkage, or (`compliant`) in the compliant mechanism at `config`'s level. The shared
    stroke solve (symkin.studies.stroke_solver) on a batch of one configuration at `dps` + 10
    digits, its rules at `dps` digits' ε (SOLVER.strokes.mpmath_rules)."""
    mech = config.mechanism
    if mech.is_structure:  # its force actuators are loads: no surrogate moves its rigid pose
        return {}
    names = [a.surrogate for a in mech.actuators]
    level = config.level if compliant else levels.get("paper")
    with mpmath.workdps(dps + 10):
        target = [mpmath.mpf(sp.N(s, dps + 10)) for s in strokes]
        values = config.params
        at = [
            [mpmath.mpf(sp.N(c.xreplace(values), dps + 10)) for c in a.at] for a in mech.actuators
        ]
        lines = [
            [mpmath.mpf(sp.N(c.xreplace(values), dps + 10)) for c in a.direction]
            for a in mech.actuators
        ]
        rules = SOLVER.strokes.mpmath_rules(dps)
        scale = max([abs(c) for xy in at for c in xy] + [abs(t) for t in target] + [rules["floor"]])
        first = dict(start) if start else dict.fromkeys(names, mpmath.mpf(0))

        def residual(trial: list[np.ndarray]) -> tuple[list[np.ndarray], None]:
            # each angle the double its dps + 10 digits round to, as an input given as text
            angles = {n: float(mpmath.nstr(v[0], dps + 10)) for n, v in zip(names, trial)}
            try:
                found = solver.values(config.with_angles(angles), dps + 10, level)
            except AssemblyError:  # past a toggle: the shared solve halves its step
                return [np.array([mpmath.nan], dtype=object) for _ in names], None
            out = []
            for a, xy, d, s in zip(mech.actuators, at, lines, target):
                rig, dev = found[a.point]
                pos = [rig[i] + (dev[i] if compliant else 0) for i in range(2)]
                r = d[0] * (pos[0] - xy[0]) + d[1] * (pos[1] - xy[1]) - s
                out.append(np.array([r], dtype=object))
            return out, None

        theta = [np.array([mpmath.mpf(first[n])], dtype=object) for n in names]
        # a start already met is polished too (the compliant solve starts at the rigid one's
        # angles without its Jacobian): as close to the strokes as the doubles allow
        solved, met, _, _ = _stroke_solve(residual, theta, rules, scale, fresh_polish=True)
        if bool(met[0]):
            return {n: v[0] for n, v in zip(names, solved)}
    raise ReachError(
        f"{mech.path}: no pose of the "
        + ("compliant mechanism" if compliant else "rigid linkage")
        + " reaches the strokes "
        + ", ".join(f"{a.name}={float(sp.N(s, 20)):g}" for a, s in zip(mech.actuators, strokes))
        + " (the surrogate hinges "
        + ", ".join(names)
        + " found no solution: past a toggle or the linkage's reach)"
    )


def reach_note(produced: Mapping[str, float]) -> str:
    """The `deviation_note` of a point whose rigid reference no pose of the rigid linkage
    reaches: the strokes the force actuators produced (docs/physics.md, "Beyond the rigid
    reach")."""
    strokes = ", ".join(f"{n}={v:.6g}" for n, v in produced.items())
    return (
        f"no pose of the rigid linkage reaches the stroke {strokes} the force produced (past a "
        "toggle or the linkage's reach): the compliant position is reported, no deviation"
    )
