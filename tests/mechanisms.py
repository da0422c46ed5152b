"""Mechanism files used by the tests beyond examples/: each a TOML text (docs/file-format.md)."""

from __future__ import annotations

import json
import math
from pathlib import Path

ZOO = Path(__file__).resolve().parent / "mechanisms"


def q(name: str) -> str:
    """A TOML basic string for any name (JSON's escapes are TOML's)."""
    return json.dumps(name)


HEADER = """format = 1
name = "{name}"
[parameters]
l = {l}
[defaults]
length = "l"
model = "{model}"
"""


def text(name: str, body: str, l: str = "1e-3", model: str = "circular_arc") -> str:
    return HEADER.format(name=name, l=l, model=model) + body


def links(*names: str) -> str:
    return "".join(f"[[link]]\nname = {q(n)}\n" for n in names)


def hinge(
    name: str,
    p: str,
    m: str,
    x: float,
    y: float,
    angle: str = "0",
    extra: str = "",
    input: bool = False,
) -> str:
    return (
        f"[[hinge]]\nname = {q(name)}\nlinks = [{q(p)}, {q(m)}]\nat = [{x}, {y}]\n"
        f'plate_angle = "{angle}"\n' + ("input = true\n" if input else "") + extra
    )


def point(name: str, link: str, x: float, y: float) -> str:
    return f"[[point]]\nname = {q(name)}\nlink = {q(link)}\nat = [{x}, {y}]\n"


SERIAL_ARM = text(
    "serial_arm",
    links("base", "upper", "fore")
    + hinge("S", "base", "upper", 0.0, 0.0, "pi/2", input=True)
    + hinge("E", "upper", "fore", 0.0, 0.08, "pi/3", 'model = "prbm"\n', input=True)
    + point("T", "fore", 0.05, 0.12),
)

FIVE_BAR = text(
    "five_bar",
    links("ground", "left", "left_top", "right_top", "right")
    + hinge("O1", "ground", "left", 0.0, 0.0, "pi/2", input=True)
    + hinge("O2", "right", "ground", 0.08, 0.0, "pi/2", input=True)
    + hinge("A", "left", "left_top", -0.01, 0.05, "0", 'model = "small_deflection"\n')
    + hinge("B", "right_top", "right", 0.095, 0.05, "pi/4")
    + hinge(
        "P", "left_top", "right_top", 0.04, 0.09, "-pi/6", 'model = "prbm"\npreset = "moment"\n'
    )
    + point("P_tip", "left_top", 0.04, 0.09),
)

WATT_II = text(
    "watt_ii",
    links("ground", "crank", "coupler", "rocker", "coupler2", "output")
    + hinge("O1", "ground", "crank", 0.0, 0.0, "pi/2", input=True)
    + hinge("A", "crank", "coupler", 0.015, 0.025, "0")
    + hinge("O3", "ground", "rocker", 0.1, 0.0, "pi/2")
    + hinge("B", "coupler", "rocker", 0.09, 0.065, "pi/3", 'model = "prbm"\n')
    + hinge("C", "rocker", "coupler2", 0.13, 0.05, "0", 'model = "rigid"\n')
    + hinge(
        "O5",
        "ground",
        "output",
        0.2,
        0.0,
        "pi/2",
        'model = "expr"\nf = "l*sin(theta)/theta"\ng = "l*(1 - cos(theta))/theta"\n',
    )
    + hinge("D", "coupler2", "output", 0.19, 0.07, "pi/2")
    + point("Q", "coupler2", 0.16, 0.09),
)

TRIAD_SIX_BAR = text(
    "triad_six_bar",
    links("ground", "crank", "link1", "tri", "link2", "link3")
    + hinge("O1", "ground", "crank", 0.0, 0.0, "pi/2", input=True)
    + hinge("A", "crank", "link1", 0.02, 0.02, "0")
    + hinge("B", "link1", "tri", 0.06, 0.05, "pi/4", 'model = "elastica_force"\n')
    + hinge("C", "tri", "link2", 0.1, 0.07, "0")
    + hinge("O4", "ground", "link2", 0.14, 0.01, "pi/2")
    + hinge("D", "tri", "link3", 0.08, 0.1, "pi/2")
    + hinge("O5", "ground", "link3", 0.03, 0.12, "0")
    + point("T", "tri", 0.09, 0.08),
)

NON_GRASHOF = text(
    "non_grashof",
    links("frame", "crank", "coupler", "rocker")
    + hinge("A0", "frame", "crank", 0.0, 0.0, "pi/2", input=True)
    + hinge("A", "crank", "coupler", 0.0, 0.06, "0")
    + hinge("B0", "frame", "rocker", 0.1, 0.0, "pi/2")
    + hinge("B", "coupler", "rocker", 0.08, 0.05, "0")
    + point("C", "coupler", 0.04, 0.08),
)

# The four-bar with its geometry in parameters: a dependent default (L2 = 2*l), a PRBM plate
# whose gamma and direction are parameters, a point placed by parameters (sensitivity tests).
PARAM_FOUR_BAR = (
    """format = 1
name = "param_four_bar"
[parameters]
l = 1e-3
L2 = "2*l"
ax = 0.015
ay = 0.026
bx = 0.085
by = 0.068
g = 0.8517
tilt = "pi/3"
cx = 0.06
[defaults]
model = "circular_arc"
length = "l"
"""
    + links("frame", "crank", "coupler", "rocker")
    + hinge("A0", "frame", "crank", 0.0, 0.0, "pi/2", input=True)
    + '[[hinge]]\nname = "A"\nlinks = ["crank", "coupler"]\nat = ["ax", "ay"]\n'
    'plate_angle = "tilt"\nmodel = "prbm"\ngamma = "g"\nlength = "L2"\n'
    + hinge("B0", "frame", "rocker", 0.1, 0.0, "pi/2")
    + '[[hinge]]\nname = "B"\nlinks = ["coupler", "rocker"]\nat = ["bx", "by"]\n'
    + '[[point]]\nname = "C"\nlink = "coupler"\nat = ["cx", "0.064 + ay"]\n'
)


def without_stiffness(path) -> str:
    """An example file's text without the plates' E, thickness and width (for tests that set
    their own stiffness, or need a file without any)."""
    import re
    from pathlib import Path

    text = Path(path).read_text()
    return re.sub(r"^(E|thickness|width) = .*\n", "", text, flags=re.M)


def with_beam(text: str, beam: str) -> str:
    """A file's text with every plate's beam theory set in [defaults] (docs/physics.md):
    "elastica" where a test compares with the inextensible reference, tests/reference_physics.py."""
    if "[defaults]\n" in text:
        return text.replace("[defaults]\n", f'[defaults]\nbeam = "{beam}"\n', 1)
    return text.replace("\n[[link]]", f'\n[defaults]\nbeam = "{beam}"\n\n[[link]]', 1)


# -- a lone plate held by its actuator (tests/test_physics.py, tests/test_buckling.py) -------


def lone_plate(
    units: str = "mm",
    width: str = "5",
    nu: str = "0.3",
    scale: float = 1.0,
    load: str = "",
    beam: str = "reissner",
) -> str:
    """A plate of length l = 10 along +y from the ground's clamp at the origin to link `arm`,
    point T on the arm at (0, 3 l); lengths in `units`, all of them times `scale`."""
    return (
        f"""format = 1
name = "lone_plate"
units = "{units}"
[parameters]
l = {10 * scale}
F = 0
[defaults]
E = 200e9
thickness = {0.2 * scale}
width = {float(width) * scale}
nu = {nu}
beam = "{beam}"
[[link]]
name = "ground"
[[link]]
name = "arm"
[[hinge]]
name = "A"
links = ["ground", "arm"]
at = [0, "l/2"]
plate_angle = "pi/2"
length = "l"
input = true
[[point]]
name = "T"
link = "arm"
at = [0, "3*l"]
"""
        + load
    )


def bending_stiffness(width: float, nu: float, unit: float, scale: float = 1.0) -> float:
    """EI (N m²) of the lone plate, written here from the documented rule: E/(1 - ν²) when the
    plate is at least 5 thicknesses wide."""
    b, t = width * scale * unit, 0.2 * scale * unit
    modulus = 200e9 / (1 - nu**2) if b >= 5 * t else 200e9
    return modulus * b * t**3 / 12


def axial_stiffness(width: float, nu: float, unit: float) -> float:
    """EA (N) of the lone plate: E' b t, E' as for EI."""
    b, t = width * unit, 0.2 * unit
    return (200e9 / (1 - nu**2) if b >= 5 * t else 200e9) * b * t


def shear_stiffness(width: float, nu: float, unit: float) -> float:
    """κGA (N) of the lone plate: κ = 5/6, G = E/(2(1 + ν)), A = b t (Timoshenko)."""
    return 5 / 6 * 200e9 / (2 * (1 + nu)) * width * unit * 0.2 * unit


def column_buckling_load(beam: str, width: float = 5, nu: float = 0.3) -> float:
    """The fixed–guided lone plate's critical axial load (N): Euler's P_E = π² EI/l² for the
    elastica; for Reissner's beam the linearised equilibrium EI ψ'' = −P (1 − P/EA + P/κGA) ψ
    about the compressed straight plate gives P (1 + c P) = P_E, c = 1/κGA − 1/EA."""
    euler = math.pi**2 * bending_stiffness(width, nu, 1e-3) / 0.01**2
    if beam == "elastica":
        return euler
    c = 1 / shear_stiffness(width, nu, 1e-3) - 1 / axial_stiffness(width, nu, 1e-3)
    return (math.sqrt(1 + 4 * c * euler) - 1) / (2 * c)


# -- actuators ----------------------------------------------------------------------------------

#: A piezo on the stage of tests/mechanisms/parallelogram.toml pushing along x (format `drive`).
PIEZO = """
[[actuator]]
name = "piezo"
link = "stage"
at = ["w/2", "L"]
direction = [1.0, 0.0]
drive = "{drive}"
"""


def made_passive(text: str, hinge: str) -> str:
    """`text` with the input hinge `hinge` made passive (its `input = true` removed)."""
    head, tail = text.split(f"name = {q(hinge)}", 1)
    return head + f"name = {q(hinge)}" + tail.replace("input = true\n", "", 1)


def parallelogram_driven(drive: str = "stroke", extra: str = "") -> str:
    """The parallelogram with F1 passive, `extra` (say a load) and the piezo driving by `drive`."""
    text = (ZOO / "parallelogram.toml").read_text()
    return made_passive(text, "F1") + extra + PIEZO.format(drive=drive)
