"""symkin's numpy runtime for the `loaded` level (docs/physics.md, "`loaded`: Newton on the reduced
equilibrium"): the reduced equilibrium of symkin.physics.reduced solved by Newton and continuation
over the mechanism's loaded_* routines, with the same rules in the same float64 arithmetic. Only
modules that hold the level hold it (templates/numpy/module.py.j2), after the runtime.
"""

import math

import numpy
from runtime import _rigid_angles  # the module holds both: runtime.py

# ---- symkin runtime: every generated module with the loaded level holds what follows ----

# symkin reduced-equilibrium runtime (templates/numpy/reduced.py): Newton from x = 0 at load
# factor 1, continuation in the inputs and loads together where Newton fails, the refusals (a
# plate at P_LIMIT of its sway buckling load, the truncation estimate), two half plates per plate
# where one relation is refused by its estimate; all configurations at once, each on its own.


class _LoadedTables:
    """The loaded level's routines and rules: per variant (one, two half plates per plate) its
    (plates, system, residual, dev) routines, its size, its half plates and its unknowns'
    scales."""

    forces = 0  # the force actuators' forces after the rigid angles in theta (with actuators)

    def __init__(self, **fields):
        self.__dict__.update(fields)


class _Solved(list):
    """What the loaded level's deviation reads (q): the parameters, and the deviation solved."""


def _loaded_deviation(theta, delta, q):
    """The loaded level's `dev` routine: the deviation its driver solved for."""
    return q.deviation


def _red_column(v, b):
    """A routine's output as a (b,) float array (constants come back as numbers)."""
    return numpy.broadcast_to(numpy.asarray(v, dtype=float), (b,))


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


class _Batch:
    """One variant of the reduced equilibrium over b configurations at once: Newton on all of
    them with a mask each, stacked solves; every step elementwise, so a configuration's answer
    does not depend on the others in its batch."""

    def __init__(self, tables, variant, count):
        self.t, self.count = tables, count  # count: half plates per plate
        self.plates_fn, self.system_fn, self.res_fn, self.dev_fn, self.size, self.plates = variant[
            :6
        ]
        scale = variant[6]
        self.scale = numpy.array(scale, dtype=float)

    def _inputs(self, x, theta, p, t):
        """The routines' x argument (x, then t), the half plates' inputs (5 per half plate) and
        their x-Jacobian (3 per half plate x n), each a (b,) array (t: a number or one per
        configuration, a (b,) array)."""
        b = x.shape[1]
        args = [x[i] for i in range(self.size)] + [numpy.array(_red_column(t, b))]
        out = [_red_column(v, b) for v in self.plates_fn(args, theta, p)]
        return args, out[: 5 * self.plates], out[5 * self.plates :]

    def _relation(self, ins):
        """The plate relation at order 4 per half plate (12 (b,) arrays: values, partials) and
        the values (along, across, omega) one half plate after the other."""
        b = ins[0].shape[0] if ins else 0
        rel = []
        for k in range(self.plates):
            plate = ins[5 * k : 5 * k + 5]
            rest = (plate[1] == 0.0) & (plate[2] == 0.0)
            if numpy.all(rest):
                # no force on the plate (x = 0 without loads): reduced.c's plate_rest4
                rel.append([_red_column(v, b) for v in self.t.rest4(plate)])
                continue
            out = [_red_column(v, b) for v in self.t.relation4(plate)]
            if numpy.any(rest):
                at_rest = self.t.rest4(plate)
                out = [numpy.where(rest, r, v) for r, v in zip(at_rest, out)]
            rel.append(out)
        return rel, [r[j] for r in rel for j in range(3)]

    def _values4(self, ins):
        """The plate relation at order 4, values alone (a chord step's; reduced.c's
        sk_red_values4), one half plate after the other."""
        b = ins[0].shape[0] if ins else 0
        vals = []
        for k in range(self.plates):
            plate = ins[5 * k : 5 * k + 5]
            rest = (plate[1] == 0.0) & (plate[2] == 0.0)
            if numpy.all(rest):
                out = [_red_column(v, b) for v in self.t.rest4(plate)[:3]]
            else:
                out = [_red_column(v, b) for v in self.t.values4(plate)]
                if numpy.any(rest):
                    at_rest = self.t.rest4(plate)[:3]
                    out = [numpy.where(rest, r, v) for r, v in zip(at_rest, out)]
            vals += out
        return vals

    def residual(self, x, theta, p, t):
        """R (n, b) at order 4 from the relation's values alone (a chord step's); t a number or
        a (b,) array."""
        b = x.shape[1]
        args, ins, _ = self._inputs(x, theta, p, t)
        vals = self._values4(ins)
        return numpy.array([_red_column(v, b) for v in self.res_fn(args, theta, vals, p)])

    def _values2(self, ins):
        """The plate relation at order 2, values alone (the truncation estimate's), one half
        plate after the other."""
        b = ins[0].shape[0] if ins else 0
        plates = range(self.plates)
        return [_red_column(v, b) for k in plates for v in self.t.values2(ins[5 * k : 5 * k + 5])]

    def system(self, x, theta, p, t):
        """R (n, b) and J (b, n, n) at order 4: dR/dx + dR/d(plates) . the plates' partials .
        d(theta_c, p, f)/dx, summed in reduced.c's order; t a number or a (b,) array."""
        n, ns, b = self.size, self.plates, x.shape[1]
        args, ins, dins = self._inputs(x, theta, p, t)
        rel, vals = self._relation(ins)
        sys = numpy.array([_red_column(v, b) for v in self.system_fn(args, theta, vals, p)])
        res = sys[:n]
        jac = sys[n : n + n * n].reshape(n, n, b).copy()
        jo = sys[n + n * n :].reshape(n, 3 * ns, b)
        d = numpy.array(dins).reshape(3 * ns, n, b) if ns else None
        for k in range(ns):
            part = rel[k][3:]
            w = [
                jo[:, 3 * k] * part[c]
                + jo[:, 3 * k + 1] * part[3 + c]
                + jo[:, 3 * k + 2] * part[6 + c]
                for c in range(3)
            ]
            jac += (
                w[0][:, None] * d[3 * k][None]
                + w[1][:, None] * d[3 * k + 1][None]
                + w[2][:, None] * d[3 * k + 2][None]
            )
        return res, numpy.ascontiguousarray(jac.transpose(2, 0, 1))

    def newton(self, x, theta, p, t):
        """Newton from x (n, b) at (theta, t), each configuration until it converges or fails
        (a singular or non-finite J, a step turning a hinge by more than max_turn, a non-finite
        iterate, too many steps), with reduced.c's chord steps (after a step below chord, R
        alone with that step's J while each step shrinks tenfold): (x, converged, each one's
        last full step's J, det J's sign at the first step); t a number or a (b,) array."""
        tb, n, nu = self.t, self.size, self.t.unknowns
        b = x.shape[1]
        each = numpy.ndim(t) > 0  # a load factor per configuration: indexed as x is
        if each:
            t = numpy.asarray(t, dtype=float)
        x, converged = x.copy(), numpy.zeros(b, dtype=bool)
        last, first = numpy.zeros((b, n, n)), None
        prev = numpy.full(b, math.inf)
        chord = numpy.zeros(b, dtype=bool)
        act = numpy.arange(b)
        for it in range(1, tb.max_iter + 1):
            c = chord[act]
            step = numpy.zeros((n, act.size))
            full = act[~c]
            if full.size:
                tf = t[full] if each else t
                res, jac = self.system(
                    x[:, full], [v[full] for v in theta], [v[full] for v in p], tf
                )
                last[full] = jac
                if first is None:
                    first = _red_signs(jac)  # the first step: every configuration's full
                step[:, ~c] = _red_solve(jac, res)
            if c.any():
                k = act[c]
                tk = t[k] if each else t
                res = self.residual(x[:, k], [v[k] for v in theta], [v[k] for v in p], tk)
                step[:, c] = _red_solve(last[k], res)
            turn = numpy.max(numpy.abs(step[:nu]), axis=0) * self.scale[0] if nu else 0.0
            xn = x[:, act] - step
            fail = ~(turn <= tb.max_turn) | ~numpy.all(numpy.isfinite(xn), axis=0)
            size = numpy.max(numpy.abs(step), axis=0)
            top = numpy.max(numpy.abs(xn), axis=0)
            # a Newton step leaves about its square; a chord step its size times the contraction
            left = ~c | (size * size <= tb.chord_error * top * prev[act])
            done = ((size <= tb.tol * top) & left) | (size == 0)
            # stalled at rounding (a full step's: a slow chord step's is its J's, not rounding)
            done |= (
                ~c
                & (it > tb.stall_after)
                & (size > tb.stall_ratio * prev[act])
                & (size < tb.stalled * top)
            )
            x[:, act] = xn
            converged[act[done & ~fail]] = True
            chord[act] = (size <= tb.chord * top) & (~c | (size <= tb.chord_shrink * prev[act]))
            prev[act] = size
            act = act[~done & ~fail]
            if not act.size:
                break
        return x, converged, last, first

    def accept(self, x, theta, jac, sign):
        """Converged x on the branch followed: det J (the last Newton step's) of the sign at the
        unloaded state, every compliant angle within (-pi, pi) (theta's angles: the force
        actuators' forces follow them)."""
        ok = _red_signs(jac) == sign
        for i, th in enumerate(theta[: len(theta) - self.t.forces]):
            angle = th
            for j, h in enumerate(self.t.unknown_index):
                if h == i:
                    angle = angle + x[j] * self.scale[j]
            ok &= numpy.abs(angle) < math.pi
        return ok

    def solve(self, inputs, theta, p, mech):
        """Every configuration (inputs, theta, p: lists of (b,) arrays): x (n, b), the deviation
        (2 per point, b) and a status each: 0, 1 refused or no convergence, 4 refused by the
        truncation estimate. Newton from x = 0 on all; continuation one by one where it fails."""
        tb, n, b = self.t, self.size, theta[0].shape[0]
        x, jac = numpy.zeros((n, b)), numpy.zeros((b, n, n))
        status = numpy.zeros(b, dtype=int)
        if n:
            sign0 = None
            if tb.loads:
                sign0 = _red_signs(self.system(x, theta, p, 0.0)[1])
            xn, converged, jac, first = self.newton(x, theta, p, 1.0)
            # without loads t enters nowhere: the first step's J is the unloaded state's
            good = converged & self.accept(xn, theta, jac, first if sign0 is None else sign0)
            x[:, good] = xn[:, good]
            for k in numpy.flatnonzero(~good):
                found = self.continuation(k, inputs, theta, p, mech)
                if found is None:
                    status[k] = 1
                else:
                    x[:, k], jac[k] = found
        dev = numpy.full((2 * len(mech.point_names), b), numpy.nan)
        live = numpy.flatnonzero(status == 0)
        if live.size:
            dev[:, live], status[live] = self.answer(
                x[:, live], [v[live] for v in theta], [v[live] for v in p], jac[live]
            )
        return x, dev, status

    def continuation(self, k, inputs, theta, p, mech):
        """Configuration k by continuation (inputs and loads scaled together by s from the
        as-fabricated pose; the force actuators' forces at the end of theta are kept, the load
        factor scales them): (x, the last Newton step's J), None where it does not converge."""
        tb, n = self.t, self.size
        th = [float(v[k]) for v in theta]
        forces = th[len(th) - tb.forces :]
        pk = [v[k : k + 1] for v in p]
        xi = [float(v[k]) for v in inputs]

        def rigid(s):
            if s == 1.0:
                return th
            with numpy.errstate(all="ignore"):
                angles, good = _rigid_angles(
                    mech,
                    [numpy.array(v * s) for v in xi],
                    [float(v[0]) for v in pk],
                    numpy.array(True),
                )
            return [float(v) for v in angles] + forces if bool(good) else None

        def column(values):
            return [numpy.array([v]) for v in values]

        s, ds = 0.0, tb.first_step
        th_s = rigid(0.0)
        if th_s is None:
            return None
        x = numpy.zeros((n, 1))
        sign = _red_signs(self.system(x, column(th_s), pk, 0.0)[1])
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
                    guess[j] = (th_s[i] + x[j] * self.scale[j] - th_1[i]) / self.scale[j]
                xn, conv, last, _ = self.newton(guess, column(th_1), pk, s1)
                okn = bool(conv[0]) and bool(self.accept(xn, column(th_1), last, sign)[0])
            if okn:
                x, s, th_s, jac = xn, s1, th_1, last[0]
                ds = min(tb.largest_step, ds * tb.step_growth)
            else:
                ds *= tb.step_cut
        return x[:, 0], jac

    def compression(self, ins, b):
        """The worst half plate's compression over its sway buckling load per configuration
        (b,), from the half plates' inputs alone (no relation: past buckling too)."""
        worst = numpy.zeros(b)
        for k in range(self.plates):
            pk, ea, es = ins[5 * k + 1], ins[5 * k + 3], ins[5 * k + 4]
            w = -(1 + (ea - es) * pk) * pk * self.count**2 / math.pi**2
            worst = numpy.where(w > worst, w, worst)
        return worst

    def answer(self, x, theta, p, jac):
        """The deviation at each solution x (n, b) and its status: 0, 1 where a plate is at
        p_limit of its sway buckling load, 4 where the truncation estimate (one order-2 Newton
        step with jac, the last Newton step's J) is above est_limit."""
        tb, n, b = self.t, self.size, x.shape[1]
        args, ins, _ = self._inputs(x, theta, p, 1.0)
        _, vals = self._relation(ins)
        dev = numpy.array([_red_column(v, b) for v in self.dev_fn(args, theta, vals, p)])
        worst = self.compression(ins, b)
        x2 = x
        if n:
            vals2 = self._values2(ins)
            sys = self.res_fn(args, theta, vals2, p)
            res = numpy.array([_red_column(v, b) for v in sys])
            x2 = x - _red_solve(jac, res)
        args2, ins2, _ = self._inputs(x2, theta, p, 1.0)
        vals2 = self._values2(ins2)
        dev2 = numpy.array([_red_column(v, b) for v in self.dev_fn(args2, theta, vals2, p)])
        e24 = numpy.zeros(b)
        # each point's change against its deviation, at least est_share of the largest one and
        # est_size times the mechanism's size (reduced.py's Reduced.estimate_floor)
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
        return dev, numpy.where(refused, 1, status)


def _reduced_solve(mech, x, theta, p, ok):
    """The loaded level at every configuration where ok, all at once: delta of the non-input
    hinges, what its deviation reads (q: the parameters and the deviation solved) and ok, False
    where the reduced equilibrium refuses or does not converge."""
    tb = mech.loaded
    shape, dtype = ok.shape, mech.dtype
    ok = numpy.array(ok)
    n_dev = 2 * len(mech.point_names)
    delta = [numpy.zeros(shape, dtype=dtype) for _ in mech.unknown_index]
    dev = [numpy.full(shape, numpy.nan, dtype=dtype) for _ in range(n_dev)]
    where = numpy.flatnonzero(ok.reshape(-1))

    def flat(values):
        return [numpy.broadcast_to(v, shape).reshape(-1)[where].astype(float) for v in values]

    xs, ths, ps = flat(x), flat(theta), flat(p)
    todo = numpy.arange(where.size)  # the configurations the next variant solves
    okf = numpy.zeros(where.size, dtype=bool)
    flat_delta = [numpy.zeros(where.size) for _ in mech.unknown_index]
    flat_dev = [numpy.full(where.size, numpy.nan) for _ in range(n_dev)]
    # the variant and its solution x, for the sensitivities (templates/numpy/reduced_sens.py)
    flat_x = [numpy.full(where.size, numpy.nan) for _ in range(max(v[4] for v in tb.variants))]
    flat_variant = numpy.full(where.size, -1)
    for count, variant in enumerate(tb.variants, 1):
        if not todo.size:
            break
        solver = _Batch(tb, variant, count)
        with numpy.errstate(all="ignore"):
            sx, sdev, status = solver.solve(
                [v[todo] for v in xs], [v[todo] for v in ths], [v[todo] for v in ps], mech
            )
        good = status == 0
        for j in range(len(mech.unknown_index)):
            flat_delta[j][todo[good]] = sx[j, good] * solver.scale[j]
        for i in range(n_dev):
            flat_dev[i][todo[good]] = sdev[i, good]
        for i in range(solver.size):
            flat_x[i][todo[good]] = sx[i, good]
        flat_variant[todo[good]] = count - 1
        okf[todo[good]] = True
        # refused by the truncation estimate: two half plates per plate
        todo = todo[status == 4]
    okflat = ok.reshape(-1)
    okflat[where] = okf
    ok = okflat.reshape(shape)
    for j in range(len(mech.unknown_index)):
        delta[j].reshape(-1)[where] = flat_delta[j]
    for i in range(n_dev):
        dev[i].reshape(-1)[where] = flat_dev[i]
    q = _Solved(p)
    q.deviation = dev
    q.x = [numpy.zeros(shape) for _ in flat_x]
    q.variant = numpy.full(shape, -1)
    for i, v in enumerate(flat_x):
        q.x[i].reshape(-1)[where] = v
    q.variant.reshape(-1)[where] = flat_variant
    return delta, q, ok


def _red_block(out, block, b):
    """A routine's block (offset, rows, cols) as a (b, rows, cols) array."""
    at, rows, cols = block
    if not rows * cols:
        return numpy.zeros((b, rows, cols))
    values = [_red_column(out[at + i], b) for i in range(rows * cols)]
    return numpy.stack(values, axis=-1).reshape(b, rows, cols)


def _red_solutions(mech, theta, p, q, shape, good, routines):
    """The configurations the loaded level solved (q: the variant and its x; shape: the
    configurations', good: a flat mask of them),
    variant by variant, evaluated again at their solution for the implicit-function theorem
    (templates/numpy/reduced_sens.py, reduced_report.py): per variant solved (where, solver,
    routines[variant]'s output, J (b, n, n), dR/d(plates) (b, n, 3 n_s), the half plates'
    inputs, their x-Jacobian and the relation there)."""
    tb = mech.loaded
    variant = numpy.broadcast_to(q.variant, shape).reshape(-1)

    def flat(values, where):
        return [numpy.broadcast_to(v, shape).reshape(-1)[where].astype(float) for v in values]

    for index, (variant_row, fn) in enumerate(zip(tb.variants, routines)):
        where = numpy.flatnonzero(good & (variant == index))
        b = where.size
        if not b:
            continue
        solver = _Batch(tb, variant_row, index + 1)
        n, ns = solver.size, solver.plates
        x = numpy.array(flat(q.x[:n], where)).reshape(n, b)
        th, pb = flat(theta, where), flat(p, where)
        with numpy.errstate(all="ignore"):
            _, jac = solver.system(x, th, pb, 1.0)
            args, ins, dins = solver._inputs(x, th, pb, 1.0)
            rel, vals = solver._relation(ins)
            sys = solver.system_fn(args, th, vals, pb)
            out = fn(args, th, vals, pb)
        jo = _red_block(sys, (n + n * n, n, 3 * ns), b)
        yield where, solver, out, jac, jo, ins, dins, rel
