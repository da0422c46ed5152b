"""The generated evaluators of a structure (docs/levels.md, "Structures"; docs/generated-code.md):
they hold the `loaded` level alone and take no inputs, a batch coming from the parameters'
arrays; a kinematic level is refused at run time (numpy: ValueError, C: the bad-argument code
3); `tolerance` and `sweep` run on them. References written here: the leaf parallelogram's
linear frame (two Timoshenko legs that stretch, the stage free to turn) and its textbook
F/(24EI/L^3) with y ∝ t^-3, the three-leaf hub's beam stiffness."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from evaluators import backends_with, require
from mechanisms import ZOO

import symkin
from symkin.cli.commands import main
from symkin.core import levels

GENERATED = backends_with(generated=True, levels="loaded")

# -- the three-leaf flexure with a point at its hub's centre ------------------------------------
HUB = ZOO / "three_leaf.toml"
CENTRE = '\n[[point]]\nname = "O"\nlink = "hub"\nat = [0.0, 0.0]\n'


def hub_stiffness() -> float:
    """Three Timoshenko plates (L = 20 mm, hub radius r = 5 mm, t = 0.2 mm, b = 5 mm, nu = 0)
    clamped in the frame and the hub, each seen from the hub's centre: EI (12 r^2 + 12 r L +
    (4 + Phi) L^2) / (L^3 (1 + Phi))."""
    length, r, modulus, b, t = 0.020, 0.005, 210e9, 5e-3, 0.2e-3
    ei, kga = modulus * b * t**3 / 12, 5 / 6 * modulus / 2 * b * t
    phi = 12 * ei / (kga * length**2)
    return 3 * ei * (12 * r**2 + 12 * r * length + (4 + phi) * length**2) / (length**3 * (1 + phi))


@pytest.fixture(scope="module")
def hub():
    return symkin.loads(HUB.read_text() + CENTRE, "three_leaf.toml")


@pytest.mark.parametrize("backend", GENERATED)
def test_a_structures_evaluator_takes_no_inputs(backend, hub):
    """evaluate({}) at `loaded`: the hub turns by M/k, its rim point Q by r sin(turn), its
    centre O stays put (the truncation estimate takes it); the same through symkin.evaluate."""
    require(backend)
    ev = symkin.compile(hub, backend=backend)
    assert ev.inputs == () and ev.levels == ("loaded",)
    moment = 1e-6
    res = ev.evaluate({}, "loaded", {"M": moment})
    assert bool(res["ok"])
    turn = moment / hub_stiffness()
    q, o = res["points"]["Q"]["deviation"], res["points"]["O"]["deviation"]
    assert q[1] == pytest.approx(0.005 * math.sin(turn), rel=1e-6)
    assert abs(q[0]) <= 1e-6 * q[1] and math.hypot(*o) <= 1e-12 * q[1]
    got = symkin.evaluate(
        symkin.analyze(hub), {}, level="loaded", params={"M": str(moment)}, backend=backend
    )
    assert got.inputs == {} and got.links["hub"].deviation == pytest.approx(turn, rel=1e-6)
    assert math.hypot(*got.points["O"].deviation) <= 1e-12 * q[1]


def test_the_numpy_batch_comes_from_the_parameters(hub):
    """Arrays of parameter values broadcast into the batch (a (3, 2) grid of moments and radii
    here), each configuration as alone; cut into blocks as inputs are (the block size lowered
    to 2 to cut this one)."""
    ev = symkin.compile(hub, backend="numpy")
    moments = np.array([1e-6, -2e-6, 3e-6])[:, None]
    radii = np.array([0.005, 0.006])
    full = ev.evaluate({}, "loaded", {"M": moments, "r": radii}, report=False)
    assert full["ok"].shape == (3, 2) and full["ok"].all()
    for i in range(3):
        for j in range(2):
            one = ev.evaluate(
                {}, "loaded", {"M": float(moments[i, 0]), "r": float(radii[j])}, report=False
            )
            for name in ("Q", "O"):
                got = full["points"][name]["deviation"][:, i, j]
                assert np.allclose(got, one["points"][name]["deviation"], rtol=1e-12, atol=1e-24)
    # the rim point Q = (r, 0) turns with the hub: linear in M at this size
    dy = full["points"]["Q"]["deviation"][1]
    assert dy[1, 0] / dy[0, 0] == pytest.approx(-2.0, rel=1e-5)
    ev.module._CHUNK = 2
    cut = ev.evaluate({}, "loaded", {"M": moments, "r": radii}, report=False)
    for name in ("Q", "O"):
        assert np.array_equal(cut["points"][name]["deviation"], full["points"][name]["deviation"])


@pytest.mark.parametrize("backend", GENERATED)
def test_a_kinematic_level_is_refused_at_run_time(backend, hub):
    require(backend)
    ev = symkin.compile(hub, backend=backend)
    with pytest.raises(ValueError, match="level must be one of"):
        ev.evaluate({}, "exact")
    if backend == "c":  # the C entry point itself: the bad-argument code
        status, _ = ev.library.evaluate_rows(
            np.zeros((2, 0)), None, levels.get("exact").code, False
        )[:2]
        assert list(status) == [3, 3]
        status, out = ev.library.evaluate_rows(
            np.zeros((1, 0)), None, levels.get("loaded").code, False
        )[:2]
        assert list(status) == [0] and np.isfinite(out).all()


# -- tolerance and sweep on a leaf parallelogram: its stage under a load, by plate thickness ----
LEAF = """format = 1
name = "leaf_thickness"
[parameters]
L = 0.040
w = 0.025
F = 0.02
t = 0.5e-3
[defaults]
length = "L"
E = 210e9
nu = 0
thickness = "t"
width = 10e-3
[[link]]
name = "frame"
[[link]]
name = "stage"
[[hinge]]
name = "A"
links = ["frame", "stage"]
at = [0.0, "L/2"]
plate_angle = "pi/2"
[[hinge]]
name = "B"
links = ["frame", "stage"]
at = ["w", "L/2"]
plate_angle = "pi/2"
[[point]]
name = "P"
link = "stage"
at = ["w/2", "L"]
[[load]]
point = "P"
force = ["F", 0.0]
"""
L_LEG, E, WIDTH, SPACING, FORCE, THICK = 0.040, 210e9, 10e-3, 0.025, 0.02, 0.5e-3


def stage_x(t: float) -> float:
    """The stage's transverse displacement under FORCE, linear frame: two Timoshenko legs (nu =
    0, k = 5/6) along y at x = 0 and w, clamped in the frame and the stage, stretching by EA/L;
    the stage (u, v, phi) free to turn."""
    ei, ea, kga = E * WIDTH * t**3 / 12, E * WIDTH * t, 5 / 6 * E / 2 * WIDTH * t
    phi = 12 * ei / (kga * L_LEG**2)
    bend = (
        ei
        / (L_LEG**3 * (1 + phi))
        * np.array([[12, -6 * L_LEG], [-6 * L_LEG, (4 + phi) * L_LEG**2]])
    )
    stiffness = np.zeros((3, 3))
    for x in (0.0, SPACING):
        across = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])
        along = np.array([0.0, 1.0, x - SPACING / 2])
        stiffness += across.T @ bend @ across + ea / L_LEG * np.outer(along, along)
    return float(np.linalg.solve(stiffness, [FORCE, 0.0, 0.0])[0])


@pytest.fixture(scope="module")
def leaf(tmp_path_factory):
    path = tmp_path_factory.mktemp("leaf") / "leaf_thickness.toml"
    path.write_text(LEAF)
    return path


def run(args, capsys):
    code = main(args)
    return (code, *capsys.readouterr())


@pytest.mark.parametrize("backend", GENERATED)
def test_tolerance_of_a_structure_by_its_plate_thickness(backend, leaf, capsys):
    """d(dx)/dt of the stage: the linear frame's by central differences (written here), and the
    textbook's -3 y/t (y = F/(24 EI/L^3) ∝ t^-3) to the shear's and the stretch's shares."""
    require(backend)
    args = ["tolerance", str(leaf), "--level", "loaded", "--vary", "t=±5%", "--json"]
    code, out, err = run([*args, "--backend", backend], capsys)
    assert code == 0 and err == ""
    doc = json.loads(out)
    assert doc["configurations"] == 1 and doc["inputs"] == {} and doc["failed"] == 0
    dx = doc["points"]["P"]["components"]["dx"]
    h = 1e-4 * THICK
    frame = (stage_x(THICK + h) - stage_x(THICK - h)) / (2 * h)
    assert dx["rates"]["t"] == pytest.approx(frame, rel=1e-5)
    y = stage_x(THICK)
    assert dx["nominal"] == pytest.approx(y, rel=1e-6)
    assert dx["rates"]["t"] == pytest.approx(-3 * y / THICK, rel=2e-3)
    assert dx["worst_case"] == pytest.approx(0.05 * THICK * abs(frame), rel=1e-5)
    code, out, _ = run(args[:-1], capsys)
    assert code == 0 and "at its one configuration (a structure: no inputs)" in out


def test_sweep_of_a_structure_by_its_plate_thickness(leaf, capsys):
    """t uniform within ±5 %: every sample's displacement lies between the frame's at 1.05 t
    and at 0.95 t, and the mean is the frame's mean over the uniform t (Simpson's rule here)
    to its Monte Carlo error (std/sqrt(n) about 0.5 %)."""
    samples = 300
    code, out, err = run(
        [
            "sweep",
            str(leaf),
            "--level",
            "loaded",
            "--vary",
            "t=±5%",
            "--samples",
            str(samples),
            "--scheduler",
            "sync",
            "--json",
        ],
        capsys,
    )
    assert code == 0 and err == ""
    doc = json.loads(out)
    assert doc["failed"] == 0 and doc["configurations"] == 1
    stats = doc["points"]["P"]
    assert stats["nominal"] == pytest.approx(stage_x(THICK), rel=1e-6)
    assert stats["max"] <= stage_x(0.95 * THICK) * (1 + 1e-6)
    assert stats["max"] >= stage_x(0.95 * THICK) * (1 - 0.03)
    ts = np.linspace(0.95 * THICK, 1.05 * THICK, 101)
    ys = np.array([stage_x(t) for t in ts])
    weights = np.ones(101)
    weights[1:-1:2], weights[2:-1:2] = 4, 2
    mean = float(weights @ ys) / (3 * 100)
    assert stats["mean"] == pytest.approx(mean, rel=0.025)


# -- what still refuses ---------------------------------------------------------------------
def test_a_kinematic_level_of_a_structure_is_refused_before_deriving(leaf, capsys):
    for args in (
        ["tolerance", str(leaf), "--level", "exact", "--vary", "t=±5%"],
        ["sweep", str(leaf), "--level", "paper", "--vary", "t=±5%"],
    ):
        code, out, err = run(args, capsys)
        assert code == 2 and out == "", args
        assert "structure" in err and "has nothing to evaluate" in err, args
        assert "fix: ask for --level loaded" in err, args


@pytest.mark.parametrize("backend", GENERATED)
def test_a_structures_force_actuators_are_refused_by_the_generated_code(backend, capsys):
    """Their forces would be the evaluators' inputs: not generated yet (exit 2, naming the
    actuator and the [[load]] way)."""
    path = str(ZOO / "leaf_parallelogram.toml")
    code, out, err = run(
        ["eval", path, "--level", "loaded", "--backend", backend, "--input", "push=0"], capsys
    )
    assert code == 2 and out == ""
    assert "structure's force actuators" in err and "'push'" in err
    assert "fix: load the structure by a [[load]] whose force is a parameter" in err
