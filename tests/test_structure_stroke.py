"""A stroke actuator driving a structure (docs/levels.md, "Structures"): the textbook
nanopositioning stage, a leaf-spring parallelogram (two single plates between the frame and the
stage, rigid mobility 0) pushed by a piezo stack. At `loaded` and `equilibrium` the stroke
prescribes its point's displacement along its line from the as-fabricated pose (a constraint, its
force the reaction); with `spring = k` the command s is the piezo's free stroke behind k, the
actual stroke s - F/k. References written here, none of them the code under test: the linear
two-leg Timoshenko frame (as tests/test_structures.py), series springs, the clamped beam's
stretch-stiffening F = k y + 1.44 EA y^3/L^3 (Awtar's (3/5) y^2/L shortening), Awtar's
parasitic coupling dy/dx = -(6/5) x/L, the three-leaf hub's translation and rotation
stiffnesses.
"""

from __future__ import annotations

import json
import os
import shutil

import numpy as np
import pytest
from mechanisms import ZOO

import symkin
from symkin.cli.commands import main

LEAF = ZOO / "leaf_parallelogram.toml"
PHYSICAL = ("loaded", "equilibrium")
L_LEG, W, E, WIDTH, THICK = 0.040, 0.025, 210e9, 10e-3, 0.5e-3
STROKE = 1e-5  # m: x/L = 2.5e-4, the nonlinear terms ~1e-7 of the stroke

needs_ccx = pytest.mark.skipif(
    shutil.which("ccx") is None and os.environ.get("CI") != "true",
    reason="CalculiX ccx (Debian package calculix-ccx) not installed",
)


def run(args, capsys):
    code = main(args)
    return (code, *capsys.readouterr())


def beam(e: float, b: float, t: float) -> tuple[float, float, float]:
    """EI, EA and kGA of a plate with nu = 0 (G = E/2, Timoshenko's k = 5/6)."""
    return e * b * t**3 / 12, e * b * t, 5 / 6 * (e / 2) * b * t


def frame_stiffness() -> np.ndarray:
    """The stage's 3x3 stiffness at P = (w/2, L) (x, y, rotation), linear beams: two Timoshenko
    legs along y from (x_i, 0) to (x_i, L), clamped in the frame and in the stage, each bending
    across ([12, -6L; -6L, (4 + Phi) L^2] EI/(L^3 (1 + Phi)) on its tip's (u, slope -phi)) and
    stretching along (EA/L on v + phi (x_i - w/2))."""
    ei, ea, kga = beam(E, WIDTH, THICK)
    phi = 12 * ei / (kga * L_LEG**2)
    bend = (
        ei
        / (L_LEG**3 * (1 + phi))
        * np.array([[12, -6 * L_LEG], [-6 * L_LEG, (4 + phi) * L_LEG**2]])
    )
    out = np.zeros((3, 3))
    for x in (0.0, W):
        across = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])
        along = np.array([0.0, 1.0, x - W / 2])
        out += across.T @ bend @ across + ea / L_LEG * np.outer(along, along)
    return out


def stage_k() -> float:
    """K: the stage's stiffness along x at P, free to move along y and to turn (1/C_xx)."""
    return 1 / np.linalg.inv(frame_stiffness())[0, 0]


def leaf(spring: str | None = None) -> str:
    """The parallelogram with its actuator a stroke (with `spring`, a parameter k), unloaded."""
    text = LEAF.read_text().replace("F = 1.0 ", "F = 0.0 ")
    if spring == "k":
        text = text.replace("F = 0.0 ", "k = 1e4\nF = 0.0 ")
    value = '"k"' if spring == "k" else spring
    drive = 'drive = "stroke"' + (f"\nspring = {value}" if spring else "")
    return text.replace('drive = "force"', drive)


def evaluate(text: str, level: str, stroke: float, **params) -> symkin.Evaluation:
    return symkin.evaluate(
        symkin.analyze(symkin.loads(text)),
        {"push": stroke},
        level=level,
        params={k: str(v) for k, v in params.items()},
    )


# -- the ideal stroke -------------------------------------------------------------------------
@pytest.mark.parametrize("level", PHYSICAL)
def test_an_ideal_stroke_moves_the_stage_by_itself_against_the_frame(level):
    """The stage's point of action moves by the stroke along x (to solver tolerance), the
    actuator delivers the linear frame's K s (K from two Timoshenko legs), dF/ds = K, and the
    stage drops by Awtar's (3/5) s^2/L."""
    res = evaluate(leaf(), level, STROKE)
    dx, dy = res.points["P"].deviation  # P is the point of action
    assert dx == pytest.approx(STROKE, rel=1e-12)
    assert dy == pytest.approx(-0.6 * STROKE**2 / L_LEG, rel=2e-3)
    act = res.actuators["push"]
    assert act.command is None and act.stroke == pytest.approx(STROKE, rel=1e-12)
    k = stage_k()
    assert act.force == pytest.approx(k * STROKE, rel=1e-6)
    assert act.stiffness == pytest.approx(k, rel=1e-6)
    assert res.inputs == {"push": STROKE}
    assert res.points["P"].rigid == pytest.approx((W / 2, L_LEG), abs=1e-17)  # as fabricated
    assert res.links["stage"].rigid == 0.0
    # the stroke holds P along x: no point compliance to invert there
    assert res.stiffness["P"] is None


@pytest.mark.parametrize("level", PHYSICAL)
def test_a_zero_stroke_leaves_the_stage_as_fabricated(level):
    res = evaluate(leaf(), level, 0.0)
    assert res.points["P"].deviation == pytest.approx((0.0, 0.0), abs=1e-20)
    assert res.actuators["push"].force == pytest.approx(0.0, abs=1e-15)


@pytest.mark.parametrize("level", PHYSICAL)
def test_a_stroke_against_a_load_adds_its_force(level):
    """A 0.05 N [[load]] along x beside the stroke: the stage still sits at the stroke, the
    actuator delivers K s less the load (superposition, linear frame)."""
    load = 0.05
    res = evaluate(leaf(), level, STROKE, F=load)
    assert res.points["P"].deviation[0] == pytest.approx(STROKE, rel=1e-12)
    assert res.actuators["push"].force == pytest.approx(stage_k() * STROKE - load, rel=1e-6)


# -- a piezo behind a spring ------------------------------------------------------------------
@pytest.mark.parametrize("level", PHYSICAL)
@pytest.mark.parametrize("k", [1e4, 5e6])  # N/m: near the stage's K = 8.2e3, and a stiff stack
def test_a_piezo_in_series_with_a_spring_shares_the_command(level, k):
    """Series springs: the actual stroke is s k/(k + K), the force K times it, dF/ds by the
    command k K/(k + K); the point stiffness with the command held is the frame's plus k along
    the line; the coupling K_yx its drop's slope (6/5)(x/L) K_yy."""
    res = evaluate(leaf("k"), level, STROKE, k=k)
    big_k = stage_k()
    actual = STROKE * k / (k + big_k)
    act = res.actuators["push"]
    assert act.command == STROKE
    assert act.stroke == pytest.approx(actual, rel=1e-6)
    assert act.force == pytest.approx(big_k * actual, rel=1e-6)
    assert act.stiffness == pytest.approx(k * big_k / (k + big_k), rel=1e-6)
    dx = res.points["P"].deviation[0]
    assert dx == pytest.approx(actual, rel=1e-6)
    got = np.array(res.stiffness["P"])
    want = frame_stiffness() + np.diag([k, 0.0, 0.0])
    assert np.diag(got) == pytest.approx(np.diag(want), rel=2e-4)
    assert got[1, 0] == pytest.approx(1.2 * dx / L_LEG * got[1, 1], rel=1e-3)
    assert abs(got[2, 0] - want[2, 0]) <= 1e-5 * np.abs(want).max()


def test_loaded_and_equilibrium_agree_on_a_piezo_driven_stage():
    got = {lv: evaluate(leaf("k"), lv, STROKE, k=1e4) for lv in PHYSICAL}
    a, b = (got[lv] for lv in PHYSICAL)
    for key in ("stroke", "force", "stiffness"):
        va, vb = getattr(a.actuators["push"], key), getattr(b.actuators["push"], key)
        assert abs(va - vb) <= 1e-4 * abs(vb)
    da, db = np.array(a.points["P"].deviation), np.array(b.points["P"].deviation)
    assert np.linalg.norm(da - db) <= 1e-4 * np.linalg.norm(db)


def test_the_sensitivity_by_the_command_is_the_spring_share():
    """d(deviation)/ds at `loaded`: k/(k + K) along x, along y the drop's slope times it."""
    k = 1e4
    res = symkin.evaluate(
        symkin.analyze(symkin.loads(leaf("k"))),
        {"push": STROKE},
        level="loaded",
        params={"k": str(k)},
        sensitivity=True,
    )
    assert res.sensitivity is not None
    rate = res.sensitivity.deviation_inputs["P"]["push"]
    share = k / (k + stage_k())
    assert rate[0] == pytest.approx(share, rel=1e-6)
    dx = res.points["P"].deviation[0]
    assert rate[1] == pytest.approx(-1.2 * dx / L_LEG * share, rel=2e-3)
    assert res.sensitivity.rigid_inputs["P"]["push"] == (0.0, 0.0)  # the reference stays


# -- a clamped beam with a block, driven by a stroke ------------------------------------------
BLOCK = """format = 1
name = "clamped_block_stroke"
[parameters]
L = 0.020
a = 0.005
[defaults]
length = "L"
E = 210e9
nu = 0
thickness = 0.2e-3
width = 5e-3
[[link]]
name = "frame"
[[link]]
name = "block"
[[hinge]]
name = "A"
links = ["frame", "block"]
at = ["-a - L/2", 0.0]
[[hinge]]
name = "B"
links = ["block", "frame"]
at = ["a + L/2", 0.0]
[[point]]
name = "C"
link = "block"
at = [0.0, 0.0]
[[actuator]]
name = "pusher"
link = "block"
at = [0.0, 0.0]
direction = [0.0, 1.0]
"""


@pytest.mark.parametrize("level", PHYSICAL)
@pytest.mark.parametrize("stroke", [1e-7, 1.5e-5])
def test_a_stroke_on_a_clamped_block_meets_its_stretch_stiffening(level, stroke):
    """Two collinear plates from the frame to a block pushed across them by a stroke y: the
    force F = k y + 1.44 EA y^3/L^3 (k the two clamped-guided Timoshenko plates, the cubic
    their stretch: tests/test_structures.py) and dF/dy = k + 4.32 EA y^2/L^3. At 1.5e-5 the
    cubic term is 4e-3 of F."""
    L = 0.020
    ei, ea, kga = beam(210e9, 5e-3, 0.2e-3)
    k = 2 / (L**3 / (12 * ei) + L / kga)
    res = symkin.evaluate(symkin.analyze(symkin.loads(BLOCK)), {"pusher": stroke}, level=level)
    act = res.actuators["pusher"]
    assert res.points["C"].deviation[1] == pytest.approx(stroke, rel=1e-12)
    assert act.force == pytest.approx(k * stroke + 1.44 * ea * stroke**3 / L**3, rel=1e-5)
    assert act.stiffness == pytest.approx(k + 4.32 * ea * stroke**2 / L**3, rel=2e-5)
    if stroke > 1e-6:
        assert act.force / (k * stroke) - 1 > 3e-3  # the linear beam alone is off


# -- a three-leaf pivot turned by a stroke at its rim -----------------------------------------
THREE = ZOO / "three_leaf.toml"


@pytest.mark.parametrize("level", PHYSICAL)
def test_a_stroke_at_the_rim_turns_and_shifts_a_three_leaf_hub(level):
    """A stroke s along y at the rim point Q = (r, 0) of the three-leaf hub (its moment M set to
    0): three-fold symmetry leaves the hub's translation and rotation uncoupled at its centre,
    translation stiffness k_t = (3/2)(EA/L + k_across) (k_across the clamped-guided Timoshenko
    plate's) and rotation stiffness k_th = sum over the plates of the Timoshenko end stiffness
    seen from the centre, so F = s / (1/k_t + r^2/k_th) and the hub turns by F r/k_th."""
    L, r, e, b, t = 0.020, 0.005, 210e9, 5e-3, 0.2e-3
    ei, ea, kga = beam(e, b, t)
    k_t = 1.5 * (ea / L + 1 / (L**3 / (12 * ei) + L / kga))
    phi = 12 * ei / (kga * L**2)
    k_th = 3 * ei * (12 * r**2 + 12 * r * L + (4 + phi) * L**2) / (L**3 * (1 + phi))
    k = 1 / (1 / k_t + r**2 / k_th)
    text = THREE.read_text().replace("M = 1e-5 ", "M = 0.0 ")
    text += '[[actuator]]\nname = "piezo"\nlink = "hub"\nat = ["r", 0.0]\ndirection = [0.0, 1.0]\n'
    stroke = 1e-7
    res = symkin.evaluate(symkin.analyze(symkin.loads(text)), {"piezo": stroke}, level=level)
    act = res.actuators["piezo"]
    assert res.points["Q"].deviation[1] == pytest.approx(stroke, rel=1e-12)
    assert act.force == pytest.approx(k * stroke, rel=1e-5)
    assert act.stiffness == pytest.approx(k, rel=1e-5)
    assert res.links["hub"].deviation == pytest.approx(act.force * r / k_th, rel=1e-5)


# -- what refuses it, and what check says -----------------------------------------------------
@pytest.mark.parametrize("level", ["paper", "first_order", "exact"])
def test_the_kinematic_levels_refuse_a_stroke_driven_structure(tmp_path, capsys, level):
    path = tmp_path / "leaf.toml"
    path.write_text(leaf())
    code, out, err = run(["eval", str(path), "--level", level, "--input", "push=1e-5"], capsys)
    assert code == 2 and out == ""
    assert str(path) in err and "structure" in err and "no motion (mobility 0)" in err
    assert "fix: ask for --level loaded (or equilibrium)" in err and "stroke actuators" in err


@pytest.mark.parametrize("backend", ["numpy", "c"])
def test_the_generated_evaluators_refuse_a_structures_stroke(tmp_path, capsys, backend):
    path = tmp_path / "leaf.toml"
    path.write_text(leaf())
    code, out, err = run(
        ["eval", str(path), "--level", "loaded", "--backend", backend, "--input", "push=1e-5"],
        capsys,
    )
    assert code == 2 and out == ""
    assert "[[actuator]] #1 'push'" in err and "structure's stroke actuators" in err
    assert "--backend sympy" in err
    code, out, err = run(["derive", str(path), "-o", str(tmp_path / "out"), "--quiet"], capsys)
    assert code == 2 and "structure's stroke actuators" in err
    assert not (tmp_path / "out").exists()


def test_check_prints_a_stroke_driven_structure(tmp_path, capsys):
    path = tmp_path / "leaf.toml"
    path.write_text(leaf("5e6"))
    code, out, err = run(["check", str(path)], capsys)
    assert code == 0 and err == ""
    lines = out.splitlines()
    assert "mobility: 0" in lines
    assert any(
        line.startswith("  a structure: the rigid linkage is locked")
        and "its stroke actuators move their points from the as-fabricated pose" in line
        for line in lines
    )
    assert any(
        line.startswith("inputs: push (a structure's stroke actuators:")
        and "counts for no mobility" in line
        for line in lines
    )
    assert any(
        line.startswith("  actuator push: stroke (file unit)") and "a constraint" in line
        for line in lines
    )


def test_the_json_reports_command_stroke_and_force(tmp_path, capsys):
    path = tmp_path / "leaf.toml"
    path.write_text(leaf("1e4"))
    code, out, err = run(
        ["eval", str(path), "--level", "loaded", "--input", "push=1e-5", "--json"], capsys
    )
    assert code == 0 and err == ""
    data = json.loads(out)
    entry = data["actuators"]["push"]
    assert list(entry) == ["command", "stroke", "force", "stiffness"]
    assert entry["command"] == 1e-5
    big_k = stage_k()
    assert entry["stroke"] == pytest.approx(1e-5 * 1e4 / (1e4 + big_k), rel=1e-6)
    assert data["inputs"] == {"push": 1e-5}


@needs_ccx
def test_the_fe_model_moves_the_stage_by_the_stroke(tmp_path, capsys):
    """`symkin fea` prescribes the stroke from the as-fabricated pose: its stage, and the
    stroke it reports, at s (not the rigid pose's stroke added twice)."""
    path = tmp_path / "leaf.toml"
    path.write_text(leaf())
    code, out, err = run(
        [
            "fea",
            str(path),
            "--input",
            "push=1e-5",
            "--mesh",
            "20,2",
            "-o",
            str(tmp_path),
            "--run",
            "--json",
            "--quiet",
        ],
        capsys,
    )
    assert code == 0, err
    data = json.loads(out)
    assert data["actuators"]["push"]["fea"] == pytest.approx(1e-5, rel=1e-6)
    fe = data["points"]["P"]["fea"]
    assert fe[0] == pytest.approx(1e-5, rel=1e-6)
    assert data["points"]["P"]["difference"]["equilibrium"] <= 1e-3
