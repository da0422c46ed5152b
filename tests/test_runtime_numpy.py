"""templates/numpy/runtime.py on its own: imported as a module and driven with routines of the
toy mechanism of tests/runtime_toy.py, every function checked against independent computations
(an elimination written out in Python floats, numpy.linalg, mpmath at 30 digits)."""

from __future__ import annotations

import importlib.util
import math

import numpy as np
import pytest
from conftest import ROOT
from runtime_toy import close, eliminate, toy, toy_partials

from symkin.codegen.templating import runtime, shared
from symkin.kinematics.loop_newton import _newton_stop, _Rule

PATH = ROOT / "templates" / "numpy" / "runtime.py"


@pytest.fixture(scope="module")
def rt():
    spec = importlib.util.spec_from_file_location("symkin_numpy_runtime", PATH)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


# ---- dense linear algebra over element arrays ----


@pytest.mark.parametrize("k, m", [(1, 1), (2, 3), (3, 1), (5, 2), (12, 1)])
def test_gauss_is_the_elimination_bit_for_bit_per_element(rt, k, m):
    rng = np.random.default_rng(k * 10 + m)
    a = rng.normal(size=(k, k, 7))
    a[rng.integers(k)] *= 1e3  # pivoting matters
    b = rng.normal(size=(k, m, 7))
    ok = np.ones(7, dtype=bool)
    x, good = rt._solve(list(a.reshape(k * k, 7)), list(b.reshape(k * m, 7)), ok, m)
    assert good.all()
    x = np.array(x).reshape(k, m, 7)
    for e in range(7):
        want = eliminate(a[:, :, e].tolist(), b[:, :, e].tolist())
        assert x[:, :, e].tolist() == want
        np.testing.assert_allclose(
            x[:, :, e], np.linalg.solve(a[:, :, e], b[:, :, e]), rtol=1e-9, atol=1e-12
        )


def test_solve_beyond_gauss_max_uses_lapack_per_element(rt):
    k = rt._GAUSS_MAX + 2
    rng = np.random.default_rng(1)
    a = rng.normal(size=(k, k, 4))
    a[:, :, 2] = 0.0  # singular element
    b = rng.normal(size=(k, 4))
    ok = np.array([True, True, True, False])
    x, good = rt._solve(list(a.reshape(k * k, 4)), list(b), ok)
    assert good.tolist() == [True, True, False, False]
    for e in (0, 1):
        np.testing.assert_allclose(
            np.array(x)[:, e], np.linalg.solve(a[:, :, e], b[:, e]), rtol=1e-9, atol=1e-12
        )


def test_solve_marks_singular_and_non_finite_elements(rt):
    nan, inf = float("nan"), float("inf")
    # elements: regular, zero, rank one, NaN entry, infinite entry
    a = [
        np.array([2.0, 0.0, 1.0, 1.0, inf]),
        np.array([1.0, 0.0, 2.0, nan, 0.0]),
        np.array([1.0, 0.0, 2.0, 0.0, 0.0]),
        np.array([3.0, 0.0, 4.0, 1.0, 1.0]),
    ]
    b = [np.ones(5), np.ones(5)]
    with np.errstate(all="ignore"):
        x, good = rt._solve(a, b, np.ones(5, dtype=bool))
    assert good.tolist() == [True, False, False, False, False]
    assert [x[0][0], x[1][0]] == [0.4, 0.2]


def test_wrap_keeps_half_turns_and_wraps_the_rest(rt):
    x = np.array([0.0, 1.0, -3.0, math.pi, 3.5, -3.5, 7.0, -20.0])
    got = rt._wrap(x)
    assert got[:4].tolist() == x[:4].tolist()
    want = [math.remainder(v, 2 * math.pi) for v in x]
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-14)


# ---- Newton and continuation ----


def circle(t):
    """x0^2 + x1^2 = 4 and x0 = t x1, residual then Jacobian (the C driver's system)."""

    def system(x):
        x0, x1 = x[0], x[1]
        one = np.ones_like(x0)
        return [x0 * x0 + x1 * x1 - 4.0, x0 - t * x1, 2.0 * x0, 2.0 * x1, one, -t * one]

    return system


@pytest.mark.parametrize(
    "rule, change, size, previous, stop",
    [
        ((30, 1e-10), 1e-10, 1.0, math.inf, True),
        ((30, 1e-10), 2e-10, 0.0, math.inf, False),
        ((30, 1e-10), 2e-10, 1.0, 1e-10, False),
        ((40, 0.0, 1e-8, 1e-12, 0.5), 1e-9, 0.2, math.inf, True),
        ((40, 0.0, 1e-8, 1e-12, 0.5), 1e-8, 0.2, math.inf, False),
        ((40, 0.0, 1e-8, 1e-12, 0.5), 0.5, 0.0, math.inf, False),  # onto zero: goes on
        ((40, 0.0, 1e-8, 1e-12, 0.5), 0.0, 0.0, math.inf, True),  # a zero step at zero
        ((40, 0.0, 1e-20, 1e-12, 0.5), 1e-13, 1.0, 1e-13, True),
        ((40, 0.0, 1e-20, 1e-12, 0.5), 1e-13, 1.0, 1e-12, False),
        ((40, 0.0, 1e-20, 1e-12, 0.5), 1e-11, 1.0, 1e-11, False),
        ((40, 0.0, 1e-8, 1e-12, 0.5), math.nan, 1.0, math.inf, False),
    ],
)
def test_newton_stop(rt, rule, change, size, previous, stop):
    with np.errstate(all="ignore"):
        got = _newton_stop(_Rule(*rule), np.array(change), np.array(size), previous)
    assert bool(got) is stop


def test_newton_per_element(rt):
    rule = _Rule(40, 0.0, 1e-8, 1e-12, 0.5)
    start = [np.array([1.0, 0.0, 30.0, 1.2]), np.array([1.5, 0.0, -7.0, 1.4])]
    ok = np.array([True, True, True, False])
    with np.errstate(all="ignore"):
        x, good, stopped = rt._newton_solve(
            rt._Arith(np.float64), circle(1.0), [v.copy() for v in start], [0, 1], ok, rule
        )
    root = math.sqrt(2.0)
    # element 1 starts where J is singular; element 3 is not ok to begin with
    assert good.tolist() == [True, False, True, False]
    assert stopped[[0, 2]].all()
    for e in (0, 2):
        assert abs(x[0][e] - root) <= 2e-16 * root and abs(x[1][e] - root) <= 2e-16 * root
    assert x[0][3] == 1.2 and x[1][3] == 1.4  # untouched where not ok
    # the unknowns at x[3], x[1] of a longer list, and the system given at the start
    longer = [np.full(4, 100.0 + i) for i in range(5)]
    longer[3], longer[1] = start[0].copy(), start[1].copy()

    def mapped(x):
        return circle(1.0)([x[3], x[1]])

    with np.errstate(all="ignore"):
        y, good2, stopped2 = rt._newton_solve(
            rt._Arith(np.float64), mapped, longer, [3, 1], ok, rule, mapped(longer)
        )
    assert good2.tolist() == good.tolist() and stopped2.tolist() == stopped.tolist()
    assert np.array_equal(y[3], x[0], equal_nan=True) and np.array_equal(y[1], x[1], equal_nan=True)
    assert all((y[i] == 100.0 + i).all() for i in (0, 2, 4))
    with np.errstate(all="ignore"):
        _, _, stopped = rt._newton_solve(
            rt._Arith(np.float64),
            circle(1.0),
            [v.copy() for v in start],
            [0, 1],
            ok,
            _Rule(1, 0.0, 1e-8, 1e-12, 0.5),
        )
    assert not stopped[[0, 2]].any()  # one step from there is not enough


def test_newton_stops_at_a_residual_at_rounding(rt):
    """A root at zero whose residual stays at rounding noise (+-1e-17, terms of size 1): without
    the residual rule Newton chases the noise to its step limit; with it (symkin.core.settings,
    3b), it stops after the first evaluation, where |f| = 1e-17 <= 2e-13 (1 + |J x|)."""
    for residual, stops, evaluations in ((0.0, False, 40), (2e-13, True, 1)):
        calls = []

        def noisy(x, calls=calls):
            calls.append(1)
            return [x[0] - (1e-17 if len(calls) % 2 else -1e-17), np.ones_like(x[0])]

        _, good, stopped = rt._newton_solve(
            rt._Arith(np.float64),
            noisy,
            [np.zeros(1)],
            [0],
            np.ones(1, dtype=bool),
            _Rule(40, 0.0, 1e-8, 1e-12, 0.5, residual),
            scale=[1.0],
        )
        assert good.all() and bool(stopped[0]) is stops and len(calls) == evaluations


@pytest.mark.parametrize("steps", [1, 3, 20])
def test_continuation(rt, steps):
    stages = []
    state = {"t": 0.0}

    def stage(t):
        stages.append(t)
        state["t"] = t

    def system(x):
        return circle(state["t"])(x)

    x = [np.array([2.0, 2.0]), np.array([0.0, 0.0])]
    # `steps` stages: the largest input `steps`, at most 1 per stage
    x, ok = rt._continuation(
        rt._Arith(np.float64),
        stage,
        system,
        x,
        [0, 1],
        np.ones(2, dtype=bool),
        _Rule(30, 1e-10),
        float(steps),
        1.0,
    )
    assert stages == [s / steps for s in range(1, steps + 1)] and ok.all()
    assert np.abs(np.array(x) - math.sqrt(2.0)).max() < 1e-15


# ---- one mechanism's evaluator: the toy ----


def mechanism(rt, closed: bool, dtype=np.float64):
    """The toy mechanism of tests/runtime_toy.py as the runtime's tables and routines."""

    def rigid(inputs, params):
        (t0,), (p0, _) = inputs, params
        return [p0 * t0, t0 - p0 * t0, 1.0 - t0 * t0, 0.0 * t0]

    def rigid_res(theta, params):
        return [theta[1] - params[0] * theta[0], theta[1] + theta[2] - theta[0], 1.0, 0.0, 1.0, 1.0]

    def linear(theta, params):
        r = [-0.1 * theta[1], -0.05 * theta[2] - params[1]]
        size = [abs(0.1 * theta[1]), abs(0.05 * theta[2]) + abs(params[1])]
        return [1.0, 0.0, 1.0, 1.0, *r, *size]

    def newton(theta, delta, params):
        d0, d1 = delta
        return [
            d0 + d0**3 - 0.1 * theta[1],
            d0 + d1 - 0.05 * theta[2] - params[1],
            1.0 + 3.0 * d0 * d0,
            0.0,
            1.0,
            1.0,
        ]

    def loaded_solve(mech, x, theta, params, ok):
        # a stand-in for templates/numpy/reduced.py's driver (tests/runtime_toy.py): delta, what
        # the level's deviation reads, ok (refused where p1 theta_0 > 1)
        delta = [theta[1] / 50 + params[1] / 1000, -3 * theta[2] / 100]
        ok = ok & ~(params[1] * theta[0] > 1.0)
        return delta, [*params, delta[0] + delta[1], 2 * delta[0]], ok

    def sens_rigid(theta, params):
        zero = 0.0 * theta[0]
        return [
            1.0,
            0.0,
            1.0,
            1.0,
            -theta[0],
            zero,
            -params[0],
            zero,
            zero,
            -1.0,
            -np.sin(theta[1]),
            zero,
            zero,
            np.cos(theta[2]),
        ] + [zero] * 6

    def sens_paper(theta, delta, params):
        return [0.1, 0.0, 0.0, 0.05] + [0.0] * 6

    def sens_exact(theta, delta, params):
        s = [0.0] * 28
        s[0], s[2], s[3] = 1.0 + 3.0 * delta[0] * delta[0], 1.0, 1.0
        s[4], s[7], s[12], s[18], s[21] = -0.1, -0.05, -1.0, 1.0, 1.0
        return s

    def parameters(given=None, shifts=None):
        given = dict(given or {})
        p0 = given.get("p0", 0.5)
        return [p0, given.get("p1", 2 * p0)]

    stage = {
        "M": (0, 2, 2),
        "dE_dtheta": (4, 2, 2),
        "dE_dv": (8, 2, 3),
        "dD_dtheta": (14, 2, 2),
        "dD_ddelta": (18, 2, 2),
        "dD_dv": (22, 2, 3),
    }
    return rt._Mechanism(
        input_names=("t0",),
        pruned_inputs=("ignored",),
        parameter_names=("p0", "p1"),
        hinge_names=("t0", "t1", "t2"),
        link_names=("L",),
        point_names=("P",),
        parameters=parameters,
        dtype=dtype,
        n_theta=3,
        n_variables=3,
        n_dyads=1,
        input_index=(0,),
        unknown_index=(1, 2),
        fixed=(),
        limits=((1, 2.0),),
        needs_loops=True,
        loops_for_links=False,
        rigid=rigid if closed else None,
        rigid_res=rigid_res,
        linear=linear,
        rigid_points=lambda theta, params: [np.cos(theta[1]), np.sin(theta[2])],
        links=lambda theta, delta: [theta[1] + theta[2], delta[0] + delta[1]],
        loaded=None,
        loaded_solve=loaded_solve,
        sens_rigid=sens_rigid,
        sens_chain=lambda params: [0.0, 0.0, 2.0, 0.0],
        sens_rigid_blocks={
            "A": (0, 2, 2),
            "dG_dv": (4, 2, 3),
            "dR_dtheta": (10, 2, 2),
            "dR_dv": (14, 2, 3),
        },
        rigid_rule=_Rule(30, 1e-10),
        polish_rule=_Rule(8, 0.0, 1e-8, 1e-12, 0.5),
        exact_rule=_Rule(40, 0.0, 1e-8, 1e-12, 0.5, 2e-13),
        continuation_step=0.05,
        angular=(0,),
        rest=(),
        n_dropped=0,
        consistent=1e-8,
        consistency_rigid=None,
        winding=math.pi,
        levels={
            "paper": rt._Level(
                lambda t, d, p: [0.1 * t[1], 0.05 * t[2]],
                sens=sens_paper,
                blocks={"dD_dtheta": (0, 2, 2), "dD_dv": (4, 2, 3)},
            ),
            "first_order": rt._Level(lambda t, d, p: list(d), linear),
            "exact": rt._Level(
                lambda t, d, p: list(d), linear, newton, sens=sens_exact, blocks=stage
            ),
            "loaded": rt._Level(lambda t, d, q: q[2:4], loaded=1),
        },
    )


CODES = {"paper": 0, "first_order": 1, "exact": 2, "loaded": 3}
CASES = [(0.3, 0.5, 1.0), (-0.8, 1.7, -0.2), (0.05, -0.4, 0.0)]


@pytest.mark.parametrize("closed", [True, False])
@pytest.mark.parametrize("level", list(CODES))
def test_evaluate_at_every_level(rt, closed, level):
    mech = mechanism(rt, closed)
    for theta0, p0, p1 in CASES:
        res = rt._evaluate(mech, {"t0": [theta0, 0.0]}, level, {"p0": p0, "p1": p1}, True)
        want = toy(theta0, p0, p1, CODES[level])
        assert res["ok"].tolist() == [True, True]
        r, d, t, u = want["rigid"], want["dev"], want["theta"], want["delta"]
        point = res["points"]["P"]
        assert close(point["rigid"][:, 0], r) and close(point["deviation"][:, 0], d)
        assert close(point["compliant"][:, 0], [r[0] + d[0], r[1] + d[1]])
        assert close([res["angles"]["rigid"][h][0] for h in ("t0", "t1", "t2")], t)
        assert close(
            [res["angles"]["compliant"][h][0] for h in ("t1", "t2")], [t[1] + u[0], t[2] + u[1]]
        )
        link = res["links"]["L"]
        assert close([link["rigid"][0], link["deviation"][0]], [want["link"], u[0] + u[1]])


@pytest.mark.parametrize(
    "theta0, p0, level",
    [
        (3.2, 0.5, "exact"),  # an input beyond a half turn
        (float("nan"), 0.5, "exact"),
        (1.2, 0.5, "exact"),  # closed form: the dyad's reach 1 - theta_0^2 < 0
        (0.3, 8.0, "paper"),  # hinge 1 beyond its limit 2: theta_1 = 2.4
        (0.3, 6.6, "exact"),  # theta_1 = 1.98, but theta_1 + delta_0 > 2
        (0.3, 0.5, "loaded"),  # the loaded level's driver refuses (p1 theta_0 = 1.8 > 1)
    ],
)
def test_evaluate_failures_are_nan(rt, theta0, p0, level):
    params = {"p0": p0} if level != "loaded" else {"p0": 0.5, "p1": 6.0}
    res = rt._evaluate(mechanism(rt, True), {"t0": [theta0, 0.1]}, level, params, True)
    assert res["ok"].tolist() == [False, True]
    for part in res["points"]["P"].values():
        assert np.isnan(part[:, 0]).all() and np.isfinite(part[:, 1]).all()
    assert np.isnan(res["links"]["L"]["rigid"][0])


def test_evaluate_checks_its_arguments(rt):
    mech = mechanism(rt, True)
    with pytest.raises(ValueError, match="level must be one of"):
        rt._evaluate(mech, {"t0": 0.1}, "equilibrium", None, True)
    with pytest.raises(ValueError, match="accepted and ignored"):
        rt._evaluate(mech, {"t1": 0.1}, "exact", None, True)
    res = rt._evaluate(mech, {"t0": 0.1, "ignored": 5.0}, "exact", None, False)
    assert res["ok"] and res["links"] == {}


def test_evaluate_in_blocks_equals_one_block(rt):
    mech = mechanism(rt, True)
    x = np.linspace(-0.9, 0.9, 2 * rt._CHUNK + 17).reshape(-1, 1) * np.ones((1, 2))
    whole = rt._evaluate(mech, {"t0": x}, "exact", None, True)
    assert whole["points"]["P"]["deviation"].shape == (2,) + x.shape
    part = rt._evaluate(mech, {"t0": x[:100]}, "exact", None, True)
    assert np.array_equal(
        whole["points"]["P"]["deviation"][:, :100], part["points"]["P"]["deviation"]
    )


def test_float32(rt):
    mech = mechanism(rt, True, np.float32)
    res = rt._evaluate(mech, {"t0": [0.3]}, "exact", None, True)
    dev = res["points"]["P"]["deviation"]
    assert dev.dtype == np.float32
    want = toy(0.3, 0.5, 1.0, 2)["dev"]
    assert close(dev[:, 0], want, 1e-6)


@pytest.mark.parametrize("closed", [True, False])
@pytest.mark.parametrize("level", ["paper", "exact"])
def test_sensitivities_are_the_derivatives(rt, closed, level):
    theta0, p0, p1 = 0.3, 0.5, 1.0
    res = rt._sensitivity_full(mechanism(rt, closed), {"t0": [theta0]}, level, {"p0": p0, "p1": p1})
    assert res["ok"].tolist() == [True]
    for table, key in (("deviation", "dev"), ("rigid", "rigid")):
        entry = res[table]["P"]
        got = [entry["params"]["p0"], entry["params"]["p1"], entry["inputs"]["t0"]]
        want = toy_partials(theta0, p0, p1, CODES[level], key)
        assert close(np.array(got)[:, :, 0].ravel(), [w for row in want for w in row], 1e-12)


def test_sensitivities_only_where_a_level_has_them(rt):
    with pytest.raises(ValueError, match="sensitivities are derived at the levels"):
        rt._sensitivity_full(mechanism(rt, True), {"t0": 0.1}, "loaded", None)
    res = rt._sensitivity_full(mechanism(rt, True), {"t0": [0.3, 1.2]}, "exact", None)
    assert res["ok"].tolist() == [True, False]
    assert np.isnan(res["deviation"]["P"]["params"]["p0"][:, 1]).all()


def test_generated_module_holds_the_runtime_verbatim():
    from evaluators import generated

    from symkin.codegen.backends.numpy import backend as numpy_backend

    text = runtime("numpy/runtime.py")
    module = numpy_backend.emit(generated("four_bar").plan, "test")
    assert text in module and text in PATH.read_text()
    assert "\nimport" not in text  # the generated module's own imports serve it
    # the Newton and continuation it runs: the Python path's own text, held once
    newton = shared("symkin.kinematics.loop_newton")
    assert newton in module and module.count("def _newton_solve(") == 1
    assert "\nimport" not in newton and "\nfrom" not in newton
