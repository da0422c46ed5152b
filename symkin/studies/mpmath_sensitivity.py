"""The `sympy` backend's sensitivities (docs/sensitivity.md): total derivatives of every point's
deviation and rigid position by every parameter and input, by the implicit-function theorem on
the closures (symkin.kinematics.sensitivity) evaluated in mpmath at a solved configuration of
symkin.studies.mpmath_evaluator; at `loaded`, on its reduced equilibrium
(symkin.physics.reduced_sensitivity), by the actuators' strokes and forces where they drive."""

from __future__ import annotations

import mpmath
import numpy as np
import sympy as sp

from ..codegen.backends.numpy.kernels import float64_namespace
from ..core import levels
from ..core.errors import AssemblyError, InputError
from ..physics import reduced, reduced_sensitivity
from .mpmath_evaluator import MpmathEvaluator, State
from .results import Sensitivity


def of(ev: MpmathEvaluator, state: State, answer: reduced.Answer | None = None) -> Sensitivity:
    """Total derivatives by the implicit-function theorem on the closures
    (symkin.sensitivity), in mpmath; at `loaded`, on its reduced equilibrium (`answer`)."""
    from ..kinematics import sensitivity

    an, kin = ev.an, ev.kin
    if not an.points:
        return Sensitivity({}, {}, {}, {})
    terms = sensitivity.of(an)
    args, values = ev.arguments(state)
    level = state.level

    def matrix(key: str, expr: sp.Matrix):
        if not expr.rows or not expr.cols:
            return mpmath.zeros(expr.rows, expr.cols)
        return mpmath.matrix(ev.fn(f"sens:{key}", expr.tolist(), args)(*values))

    def solve(m, rhs):
        try:
            cols = [mpmath.lu_solve(m, rhs.column(j)) for j in range(rhs.cols)]
        except ZeroDivisionError:
            raise AssemblyError(
                f"{ev.mechanism.path}: the mechanism is at a toggle "
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
        total_d = mpmath.matrix(_loaded_rates(ev, state, answer, theta_v).tolist())
    else:
        total_d = _level_rates(ev, state, terms, matrix, solve, theta_v)
    chain = ev.fn(
        "sens:chain",
        sensitivity.parameter_chain([p.expr for p in ev.mechanism.parameters], an.params).tolist(),
        args,
    )(*values)
    n_p = len(an.params)
    inputs = [kin.hinges[a].name for a in kin.inputs]
    by_strokes = bool(ev.mechanism.actuators) and level in levels.LOADED
    if by_strokes:
        # by the strokes instead of the surrogates' angles (at `loaded`; the kinematic
        # levels' are carried over by _stroke_sensitivity, which reads the surrogates')
        assert answer is not None
        forces = len(answer.solver.given) if answer.solver else 0
        if forces:  # the rigid positions do not read the forces (nor a structure's strokes)
            total_r = total_r.T.tolist() + [[0] * total_r.rows for _ in range(forces)]
            total_r = mpmath.matrix(total_r).T
        to_drives = _stroke_columns(ev, state, total_r, total_d, answer)
        total_d, total_r = total_d * to_drives, total_r * to_drives
        inputs, nv = list(ev.mechanism.drives), to_drives.cols

    def per_point(m) -> list:
        cols = [[(m[2 * i, j], m[2 * i + 1, j]) for i in range(len(an.points))] for j in range(nv)]
        cols[:n_p] = sensitivity.total(cols[:n_p], chain)
        return [[cols[j][i] for j in range(nv)] for i in range(len(an.points))]

    names = [p.name for p in an.points]
    found = Sensitivity.from_columns(
        names,
        [p.name for p in ev.mechanism.parameters],
        inputs,
        per_point(total_d),
        per_point(total_r),
    )
    if not by_strokes:
        return found
    hidden = {a.point for a in ev.mechanism.actuators}
    return Sensitivity(
        *({p: row for p, row in table.items() if p not in hidden} for table in vars(found).values())
    )


def _stroke_columns(ev: MpmathEvaluator, state: State, total_r, total_d, answer: reduced.Answer):
    """d(parameters, kinematic inputs, forces)/d(parameters, drives) at `loaded`
    (docs/sensitivity.md, "Actuators"): each actuator's surrogate angle θ_v of the rigid
    reference solves, for a stroke, g = d·(X_a(θ) − a) − s = 0 (the rigid linkage at the
    stroke) and, for a force, c = d·ΔX_a = 0 (the reference at the stroke the force
    produced), so dθ_v/dy = −(∂(g, c)/∂θ_v)⁻¹ ∂(g, c)/∂y for every parameter (partial: the
    chain follows), input hinge, stroke and force y. `total_r` and `total_d` the rigid
    positions' and the deviations' rates by (parameters, kinematic inputs, forces), the
    actuators' hidden points among them."""
    an, kin, mech = ev.an, ev.kin, ev.mechanism
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
    column |= {name: n_p + n_in + j for j, name in enumerate(red.given)}
    params = list(an.params)
    args = [*an.params, *an.thetas]
    at = [*state.pvals, *(state.theta[a] for a in sorted(state.theta))]
    acted = red.acted(answer.x, answer.theta)
    out = mpmath.zeros(n_p + n_in + len(red.given), n_p + len(drives))
    for c in range(n_p):
        out[c, c] = 1
    for name in hinges:
        out[column[labels[name]], user[name]] = 1
    for name in red.given:
        out[column[name], user[name]] = 1
    if mech.is_structure:  # its rigid reference stays as fabricated: no surrogate angle moves
        return out
    jac, rhs = mpmath.zeros(k, k), mpmath.zeros(k, n_p + len(drives))
    for i, act in enumerate(acts):
        exprs = [*act.direction, *act.at]
        exprs += [sp.diff(e, q) for e in exprs for q in params]
        got = ev.fn(f"stroke:{act.name}", exprs, params)(*state.pvals)
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
            x = ev.fn(f"rigid(theta):{act.point}", list(an.point_rigid(act.point)), args)(*at)
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


def _level_rates(ev: MpmathEvaluator, state: State, terms, matrix, solve, theta_v):
    """dΔR/dv at a kinematic level (partial by the parameters: no chain yet)."""
    level, k = state.level, len(ev.kin.unknowns)
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


def _loaded_rates(ev: MpmathEvaluator, state: State, answer: reduced.Answer, theta_v) -> np.ndarray:
    """dΔR/dv at `loaded` from its solution (symkin.physics.reduced_sensitivity)."""
    an, kin = ev.an, ev.kin
    _fixed_notches(ev)
    if ev.loaded_terms is None:
        # float64 kernels: the solution is float64 (as the solver's, symkin.physics.reduced)
        ev.loaded_terms = reduced_sensitivity.LoadedSensitivity(
            an, lambda: [float64_namespace(), "math"]
        )
    red = answer.solver
    assert red is not None
    npar = len(an.params)
    theta_u = np.array(theta_v.tolist(), dtype=float).reshape(len(kin.unknowns), -1)
    # the force actuators' forces (a structure's strokes): beside θ, a column each
    rates = reduced_sensitivity.theta_rates(an, theta_u, npar, kin.inputs, len(red.given))
    return ev.loaded_terms.rates(
        answer.x,
        red.scale,
        answer.segments,
        answer.theta,
        [float(v) for v in state.pvals],
        rates,
    )


def _fixed_notches(ev: MpmathEvaluator) -> None:
    """`loaded`'s reduced equilibrium takes a notch's EI₀, EA, κGA and relation terms as numbers
    at the file's values (symkin.physics.reduced): its derivatives by a parameter that a
    notch's key reads would miss that key's share, so they are refused (exit 2, naming the
    hinge and the parameters; docs/sensitivity.md)."""
    mech = ev.mechanism
    free = {p.symbol for p in mech.parameters}
    for h in mech.hinges:
        if not h.is_plate or h.profile == "uniform":
            continue
        keys = {k: getattr(h, k) for k in ("length", "thickness", "width", "E", "nu")}
        keys.update(dict(h.profile_params))
        for key, value in keys.items():
            found = sp.sympify(value).free_symbols & free if value is not None else set()
            if found:
                raise InputError(
                    "the loaded level's sensitivities take a notch's section as numbers: its "
                    f"{key} reads the parameter(s) {', '.join(sorted(map(str, found)))}",
                    file=mech.path,
                    line=h.line,
                    entry=f"[[hinge]] '{h.name}'",
                    hint="give the notch's keys as numbers, or ask for the sensitivities at "
                    "--level exact (docs/sensitivity.md)",
                )
