"""Inputs and overrides at and beyond the limits: the same refusal in every backend, never a
result marked ok that is not finite, no partial output from the C evaluator."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from conftest import EXAMPLES
from evaluators import BACKENDS, generated, rel_err
from reference_solver import Reference

import symkin
from symkin.cli.commands import main
from symkin.codegen import pipeline

FOUR_BAR = str(EXAMPLES / "four_bar.toml")


def run(args, capsys):
    code = main(args)
    return (code, *capsys.readouterr())


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize(
    "param, message",
    [
        ("l=-1e-3", "plate length must be positive"),
        ("l=0", "plate length must be positive"),
    ],
)
def test_overrides_are_validated_like_the_file(capsys, backend, param, message):
    code, out, err = run(
        ["eval", FOUR_BAR, "--input", "A0=0.2", "--param", param, "--backend", backend], capsys
    )
    assert code == 2 and message in err and "fix:" in err and out == ""


def test_a_negative_length_in_the_file_is_refused_too(tmp_path, capsys):
    path = tmp_path / "f.toml"
    path.write_text((EXAMPLES / "four_bar.toml").read_text().replace("l = 1e-3", "l = -1e-3"))
    code, _, err = run(["check", str(path)], capsys)
    assert code == 2 and "positive" in err


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("angle", ["2*pi-0.3", "-3.2", "1e300", "1e8"])
def test_inputs_beyond_a_half_turn_exit_3_in_every_backend(capsys, backend, angle):
    code, out, err = run(["eval", FOUR_BAR, "--input", f"A0={angle}", "--backend", backend], capsys)
    assert code == 3 and "|angle| <= pi" in err and out == ""


def test_the_refusal_names_the_same_pose(capsys):
    _, _, err = run(["eval", FOUR_BAR, "--input", "A0=2*pi-0.3"], capsys)
    assert "A0=-0.3" in err


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_half_turn_itself_is_accepted(capsys, backend):
    """The double nearest pi lies below pi: the crank-rocker's crank reaches a half turn in every
    backend, with the independent solver's deviation (every hinge stays within a half turn)."""
    code, out, err = run(
        # the independent solver is the kinematic model's: the exact level
        ["eval", FOUR_BAR, "--input", "A0=3.141592653589793", "--json", "--backend", backend]
        + ["--level", "exact"],
        capsys,
    )
    assert code == 0, err
    dev = json.loads(out)["points"]["C"]["deviation"]
    ref = Reference(symkin.load(FOUR_BAR)).deviation({"A0": "3.141592653589793"})
    assert rel_err(dev, ref["points"]["C"]["deviation"]) <= 1e-9


def test_c_api_refuses_and_fills_nan():
    g = generated("four_bar")
    for x, want in ((1e300, 3), (4.0, 3), (math.nan, 3), (math.inf, 3)):
        status, out, angles = g.lib.evaluate([x], None, 2)
        assert status == want
        assert all(math.isnan(v) for v in out) and all(math.isnan(v) for v in angles)
    # beyond the assembly range (the crank-rocker's crank turns fully; the non-Grashof doesn't)
    h = generated("non_grashof")
    status, out, _ = h.lib.evaluate([2.5], None, 2)
    assert status == 1 and all(math.isnan(v) for v in out)
    status, out, _ = g.lib.evaluate([0.2], None, 7)  # a level not generated
    assert status == 3 and all(math.isnan(v) for v in out)


def test_c_api_refuses_non_finite_parameters():
    g = generated("four_bar")
    for bad in (math.nan, math.inf):
        status, out, _ = g.lib.evaluate([0.2], [bad], 2)
        assert status == 3 and all(math.isnan(v) for v in out)


@pytest.mark.parametrize("params", [{"l": math.nan}, {"l": math.inf}, {"l": 1e300}])
def test_numpy_never_ok_when_not_finite(params):
    g = generated("four_bar")
    res = g.numpy.evaluate({"A0": np.array([0.1, 0.2])}, "exact", params)
    dev = res["points"]["C"]["deviation"]
    assert not np.any(res["ok"] & ~np.isfinite(dev).all(axis=0))


def test_numpy_refuses_inputs_beyond_a_half_turn():
    g = generated("four_bar")
    x = np.array([0.2, 2 * math.pi - 0.3, 1e300, -3.5, math.nan])
    res = g.numpy.evaluate({"A0": x}, "exact")
    assert res["ok"].tolist() == [True, False, False, False, False]
    assert np.isnan(res["points"]["C"]["deviation"][:, 1:]).all()


def test_numpy_default_level_is_the_most_faithful_generated():
    an = symkin.analyze(symkin.load(FOUR_BAR))
    _, module = pipeline.build(an, "numpy", "test", levels=["paper", "first_order"])
    assert module.LEVELS == ("paper", "first_order")
    default = module.evaluate({"A0": 0.2})
    explicit = module.evaluate({"A0": 0.2}, "first_order")
    assert np.array_equal(default["points"]["C"]["deviation"], explicit["points"]["C"]["deviation"])
