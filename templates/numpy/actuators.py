"""symkin's numpy runtime for actuators (docs/levels.md, "Actuators"): what a generated numpy
module of a mechanism with stroke actuators runs around templates/numpy/runtime.py's _evaluate.
Only those modules hold it (templates/numpy/module.py.j2), after the runtime.
"""

import math

import numpy
from runtime import _evaluate, _prepare, _rigid_angles, _sensitivity_full, _solve  # runtime.py

from symkin.studies.stroke_solver import _stroke_solve  # and the stroke solve (shared)

# ---- symkin runtime: every generated module holds what follows ----

# symkin actuators runtime (templates/numpy/actuators.py): the strokes to the surrogate hinges'
# angles, twice (the rigid linkage and the compliant mechanism) by the stroke solve above
# (symkin/studies/stroke_solver.py's _stroke_solve), its evaluations the answer's.


def _action_places(mech, params):
    """Each actuator's point of action as fabricated, (x, y), from the parameters alone (the
    module's action_at): where its stroke is measured from. Not the pose at zero inputs, which
    an input folded into the routines (derive --fix) would move."""
    flat = mech.action_at([mech.dtype(v) for v in mech.parameters(params)])
    return [(flat[2 * i], flat[2 * i + 1]) for i in range(len(flat) // 2)]


def _action_scale(mech, at):
    """The stroke solves' scale: the largest coordinate of the points of action as fabricated,
    that at least the module's floor."""
    sizes = [float(numpy.nanmax(numpy.abs(numpy.asarray(c, dtype=float)))) for xy in at for c in xy]
    return max(sizes + [mech.stroke_rules["floor"]])


def _stroke_keep(mask, new, old):
    """The evaluation `new` where `mask`, else `old` (evaluate()'s nested dicts of arrays)."""
    if isinstance(new, dict):
        return {key: _stroke_keep(mask, v, old[key]) for key, v in new.items()}
    return numpy.where(mask, new, old)


def _stroke_poses(mech, actuators, drives, inputs, level, params, links=False):
    """The kinematic inputs at which the rigid linkage and the compliant mechanism meet the
    strokes (docs/levels.md, "Actuators"): (rigid, compliant, ok, ev_r, ev_c), rigid and
    compliant each a dict of the input hinges and the surrogate hinges' angles, ev_r and ev_c
    evaluate() at `level` there (with `links`). The shared stroke solve (stroke_solver.py's
    _stroke_solve) elementwise over the input arrays: the rigid linkage's from the
    as-fabricated pose, then the compliant mechanism's from the rigid one's angles and
    Jacobian; its first and last evaluations are the answer's, nothing is evaluated twice."""
    kinematic = tuple(n for n in mech.levels if n in ("paper", "first_order", "exact"))
    if level not in kinematic:
        raise ValueError(f"with actuators, level must be one of {kinematic}, got {level!r}")
    if set(inputs) != set(drives):
        raise ValueError(f"inputs must be exactly {drives}, got {tuple(sorted(inputs))}")
    arrays = numpy.broadcast_arrays(*(numpy.asarray(inputs[n], dtype=mech.dtype) for n in drives))
    given = dict(zip(drives, arrays))
    names = [a[0] for a in actuators]
    hinges = {n: v for n, v in given.items() if n not in names}
    strokes = [given[n] for n in names]
    surrogates = [a[1] for a in actuators]
    zero = numpy.zeros_like(arrays[0]) if arrays else mech.dtype(0)
    at = _action_places(mech, params)
    scale = _action_scale(mech, at)
    where = [mech.point_names.index(a[2]) for a in actuators]

    def rigid_residual(theta):
        # the rigid linkage alone (every level's rigid positions), as _pose solves it
        arrays, p = _prepare(mech, hinges | dict(zip(surrogates, theta)), level, params)
        ok = numpy.ones(arrays[0].shape, dtype=bool)
        for a in arrays:
            ok &= numpy.isfinite(a) & (numpy.abs(a) <= math.pi)
        angles, ok = _rigid_angles(mech, [numpy.where(ok, a, 0.0) for a in arrays], p, ok)
        for i, limit in mech.limits:
            ok = ok & (numpy.abs(angles[i]) <= limit)
        xy = mech.rigid_points(angles, p)
        out = []
        for (_, _, _, d), i, x0, s in zip(actuators, where, at, strokes):
            r = d[0] * (xy[2 * i] - x0[0]) + d[1] * (xy[2 * i + 1] - x0[1]) - s
            out.append(numpy.where(ok, r, numpy.nan))  # NaN: the linkage does not assemble
        return out, None

    def residual(theta):
        res = _evaluate(mech, hinges | dict(zip(surrogates, theta)), level, params, links)
        out = []
        for (_, _, point, d), x0, s in zip(actuators, at, strokes):
            r = res["points"][point]["compliant"]
            out.append(d[0] * (r[0] - x0[0]) + d[1] * (r[1] - x0[1]) - s)
        return out, res

    start = [zero + numpy.asarray(s) * 0 for s in strokes]
    t = mech.stroke_rules
    with numpy.errstate(all="ignore"):
        rigid, ok_r, jac, _ = _stroke_solve(rigid_residual, start, t, scale)
        first = residual(rigid)
        compliant, ok_c, _, ev_c = _stroke_solve(
            residual, rigid, t, scale, jac=jac, keep=_stroke_keep, first=first
        )
    return (
        hinges | dict(zip(surrogates, rigid)),
        hinges | dict(zip(surrogates, compliant)),
        ok_r & ok_c,
        first[1],
        ev_c,
    )


def _actuated(mech, actuators, drives, shown, inputs, level, params, links):
    """The module's evaluate() for a mechanism driven by stroke actuators (docs/levels.md,
    "Actuators"): each actuator's surrogate hinge takes the angle at which the rigid point of
    action has moved by the stroke along its line, and separately the angle at which the
    compliant point has (_stroke_poses); the deviation is compliant - rigid, each at its own
    angles: the rigid motion between them plus the level's deviation at the compliant ones."""
    _, _, ok, ev_r, ev_c = _stroke_poses(mech, actuators, drives, inputs, level, params, links)
    ok = ev_r["ok"] & ev_c["ok"] & ok
    out = {"points": {}, "ok": ok}
    for n in shown:
        r, c = ev_r["points"][n], ev_c["points"][n]
        out["points"][n] = {
            "rigid": r["rigid"],
            "compliant": c["compliant"],
            "deviation": c["rigid"] - r["rigid"] + c["deviation"],
        }
    out["angles"] = {"rigid": ev_r["angles"]["rigid"], "compliant": ev_c["angles"]["compliant"]}
    if "links" in ev_c:
        out["links"] = {
            n: {
                "rigid": ev_r["links"][n]["rigid"],
                "compliant": c["compliant"],
                "deviation": c["rigid"] - ev_r["links"][n]["rigid"] + c["deviation"],
            }
            for n, c in ev_c["links"].items()
        }
    for table in out["points"].values():
        for key, v in table.items():
            table[key] = numpy.where(ok, v, numpy.nan)
    return out


def _actuated_sensitivity(mech, actuators, drives, shown, inputs, level, params):
    """The module's sensitivity_full() with actuators (docs/sensitivity.md, "Actuators"): the
    implicit-function theorem on the strokes. Each surrogate angle v solves g(v, y) = d.(X(v, y)
    - X0(y)) - s = 0, X the point of action (rigid, or rigid + deviation), X0 its as-fabricated
    place, so dv/dy = -(dg/dv)^-1 dg/dy for every parameter, input hinge and stroke y; the
    derivatives at fixed kinematic inputs come from sensitivity_full at the two poses."""
    rigid, compliant, ok, _, _ = _stroke_poses(mech, actuators, drives, inputs, level, params)
    names = [a[0] for a in actuators]
    surrogates = [a[1] for a in actuators]
    k = len(actuators)
    at_r = _sensitivity_full(mech, rigid, level, params)
    at_c = _sensitivity_full(mech, compliant, level, params)
    zero = dict.fromkeys(mech.input_names, numpy.zeros_like(rigid[surrogates[0]]))
    rest = _sensitivity_full(mech, zero, level, params)["rigid"]
    ok = ok & at_r["ok"] & at_c["ok"]
    params_ = list(mech.parameter_names)
    hinges = [n for n in drives if n not in names]
    variables = [("params", q) for q in params_] + [("inputs", h) for h in hinges]

    def part(table, point, kind, name):
        return numpy.asarray(table[point][kind][name])

    def moved(res, point, kind, name, compliant_):
        out = part(res["rigid"], point, kind, name)
        return out + part(res["deviation"], point, kind, name) if compliant_ else out

    def dot(d, v):
        return d[0] * v[0] + d[1] * v[1]

    def surrogate_rates(res, compliant_):
        """dv/dy of every surrogate by every variable, then by every stroke: a row-major list."""
        jac = [
            dot(d, moved(res, point, "inputs", v, compliant_))
            for (_, _, point, d) in actuators
            for v in surrogates
        ]
        rhs = []
        for a, (_, _, point, d) in enumerate(actuators):
            for kind, y in variables:
                g = dot(d, moved(res, point, kind, y, compliant_))
                if kind == "params":  # the as-fabricated point of action moves too
                    g = g - dot(d, part(rest, point, kind, y))
                rhs.append(-g)
            # dg_a/ds_b = -1 when a = b
            rhs += [numpy.full(ok.shape, float(a == b), dtype=mech.dtype) for b in range(k)]
        return _solve(jac, rhs, numpy.array(ok), len(variables) + k, mech.dtype)

    with numpy.errstate(all="ignore"):
        rate_r, good_r = surrogate_rates(at_r, False)
        rate_c, good_c = surrogate_rates(at_c, True)
    ok = ok & good_r & good_c
    m = len(variables) + k
    out = {"points": {}, "deviation": {}, "rigid": {}}
    for n in shown:
        rig, dev = {"params": {}, "inputs": {}}, {"params": {}, "inputs": {}}
        for j, (kind, y) in enumerate(variables + [("inputs", a) for a in names]):
            stroke = j >= len(variables)
            r = 0 if stroke else moved(at_r, n, kind, y, False)
            c = 0 if stroke else moved(at_c, n, kind, y, True)
            for i, v in enumerate(surrogates):
                r = r + moved(at_r, n, "inputs", v, False) * rate_r[i * m + j]
                c = c + moved(at_c, n, "inputs", v, True) * rate_c[i * m + j]
            rig[kind][y] = numpy.where(ok, r, numpy.nan)
            dev[kind][y] = numpy.where(ok, c - r, numpy.nan)
        out["rigid"][n] = {"params": rig["params"], "inputs": {h: rig["inputs"][h] for h in drives}}
        out["deviation"][n] = {
            "params": dev["params"],
            "inputs": {h: dev["inputs"][h] for h in drives},
        }
        r, c = at_r["points"][n], at_c["points"][n]
        out["points"][n] = {
            "rigid": numpy.where(ok, r["rigid"], numpy.nan),
            "compliant": numpy.where(ok, c["compliant"], numpy.nan),
            "deviation": numpy.where(ok, c["rigid"] - r["rigid"] + c["deviation"], numpy.nan),
        }
    out["angles"] = {"rigid": at_r["angles"]["rigid"], "compliant": at_c["angles"]["compliant"]}
    out["ok"] = ok
    return out
