"""Hinge angles are tracked continuously from the as-fabricated pose, by one rule in every backend
(symkin.core.settings, the winding rule): the closed-form dyads wrap angles into (-pi, pi], so a
hinge
that turned beyond half a turn must be refused (exit 3), never reported wrapped. Over the whole
input range every backend agrees with the independent solver, and none answers where another
(or the oracle) finds no assembly.
"""

from __future__ import annotations

import math

import mpmath
import numpy
import pytest
from conftest import EXAMPLES
from evaluators import BACKENDS, GENERATED, Generated, rel_err
from reference_solver import Reference, ReferenceAssemblyError

import symkin
from symkin.core.errors import AssemblyError
from symkin.core.settings import SOLVER
from symkin.studies.evaluation import evaluate


def moved_input(text: str, old: str, new: str) -> str:
    """The mechanism with the input at hinge `old` moved to hinge `new`."""
    parts = text.split("[[hinge]]")
    for i, part in enumerate(parts):
        if f'name = "{old}"\n' in part:
            parts[i] = part.replace("input = true\n", "")
        if f'name = "{new}"\nlinks' in part:
            parts[i] = part.replace(f'name = "{new}"\n', f'name = "{new}"\ninput = true\n', 1)
    return "[[hinge]]".join(parts)


FOUR_BAR = (EXAMPLES / "four_bar.toml").read_text()
STEPHENSON = (EXAMPLES / "stephenson_six_bar.toml").read_text()
CASES = {
    "four_bar": (FOUR_BAR, "A0"),
    "stephenson_at_D": (moved_input(STEPHENSON, "O_A", "D"), "D"),
}
GRID = [round(-math.pi + 2 * math.pi * k / 12, 6) for k in range(1, 12)] + [-3.0, 3.1, -0.1]


def reference(ref: Reference, name: str, value: float) -> dict | None:
    """The oracle's rigid and compliant angles, or None where it finds no assembly or a hinge
    beyond half a turn (the documented exit 3)."""
    try:
        r = ref.deviation({name: repr(value)}, dps=25, min_digits=10)
    except ReferenceAssemblyError:
        return None
    angles = [*r["angles"]["rigid"].values(), *r["angles"]["compliant"].values()]
    if max(abs(float(a)) for a in angles) >= math.pi:
        return None
    return r


@pytest.mark.parametrize("key", sorted(CASES))
def test_every_backend_follows_the_oracle_over_the_input_range(key):
    text, name = CASES[key]
    g = Generated(mech=symkin.loads(text, f"{key}.toml"), sensitivity=False, levels=["exact"])
    ref = Reference(g.mech)
    outcomes = {"refused": 0, "agreed": 0}
    for value in GRID:
        want = reference(ref, name, value)
        # the generated evaluators themselves, not through evaluate() (which asks mpmath why)
        direct = {b: g.pose(b, {name: value}, "exact")[0] == 0 for b in GENERATED}
        if want is None:
            outcomes["refused"] += 1
            assert not any(direct.values()), (value, direct)
            with pytest.raises(AssemblyError):
                evaluate(g.analysis, {name: repr(value)}, "exact")
            continue
        outcomes["agreed"] += 1
        assert all(direct.values()), (value, direct)
        for backend in BACKENDS:
            got = evaluate(g.analysis, {name: repr(value)}, "exact", backend=backend)
            for hinge, angle in got.angles_rigid.items():
                assert abs(angle - float(want["angles"]["rigid"][hinge])) <= 1e-9, (
                    backend,
                    value,
                    hinge,
                )
            for hinge, angle in got.angles_compliant.items():
                assert abs(angle - float(want["angles"]["compliant"][hinge])) <= 1e-9, (
                    backend,
                    value,
                    hinge,
                )
            for point, res in got.points.items():
                ref_dev = [float(v) for v in want["points"][point]["deviation"]]
                if max(map(abs, ref_dev)) > 1e-15:
                    assert rel_err(res.deviation, ref_dev) <= 1e-7, (backend, value, point)
                else:  # a point the plates do not move
                    assert max(map(abs, res.deviation)) <= 1e-15, (backend, value, point)
    # the grid reaches both outcomes in both cases
    assert outcomes["refused"] and outcomes["agreed"], outcomes


def test_the_four_bar_beyond_half_a_turn_is_refused_not_wrapped():
    """A0 = -3: the oracle's hinge A reaches +3.35 rad continuously; the dyad formula wraps it
    to -2.93. Every backend refuses, and says why."""
    g = Generated(mech=symkin.load(EXAMPLES / "four_bar.toml"), sensitivity=False, levels=["exact"])
    with mpmath.workdps(25):
        a = Reference(g.mech).solve({"A0": "-3.0"}, dps=25)["angles"]["A"]
    assert 3.3 < a < 3.4
    for backend in BACKENDS:
        with pytest.raises(AssemblyError, match="half a turn"):
            evaluate(g.analysis, {"A0": "-3.0"}, "exact", backend=backend)
    # a vector through the numpy module: only the elements that wrapped are refused
    res = g.numpy.evaluate({"A0": numpy.array([-3.0, -2.0, 3.1])})
    assert res["ok"].tolist() == [False, True, True]


@pytest.mark.parametrize("value", ["1e8", "-1e8", "1e12", "1e16", "-1e16", "6.3"])
def test_inputs_beyond_the_bound_are_refused_alike(value):
    g = Generated(mech=symkin.load(EXAMPLES / "four_bar.toml"), sensitivity=False, levels=["exact"])
    for backend in BACKENDS:
        with pytest.raises(AssemblyError, match=r"\|angle\| <= pi"):
            evaluate(g.analysis, {"A0": value}, "exact", backend=backend)
    assert not bool(g.numpy.evaluate({"A0": float(value)})["ok"])
    assert g.lib.evaluate([float(value)], None, 2)[0] != 0


def test_the_rule_lives_in_the_solver_settings():
    g = Generated(mech=symkin.load(EXAMPLES / "four_bar.toml"), sensitivity=False, levels=["exact"])
    from symkin.codegen import pipeline

    # the generated tables carry it to the runtimes' winding test
    assert f"winding={SOLVER.winding}," in pipeline.emit(g.plan, "numpy", "t")[0]
    assert f".winding = {SOLVER.winding}," in pipeline.emit(g.plan, "c", "t")[1]
