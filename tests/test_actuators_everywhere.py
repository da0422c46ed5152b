"""Actuators everywhere (docs/scene.md, docs/cli.md): `derive --points` and scene
files take files with actuators (a stroke, a force), their evaluators taking the strokes and
forces; `derive --fix` and a scene's [fix] hold input hinges only, not an actuator or the
hinge its stroke sets (exit 2; the fixed inputs beside actuators: tests/test_fix_actuators.py); the
report labels a stroke in the file's length unit and a force in N. The numbers against `symkin
eval`'s sympy backend (mpmath), which tests/test_loaded_actuators.py and tests/test_actuators.py
check against independent references."""

from __future__ import annotations

import importlib.util
import json
import math
from pathlib import Path

import numpy as np
import pytest
from cli_runs import symkin_cli
from conftest import EXAMPLES
from test_beyond_reach import CANTILEVER

from symkin.report.sections import input_axis, input_unit

PIEZO = EXAMPLES / "piezo_amplifier.toml"


def _import(path: Path):
    spec = importlib.util.spec_from_file_location(f"everywhere_{path.stem}", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _eval(path: Path, level: str, **inputs: float) -> dict:
    argv = ["eval", str(path), "--level", level, "--json"]
    for name, value in inputs.items():
        argv += ["--input", f"{name}={value!r}"]
    run = symkin_cli(*argv)
    assert run.returncode == 0, run.stderr
    return json.loads(run.stdout)


def test_derive_points_takes_a_stroke_actuator(tmp_path):
    """`derive --points B` on the piezo amplifier: the module's input is the stroke, its one point
    B, its deviations eval's at exact and loaded (1e-9 of |dR|)."""
    run = symkin_cli("derive", str(PIEZO), "--points", "B", "--emit", "numpy", "-o", str(tmp_path))
    assert run.returncode == 0, run.stderr
    module = _import(tmp_path / "piezo_amplifier.py")
    assert module.INPUTS == ("piezo",) and module.POINTS == ("B",)
    strokes = [0.01, 0.03]
    for level in ("exact", "loaded"):
        got = module.evaluate({"piezo": np.array(strokes)}, level)
        assert got["ok"].all()
        for k, s in enumerate(strokes):
            want = _eval(PIEZO, level, piezo=s)["points"]["B"]
            dev = got["points"]["B"]["deviation"][:, k]
            assert math.dist(dev, want["deviation"]) <= 1e-9 * want["norm"], (level, s)


def test_derive_fix_refuses_the_actuator_itself(tmp_path):
    run = symkin_cli("derive", str(PIEZO), "--fix", "piezo=0.01", "-o", str(tmp_path))
    assert run.returncode == 2
    assert "'piezo' is an actuator" in run.stderr and "--fix" in run.stderr, run.stderr


SCENE = """format = 1
name = "{name}"
reference = "{reference}"
samples = 5
backend = "{backend}"
{fix}
[ranges]
{ranges}

[[point]]
name = "{point}"
relative_tolerance = {tol}
"""


def _scene(tmp_path: Path, mech: Path, emit: str = "numpy", **keys: str) -> tuple[int, str, Path]:
    defaults = {"fix": "", "reference": "exact", "tol": "0.05", "backend": "numpy"}
    text = SCENE.format(**(defaults | keys))
    scene = tmp_path / "scene.toml"
    scene.write_text(text)
    out = tmp_path / "out"
    run = symkin_cli("derive", str(mech), "--scene", str(scene), "--emit", emit, "-o", str(out))
    return run.returncode, run.stderr, out


def test_a_scene_with_a_stroke_actuator(tmp_path):
    """The piezo amplifier's B within 5 % over strokes 0 to 0.05 mm: the scene evaluator takes
    the stroke and meets the tolerance against eval's exact level."""
    code, err, out = _scene(
        tmp_path, PIEZO, "numpy,c", name="amp", ranges="piezo = [0.0, 0.05]", point="B",
        backend="c",
    )  # fmt: skip
    assert code == 0, err
    # the C header names the stroke's unit, not radians alone
    assert (
        "then the actuators' strokes or forces\n *           (piezo in mm)"
        in (out / "amp.h").read_text()
    )
    scene = _import(out / "amp.py")
    assert scene.INPUTS == ("piezo",)
    strokes = [0.005, 0.02, 0.045]
    got = scene.evaluate({"piezo": np.array(strokes)})
    assert got["ok"].all()
    for k, s in enumerate(strokes):
        want = _eval(PIEZO, "exact", piezo=s)["points"]["B"]
        err = math.dist(got["points"]["B"]["deviation"][:, k], want["deviation"])
        assert err <= 0.05 * want["norm"], (s, err)


def test_a_scene_with_a_force_actuator(tmp_path):
    """The cantilever's tip within 1 % against `equilibrium` over forces 0 to 3 N (α up to 1.8):
    the force actuator takes the `loaded` variant; a kinematic reference, a missing force range
    and a [fix] of the hinge the piezo's stroke sets are refused naming the entry."""
    mech = tmp_path / "cantilever_force.toml"
    mech.write_text(CANTILEVER)
    keys = {"name": "tip", "reference": "equilibrium", "point": "T", "tol": "0.01"}
    code, err, out = _scene(tmp_path, mech, ranges="push = [0.0, 3.0]", **keys)
    assert code == 0, err
    scene = _import(out / "tip.py")
    assert scene.INPUTS == ("push",) and scene.VARIANTS["T"].startswith("loaded")
    forces = [0.7, 2.9]
    got = scene.evaluate({"push": np.array(forces)})
    assert got["ok"].all()
    for k, f in enumerate(forces):
        want = _eval(mech, "equilibrium", push=f)["points"]["T"]
        err = math.dist(got["points"]["T"]["deviation"][:, k], want["deviation"])
        assert err <= 0.01 * want["norm"], (f, err)
    code, err, _ = _scene(
        tmp_path, mech, ranges="push = [0.0, 3.0]", **(keys | {"reference": "exact"})
    )
    assert code == 2 and "the force actuator push drives the physical levels alone" in err, err
    code, err, _ = _scene(tmp_path, mech, ranges="", **keys)
    assert code == 2 and "the force actuator push needs a range" in err, err
    code, err, _ = _scene(tmp_path, PIEZO, name="amp", ranges="", point="B", fix="[fix]\nRA0 = 0.0")
    assert code == 2 and "the actuator 'piezo' sets (its surrogate)" in err, err


def test_the_report_labels_strokes_and_forces_in_their_units(tmp_path):
    """A stroke in the file's length unit, a force in N, a hinge in rad: in the deviation
    plot's axis and the report's text of the swept range."""
    import symkin

    piezo = symkin.load(PIEZO)
    assert input_axis(piezo, "piezo", "piezo") == "stroke of piezo (mm)"
    assert input_unit(piezo, "piezo", tex=True) == r"$\mathrm{mm}$"
    mech = tmp_path / "cantilever_force.toml"
    mech.write_text(CANTILEVER)
    cantilever = symkin.load(mech)
    assert input_axis(cantilever, "push", "push") == "force of push (N)"
    four_bar = symkin.load(EXAMPLES / "four_bar.toml")
    assert input_axis(four_bar, "A0", "A0") == "input θ of A0 (rad)"
    run = symkin_cli("derive", str(mech), "--emit", "latex", "-o", str(tmp_path / "tex"))
    assert run.returncode == 0, run.stderr
    tex = (tmp_path / "tex" / "cantilever_force.tex").read_text()
    assert "of the force of push from" in tex and "~N," in tex


@pytest.mark.parametrize("example", ["piezo_amplifier"])
def test_the_committed_report_gives_the_stroke_in_mm(example):
    """generated/'s report of the piezo amplifier: its equilibrium tables at strokes in mm, not
    rad (the caption used to say `piezo = 0.02 rad`)."""
    tex = (EXAMPLES.parent / "generated" / example / f"{example}.tex").read_text()
    captions = [x for x in tex.splitlines() if "The level \\emph{equilibrium} at" in x]
    assert captions and all("$\\mathrm{mm}$" in x and "~rad" not in x for x in captions)
