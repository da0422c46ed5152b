"""symkin/kinematics/loop_newton.py, the kinematic levels' Newton written once: the same text in
the generated numpy modules' arithmetic (float64 element arrays, templates/numpy/runtime.py's
_Arith) and in the 40-digit evaluation's (one configuration in mpmath numbers,
symkin.studies.mpmath_evaluator's MPMATH), each checked against roots computed here."""

from __future__ import annotations

import importlib.util

import mpmath
import numpy as np
import pytest
from conftest import ROOT

from symkin.core.settings import SOLVER
from symkin.kinematics.loop_newton import _continuation, _newton_solve, _Rule
from symkin.studies.mpmath_evaluator import MPMATH


@pytest.fixture(scope="module")
def float64():
    spec = importlib.util.spec_from_file_location(
        "symkin_numpy_runtime_newton", ROOT / "templates" / "numpy" / "runtime.py"
    )
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module._Arith(np.float64)


def circle(t, one):
    """x0^2 + x1^2 = 4 and x0 = t x1: residual, then the Jacobian row-major; root
    x1 = 2 / sqrt(1 + t^2), x0 = t x1."""

    def system(x):
        x0, x1 = x[0], x[1]
        return [x0 * x0 + x1 * x1 - 4 * one, x0 - t * x1, 2 * x0, 2 * x1, one, -t * one]

    return system


def test_forty_digits_stop_at_their_own_rounding():
    """The exact rule at 40 digits (its ε's multiples) takes Newton to the root to 40 digits; at
    float64's numbers it would stop some 25 digits short."""
    with mpmath.workdps(40):
        t = mpmath.mpf(3) / 7
        root1 = 2 / mpmath.sqrt(1 + t * t)
        for tol, error in ((SOLVER.mpmath(40), mpmath.mpf(10) ** -38), (SOLVER.float64, None)):
            rule = _Rule(*SOLVER.loop_rules(tol)["exact"])
            x = [mpmath.mpf(1), mpmath.mpf(1)]
            x, ok, stopped = _newton_solve(
                MPMATH, circle(t, mpmath.mpf(1)), x, [0, 1], np.True_, rule, scale=[4, 0]
            )
            assert ok and stopped
            off = max(abs(x[1] - root1), abs(x[0] - t * root1))
            if error is not None:
                assert off <= error
            else:
                assert mpmath.mpf(10) ** -30 < off < 1e-12  # float64's rule: a float's digits


def test_one_configuration_alike_in_either_arithmetic(float64):
    """The same text, the same decisions: per element the float64 batch agrees with the
    40-digit solve to float64's rounding, a singular start is refused in both, and an
    element's answer does not depend on its batch (bit for bit alone and in the batch)."""
    ts = [0.2, 0.5, 3.0, -1.5]
    rule = _Rule(*SOLVER.loop_rules(SOLVER.float64)["exact"])
    starts = [(1.0, 1.5), (0.0, 0.0), (30.0, -7.0), (-1.0, 2.0)]  # the second: J singular
    t = np.array(ts)

    def batch(index):
        x = [np.array([starts[i][0] for i in index]), np.array([starts[i][1] for i in index])]
        one = np.ones(len(index))
        with np.errstate(all="ignore"):  # the singular start divides by zero
            return _newton_solve(
                float64,
                circle(t[index], one),
                x,
                [0, 1],
                np.ones(len(index), dtype=bool),
                rule,
                scale=[4 * one, 0 * one],
            )

    x, ok, stopped = batch(list(range(4)))
    assert ok.tolist() == [True, False, True, True] and stopped[ok].all()
    for e, (ti, start) in enumerate(zip(ts, starts)):
        alone, ok1, _ = batch([e])
        assert all(np.array_equal(alone[i], x[i][e : e + 1]) for i in (0, 1))
        assert ok1[0] == ok[e]
        with mpmath.workdps(40):
            mt = mpmath.mpf(ti)
            y, good, done = _newton_solve(
                MPMATH,
                circle(mt, mpmath.mpf(1)),
                [mpmath.mpf(start[0]), mpmath.mpf(start[1])],
                [0, 1],
                np.True_,
                _Rule(*SOLVER.loop_rules(SOLVER.mpmath(40))["exact"]),
                scale=[4, 0],
            )
            assert bool(good) == bool(ok[e])
            if not good:
                continue
            assert done
            root1 = 2 / mpmath.sqrt(1 + mt * mt)
            assert abs(y[1] - root1) < mpmath.mpf(10) ** -38
            # the root of this configuration's branch: Newton from either start lands on it
            sign = 1 if y[1] > 0 else -1
            assert abs(x[1][e] - sign * float(root1)) <= 4e-16 * float(root1)
            assert abs(x[0][e] - sign * float(mt * root1)) <= 4e-16 * abs(float(mt * root1))


def test_continuation_in_mpmath_reports_where_it_stopped():
    """The continuation staged in mpmath: t = 1/8, ..., 1 (a largest input 1 in steps of at most
    1/8) for a reachable end, and for an unreachable one (x0 = t c with |t c| > 2 leaves the
    circle x0^2 + x1^2 = 4) it ends at the first stage that fails, which the 40-digit path names
    in its refusal."""
    rule = _Rule(*SOLVER.loop_rules(SOLVER.mpmath(40))["rigid"])
    with mpmath.workdps(40):
        for c, reached in ((mpmath.mpf("1.5"), 8), (mpmath.mpf(3), 6)):
            staged = []
            x = [mpmath.mpf(0), mpmath.mpf(2)]  # x[0] the input, x[1] solved

            def stage(t, staged=staged, x=x, c=c):
                staged.append(t)
                x[0] = c * mpmath.mpf(t)

            def system(x):
                return [x[0] * x[0] + x[1] * x[1] - 4, 2 * x[1]]

            x, ok = _continuation(MPMATH, stage, system, x, [1], np.True_, rule, 1.0, 0.125)
            assert staged == [s / 8 for s in range(1, reached + 1)]
            if reached == 8:
                assert ok and abs(x[1] - mpmath.sqrt(4 - c * c)) < mpmath.mpf(10) ** -35
            else:
                assert not ok and c * staged[-1] > 2 > c * staged[-2]
