"""The rotation of every link (parasitic rotation of a stage or an output link) in every backend,
against the independent solver's full link poses (tests/reference_solver.py)."""

from __future__ import annotations

import json
import math

import mpmath
import pytest
from conftest import EXAMPLES
from evaluators import BACKENDS, GENERATED, INPUTS, generated
from reference_solver import Reference

import symkin
from symkin.cli.commands import main
from symkin.codegen import pipeline
from symkin.codegen.plan import plan

KEYS = ["four_bar", "six_bar", "nine_bar", "five_bar", "triad", "serial_arm"]


def reference_rotations(mech, inputs, overrides=None) -> dict[str, tuple[float, float]]:
    """(rigid φ, compliant − rigid φ) of every link from the reference's full poses."""
    ref = Reference(mech, overrides).deviation(inputs)
    with mpmath.workdps(ref["dps"]):
        rigid, compliant = ref["rigid"]["poses"], ref["compliant"]["poses"]
        return {
            name: (float(rigid[name][2]), float(compliant[name][2] - rigid[name][2]))
            for name in rigid
        }


def run_backend(g, inputs, level, backend, overrides=None):
    return symkin.evaluate(g.analysis, inputs, level, overrides, backend=backend).links


@pytest.mark.parametrize("key", KEYS)
@pytest.mark.parametrize("backend", BACKENDS)
def test_exact_link_rotations_against_the_independent_solver(key, backend):
    g = generated(key)
    want = reference_rotations(g.mech, INPUTS[key])
    got = run_backend(g, INPUTS[key], "exact", backend)
    assert set(got) == set(want)
    for name, (rigid, dev) in want.items():
        assert got[name].rigid == pytest.approx(rigid, rel=1e-12, abs=1e-15), name
        assert got[name].compliant == pytest.approx(
            got[name].rigid + got[name].deviation, rel=1e-15, abs=1e-18
        )
        if dev == 0.0:
            assert got[name].deviation == 0.0, name
        else:
            assert abs(got[name].deviation - dev) <= 1e-9 * abs(dev), (name, got[name], dev)


@pytest.mark.parametrize("backend", GENERATED)
def test_tiny_plates_keep_the_relative_accuracy_of_the_rotation(backend):
    g = generated("four_bar")
    overrides = {"l": "5e-11"}
    want = reference_rotations(g.mech, {"A0": "0.2"}, overrides)
    got = run_backend(g, {"A0": "0.2"}, "exact", backend, overrides)
    for name in ("coupler", "rocker"):
        assert abs(got[name].deviation - want[name][1]) <= 1e-9 * abs(want[name][1])


@pytest.mark.parametrize("key", ["four_bar", "nine_bar"])
@pytest.mark.parametrize("backend", GENERATED)
def test_every_level_matches_the_sympy_backend(key, backend):
    g = generated(key)
    for level in ("paper", "first_order", "exact"):
        want = run_backend(g, INPUTS[key], level, "sympy")
        got = run_backend(g, INPUTS[key], level, backend)
        for name, r in want.items():
            assert got[name].deviation == pytest.approx(r.deviation, rel=1e-12, abs=1e-300)
            if level == "paper":
                assert r.deviation == 0.0  # (4.8) keeps the rigid angles


def test_json_and_text_carry_the_links(capsys):
    assert (
        main(
            [
                "eval",
                str(EXAMPLES / "four_bar.toml"),
                "--input",
                "A0=0.2",
                "--json",
                "--backend",
                "c",
            ]
        )
        == 0
    )
    data = json.loads(capsys.readouterr().out)
    assert set(data["links"]) == {"frame", "crank", "coupler", "rocker"}
    assert data["links"]["crank"] == {"rigid": 0.2, "compliant": 0.2, "deviation": 0.0}
    assert main(["eval", str(EXAMPLES / "four_bar.toml"), "--input", "A0=0.2"]) == 0
    assert "link rotations (rad)" in capsys.readouterr().out


def test_c_pose_fills_nan_on_failure_and_accepts_null():
    g = generated("four_bar")
    header, _ = pipeline.emit(g.plan, "c", g.mech.path)
    assert "#define FOUR_BAR_N_LINKS 4" in header and "four_bar_evaluate_pose" in header
    lib = pipeline.evaluator(g.plan, "c", g.mech.path)
    status, _, _, links = lib.pose([0.2], None, 2)
    assert status == 0 and links[3 * 1] == 0.2  # the crank turns by its input
    status, out, angles, links = lib.pose([4.0], None, 2)
    assert status == 3 and all(math.isnan(v) for v in links + out + angles)
    status, out, _ = lib.evaluate([0.2], None, 2)  # evaluate_pose with links NULL
    assert status == 0


def test_points_singled_out_report_no_links():
    g = generated("four_bar")
    assert plan(g.analysis, points=["C"]).reported_links == ()
    assert plan(g.analysis).reported_links == ("frame", "crank", "coupler", "rocker")


def test_links_solve_the_loops_only_when_asked(tmp_path):
    """The nine-bar's F needs no loop: the plain evaluators skip the loops, the pose (C) and the
    numpy default (links=True) solve them for the links' rotations."""
    g = generated("nine_bar")
    assert not g.plan.needs_loops and g.plan.loops_for_links
    inputs = {k: float(v) for k, v in INPUTS["nine_bar"].items()}
    with_links = g.numpy.evaluate(inputs, "exact")
    without = g.numpy.evaluate(inputs, "exact", links=False)
    assert without["links"] == {} and with_links["links"]["b5"]["deviation"] != 0
    assert (without["points"]["F"]["deviation"] == with_links["points"]["F"]["deviation"]).all()
    want = reference_rotations(g.mech, INPUTS["nine_bar"])["b5"][1]
    assert abs(float(with_links["links"]["b5"]["deviation"]) - want) <= 1e-9 * abs(want)
