"""Scene files (docs/scene.md): each point by the cheapest variant meeting its tolerance over its
range, one scene evaluator over them (numpy and C), fixed inputs folded in, bad scenes refused.

Every deviation is checked against the independent 40-digit solver (tests/reference_solver.py),
not against symkin's own measurement: a point's error at inputs the measurement never sampled
must stay within the tolerance the scene asked for.
"""

from __future__ import annotations

import ctypes
import importlib.util
import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import sympy as sp
from conftest import EXAMPLES, once_per_run
from evaluators import require_compiler
from reference_solver import Reference

import symkin
from symkin.core.errors import InputError
from symkin.studies.scene import derive as derive_scene

NINE_BAR = EXAMPLES / "nine_bar_platform.toml"
FOUR_BAR = EXAMPLES / "four_bar.toml"

# Two points the nine-bar file does not have: P8 on b8 (loop 2 only) held to an absolute
# tolerance, P5 on b5 (loop 1) to a loose relative one; K held at pi/60.
SCENE = """
format = 1
name = "stage"
reference = "exact"

[ranges]
O = [-0.1, 0.1]
A = [-0.1, 0.1]
B = ["-pi/30", "pi/30"]

[fix]
K = "pi/60"

[[point]]
name = "P8"
link = "b8"
at = [0.1, 0.01]
tolerance = 1e-12

[[point]]
name = "P5"
link = "b5"
at = [0.18, 0.075]
relative_tolerance = 0.05
ranges = { O = [-0.05, 0.05] }
"""
TOLERANCE = {"P8": (1e-12, False), "P5": (0.05, True)}
AT = {"P8": ("b8", (0.1, 0.01)), "P5": ("b5", (0.18, 0.075))}
K_EXACT = sp.pi / 60
K = float(sp.N(K_EXACT, 30))  # correctly rounded, as the generated code holds it


def _with_points(path: Path) -> symkin.Mechanism:
    """The nine-bar with the scene's points written into the file (for the reference solver)."""
    extra = "".join(
        f'\n[[point]]\nname = "{p}"\nlink = "{link}"\nat = [{x}, {y}]\n'
        for p, (link, (x, y)) in AT.items()
    )
    return symkin.loads(path.read_text() + extra, "nine_bar_points.toml")


def _import(path: Path):
    spec = importlib.util.spec_from_file_location(f"scene_test_{path.stem}", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _derive_stage(folder: Path) -> None:
    """The stage scene derived into folder/out (C and numpy)."""
    scene = folder / "stage.toml"
    scene.write_text(SCENE)
    derive_scene(NINE_BAR, scene, folder / "out", emit=["c", "numpy"])


@pytest.fixture(scope="module")
def derived(tmp_path_factory) -> Path:
    # derived once for the tests on every xdist worker (conftest.once_per_run)
    return once_per_run(tmp_path_factory, "scene-stage", _derive_stage) / "out"


def _samples(n: int, seed: int = 7) -> list[dict[str, float]]:
    rng = np.random.default_rng(seed)
    return [
        {
            "O": rng.uniform(-0.05, 0.05),
            "A": rng.uniform(-0.1, 0.1),
            "B": rng.uniform(-math.pi / 30, math.pi / 30),
        }
        for _ in range(n)
    ]


def test_every_point_meets_its_tolerance_against_the_independent_solver(derived):
    out = derived
    scene = _import(out / "stage.py")
    assert scene.INPUTS == ("O", "A", "B") and scene.FIXED == {"K": K}
    ref = Reference(_with_points(NINE_BAR))
    samples = _samples(6)
    got = scene.evaluate({h: np.array([s[h] for s in samples]) for h in scene.INPUTS})
    assert got["ok"].all()
    for j, s in enumerate(samples):
        want = ref.deviation({**s, "K": K_EXACT})["points"]
        for p, (tol, relative) in TOLERANCE.items():
            w = np.array([float(v) for v in want[p]["deviation"]])
            err = np.hypot(*(got["points"][p]["deviation"][:, j] - w))
            assert err <= tol * (np.hypot(*w) if relative else 1.0), (p, s, err)
    # the loose point really is computed more cheaply: not by the tight point's variant
    assert scene.VARIANTS["P8"] != scene.VARIANTS["P5"]


def test_scene_evaluator_in_c_agrees_with_numpy(derived):
    require_compiler()
    out = derived
    scene = _import(out / "stage.py")
    lib_path = out / "libstage.so"
    sources = sorted(str(p) for p in out.glob("*.c"))
    cc = os.environ.get("CC", "cc")
    subprocess.run(
        [
            cc,
            "-std=c99",
            "-O2",
            "-shared",
            "-fPIC",
            "-Wall",
            "-Werror",
            *sources,
            "-o",
            str(lib_path),
            "-lm",
        ],
        check=True,
        capture_output=True,
    )
    lib = ctypes.CDLL(str(lib_path))
    dbl = ctypes.POINTER(ctypes.c_double)
    lib.stage_evaluate.argtypes = [dbl, dbl, dbl]
    lib.stage_evaluate_batch.argtypes = [ctypes.c_int, dbl, dbl, dbl, ctypes.POINTER(ctypes.c_int)]
    names = [ctypes.c_char_p.in_dll(lib, "stage_input_names").value]  # first entry
    assert names == [b"O"]
    samples = _samples(5, seed=3)
    x = np.array([[s[h] for h in scene.INPUTS] for s in samples])
    out_c = np.zeros((len(samples), 6 * len(scene.POINTS)))
    status = np.zeros(len(samples), dtype=np.int32)
    failed = lib.stage_evaluate_batch(
        len(samples),
        x.ctypes.data_as(dbl),
        None,
        out_c.ctypes.data_as(dbl),
        status.ctypes.data_as(ctypes.POINTER(ctypes.c_int)),
    )
    assert failed == 0 and not status.any()
    got = scene.evaluate({h: x[:, i] for i, h in enumerate(scene.INPUTS)})
    for i, p in enumerate(scene.POINTS):
        for k, key in enumerate(("rigid", "compliant", "deviation")):
            c = out_c[:, 6 * i + 2 * k : 6 * i + 2 * k + 2].T
            n = got["points"][p][key]
            assert np.abs(c - n).max() <= 1e-13 * np.abs(n).max(), (p, key)
    # a parameter given explicitly reaches every evaluator
    params = np.array([1.2e-3])
    one = np.zeros(6 * len(scene.POINTS))
    assert (
        lib.stage_evaluate(
            x[0].ctypes.data_as(dbl), params.ctypes.data_as(dbl), one.ctypes.data_as(dbl)
        )
        == 0
    )
    want = scene.evaluate({h: x[0, i] for i, h in enumerate(scene.INPUTS)}, {"l": 1.2e-3})
    assert np.allclose(one[4:6], want["points"]["P8"]["deviation"], rtol=1e-13, atol=0)
    # bad argument: NaN everywhere, code 3
    assert lib.stage_evaluate(None, None, one.ctypes.data_as(dbl)) == 3
    assert np.isnan(one).all()


def test_numpy_scene_checks_its_inputs(derived):
    out = derived
    scene = _import(out / "stage.py")
    with pytest.raises(ValueError, match="missing"):
        scene.evaluate({"O": 0.0, "A": 0.0})
    with pytest.raises(ValueError, match="unknown"):
        scene.evaluate({"O": 0.0, "A": 0.0, "B": 0.0, "K": 0.1})
    with pytest.raises(ValueError, match="unknown parameters"):
        scene.evaluate({"O": 0.0, "A": 0.0, "B": 0.0}, {"L": 1.0})
    # shapes broadcast across evaluators that take different inputs
    res = scene.evaluate({"O": np.zeros((3, 1)), "A": np.zeros(4), "B": 0.01})
    assert res["points"]["P8"]["deviation"].shape == (2, 3, 4)
    assert res["points"]["P5"]["deviation"].shape == (2, 3, 4)


def _scene_error(text: str, mech: symkin.Mechanism | None = None) -> InputError:
    from symkin.studies import scene

    with pytest.raises(InputError) as exc:
        scene.loads(text, mech or symkin.load(FOUR_BAR), "bad.toml")
    return exc.value


def test_the_equilibrium_reference_needs_stiffness():
    import mechanisms as M

    err = _scene_error(
        'format = 1\n[[point]]\nname = "C"\ntolerance = 1e-6\nreference = "equilibrium"\n',
        symkin.loads(M.without_stiffness(FOUR_BAR), "plain.toml"),
    )
    assert "stiffness" in err.message and err.entry == "[[point]] #1 'C'"


@pytest.mark.parametrize(
    "text, message, entry",
    [
        (
            'format = 1\n[[point]]\nname = "C"\ntolerance = 1e-6\nspeed = 1\n',
            "unknown key 'speed'",
            "[[point]] #1",
        ),
        (
            'format = 1\n[[point]]\nname = "Q"\ntolerance = 1e-6\n',
            "no point 'Q'",
            "[[point]] #1 'Q'",
        ),
        (
            'format = 1\n[[point]]\nname = "C"\ntolerance = 1e-6\nrelative_tolerance = 0.1\n',
            "exactly one",
            "[[point]] #1 'C'",
        ),
        ('format = 1\n[[point]]\nname = "C"\ntolerance = -1\n', "positive", "[[point]] #1 'C'"),
        (
            'format = 1\n[[point]]\nname = "C"\ntolerance = 1e-6\nprecision = "float32"\n',
            "numpy only",
            "[[point]] #1 'C'",
        ),
        (
            'format = 1\n[fix]\nA0 = 0.1\n[[point]]\nname = "C"\ntolerance = 1e-6\n',
            "every input is fixed",
            "[fix]",
        ),
        (
            'format = 1\n[fix]\nB = 0.1\n[[point]]\nname = "C"\ntolerance = 1e-6\n',
            "not an input",
            "[fix] 'B'",
        ),
        (
            'format = 1\n[ranges]\nA0 = [0.2, 0.1]\n[[point]]\nname = "C"\ntolerance = 1e-6\n',
            "empty range",
            "[ranges] 'A0'",
        ),
        (
            'format = 1\n[ranges]\nA0 = [0, 4]\n[[point]]\nname = "C"\ntolerance = 1e-6\n',
            "[-pi, pi]",
            "[ranges] 'A0'",
        ),
        (
            'format = 1\n[ranges]\nA0 = ["__import__(\'os\')", 1]\n[[point]]\nname = "C"\n'
            "tolerance = 1e-6\n",
            "",
            "[ranges] 'A0'",
        ),
        ('format = 1\nname = "sys"\n[[point]]\nname = "C"\ntolerance = 1e-6\n', "keyword", "name"),
        ("format = 1\n", "no point", "[[point]]"),
        ('format = 2\n[[point]]\nname = "C"\ntolerance = 1e-6\n', "format", "format"),
        (
            'format = 1\n[[point]]\nname = "C"\nlink = "coupler"\nat = [0.1, 0.2]\n'
            "tolerance = 1e-6\n",
            "already has a point",
            "[[point]] 'C'",
        ),
        (
            'format = 1\n[[point]]\nname = "N"\nlink = "nowhere"\nat = [0.1, 0.2]\n'
            "tolerance = 1e-6\n",
            "unknown link",
            "[[point]] #1 'N'",
        ),
        ("format = 1\n[[point\n", "TOML", None),
    ],
)
def test_bad_scenes_name_the_entry_and_the_fix(text, message, entry):
    err = _scene_error(text)
    assert err.file == "bad.toml" and message in err.message and err.hint
    if entry is not None:
        assert err.entry == entry


def test_a_tolerance_no_variant_meets_exits_2_naming_the_point(tmp_path):
    scene = tmp_path / "tight.toml"
    scene.write_text('format = 1\n[[point]]\nname = "C"\ntolerance = 1e-40\n')
    out = tmp_path / "out"
    run = subprocess.run(
        [
            sys.executable,
            "-m",
            "symkin",
            "derive",
            str(FOUR_BAR),
            "--scene",
            str(scene),
            "-o",
            str(out),
            "--quiet",
        ],
        capture_output=True,
        text=True,
    )
    assert run.returncode == 2, run.stderr
    assert "'C'" in run.stderr and "no variant meets" in run.stderr and "fix:" in run.stderr
    assert not out.exists() or not any(out.iterdir())


def test_scene_and_points_together_are_refused(tmp_path):
    scene = tmp_path / "s.toml"
    scene.write_text('format = 1\n[[point]]\nname = "C"\nrelative_tolerance = 0.1\n')
    run = subprocess.run(
        [
            sys.executable,
            "-m",
            "symkin",
            "derive",
            str(FOUR_BAR),
            "--scene",
            str(scene),
            "--points",
            "C",
            "-o",
            str(tmp_path / "o"),
        ],
        capture_output=True,
        text=True,
    )
    assert run.returncode == 2 and "--points" in run.stderr


FOUR_BAR_SCENE = """
format = 1
reference = "exact"
[[point]]
name = "C"
relative_tolerance = 0.02

[[point]]
name = "R"
link = "rocker"
at = ["0.5 * 0.09", 0.1]
tolerance = 1e-12
"""


def test_scene_output_is_deterministic_and_reports_compile(tmp_path):
    from test_latex import compile_tex

    scene = tmp_path / "s.toml"
    scene.write_text(FOUR_BAR_SCENE)
    first = derive_scene(FOUR_BAR, scene, tmp_path / "a", emit=["numpy", "latex", "c"])
    second = derive_scene(FOUR_BAR, scene, tmp_path / "b", emit=["numpy", "latex", "c"])
    assert [p.name for p in first] == [p.name for p in second]
    for a, b in zip(first, second):
        assert a.read_bytes() == b.read_bytes(), a.name
    names = {p.name for p in first}
    assert {"four_bar_scene.py", "four_bar_scene.h", "four_bar_scene.c"} <= names
    texs = sorted(n for n in names if n.endswith(".tex"))
    assert texs, names
    for tex in texs:
        text = (tmp_path / "a" / tex).read_text()
        assert "Scene s.toml" in text.replace("\\_", "_") or "s.toml" in text
        compile_tex(tmp_path / "a", tex)
    # the scene module reads its evaluators from its own folder
    module = _import(tmp_path / "a" / "four_bar_scene.py")
    ref = Reference(
        symkin.loads(
            FOUR_BAR.read_text() + '\n[[point]]\nname = "R"\nlink = "rocker"\nat = [0.045, 0.1]\n',
            "fb.toml",
        )
    )
    for q in (-0.15, 0.05, 0.2):
        got = module.evaluate({"A0": q})
        want = ref.deviation({"A0": q})["points"]
        w = np.array([float(v) for v in want["R"]["deviation"]])
        assert np.hypot(*(got["points"]["R"]["deviation"] - w)) <= 1e-12
        w = np.array([float(v) for v in want["C"]["deviation"]])
        assert np.hypot(*(got["points"]["C"]["deviation"] - w)) <= 0.02 * np.hypot(*w)
