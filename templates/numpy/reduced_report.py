"""symkin's numpy runtime for what the `loaded` level reports beyond the deviations
(docs/physics.md, "What loaded reports"; symkin.physics.reduced_reported): every input's moment
and dM/dtheta and every point's 3 x 3 stiffness by the implicit-function theorem on the reduced
equilibrium at the solution templates/numpy/reduced.py found (the mechanism's loaded_report<g>
routines), every plate's largest normal stress by integrating the plate from its end loads with
RK4. Only modules with the level's loaded_report<g> routines hold it
(templates/numpy/module.py.j2), after templates/numpy/reduced.py.
"""

import math

import numpy
from reduced import _red_block, _red_column, _red_solutions  # the module holds them all
from runtime import _blocks, _points, _pose, _prepare

# ---- symkin runtime: every generated module with the loaded level's report holds it ----

#: Sections per plate where the stress is sampled (symkin.physics.reported.SECTIONS), one RK4
#: step each (against the Python path's Taylor series: 5e-12 of the stress, tests/
#: test_loaded_reported_codegen.py).
_STRESS_SECTIONS = 64
#: A point's scaled compliance this ill-conditioned is singular (reported.SINGULAR): NaN.
_SINGULAR = 1e12


def _evaluate_reported(mech, inputs, level, params, links, report=True):
    """The module's evaluate() (runtime.py's _evaluate) with, at the loaded level and with
    `report`, what it reports beyond the deviations: "inputs", "stiffness", "plates"
    (_reduced_report)."""
    arrays, p = _prepare(mech, inputs, level, params)
    return _blocks(_reported_block, arrays, mech, level, p, links, report)


def _reported_block(arrays, mech, level, p, links, report):
    """evaluate() on one block of broadcast input arrays (runtime.py's _evaluate_block), the
    report added at the loaded level."""
    theta, delta, ok, q = _pose(mech, arrays, level, p, links)
    result = _points(mech, theta, delta, ok, level, p, q, links)
    if report and mech.levels[level].loaded:
        result.update(_reduced_report(mech, theta, p, q, result["ok"]))
    return result


def _plate_stress(k0, lx, ly, ea, es, slender, modulus, limit, has_limit):
    """Largest normal stress (Pa), its strain, the safety factor (NaN without an allowable
    stress) and where along the plate (0..1), per configuration ((b,) arrays): the plate's IVP
    psi'' = -f_Q (1 + (e_a - e_s) f_N), psi(0) = 0, psi'(0) = k0 (symkin.physics.beams) by
    fixed-step RK4, the strain |psi'| t/(2l) + |f_N| (t/l)^2/12 at every section and the
    parabola's vertex through the three samples around an interior maximum
    (symkin.physics.reported.plate_stress)."""
    d = ea - es

    def rate(psi, om):
        c, s = numpy.cos(psi), numpy.sin(psi)
        return om, -(ly * c - lx * s) * (1 + d * (lx * c + ly * s))

    n = _STRESS_SECTIONS
    h = 1.0 / n
    psi, om = numpy.zeros_like(k0), numpy.array(k0, dtype=float)
    psis, oms = [psi], [om]
    for _ in range(n):
        a1, b1 = rate(psi, om)
        a2, b2 = rate(psi + h / 2 * a1, om + h / 2 * b1)
        a3, b3 = rate(psi + h / 2 * a2, om + h / 2 * b2)
        a4, b4 = rate(psi + h * a3, om + h * b3)
        psi = psi + h / 6 * (a1 + 2 * a2 + 2 * a3 + a4)
        om = om + h / 6 * (b1 + 2 * b2 + 2 * b3 + b4)
        psis.append(psi)
        oms.append(om)
    psi, om = numpy.array(psis), numpy.array(oms)  # (n + 1, b)
    normal = lx * numpy.cos(psi) + ly * numpy.sin(psi)
    strain = numpy.abs(om) * slender / 2 + numpy.abs(normal) * slender**2 / 12
    b = k0.shape[0]
    j = numpy.argmax(strain, axis=0)
    cols = numpy.arange(b)
    value = strain[j, cols]
    where = j / n
    inner = (j > 0) & (j < n)
    ja, jc = numpy.clip(j - 1, 0, n), numpy.clip(j + 1, 0, n)
    sa, sc = strain[ja, cols], strain[jc, cols]
    bend = sa - 2 * value + sc
    vertex = inner & (bend < 0)
    with numpy.errstate(all="ignore"):
        shift = (sa - sc) / (2 * bend)
        value = numpy.where(vertex, value - (sa - sc) * shift / 4, value)
        where = numpy.where(vertex, (j + shift) / n, where)
        stress = modulus * value
        safety = numpy.where(stress > 0, limit / stress, math.inf)
    safety = numpy.where(has_limit, safety, numpy.nan)
    return stress, value, safety, where


def _reduced_report(mech, theta, p, q, ok):
    """What the loaded level reports at its solutions (q: the variant solved and its x,
    templates/numpy/reduced.py), NaN where not ok: {"inputs": {H: {"angle", "moment",
    "stiffness"}}, "stiffness": {P: (3, 3, *shape)}, "plates": {H: {"stress", "strain",
    "safety", "section"}}} (N m, N m/rad; the stiffness in the file's length unit; Pa)."""
    tb = mech.loaded
    rep = tb.report
    shape = ok.shape
    nin, npt, npl = len(rep.inputs), len(rep.points), len(rep.plates)
    size = ok.size
    ys = numpy.full((size, nin + 3 * npt), numpy.nan)
    rates = numpy.full((size, nin + 3 * npt, nin + 3 * npt), numpy.nan)
    stress = numpy.full((size, npl, 8), numpy.nan)
    good = numpy.broadcast_to(ok, shape).reshape(-1)
    routines = [fn for fn, _ in rep.routines]
    for where, solver, out, jac, jo, _, dins, rel in _red_solutions(
        mech, theta, p, q, shape, good, routines
    ):
        blocks = rep.routines[solver.count - 1][1]
        b, n, ns = where.size, solver.size, solver.plates
        # the plate relation's partials by (theta_c, p, f), block diagonal
        part = numpy.zeros((b, 3 * ns, 3 * ns))
        for k in range(ns):
            for i in range(3):
                for c in range(3):
                    part[:, 3 * k + i, 3 * k + c] = rel[k][3 + 3 * i + c]
        dinx = numpy.zeros((b, 3 * ns, n))
        if ns and n:
            dinx = numpy.array([_red_column(v, b) for v in dins]).reshape(3 * ns, n, b)
            dinx = dinx.transpose(2, 0, 1)
        dr_v = _red_block(out, blocks["dR_dv"], b)
        din_v = _red_block(out, blocks["din_dv"], b)
        dy_o = _red_block(out, blocks["dy_dout"], b)
        by_o = numpy.matmul(dy_o, part)
        total = _red_block(out, blocks["dy_dv"], b) + numpy.matmul(by_o, din_v)
        if n:
            rhs = dr_v + numpy.matmul(jo, numpy.matmul(part, din_v))
            try:
                dx = -numpy.linalg.solve(jac, rhs)
            except numpy.linalg.LinAlgError:
                # one singular J stops the stacked solve: each on its own
                dx = numpy.full(rhs.shape, numpy.nan)
                for c in range(b):
                    try:
                        dx[c] = -numpy.linalg.solve(jac[c], rhs[c])
                    except numpy.linalg.LinAlgError:
                        continue  # singular: NaN
            dy_x = _red_block(out, blocks["dy_dx"], b) + numpy.matmul(by_o, dinx)
            total = total + numpy.matmul(dy_x, dx)
        ys[where] = _red_block(out, blocks["y"], b)[:, :, 0]
        rates[where] = total
        stress[where] = _red_block(out, blocks["stress"], b)
    ok_flat = good
    result = {"inputs": {}, "stiffness": {}, "plates": {}}
    angles = {name: theta[i] for name, i in zip(mech.hinge_names, range(len(theta)))}

    def shaped(v):
        return numpy.where(ok_flat, v, numpy.nan).reshape(shape)

    for k, name in enumerate(rep.inputs):
        result["inputs"][name] = {
            "angle": numpy.where(ok, numpy.broadcast_to(angles[name], shape), numpy.nan),
            "moment": shaped(ys[:, k] * rep.unit_scale),
            "stiffness": shaped(rates[:, k, k] * rep.unit_scale),
        }
    big_l, big_f = rep.L, rep.F
    norm = numpy.array([big_f / big_l, big_f / big_l, big_f])[:, None] * numpy.array(
        [1, 1, 1 / big_l]
    )
    for k, name in enumerate(rep.points):
        rows = slice(nin + 3 * k, nin + 3 * k + 3)
        c = rates[:, rows, rows]
        live = ok_flat & numpy.all(numpy.isfinite(c), axis=(1, 2)) & (not rep.frame[k])
        stiff = numpy.full((size, 3, 3), numpy.nan)
        if live.any():
            cond = numpy.linalg.cond(c[live] * norm)
            keep = numpy.flatnonzero(live)[cond <= _SINGULAR]
            if keep.size:
                stiff[keep] = numpy.linalg.inv(c[keep])
        result["stiffness"][name] = numpy.moveaxis(stiff, 0, -1).reshape((3, 3) + shape)
    for k, name in enumerate(rep.plates):
        row = [stress[:, k, c] for c in range(8)]
        live = numpy.flatnonzero(ok_flat)
        values = [numpy.full(size, numpy.nan) for _ in range(4)]
        if live.size:
            found = _plate_stress(*(v[live] for v in row), rep.limits[k])
            for v, f in zip(values, found):
                v[live] = f
        result["plates"][name] = {
            key: shaped(v) for key, v in zip(("stress", "strain", "safety", "section"), values)
        }
    return result
