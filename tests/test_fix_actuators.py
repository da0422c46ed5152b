"""Fixed inputs beside actuators (docs/cli.md `--fix`,
docs/scene.md "Actuators"): `derive --points P --fix H=V` and a scene's [fix] on a file with an
actuator and an input hinge. The generated runtimes measure a stroke from the point of action as
fabricated (the actuator's `at`), not from the pose at zero inputs, which the folded input moves.
Checked against `symkin eval --backend sympy` at the same fixed angle (mpmath; its actuators are
checked against independent references in tests/test_actuators.py and
tests/test_loaded_actuators.py), numpy and C, at `exact` and `loaded`. And a scene evaluator
beyond the rigid reach (docs/scene.md): its return code 4, as <name>_evaluate's."""

from __future__ import annotations

import ctypes
import importlib.util
import json
import math
import os
import subprocess
from pathlib import Path

import numpy as np
import pytest
from cli_runs import symkin_cli
from conftest import ROOT
from evaluators import require_compiler
from test_beyond_reach import AGAINST_BD, ALPHA, CANTILEVER, EI, FORCE, L, bisshopp_drucker

from symkin.core import levels

FIVE_BAR = ROOT / "tests" / "mechanisms" / "five_bar_piezo.toml"
FIXED = 0.03  # O1 held (rad)
#: the generated evaluators against eval's mpmath: of |dR| (deviation), of the mechanism's size
#: (positions). Measured: 1.2e-11 (exact, its Newton's stopping rule), 8e-14 (loaded).
AGREEMENT = 1e-9
SIZE = 0.05


def _force_file(tmp_path: Path) -> Path:
    """five_bar_piezo.toml with its actuator driven by a force (N) instead of a stroke."""
    text = FIVE_BAR.read_text()
    assert text.count('drive = "stroke"') == 1
    path = tmp_path / "five_bar_force.toml"
    path.write_text(text.replace('drive = "stroke"', 'drive = "force"'))
    return path


def _import(path: Path):
    spec = importlib.util.spec_from_file_location(f"fixact_{path.stem}", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _library(folder: Path, name: str) -> ctypes.CDLL:
    require_compiler()
    lib = folder / f"lib{name}.so"
    sources = sorted(str(p) for p in folder.glob("*.c"))
    cc = os.environ.get("CC", "cc")
    argv = [cc, "-std=c99", "-O2", "-shared", "-fPIC", "-Wall", "-Werror", *sources]
    subprocess.run([*argv, "-o", str(lib), "-lm"], check=True, capture_output=True)
    return ctypes.CDLL(str(lib))


DOUBLES = ctypes.POINTER(ctypes.c_double)


def _c_evaluate(lib, name: str, x: list[float], level: str | None) -> tuple[int, np.ndarray]:
    """(status, out) of <name>_evaluate (a scene's: no level) at the public inputs x."""
    out = np.full(6, np.nan)
    inputs = np.array(x, dtype=float)
    f = getattr(lib, f"{name}_evaluate")
    if level is None:
        f.argtypes = [DOUBLES, DOUBLES, DOUBLES]
        status = f(inputs.ctypes.data_as(DOUBLES), None, out.ctypes.data_as(DOUBLES))
    else:
        f.argtypes = [DOUBLES, DOUBLES, ctypes.c_int, DOUBLES]
        code = levels.get(level).code
        status = f(inputs.ctypes.data_as(DOUBLES), None, code, out.ctypes.data_as(DOUBLES))
    return status, out


def _eval(path: Path, level: str, point: str, **inputs: float) -> dict:
    argv = ["eval", str(path), "--level", level, "--backend", "sympy", "--json"]
    for name, value in inputs.items():
        argv += ["--input", f"{name}={value!r}"]
    run = symkin_cli(*argv)
    assert run.returncode == 0, run.stderr
    return json.loads(run.stdout)["points"][point]


def _agrees(rigid, compliant, deviation, want: dict, what, slack: float = 0.0) -> None:
    """The generated point against eval's: positions to AGREEMENT of the size, the deviation
    to AGREEMENT of |dR| (or `slack`, file unit, where larger: a scene's tolerance)."""
    assert math.dist(rigid, want["rigid"]) <= AGREEMENT * SIZE, (what, rigid, want["rigid"])
    assert math.dist(compliant, want["compliant"]) <= AGREEMENT * SIZE, what
    err = math.dist(deviation, want["deviation"])
    assert err <= max(AGREEMENT * want["norm"], slack), (what, err / want["norm"])


@pytest.mark.parametrize("drive", ["stroke", "force"])
def test_derive_fix_beside_an_actuator(tmp_path, drive):
    """`derive --points T --fix O1=0.03` of the five-bar driven by O1 and an actuator on its
    crank c2: the evaluators take the actuator alone, and give eval's answer with O1 = 0.03 at
    every level they have (a stroke: exact and loaded; a force: loaded), numpy and C. Measured
    from the pose at zero inputs (O1 at 0.03, the point of action 1.6e-4 m from its `at`), T's
    rigid position at a stroke of 1e-5 m came out 3.0e-4 m off."""
    path = FIVE_BAR if drive == "stroke" else _force_file(tmp_path)
    out = tmp_path / "out"
    argv = ["derive", str(path), "--points", "T", "--fix", f"O1={FIXED!r}", "--emit", "numpy,c"]
    run = symkin_cli(*argv, "-o", str(out))
    assert run.returncode == 0, run.stderr
    module = _import(out / "five_bar_piezo.py")  # the file's name
    assert module.INPUTS == ("piezo",) and module.POINTS == ("T",)
    assert "O1 = 3/100 rad" in (out / "five_bar_piezo.h").read_text()
    lib = _library(out, "five_bar_piezo")
    values = [1e-5, -2e-5] if drive == "stroke" else [0.5, -1.0]  # m; N
    for level in ("exact", "loaded") if drive == "stroke" else ("loaded",):
        got = module.evaluate({"piezo": np.array(values)}, level)
        assert got["ok"].all()
        for k, v in enumerate(values):
            want = _eval(path, level, "T", O1=FIXED, piezo=v)
            p = got["points"]["T"]
            _agrees(p["rigid"][:, k], p["compliant"][:, k], p["deviation"][:, k], want, level)
            status, c = _c_evaluate(lib, "five_bar_piezo", [v], level)
            assert status == 0, (level, v)
            _agrees(c[0:2], c[2:4], c[4:6], want, ("C", level, v))


def test_fix_refuses_an_actuator_and_its_surrogate(tmp_path):
    """Only input hinges are held: the actuator itself and the hinge its stroke sets exit 2."""
    for name, words in (("piezo", "is an actuator"), ("B", "surrogate")):
        run = symkin_cli("derive", str(FIVE_BAR), "--fix", f"{name}=0.01", "-o", str(tmp_path))
        assert run.returncode == 2 and words in run.stderr and "O1" in run.stderr, run.stderr


SCENE = """format = 1
name = "{name}"
reference = "{reference}"
samples = 5
backend = "c"

[fix]
O1 = {fixed!r}

[ranges]
piezo = {span}

[[point]]
name = "T"
{tolerance}
"""


@pytest.mark.parametrize("drive", ["stroke", "force"])
def test_a_scene_fixes_an_input_beside_an_actuator(tmp_path, drive):
    """A scene with [fix] O1 = 0.03 beside the actuator: a stroke's point at 1e-15 m against
    `exact` takes an `exact` variant (a Taylor plate model may meet it), a force's within 1 % of
    `equilibrium` the `loaded` one; the scene evaluator (numpy and C) gives eval's answer at
    that level with O1 = 0.03, at values between the samples: positions to 1e-9 of the size,
    the deviation to 1e-9 of |dR| (the stroke's: or the scene's 1e-15 m, about 1.5e-9 of |dR|,
    what its variant's plate model may differ by)."""
    if drive == "stroke":
        path, level, span, values = FIVE_BAR, "exact", "[-2e-5, 2e-5]", [1.3e-5, -0.7e-5]
        keys, slack = {"reference": "exact", "tolerance": "tolerance = 1e-15"}, 1e-15
    else:
        path, level, span, values = _force_file(tmp_path), "loaded", "[-1.0, 1.0]", [0.55, -0.35]
        keys, slack = {"reference": "equilibrium", "tolerance": "relative_tolerance = 0.01"}, 0.0
    scene = tmp_path / "scene.toml"
    scene.write_text(SCENE.format(name="held", fixed=FIXED, span=span, **keys))
    out = tmp_path / "out"
    run = symkin_cli("derive", str(path), "--scene", str(scene), "-o", str(out))
    assert run.returncode == 0, run.stderr
    module = _import(out / "held.py")
    assert module.INPUTS == ("piezo",) and module.FIXED == {"O1": FIXED}
    assert module.VARIANTS["T"].split("/")[0] == level
    got = module.evaluate({"piezo": np.array(values)})
    assert got["ok"].all()
    lib = _library(out, "held")
    for k, v in enumerate(values):
        want = _eval(path, level, "T", O1=FIXED, piezo=v)
        p = got["points"]["T"]
        _agrees(p["rigid"][:, k], p["compliant"][:, k], p["deviation"][:, k], want, v, slack)
        status, c = _c_evaluate(lib, "held", [v], None)
        assert status == 0, v
        _agrees(c[0:2], c[2:4], c[4:6], want, ("C", v), slack)


def test_a_scene_reports_beyond_the_rigid_reach(tmp_path):
    """The force-driven cantilever of tests/test_beyond_reach.py in a scene (its tip within 1 %
    of `equilibrium` over 0 to 3 N: the `loaded` variant), evaluated within reach (α = 2) and
    beyond it (α = 10, the tip at 0.81 l where the rigid pin reaches l/2): the C scene evaluator
    returns 0 and 4, beyond the reach the compliant tip filled where Bisshopp and Drucker put
    it (1e-3 of l, as the evaluator's own test) and the rigid tip and deviation NaN, as
    <name>_evaluate; its batch counts no failure. The numpy scene: ok True both, "reference"
    True and False, the same positions."""
    path = tmp_path / "cantilever_force.toml"
    path.write_text(CANTILEVER)
    scene = tmp_path / "scene.toml"
    scene.write_text(
        'format = 1\nname = "tip"\nreference = "equilibrium"\nsamples = 5\nbackend = "c"\n\n'
        '[ranges]\npush = [0.0, 3.0]\n\n[[point]]\nname = "T"\nrelative_tolerance = 0.01\n'
    )
    out = tmp_path / "out"
    run = symkin_cli("derive", str(path), "--scene", str(scene), "-o", str(out))
    assert run.returncode == 0, run.stderr
    module = _import(out / "tip.py")
    assert module.VARIANTS["T"].startswith("loaded")
    forces = np.array([2 * EI / L**2, FORCE])
    got = module.evaluate({"push": forces})
    assert got["ok"].tolist() == [True, True]
    assert got["reference"].tolist() == [True, False]
    tip = got["points"]["T"]
    assert np.isfinite(tip["deviation"][:, 0]).all()
    assert np.isnan(tip["deviation"][:, 1]).all() and np.isnan(tip["rigid"][:, 1]).all()
    _, x, y = bisshopp_drucker(ALPHA)
    assert math.dist(tip["compliant"][:, 1], (x * L, y * L)) <= AGAINST_BD["loaded"] * L

    lib = _library(out, "tip")
    rows = np.zeros((2, 6))
    status = np.zeros(2, dtype=np.int32)
    batch = lib.tip_evaluate_batch
    batch.argtypes = [ctypes.c_int, DOUBLES, DOUBLES, DOUBLES, ctypes.POINTER(ctypes.c_int)]
    failed = batch(
        2,
        forces.ctypes.data_as(DOUBLES),
        None,
        rows.ctypes.data_as(DOUBLES),
        status.ctypes.data_as(ctypes.POINTER(ctypes.c_int)),
    )
    assert failed == 0 and status.tolist() == [0, 4]
    for k, f in enumerate(forces):
        code, one = _c_evaluate(lib, "tip", [f], None)
        assert code == status[k]
        assert np.array_equal(one, rows[k], equal_nan=True)
    assert np.isnan(rows[1, [0, 1, 4, 5]]).all()
    assert math.dist(rows[1, 2:4], (x * L, y * L)) <= AGAINST_BD["loaded"] * L
    assert rows[1, 2:4] == pytest.approx(tip["compliant"][:, 1], rel=1e-12)
    assert rows[0, 4:6] == pytest.approx(tip["deviation"][:, 0], rel=1e-10)
