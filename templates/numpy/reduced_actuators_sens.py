"""symkin's numpy runtime for the `loaded` level's sensitivities with actuators
(docs/sensitivity.md, "Actuators"; symkin.studies.mpmath_sensitivity's _stroke_columns): what a
generated numpy module with actuators, the loaded level and sensitivities runs. Only those
modules hold it (templates/numpy/module.py.j2), after templates/numpy/reduced_actuators.py.
"""

import numpy
from reduced_actuators import _actuated_result, _actuated_state  # the module holds them all
from reduced_sens import _reduced_rates
from runtime import _chained, _rigid_rates, _solve

# ---- symkin runtime: every generated module with actuators and loaded sensitivities holds it ----


def _actuated_loaded_sensitivity(mech, actuators, forces, drives, shown, inputs, params):
    """The module's sensitivity_full() at level "loaded" with actuators: the reduced
    equilibrium's rates by the parameters, the kinematic inputs (the surrogate angles among
    them) and the forces (_reduced_rates), carried to the drives through each surrogate angle
    theta_v of the reference. A stroke's solves g = d.(X_a(theta) - X_a(0)) - s = 0 (the rigid
    linkage at the stroke), a force's c = d.dX_a = 0 (the rigid linkage at the stroke the force
    produced), so dtheta_v/dy = -(d(g, c)/dtheta_v)^-1 d(g, c)/dy for every parameter, input
    hinge, stroke and force y; then dD/dy = dD/dy + dD/dtheta_v dtheta_v/dy, as the rigid."""
    st = _actuated_state(mech, actuators, forces, drives, inputs, params, resolve=True)
    shape, theta, p, dtype = st["shape"], st["theta"], st["p"], mech.dtype
    ok = numpy.array(st["ok"])
    npar, nv, nf = len(mech.parameter_names), mech.n_variables, len(forces)
    names = [a[0] for a in actuators]
    hinges = [n for n in drives if n not in names]
    column = {h: npar + i for i, h in enumerate(mech.input_names)} | {
        f: nv + j for j, f in enumerate(forces)
    }
    user = {n: npar + j for j, n in enumerate(drives)}
    ny = npar + len(drives)
    zero = numpy.zeros(shape, dtype=dtype)
    with numpy.errstate(all="ignore"):
        rig, thu, ok = _rigid_rates(mech, theta, p, ok)
        # the as-fabricated points of action move with the parameters too
        rest, _, ok = _rigid_rates(mech, [zero for _ in theta], p, ok)
        rig = numpy.concatenate([rig, numpy.zeros(rig.shape[:-1] + (nf,), dtype=dtype)], -1)
        dev = _reduced_rates(mech, list(theta) + st["loads"], p, st["q"], thu, ok, nf)
        dev = dev.astype(dtype)
        jac, rhs = [], []
        for name, _, point, d in actuators:
            r = 2 * mech.point_names.index(point)
            stroke = name not in forces
            table = rig if stroke else dev

            def along(c, table=table, r=r, d=d):
                return d[0] * table[..., r, c] + d[1] * table[..., r + 1, c]

            jac += [along(column[a[1]]) for a in actuators]
            row = [zero] * ny
            for c in range(npar):
                row[c] = along(c)
                if stroke:
                    row[c] = row[c] - d[0] * rest[..., r, c] - d[1] * rest[..., r + 1, c]
            for h in hinges:
                row[user[h]] = along(column[h])
            if stroke:
                row[user[name]] = zero - 1.0
            else:
                for f in forces:
                    row[user[f]] = along(column[f])
            rhs += [-v for v in row]
        rates, good = _solve(jac, rhs, ok, ny, dtype)
        ok = ok & good
        totals = []
        for m in (dev, rig):
            out = numpy.zeros(m.shape[:-1] + (ny,), dtype=dtype)
            out[..., :npar] = m[..., :npar]
            for n in hinges + list(forces):
                out[..., user[n]] = m[..., column[n]]
            for b, a in enumerate(actuators):
                for c in range(ny):
                    out[..., c] += m[..., column[a[1]]] * rates[b * ny + c][..., None]
            totals.append(out)
        dev, rig = totals
        _chained(mech, p, dev, rig)
    ok = ok & numpy.isfinite(dev).all(axis=(-1, -2)) & numpy.isfinite(rig).all(axis=(-1, -2))
    result = _actuated_result(mech, actuators, st, shown, False, ok)

    def table(m, i):
        rows = numpy.where(ok[..., None, None], m[..., 2 * i : 2 * i + 2, :], numpy.nan)
        rows = numpy.moveaxis(numpy.moveaxis(rows, -1, 0), -1, 1)  # (variable, 2, *shape)
        return {
            "params": {q: rows[c] for c, q in enumerate(mech.parameter_names)},
            "inputs": {n: rows[user[n]] for n in drives},
        }

    index = {n: mech.point_names.index(n) for n in shown}
    result["deviation"] = {n: table(dev, index[n]) for n in shown}
    result["rigid"] = {n: table(rig, index[n]) for n in shown}
    return result
