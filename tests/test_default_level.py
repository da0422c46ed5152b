"""The default level (docs/levels.md, "The default level"): `loaded` where every plate has E,
thickness and width, else `exact`; in eval, tolerance, sweep, the Python API and the generated
numpy and C evaluators; the line that says which level ran and why; the warning on a kinematic
level asked for on a stiff file; the same command twice gives the same bytes."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tomllib

import numpy as np
import pytest
from cli_runs import symkin_cli
from conftest import EXAMPLES, ROOT
from evaluators import require_compiler

import symkin
from symkin.codegen import pipeline
from symkin.core import levels

FOUR_BAR = EXAMPLES / "four_bar.toml"  # steel plates with E, thickness and width
DIMENSIONS = EXAMPLES / "four_bar_dimensions.toml"  # no E: kinematic only
STIFF_LINE = "level: loaded (default: every plate has E, thickness and width)"


def has_stiffness_by_hand(path) -> bool:
    """The rule read off the TOML itself: every hinge that is not `rigid` has E, thickness and
    width, its own or [defaults]' (a notch hinge too: loaded takes it)."""
    data = tomllib.loads(path.read_text())
    defaults = data.get("defaults", {})
    for hinge in data["hinge"]:
        merged = {**defaults, **hinge}
        if merged.get("model") == "rigid":
            continue
        if not all(key in merged for key in ("E", "thickness", "width")):
            return False
    return True


@pytest.mark.parametrize("path", sorted(EXAMPLES.glob("*.toml")), ids=lambda p: p.stem)
def test_the_default_follows_the_files_stiffness_data(path):
    expected = "loaded" if has_stiffness_by_hand(path) else "exact"
    choice = levels.default_for(symkin.load(path))
    assert choice.name == expected and choice.default
    assert choice.reason.startswith("default: ")


def test_a_stiff_and_a_kinematic_file():
    assert has_stiffness_by_hand(FOUR_BAR) and not has_stiffness_by_hand(DIMENSIONS)
    stiff = levels.default_for(symkin.load(FOUR_BAR))
    assert stiff.line == STIFF_LINE
    plain = levels.default_for(symkin.load(DIMENSIONS))
    assert plain.name == "exact"
    # names the first plate without the data, and the key
    assert "hinge 'A0' has no E" in plain.line and "no forces" in plain.line
    assert levels.choose(symkin.load(FOUR_BAR), "paper").line == "level: paper (asked for)"
    with pytest.raises(symkin.InputError, match="unknown level 'best'"):
        levels.choose(symkin.load(FOUR_BAR), "best")


def test_a_redundant_mechanism_of_elastica_plates_falls_back_to_exact(tmp_path):
    """loaded refuses such a file whatever the inputs (exit 3): the default is exact, with the
    reason, and the default run succeeds; the same file with Reissner plates defaults to
    loaded."""
    source = ROOT / "tests" / "mechanisms" / "three_leg_stage.toml"
    path = tmp_path / "elastica_stage.toml"
    path.write_text(source.read_text().replace("[defaults]", '[defaults]\nbeam = "elastica"', 1))
    mech = symkin.load(path)
    assert mech.redundant and mech.has_stiffness
    choice = levels.default_for(mech)
    assert choice.name == "exact" and "redundant" in choice.reason and "elastica" in choice.reason
    assert levels.default_for(symkin.load(source)).name == "loaded"
    asked = symkin_cli("eval", path, "--input", "F1=0.05", "--level", "loaded")
    assert asked.returncode == 3 and "redundant" in asked.stderr
    run = symkin_cli("eval", path, "--input", "F1=0.05")
    assert run.returncode == 0, run.stderr
    assert run.stdout.splitlines()[0] == choice.line and run.stderr == ""


def test_eval_says_which_level_and_why():
    default = symkin_cli("eval", FOUR_BAR, "--input", "A0=0.2")
    asked = symkin_cli("eval", FOUR_BAR, "--input", "A0=0.2", "--level", "loaded")
    assert default.returncode == asked.returncode == 0
    first, rest = default.stdout.split("\n", 1)
    assert first == STIFF_LINE and default.stderr == ""
    # the rest is what --level loaded prints, under its own first line
    asked_first, asked_rest = asked.stdout.split("\n", 1)
    assert asked_first == "level: loaded (asked for)" and rest == asked_rest
    plain = symkin_cli("eval", DIMENSIONS, "--input", "A0=0.2")
    assert plain.returncode == 0 and plain.stderr == ""
    assert plain.stdout.startswith("level: exact (default: not every plate has E, thickness ")
    assert plain.stdout.splitlines()[1].startswith("backend sympy; inputs: A0 = 0.2")


def test_eval_json_names_the_default_level():
    default = symkin_cli("eval", FOUR_BAR, "--input", "A0=0.2", "--json")
    asked = symkin_cli("eval", FOUR_BAR, "--input", "A0=0.2", "--json", "--level", "loaded")
    assert json.loads(default.stdout)["level"] == "loaded"
    assert default.stdout == asked.stdout
    plain = symkin_cli("eval", DIMENSIONS, "--input", "A0=0.2", "--json")
    assert json.loads(plain.stdout)["level"] == "exact"


def _process(*args: str) -> subprocess.CompletedProcess:
    """`python -m symkin *args` in a process of its own: its real stderr, its own hash seed."""
    env = {k: v for k, v in os.environ.items() if k != "PYTHONHASHSEED"}
    return subprocess.run(
        [sys.executable, "-m", "symkin", *args],
        capture_output=True,
        text=True,
        cwd=ROOT,
        env=env,
        timeout=300,
    )


@pytest.mark.parametrize("level", ["paper", "first_order", "exact"])
def test_a_kinematic_level_on_a_stiff_file_warns_in_one_line(level):
    run = _process("eval", "examples/four_bar.toml", "--input", "A0=0.2", "--level", level)
    assert run.returncode == 0, run.stderr
    assert run.stderr == (
        f"symkin: warning: --level {level} ignores the plates' forces (every plate has E, "
        "thickness and width); --level loaded includes them (LevelWarning)\n"
    )
    assert run.stdout.startswith(f"level: {level} (asked for)\n")


def test_no_warning_where_the_level_is_the_files_own():
    for args in (
        ("eval", FOUR_BAR, "--input", "A0=0.2", "--level", "loaded"),
        ("eval", DIMENSIONS, "--input", "A0=0.2", "--level", "exact"),
        ("eval", DIMENSIONS, "--input", "A0=0.2", "--level", "paper"),
    ):
        run = symkin_cli(*args)
        assert run.returncode == 0 and run.stderr == "", args


def test_the_same_command_twice_gives_the_same_bytes():
    first = _process("eval", "examples/four_bar.toml", "--input", "A0=0.2")
    second = _process("eval", "examples/four_bar.toml", "--input", "A0=0.2")
    assert first.returncode == second.returncode == 0
    assert first.stdout == second.stdout and first.stderr == second.stderr == ""
    assert first.stdout.startswith(STIFF_LINE + "\n")


def test_the_python_api_takes_the_files_default():
    an = symkin.analyze(FOUR_BAR)
    default = symkin.evaluate(an, {"A0": 0.2})
    asked = symkin.evaluate(an, {"A0": 0.2}, level="loaded")
    assert default.level == "loaded" and default.points["C"] == asked.points["C"]
    assert symkin.evaluate(symkin.analyze(DIMENSIONS), {"A0": 0.2}).level == "exact"
    ev = symkin.compile(FOUR_BAR, "numpy", sensitivity=False)
    x = {"A0": np.array([0.1, 0.2])}
    assert ev.code(None) == "loaded"
    got, want = ev.evaluate(x), ev.evaluate(x, "loaded")
    assert np.array_equal(got["points"]["C"]["deviation"], want["points"]["C"]["deviation"])


def test_tolerance_and_sweep_say_which_level_and_why():
    vary = ("--vary", "l=±1%", "--input", "A0=0.1:0.2:2", "--backend", "numpy")
    tol = symkin_cli("tolerance", FOUR_BAR, *vary)
    assert tol.returncode == 0, tol.stderr
    lines = tol.stdout.splitlines()
    assert lines[0] == STIFF_LINE and "at level loaded (numpy)" in lines[1]
    assert tol.stderr == ""
    asked = symkin_cli("tolerance", FOUR_BAR, *vary, "--level", "loaded")
    assert asked.stdout.split("\n", 1)[1] == tol.stdout.split("\n", 1)[1]
    plain = symkin_cli("tolerance", DIMENSIONS, "--vary", "l=±1%", "--input", "A0=0.2")
    assert plain.returncode == 0, plain.stderr
    assert plain.stdout.startswith("level: exact (default: not every plate has E")
    sweep = ("--vary", "l=±1%", "--input", "A0=0.1:0.2:2", "--samples", "4", "--scheduler", "sync")
    run = symkin_cli("sweep", FOUR_BAR, *sweep, "--backend", "numpy")
    assert run.returncode == 0, run.stderr
    assert run.stdout.splitlines()[0] == STIFF_LINE and "level loaded (numpy)" in run.stdout
    as_json = symkin_cli("sweep", FOUR_BAR, *sweep, "--backend", "numpy", "--json")
    assert json.loads(as_json.stdout)["level"] == "loaded"
    warned = symkin_cli("sweep", FOUR_BAR, *sweep, "--backend", "numpy", "--level", "exact")
    assert warned.returncode == 0 and "ignores the plates' forces" in warned.stderr


def test_the_generated_numpy_module_has_the_default(tmp_path):
    for path, expected in ((FOUR_BAR, "loaded"), (DIMENSIONS, "exact")):
        an = symkin.analyze(path)
        _, module = pipeline.build(an, "numpy", "dl_" + path.stem)
        # derive's default levels hold the default: loaded with the plates' data
        assert expected in module.LEVELS
        assert expected == module.DEFAULT_LEVEL
        x = {"A0": np.array([-0.1, 0.2])}
        got, want = module.evaluate(x), module.evaluate(x, expected)
        assert np.array_equal(got["points"]["C"]["deviation"], want["points"]["C"]["deviation"])
    # the levels given leave the default out: exact when generated, else the most faithful
    _, module = pipeline.build(symkin.analyze(FOUR_BAR), "numpy", "dl_k", levels=["exact"])
    assert module.DEFAULT_LEVEL == "exact"


DRIVER = r"""
#include <stdio.h>
#include "four_bar.h"
int main(void) {
    double inputs[1] = {0.2}, out[6 * FOUR_BAR_N_POINTS];
    int status = four_bar_evaluate(inputs, NULL, FOUR_BAR_DEFAULT_LEVEL, out);
    printf("%d %d %.17g %.17g\n", FOUR_BAR_DEFAULT_LEVEL, status, out[4], out[5]);
    return 0;
}
"""


def test_the_c_header_defines_the_default(tmp_path):
    """`symkin derive` writes <NAME>_DEFAULT_LEVEL; a program compiled with cc passes it and gets
    the loaded level's deviation (the 40-digit evaluation's, to float64's Newton tolerance)."""
    require_compiler()
    run = symkin_cli("derive", FOUR_BAR, "-o", tmp_path, "--emit", "c", "--quiet")
    assert run.returncode == 0, run.stderr
    header = (tmp_path / "four_bar.h").read_text()
    assert f"#define FOUR_BAR_DEFAULT_LEVEL {levels.get('loaded').code}\n" in header
    (tmp_path / "main.c").write_text(DRIVER)
    cc = os.environ.get("CC", "cc")
    exe = tmp_path / "main"
    subprocess.run(
        [cc, "-std=c99", "-O1", "-o", exe, tmp_path / "main.c", tmp_path / "four_bar.c", "-lm"],
        check=True,
        cwd=tmp_path,
        timeout=600,
    )
    code, status, dx, dy = subprocess.run(
        [exe], capture_output=True, text=True, check=True, timeout=60
    ).stdout.split()
    assert (int(code), int(status)) == (3, 0)
    ref = symkin.evaluate(symkin.analyze(FOUR_BAR), {"A0": 0.2}, level="loaded")
    assert np.allclose([float(dx), float(dy)], ref.points["C"].deviation, rtol=1e-9, atol=0)
    # a kinematic file's header: exact (2)
    run = symkin_cli("derive", DIMENSIONS, "-o", tmp_path / "k", "--emit", "c", "--quiet")
    assert run.returncode == 0, run.stderr
    assert (
        "#define FOUR_BAR_DIMENSIONS_DEFAULT_LEVEL 2\n"
        in (tmp_path / "k" / "four_bar_dimensions.h").read_text()
    )


def test_the_reports_sensitivity_table_takes_the_default_level(tmp_path):
    """The elastica stage's default is exact (loaded refuses it at every input): the report
    ranks the parameters at exact, where the most faithful level with sensitivities, loaded,
    gave no table at all."""
    from symkin.studies.derive import generate

    source = ROOT / "tests" / "mechanisms" / "three_leg_stage.toml"
    text = source.read_text().replace("[defaults]", '[defaults]\nbeam = "elastica"', 1)
    mech = symkin.loads(text, "elastica_stage.toml")
    assert levels.default_for(mech).name == "exact"
    tex = generate(mech, emit=["latex"])[f"{mech.name}.tex"].decode()
    assert "deviation (level exact)" in tex and ":sensitivity}" in tex
    # the committed four-bar's report: its default, loaded
    committed = (ROOT / "generated" / "four_bar" / "four_bar.tex").read_text()
    assert "deviation (level loaded)" in committed


def test_a_file_with_notches_defaults_to_loaded_but_not_in_generated_c_code():
    """loaded takes notch hinges: a notch file's default is loaded, and `eval` without --level
    runs it, in the generated numpy evaluator too; for the generated C evaluator (or a generated
    backend not named), whose loaded takes uniform plates, it is exact, with the reason naming
    the hinge and its profile."""
    path = ROOT / "examples" / "notch_lever.toml"
    mech = symkin.load(path)
    assert mech.has_stiffness
    choice = levels.default_for(mech)
    assert choice.name == "loaded" and choice.default
    assert levels.default_for(mech, generated="numpy") == choice
    for backend in ("c", True):
        generated = levels.default_for(mech, generated=backend)
        assert generated.name == "exact" and generated.default
        assert "circular" in generated.reason and "'O'" in generated.reason
    run = symkin_cli("eval", path, "--input", "piezo=0.02")
    assert run.returncode == 0, run.stderr
    assert run.stdout.splitlines()[0] == choice.line and run.stderr == ""
