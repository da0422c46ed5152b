"""The report's natural frequencies (docs/physics.md, "Natural frequencies"; symkin.report.modes):
a file whose stage carries mass gets a table of the lowest frequencies over its input's range,
each entry checked against `symkin modes --level loaded` (symkin.studies.modes, the sympy path)
and the legs' formula of tests/test_modes.py; a file without masses has none."""

from __future__ import annotations

import math
import re

import pytest
from conftest import ROOT
from test_modes import leaf_stiffness, stage

import symkin
from symkin.studies.derive import generate
from symkin.studies.modes import modes

SPAN = (-0.5, 0.5)  # N: the force actuator's range


@pytest.fixture(scope="module")
def tex():
    mech = symkin.loads(stage(inertia=2e-5), "stage.toml")
    files = generate(mech, emit=("latex",), spans={"push": SPAN})
    return mech, files["stage.tex"].decode()


def test_the_table_holds_the_sympy_paths_frequencies(tex):
    mech, text = tex
    assert r"\subsection{Natural frequencies}" in text
    rows = re.findall(r"^push & \$([-+0-9.]+)\$ N((?: & \$[^$]*\$)+) \\\\$", text, re.M)
    assert len(rows) == 5
    assert [float(v) for v, _ in rows] == pytest.approx([-0.5, -0.25, 0.0, 0.25, 0.5])
    for value, cells in rows:
        printed = [float(c) for c in re.findall(r"\$([^$]*)\$", cells)]
        reference = modes(mech, {"push": float(value)}, "loaded", None, 3).frequencies
        assert printed == pytest.approx(reference, rel=6e-4)  # 4 significant digits
    # the first frequency: the legs' sway, (1/2π)√(2 k_leaf / m)
    sway = math.sqrt(2 * leaf_stiffness() / 0.1) / (2 * math.pi)
    lo, hi = re.search(
        r"first frequency lies between \$([0-9.]+)\$ and \$([0-9.]+)\$", text
    ).groups()
    assert float(lo) == pytest.approx(sway, rel=1e-3) and float(hi) == pytest.approx(sway, rel=1e-3)


def test_a_file_without_masses_has_no_frequencies():
    mech = symkin.load(ROOT / "tests" / "mechanisms" / "parallelogram_mm.toml")
    files = generate(mech, emit=("latex",))
    assert "Natural frequencies" not in files[f"{mech.name}.tex"].decode()


def test_the_pose_caption_names_the_first_mode_drawn(tex):
    mech, text = tex
    found = re.search(
        r"Blue arrows: the first natural mode, \$f_1 = ([0-9.]+)\$~Hz at push = 0", text
    )
    assert found, text[:3000]
    reference = modes(mech, {"push": 0.0}, "loaded", None, 1).frequencies[0]
    assert float(found[1]) == pytest.approx(reference, rel=6e-4)
