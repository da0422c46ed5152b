"""symkin's numpy runtime for the natural frequencies and mode shapes at the `loaded` level
(docs/physics.md, "Natural frequencies"; docs/generated-code.md, "Natural frequencies in
generated code"): the compliance of virtual loads at the massive links' centres by the
implicit-function theorem at the solution templates/numpy/reduced.py found (the mechanism's
loaded_modes<g> routines, assembled as reduced_report.py assembles the report's), then the
eigenproblem M^1/2 C M^1/2 v = v/omega^2 of symkin.physics.modes.solve on every configuration
at once (numpy.linalg.eigh on the stacked matrices: each configuration's answer its own). Only
modules whose files give links a mass hold it (templates/numpy/module.py.j2), after
templates/numpy/reduced.py (and reduced_actuators.py with actuators).
"""

import math

import numpy
from reduced import _red_rates, _red_solutions  # the module holds them all
from reduced_actuators import _actuated_state
from runtime import _blocks, _points, _pose, _prepare

# ---- symkin runtime: every generated module whose links carry mass holds this ----

# Its rules (symkin.core.settings.ModesSettings) are the modes table's (mech.modes): rigid, an
# eigenvalue 1/omega^2 this small against the largest is a direction held rigidly (an infinite
# frequency), this negative an unstable equilibrium (not ok); pure_rotation, a mode whose
# largest centre translation is below this times its largest rotation times the span is
# normalised by its rotation.


def _modes(mech, inputs, params, count, actuated=None):
    """The module's modes(): the `count` lowest natural modes at `loaded` of every configuration
    (inputs and parameters broadcast as evaluate()'s; `actuated`: the module's (ACTUATORS,
    FORCES, INPUTS) when it has actuators). {"frequencies": (count, *shape) Hz, "links": {L:
    (count, 3, *shape)}, "points": {P: (count, 2, *shape)}, "ok": (*shape)}; a mode the
    configuration does not have (held rigidly, or beyond its degrees of freedom with mass) has
    an infinite frequency and a NaN shape; NaN everywhere where not ok."""
    count = int(count)
    if count < 1:
        raise ValueError(f"count must be at least 1, got {count}")
    # the inputs broadcast with the parameters' arrays too (a batch of parameter sets)
    given = [numpy.shape(v) for v in inputs.values()]
    values = [numpy.shape(v) for v in mech.parameters(params)]
    shape = numpy.broadcast_shapes(*given, *values)
    inputs = {n: numpy.broadcast_to(v, shape) for n, v in inputs.items()}
    if actuated is not None:
        actuators, forces, drives = actuated
        with numpy.errstate(all="ignore"):
            st = _actuated_state(mech, actuators, forces, drives, inputs, params)
        theta = list(st["theta"]) + st["loads"]
        return _modes_at(mech, theta, st["p"], st["q"], st["ok"], count)
    arrays, p = _prepare(mech, inputs, "loaded", params)
    if any(values):  # parameter arrays: one block (runtime.py's _blocks splits the inputs alone)
        return _modes_block(arrays, mech, p, count)
    return _blocks(_modes_block, arrays, mech, p, count)


def _modes_block(arrays, mech, p, count):
    """_modes on one block of broadcast input arrays (runtime.py's _blocks)."""
    theta, delta, ok, q = _pose(mech, arrays, "loaded", p, False)
    ok = _points(mech, theta, delta, ok, "loaded", p, q, False)["ok"]
    return _modes_at(mech, theta, p, q, ok, count)


def _modes_compliance(mech, theta, p, q, shape, good):
    """The compliance (size, 3 (C + P), 3 C) of the solved configurations (good: a flat mask),
    NaN elsewhere: rows the C centres' then the P shown points' (dx, dy, dphi) (file unit, rad),
    columns a virtual (F_x, F_y, M) at each centre (N, N u): dy/dv by the implicit-function
    theorem on the reduced equilibrium (reduced.py's _red_rates, as the report's rates)."""
    md = mech.modes
    nc, npt = len(md.links), len(md.points)
    out_c = numpy.full((good.size, 3 * (nc + npt), 3 * nc), numpy.nan)
    routines = [fn for fn, _ in md.routines]
    for where, solver, out, jac, jo, _, dins, rel in _red_solutions(
        mech, theta, p, q, shape, good, routines
    ):
        blocks = md.routines[solver.count - 1][1]
        out_c[where] = _red_rates(solver, out, blocks, jac, jo, dins, rel, where.size)
    return out_c


def _modes_at(mech, theta, p, q, ok, count):
    """The modes of the configurations solved (ok), as _modes returns them."""
    md = mech.modes
    shape = ok.shape
    size = ok.size
    nc, npt = len(md.links), len(md.points)
    good = numpy.broadcast_to(ok, shape).reshape(-1).copy()
    compliance = _modes_compliance(mech, theta, p, q, shape, good)
    data = [numpy.broadcast_to(numpy.asarray(v, float), shape).reshape(-1) for v in md.data(p)]
    masses = numpy.array(data[: 2 * nc]).T.reshape(size, nc, 2)
    at = numpy.array(data[2 * nc : 2 * nc + 2 * md.coordinates]).T.reshape(size, -1, 2)
    lengths = numpy.array(data[2 * nc + 2 * md.coordinates :]).reshape(-1, size)
    # the span (symkin.physics.modes.span_of): the largest distance, at least the longest hinge
    span = numpy.sqrt(((at[:, :, None, :] - at[:, None, :, :]) ** 2).sum(-1)).max(axis=(1, 2))
    if lengths.size:
        span = numpy.maximum(span, lengths.max(axis=0))
    # SI: C_SI = D C D, D = (sqrt s, sqrt s, 1/sqrt s) per point, s metres per file unit
    root_s = math.sqrt(md.unit_scale)
    d = numpy.tile([root_s, root_s, 1 / root_s], nc + npt)
    c_si = compliance * d[None, :, None] * d[None, None, : 3 * nc]
    weights = numpy.stack([masses[:, :, 0], masses[:, :, 0], masses[:, :, 1]], axis=-1)
    root = numpy.sqrt(weights.reshape(size, 3 * nc))  # an inertia 0: a zero row, mu = 0
    reduced = c_si[:, : 3 * nc, :]
    a = root[:, :, None] * (reduced + reduced.transpose(0, 2, 1)) / 2 * root[:, None, :]
    good &= numpy.all(numpy.isfinite(a), axis=(1, 2)) & numpy.isfinite(span)
    mu = numpy.full((size, 3 * nc), numpy.nan)
    v = numpy.full((size, 3 * nc, 3 * nc), numpy.nan)
    live = numpy.flatnonzero(good)
    if live.size:
        mu[live], v[live] = numpy.linalg.eigh(a[live])
    with numpy.errstate(all="ignore"):
        largest = numpy.max(numpy.abs(mu), axis=1)
        # an unstable equilibrium (loads beyond buckling): no natural frequencies
        good &= (largest > 0) & (mu[:, 0] >= -md.rigid * largest)
        mu, v = mu[:, ::-1], v[:, :, ::-1]  # the lowest frequencies first
        finite = mu > md.rigid * largest[:, None]
        freq = numpy.where(finite, numpy.sqrt(1 / mu) / (2 * math.pi), math.inf)
        # every row's response to the mode's inertia loads omega^2 M q = omega^2 root v
        modes = numpy.matmul(c_si, root[:, :, None] * v / mu[:, None, :]) / d[None, :, None]
    k = min(count, 3 * nc)
    freq = numpy.concatenate([freq[:, :k], numpy.full((size, count - k), math.inf)], axis=1)
    finite = numpy.concatenate([finite[:, :k], numpy.zeros((size, count - k), bool)], axis=1)
    modes = numpy.concatenate(
        [modes[:, :, :k], numpy.full((size, 3 * (nc + npt), count - k), numpy.nan)], axis=2
    )
    modes = _modes_normalised(modes, nc, span, md.pure_rotation)
    modes = numpy.where((good[:, None] & finite)[:, None, :], modes, numpy.nan)
    freq = numpy.where(good[:, None], freq, numpy.nan)
    ok = good.reshape(shape)

    def shaped(values):  # (size, rows, count) -> (count, rows, *shape)
        return (
            numpy.moveaxis(values, 0, -1)
            .transpose(1, 0, 2)
            .reshape((count, values.shape[1]) + shape)
        )

    return {
        "frequencies": freq.T.reshape((count,) + shape),
        "links": {n: shaped(modes[:, 3 * j : 3 * j + 3]) for j, n in enumerate(md.links)},
        "points": {
            n: shaped(modes[:, 3 * (nc + j) : 3 * (nc + j) + 2]) for j, n in enumerate(md.points)
        },
        "ok": ok,
    }


def _modes_normalised(modes, nc, span, pure_rotation):
    """Each mode (size, rows, count) scaled so that its largest centre translation is +1, or,
    a pure rotation (that translation below pure_rotation times its largest rotation times the
    span), its largest rotation +1 rad (symkin.physics.modes._normalised)."""
    index = numpy.arange(3 * nc).reshape(nc, 3)
    moves = modes[:, index[:, :2].reshape(-1), :]
    turns = modes[:, index[:, 2], :]
    with numpy.errstate(all="ignore"):
        j = numpy.argmax(numpy.where(numpy.isnan(moves), -1, numpy.abs(moves)), axis=1)
        move = numpy.take_along_axis(moves, j[:, None, :], axis=1)[:, 0, :]
        i = numpy.argmax(numpy.where(numpy.isnan(turns), -1, numpy.abs(turns)), axis=1)
        turn = numpy.take_along_axis(turns, i[:, None, :], axis=1)[:, 0, :]
        pure = numpy.abs(move) <= pure_rotation * numpy.abs(turn) * span[:, None]
        return modes / numpy.where(pure, turn, move)[:, None, :]
