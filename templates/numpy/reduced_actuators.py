"""symkin's numpy runtime for the `loaded` level with actuators (docs/physics.md, "Actuators at
loaded"): what a generated numpy module of a mechanism with actuators and the loaded level runs
around templates/numpy/reduced.py's driver. Only those modules hold it
(templates/numpy/module.py.j2), after the reduced-equilibrium runtime.
"""

import math

import numpy
from actuators import _action_places, _action_scale  # the module holds them all: actuators.py,
from reduced import _LoadedTables  # reduced.py, reduced_report.py, runtime.py and the shared
from reduced_report import _reduced_report
from runtime import _Mechanism, _points, _prepare, _rigid_angles, _wrap  # stroke solve

from symkin.studies.stroke_solver import _stroke_solve

# ---- symkin runtime: every generated module with actuators and the loaded level holds this ----

# symkin loaded-actuators runtime (templates/numpy/reduced_actuators.py): the rigid linkage at
# the strokes (the shared stroke solve on the surrogate angles), the reduced equilibrium with
# the surrogates free and the force actuators' forces after the rigid angles (reduced.py's
# _Batch keeps them through its continuation), and for a force actuator the rigid linkage at
# the stroke the force produced, which the deviations are taken against.


def _rigid_at(mech, kinematic, params):
    """The rigid linkage at the kinematic inputs (input hinges and surrogate angles, a dict of
    arrays): (x, theta, rigid points (2 per point), ok, parameters)."""
    arrays, p = _prepare(mech, kinematic, "loaded", params)
    ok = numpy.ones(arrays[0].shape, dtype=bool)
    for a in arrays:
        ok &= numpy.isfinite(a) & (numpy.abs(a) <= math.pi)
    x = [numpy.where(ok, a, 0.0) for a in arrays]
    with numpy.errstate(all="ignore"):
        theta, ok = _rigid_angles(mech, x, p, ok)
        rigid = [numpy.broadcast_to(v, ok.shape) for v in mech.rigid_points(theta, p)]
    return x, theta, rigid, ok, p


def _rigid_strokes(mech, actuators, hinges, strokes, params, start):
    """The surrogate angles at which the rigid point of action of every actuator has moved by
    its stroke along its line from its as-fabricated place (docs/levels.md, "Actuators"): the
    shared stroke solve (stroke_solver.py's _stroke_solve) from `start`; (angles, ok)."""
    surrogates = [a[1] for a in actuators]
    where = [mech.point_names.index(a[2]) for a in actuators]
    at = _action_places(mech, params)

    def residual(theta):
        _, _, rigid, ok, _ = _rigid_at(mech, hinges | dict(zip(surrogates, theta)), params)
        out = []
        for (_, _, _, d), i, x0, s in zip(actuators, where, at, strokes):
            r = d[0] * (rigid[2 * i] - x0[0]) + d[1] * (rigid[2 * i + 1] - x0[1]) - s
            out.append(numpy.where(ok, r, numpy.nan))  # NaN: the linkage does not assemble
        return out, None

    t, scale = mech.stroke_rules, _action_scale(mech, at)
    angles, ok, _, _ = _stroke_solve(residual, list(start), t, scale)
    return angles, ok


def _actuated_state(mech, actuators, forces, drives, inputs, params, resolve=False):
    """The loaded level with actuators solved (docs/physics.md, "Actuators at loaded"): the rigid
    linkage at the strokes (a force actuator's: 0), the reduced equilibrium there with the
    surrogates free (a stroke's force and a force's stroke solved for); a force actuator's
    reference is then the rigid linkage at the stroke the force produced (the compliant pose
    does not depend on the reference), with `resolve` the reduced equilibrium solved again
    against it (the sensitivities read its solution there). A dict of what it found."""
    if set(inputs) != set(drives):
        raise ValueError(f"inputs must be exactly {drives}, got {tuple(sorted(inputs))}")
    arrays = numpy.broadcast_arrays(*(numpy.asarray(inputs[n], dtype=mech.dtype) for n in drives))
    given = dict(zip(drives, arrays))
    names = [a[0] for a in actuators]
    surrogates = [a[1] for a in actuators]
    hinges = {n: v for n, v in given.items() if n not in names}
    shape = arrays[0].shape
    zero = numpy.zeros(shape, dtype=mech.dtype)
    strokes = [zero if n in forces else given[n] for n in names]
    start = [zero for _ in actuators]
    with numpy.errstate(all="ignore"):
        angles, ok_s = _rigid_strokes(mech, actuators, hinges, strokes, params, start)
    x, theta, _, ok, p = _rigid_at(mech, hinges | dict(zip(surrogates, angles)), params)
    ok = ok & ok_s
    loads = [numpy.broadcast_to(given[n], shape).astype(float) for n in forces]
    with numpy.errstate(all="ignore"):
        delta, q, ok = mech.loaded_solve(mech, x, list(theta) + loads, p, ok)
    for i, limit in mech.limits:
        ok = ok & (numpy.abs(theta[i]) <= limit)
    res = _points(mech, theta, delta, ok, "loaded", p, q, False)
    ok = res["ok"]
    # the surrogates' angles beyond the rigid (unknowns after the non-input hinges')
    tb = mech.loaded
    first, scales = len(mech.unknown_index), tb.variants[0][6]
    turned = [
        numpy.broadcast_to(q.x[first + k] * scales[first + k], shape) for k in range(len(names))
    ]
    index = {n: i for i, n in enumerate(mech.hinge_names)}
    compliant = list(theta)
    for j, i in enumerate(mech.unknown_index):
        compliant[i] = theta[i] + delta[j]
    for s, v in zip(surrogates, turned):
        compliant[index[s]] = theta[index[s]] + v
    state = {
        "given": given,
        "shape": shape,
        "ok": ok,
        "x": x,
        "theta": theta,
        "reference": theta,
        "loads": loads,
        "p": p,
        "q": q,
        "delta": delta,
        "turned": turned,
        "compliant": compliant,
        "res": res,
        "points": None,
    }
    if forces:
        # the stroke each force produced: its point of action's compliant place along d
        produced = []
        for n, (_, _, point, d), x0 in zip(names, actuators, _action_places(mech, params)):
            if n not in forces:
                produced.append(given[n])
                continue
            c = res["points"][point]["compliant"]
            produced.append(d[0] * (c[0] - x0[0]) + d[1] * (c[1] - x0[1]))
        with numpy.errstate(all="ignore"):
            angles, ok_f = _rigid_strokes(mech, actuators, hinges, produced, params, angles)
        x, reference, rigid, ok_r, _ = _rigid_at(
            mech, hinges | dict(zip(surrogates, angles)), params
        )
        # beyond the rigid reach (no rigid pose at the stroke a force produced): the compliant
        # pose stands, the reference and the deviations are NaN (docs/physics.md, "Beyond the
        # rigid reach"), "reference" False
        reach = numpy.broadcast_to(ok_f & ok_r, shape)
        reference = [numpy.where(reach, v, numpy.nan) for v in reference]
        rigid = [numpy.where(reach, v, numpy.nan) for v in rigid]
        state.update(ok=ok, reference=reference, rigid=rigid, reach=reach)
        if resolve:
            solved = ok
            with numpy.errstate(all="ignore"):
                delta, q, ok = mech.loaded_solve(mech, x, list(reference) + loads, p, ok & reach)
            state.update(ok=ok & reach, x=x, theta=reference, delta=delta, q=q, solved=solved)
    return state


def _actuated_loaded(
    mech,
    actuators,
    forces,
    drives,
    shown,
    inputs,
    params,
    links,
    report=False,
    buckling=True,
    springs=(),
):
    """The module's evaluate() at level "loaded" for a mechanism with actuators (docs/physics.md,
    "Actuators at loaded"; _actuated_state): the deviations against the rigid linkage at the
    strokes, a force actuator's at the stroke the force produced. With `report` (modules with
    the level's report), what it reports beyond the deviations (_actuated_report; with
    `buckling` its buckling factor too, where the file has loads or force actuators; `springs`
    the stroke actuators with a series spring, whose actual stroke it reports)."""
    st = _actuated_state(mech, actuators, forces, drives, inputs, params)
    out = _actuated_result(mech, actuators, st, shown, links, st["ok"])
    if report:
        # at the solution found (the reference only moves the deviations: what the level
        # reports is the compliant pose's; a force's stroke from the as-fabricated reference)
        theta = list(st["theta"]) + st["loads"]
        given = [st["given"][a[0]] for a in actuators]
        out.update(
            _actuated_report(
                mech, actuators, forces, theta, st["p"], st["q"], out["ok"], given, buckling
            )
        )
        for name, _, point, d in actuators:
            if name in springs:
                # the actual stroke: the command plus its point's deviation along d from the
                # rigid linkage at the command (d.dX = -force/spring)
                entry = out["actuators"][name]
                dev = st["res"]["points"][point]["deviation"]
                fixed = entry["stroke"]
                entry["stroke"] = fixed + d[0] * dev[0] + d[1] * dev[1]
                out["actuators"][name] = {"command": fixed} | entry
    return out


def _actuated_result(mech, actuators, st, shown, links, ok):
    """evaluate()'s dict from _actuated_state's `st`, NaN where not `ok`: the shown points and
    every hinge's angle (rigid: the reference; compliant) and, with `links`, every link's."""
    shape, theta, reference = st["shape"], st["theta"], st["reference"]
    res, delta = st["res"], st["delta"]
    points = {n: res["points"][n] for n in shown}
    if "rigid" in st:  # a force actuator's reference: the rigid linkage at its stroke
        for n in shown:
            i = mech.point_names.index(n)
            r = numpy.stack([st["rigid"][2 * i], st["rigid"][2 * i + 1]])
            c = res["points"][n]["compliant"]
            points[n] = {"rigid": r, "compliant": c, "deviation": c - r}
    # "reference" False where the compliant pose was solved but no pose of the rigid linkage
    # reaches the stroke a force produced (docs/generated-code.md)
    reach = st.get("reach", numpy.ones(shape, dtype=bool))
    out = {"points": {}, "ok": ok, "reference": ~(st.get("solved", ok) & ~reach)}
    for n, table in points.items():
        out["points"][n] = {key: numpy.where(ok, v, numpy.nan) for key, v in table.items()}
    out["angles"] = {
        kind: {
            h: numpy.where(ok, numpy.broadcast_to(v[i], shape), numpy.nan)
            for i, h in enumerate(mech.hinge_names)
        }
        for kind, v in (("rigid", reference), ("compliant", st["compliant"]))
    }
    out["links"] = {}  # as the other levels' (empty without `links`)
    if links and mech.links is not None:
        # each link's deviation: its rotation at the compliant angles (the surrogates turned)
        # less the reference's, plus the non-input hinges' deviation (computed directly)
        index = {n: i for i, n in enumerate(mech.hinge_names)}
        turned_theta = list(theta)
        for a, v in zip(actuators, st["turned"]):
            turned_theta[index[a[1]]] = theta[index[a[1]]] + v
        with numpy.errstate(all="ignore"):
            at_t = mech.links(turned_theta, delta)
            at_r = mech.links(reference, delta)
        m = len(mech.link_names)
        for i, name in enumerate(mech.link_names):
            dev = at_t[i] - at_r[i] + at_t[m + i]
            r = _wrap(numpy.broadcast_to(at_r[i], shape))
            # without a reference: the turned rotation itself
            turned_rot = _wrap(numpy.broadcast_to(at_t[i], shape)) + at_t[m + i]
            out["links"][name] = {
                "rigid": numpy.where(ok, r, numpy.nan),
                "compliant": numpy.where(ok, numpy.where(reach, r + dev, turned_rot), numpy.nan),
                "deviation": numpy.where(ok, numpy.broadcast_to(dev, shape), numpy.nan),
            }
    return out


def _actuated_report(mech, actuators, forces, theta, p, q, ok, given, buckling=True):
    """What the loaded level reports with actuators (reduced_reported.report): _reduced_report's
    "inputs", "stiffness", "plates" and (with `buckling`, where the file has loads or force
    actuators) "buckling", and "actuators": {A: {"stroke", "force", "stiffness"}}
    (file unit, N, N per file unit). The report routines' rows of the actuators (a stroke's
    force and dF/ds, a force's stroke and ds/dF) follow the input hinges' as the inputs' rows
    do: _reduced_report reads them as inputs named by their surrogate hinges, unscaled (theta:
    the rigid angles then the forces; `given`: each actuator's stroke or force as given)."""
    tb = mech.loaded
    rep = tb.report
    surrogates = tuple(a[1] for a in actuators)
    rows = _LoadedTables(**{**rep.__dict__, "inputs": rep.inputs + surrogates, "unit_scale": 1.0})
    view = _Mechanism(
        **{**mech.__dict__, "loaded": _LoadedTables(**{**tb.__dict__, "report": rows})}
    )
    out = _reduced_report(view, theta, p, q, ok, buckling)
    found = out["inputs"]
    scale = rep.unit_scale  # the input hinges' moments in N m, as _reduced_report's
    out["inputs"] = {
        h: {
            "angle": found[h]["angle"],
            "moment": found[h]["moment"] * scale,
            "stiffness": found[h]["stiffness"] * scale,
        }
        for h in rep.inputs
    }
    out["actuators"] = {}
    for (name, surrogate, _, _), fixed in zip(actuators, given):
        value, rate = found[surrogate]["moment"], found[surrogate]["stiffness"]
        fixed = numpy.where(ok, fixed, numpy.nan)
        if name in forces:
            with numpy.errstate(divide="ignore"):
                entry = {
                    "stroke": value,
                    "force": fixed,
                    "stiffness": numpy.where(rate != 0, 1 / rate, math.inf),
                }
        else:
            entry = {"stroke": fixed, "force": value, "stiffness": rate}
        out["actuators"][name] = entry
    return out
