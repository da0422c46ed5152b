"""symkin's numpy runtime for the `loaded` level's sensitivities (docs/sensitivity.md;
symkin.physics.reduced_sensitivity): the implicit-function theorem on the reduced equilibrium at
the solution templates/numpy/reduced.py found, over the mechanism's loaded_sens<g> and
plate_eps4 routines, as templates/c/reduced_sens.c. Only modules with the level and
sensitivities hold it (templates/numpy/module.py.j2), after templates/numpy/reduced.py.
"""

import numpy
from reduced import _red_block, _red_column, _red_solutions  # the module holds them: reduced.py

# ---- symkin runtime: every generated module with the loaded level's sensitivities holds it ----


def _reduced_rates(mech, theta, p, q, thu, ok, forces=0):
    """dev (*shape, 2 n_P, n_v) of the loaded level at its solutions (q: the variant solved and
    its x, templates/numpy/reduced.py); thu dtheta_u/dv (*shape, k, n_v), None without; with
    `forces` (the force actuators': theta's last entries) n_v + forces columns, theirs last. J is
    evaluated once more at the solution, then dx/dv = -J^-1 dR/dv at fixed x and
    dD/dv = dD/dx dx/dv + dD/dtheta dtheta/dv + dD/dp + dD/dout dout/dv (reduced_sens.c)."""
    tb = mech.loaded
    shape = ok.shape
    npar, nv, m = len(mech.parameter_names), mech.n_variables + forces, mech.n_theta
    npt = 2 * len(mech.point_names)
    dev = numpy.full((ok.size, npt, nv), numpy.nan)
    good = numpy.broadcast_to(ok, shape).reshape(-1)
    routines = [fn for fn, _ in tb.sens]
    for where, solver, s, jac, jo, ins, dins, rel in _red_solutions(
        mech, theta, p, q, shape, good, routines
    ):
        blocks = tb.sens[solver.count - 1][1]
        b, n, ns = where.size, solver.size, solver.plates
        # dtheta/dv of every hinge: the non-input ones' from the rigid closure, an input's own 1
        dth = numpy.zeros((b, m + forces, nv))
        if thu is not None:
            tu = numpy.broadcast_to(thu, shape + thu.shape[-2:]).reshape(-1, *thu.shape[-2:])
            for j, i in enumerate(mech.unknown_index):
                dth[:, i, : mech.n_variables] = tu[where, j]
        for j, i in enumerate(mech.input_index):
            dth[:, i, npar + j] = 1.0
        for j in range(forces):
            dth[:, m + j, mech.n_variables + j] = 1.0
        # the relation's partials by (theta_c, p, f, e_a, e_s), 3 x 5 per half plate
        part = numpy.zeros((b, 3 * ns, 5 * ns))
        dinx = numpy.zeros((b, 5 * ns, n))
        d = numpy.array(dins).reshape(3 * ns, n, b) if ns and n else numpy.zeros((3 * ns, n, b))
        for k in range(ns):
            eps = [_red_column(v, b) for v in tb.eps4(ins[5 * k : 5 * k + 5])]
            for i in range(3):
                for c in range(3):
                    part[:, 3 * k + i, 5 * k + c] = rel[k][3 + 3 * i + c]
                part[:, 3 * k + i, 5 * k + 3] = eps[2 * i]
                part[:, 3 * k + i, 5 * k + 4] = eps[2 * i + 1]
            dinx[:, 5 * k : 5 * k + 3] = d[3 * k : 3 * k + 3].transpose(2, 0, 1)

        def by_v(theta_block, p_block):
            out = numpy.matmul(_red_block(s, blocks[theta_block], b), dth)
            out[:, :, :npar] += _red_block(s, blocks[p_block], b)
            return out

        din = by_v("din_dtheta", "din_dp")
        dout = numpy.matmul(part, din)
        rhs = by_v("dR_dtheta", "dR_dp") + numpy.matmul(jo, dout)
        dx = numpy.full((b, n, nv), numpy.nan)
        for c in range(b):
            try:
                dx[c] = -numpy.linalg.solve(jac[c], rhs[c]) if n else dx[c]
            except numpy.linalg.LinAlgError:
                continue  # singular: NaN
        dout = dout + numpy.matmul(part, numpy.matmul(dinx, dx))
        dev[where] = (
            numpy.matmul(_red_block(s, blocks["dD_dx"], b), dx)
            + by_v("dD_dtheta", "dD_dp")
            + numpy.matmul(_red_block(s, blocks["dD_dout"], b), dout)
        )
    return dev.reshape(shape + (npt, nv))
