"""The `loaded` level's truncation estimate at points that barely move (docs/physics.md, "The
Newton level"; docs/levels.md, "Structures"): a point's change when the quartic terms are
dropped is measured against its deviation, but at least a share of the largest point deviation
and a multiple of ε times the mechanism's size, so that a point at the centre of a link's
rotation (whose deviation is rounding, or a cancellation of the link's motions) is no longer
refused while the estimate still refuses where the plates' truncation is too coarse.
References written here: the three-leaf hub's beam stiffness and its centre at rest (three-fold
symmetry), and the rigid-body relation between two points of one link."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from conftest import EXAMPLES
from evaluators import backends_with, require
from mechanisms import ZOO

import symkin
from symkin.physics import reduced
from symkin.studies.physical import reduced_equilibrium

LOADED_BACKENDS = ("sympy", *backends_with(generated=True, levels="loaded"))

#: the three-leaf flexure (tests/mechanisms/three_leaf.toml) with a point O at its hub's centre
HUB = ZOO / "three_leaf.toml"
CENTRE = '\n[[point]]\nname = "O"\nlink = "hub"\nat = [0.0, 0.0]\n'


def hub_turn(moment: float) -> float:
    """The hub's turn under a moment: three Timoshenko plates (nu = 0, k = 5/6) clamped in the
    frame and in the hub at radius r, each seen from the hub's centre with the end stiffness
    EI (12 r^2 + 12 r L + (4 + Phi) L^2) / (L^3 (1 + Phi))."""
    length, r, modulus, b, t = 0.020, 0.005, 210e9, 5e-3, 0.2e-3
    ei, kga = modulus * b * t**3 / 12, 5 / 6 * modulus / 2 * b * t
    phi = 12 * ei / (kga * length**2)
    k = ei * (12 * r**2 + 12 * r * length + (4 + phi) * length**2) / (length**3 * (1 + phi))
    return moment / (3 * k)


def without_floor(monkeypatch) -> None:
    """The estimate as it was: each point's change against its own deviation alone."""
    rules = dataclasses.replace(reduced.RULES, est_share=0.0, est_size_eps=0.0)
    monkeypatch.setattr(reduced, "RULES", rules)


@pytest.mark.parametrize("moment", [1e-6, 1e-5])
def test_a_point_at_the_hubs_centre_is_taken_at_loaded(moment, monkeypatch):
    """Under a moment the hub turns about its centre, which stays put (three-fold symmetry): its
    deviation is rounding (~1e-22 m), once refused with an estimate of 1e3 % and more; now the
    level answers and its rim point turns by the beam formula."""
    an = symkin.analyze(symkin.loads(HUB.read_text() + CENTRE, "three_leaf.toml"))
    res = symkin.evaluate(an, {}, level="loaded", params={"M": str(moment)})
    turn = hub_turn(moment)
    assert res.links["hub"].deviation == pytest.approx(turn, rel=1e-6)
    q = res.points["Q"].deviation
    assert q[1] == pytest.approx(0.005 * math.sin(turn), rel=1e-6)
    assert math.hypot(*res.points["O"].deviation) <= 1e-12 * math.hypot(*q)
    # the per-point estimate refuses the same configuration: the floor is what takes it
    without_floor(monkeypatch)
    answer = reduced_equilibrium(an, {}, {"M": str(moment)}, segments=1)
    assert answer.refused.startswith(reduced.TRUNCATION)


def coupler_centre(inputs: dict[str, float]) -> tuple[float, float]:
    """Where on the four-bar's coupler (its as-fabricated coordinates) the loaded deviation is
    zero: the coupler's deviation is the rigid-body motion d(p) = (R(phi_c) - R(phi_r))(p - C)
    + d(C), from C's deviation and the coupler's rigid and compliant rotations."""
    an = symkin.analyze(symkin.load(EXAMPLES / "four_bar.toml"))
    res = symkin.evaluate(an, inputs, level="loaded")
    link = res.links["coupler"]

    def rot(a: float) -> np.ndarray:
        return np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])

    at = np.array([0.06, 0.09]) - np.linalg.solve(
        rot(link.compliant) - rot(link.rigid), np.array(res.points["C"].deviation)
    )
    return float(at[0]), float(at[1])


@pytest.fixture(scope="module")
def four_bar_with_centre():
    inputs = {"A0": 0.3}
    x, y = coupler_centre(inputs)
    text = (EXAMPLES / "four_bar.toml").read_text()
    text += f'\n[[point]]\nname = "Z"\nlink = "coupler"\nat = [{x!r}, {y!r}]\n'
    return symkin.analyze(symkin.loads(text, "four_bar.toml")), inputs


def rotation(a: float) -> np.ndarray:
    return np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])


@pytest.mark.parametrize("backend", LOADED_BACKENDS)
def test_a_hinge_driven_mechanism_with_a_point_at_a_links_centre(backend, four_bar_with_centre):
    """The four-bar driven by its input hinge, with a point Z where the coupler's deviation
    vanishes (1e-12 of C's: rounding): refused before on every backend (estimate 1538 %), now
    answered alike, Z's deviation the rigid-body relation's zero."""
    require(backend)
    an, inputs = four_bar_with_centre
    res = symkin.evaluate(an, inputs, level="loaded", backend=backend)
    c, z = np.array(res.points["C"].deviation), np.array(res.points["Z"].deviation)
    assert np.hypot(*z) <= 1e-9 * np.hypot(*c)
    link = res.links["coupler"]
    # the rigid-body relation from Z to C: d(C) = (R(phi_c) - R(phi_r))(C - Z) + d(Z)
    arm = np.array([0.06, 0.09]) - np.array([float(v) for v in an.mechanism.point("Z").at])
    moved = (rotation(link.compliant) - rotation(link.rigid)) @ arm + z
    assert np.hypot(*(moved - c)) <= 1e-8 * np.hypot(*c)


def loaded_parallelogram(fraction: float):
    """The parallelogram (tests/mechanisms/parallelogram.toml) with a dead load pressing its
    stage down, `fraction` times the force that puts each plate at its Euler load pi^2 EI/l^2
    (E' = E/(1 - nu^2): a wide plate)."""
    ei = 210e9 / (1 - 0.3**2) * 10e-3 * (0.15e-3) ** 3 / 12
    force = 2 * fraction * math.pi**2 * ei / 5e-3**2
    text = (ZOO / "parallelogram.toml").read_text()
    text += f'\n[[load]]\nlink = "stage"\nat = ["w/2", "L"]\nforce = [0.0, {-force!r}]\n'
    return symkin.analyze(symkin.loads(text, "parallelogram.toml"))


def test_the_estimate_still_refuses_a_coarse_truncation():
    """Where one plate relation is too coarse (the plates pressed to 80 % of the first buckling
    factor, tests/test_loaded_newton.py) the estimate refuses it as before: the stage's points
    move alike, each measured against its own deviation (the floor is a tenth of the largest)."""
    an = loaded_parallelogram(0.654)
    answer = reduced_equilibrium(an, {"F1": 0.05}, segments=1)
    assert answer.refused.startswith(reduced.TRUNCATION)
    sizes = sorted(math.hypot(*d) for d in answer.deviations.values() if any(d))
    assert sizes[0] >= reduced.RULES.est_share * sizes[-1]


def test_the_floor_leaves_a_mechanism_without_such_points_alone(four_bar_with_centre, monkeypatch):
    """The four-bar's own point C is the largest deviation: its estimate is the same with and
    without the floor; with Z, the estimate without the floor refuses (Z's change against its
    rounding-sized deviation)."""
    an, inputs = four_bar_with_centre
    plain = symkin.analyze(symkin.load(EXAMPLES / "four_bar.toml"))
    floored = reduced_equilibrium(plain, inputs, segments=1).estimate
    assert not reduced_equilibrium(an, inputs, segments=1).refused
    without_floor(monkeypatch)
    assert reduced_equilibrium(plain, inputs, segments=1).estimate == floored
    assert reduced_equilibrium(an, inputs, segments=1).refused.startswith(reduced.TRUNCATION)
