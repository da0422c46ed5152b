"""Parallelograms and redundant guidances (issue 22, items 1 and 2): every backend solves them.

- In a parallelogram every compliant hinge angle equals the rigid one (δ = 0 exactly, by
  symmetry): the compliant Newton iterate is rounding noise and only a stopping test scaled by
  the plate and link lengths can accept it (symkin.core.settings, rule 3b).
- A stage with a third leg has Grübler mobility 0 but moves (mobility 1 from the rank of the
  closure Jacobian, docs/levels.md): its dependent closure row is dropped from the solves and
  checked at the solution (rule 4).

Every deviation is compared with the independent 40-digit reference (tests/reference_solver.py:
full link poses, its own rank-revealing row choice); the kinematic levels are all exact here
(every hinge angle of these stages equals the rigid one, so paper's Σ Δz holds too).
Refusals are compared across the backends: the same exit code and the same message.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import mpmath
import numpy as np
import pytest
from evaluators import BACKENDS, KINEMATIC, Generated, require, require_compiler
from reference_solver import Reference, mobility

import symkin
from symkin.cli.commands import main
from symkin.codegen.backends.numpy import backend as numpy_backend
from symkin.codegen.plan import plan
from symkin.codegen.toolchain import import_numpy_module
from symkin.core import levels
from symkin.core.settings import SOLVER
from symkin.studies import mpmath_evaluator

ZOO = Path(__file__).resolve().parent / "mechanisms"
TOL = 1e-9

SINGLE = ("0", "1e-9", "1e-6", "0.01", "0.05", "-0.1")
CASES = {
    "parallelogram": [{"F1": q} for q in SINGLE],
    "parallelogram_mm": [{"F1": q} for q in SINGLE],
    "three_leg_stage": [{"F1": q} for q in SINGLE],
    # two inputs; the straight-line case I1 = -F1 cancels the stage's y deviation exactly, so it
    # is taken at a working input only (at 1e-9 float64 keeps only 1e-7 of the remainder)
    "double_parallelogram": [
        {"F1": a, "I1": b}
        for a, b in (
            ("0", "0"),
            ("1e-9", "5e-10"),
            ("1e-6", "-3e-7"),
            ("0", "0.02"),
            ("0.03", "0.02"),
            ("0.05", "-0.05"),
            ("-0.08", "0.03"),
        )
    ],
}


@pytest.fixture(scope="module")
def zoo():
    """Per zoo file: the mechanism, its analysis and the reference deviations of every case."""
    out = {}
    for name, cases in CASES.items():
        mech = symkin.load(ZOO / f"{name}.toml")
        ref = Reference(mech)
        want = []
        for inputs in cases:
            res = ref.deviation(inputs)
            with mpmath.workdps(res["dps"]):
                want.append(
                    {p: tuple(float(v) for v in d["deviation"]) for p, d in res["points"].items()}
                )
        out[name] = (mech, symkin.analyze(mech), want)
    return out


def close(got, want) -> bool:
    """1e-9 of the reference deviation; where it is zero (the as-fabricated pose), zero."""
    size = math.hypot(*want)
    return math.hypot(got[0] - want[0], got[1] - want[1]) <= TOL * size


@pytest.mark.parametrize("name", sorted(CASES))
def test_sympy_backend_matches_the_reference(zoo, name):
    _, analysis, want = zoo[name]
    for inputs, ref in zip(CASES[name], want):
        for level in KINEMATIC:
            res = symkin.evaluate(analysis, inputs, level)
            for point, d in ref.items():
                got = res.points[point].deviation
                assert close(got, d), (name, inputs, level, point, got, d)


@pytest.fixture(scope="module")
def generated(zoo):
    # the kinematic levels are what these tests evaluate: their plans alone
    return {
        name: Generated(mech=mech, sensitivity=False, levels=list(KINEMATIC))
        for name, (mech, _, _) in zoo.items()
    }


@pytest.mark.parametrize("name", sorted(CASES))
def test_numpy_backend_matches_the_reference(zoo, generated, name):
    g, want = generated[name], zoo[name][2]
    inputs = {h: np.array([float(c[h]) for c in CASES[name]]) for h in g.numpy.INPUTS}
    for level in KINEMATIC:
        res = g.numpy.evaluate(inputs, level)
        assert res["ok"].all(), (name, level, res["ok"])
        for k, ref in enumerate(want):
            for point, d in ref.items():
                got = res["points"][point]["deviation"][:, k]
                assert close(got, d), (name, CASES[name][k], level, point, got, d)


@pytest.mark.parametrize("name", sorted(CASES))
def test_c_backend_matches_the_reference(zoo, generated, name):
    require_compiler()
    g, want = generated[name], zoo[name][2]
    order = [g.analysis.kin.hinges[a].name for a in g.analysis.kin.inputs]
    for level in KINEMATIC:
        for case, ref in zip(CASES[name], want):
            x = [float(case[h]) for h in order]
            status, out, _ = g.lib.evaluate(x, None, levels.get(level).code)
            assert status == 0, (name, case, level)
            for i, point in enumerate(g.plan.points):
                got = (out[6 * i + 4], out[6 * i + 5])
                assert close(got, ref[point]), (name, case, level, point, got, ref[point])


def test_the_rank_revealing_newton_matches_the_reference(zoo):
    """The three-leg stage with its closed form withheld: the rigid linkage by Newton with
    continuation on the kept rows, the dropped row checked, in every backend."""
    mech, _, want = zoo["three_leg_stage"]
    analysis = symkin.analyze(mech)
    analysis.rigid = dataclasses.replace(analysis.rigid, phi=None)
    assert not analysis.rigid.closed_form
    g = Generated(mech=mech, sensitivity=False, levels=["exact"])
    g.analysis = analysis
    g.plan = plan(analysis, levels=["exact"], sensitivity=False)
    g.numpy = import_numpy_module(numpy_backend.emit(g.plan, "test"), "three_leg_newton")
    assert "consistency_rigid" in g.plan.routines and not g.plan.closed_form
    inputs = {"F1": np.array([float(c["F1"]) for c in CASES["three_leg_stage"]])}
    res = g.numpy.evaluate(inputs, "exact")
    assert res["ok"].all()
    for k, (case, ref) in enumerate(zip(CASES["three_leg_stage"], want)):
        sympy_dev = symkin.evaluate(analysis, case, "exact").points["P"].deviation
        assert close(sympy_dev, ref["P"]), (case, sympy_dev, ref["P"])
        assert close(res["points"]["P"]["deviation"][:, k], ref["P"]), case
        if k == 0:
            require_compiler()
        status, out, _ = g.lib.evaluate([float(case["F1"])], None, 2)
        assert status == 0 and close((out[4], out[5]), ref["P"]), (case, out[4:6])


def test_the_compliant_angles_equal_the_rigid_ones_and_the_rule_is_what_accepts_them(
    zoo, monkeypatch
):
    """δ = 0 exactly in a parallelogram: without rule 3b (a residual at the rounding level of
    its terms) Newton never stops, and the refusal names the loop and its hinges."""
    analysis = zoo["parallelogram"][1]
    res = symkin.evaluate(analysis, {"F1": "0.05"}, "exact")
    for hinge, angle in res.angles_rigid.items():
        assert abs(res.angles_compliant[hinge] - angle) <= 1e-30
    monkeypatch.setattr(mpmath_evaluator, "SOLVER", _NoFloor())
    with pytest.raises(symkin.AssemblyError) as err:
        symkin.evaluate(analysis, {"F1": "0.05"}, "exact")
    message = str(err.value)
    assert "did not converge in 40 Newton steps" in message
    assert "the loop of 'S2' (F1 + S1 - F2 + S2)" in message and "F1=0.05" in message


class _NoFloor(type(SOLVER)):
    """The settings without rule 3b: a residual is never taken for rounding noise."""

    def mpmath(self, dps: int):
        return dataclasses.replace(super().mpmath(dps), residual=0.0)


def two_stages(tmp_path) -> str:
    """The three-leg stage and a two-leg parallelogram beside it on one frame: two inputs, one
    per stage (mobility 2, Grübler 1)."""
    text = (
        (ZOO / "three_leg_stage.toml")
        .read_text()
        .replace('name = "three_leg_stage"', 'name = "two_stages"')
    )
    text += """
[[link]]
name = "left2"
[[link]]
name = "stage2"
[[link]]
name = "right2"

[[hinge]]
name = "G1"
links = ["frame", "left2"]
at = [0.1, 0.0]
plate_angle = "pi/2"
input = true

[[hinge]]
name = "T1"
links = ["left2", "stage2"]
at = [0.1, "L"]
plate_angle = "pi/2"

[[hinge]]
name = "G2"
links = ["frame", "right2"]
at = [0.13, 0.0]
plate_angle = "pi/2"

[[hinge]]
name = "T2"
links = ["right2", "stage2"]
at = [0.13, "L"]
plate_angle = "pi/2"

[[point]]
name = "Q"
link = "stage2"
at = [0.115, "L + 0.010"]
"""
    path = tmp_path / "two_stages.toml"
    path.write_text(text)
    return str(path)


def test_a_redundant_stage_at_rest_beside_a_moving_one(zoo, tmp_path):
    """One stage still (its input 0), the other moving: the still stage's angles are exactly
    zero (they read only its own input), so its redundant row is checked against zero, not
    against rounding noise, in every backend."""
    mech = symkin.load(two_stages(tmp_path))
    assert (mech.grubler, mech.mobility) == (1, 2) == mobility(mech)
    analysis = symkin.analyze(mech)
    g = Generated(mech=mech, sensitivity=False, levels=["exact"])
    want = zoo["parallelogram"][2][4]["P"]  # the two-leg stage's P at F1 = 0.05
    for case in ({"F1": "0", "G1": "0.05"}, {"F1": "0.05", "G1": "0"}):
        moving = "Q" if case["F1"] == "0" else "P"
        still = "P" if moving == "Q" else "Q"
        res = symkin.evaluate(analysis, case, "exact")
        num = g.numpy.evaluate({k: float(v) for k, v in case.items()}, "exact")
        require_compiler()
        status, out, _ = g.lib.evaluate([float(case["F1"]), float(case["G1"])], None, 2)
        assert bool(num["ok"]) and status == 0
        k = g.plan.points.index(moving)
        for got in (
            res.points[moving].deviation,
            tuple(num["points"][moving]["deviation"]),
            (out[6 * k + 4], out[6 * k + 5]),
        ):
            assert close(got, want), (case, got)
        k = g.plan.points.index(still)
        assert res.points[still].deviation == (0.0, 0.0)
        assert tuple(num["points"][still]["deviation"]) == (0.0, 0.0)
        assert (out[6 * k + 4], out[6 * k + 5]) == (0.0, 0.0)


# ---- mobility and what the reader refuses -----------------------------------------------------


@pytest.mark.parametrize("name", sorted(CASES) + ["scott_russell", "roberts", "lever_amplifier"])
def test_mobility_by_rank_matches_the_reference(name):
    mech = symkin.load(ZOO / f"{name}.toml")
    assert (mech.grubler, mech.mobility) == mobility(mech)


def run(args, capsys):
    code = main(args)
    return (code, *capsys.readouterr())


def test_check_prints_both_mobilities(capsys):
    code, out, _ = run(["check", str(ZOO / "three_leg_stage.toml")], capsys)
    assert code == 0
    assert "mobility: 1\n" in out
    assert "Grübler: 3n - 2m = 3*4 - 2*6 = 0" in out
    assert "3n - rank = 3*4 - 11 = 1 (1 redundant constraint)" in out
    assert "the y closure of the loop of u6 is redundant" in out
    code, out, _ = run(["check", str(ZOO / "parallelogram.toml")], capsys)
    assert "Grübler: 3n - 2m = 3*3 - 2*4 = 1" in out and "redundant" not in out


def edited(tmp_path, name: str, *changes: tuple[str, str]) -> str:
    """A copy of a zoo file with each (old, new) replaced (old must occur once)."""
    text = (ZOO / f"{name}.toml").read_text()
    for old, new in changes:
        assert text.count(old) == 1, old
        text = text.replace(old, new)
    path = tmp_path / f"{name}.toml"
    path.write_text(text)
    return str(path)


def test_the_reader_refuses_inputs_that_do_not_number_the_rank_mobility(tmp_path, capsys):
    path = edited(
        tmp_path,
        "three_leg_stage",
        (
            'at = ["w/2", 0.0]\nplate_angle = "pi/2"',
            'at = ["w/2", 0.0]\nplate_angle = "pi/2"\ninput = true',
        ),
    )
    code, out, err = run(["eval", path, "--input", "F1=0.1", "--input", "F3=0.1"], capsys)
    assert code == 2 and out == ""
    assert "2 input hinge(s) (F1, F3) but the mobility is 1" in err
    assert "rank 11 of 2m = 12 (1 redundant)" in err and "mark exactly 1 hinge(s)" in err


def test_the_reader_refuses_a_dependent_input(tmp_path, capsys):
    # both outer legs of the double parallelogram as inputs: one fixes the other
    path = edited(
        tmp_path,
        "double_parallelogram",
        ('at = [50, 0]\nplate_angle = "pi/2"', 'at = [50, 0]\nplate_angle = "pi/2"\ninput = true'),
        ('plate_angle = "-pi/2"\ninput = true', 'plate_angle = "-pi/2"'),
    )
    for backend in BACKENDS:
        args = ["eval", path, "--input", "F1=0.1", "--input", "F2=0.1", "--backend", backend]
        code, out, err = run(args, capsys)
        assert code == 2 and out == ""
        assert "do not determine the pose" in err and "a dependent input" in err
        assert "fix: mark one of I1, T1, I2, T2 as input instead of one of F1, F2" in err


# ---- refusals, alike in every backend ---------------------------------------------------------


def refusals(path, inputs, level, capsys) -> set:
    """The (exit code, message) of `eval` through every backend."""
    seen = set()
    for backend in BACKENDS:
        require(backend)
        args = ["eval", path, "--level", level, "--backend", backend]
        for k, v in inputs.items():
            args += ["--input", f"{k}={v}"]
        code, out, err = run(args, capsys)
        assert out == ""
        seen.add((code, err))
    return seen


def test_plates_that_cannot_close_a_redundant_loop_are_refused_alike(tmp_path, capsys):
    """A third leg with 1 % longer plates: the rigid linkage still moves, but no kinematic
    level can bend each plate by its model and also close the redundant loop."""
    path = edited(
        tmp_path,
        "three_leg_stage",
        ('at = ["w/2", 0.0]\n', 'at = ["w/2", 0.0]\nlength = "1.01*l"\n'),
        ('at = ["w/2", "L"]\n', 'at = ["w/2", "L"]\nlength = "1.01*l"\n'),
    )
    code, out, _ = run(["eval", path, "--input", "F1=0.05", "--level", "paper"], capsys)
    assert code == 0 and "deviation" in out
    for level in ("first_order", "exact"):
        ((code, err),) = refusals(path, {"F1": "0.05"}, level, capsys)
        assert code == 3
        loop = "the redundant loop of 'S3' (F1 + S1 - F3 + S3)"
        assert f"the plates do not close {loop} at level {level}" in err
        assert "F1=0.05" in err and "equilibrium" in err


def test_a_locked_redundant_linkage_is_refused_alike(tmp_path, capsys):
    """A third leg 0.1 % longer than the others: mobility 1 at the as-fabricated pose (first
    order), but the rigid linkage locks once it moves: exit 3 in every backend."""
    path = edited(tmp_path, "three_leg_stage", ('at = ["w/2", "L"]', 'at = ["w/2", "L*1.001"]'))
    for level in KINEMATIC:
        ((code, err),) = refusals(path, {"F1": "0.05"}, level, capsys)
        assert code == 3
        assert "the redundant loop of 'S3' (F1 + S1 - F3 + S3) cannot close" in err
        assert "the rigid linkage locks" in err


def test_loaded_solves_a_redundant_mechanism(capsys):
    """The reduced equilibrium shares the redundant loops' forces by the plates' compliance: the
    three-leg stage answers at `loaded` (against equilibrium: tests/test_loaded_newton.py)."""
    path = str(ZOO / "three_leg_stage.toml")
    code, out, err = run(["eval", path, "--input", "F1=0.05", "--level", "loaded"], capsys)
    assert code == 0, err
    assert "point P" in out and "plate loads" in out


def test_eval_help_states_the_defaults(capsys):
    with pytest.raises(SystemExit):
        main(["eval", "--help"])
    out = capsys.readouterr().out
    assert "default: loaded where every plate has E, thickness and width, else exact" in " ".join(
        out.split()
    )
    assert "default: sympy" in " ".join(out.split())
