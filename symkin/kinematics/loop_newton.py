"""The kinematic levels' Newton, written once for Python (symkin.core.settings, rules 1-3;
docs/numerics.md, "When Newton stops"): the Newton driver with its stopping rule (a step
relative to the unknowns, the stall test, the residual at the rounding level of its terms), the
continuation from the as-fabricated pose and the refusals (a singular or non-finite step, no
stop within the cap). symkin.studies.mpmath_evaluator (the `sympy` backend, one configuration in
mpmath numbers at 40 digits) solves with it, and every generated numpy module holds the text
below the marker verbatim (symkin.codegen.templating.shared; templates/numpy/runtime.py runs it
over element arrays), so it imports only numpy and math. The C runtime's twin is
templates/c/runtime.c (sk_newton_solve, sk_newton_stop, sk_continuation). The tests' references
(tests/reference_*.py) do not read it.

The functions take an *arithmetic* ``ar``, what differs between the two:

- ``ar.solve(a, b, ok)``: the solution of a x = b (a row-major k*k list, b a list of k) as a
  list of k, and where it is good (a mask; never good where `ok` is not);
- ``ar.where(mask, a, b)``: a where the mask holds, else b;
- ``ar.largest(values)``: the largest magnitude of a list of values (NaN if one is NaN);
- ``ar.full(ok, value)``: `value` wherever `ok` is defined.

Values are element arrays (numpy: one configuration per element, each on its own, so a
configuration's answer does not depend on its batch) or numbers (mpmath: one configuration);
masks are numpy booleans (arrays, or numpy.bool_ for numbers: ``~`` negates both).
"""

import math

import numpy

# ---- symkin runtime: every generated module holds what follows ----

# symkin loop Newton (symkin/kinematics/loop_newton.py, shared with the Python path): the
# Newton driver with its stopping rule and the continuation of the kinematic levels, over an
# arithmetic (_Arith: element arrays of the module's dtype).


class _Rule:
    """When a Newton iteration stops (symkin.core.settings): after `iterations` steps at most,
    and once a step is at most `tolerance`, or at most `converged` times the largest unknown
    (with converged > 0; a step onto all-zero unknowns goes on), or has stalled at
    rounding: at least `stall_ratio` times the previous step and at most `stalled` times the
    largest unknown; with `residual` > 0, also once every residual is at most `residual` times
    the size of its terms (symkin.core.settings, 3b). The numbers: SOLVER.loop_rules."""

    def __init__(
        self, iterations, tolerance=0.0, converged=0.0, stalled=0.0, stall_ratio=0.0, residual=0.0
    ):
        self.iterations, self.tolerance, self.converged = iterations, tolerance, converged
        self.stalled, self.stall_ratio, self.residual = stalled, stall_ratio, residual


def _newton_stop(rule, change, size, previous, noise=False):
    """Where Newton stops after a step `change` (largest entry), the unknowns now at most `size`
    in magnitude, the previous step `previous` (inf before the second), `noise` where the
    residuals were at rounding (_residual_noise): the one stopping test of every Newton
    iteration."""
    done = numpy.logical_or(change <= rule.tolerance, noise)
    if rule.converged > 0.0:
        done = done | (change <= rule.converged * size)
    # 0 * inf is nan (a rule without the stall test, before the second step): the comparison is
    # then false, as in C, and numpy need not warn about it
    with numpy.errstate(invalid="ignore"):
        stalled = (change >= rule.stall_ratio * previous) & (change <= rule.stalled * size)
    return done | stalled


def _residual_noise(out, x, scale, residual):
    """Where every residual out[r] of a system (f, then its row-major Jacobian J) at x is at the
    rounding level of its terms: |f_r| <= residual (scale_r + sum_j |J_rj x_j|)."""
    k = len(x)
    noise = True
    for r in range(k):
        terms = abs(scale[r]) + sum(abs(out[k + r * k + j] * x[j]) for j in range(k))
        noise = noise & (abs(out[r]) <= residual * terms)
    return noise


def _newton_solve(ar, system, x, index, ok, rule, evaluated=None, scale=None):
    """Newton on `system` (x -> its residual f, then its row-major Jacobian, as one list) from
    the list x, stepping the unknowns x[i] for i in `index`, each configuration until `rule`
    stops it; `evaluated`: the system at x, when it is known; `scale` (with rule.residual > 0,
    index covering x): the size of each residual's constant terms. Returns x, ok (False where a
    step is singular or not finite: the refusal) and where Newton stopped (not stopped within
    rule.iterations steps: the other refusal)."""
    k = len(index)
    active = ok.copy()
    previous = ar.full(ok, math.inf)
    out = evaluated
    for _ in range(rule.iterations):
        if out is None:
            out = system(x)
        noise = False
        if rule.residual > 0.0:
            noise = _residual_noise(out, [x[i] for i in index], scale, rule.residual)
        step, good = ar.solve(out[k:], out[:k], active)
        out = None
        ok = ok & (good | ~active)
        active = active & good
        for j, i in enumerate(index):
            x[i] = ar.where(active, x[i] - step[j], x[i])
        size = ar.largest([x[i] for i in index])
        change = ar.largest(step)
        done = _newton_stop(rule, change, size, previous, noise)
        previous = ar.where(active, change, previous)
        active = active & ~done
        if not active.any():
            break
    return x, ok, ~active


def _continuation(ar, stage, system, x, index, ok, rule, top, largest_step):
    """Continuation from the as-fabricated pose: stage(t) at t = 1/steps, ..., 1, steps the
    fewest that move no input by more than `largest_step` (`top`: the largest input's
    magnitude), each followed by Newton on `system` from the previous stage's unknowns (as
    _newton_solve); where one does not stop, not ok, and once none is ok it ends (the last
    stage staged is where the last configuration failed)."""
    steps = max(1, math.ceil(top / largest_step))
    for s in range(1, steps + 1):
        stage(s / steps)
        x, ok, converged = _newton_solve(ar, system, x, index, ok, rule)
        ok = ok & converged
        if not ok.any():
            break
    return x, ok
