"""`equilibrium` with both beam theories against the independent beam reference
(tests/reference_beams.py: Reissner's plane beam and the elastica, shot in fixed-point arithmetic
and checked against Hencky chains that stretch and shear, written apart from symkin).

The four-bar example and the parallelogram stage of tests/mechanisms, each with and without a
load, at small and large inputs: the points' deviations to 1e-9 relative (symkin claims 1e-10;
the contract asks 1e-8), the plate forces, moments, energy and the links' rotations (the stage's
parasitic rotation among them) likewise; the Scott–Russell amplifier's limit point
(`buckling_factor`) where the reference's continuation stops. Needs tests/reference_beams.py.
"""

from __future__ import annotations

import math

import mechanisms as M
import pytest
import sympy as sp
from conftest import EXAMPLES, ROOT
from reference_beams import BeamEquilibrium
from reference_physics import ContinuationError

import symkin
from symkin.physics import equilibrium
from symkin.studies.configuration import parameter_values

ZOO = ROOT / "tests" / "mechanisms"
CASES = [
    (EXAMPLES / "four_bar.toml", "A0", ("0.02", "0.3"), ""),
    (
        EXAMPLES / "four_bar.toml",
        "A0",
        ("0.02", "0.3"),
        '\n[[load]]\npoint = "C"\nforce = [0.5, -2.0]\nmoment = 0.01\n',
    ),
    (ZOO / "parallelogram.toml", "F1", ("0.01", "0.1"), ""),
    (
        ZOO / "parallelogram.toml",
        "F1",
        ("0.01", "0.1"),
        '\n[[load]]\npoint = "P"\nforce = [1.5, -4.0]\nmoment = 0.02\n',
    ),
]


def relative_gap(ours, ref) -> float:
    d = [float(v) for v in ref]
    return math.hypot(ours[0] - d[0], ours[1] - d[1]) / math.hypot(*d)


@pytest.mark.parametrize("beam", ["reissner", "elastica"])
@pytest.mark.parametrize("path, hinge, angles, load", CASES)
def test_equilibrium_agrees_with_the_beam_reference(path, hinge, angles, load, beam):
    text = M.with_beam(path.read_text(), beam) + load
    mech = symkin.loads(text, path.name)
    an = symkin.analyze(mech)
    reference = BeamEquilibrium(mech, beam=beam)
    for angle in angles:
        ref = reference.solve({hinge: angle})
        ours = symkin.evaluate(an, {hinge: float(angle)}, "equilibrium")
        assert ours.error_estimate < 1e-10
        for name, point in ref["points"].items():
            assert relative_gap(ours.points[name].deviation, point["deviation"]) < 1e-9, name
        for name, h in ref["hinges"].items():
            scale = max(abs(float(v)) for v in h["force"]) + 1e-300
            gap = max(abs(a - float(b)) for a, b in zip(ours.hinges[name].force, h["force"]))
            assert gap < 1e-9 * scale, name
            assert ours.hinges[name].moment == pytest.approx(
                float(h["moment"]), rel=1e-9, abs=1e-15
            )
        assert ours.energy == pytest.approx(float(ref["energy"]), rel=1e-9)
        for name, pose in ref["poses"].items():  # every moving link's rotation and its deviation
            link = ours.links[name]
            assert link.compliant == pytest.approx(float(pose[2]), rel=1e-12, abs=1e-15)
            deviation = float(pose[2] - link.rigid)
            assert link.deviation == pytest.approx(deviation, rel=1e-9, abs=1e-16), name


def test_reissner_limit_point_of_the_scott_russell_amplifier():
    mech = symkin.load(ZOO / "scott_russell.toml")
    with pytest.raises(ContinuationError) as stop:
        BeamEquilibrium(mech).solve({"RA0": "0"}, load_factor=10)
    found = equilibrium.buckling_factor(mech, parameter_values(mech, None), {"RA0": sp.Integer(0)})
    assert found.factor == pytest.approx(10 * stop.value.load_factor, rel=2e-6)
