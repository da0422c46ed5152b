"""symkin's numpy runtime for the `loaded` level (docs/physics.md, "`loaded`: Newton on the reduced
equilibrium"): the reduced equilibrium of symkin.physics.reduced over the mechanism's loaded_*
routines, solved by the solver the Python path runs (symkin/physics/reduced_solver.py: Newton,
continuation, refusals, buckling search), which the module holds before this text; here its
system (_Batch) and the driver over the variants. Only modules that hold the level hold it
(templates/numpy/module.py.j2), after the runtime.
"""

import numpy
from runtime import _rigid_angles  # the module holds them all: runtime.py and the solver

from symkin.physics.reduced_rates import _red_implicit, _red_inputs_x, _red_relation
from symkin.physics.reduced_solver import _red_equilibrium, _red_sway, _red_verdict

# ---- symkin runtime: every generated module with the loaded level holds what follows ----

# symkin reduced-equilibrium runtime (templates/numpy/reduced.py): the system the solver above
# (reduced_solver.py's _red_equilibrium, _red_verdict) runs on, over the generated routines, and
# the driver: two half plates per plate where one relation is refused by its estimate; all
# configurations at once, each on its own.


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


class _Batch:
    """One variant of the reduced equilibrium over b configurations at once, as the solver
    (reduced_solver.py) takes a system: R and J by stacked routines, the compression, the
    deviations; every step elementwise, so a configuration's answer does not depend on the
    others in its batch."""

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

    def compression(self, x, theta, p, t):
        """The worst half plate's compression over its sway buckling load per configuration
        (b,), from the half plates' inputs alone (no relation: past buckling too)."""
        _, ins, _ = self._inputs(x, theta, p, t)
        return self._worst(ins, x.shape[1])

    def _worst(self, ins, b):
        worst = numpy.zeros(b)
        for k in range(self.plates):
            w = _red_sway(ins[5 * k + 1], ins[5 * k + 3], ins[5 * k + 4], self.count)
            worst = numpy.where(w > worst, w, worst)
        return worst

    def measure(self, x, theta, p):
        """At load factor 1: the deviation (2 per point, b) at order 4, the worst compression
        (b,) and R (n, b) at order 2 (the truncation estimate's step)."""
        b = x.shape[1]
        args, ins, _ = self._inputs(x, theta, p, 1.0)
        _, vals = self._relation(ins)
        dev = numpy.array([_red_column(v, b) for v in self.dev_fn(args, theta, vals, p)])
        res = None
        if self.size:
            sys = self.res_fn(args, theta, self._values2(ins), p)
            res = numpy.array([_red_column(v, b) for v in sys])
        return dev, self._worst(ins, b), res

    def deviation2(self, x, theta, p):
        """The deviation (2 per point, b) at order 2 (the truncation estimate's)."""
        args, ins, _ = self._inputs(x, theta, p, 1.0)
        vals = self._values2(ins)
        return numpy.array([_red_column(v, x.shape[1]) for v in self.dev_fn(args, theta, vals, p)])

    def solve(self, inputs, theta, p, mech):
        """Every configuration (inputs, theta, p: lists of (b,) arrays): x (n, b), the deviation
        (2 per point, b) and a status each: 0, 1 refused or no convergence, 4 refused by the
        truncation estimate (reduced_solver.py's _red_equilibrium and _red_verdict)."""
        b = theta[0].shape[0]

        def rigid(k):
            return self._rigid(k, inputs, theta, p, mech)

        x, jac, ok, _, _ = _red_equilibrium(self, theta, p, rigid)
        status = numpy.where(ok, 0, 1)
        dev = numpy.full((2 * len(mech.point_names), b), numpy.nan)
        live = numpy.flatnonzero(ok)
        if live.size:
            th, pl = [v[live] for v in theta], [v[live] for v in p]
            dev[:, live], _, _, status[live] = _red_verdict(self, x[:, live], th, pl, jac[live])
        return x, dev, status

    def _rigid(self, k, inputs, theta, p, mech):
        """Configuration k's rigid(s) for the continuation: theta (numbers) at its inputs scaled
        by s, the force actuators' forces at its end kept (the load factor scales them); None
        where the rigid linkage has no pose."""
        tb = self.t
        th = [float(v[k]) for v in theta]
        forces = th[len(th) - tb.forces :]
        pk = [float(v[k]) for v in p]
        xi = [float(v[k]) for v in inputs]

        def rigid(s):
            if s == 1.0:
                return th
            with numpy.errstate(all="ignore"):
                angles, good = _rigid_angles(
                    mech, [numpy.array(v * s) for v in xi], pk, numpy.array(True)
                )
            return [float(v) for v in angles] + forces if bool(good) else None

        return rigid


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


def _red_rates(solver, out, blocks, jac, jo, dins, rel, b):
    """dy/dv (b, rows, cols) at the solutions of a variant (_red_solutions' solver, routine
    output, J, dR/d(plates), the half plates' x-Jacobian and relation) from a routine's blocks
    (dR_dv, din_dv, dy_dx, dy_dv, dy_dout), by the shared implicit-function theorem
    (reduced_rates.py's _red_implicit; reduced_report.py's rates, modes.py's compliance)."""
    n, ns = solver.size, solver.plates
    by = [_red_block(out, blocks[k], b) for k in ("dR_dv", "din_dv", "dy_dx", "dy_dout", "dy_dv")]
    part = _red_relation([r[3:] for r in rel], None, b)
    return _red_implicit(jac, jo, part, _red_inputs_x(dins, n, ns, b, 3), *by)
