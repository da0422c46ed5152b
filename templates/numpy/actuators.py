"""symkin's numpy runtime for actuators (docs/levels.md, "Actuators"): what a generated numpy
module of a mechanism with stroke actuators runs around templates/numpy/runtime.py's _evaluate.
Only those modules hold it (templates/numpy/module.py.j2), after the runtime.
"""

import numpy
from runtime import _evaluate  # the module holds both: templates/numpy/runtime.py's

# ---- symkin runtime: every generated module holds what follows ----

# symkin actuators runtime (templates/numpy/actuators.py): the strokes to the surrogate hinges'
# angles, twice (the rigid linkage and the compliant mechanism), then one evaluate at each.


def _actuated(mech, actuators, drives, shown, inputs, level, params, links):
    """The module's evaluate() for a mechanism driven by stroke actuators (docs/levels.md,
    "Actuators"): each actuator's surrogate hinge takes the angle at which the rigid point of
    action has moved by the stroke along its line, and separately the angle at which the
    compliant point has (Newton's method, its Jacobian by central differences); the deviation
    is compliant - rigid, each at its own angles: the rigid motion between them plus the
    level's deviation at the compliant ones."""
    if level not in mech.levels or level not in ("paper", "first_order", "exact"):
        kinematic = tuple(n for n in mech.levels if n in ("paper", "first_order", "exact"))
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
    rest = _evaluate(mech, dict.fromkeys(mech.input_names, zero), "paper", params, False)["points"]
    at = [rest[a[2]]["rigid"] for a in actuators]
    eps = numpy.finfo(mech.dtype).eps
    scale = max([float(numpy.nanmax(numpy.abs(x))) for x in at] + [1e-300])
    tol = 64 * eps * scale
    step = numpy.sqrt(eps)

    def residual(theta, lv, kind):
        res = _evaluate(mech, hinges | dict(zip(surrogates, theta)), lv, params, False)
        out = []
        for (_, _, point, d), x0, s in zip(actuators, at, strokes):
            r = res["points"][point][kind]
            out.append(d[0] * (r[0] - x0[0]) + d[1] * (r[1] - x0[1]) - s)
        return out

    def solve(theta, lv, kind):
        k = len(theta)
        for _ in range(40):
            r = residual(theta, lv, kind)
            done = numpy.all([numpy.abs(x) <= tol for x in r], axis=0)
            if numpy.all(done | numpy.isnan(r[0])):
                return theta, done
            jac = numpy.empty(numpy.shape(r[0]) + (k, k), dtype=mech.dtype)
            for j in range(k):
                up = residual([t + step * (i == j) for i, t in enumerate(theta)], lv, kind)
                down = residual([t - step * (i == j) for i, t in enumerate(theta)], lv, kind)
                for i in range(k):
                    jac[..., i, j] = (up[i] - down[i]) / (2 * step)
            with numpy.errstate(all="ignore"):
                rhs = numpy.stack(r, axis=-1)[..., None]
                move = numpy.linalg.solve(jac, rhs)[..., 0] if k > 1 else rhs[..., 0] / jac[..., 0]
            theta = [t - numpy.where(done, 0, move[..., j]) for j, t in enumerate(theta)]
        r = residual(theta, lv, kind)
        return theta, numpy.all([numpy.abs(x) <= tol for x in r], axis=0)

    start = [zero + numpy.asarray(s) * 0 for s in strokes]
    rigid, ok_r = solve(start, "paper", "rigid")
    compliant, ok_c = solve(rigid, level, "compliant")
    ev_r = _evaluate(mech, hinges | dict(zip(surrogates, rigid)), level, params, links)
    ev_c = _evaluate(mech, hinges | dict(zip(surrogates, compliant)), level, params, links)
    ok = ev_r["ok"] & ev_c["ok"] & ok_r & ok_c
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
