"""symkin's numpy runtime (docs/runtime.md): what every generated numpy module runs around its
mechanism's routines, elementwise over arrays of configurations.

A generated module `<name>.py` holds the text below the marker line, verbatim
(templates/numpy/module.py.j2), so it imports only numpy and the standard library: its own
imports come first, then this text, then its routines, its tables (one _Mechanism) and its
public functions, each a call into this text. Imported on its own (tests/test_runtime_numpy.py),
this file is an ordinary module whose functions take small routines of the test's own; the
Newton driver and continuation it runs are the Python path's (symkin/kinematics/loop_newton.py,
which a generated module holds before this text).
"""

import math

import numpy

from symkin.kinematics.loop_newton import _continuation, _newton_solve

# ---- symkin runtime: every generated module holds what follows ----

# symkin runtime (templates/numpy/runtime.py, docs/runtime.md; tested on its own by
# tests/test_runtime_numpy.py): dense linear algebra over element arrays, the arithmetic the
# shared Newton and continuation run on (_Arith), the evaluation at every level, the
# sensitivities and the blockwise evaluation, all driven by the tables of one _Mechanism.

_TWO_PI = 2.0 * math.pi
_GAUSS_MAX = 12  # systems up to this size: elementwise elimination, as the C evaluator does
_CHUNK = 8192  # elements per block: the temporaries of a block stay in the CPU cache


class _Mechanism:
    """One generated module's tables, routines and solver settings (the C sk_mechanism):
    routines it lacks are None."""

    def __init__(self, **fields):
        self.__dict__.update(fields)


class _Level:
    """A generated level: its deviation routine, the closure it solves for delta (linear: A and
    r; newton: F and dF/ddelta, None for the first-order delta; both None: none), whether the
    loaded level's driver solves it (mech.loaded_solve, templates/numpy/reduced.py) and its
    sensitivity routine with the (offset, rows, cols) of its blocks; with redundant loops,
    `consistency`: its closure's dropped rows and their terms' size (theta, delta, q)."""

    def __init__(
        self, dev, linear=None, newton=None, loaded=0, sens=None, blocks=None, consistency=None
    ):
        self.dev, self.linear, self.newton, self.loaded = dev, linear, newton, loaded
        self.sens, self.blocks, self.consistency = sens, blocks or {}, consistency


def _value(v, dtype):
    """A parameter value: a float, or an array for many parameter sets at once."""
    return float(v) if numpy.ndim(v) == 0 else numpy.asarray(v, dtype=dtype)


def _wrap(angle):
    return angle - _TWO_PI * numpy.round(angle / _TWO_PI)


def _matrix(entries, rows, cols, shape, dtype):
    """A (*shape, rows, cols) array from a row-major list of arrays (or numbers)."""
    out = numpy.empty(shape + (rows, cols), dtype=dtype)
    for i in range(rows):
        for j in range(cols):
            out[..., i, j] = entries[i * cols + j]
    return out


def _block(entries, block, shape, dtype):
    """The (offset, rows, cols) block of a routine's outputs as a (*shape, rows, cols) array."""
    at, rows, cols = block
    return _matrix(entries[at : at + rows * cols], rows, cols, shape, dtype)


def _solve(a, b, ok, m=1, dtype=numpy.float64):
    """Batched dense solve a x = b (a row-major k*k list, b a row-major k*m list: m right-hand
    sides); bad elements -> ok False. The solution as a row-major k*m list."""
    k = len(b) // m
    if k <= _GAUSS_MAX:
        return _gauss(a, b, ok, k, m, dtype)
    shape = ok.shape
    am = _matrix(a, k, k, shape, dtype)
    bm = _matrix(b, k, m, shape, dtype)
    # numpy.array: a writable array even for 0-d input, where & gives a numpy.bool scalar
    good = numpy.array(
        ok & numpy.isfinite(am).all(axis=(-1, -2)) & numpy.isfinite(bm).all(axis=(-1, -2))
    )
    am[~good] = numpy.eye(k)
    bm[~good] = 0.0
    try:
        x = numpy.linalg.solve(am, bm)
    except numpy.linalg.LinAlgError:
        x = numpy.zeros(shape + (k, m), dtype=dtype)
        for index in numpy.ndindex(*shape):
            try:
                x[index] = numpy.linalg.solve(am[index], bm[index])
            except numpy.linalg.LinAlgError:
                good[index] = False
    good &= numpy.isfinite(x).all(axis=(-1, -2))
    return [x[..., i, j] for i in range(k) for j in range(m)], good


def _gauss(a, b, ok, k, m, dtype):
    """_solve by Gaussian elimination with partial pivoting written out over the element
    arrays, step for step the C evaluator's sk_solve (one small LAPACK call per element costs
    more than the whole elimination)."""
    shape = ok.shape
    A = [
        [numpy.array(numpy.broadcast_to(a[i * k + j], shape), dtype=dtype) for j in range(k)]
        for i in range(k)
    ]
    B = [
        [numpy.array(numpy.broadcast_to(b[i * m + r], shape), dtype=dtype) for r in range(m)]
        for i in range(k)
    ]
    good = numpy.array(ok)
    for c in range(k):
        # the pivot: the first row i >= c with the largest |a[i][c]|
        best = numpy.abs(A[c][c])
        pivot = numpy.full(shape, c)
        for i in range(c + 1, k):
            size = numpy.abs(A[i][c])
            larger = size > best
            best = numpy.where(larger, size, best)
            pivot = numpy.where(larger, i, pivot)
        good &= (best > 0.0) & numpy.isfinite(best)
        for i in range(c + 1, k):
            swap = pivot == i
            if swap.any():
                for row in (A, B):
                    for j in range(len(row[c])):
                        row[c][j], row[i][j] = (
                            numpy.where(swap, row[i][j], row[c][j]),
                            numpy.where(swap, row[c][j], row[i][j]),
                        )
        for i in range(c + 1, k):
            f = A[i][c] / A[c][c]
            for j in range(c, k):
                A[i][j] = A[i][j] - f * A[c][j]
            for r in range(m):
                B[i][r] = B[i][r] - f * B[c][r]
    for r in range(m):
        for i in range(k - 1, -1, -1):
            s = B[i][r]
            for j in range(i + 1, k):
                s = s - A[i][j] * B[j][r]
            B[i][r] = s / A[i][i]
    x = [B[i][r] for i in range(k) for r in range(m)]
    for v in x:
        good &= numpy.isfinite(v)
    return x, good


class _Arith:
    """The arithmetic of the shared Newton (symkin/kinematics/loop_newton.py) over element
    arrays of `dtype`: the solve is _solve's elimination, step for step the C evaluator's."""

    def __init__(self, dtype):
        self.dtype = dtype

    def solve(self, a, b, ok):
        return _solve(a, b, ok, 1, self.dtype)

    where = staticmethod(numpy.where)

    @staticmethod
    def largest(values):
        return numpy.max(numpy.abs(numpy.array(values)), axis=0)

    @staticmethod
    def full(ok, value):
        return numpy.full(ok.shape, value)


def _rigid_angles(mech, x, params, ok):
    """The rigid hinge angles (all hinges, label order) and the updated ok mask: the closed-form
    dyads, or continuation from the as-fabricated pose; then the winding rule (every loop's
    angles sum to 0, not +-2 pi) and the polish (the relative accuracy of small angles)."""
    shape, dtype = ok.shape, mech.dtype
    theta = [numpy.zeros(shape, dtype=dtype) for _ in range(mech.n_theta)]
    for j, i in enumerate(mech.input_index):
        theta[i] = x[j]
    for i, value in mech.fixed:
        theta[i] = numpy.full(shape, value, dtype=dtype)
    if not mech.unknown_index:
        return theta, ok
    k = len(mech.unknown_index)
    ar = _Arith(dtype)

    def system(theta):
        # the residual, then A (rigid_res holds both)
        fj = mech.rigid_res(theta, params)
        return [numpy.broadcast_to(r, shape) for r in fj[:k]] + fj[k:]

    if mech.rigid is not None:
        out = mech.rigid(x, params)
        for reach in out[k : k + mech.n_dyads]:
            ok = ok & (numpy.broadcast_to(reach, shape) >= 0.0)
        for j, i in enumerate(mech.unknown_index):
            theta[i] = numpy.where(ok, _wrap(numpy.broadcast_to(out[j], shape)), 0.0)
        # an angle whose inputs are all zero is exactly zero (its formula rounds to noise there)
        for i, reads in mech.rest:
            moved = numpy.zeros(shape, dtype=bool)
            for j in reads:
                moved = moved | (x[j] != 0.0)
            theta[i] = numpy.where(moved, theta[i], 0.0)
    else:
        top = max(
            [float(numpy.max(numpy.abs(v))) if v.size else 0.0 for v in x]
            + [0.0]
            + [abs(value) for _, value in mech.fixed]
        )

        def stage(t):
            for j, i in enumerate(mech.input_index):
                theta[i] = x[j] * t
            for i, value in mech.fixed:
                theta[i] = numpy.full(shape, value * t, dtype=dtype)

        theta, ok = _continuation(
            ar,
            stage,
            system,
            theta,
            mech.unknown_index,
            ok,
            mech.rigid_rule,
            top,
            mech.continuation_step,
        )
    out = system(theta)
    for n in mech.angular:
        ok = ok & (numpy.abs(out[n]) < mech.winding)
    theta, ok, _ = _newton_solve(ar, system, theta, mech.unknown_index, ok, mech.polish_rule, out)
    if mech.consistency_rigid is not None:
        ok = _consistent(mech, mech.consistency_rigid(theta, params), ok)
    return theta, ok


def _consistent(mech, out, ok):
    """Redundant loops (symkin.core.settings, 4): where each dropped closure row (out: the rows,
    then the size of their terms) vanishes to mech.consistent of its size; else not ok."""
    n = mech.n_dropped
    for i in range(n):
        ok = ok & (numpy.abs(out[i]) <= mech.consistent * numpy.asarray(out[n + i]))
    return ok


def _solve_closure(mech, linear, newton, theta, q, ok):
    """delta of a closure: A delta = -r (its first-order delta), then with `newton` (F,
    dF/ddelta) Newton from there; and ok."""
    k = len(mech.unknown_index)
    lin = linear(theta, q)  # A, r, then S: the size of r's terms
    rhs = [-numpy.asarray(r) for r in lin[k * k : k * k + k]]
    delta, good = _solve(lin[: k * k], rhs, ok, 1, mech.dtype)
    ok = ok & good
    if newton is None:
        return delta, ok
    delta, ok, converged = _newton_solve(
        _Arith(mech.dtype),
        lambda delta: newton(theta, delta, q),
        delta,
        range(k),
        ok,
        mech.exact_rule,
        scale=lin[k * k + k :],
    )
    return delta, ok & converged


def _pose(mech, arrays, level, p, links):
    """The rigid angles theta (every hinge), delta (the non-input hinges; solved for the links'
    rotations only when `links`), the ok mask and what the level's routines read (q)."""
    lv = mech.levels[level]
    shape = arrays[0].shape
    ok = numpy.ones(shape, dtype=bool)
    for a in arrays:
        # an input is a plate's rotation from the as-fabricated pose: |angle| <= pi
        ok &= numpy.isfinite(a) & (numpy.abs(a) <= math.pi)
    x = [numpy.where(ok, a, 0.0) for a in arrays]
    with numpy.errstate(all="ignore"):
        theta, ok = _rigid_angles(mech, x, p, ok)
        q = p  # what the level's routines read: the parameters (loaded: and its deviation)
        delta = [numpy.zeros(shape, dtype=mech.dtype) for _ in mech.unknown_index]
        if lv.loaded:
            # the reduced equilibrium (templates/numpy/reduced.py) gives delta and the deviation
            delta, q, ok = mech.loaded_solve(mech, x, theta, p, ok)
        elif lv.linear is not None and (mech.needs_loops or (links and mech.loops_for_links)):
            delta, ok = _solve_closure(mech, lv.linear, lv.newton, theta, q, ok)
            if lv.consistency is not None:
                ok = _consistent(mech, lv.consistency(theta, delta, q), ok)
        for i, limit in mech.limits:
            ok = ok & (numpy.abs(theta[i]) <= limit)
            if i in mech.unknown_index:
                ok = ok & (numpy.abs(theta[i] + delta[mech.unknown_index.index(i)]) <= limit)
    return theta, delta, ok, q


def _points(mech, theta, delta, ok, level, p, q, links):
    """The points, angles and (with `links`) the links' rotations of solved configurations, NaN
    where not ok; the rigid points read the parameters p, the level's deviation q."""
    shape, dtype = ok.shape, mech.dtype
    with numpy.errstate(all="ignore"):
        rigid = mech.rigid_points(theta, p)
        dev = mech.levels[level].dev(theta, delta, q)
        use = links and mech.links is not None
        rot = [numpy.broadcast_to(v, shape) for v in mech.links(theta, delta)] if use else []
    rigid = [numpy.broadcast_to(v, shape) for v in rigid]
    dev = [numpy.broadcast_to(v, shape) for v in dev]
    for v in rigid + dev + rot:
        ok = ok & numpy.isfinite(v)  # a non-finite result is never ok
    compliant = list(theta)
    for j, i in enumerate(mech.unknown_index):
        compliant[i] = theta[i] + delta[j]
    angles = {"rigid": {}, "compliant": {}}
    for i, name in enumerate(mech.hinge_names):
        angles["rigid"][name] = numpy.where(ok, numpy.broadcast_to(theta[i], shape), numpy.nan)
        angles["compliant"][name] = numpy.where(
            ok, numpy.broadcast_to(compliant[i], shape), numpy.nan
        )
    result = {}
    for n, name in enumerate(mech.point_names):
        r = numpy.stack(rigid[2 * n : 2 * n + 2])
        d = numpy.stack(dev[2 * n : 2 * n + 2])
        r = numpy.where(ok, r, numpy.nan).astype(dtype)
        d = numpy.where(ok, d, numpy.nan).astype(dtype)
        result[name] = {"rigid": r, "compliant": r + d, "deviation": d}
    rotations = {}
    n_links = len(mech.link_names)
    for i, name in enumerate(mech.link_names if links else ()):
        r = numpy.where(ok, _wrap(rot[i]), numpy.nan).astype(dtype)
        d = numpy.where(ok, rot[n_links + i], numpy.nan).astype(dtype)
        rotations[name] = {"rigid": r, "compliant": r + d, "deviation": d}
    return {"points": result, "ok": ok, "angles": angles, "links": rotations}


def _prepare(mech, inputs, level, params):
    """Checked arguments: the broadcast input arrays and the parameter values."""
    if level not in mech.levels:
        raise ValueError(f"level must be one of {tuple(mech.levels)}, got {level!r}")
    names = set(inputs) - set(mech.pruned_inputs)
    if names != set(mech.input_names):
        pruned = mech.pruned_inputs
        ignored = f" (accepted and ignored: {pruned})" if pruned else ""
        raise ValueError(
            f"inputs must be exactly {mech.input_names}{ignored}, got {tuple(sorted(inputs))}"
        )
    if not mech.input_names:
        # a structure (docs/levels.md, "Structures"): no inputs, the batch is its parameters'
        # arrays broadcast, carried by one zero array of their shape that no routine reads
        values = [numpy.asarray(v, dtype=mech.dtype) for v in mech.parameters(params)]
        shape = numpy.broadcast_shapes(*(v.shape for v in values))
        p = [numpy.broadcast_to(v, shape) if v.shape else mech.dtype(v) for v in values]
        return [numpy.zeros(shape, dtype=mech.dtype)], p
    arrays = numpy.broadcast_arrays(
        *(numpy.asarray(inputs[n], dtype=mech.dtype) for n in mech.input_names)
    )
    return arrays, [mech.dtype(v) for v in mech.parameters(params)]


def _blocks(run, arrays, *args):
    """run(arrays, *args) over cache-sized blocks of the flattened inputs, its nested dict of
    arrays (elements on the last axis) joined and shaped like the inputs; parameter values
    shaped like the inputs (a structure's batch, _prepare) are cut alike."""
    shape = arrays[0].shape
    size = arrays[0].size
    if size <= _CHUNK:
        return run(arrays, *args)
    flat = [a.reshape(-1) for a in arrays]

    def cut(arg, k):
        if isinstance(arg, list) and any(numpy.shape(v) == shape for v in arg):
            return [v.reshape(-1)[k : k + _CHUNK] if numpy.shape(v) == shape else v for v in arg]
        return arg

    parts = [
        run([a[k : k + _CHUNK] for a in flat], *(cut(g, k) for g in args))
        for k in range(0, size, _CHUNK)
    ]

    def join(items):
        if isinstance(items[0], dict):
            return {key: join([item[key] for item in items]) for key in items[0]}
        return numpy.concatenate(items, axis=-1).reshape(items[0].shape[:-1] + shape)

    return join(parts)


def _evaluate(mech, inputs, level, params, links):
    """The module's evaluate()."""
    arrays, p = _prepare(mech, inputs, level, params)
    return _blocks(_evaluate_block, arrays, mech, level, p, links)


def _evaluate_block(arrays, mech, level, p, links):
    """evaluate() on one block of broadcast input arrays and parameter values p."""
    theta, delta, ok, q = _pose(mech, arrays, level, p, links)
    return _points(mech, theta, delta, ok, level, p, q, links)


def _sensitivity_full(mech, inputs, level, params):
    """The module's sensitivity_full()."""
    levels = tuple(name for name, lv in mech.levels.items() if lv.sens is not None)
    if level not in levels:
        raise ValueError(
            f"sensitivities are derived at the levels {levels}, not {level!r} (docs/sensitivity.md)"
        )
    arrays, p = _prepare(mech, inputs, level, params)
    return _blocks(_sensitivity_block, arrays, mech, level, p)


def _rigid_rates(mech, theta, p, ok):
    """The rigid points' dR/dv (*shape, 2 n_P, n_v) at the hinge angles theta, the non-input
    hinges' dtheta_u/dv (*shape, k, n_v; None without them) and ok: the implicit-function
    theorem on the rigid closure, Theta = -A^-1 dG/dv, dR/dv + dR/dtheta_u Theta."""
    shape, dtype = ok.shape, mech.dtype
    k, nv = len(mech.unknown_index), mech.n_variables
    sr = mech.sens_rigid(theta, p)
    rb = mech.sens_rigid_blocks
    rig = _block(sr, rb["dR_dv"], shape, dtype)
    if not k:
        return rig, None, ok
    at, size = rb["dG_dv"][0], k * nv
    a = sr[rb["A"][0] : rb["A"][0] + k * k]
    th, good = _solve(a, [-numpy.asarray(v) for v in sr[at : at + size]], ok, nv, dtype)
    th = _matrix(th, k, nv, shape, dtype)
    rig = rig + numpy.matmul(_block(sr, rb["dR_dtheta"], shape, dtype), th)
    return rig, th, ok & good


def _chained(mech, p, *rates):
    """The rates (*shape, rows, n_v) by the parameters made totals in place: a parameter's
    default that reads earlier ones follows them (sens_chain), last first."""
    if mech.sens_chain is None:
        return
    c = mech.sens_chain(p)
    n = len(mech.parameter_names)
    for i in range(n - 1, -1, -1):
        for j in range(i + 1, n):
            for r in rates:
                r[..., i] += c[j * n + i] * r[..., j]


def _sensitivity_block(arrays, mech, level, p):
    """sensitivity_full() on one block: the implicit-function theorem on the closures."""
    theta, delta, ok, q = _pose(mech, arrays, level, p, True)
    result = _points(mech, theta, delta, ok, level, p, q, True)
    ok = result["ok"]
    shape, dtype = ok.shape, mech.dtype
    k, nv = len(mech.unknown_index), mech.n_variables
    lv = mech.levels[level]
    b = lv.blocks
    with numpy.errstate(all="ignore"):
        rig, th, ok = _rigid_rates(mech, theta, p, ok)
        if lv.loaded:
            # the reduced equilibrium's own (templates/numpy/reduced_sens.py)
            dev = lv.sens(mech, theta, p, q, th, ok).astype(dtype)
        else:
            s = lv.sens(theta, delta, p)
            dev = _block(s, b["dD_dv"], shape, dtype)
        if "M" in b:
            # Y = -M^-1 (dE/dv + dE/dtheta_u Theta)
            rhs = -(
                _block(s, b["dE_dv"], shape, dtype)
                + numpy.matmul(_block(s, b["dE_dtheta"], shape, dtype), th)
            )
            m = s[b["M"][0] : b["M"][0] + k * k]
            y, good = _solve(
                m, [rhs[..., i, j] for i in range(k) for j in range(nv)], ok, nv, dtype
            )
            ok = ok & good
            dev = dev + numpy.matmul(
                _block(s, b["dD_ddelta"], shape, dtype), _matrix(y, k, nv, shape, dtype)
            )
        if k and not lv.loaded:
            dev = dev + numpy.matmul(_block(s, b["dD_dtheta"], shape, dtype), th)
        _chained(mech, p, dev, rig)
    ok = ok & numpy.isfinite(dev).all(axis=(-1, -2)) & numpy.isfinite(rig).all(axis=(-1, -2))
    if not ok.all():
        for key in result["points"]:
            for part in result["points"][key].values():
                part[..., ~ok] = numpy.nan
        for kind in result["angles"].values():
            for h in kind:
                kind[h] = numpy.where(ok, kind[h], numpy.nan)
        for link in result["links"].values():
            for key in link:
                link[key] = numpy.where(ok, link[key], numpy.nan)
    dev = numpy.where(ok[..., None, None], dev, numpy.nan)
    rig = numpy.where(ok[..., None, None], rig, numpy.nan)
    names = list(mech.parameter_names)

    def table(m, n):
        rows = numpy.moveaxis(m[..., 2 * n : 2 * n + 2, :], -1, 0)
        rows = numpy.moveaxis(rows, -1, 1)  # (variable, 2, *shape)
        return {
            "params": {q: rows[v] for v, q in enumerate(names)},
            "inputs": {h: rows[len(names) + v] for v, h in enumerate(mech.input_names)},
        }

    result["ok"] = ok
    result["deviation"] = {n: table(dev, i) for i, n in enumerate(mech.point_names)}
    result["rigid"] = {n: table(rig, i) for i, n in enumerate(mech.point_names)}
    return result
