"""symkin's numpy runtime for the `loaded` level's sensitivities (docs/sensitivity.md;
symkin.physics.reduced_sensitivity): the implicit-function theorem on the reduced equilibrium at
the solution templates/numpy/reduced.py found, over the mechanism's loaded_sens<g> and
plate_eps4 routines, by the theorem the Python path runs (symkin/physics/reduced_rates.py, which
the module holds before this text), as templates/c/reduced_sens.c. Only modules with the level and
sensitivities hold it (templates/numpy/module.py.j2), after templates/numpy/reduced.py.
"""

import numpy
from reduced import _red_block, _red_solutions  # the module holds them: reduced.py

from symkin.physics.reduced_rates import _red_sensitivity, _red_theta_v

# ---- symkin runtime: every generated module with the loaded level's sensitivities holds it ----


def _reduced_rates(mech, theta, p, q, thu, ok, forces=0):
    """dev (*shape, 2 n_P, n_v) of the loaded level at its solutions (q: the variant solved and
    its x, templates/numpy/reduced.py); thu dtheta_u/dv (*shape, k, n_v), None without; with
    `forces` (the force actuators': theta's last entries) n_v + forces columns, theirs last. J is
    evaluated once more at the solution, then the shared implicit-function theorem
    (reduced_rates.py's _red_sensitivity; reduced_sens.c)."""
    tb = mech.loaded
    shape = ok.shape
    npar, nv = len(mech.parameter_names), mech.n_variables
    npt = 2 * len(mech.point_names)
    dev = numpy.full((ok.size, npt, nv + forces), numpy.nan)
    good = numpy.broadcast_to(ok, shape).reshape(-1)
    tu = None
    if thu is not None:
        tu = numpy.broadcast_to(thu, shape + thu.shape[-2:]).reshape(-1, *thu.shape[-2:])
    routines = [fn for fn, _ in tb.sens]
    for where, solver, s, jac, jo, ins, dins, rel in _red_solutions(
        mech, theta, p, q, shape, good, routines
    ):
        b = where.size
        blocks = {k: _red_block(s, v, b) for k, v in tb.sens[solver.count - 1][1].items()}
        # dtheta/dv of every hinge: the non-input ones' from the rigid closure, an input's own 1
        dth = _red_theta_v(
            None if tu is None else tu[where],
            b,
            mech.n_theta,
            nv,
            npar,
            mech.unknown_index,
            mech.input_index,
            forces,
        )
        parts = [r[3:] for r in rel]
        eps = [tb.eps4(ins[5 * k : 5 * k + 5]) for k in range(solver.plates)]
        dev[where] = _red_sensitivity(jac, jo, parts, eps, dins, dth, npar, blocks)
    return dev.reshape(shape + (npt, nv + forces))
