"""Geometry as CAD exports it: many significant digits, millimetre units, random decimals.

Exact rationals with 10-digit numerators once reached the printers as huge integers (C: "integer
constant is too large"; numpy: object arrays without sqrt). Every backend must agree with the
40-digit derivation and with the independent solver whatever digits the file holds.
"""

from __future__ import annotations

import re
from decimal import Decimal

import pytest
from conftest import EXAMPLES
from evaluators import GENERATED, Generated, rel_err
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from reference_solver import Reference

import symkin

FOUR_BAR = (EXAMPLES / "four_bar.toml").read_text()
#: The four-bar's coordinates as CAD writes them: 10 significant digits.
CAD = {
    "[0.015, 0.026]": "[0.01512345678, 0.02598765432]",
    "[0.1, 0.0]": "[0.1000012345, 0.0]",
    "[0.085, 0.068]": "[0.08512345671, 0.06800000012]",
    "[0.06, 0.09]": "[0.06012345678, 0.09000123457]",
}


def cad_text(scale_mm: bool = False) -> str:
    text = FOUR_BAR
    for old, new in CAD.items():
        text = text.replace(f"at = {old}", f"at = {new}")
    if scale_mm:
        # The same mechanism in millimetres: every length times 1000.
        text = re.sub(
            r"at = \[([^,\]]+), ([^\]]+)\]",
            lambda m: "at = [{}, {}]".format(*(Decimal(v) * 1000 for v in m.groups())),
            text,
        )
        text = text.replace("l = 1e-3", "l = 1.000000001")
    return text


def run_all(mech, inputs: dict[str, str], level: str = "exact") -> dict[str, dict]:
    """Deviation of every point by every backend: sympy (mpmath) and the generated ones."""
    g = Generated(mech=mech, sensitivity=False, levels=[level])
    sympy = symkin.evaluate(g.analysis, inputs, level).points
    return {
        "sympy": {n: p.deviation for n, p in sympy.items()},
        **{backend: g.run(backend, inputs, level) for backend in GENERATED},
    }


@pytest.mark.parametrize("mm", [False, True], ids=["metres", "millimetres"])
def test_ten_digit_coordinates_in_every_backend(mm):
    text = cad_text(mm)
    mech = symkin.loads(text, "cad_four_bar.toml")
    inputs = {"A0": "0.2"}
    ref = Reference(mech).deviation(inputs)
    for backend, points in run_all(mech, inputs).items():
        for name, dev in points.items():
            assert rel_err(dev, ref["points"][name]["deviation"]) <= 1e-9, (backend, name)


def test_millimetres_scale_the_deviation_by_a_thousand():
    inputs = {"A0": "0.15"}
    metres = Reference(symkin.loads(cad_text(False))).deviation(inputs)["points"]["C"]
    mm = run_all(symkin.loads(cad_text(True)), inputs)["c"]["C"]
    # l differs by 1e-9 relative between the two files; the deviation is linear in l.
    assert rel_err([v / 1000 for v in mm], metres["deviation"]) <= 1e-8


def test_generated_code_holds_no_huge_integer(tmp_path):
    from symkin.studies.derive import generate

    files = generate(symkin.loads(cad_text(), "cad.toml"), emit=("c", "numpy"))
    for name in ("four_bar.c", "four_bar.py"):
        text = files[name].decode()
        assert not re.search(r"(?<![.\deE+-])\d{18,}", text), name


decimal_offset = st.builds(
    lambda mantissa, digits: Decimal(mantissa).scaleb(-digits),
    st.integers(-2_000_000_000, 2_000_000_000),
    st.integers(12, 14),
)


@settings(
    max_examples=6, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow]
)
@given(
    offsets=st.lists(decimal_offset, min_size=6, max_size=6),
    angle=st.sampled_from(["-0.25", "0.05", "0.3"]),
)
def test_random_decimal_geometry_every_backend_agrees_with_mpmath(offsets, angle):
    """Hinge and point coordinates moved by up to 2 mm, written with 6 to 14 decimals."""
    text = FOUR_BAR
    moves = iter(offsets)
    for old in ("[0.015, 0.026]", "[0.085, 0.068]", "[0.06, 0.09]"):
        x, y = (Decimal(v) + next(moves) for v in old.strip("[]").split(", "))
        text = text.replace(f"at = {old}", f"at = [{x}, {y}]")
    mech = symkin.loads(text, "random_four_bar.toml")
    results = run_all(mech, {"A0": angle})
    for backend in GENERATED:
        for name, dev in results[backend].items():
            assert rel_err(dev, results["sympy"][name]) <= 1e-12, (backend, name)
