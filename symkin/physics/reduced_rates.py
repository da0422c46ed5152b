"""The `loaded` level's rates, written once for Python (docs/sensitivity.md; docs/physics.md,
"What loaded reports"): the implicit-function theorem on the reduced equilibrium R(x, θ, p) = 0
at a solution x, the plates' relation outputs o = rel(i) of their inputs i(x, v) through the
chain rule. What `loaded` reports (symkin.physics.reduced's Reduced.reported, the natural
frequencies' compliance) and its sensitivities (symkin.physics.reduced_sensitivity) run it on a
batch of one configuration; every generated numpy module with the level holds the text below the
marker verbatim (symkin.codegen.templating.shared; templates/numpy/reduced.py and reduced_sens.py
give it the generated routines' blocks), so it imports only numpy. The C runtime's twins are
templates/c/reduced_report.c and reduced_sens.c. The tests' references (tests/reference_*.py) do
not read it.

Every function works on b configurations at once, each on its own: a matrix is a (b, rows, cols)
array, a scalar entry a number or a (b,) array. With v the variables differentiated by:

    dx/dv = −J⁻¹ (∂R/∂v + ∂R/∂o ∂rel/∂i ∂i/∂v)
    dy/dv = (∂y/∂x + ∂y/∂o ∂rel/∂i ∂i/∂x) dx/dv + ∂y/∂v + ∂y/∂o ∂rel/∂i ∂i/∂v

the `∂/∂v` at fixed x and o; for the sensitivities v are the parameters, then the inputs, then
the force actuators' forces, and ∂/∂v = ∂/∂θ dθ/dv + ∂/∂p (θ every hinge's rigid angle).
"""

import numpy

# ---- symkin runtime: every generated module with the loaded level holds what follows ----

# symkin loaded-level rates (symkin/physics/reduced_rates.py, shared with the Python path): the
# implicit-function theorem at the reduced equilibrium's solutions; all configurations at once,
# each on its own.


def _red_relation(parts, eps, b):
    """∂rel/∂i, block diagonal: per half plate its relation's partials by (θ_c, p, f) (parts[k]:
    9 entries, row-major), (b, 3 n_s, 3 n_s); with eps (eps[k]: the partials by (ε_a, ε_s), 3 × 2
    row-major) beside them, (b, 3 n_s, 5 n_s)."""
    ns, width = len(parts), 3 if eps is None else 5
    out = numpy.zeros((b, 3 * ns, width * ns))
    for k in range(ns):
        for i in range(3):
            for c in range(3):
                out[:, 3 * k + i, width * k + c] = parts[k][3 * i + c]
            if eps is not None:
                out[:, 3 * k + i, width * k + 3] = eps[k][2 * i]
                out[:, 3 * k + i, width * k + 4] = eps[k][2 * i + 1]
    return out


def _red_inputs_x(dins, n, ns, b, width):
    """∂i/∂x (b, width n_s, n) from the half plates' (θ_c, p, f) by x (dins: 3 n_s × n entries,
    row-major); with width 5 the rows of (ε_a, ε_s) are zero: they do not move with x."""
    out = numpy.zeros((b, width * ns, n))
    if ns and n:
        rows = [numpy.broadcast_to(numpy.asarray(v, dtype=float), (b,)) for v in dins]
        d = numpy.array(rows).reshape(3 * ns, n, b).transpose(2, 0, 1)
        for k in range(ns):
            out[:, width * k : width * k + 3] = d[:, 3 * k : 3 * k + 3]
    return out


def _red_dx(jac, rhs, each):
    """−J⁻¹ rhs per configuration (jac (b, n, n), rhs (b, n, k)); with `each` NaN where J is
    singular, else numpy's LinAlgError."""
    try:
        return -numpy.linalg.solve(jac, rhs)
    except numpy.linalg.LinAlgError:
        if not each:
            raise
        # one singular J stops the stacked solve: each on its own
        out = numpy.full(rhs.shape, numpy.nan)
        for c in range(rhs.shape[0]):
            try:
                out[c] = -numpy.linalg.solve(jac[c], rhs[c])
            except numpy.linalg.LinAlgError:
                continue  # singular: NaN
        return out


def _red_implicit(jac, jo, block, dins_x, dr_by, dins_by, dy_x, dy_o, dy_by, each=True):
    """dy/dv (b, rows, n_v) by the module docstring's formulas: `jac` J (b, n, n), `jo` ∂R/∂o,
    `block` ∂rel/∂i (_red_relation), `dins_x` ∂i/∂x (_red_inputs_x); the `_by` arguments the
    partial derivatives by v (x and o held), `dy_x`, `dy_o` y's by x and o. `each`: see _red_dx."""
    by_o = numpy.matmul(dy_o, block)
    total = dy_by + numpy.matmul(by_o, dins_by)
    if jac.shape[-1]:
        rhs = dr_by + numpy.matmul(jo, numpy.matmul(block, dins_by))
        dx = _red_dx(jac, rhs, each)
        total = total + numpy.matmul(dy_x + numpy.matmul(by_o, dins_x), dx)
    return total


def _red_theta_v(thu, b, m, nv, npar, unknown_index, input_index, forces):
    """dθ/dv (b, m + forces, nv + forces) of every hinge's rigid angle (label order; then the
    force actuators' forces) by the parameters and the inputs (nv of them, the parameters first),
    then the forces: the non-input hinges' rows (unknown_index) from the rigid closure (thu
    (b, k, nv); None: none), an input's own angle (input_index) moving by 1, a held one's by
    nothing, a force by 1."""
    out = numpy.zeros((b, m + forces, nv + forces))
    if thu is not None:
        for j, i in enumerate(unknown_index):
            out[:, i, :nv] = thu[:, j]
    for j, i in enumerate(input_index):
        out[:, i, npar + j] = 1.0
    for j in range(forces):
        out[:, m + j, nv + j] = 1.0
    return out


def _red_by_v(d_theta, d_p, theta_v, npar):
    """A block's partial derivative by v at fixed x and o: ∂/∂θ dθ/dv plus ∂/∂p in the
    parameters' columns."""
    out = numpy.matmul(d_theta, theta_v)
    out[:, :, :npar] += d_p
    return out


def _red_sensitivity(jac, jo, parts, eps, dins, theta_v, npar, blocks, each=True):
    """dD/dv (b, 2 n_P, n_v) of the points' deviations at the solutions (docs/sensitivity.md):
    `jac` J, `jo` ∂R/∂o, the half plates' relation partials (parts, eps: _red_relation's) and
    (θ_c, p, f) by x (dins: _red_inputs_x's), dθ/dv (_red_theta_v), and the loaded_sens
    routine's blocks by name (b, rows, cols): dR_dtheta, dR_dp, din_dtheta, din_dp, dD_dx,
    dD_dtheta, dD_dp, dD_dout. `each`: see _red_dx."""
    b, n = jac.shape[0], jac.shape[-1]
    return _red_implicit(
        jac,
        jo,
        _red_relation(parts, eps, b),
        _red_inputs_x(dins, n, len(parts), b, 5),
        _red_by_v(blocks["dR_dtheta"], blocks["dR_dp"], theta_v, npar),
        _red_by_v(blocks["din_dtheta"], blocks["din_dp"], theta_v, npar),
        blocks["dD_dx"],
        blocks["dD_dout"],
        _red_by_v(blocks["dD_dtheta"], blocks["dD_dp"], theta_v, npar),
        each,
    )
