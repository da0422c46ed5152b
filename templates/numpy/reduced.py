"""symkin's numpy runtime for the `loaded` level (docs/physics.md, "The Newton level"): the
reduced equilibrium of symkin.physics.reduced solved by Newton and continuation over the
mechanism's loaded_* routines, with the same rules in the same float64 arithmetic. Only modules
that hold the level hold it (templates/numpy/module.py.j2), after the runtime.
"""

import math

import numpy
from runtime import _rigid_angles  # the module holds both: runtime.py

# ---- symkin runtime: every generated module with the loaded level holds what follows ----

# symkin reduced-equilibrium runtime (templates/numpy/reduced.py): Newton from x = 0 at load
# factor 1, continuation in the inputs and loads together where Newton fails, the refusals (a
# plate at P_LIMIT of its sway buckling load, the truncation estimate), two half plates per plate
# where one relation is refused by its estimate; elementwise over the configurations.


class _LoadedTables:
    """The loaded level's routines and rules: per variant (one, two half plates per plate) its
    (plates, system, dev) routines, its size, its half plates and its unknowns' scales."""

    def __init__(self, **fields):
        self.__dict__.update(fields)


class _Refused(Exception):
    """The reduced equilibrium has no answer here (a refusal rule, or no convergence)."""

    def __init__(self, truncation=False):
        super().__init__()
        self.truncation = truncation


class _Solved(list):
    """What the loaded level's deviation reads (q): the parameters, and the deviation solved."""


def _loaded_deviation(theta, delta, q):
    """The loaded level's `dev` routine: the deviation its driver solved for."""
    return q.deviation


class _Variant:
    """One variant of the reduced equilibrium at one configuration's parameters."""

    def __init__(self, tables, variant, count, relations, params):
        self.t, self.count = tables, count  # count: half plates per plate
        self.plates_fn, self.system_fn, self.dev_fn, self.size, self.plates, scale = variant
        self.scale = numpy.array(scale, dtype=float)
        self.relations = relations  # order -> plate_relation routine
        self.p = params

    def _eval(self, x, theta, t, order=4):
        """Plate inputs, their x-Jacobian, the plates' outputs and partials at (x, theta, t)."""
        args = list(map(float, x)) + [float(t)]
        plates = self.plates_fn(args, theta, self.p)
        n, ns = self.size, self.plates
        ins = [float(v) for v in plates[: 5 * ns]]
        dins = numpy.array([float(v) for v in plates[5 * ns :]]).reshape(3 * ns, n)
        relation = self.relations[order]
        outs, parts = [], []
        for k in range(ns):
            v = [float(u) for u in relation(ins[5 * k : 5 * k + 5])]
            outs += v[:3]
            parts.append(numpy.array(v[3:]).reshape(3, 3))
        return args, ins, dins, outs, parts

    def residual(self, x, theta, t, order=4):
        args, _, _, outs, _ = self._eval(x, theta, t, order)
        return numpy.array(
            [float(v) for v in self.system_fn(args, theta, outs, self.p)[: self.size]]
        )

    def jacobian(self, x, theta, t):
        """dR/dx = dR/dx at fixed plate outputs + dR/doutputs . d outputs/d in . d in/dx."""
        args, _, dins, outs, parts = self._eval(x, theta, t)
        n, ns = self.size, self.plates
        sys = [float(v) for v in self.system_fn(args, theta, outs, self.p)]
        jx = numpy.array(sys[n : n + n * n]).reshape(n, n)
        if not ns:
            return jx
        jo = numpy.array(sys[n + n * n :]).reshape(n, 3 * ns)
        block = numpy.zeros((3 * ns, 3 * ns))
        for k, d in enumerate(parts):
            block[3 * k : 3 * k + 3, 3 * k : 3 * k + 3] = d
        return jx + jo @ block @ dins

    def deviations(self, x, theta, order=4):
        args, _, _, outs, _ = self._eval(x, theta, 1.0, order)
        return numpy.array([float(v) for v in self.dev_fn(args, theta, outs, self.p)])

    def newton(self, x, theta, t):
        """Newton from x: (x, converged); a step that turns a hinge by more than max_turn fails
        (continuation takes over)."""
        tb, nu = self.t, self.t.unknowns
        prev = math.inf
        for it in range(1, tb.max_iter + 1):
            with numpy.errstate(all="ignore"):
                try:
                    step = numpy.linalg.solve(
                        self.jacobian(x, theta, t), self.residual(x, theta, t)
                    )
                except (numpy.linalg.LinAlgError, ValueError, ZeroDivisionError, OverflowError):
                    return x, False
            turn = float(numpy.max(numpy.abs(step[:nu]))) * self.scale[0] if nu else 0.0
            if not turn <= tb.max_turn:
                return x, False
            x = x - step
            if not numpy.all(numpy.isfinite(x)):
                return x, False
            size, top = float(numpy.max(numpy.abs(step))), float(numpy.max(numpy.abs(x)))
            if size <= tb.tol * top or size == 0:
                return x, True
            if it > 3 and size > 0.5 * prev and size < 1e-9 * top:
                return x, True  # stalled at rounding
            prev = size
        return x, False

    def sign(self, x, theta, t):
        with numpy.errstate(all="ignore"):
            return float(numpy.sign(numpy.linalg.det(self.jacobian(x, theta, t))))

    def accept(self, x, theta, t, sign):
        """A converged x on the branch followed: det J of the sign at the unloaded state, every
        compliant angle within (-pi, pi)."""
        try:
            same = self.sign(x, theta, t) == sign
        except (ValueError, ZeroDivisionError, OverflowError):
            return False
        angles = numpy.array(theta, dtype=float)
        for j, i in enumerate(self.t.unknown_index):
            angles[i] += x[j] * self.scale[j]
        return same and bool(numpy.all(numpy.abs(angles) < math.pi))

    def solve(self, rigid):
        """x at the configuration (rigid(s): the rigid angles at the inputs scaled by s, None
        where they cannot be reached), its deviation; _Refused where there is none."""
        theta = rigid(1.0)
        zero = numpy.zeros(self.size)
        if not self.size:
            return self.answer(zero, theta)
        sign0 = self.sign(zero, theta, 0.0)
        x, ok = self.newton(zero, theta, 1.0)
        if ok:
            ok = self.accept(x, theta, 1.0, sign0)
        if not ok:
            # continuation: inputs and loads scaled together by s from the as-fabricated pose
            s, ds = 0.0, 0.25
            th_s = rigid(0.0)
            x = zero
            sign = self.sign(x, th_s, 0.0)
            while s < 1:
                if ds < 1e-3:
                    raise _Refused()
                s1 = min(1.0, s + ds)
                th_1 = rigid(s1)
                okn = th_1 is not None
                if okn:
                    guess = x.copy()
                    for j, i in enumerate(self.t.unknown_index):
                        guess[j] = (th_s[i] + x[j] * self.scale[j] - th_1[i]) / self.scale[j]
                    xn, okn = self.newton(guess, th_1, s1)
                if okn:
                    okn = self.accept(xn, th_1, s1, sign)
                if okn:
                    x, s, th_s = xn, s1, th_1
                    ds = min(0.5, ds * 1.5)
                else:
                    ds /= 2
        return self.answer(x, theta)

    def answer(self, x, theta):
        """The deviation at the solution x; _Refused where a plate is at p_limit of its sway
        buckling load or the truncation estimate is above est_limit."""
        tb = self.t
        with numpy.errstate(all="ignore"):
            dev = self.deviations(x, theta)
            ins = self._eval(x, theta, 1.0)[1]
            worst = 0.0
            for k in range(self.plates):
                p, ea, es = ins[5 * k + 1], ins[5 * k + 3], ins[5 * k + 4]
                worst = max(worst, -(1 + (ea - es) * p) * p * self.count**2 / math.pi**2)
            x2 = x
            if self.size:
                try:
                    x2 = x - numpy.linalg.solve(
                        self.jacobian(x, theta, 1.0), self.residual(x, theta, 1.0, 2)
                    )
                except numpy.linalg.LinAlgError:
                    raise _Refused() from None
            dev2 = self.deviations(x2, theta, 2)
        e24 = 0.0
        for k in range(len(dev) // 2):
            size = math.hypot(dev[2 * k], dev[2 * k + 1])
            if size > 0:
                change = math.hypot(dev2[2 * k] - dev[2 * k], dev2[2 * k + 1] - dev[2 * k + 1])
                e24 = max(e24, change / size)
        estimate = tb.est_factor * e24**2
        if not numpy.all(numpy.isfinite(dev)) or not worst < tb.p_limit:
            raise _Refused()
        if not estimate <= tb.est_limit:
            raise _Refused(truncation=True)
        return x, dev


def _reduced_solve(mech, x, theta, p, ok):
    """The loaded level at every configuration where ok: delta of the non-input hinges, what its
    deviation reads (q: the parameters and the deviation solved) and ok, False where the reduced
    equilibrium refuses or does not converge."""
    tb = mech.loaded
    shape, dtype = ok.shape, mech.dtype
    ok = numpy.array(ok)
    delta = [numpy.zeros(shape, dtype=dtype) for _ in mech.unknown_index]
    n_dev = 2 * len(mech.point_names)
    dev = [numpy.full(shape, numpy.nan, dtype=dtype) for _ in range(n_dev)]
    relations = {4: tb.relation4, 2: tb.relation2}
    for index in numpy.ndindex(*shape):
        if not ok[index]:
            continue
        pi = [float(numpy.broadcast_to(v, shape)[index]) for v in p]
        th = [float(numpy.broadcast_to(v, shape)[index]) for v in theta]
        xi = [float(numpy.broadcast_to(v, shape)[index]) for v in x]

        def rigid(s, th=th, xi=xi, pi=pi):
            if s == 1.0:
                return th
            with numpy.errstate(all="ignore"):
                angles, good = _rigid_angles(
                    mech, [numpy.array(v * s) for v in xi], pi, numpy.array(True)
                )
            return [float(v) for v in angles] if bool(good) else None

        found = None
        for count, variant in enumerate(tb.variants, 1):
            solver = _Variant(tb, variant, count, relations, pi)
            try:
                found = solver.solve(rigid), solver
                break
            except _Refused as refused:
                if not refused.truncation:
                    break
        if found is None:
            ok[index] = False
            continue
        (xs, d), solver = found
        for j in range(len(mech.unknown_index)):
            delta[j][index] = xs[j] * solver.scale[j]
        for i in range(n_dev):
            dev[i][index] = d[i]
    q = _Solved(p)
    q.deviation = dev
    return delta, q, ok
