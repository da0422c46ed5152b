"""Structures and close plates (docs/levels.md, "Structures"; docs/file-format.md, "[[hinge]]"):
a file whose rigid linkage is locked (mobility 0) and that nothing drives is evaluated at the
physical levels under its loads and force actuators, its deviation the displacement from the
as-fabricated pose; the kinematic levels and the generated evaluators refuse it (exit 2); plates
may sit closer together than their length and may cross. References, none of them the code
under test: linear beam theory written out here (Euler-Bernoulli with Timoshenko's shear term,
the stretch EA/L), Awtar's parasitic motion -(3/5) y^2/L of a parallel-guided beam, the
pure-bending stiffness of a cross-spring pivot.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from conftest import EXAMPLES
from mechanisms import ZOO

import symkin
from symkin.cli.commands import main

LEAF = ZOO / "leaf_parallelogram.toml"
THREE = ZOO / "three_leaf.toml"
KINEMATIC = ("paper", "first_order", "exact")
PHYSICAL = ("loaded", "equilibrium")


def run(args, capsys):
    code = main(args)
    return (code, *capsys.readouterr())


def beam(E: float, b: float, t: float) -> tuple[float, float, float]:
    """EI, EA and kGA of a plate with nu = 0 (E' = E, G = E/2, Timoshenko's k = 5/6)."""
    return E * b * t**3 / 12, E * b * t, 5 / 6 * (E / 2) * b * t


def evaluate(path, level: str, inputs=None, **params):
    return symkin.evaluate(
        symkin.analyze(symkin.load(path)),
        inputs or {},
        level=level,
        params={k: str(v) for k, v in params.items()},
    )


# -- the leaf-spring parallelogram ------------------------------------------------------------
L_LEG, E, WIDTH, THICK = 0.040, 210e9, 10e-3, 0.5e-3


def guided_compliance() -> float:
    """The two legs' transverse compliance, each a clamped-guided beam: L^3/(12 EI) + L/(kGA),
    in parallel (the stage held from turning)."""
    ei, _, kga = beam(E, WIDTH, THICK)
    return (L_LEG**3 / (12 * ei) + L_LEG / kga) / 2


def stage_compliance(w: float = 0.025) -> np.ndarray:
    """The 3x3 compliance of the stage at P = (w/2, L) (x, y, rotation), linear beams: each leg
    a Timoshenko beam along y from (x_i, 0) to (x_i, L), clamped in the frame and the stage; at
    its tip the stage's motion (u, v, phi) gives the displacement (u, v + phi (x_i - w/2)) and
    the rotation phi (the tip's slope dx/dy = -phi). Its stretch (EA/L) lets the stage turn."""
    ei, ea, kga = beam(E, WIDTH, THICK)
    phi = 12 * ei / (kga * L_LEG**2)
    bend = (
        ei
        / (L_LEG**3 * (1 + phi))
        * np.array([[12, -6 * L_LEG], [-6 * L_LEG, (4 + phi) * L_LEG**2]])
    )
    stiffness = np.zeros((3, 3))
    for x in (0.0, w):
        across = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])  # (transverse, slope) of (u, v, phi)
        along = np.array([0.0, 1.0, x - w / 2])  # the tip's motion along the leg
        stiffness += across.T @ bend @ across + ea / L_LEG * np.outer(along, along)
    return np.linalg.inv(stiffness)


@pytest.mark.parametrize("level", PHYSICAL)
def test_a_parallelogram_of_single_plates_moves_by_24EI_over_L3(level):
    force = 0.02  # N: y/L = 1.2e-4, the nonlinear terms ~1e-8 of y
    res = evaluate(LEAF, level, {"push": 0}, F=force)
    dx, dy = res.points["P"].deviation
    linear = stage_compliance() @ [force, 0.0, 0.0]
    assert dx == pytest.approx(linear[0], rel=1e-6)
    assert res.links["stage"].deviation == pytest.approx(linear[2], rel=1e-4)
    # the textbook's 24 EI/L^3, to the shear's share 2 (t/L)^2/k = 3.8e-4 and the stage's turn
    # from the legs' stretch, (t/w)^2 = 4e-4
    ei = beam(E, WIDTH, THICK)[0]
    assert dx == pytest.approx(force / (24 * ei / L_LEG**3), rel=1e-3)
    assert dx == pytest.approx(force * guided_compliance(), rel=5e-4)
    # Awtar's parasitic motion: the stage drops by (3/5) y^2/L
    assert dy < 0
    assert dy == pytest.approx(-0.6 * dx**2 / L_LEG, rel=2e-3)
    assert res.links["stage"].rigid == 0.0  # the rigid linkage stays as fabricated
    assert res.points["P"].rigid == pytest.approx((0.0125, 0.040), abs=1e-17)


@pytest.mark.parametrize("level", PHYSICAL)
def test_the_parasitic_motion_grows_as_y_squared_at_larger_loads(level):
    """At F = 1 N (y/L = 3e-3) the drop is still Awtar's (3/5) y^2/L (his next terms are
    O((y/L)^2) and the plates' (t/L)^2 smaller)."""
    res = evaluate(LEAF, level, {"push": 0}, F=1.0)
    dx, dy = res.points["P"].deviation
    assert dx == pytest.approx(stage_compliance()[0, 0], rel=2e-4)
    assert dy == pytest.approx(-0.6 * dx**2 / L_LEG, rel=2e-3)


@pytest.mark.parametrize("level", PHYSICAL)
def test_a_force_actuator_on_a_structure_is_a_load(level):
    """At zero force (and no load) nothing moves; at F it moves as the [[load]] of F does, by
    the beam formula; its `stroke` is the displacement of its point along its line."""
    still = evaluate(LEAF, level, {"push": 0}, F=0)
    assert still.points["P"].deviation == (0.0, 0.0)
    assert still.actuators["push"].stroke == 0.0
    pushed = evaluate(LEAF, level, {"push": 0.02}, F=0)
    dx = pushed.points["P"].deviation[0]
    assert dx == pytest.approx((stage_compliance() @ [0.02, 0.0, 0.0])[0], rel=1e-6)
    assert pushed.actuators["push"].force == 0.02
    assert pushed.actuators["push"].stroke == pytest.approx(dx, rel=1e-12)
    assert pushed.inputs == {"push": 0.02}


def test_a_structures_sensitivity_by_its_force_is_its_compliance():
    """At `loaded`, d(deviation)/d(force) of the force actuator: the linear compliance across,
    and along, the derivative of Awtar's drop, -(6/5) (y/L) dy/dF."""
    res = symkin.evaluate(
        symkin.analyze(symkin.load(LEAF)),
        {"push": 0.02},
        level="loaded",
        params={"F": "0"},
        sensitivity=True,
    )
    assert res.sensitivity is not None
    rates = res.sensitivity.deviation_inputs["P"]["push"]
    compliance = stage_compliance()[0, 0]
    assert rates[0] == pytest.approx(compliance, rel=1e-6)
    y = res.points["P"].deviation[0]
    assert rates[1] == pytest.approx(-1.2 * y / L_LEG * compliance, rel=3e-3)
    # a [[load]] of the same size along the same line has the same rate
    assert res.sensitivity.deviation["P"]["F"][0] == pytest.approx(rates[0], rel=1e-9)


def test_loaded_and_equilibrium_agree_on_a_structure():
    got = {lv: evaluate(LEAF, lv, {"push": 0.3}, F=0.5) for lv in PHYSICAL}
    a, b = (got[lv].points["P"].deviation for lv in PHYSICAL)
    assert math.dist(a, b) <= 1e-6 * math.hypot(*b)


def test_plates_closer_than_their_length_are_accepted(tmp_path, capsys):
    """The leaf parallelogram's plates stand 25 mm apart on the frame and on the stage, 40 mm
    long (once refused: 'reach past each other'); a --param that brings them closer still is
    taken too."""
    values = {p.name: float(p.value) for p in symkin.load(LEAF).parameters}
    assert values["w"] < values["L"]
    code, out, err = run(["check", str(LEAF)], capsys)
    assert code == 0 and "valid" in out and err == ""
    code, out, err = run(
        ["eval", str(LEAF), "--level", "equilibrium", "--param", "w=0.005", "--input", "push=0"],
        capsys,
    )
    assert code == 0 and err == "" and "point P" in out


def test_a_plate_longer_than_its_link_is_accepted_at_the_kinematic_levels(capsys):
    """The four-bar's plates at l = 40 mm reach past each other on its 30 mm crank: accepted
    now; the kinematic answer is the model's, whatever the plates' overlap."""
    four_bar = str(EXAMPLES / "four_bar.toml")
    code, out, err = run(["eval", four_bar, "--input", "A0=0.1", "--param", "l=0.04"], capsys)
    assert code == 0 and err == "" and "point C" in out


# -- what refuses a structure -----------------------------------------------------------------
@pytest.mark.parametrize("level", KINEMATIC)
def test_the_kinematic_levels_refuse_a_structure(capsys, level):
    code, out, err = run(["eval", str(LEAF), "--level", level, "--input", "push=0"], capsys)
    assert code == 2 and out == ""
    assert "structure" in err and "no motion (mobility 0)" in err and f"the {level} level" in err
    assert "fix: ask for --level loaded" in err
    with pytest.raises(symkin.InputError, match="mobility 0"):
        evaluate(THREE, level)


@pytest.mark.parametrize("backend", ["numpy", "c"])
def test_the_generated_evaluators_refuse_a_structures_force_actuators(capsys, backend):
    """A structure's generated evaluators take no inputs (tests/test_structure_codegen.py); its
    force actuators would be their inputs, and are refused, naming the [[load]] way."""
    code, out, err = run(
        ["eval", str(LEAF), "--level", "loaded", "--backend", backend, "--input", "push=0"], capsys
    )
    assert code == 2 and out == ""
    assert "structure's force actuators" in err and "--backend sympy" in err


def test_derive_writes_a_structures_evaluators_and_tradeoff_refuses_it(tmp_path, capsys):
    """derive, tolerance and sweep take a structure at `loaded` (its evaluators hold that level
    alone); tradeoff, which compares variants over the inputs' range, refuses it."""
    out_dir = tmp_path / "out"
    code, out, err = run(
        ["derive", str(THREE), "-o", str(out_dir), "--quiet", "--emit", "numpy"], capsys
    )
    assert code == 0 and err == ""
    module = (out_dir / "three_leaf.py").read_text()
    assert "levels: loaded." in module and "inputs none (a structure)." in module
    code, out, err = run(["tradeoff", str(THREE)], capsys)
    assert code == 2 and out == ""
    assert "structure" in err and "tradeoff" in err and "does not take structures" in err
    assert "fix: evaluate it with symkin eval --level loaded" in err


def test_a_locked_linkage_with_an_input_is_still_refused(tmp_path, capsys):
    """Mobility 0 with an input hinge: the inputs do not number the mobility (exit 2); the fix
    names the structure's way."""
    text = LEAF.read_text().replace(
        'plate_angle = "pi/2"\n\n[[hinge]]', 'plate_angle = "pi/2"\ninput = true\n\n[[hinge]]', 1
    )
    path = tmp_path / "leaf.toml"
    path.write_text(text)
    code, out, err = run(["check", str(path)], capsys)
    assert code == 2 and out == ""
    assert "two hinges join frame and stage" in err


# -- check ------------------------------------------------------------------------------------
def test_check_prints_a_structure(capsys):
    code, out, err = run(["check", str(LEAF)], capsys)
    assert code == 0 and err == ""
    lines = out.splitlines()
    assert "mobility: 0" in lines
    assert any(line.startswith("  a structure: the rigid linkage is locked") for line in lines)
    assert any(
        line.startswith("inputs: none (a structure); its force actuators are loads")
        and line.endswith(": push")
        for line in lines
    )
    assert any("actuator push: force (N)" in line and "a load" in line for line in lines)
    assert not any(line.startswith("note:") for line in lines)  # the leaves do not cross
    code, out, _ = run(["check", str(THREE)], capsys)
    assert code == 0 and "inputs: none (a structure)\n" in out


# -- the three-leaf flexure -------------------------------------------------------------------
LEAF3 = {"L": 0.020, "r": 0.005, "E": 210e9, "b": 5e-3, "t": 0.2e-3}


def hub_stiffness() -> float:
    """The hub's rotational stiffness about its centre: per plate, the Timoshenko beam's end
    stiffness [12, -6L; -6L, (4 + Phi) L^2] EI/(L^3 (1 + Phi)) under the end's displacement
    r*phi and rotation phi: EI (12 r^2 + 12 r L + (4 + Phi) L^2)/(L^3 (1 + Phi)); three plates."""
    L, r = LEAF3["L"], LEAF3["r"]
    ei, _, kga = beam(LEAF3["E"], LEAF3["b"], LEAF3["t"])
    phi = 12 * ei / (kga * L**2)
    return 3 * ei * (12 * r**2 + 12 * r * L + (4 + phi) * L**2) / (L**3 * (1 + phi))


@pytest.mark.parametrize("level", PHYSICAL)
def test_a_three_leaf_flexure_turns_by_its_beam_stiffness(level):
    moment = 1e-6  # N m: 1.2e-6 rad
    res = evaluate(THREE, level, M=moment)
    turn = res.links["hub"].deviation
    assert turn == pytest.approx(moment / hub_stiffness(), rel=1e-7)
    # the rim point Q = (r, 0) moves by r*phi along y (the centre stays put)
    qx, qy = res.points["Q"].deviation
    assert qy == pytest.approx(LEAF3["r"] * turn, rel=1e-9)
    assert abs(qx) <= 1e-6 * abs(qy)


@pytest.mark.parametrize("level", PHYSICAL)
def test_a_three_leaf_flexure_translates_by_stretch_and_bending(level):
    """A force at the hub's centre: the three plates' stretch EA/L along them and fixed-guided
    bending across, (3/2)(EA/L + k_t) in every direction (three-fold symmetry), no turn."""
    L = LEAF3["L"]
    ei, ea, kga = beam(LEAF3["E"], LEAF3["b"], LEAF3["t"])
    across = 1 / (L**3 / (12 * ei) + L / kga)
    force = 0.1
    res = evaluate(THREE, level, M=0, Fx=force)
    qx, qy = res.points["Q"].deviation
    assert qx == pytest.approx(force / (1.5 * (ea / L + across)), rel=1e-7)
    assert abs(qy) <= 1e-5 * qx and abs(res.links["hub"].deviation) <= 1e-4 * qx / L


# -- a clamped beam with a rigid block in its middle ----------------------------------------
BLOCK = """format = 1
name = "clamped_block"
[parameters]
L = 0.020
a = 0.005
F = 0.01
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
[[load]]
point = "C"
force = [0.0, "F"]
"""


@pytest.mark.parametrize("level", PHYSICAL)
@pytest.mark.parametrize("force", [1e-4, 0.01, 0.03])
def test_a_clamped_beam_with_a_block_stiffens_as_its_plates_stretch(level, force):
    """Two collinear plates from the frame to a block between them: each a clamped-guided beam
    (12 EI/L^3 with its shear), which the block's motion y also stretches: each plate's ends
    draw together by (3/5) y^2/L (Awtar's parasitic term), held by the frame, so a tension
    N = (3/5) EA y^2/L^2 whose geometric stiffness (6/5) N/L adds to the bending's:
    F = k y + 2 (6/5)(3/5) EA y^3/L^3. At 0.03 N the cubic term is 3.6e-3 of F."""
    L = 0.020
    ei, ea, kga = beam(210e9, 5e-3, 0.2e-3)
    k = 2 / (L**3 / (12 * ei) + L / kga)
    roots = np.roots([1.44 * ea / L**3, 0.0, k, -force])
    y = float(next(r.real for r in roots if abs(r.imag) <= 1e-12 * abs(r)))
    res = symkin.evaluate(
        symkin.analyze(symkin.loads(BLOCK)), {}, level=level, params={"F": str(force)}
    )
    got = res.points["C"].deviation
    assert got[1] == pytest.approx(y, rel=2e-6 * (1 + (force / 0.01) ** 2))
    assert abs(got[0]) <= 1e-12 * got[1] and abs(res.links["block"].deviation) <= 1e-12
    if force == 0.03:  # the stretch matters: the linear beam is off by 3.6e-3
        assert abs(got[1] / (force / k) - 1) > 3e-3


# -- crossing plates --------------------------------------------------------------------------
CROSS = """format = 1
name = "cross_spring"
[parameters]
l = 0.020
[defaults]
length = "l"
E = 210e9
nu = 0
thickness = 0.2e-3
width = 5e-3
[[link]]
name = "frame"
[[link]]
name = "stage"
[[hinge]]
name = "A"
links = ["frame", "stage"]
at = [0.0, 0.0]
plate_angle = "pi/4"
input = true
[[hinge]]
name = "B"
links = ["frame", "stage"]
at = [0.0, 0.0]
plate_angle = "3*pi/4"
[[point]]
name = "P"
link = "stage"
at = [0.0, 0.02]
"""


def test_a_cross_spring_pivot_is_accepted_with_a_note(tmp_path, capsys):
    path = tmp_path / "cross.toml"
    path.write_text(CROSS)
    code, out, err = run(["check", str(path)], capsys)
    assert code == 0 and err == ""
    assert (
        "note: the plates of A and B cross as fabricated (a cross-spring pivot): they must lie "
        "in different layers" in out
    )
    assert "a structure" not in out  # its rigid linkage turns about the crossing: mobility 1


def test_a_cross_spring_pivot_turns_by_its_leaves_bending():
    """Leaves crossing at their midpoints: the stage turns about the crossing and each leaf
    bends into an arc under a pure moment EI theta/l, so the input's moment is 2 EI theta/l to
    first order (the centre's shift is of order theta^2)."""
    theta = 1e-4
    res = symkin.evaluate(symkin.analyze(symkin.loads(CROSS)), {"A": theta}, level="equilibrium")
    ei = beam(210e9, 5e-3, 0.2e-3)[0]
    assert res.actuation["A"].moment == pytest.approx(2 * ei * theta / 0.020, rel=1e-3)
    assert res.actuation["A"].stiffness == pytest.approx(2 * ei / 0.020, rel=1e-3)


def test_the_json_of_a_structure(capsys):
    code, out, err = run(
        ["eval", str(THREE), "--level", "loaded", "--json", "--param", "M=1e-6"], capsys
    )
    assert code == 0 and err == ""
    data = json.loads(out)
    assert data["inputs"] == {} and data["level"] == "loaded"
    assert data["points"]["Q"]["rigid"] == pytest.approx([0.005, 0.0], abs=1e-30)
    assert data["points"]["Q"]["deviation"][1] == pytest.approx(
        LEAF3["r"] * 1e-6 / hub_stiffness(), rel=1e-7
    )


def test_the_eval_header_of_a_structure_says_it_has_no_input(capsys):
    """As `check` says it: "inputs: none (a structure)"; its force actuators, given, are named."""
    code, out, err = run(["eval", str(THREE), "--level", "loaded", "--param", "M=1e-6"], capsys)
    assert code == 0 and err == ""
    assert out.splitlines()[0] == "level: loaded (asked for)"
    assert out.splitlines()[1] == "backend sympy; inputs: none (a structure)"
    code, out, err = run(
        ["eval", str(LEAF), "--level", "loaded", "--input", "push=0.01", "--param", "F=0"], capsys
    )
    assert code == 0 and out.splitlines()[1] == "backend sympy; inputs: push = 0.01"
