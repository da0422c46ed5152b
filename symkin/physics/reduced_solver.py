"""The `loaded` level's solver, written once for Python (docs/numerics.md, "The solver table";
docs/physics.md, "`loaded`: Newton on the reduced equilibrium"): Newton with its stopping rule,
stall test and chord steps, the acceptance, the continuation in the inputs and loads, the
refusals (the sway buckling check, the truncation estimate) and the buckling search.
symkin.physics.reduced solves with it (a batch of one configuration, its kernels lambdified in
float64 or mpmath), and every generated numpy module with the level holds the text below the
marker verbatim (symkin.codegen.templating.shared; templates/numpy/reduced.py gives it the
generated routines), so it imports only numpy and math. The C runtime's twin is
templates/c/reduced.c. The tests' references (tests/reference_*.py) do not read it.

Every function works on a *system*, one variant of the reduced equilibrium over b
configurations at once, each on its own (every step elementwise, so a configuration's answer
does not depend on the others in its batch):

- ``sy.t``: the rules, symkin.core.settings.LoadedSettings.rules(ε) at the system's arithmetic's
  ε (the `_eps` rules times ε), and ``loads`` (the load factor enters the equations),
  ``unknowns`` (the hinge unknowns, x's first: a step turns them by at most max_turn),
  ``unknown_index`` (each one's place in theta), ``forces`` (theta's last entries
  that are force actuators' forces), ``length`` (the mechanism's size, the estimate's floor);
- ``sy.size`` (n unknowns), ``sy.scale`` ((n,) the unknowns' scales), ``sy.count`` (half plates
  per plate);
- ``sy.system(x, theta, p, t)``: R (n, b) and J (b, n, n) at order 4;
  ``sy.residual(x, theta, p, t)``: R (n, b) at order 4 from the relation's values alone;
  ``sy.compression(x, theta, p, t)``: the worst plate's compression over its sway buckling load
  (b,) (`_red_sway` of its half plates); ``sy.measure(x, theta, p)``: at load factor 1 the
  deviation (2 per point, b) at order 4, the compression (b,) and R (n, b) at order 2;
  ``sy.deviation2(x, theta, p)``: the deviation at order 2. Where an evaluation fails they give
  NaN (the solver reads it as a failed step or a refusal).

x is (n, b); theta and p are lists of (b,) arrays (theta: the rigid hinge angles by label, then
the force actuators' forces); t is a number or a (b,) array.
"""

import math

import numpy

# ---- symkin runtime: every generated module with the loaded level holds what follows ----

# symkin reduced-equilibrium solver (symkin/physics/reduced_solver.py, shared with the Python
# path): Newton from x = 0 at load factor 1, continuation in the inputs and loads together where
# Newton fails, the refusals (a plate at p_limit of its sway buckling load, the truncation
# estimate) and the buckling search; all configurations at once, each on its own.


def _red_signs(jac):
    """det J's sign per configuration (jac: (b, n, n)): 1, -1, 0 or NaN."""
    return numpy.sign(numpy.linalg.det(jac))


def _red_solve(jac, res):
    """J^-1 R per configuration (jac (b, n, n), res (n, b)) -> (n, b); NaN where J is singular."""
    try:
        return numpy.linalg.solve(jac, res.T[:, :, None])[:, :, 0].T
    except numpy.linalg.LinAlgError:
        # one singular J stops the stacked solve: each on its own (LAPACK's, as stacked)
        out = numpy.full(res.shape, numpy.nan)
        for k in range(res.shape[1]):
            try:
                out[:, k] = numpy.linalg.solve(jac[k], res[:, k])
            except numpy.linalg.LinAlgError:
                continue  # singular: NaN
        return out


def _red_sway(p, ea, es, count):
    """A half plate's compression over the plate's sway buckling load (its p over -pi^2; p its
    load index, the plate's over count^2): from the inputs alone, past buckling too."""
    return -(1 + (ea - es) * p) * p * count**2 / math.pi**2


def _red_newton(sy, x, theta, p, t):
    """Newton from x (n, b) at (theta, t), each configuration until it converges or fails (a
    singular or non-finite J, a step turning a hinge by more than max_turn, a non-finite
    iterate, too many steps), with chord steps (after a step below chord, R alone with that
    step's J while each step shrinks tenfold): (x, converged, each one's last full step's J,
    det J's sign at the first step, Newton steps taken)."""
    tb, n, nu = sy.t, sy.size, sy.t.unknowns
    b = x.shape[1]
    each = numpy.ndim(t) > 0  # a load factor per configuration: indexed as x is
    if each:
        t = numpy.asarray(t, dtype=float)
    x, converged = x.copy(), numpy.zeros(b, dtype=bool)
    last, first = numpy.zeros((b, n, n)), None
    prev = numpy.full(b, math.inf)
    chord = numpy.zeros(b, dtype=bool)
    steps = numpy.zeros(b, dtype=int)
    act = numpy.arange(b)
    for it in range(1, tb.max_iter + 1):
        c = chord[act]
        step = numpy.zeros((n, act.size))
        full = act[~c]
        if full.size:
            tf = t[full] if each else t
            res, jac = sy.system(x[:, full], [v[full] for v in theta], [v[full] for v in p], tf)
            last[full] = jac
            if first is None:
                first = _red_signs(jac)  # the first step: every configuration's full
            step[:, ~c] = _red_solve(jac, res)
        if c.any():
            k = act[c]
            tk = t[k] if each else t
            res = sy.residual(x[:, k], [v[k] for v in theta], [v[k] for v in p], tk)
            step[:, c] = _red_solve(last[k], res)
        turn = numpy.max(numpy.abs(step[:nu]), axis=0) * sy.scale[0] if nu else 0.0
        xn = x[:, act] - step
        fail = ~(turn <= tb.max_turn) | ~numpy.all(numpy.isfinite(xn), axis=0)
        size = numpy.max(numpy.abs(step), axis=0)
        top = numpy.max(numpy.abs(xn), axis=0)
        # a Newton step leaves about its square; a chord step its size times the contraction
        left = ~c | (size * size <= tb.chord_error * top * prev[act])
        # x is scaled (l/L, EI/(l L)): the whole vector sets the scale, so a delta that is zero
        # by symmetry cannot block the test
        done = ((size <= tb.tol * top) & left) | (size == 0)
        # stalled at rounding (a full step's: a slow chord step's is its J's, not rounding)
        done |= (
            ~c
            & (it > tb.stall_after)
            & (size > tb.stall_ratio * prev[act])
            & (size < tb.stalled * top)
        )
        x[:, act] = xn
        steps[act] = it
        converged[act[done & ~fail]] = True
        chord[act] = (size <= tb.chord * top) & (~c | (size <= tb.chord_shrink * prev[act]))
        prev[act] = size
        act = act[~done & ~fail]
        if not act.size:
            break
    return x, converged, last, first, steps


def _red_accept(sy, x, theta, jac, sign):
    """Converged x on the branch followed: det J (the last Newton step's, a step below tol from
    x) of the sign at the unloaded state, every compliant angle within (-pi, pi) (theta's
    angles: the force actuators' forces follow them)."""
    ok = _red_signs(jac) == sign
    for i, th in enumerate(theta[: len(theta) - sy.t.forces]):
        angle = th
        for j, h in enumerate(sy.t.unknown_index):
            if h == i:
                angle = angle + x[j] * sy.scale[j]
        ok &= numpy.abs(angle) < math.pi
    return ok


def _red_one(values):
    """One configuration's theta (numbers) as the solver's list of (1,) arrays."""
    return [numpy.array([v]) for v in values]


def _red_continuation(sy, rigid, p):
    """One configuration by continuation: inputs and loads scaled together by s from the
    as-fabricated pose (x = 0 exact at s = 0), the predictor keeping the compliant angles and
    the chord loads; rigid(s) its theta (numbers; the force actuators' forces at the end kept,
    the load factor scales them) or None where the rigid linkage has no pose, p its parameters
    ((1,) arrays): (x (n,), the last Newton step's J, steps, Newton steps), None where it does
    not converge."""
    tb, n = sy.t, sy.size
    s, ds, steps, total = 0.0, tb.first_step, 0, 0
    th_s = rigid(0.0)
    if th_s is None:
        return None
    x = numpy.zeros((n, 1))
    sign = _red_signs(sy.system(x, _red_one(th_s), p, 0.0)[1])
    jac = None
    while s < 1:
        if ds < tb.smallest_step:
            return None
        s1 = min(1.0, s + ds)
        th_1 = rigid(s1)
        okn = th_1 is not None
        if okn:
            guess = x.copy()
            for j, i in enumerate(tb.unknown_index):
                guess[j] = (th_s[i] + x[j] * sy.scale[j] - th_1[i]) / sy.scale[j]
            xn, conv, last, _, its = _red_newton(sy, guess, _red_one(th_1), p, s1)
            total += int(its[0])
            okn = bool(conv[0]) and bool(_red_accept(sy, xn, _red_one(th_1), last, sign)[0])
        if okn:
            x, s, th_s, jac, steps = xn, s1, th_1, last[0], steps + 1
            ds = min(tb.largest_step, ds * tb.step_growth)
        else:
            ds *= tb.step_cut
    return x[:, 0], jac, steps, total


def _red_equilibrium(sy, theta, p, rigid):
    """Every configuration solved: Newton from x = 0 at load factor 1 on all, continuation one
    by one where it fails or leaves the branch (rigid(k): configuration k's rigid(s) for
    _red_continuation): (x (n, b), the last Newton step's J (b, n, n), converged (b,),
    continuation steps (b,; 1: plain Newton), Newton steps (b,))."""
    tb, n, b = sy.t, sy.size, theta[0].shape[0]
    x, jac = numpy.zeros((n, b)), numpy.zeros((b, n, n))
    ok = numpy.ones(b, dtype=bool)
    steps, total = numpy.ones(b, dtype=int), numpy.zeros(b, dtype=int)
    if n:
        sign0 = None
        if tb.loads:
            sign0 = _red_signs(sy.system(x, theta, p, 0.0)[1])
        xn, converged, jac, first, total = _red_newton(sy, x, theta, p, 1.0)
        # without loads t enters nowhere: the first step's J is the unloaded state's
        good = converged & _red_accept(sy, xn, theta, jac, first if sign0 is None else sign0)
        x[:, good] = xn[:, good]
        for k in numpy.flatnonzero(~good):
            found = _red_continuation(sy, rigid(k), [v[k : k + 1] for v in p])
            if found is None:
                ok[k] = False
            else:
                x[:, k], jac[k], steps[k], more = found
                total[k] += more
    return x, jac, ok, steps, total


def _red_verdict(sy, x, theta, p, jac):
    """The deviation at each solution x (n, b), the worst plate's compression, the truncation
    estimate est_factor e24^2 (e24: each point's change when the quartic terms are dropped, by
    one order-2 Newton step with jac, the last Newton step's J, against the point's deviation,
    at least est_share of the largest one and est_size times the mechanism's size) and the
    status: 0, 1 where a plate is at p_limit of its sway buckling load or the deviation is not
    finite, 4 where the estimate is above est_limit."""
    tb, n, b = sy.t, sy.size, x.shape[1]
    dev, worst, res = sy.measure(x, theta, p)
    x2 = x
    if n:
        x2 = x - _red_solve(jac, res)
    dev2 = sy.deviation2(x2, theta, p)
    e24 = numpy.zeros(b)
    sizes = [numpy.hypot(dev[2 * k], dev[2 * k + 1]) for k in range(len(dev) // 2)]
    largest = numpy.max(sizes, axis=0) if sizes else numpy.zeros(b)
    least = numpy.maximum(tb.est_share * largest, tb.est_size * tb.length)
    for k, size in enumerate(sizes):
        size = numpy.maximum(size, least)
        e = numpy.hypot(dev2[2 * k] - dev[2 * k], dev2[2 * k + 1] - dev[2 * k + 1]) / size
        e24 = numpy.where((size > 0) & (e > e24), e, e24)
    estimate = tb.est_factor * e24**2
    status = numpy.where(~(estimate <= tb.est_limit), 4, 0)
    refused = ~numpy.all(numpy.isfinite(dev), axis=0) | ~(worst < tb.p_limit)
    return dev, worst, estimate, numpy.where(refused, 1, status)


def _red_state(sy, x, theta, p, t):
    """The buckling search's state at load factors t ((k,) array) from the guesses x (n, k):
    (x, converged, det J's sign at x; 0 where the worst plate's compression reaches its sway
    buckling load, which the search takes for a sign change). A non-finite det J is not
    converged."""
    n, k = sy.size, t.shape[0]
    if n:
        x, ok, _, _, _ = _red_newton(sy, x, theta, p, t)
    else:
        ok = numpy.ones(k, dtype=bool)
    sign = numpy.zeros(k)
    live = numpy.flatnonzero(ok)
    if not live.size:
        return x, ok, sign
    th, pl, tl, xl = [v[live] for v in theta], [v[live] for v in p], t[live], x[:, live]
    worst = sy.compression(xl, th, pl, tl)
    found = _red_signs(sy.system(xl, th, pl, tl)[1]) if n else numpy.ones(live.size)
    at_sway = worst >= 1  # no J there (past the relation's pole)
    ok[live] = at_sway | numpy.isfinite(found)
    sign[live] = numpy.where(at_sway, 0.0, found)
    return x, ok, sign


def _red_buckling(sy, x, theta, p):
    """The buckling factor of every configuration at once (x (n, b): each one's solution at load
    factor 1): the smallest t >= 1, the inputs held, at which det J changes sign, a plate
    reaches its sway buckling load or Newton cannot go on (a limit point); inf when none below
    buckling_limit. Each configuration steps with its own t, step, x and previous point (the
    same arithmetic, so the same steps as alone); the sign changes found are then bisected
    together."""
    tb = sy.t
    limit, locate = tb.buckling_limit, tb.buckling_locate
    b = x.shape[1]
    out = numpy.full(b, numpy.nan)
    t = numpy.ones(b)
    x, ok, sign = _red_state(sy, x, theta, p, t)
    out[~ok | (sign == 0)] = 1.0
    act = numpy.flatnonzero(ok & (sign != 0))
    dt = numpy.full(b, tb.buckling_step)
    # the previous accepted (x, t) of each configuration (none before its first step)
    x_prev, t_prev, has_prev = numpy.zeros_like(x), numpy.zeros(b), numpy.zeros(b, dtype=bool)
    lo, hi, x_lo = numpy.zeros(b), numpy.zeros(b), x.copy()
    bisect = numpy.zeros(b, dtype=bool)
    while act.size:
        ta, xa = t[act], x[:, act]
        t1 = numpy.minimum(limit, ta + dt[act])
        # the linear extrapolation from the previous accepted point
        ahead = xa + (xa - x_prev[:, act]) * (t1 - ta) / (ta - t_prev[act])
        guess = numpy.where(has_prev[act], ahead, xa)
        x1, ok1, s1 = _red_state(sy, guess, [v[act] for v in theta], [v[act] for v in p], t1)
        same = ok1 & (s1 == sign[act])
        change = ok1 & ~same  # a sign change (or a plate's sway load) in (t, t1): bisected below
        ends = ~ok1 & (dt[act] <= locate * ta)  # Newton fails this close: a limit point
        k = act[change]
        lo[k], hi[k], x_lo[:, k], bisect[k] = t[k], t1[change], x[:, k], True
        out[act[ends]] = ta[ends]
        dt[act[~ok1 & ~ends]] *= tb.buckling_cut
        k = act[same]
        x_prev[:, k], t_prev[k], has_prev[k] = x[:, k], t[k], True
        x[:, k], t[k] = x1[:, same], t1[same]
        dt[k] = numpy.minimum(tb.buckling_largest, dt[k] * tb.buckling_growth)
        act = act[same | (~ok1 & ~ends)]
        past = t[act] >= limit
        out[act[past]] = math.inf
        act = act[~past]
    k = numpy.flatnonzero(bisect)
    while k.size:
        wide = hi[k] - lo[k] > locate * hi[k]
        done = k[~wide]
        out[done] = (lo[done] + hi[done]) / 2
        k = k[wide]
        if not k.size:
            break
        mid = (lo[k] + hi[k]) / 2
        xl = x_lo[:, k]
        xm, okm, sm = _red_state(sy, xl, [v[k] for v in theta], [v[k] for v in p], mid)
        good = okm & (sm == sign[k])
        lo[k[good]], x_lo[:, k[good]] = mid[good], xm[:, good]
        hi[k[~good]] = mid[~good]
    return out
