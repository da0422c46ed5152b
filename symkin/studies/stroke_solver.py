"""The stroke actuators' solve, written once for Python (docs/levels.md, "Actuators";
docs/numerics.md, "The solver table"): the surrogate hinges' angles at which every actuator's
point of action has moved by its stroke along its line, from a start (the as-fabricated pose, or
the rigid linkage's solution for the compliant mechanism's). symkin.studies.actuators solves
with it (a batch of one configuration in mpmath, the sympy backend's), and every generated numpy
module with actuators holds the text below the marker verbatim
(symkin.codegen.templating.shared; templates/numpy/actuators.py and reduced_actuators.py give it
their residuals), so it imports only numpy and math. The C runtime's twin is
templates/c/actuators.c (sk_stroke_solve). The tests' references do not read it.

The method (the C runtime's): Newton's on the k strokes in the k surrogate angles, its Jacobian
by forward differences of step √ε once (or the caller's: the rigid linkage's, for the compliant
mechanism, which differs by the compliance alone), then Broyden's secant updates, so a step
costs one evaluation of the mechanism. A fresh Jacobian where an updated one is singular or its
step does not shrink the residual to `secant` of it; a fresh one's step halved (`cut`, at most
`halvings` times) while it leaves the assembly range or grows the residual; once met (`tolerance`
times the scale), one more step while the residual is above `polish` times the scale, kept where
it shrinks it. `iterations` steps at most. The rules are symkin.core.settings.StrokeSettings'
rules(ε) at the arithmetic's ε.

Every step is elementwise over the configurations of a batch (a list of k arrays): each
configuration's answer depends on its own start and residual alone, never on its neighbours'
(a configuration that has finished is carried unchanged while the others go on). The arrays may
be float arrays or object arrays of mpmath numbers: only arithmetic, comparisons, numpy.abs,
numpy.where and numpy.any are used.
"""

import math

import numpy

# ---- symkin runtime: every generated module with actuators holds what follows ----

# symkin stroke solve (symkin/studies/stroke_solver.py, shared with the Python path): Newton's
# method on the strokes, one Jacobian by forward differences then secant (Broyden) updates;
# all configurations at once, each on its own.


def _stroke_size(r):
    """The largest |r_i| per configuration, and whether every r_i is finite (a residual that
    could not be evaluated is NaN)."""
    size = numpy.abs(r[0])
    finite = size < math.inf
    for x in r[1:]:
        a = numpy.abs(x)
        size = numpy.where(a > size, a, size)
        finite = finite & (a < math.inf)
    return size, finite


def _stroke_linear(jac, r):
    """J^-1 r per configuration (jac: k lists of k arrays, r: k arrays) by Gaussian elimination
    with partial pivoting, as the C runtime's sk_act_solve: (the solution, solvable), not
    solvable where a pivot is zero or not finite."""
    k = len(r)
    rows = [list(row) + [x] for row, x in zip(jac, r)]
    good = numpy.abs(r[0]) == numpy.abs(r[0])  # True (NaN: False)
    for c in range(k):
        for i in range(c + 1, k):
            swap = numpy.abs(rows[i][c]) > numpy.abs(rows[c][c])
            upper = [numpy.where(swap, u, v) for u, v in zip(rows[i], rows[c])]
            rows[i] = [numpy.where(swap, v, u) for u, v in zip(rows[i], rows[c])]
            rows[c] = upper
        pivot = rows[c][c]
        good = good & (numpy.abs(pivot) > 0) & (numpy.abs(pivot) < math.inf)
        rows[c][c] = numpy.where(good, pivot, 1)
        for i in range(c + 1, k):
            f = rows[i][c] / rows[c][c]
            rows[i] = [u - f * v for u, v in zip(rows[i], rows[c])]
    out = [r[0]] * k
    for c in reversed(range(k)):
        v = rows[c][k]
        for i in range(c + 1, k):
            v = v - rows[c][i] * out[i]
        out[c] = v / rows[c][c]
    for v in out:
        good = good & (numpy.abs(v) < math.inf)
    return out, good


def _stroke_solve(residual, theta, t, scale, jac=None, keep=None, first=None, fresh_polish=False):
    """The surrogate angles `theta` (k arrays) at which residual(theta) vanishes (module
    docstring): residual(theta) -> (r, found), r the k strokes' residuals d.(X - X0) - s (NaN
    where the mechanism could not be evaluated), found what the caller keeps of the evaluation
    (any value: with `keep`, keep(mask, new, old) merges two of them elementwise, and the
    evaluation at the answer is returned). `t`: StrokeSettings.rules(ε); `scale`: the size the
    tolerances are relative to; `jac`: (J, have) a Jacobian to start from where `have`;
    `first`: residual(theta) when the caller has it; `fresh_polish`: the polish step from a
    fresh Jacobian where none is at hand (else a start already met is the answer, as in C).
    Returns (theta, met, (J, have), found): met where every stroke was met to the tolerance."""
    k = len(theta)
    tol, fine, step = t["tolerance"] * scale, t["polish"] * scale, t["step"]
    r, found = residual(theta) if first is None else first
    size, live = _stroke_size(r)
    met = live & ~live
    if jac is None:
        jac = ([[r[0] * 0 for _ in range(k)] for _ in range(k)], met)
    jac, have = [list(row) for row in jac[0]], jac[1] & live
    for _ in range(t["iterations"]):
        done = size <= tol
        stop = live & done & ~((size > fine) & (have | fresh_polish))
        met, live = met | stop, live & ~stop
        if not numpy.any(live):
            break
        fresh = live & ~have
        if numpy.any(fresh):
            # forward differences at theta (backward where a forward step does not assemble)
            for j in range(k):
                up, _ = residual([v + step if i == j else v for i, v in enumerate(theta)])
                _, ahead = _stroke_size(up)
                if numpy.any(fresh & ~ahead):
                    down, _ = residual([v - step if i == j else v for i, v in enumerate(theta)])
                    up = [numpy.where(ahead, u, 2 * x - w) for u, x, w in zip(up, r, down)]
                for i in range(k):
                    jac[i][j] = numpy.where(fresh, (up[i] - r[i]) / step, jac[i][j])
        move, solvable = _stroke_linear(jac, r)
        have = numpy.where(live, solvable, have)
        # the step, halved while a fresh Jacobian's grows the residual or leaves the assembly
        # range (an updated one's is not halved: a fresh Jacobian instead)
        pending, ok = live & have, live & ~live
        new_theta, new_r, new_size, new_found = theta, r, size, found
        for _ in range(t["halvings"]):
            if not numpy.any(pending):
                break
            trial = [v - numpy.where(pending, m, 0) for v, m in zip(theta, move)]
            got, got_found = residual(trial)
            got_size, finite = _stroke_size(got)
            shrinks = numpy.where(fresh | done, got_size < size, got_size <= t["secant"] * size)
            good = pending & finite & shrinks
            ok = ok | good
            new_theta = [numpy.where(good, u, v) for u, v in zip(trial, new_theta)]
            new_r = [numpy.where(good, u, v) for u, v in zip(got, new_r)]
            new_size = numpy.where(good, got_size, new_size)
            if keep is not None:
                new_found = keep(good, got_found, new_found)
            pending = pending & ~good & fresh & ~done
            move = [numpy.where(pending, m * t["cut"], m) for m in move]
        # met (the polish step kept or not), or a fresh Jacobian's step refused: finished
        finish = live & (done | (fresh & ~ok))
        met, live = met | (finish & done), live & ~finish
        have = numpy.where(live & ~ok, False, have)  # an updated Jacobian's step refused
        # Broyden: J += (dr - J dx) dx' / (dx' dx), dx = -move, dr = new r - r
        moved = live & ok
        dx = [u - v for u, v in zip(new_theta, theta)]
        dd = dx[0] * dx[0]
        for v in dx[1:]:
            dd = dd + v * v
        dd = numpy.where(moved & (dd > 0), dd, 1)
        for i in range(k):
            miss = new_r[i] - r[i]
            for j in range(k):
                miss = miss - jac[i][j] * dx[j]
            for j in range(k):
                jac[i][j] = numpy.where(moved, jac[i][j] + miss * dx[j] / dd, jac[i][j])
        accept = ok & (moved | met)
        theta = [numpy.where(accept, u, v) for u, v in zip(new_theta, theta)]
        r = [numpy.where(accept, u, v) for u, v in zip(new_r, r)]
        size = numpy.where(accept, new_size, size)
        found = new_found  # it holds the trial's evaluation exactly where one was accepted
    return theta, met, (jac, have), found
