"""symkin's numpy runtime for what the `loaded` level reports beyond the deviations
(docs/physics.md, "What loaded reports"; symkin.physics.reduced_reported): every input's moment
and dM/dtheta and every point's 3 x 3 compliance and stiffness by the implicit-function theorem
on the reduced equilibrium at the solution templates/numpy/reduced.py found (the mechanism's
loaded_report<g> routines), every plate's largest normal stress by integrating the plate from
its end loads with RK4. Only modules with the level's loaded_report<g> routines hold it
(templates/numpy/module.py.j2), after templates/numpy/reduced.py.
"""

import math

import numpy
from reduced import _Batch, _red_block, _red_rates, _red_solutions  # the module holds them all
from runtime import _blocks, _points, _pose, _prepare

from symkin.physics.reduced_solver import _red_buckling
from symkin.physics.stiffness_rule import _stiffness_compliance

# ---- symkin runtime: every generated module with the loaded level's report holds it ----

# Its rules (symkin.core.settings.LoadedSettings) are the loaded tables' (mech.loaded): sections,
# the stress samples per plate, one RK4 step each (against the Python path's Taylor series:
# 5e-12 of the stress, tests/test_loaded_reported_codegen.py); singular, a point's scaled
# compliance this ill-conditioned is singular (its K or C NaN: stiffness_rule.py's rule);
# buckling_*, the buckling search (reduced_solver.py's _red_buckling).


def _evaluate_reported(mech, inputs, level, params, links, report=True, buckling=True):
    """The module's evaluate() (runtime.py's _evaluate) with, at the loaded level and with
    `report`, what it reports beyond the deviations: "inputs", "stiffness", "compliance",
    "plates" and, with loads and `buckling`, "buckling" (_reduced_report)."""
    arrays, p = _prepare(mech, inputs, level, params)
    return _blocks(_reported_block, arrays, mech, level, p, links, (report, buckling))


def _reported_block(arrays, mech, level, p, links, report):
    """evaluate() on one block of broadcast input arrays (runtime.py's _evaluate_block), the
    report added at the loaded level (report: (report, buckling))."""
    report, buckling = report
    theta, delta, ok, q = _pose(mech, arrays, level, p, links)
    result = _points(mech, theta, delta, ok, level, p, q, links)
    if report and mech.levels[level].loaded:
        result.update(_reduced_report(mech, theta, p, q, result["ok"], buckling))
    return result


def _turn(fn, fq, d):
    """The end load's components along and across the plate (fn, fq) once it turns on by d, by
    the angle-sum rule: cos d and sin d by their Taylor series where |d| <= 0.03 (the terms left
    out below 2e-18 of them; an RK4 stage turns psi by h times its rate), libm's elsewhere
    (element by element: a configuration's numbers do not depend on its batch). As
    templates/c/reduced_report.c's sk_rep_turn."""
    d2 = d * d
    d4 = d2 * d2
    cd = (1 - d2 * (1 / 2)) + d4 * ((1 / 24 - d2 * (1 / 720)) + d4 * (1 / 40320))
    sd = d * ((1 - d2 * (1 / 6)) + d4 * (1 / 120 - d2 * (1 / 5040)))
    big = ~(numpy.abs(d) <= 0.03)
    if big.any():
        cd[big], sd[big] = numpy.cos(d[big]), numpy.sin(d[big])
    return fn * cd + fq * sd, fq * cd - fn * sd


def _plate_stress(k0, lx, ly, ea, es, slender, modulus, limit, has_limit, sections):
    """Largest normal stress (Pa), its strain, the safety factor (NaN without an allowable
    stress) and where along the plate (0..1), per configuration ((b,) arrays): the plate's IVP
    psi'' = -f_Q (1 + (e_a - e_s) f_N), psi(0) = 0, psi'(0) = k0 (symkin.physics.beams) by
    fixed-step RK4 over `sections` sections, the load's components f_N = lx cos psi + ly sin psi
    and f_Q = ly cos psi - lx sin psi carried from stage to stage by the angle-sum rule (_turn:
    no libm call where the turns are small), the strain |psi'| t/(2l) + |f_N| (t/l)^2/12 at
    every section and the parabola's vertex through the three samples around an interior maximum
    (symkin.physics.reported.plate_stress)."""
    d = ea - es
    n = sections
    h = 1.0 / n
    fn, fq = numpy.array(lx, dtype=float), numpy.array(ly, dtype=float)
    om = numpy.array(k0, dtype=float)
    normals, oms = [fn], [om]
    for _ in range(n):
        b1 = -fq * (1 + d * fn)
        n2, q2 = _turn(fn, fq, h / 2 * om)
        a2 = om + h / 2 * b1
        b2 = -q2 * (1 + d * n2)
        n3, q3 = _turn(fn, fq, h / 2 * a2)
        a3 = om + h / 2 * b2
        b3 = -q3 * (1 + d * n3)
        n4, q4 = _turn(fn, fq, h * a3)
        a4 = om + h * b3
        b4 = -q4 * (1 + d * n4)
        fn, fq = _turn(fn, fq, h / 6 * (om + 2 * a2 + 2 * a3 + a4))
        om = om + h / 6 * (b1 + 2 * b2 + 2 * b3 + b4)
        normals.append(fn)
        oms.append(om)
    normal, om = numpy.array(normals), numpy.array(oms)  # (n + 1, b)
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


def _reduced_report(mech, theta, p, q, ok, buckling=True):
    """What the loaded level reports at its solutions (q: the variant solved and its x,
    templates/numpy/reduced.py), NaN where not ok: {"inputs": {H: {"angle", "moment",
    "stiffness"}}, "stiffness": {P: (3, 3, *shape)}, "compliance": {P: (3, 3, *shape)},
    "plates": {H: {"stress", "strain", "safety", "section"}}} (N m, N m/rad; the stiffness and
    compliance in the file's length unit, NaN where they do not exist; Pa) and,
    when the file has loads (or force actuators) and with `buckling`, "buckling": the factor on
    them at which the tangent stiffness becomes singular (inf: none up to 10; _red_buckling)."""
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
        b = where.size
        rates[where] = _red_rates(solver, out, blocks, jac, jo, dins, rel, b)
        ys[where] = _red_block(out, blocks["y"], b)[:, :, 0]
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
    scales = numpy.array([rep.F / rep.L, rep.F / rep.L, rep.F]), numpy.array([1, 1, 1 / rep.L])
    result["compliance"] = {}
    for k, name in enumerate(rep.points):
        rows = slice(nin + 3 * k, nin + 3 * k + 3)
        c = numpy.zeros((size, 3, 3)) if rep.frame[k] else rates[:, rows, rows]
        stiff, comp = _stiffness_compliance(c, scales, tb.singular)
        stiff[~ok_flat] = comp[~ok_flat] = numpy.nan
        result["stiffness"][name] = numpy.moveaxis(stiff, 0, -1).reshape((3, 3) + shape)
        result["compliance"][name] = numpy.moveaxis(comp, 0, -1).reshape((3, 3) + shape)
    for k, name in enumerate(rep.plates):
        row = [stress[:, k, c] for c in range(8)]
        live = numpy.flatnonzero(ok_flat)
        values = [numpy.full(size, numpy.nan) for _ in range(4)]
        if live.size:
            found = _plate_stress(*(v[live] for v in row), rep.limits[k], tb.sections)
            for v, f in zip(values, found):
                v[live] = f
        result["plates"][name] = {
            key: shaped(v) for key, v in zip(("stress", "strain", "safety", "section"), values)
        }
    if buckling and tb.loads:
        result["buckling"] = shaped(_red_bucklings(mech, theta, p, q, shape, good))
    return result


def _red_bucklings(mech, theta, p, q, shape, good):
    """The buckling factor (_red_buckling) of every configuration the loaded level solved
    (good: a flat mask of them), variant by variant on the variant's own solver as
    _red_solutions groups them; a flat array, NaN elsewhere."""
    tb = mech.loaded
    variant = numpy.broadcast_to(q.variant, shape).reshape(-1)
    out = numpy.full(variant.size, numpy.nan)

    def flat(values, where):
        return [numpy.broadcast_to(v, shape).reshape(-1)[where].astype(float) for v in values]

    for index, variant_row in enumerate(tb.variants):
        where = numpy.flatnonzero(good & (variant == index))
        if not where.size:
            continue
        solver = _Batch(tb, variant_row, index + 1)
        x = numpy.array(flat(q.x[: solver.size], where)).reshape(solver.size, where.size)
        with numpy.errstate(all="ignore"):
            out[where] = _red_buckling(solver, x, flat(theta, where), flat(p, where))
    return out
