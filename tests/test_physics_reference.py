"""`equilibrium` and `loaded` against the independent physical reference
(tests/reference_physics.py, Taylor-series shooting in fixed-point arithmetic, written apart from
symkin), on plates that are elastica (`beam = "elastica"`, the reference's physics, which both
levels follow). Reissner plates, the default, are checked against tests/reference_beams.py in
test_equilibrium_beams.py.

`equilibrium` must agree to 1e-9 relative in the deviation (it claims 1e-10); `loaded` (Newton
on the reduced equilibrium) within LOADED_GOAL, far inside the goals of issue 10 (≤ 1 % relative
error of ΔR for l/L ≤ 0.05 and input angles 0.02–0.3 rad, ≤ 5 % at l/L = 0.2, loads included),
near a toggle position too. L is the shortest moving link (the four-bar's crank, 30 mm).
The reference is given E' = E/(1 − ν²) for these wide plates (width ≥ 5 thicknesses,
docs/physics.md), written here from the documented rule.
"""

from __future__ import annotations

import math

import mechanisms as M
import pytest
from conftest import EXAMPLES
from reference_physics import Equilibrium, Load, point_load

import symkin

E, NU, WIDTH = 210e9, 0.3, 5e-3
PLANE = E / (1 - NU**2)
# the reference is the elastica: every plate here is one (beam = "elastica", docs/physics.md)
STEEL = f'E = {E}\nthickness = "l/10"\nwidth = {WIDTH}\nnu = {NU}\nbeam = "elastica"\n'
CRANK = 0.03


def with_stiffness(example: str, extra: str = "", l: str | None = None) -> str:
    text = M.without_stiffness(EXAMPLES / f"{example}.toml")
    text = text.replace('length = "l"\n', 'length = "l"\n' + STEEL, 1)
    if l is not None:
        text = text.replace("l = 1e-3 ", f"l = {l} ", 1)
    return text + extra


def relative_gap(ours, ref) -> float:
    d = [float(v) for v in ref]
    return math.hypot(ours[0] - d[0], ours[1] - d[1]) / math.hypot(*d)


def goal(l_over_L: float) -> float:
    """`loaded`'s bound on the relative error of ΔR (measured: docs/physics.md)."""
    return 1e-3 if l_over_L <= 0.05 else 1e-2


def compare(mech, reference, point: str, inputs: dict, l_over_L: float):
    an = symkin.analyze(mech)
    ref = reference.solve({k: str(v) for k, v in inputs.items()})
    expected = ref["points"][point]["deviation"]
    eq = symkin.evaluate(an, inputs, "equilibrium")
    assert relative_gap(eq.points[point].deviation, expected) < 1e-9
    for name, h in ref["hinges"].items():
        scale = max(abs(float(v)) for v in h["force"]) + 1e-300
        assert (
            max(abs(a - float(b)) for a, b in zip(eq.hinges[name].force, h["force"])) < 1e-9 * scale
        )
        assert eq.hinges[name].moment == pytest.approx(float(h["moment"]), rel=1e-9, abs=1e-15)
    assert eq.energy == pytest.approx(float(ref["energy"]), rel=1e-9)
    for name, pose in ref["poses"].items():  # every moving link's rotation, its deviation
        link = eq.links[name]
        assert link.compliant == pytest.approx(float(pose[2]), rel=1e-12, abs=1e-15)
        assert link.deviation == pytest.approx(float(pose[2] - link.rigid), rel=1e-9, abs=1e-16)
    loaded = symkin.evaluate(an, inputs, "loaded")
    gap = relative_gap(loaded.points[point].deviation, expected)
    assert gap < goal(l_over_L), f"loaded is {gap:.2e} off at l/L = {l_over_L}, {inputs}"
    return gap


@pytest.mark.parametrize("l", ["0.2e-3", "1e-3", "5e-3"])
def test_four_bar_plate_lengths(l):
    mech = symkin.loads(with_stiffness("four_bar", l=l), "four_bar.toml")
    reference = Equilibrium(mech, (PLANE, WIDTH, "l/10"))
    for angle in (0.02, 0.1, 0.3):
        compare(mech, reference, "C", {"A0": angle}, float(l) / CRANK)


def test_four_bar_at_l_over_L_of_one_fifth():
    mech = symkin.loads(with_stiffness("four_bar", l="6e-3"), "four_bar.toml")
    reference = Equilibrium(mech, (PLANE, WIDTH, "l/10"))
    for angle in (0.02, 0.3):
        compare(mech, reference, "C", {"A0": angle}, 0.2)


def test_four_bar_plates_of_different_thickness():
    text = with_stiffness("four_bar")
    thickness = {"A0": "l/6", "A": "l/12", "B0": "l/8", "B": "l/20"}
    for name, t in thickness.items():
        text = text.replace(f'name = "{name}"\n', f'name = "{name}"\nthickness = "{t}"\n', 1)
    mech = symkin.loads(text, "four_bar.toml")
    reference = Equilibrium(mech, {n: (PLANE, WIDTH, t) for n, t in thickness.items()})
    for angle in (0.02, 0.1, 0.3):
        compare(mech, reference, "C", {"A0": angle}, 1e-3 / CRANK)


@pytest.mark.parametrize("angle", [0.02, -0.1, 0.3])
def test_four_bar_with_a_load_on_a_point(angle):
    load = '[[load]]\npoint = "C"\nforce = [0.5, -2.0]\nmoment = 0.01\n'
    mech = symkin.loads(with_stiffness("four_bar", load), "four_bar.toml")
    reference = Equilibrium(
        mech, (PLANE, WIDTH, "l/10"), loads=[point_load(mech, "C", ("0.5", "-2.0"), "0.01")]
    )
    compare(mech, reference, "C", {"A0": angle}, 1e-3 / CRANK)


def test_four_bar_with_a_load_on_a_link_position_in_millimetres():
    # The same four-bar written in mm: the reference reads metres, so it gets the metre file.
    load = '[[load]]\nlink = "rocker"\nat = [0.09, 0.03]\nforce = [-1.0, 0.5]\nmoment = -0.02\n'
    metres = symkin.loads(with_stiffness("four_bar", load), "four_bar.toml")
    reference = Equilibrium(
        metres,
        (PLANE, WIDTH, "l/10"),
        loads=[Load("rocker", ("0.09", "0.03"), ("-1.0", "0.5"), "-0.02")],
    )
    ref = reference.solve({"A0": "0.15"})
    mm = with_stiffness("four_bar", load.replace("[0.09, 0.03]", "[90, 30]"))
    for old, new in (
        ("[0.0, 0.0]", "[0, 0]"),
        ("[0.015, 0.026]", "[15, 26]"),
        ("[0.1, 0.0]", "[100, 0]"),
        ("[0.085, 0.068]", "[85, 68]"),
        ("[0.06, 0.09]", "[60, 90]"),
        ("l = 1e-3 ", "l = 1 "),
        ("width = 0.005", "width = 5"),
        ("format = 1\n", 'format = 1\nunits = "mm"\n'),
    ):
        assert old in mm, old
        mm = mm.replace(old, new, 1)
    result = symkin.evaluate(
        symkin.analyze(symkin.loads(mm, "four_bar_mm.toml")), {"A0": 0.15}, "equilibrium"
    )
    dev = [v / 1000 for v in result.points["C"].deviation]
    assert relative_gap(dev, ref["points"]["C"]["deviation"]) < 1e-9


@pytest.mark.parametrize("angle", [0.02, 0.1, 0.3])
def test_stephenson_six_bar(angle):
    mech = symkin.loads(with_stiffness("stephenson_six_bar"), "stephenson_six_bar.toml")
    reference = Equilibrium(mech, (PLANE, WIDTH, "l/10"))
    compare(mech, reference, "D", {"O_A": angle}, 0.8e-3 / CRANK)


@pytest.mark.parametrize("l, force", [("0.2e-3", 10.0), ("1e-3", 30.0)])
def test_four_bar_under_a_heavy_load(l, force):
    # Axial load indices p = N l²/EI near 1: the first-order correction is 1.4 % off (0.2 mm,
    # 10 N); the beam-column level keeps `loaded` within the goal.
    load = f'[[load]]\npoint = "C"\nforce = [{force / 4}, {-force}]\n'
    mech = symkin.loads(with_stiffness("four_bar", load, l=l), "four_bar.toml")
    reference = Equilibrium(
        mech, (PLANE, WIDTH, "l/10"), loads=[point_load(mech, "C", (str(force / 4), str(-force)))]
    )
    for angle in (0.02, 0.3):
        compare(mech, reference, "C", {"A0": angle}, float(l) / CRANK)


@pytest.mark.parametrize(
    "name, inputs, point",
    [
        ("WATT_II", {"O1": 0.2}, "Q"),  # a `rigid` hinge (a pin) among the plates
        ("FIVE_BAR", {"O1": 0.1, "O2": -0.05}, "P_tip"),  # two actuators
    ],
)
def test_mechanisms_with_a_pin_and_with_two_inputs(name, inputs, point):
    text = getattr(M, name).replace(
        'length = "l"', 'length = "l"\n' + STEEL.replace(f"nu = {NU}", "nu = 0"), 1
    )
    mech = symkin.loads(text, f"{name}.toml")
    reference = Equilibrium(mech, (E, WIDTH, "l/10"))
    compare(mech, reference, point, inputs, 1e-3 / 0.05)


@pytest.mark.parametrize(
    "inputs",
    [
        {"O": "0.3", "A": "0", "B": "0", "K": "0"},  # the dyad G-H-I near its toggle
        {"O": "0", "A": "0.3", "B": "0", "K": "0"},
        {"O": "-0.3", "A": "0", "B": "0", "K": "0"},
    ],
)
def test_nine_bar_near_a_toggle_position(inputs):
    """The nine-bar platform's dyad G-H-I has a toggle margin of 0.195 at O = 0.3, where the old
    linearised statics of the pin linkage was 2.5 % off; Newton on the reduced equilibrium
    takes the pose's own geometry and meets the same bound as elsewhere."""
    text = M.with_beam((EXAMPLES / "nine_bar_platform.toml").read_text(), "elastica")
    mech = symkin.loads(text, "nine_bar_platform.toml")
    reference = Equilibrium(mech, (PLANE, WIDTH, "l/10"))
    expected = reference.solve(inputs)["points"]["F"]["deviation"]
    an = symkin.analyze(mech)
    assert (
        relative_gap(symkin.evaluate(an, inputs, "equilibrium").points["F"].deviation, expected)
        < 1e-9
    )
    loaded = relative_gap(symkin.evaluate(an, inputs, "loaded").points["F"].deviation, expected)
    assert loaded < goal(0.6e-3 / CRANK)
