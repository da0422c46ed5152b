"""One solver: the mpmath evaluation and the generated C and numpy evaluators all take their
continuation, iteration caps and tolerances from symkin.core.settings (docs/numerics.md)."""

from __future__ import annotations

import dataclasses

import mechanisms as M
import numpy as np
import pytest
from evaluators import require_compiler

import symkin
from symkin.codegen import pipeline
from symkin.core.settings import SOLVER
from symkin.studies import mpmath_evaluator


def test_continuation_steps():
    assert SOLVER.continuation_steps(0.0) == 1
    assert SOLVER.continuation_steps(SOLVER.continuation_step) == 1
    assert SOLVER.continuation_steps(0.3) == 6
    assert SOLVER.continuation_steps(0.3 + 1e-9) == 7


def test_tolerances_by_arithmetic():
    assert SOLVER.tolerances("float64") == SOLVER.float64
    assert SOLVER.tolerances("float32").converged > SOLVER.float64.converged
    assert SOLVER.mpmath(40).converged < SOLVER.float64.stalled
    # the closed form's absolute 1e-40 is no relative accuracy for a tiny input: polished too
    assert SOLVER.mpmath(40).polish == SOLVER.float64.polish > 1
    # the residual floor (rule 3b) sits near the rounding of each arithmetic, far below the
    # relative step test; the redundancy check is the same in mpmath and float64 (alike refusals)
    for tol, eps in (
        (SOLVER.float64, 2.2e-16),
        (SOLVER.float32, 1.2e-7),
        (SOLVER.mpmath(40), 1e-40),
    ):
        assert 10 * eps < tol.residual < 1e5 * eps and tol.residual < tol.converged
    assert SOLVER.mpmath(40).consistent == SOLVER.mpmath(60).consistent == SOLVER.float64.consistent


@pytest.fixture(scope="module")
def triad():
    """The triad six-bar has no closed form: its rigid angles come from continuation."""
    an = symkin.analyze(symkin.loads(M.TRIAD_SIX_BAR))
    assert not an.rigid.closed_form
    return an


def evaluators(an, settings):
    p = dataclasses.replace(pipeline.plan_for(an), solver=settings)
    module = pipeline.evaluator(p, "numpy", "solver")
    return module, pipeline.evaluator(p, "c", "solver", links=False)


def test_generated_evaluators_follow_the_settings(triad):
    require_compiler()
    module, lib = evaluators(triad, SOLVER)
    assert module.evaluate({"O1": np.array([0.3])}, "exact")["ok"].all()
    assert lib.evaluate([0.3], None, 2)[0] == 0
    # one Newton step per continuation step cannot converge: both report it
    module, lib = evaluators(triad, dataclasses.replace(SOLVER, rigid_iterations=1))
    assert not module.evaluate({"O1": np.array([0.3])}, "exact")["ok"].any()
    assert lib.evaluate([0.3], None, 2)[0] == 2


def test_mpmath_follows_the_settings(triad, monkeypatch):
    assert symkin.evaluate(triad, {"O1": "0.3"}, "exact").points
    monkeypatch.setattr(mpmath_evaluator, "SOLVER", dataclasses.replace(SOLVER, rigid_iterations=1))
    with pytest.raises(symkin.AssemblyError, match="cannot close"):
        symkin.evaluate(triad, {"O1": "0.3"}, "exact")
