"""symkin's numpy runtime for the stress of notch hinges at the `loaded` level (docs/physics.md,
"Notch hinges at `loaded`"): reduced_report.py's report with every notch's largest normal
stress from the shot of its section under the same end loads, times its K_t
(symkin.physics.reported.section_stress: symkin.physics.section_beams' float RK4 on the same
grid). Only modules with notches and the level's report hold it (templates/numpy/module.py.j2),
after templates/numpy/reduced_report.py and reduced_notch.py: it redefines _reduced_report,
which the runtimes call by name.
"""

import math

import numpy
from reduced import _red_block, _red_solutions  # the module holds them all
from reduced_report import _reduced_report

# ---- symkin runtime: every generated module with the loaded report on notches holds it ----

_red_uniform_report = _reduced_report


def _notch_stress(k0, lx, ly, notch, modulus, limit, has_limit):
    """A notch's largest normal stress (Pa), its strain, the safety factor (NaN without an
    allowable stress) and where along it (0..1), per configuration ((b,) arrays of the report's
    loads in units of the relation's EI): the shot psi' = a mu, mu' = -f_Q (1 + (eps - gam) f_N)
    by RK4 on the section's grid in its variable v, the strain |mu| a T/(2l) + |f_N| axial at the
    nodes, times K_t (symkin.physics.section_beams.shoot_profile, reported.section_stress)."""
    _, _, _, _, kt, ratio, grid, length = notch
    a, eps, gam, depth, axial, ds, nodes = (
        grid[k] for k in ("a", "eps", "gam", "depth", "axial", "ds", "nodes")
    )
    k0, lx, ly = k0 * ratio, lx * ratio, ly * ratio  # in units of the grid's EI0
    steps = (len(ds) - 1) // 2
    h = 1.0 / steps

    def rates(psi, mu, k):
        c, s = numpy.cos(psi), numpy.sin(psi)
        fn = lx * c + ly * s
        fq = ly * c - lx * s
        along = 1 + (eps[k] - gam[k]) * fn
        return a[k] * mu * ds[k], -fq * along * ds[k]

    def strain(psi, mu, k):
        fn = lx * numpy.cos(psi) + ly * numpy.sin(psi)
        return numpy.abs(mu) * a[k] * depth[k] / (2 * length) + numpy.abs(fn) * axial[k]

    psi, mu = k0 * 0, k0 + k0 * 0
    best, where = strain(psi, mu, 0), numpy.zeros(k0.shape)
    for j in range(steps):
        k = 2 * j
        p1, m1 = rates(psi, mu, k)
        p2, m2 = rates(psi + h / 2 * p1, mu + h / 2 * m1, k + 1)
        p3, m3 = rates(psi + h / 2 * p2, mu + h / 2 * m2, k + 1)
        p4, m4 = rates(psi + h * p3, mu + h * m3, k + 2)
        psi = psi + h / 6 * (p1 + 2 * p2 + 2 * p3 + p4)
        mu = mu + h / 6 * (m1 + 2 * m2 + 2 * m3 + m4)
        value = strain(psi, mu, k + 2)
        larger = value > best
        best = numpy.where(larger, value, best)
        where = numpy.where(larger, nodes[j + 1], where)
    value = best * kt
    stress = modulus * value
    with numpy.errstate(all="ignore"):
        safety = numpy.where(stress > 0, limit / stress, math.inf)
    safety = numpy.where(has_limit, safety, numpy.nan)
    return stress, value, safety, where


def _reduced_report(mech, theta, p, q, ok, buckling=True):
    """reduced_report.py's report, every notch's stress from its section's shot (its end loads
    from the loaded_report<g> routine's stress block, as there)."""
    result = _red_uniform_report(mech, theta, p, q, ok, buckling)
    tb = mech.loaded
    rep = tb.report
    shape = ok.shape
    stress = numpy.full((ok.size, len(rep.plates), 8), numpy.nan)
    good = numpy.broadcast_to(ok, shape).reshape(-1)
    routines = [fn for fn, _ in rep.routines]
    for where, solver, out, *_ in _red_solutions(mech, theta, p, q, shape, good, routines):
        stress[where] = _red_block(out, rep.routines[solver.count - 1][1]["stress"], where.size)
    live = numpy.flatnonzero(good)
    for k, name in enumerate(rep.plates):
        notch = tb.notches[k]
        if notch is None:
            continue
        values = [numpy.full(ok.size, numpy.nan) for _ in range(4)]
        if live.size:
            row = stress[live, k]
            found = _notch_stress(
                row[:, 0], row[:, 1], row[:, 2], notch, row[:, 6], row[:, 7], rep.limits[k]
            )
            for v, f in zip(values, found):
                v[live] = f
        result["plates"][name] = {
            key: numpy.where(good, v, numpy.nan).reshape(shape)
            for key, v in zip(("stress", "strain", "safety", "section"), values)
        }
    return result
