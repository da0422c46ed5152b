"""Large mechanisms evaluate in every backend (docs/numerics.md, "Scale").

The two families of benchmarks/families.py that used to break the generated code: a ladder of
20 loops (one input, 61 hinges, every loop closing on the one below it) and a fan of 20 copies
of the paper's four-bar on one frame (20 inputs, 20 independent loops). Each backend is checked
against the independent 40-digit solver of tests/reference_solver.py (full link poses, no graph
theory). Their derivation time is measured by benchmarks/scale.py, not here.
"""

from __future__ import annotations

import sys

import pytest
from conftest import ROOT
from evaluators import BACKENDS, GENERATED, Generated, rel_err, require
from reference_solver import Reference

import symkin
from symkin.studies.evaluation import evaluate

sys.path.insert(0, str(ROOT / "benchmarks"))
import families

K = 20


def _cases(kind: str) -> list[dict]:
    if kind == "ladder":
        return [{"g0": 0.05}, {"g0": -0.2}]
    # every crank at its own angle in [-0.25, 0.35] (none at 0, where the deviation is 0)
    return [{f"A0_{j}": round(0.05 + 0.3 * ((j * 7) % 11 - 5) / 5, 4) for j in range(1, K + 1)}]


@pytest.fixture(scope="module", params=("ladder", "fan"))
def family(request):
    mech = symkin.loads(families.family(request.param, K), f"{request.param}_{K}.toml")
    # the exact level is what these tests evaluate: its plan alone, evaluate finds it
    return request.param, Generated(mech=mech, sensitivity=False, levels=["exact"])


def test_every_backend_agrees_with_the_independent_solver(family):
    kind, g = family
    ref = Reference(g.mech)
    # the sympy backend once (its 30-digit Newton is the slow one), numpy and C at every case
    for i, inputs in enumerate(_cases(kind)):
        want = ref.deviation(inputs)
        for backend in BACKENDS if i == 0 else GENERATED:
            require(backend)
            got = evaluate(g.analysis, inputs, "exact", backend=backend)
            assert set(got.points) == set(want["points"])
            for name, point in got.points.items():
                w = want["points"][name]
                assert rel_err(point.rigid, w["rigid"]) <= 1e-12, (backend, name)
                assert rel_err(point.deviation, w["deviation"]) <= 1e-9, (backend, name)


def test_out_of_range_input_is_refused_not_a_crash(family):
    """Past assembly (the ladder's first dyad beyond its toggle) or past a hinge's half turn (a
    fan's crank at -3 rad turns its coupler hinge beyond pi): every backend refuses (exit 3)."""
    kind, g = family
    inputs = {"g0": 1.5} if kind == "ladder" else {**_cases(kind)[0], "A0_3": -3.0}
    for backend in BACKENDS:
        with pytest.raises(symkin.core.errors.AssemblyError):
            evaluate(g.analysis, inputs, "exact", backend=backend)
