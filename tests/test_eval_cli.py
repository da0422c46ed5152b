"""`symkin eval` (docs/cli.md): JSON shape, levels, exit codes 2 and 3, and no tracebacks."""

from __future__ import annotations

import json
import math
import subprocess
import sys

import mechanisms as M
import pytest
from cli_runs import symkin_cli
from conftest import EXAMPLES
from evaluators import BACKENDS

from symkin.cli.commands import main

FOUR_BAR = str(EXAMPLES / "four_bar.toml")


def run(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


@pytest.mark.parametrize("level", ["paper", "first_order", "exact"])
def test_json_has_the_contract_keys(capsys, level):
    code, out, err = run(capsys, "eval", FOUR_BAR, "--input", "A0=0.2", "--level", level, "--json")
    assert code == 0, err
    data = json.loads(out)
    assert set(data) == {
        "level",
        "backend",
        "inputs",
        "params",
        "angles",
        "points",
        "links",
        "dyads",
    }
    assert data["level"] == level and data["backend"] == "sympy"
    assert data["inputs"] == {"A0": 0.2} and data["params"] == {"l": 1e-3}
    assert set(data["angles"]) == {"rigid", "compliant"}
    assert set(data["angles"]["rigid"]) == {"A0", "A", "B0", "B"}
    c = data["points"]["C"]
    assert set(c) == {"rigid", "compliant", "deviation", "norm"}
    assert c["norm"] == pytest.approx(math.hypot(*c["deviation"]), rel=1e-15)
    (dyad,) = data["dyads"]
    assert dyad["hinges"] == ["A", "B", "B0"] and dyad["loop"] == "B" and dyad["branch"] == 1
    assert 0 < dyad["toggle_margin"] <= 1
    for k in range(2):
        assert c["compliant"][k] == pytest.approx(
            c["rigid"][k] + c["deviation"][k], rel=1e-15, abs=1e-18
        )
    assert 1e-7 < abs(c["deviation"][0]) < 1e-4


def test_text_output_names_points_and_dyads(capsys):
    code, out, _ = run(capsys, "eval", FOUR_BAR, "--input", "A0=10*deg")
    assert code == 0
    assert "point C" in out and "deviation" in out and "toggle margin" in out


def test_param_override_changes_the_deviation(capsys):
    _, base, _ = run(capsys, "eval", FOUR_BAR, "--input", "A0=0.2", "--json")
    _, bigger, _ = run(capsys, "eval", FOUR_BAR, "--input", "A0=0.2", "--param", "l=2e-3", "--json")
    d0 = json.loads(base)["points"]["C"]["deviation"]
    d1 = json.loads(bigger)["points"]["C"]["deviation"]
    assert d1[0] / d0[0] == pytest.approx(2.0, rel=0.05)  # Δz scales with the plate length


@pytest.mark.parametrize("level", ["paper", "first_order", "exact"])
def test_out_of_assembly_range_exits_3_naming_the_loop(tmp_path, level):
    path = tmp_path / "non_grashof.toml"
    path.write_text(M.NON_GRASHOF)
    proc = symkin_cli("eval", str(path), "--input", "A0=2.5", "--level", level, timeout=120)
    assert proc.returncode == 3, proc.stderr
    assert "Traceback" not in proc.stderr
    assert "loop of hinge 'B'" in proc.stderr and "non_grashof.toml" in proc.stderr


@pytest.mark.parametrize(
    "argv, fragment",
    [
        (["--input", "A0"], "not NAME=VALUE"),
        (["--input", "B=0.2"], "'B' is not an input hinge"),
        ([], "no value for the input(s) A0"),
        (["--input", "A0=0.2", "--param", "L=1"], "unknown parameter 'L'"),
        (["--input", "A0=__import__('os')"], "not allowed"),
        (["--input", "A0=0.2", "--input", "A0=0.3"], "given twice"),
    ],
)
def test_bad_options_exit_2(capsys, argv, fragment):
    code, out, err = run(capsys, "eval", FOUR_BAR, *argv)
    assert code == 2
    assert fragment in err and out == ""
    assert "Traceback" not in err
    # every one names the file and says how to fix it
    assert "four_bar.toml" in err and "fix:" in err


def test_sensitivity_at_a_level_without_them_exits_2(capsys):
    """--sensitivity at equilibrium (no sensitivities there) names the levels that have them,
    with actuators too (it was ignored there)."""
    for path, given in (
        (EXAMPLES / "four_bar.toml", "A0=0.2"),
        (EXAMPLES / "piezo_amplifier.toml", "piezo=0.01"),
    ):
        code, out, err = run(
            capsys, "eval", str(path), "--input", given, "--level", "equilibrium", "--sensitivity"
        )
        assert code == 2 and out == ""
        assert "the equilibrium level has no sensitivities" in err
        assert "exact" in err and "loaded" in err and path.name in err


def test_param_override_cannot_build_a_huge_number(tmp_path, capsys):
    """A default that depends on an overridden parameter is re-evaluated numerically."""
    import time

    text = (
        (EXAMPLES / "four_bar.toml")
        .read_text()
        .replace("[defaults]\n", 'n = 2\nq = "l**n"\n\n[defaults]\n')
    )
    path = tmp_path / "bomb.toml"
    path.write_text(text)
    start = time.perf_counter()
    code, _out, err = run(
        capsys, "eval", str(path), "--input", "A0=0.2", "--param", "n=1e9", "--level", "paper"
    )
    assert code == 0, err
    assert time.perf_counter() - start < 20


@pytest.mark.parametrize("backend", BACKENDS)
def test_model_limit_exits_3_in_every_backend(tmp_path, backend):
    path = tmp_path / "elastica.toml"
    path.write_text(
        (EXAMPLES / "four_bar.toml")
        .read_text()
        .replace('model = "circular_arc"', 'model = "elastica_force"')
    )
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "symkin",
            "eval",
            str(path),
            "--input",
            "A0=1.7",
            "--level",  # the hinge model's limit: a kinematic level's (loaded bends beams)
            "exact",
            "--backend",
            backend,
        ],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert proc.returncode == 3, proc.stderr
    assert "hinge 'A0'" in proc.stderr and "elastica_force" in proc.stderr


@pytest.mark.parametrize("level", ["paper", "first_order", "exact"])
def test_all_backends_print_the_same_json(capsys, level):
    outputs = {}
    for backend in BACKENDS:
        code, out, err = run(
            capsys,
            "eval",
            str(EXAMPLES / "stephenson_six_bar.toml"),
            "--input",
            "O_A=0.15",
            "--param",
            "l=1.2e-3",
            "--level",
            level,
            "--backend",
            backend,
            "--json",
        )
        assert code == 0, err
        outputs[backend] = json.loads(out)
    ref = outputs.pop("sympy")
    for backend, data in outputs.items():
        assert data["backend"] == backend
        assert list(data["angles"]["rigid"]) == list(ref["angles"]["rigid"])
        for kind in ("rigid", "compliant"):
            for h, v in ref["angles"][kind].items():
                assert data["angles"][kind][h] == pytest.approx(v, rel=1e-13, abs=1e-15)
        for key in ("rigid", "compliant", "deviation"):
            for got, want in zip(data["points"]["D"][key], ref["points"]["D"][key]):
                assert got == pytest.approx(want, rel=1e-12)


def test_toggle_margin_against_an_independent_construction(capsys):
    """|sin| of the angle at B between B->A and B->B0, from the rigid four-bar built here by
    intersecting two circles (A on the crank turned by A0 about A0's centre, B0 fixed)."""
    import mpmath

    code, out, _ = run(capsys, "eval", FOUR_BAR, "--input", "A0=0.2", "--json", "--backend", "c")
    assert code == 0
    margin = json.loads(out)["dyads"][0]["toggle_margin"]
    with mpmath.workdps(30):
        t = mpmath.mpf("0.2")
        a = (
            mpmath.mpf("0.015") * mpmath.cos(t) - mpmath.mpf("0.026") * mpmath.sin(t),
            mpmath.mpf("0.015") * mpmath.sin(t) + mpmath.mpf("0.026") * mpmath.cos(t),
        )
        b0 = (mpmath.mpf("0.1"), mpmath.mpf(0))
        r1 = mpmath.hypot(mpmath.mpf("0.07"), mpmath.mpf("0.042"))  # |B - A| as fabricated
        r2 = mpmath.hypot(mpmath.mpf("-0.015"), mpmath.mpf("0.068"))  # |B - B0|
        d = mpmath.hypot(b0[0] - a[0], b0[1] - a[1])
        along = (r1**2 - r2**2 + d**2) / (2 * d)
        h = mpmath.sqrt(r1**2 - along**2)
        ex, ey = (b0[0] - a[0]) / d, (b0[1] - a[1]) / d
        b = (a[0] + along * ex - h * ey, a[1] + along * ey + h * ex)  # B lies left of A -> B0
        u, v = (a[0] - b[0], a[1] - b[1]), (b0[0] - b[0], b0[1] - b[1])
        sine = abs(u[0] * v[1] - u[1] * v[0]) / (r1 * r2)
    assert margin == pytest.approx(float(sine), rel=1e-12)
