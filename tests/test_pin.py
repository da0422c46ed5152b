"""`pin = "prbm"` (docs/physics.md, "Where the rigid pin sits"): the rigid reference pin of a hinge
at its model's pseudo-rigid-body pivot, d = g'(0) from M's clamp, so the model's O(l θ) deviation
from a pin at the plate midpoint disappears.

Checked on a lone hinge (an arm on one input plate) against the models' closed forms of
the pin placement of docs/file-format.md evaluated here with mpmath at 50 digits, and by the
scaling of the deviation with θ.
"""

from __future__ import annotations

import math

import mpmath
import pytest

import symkin
from symkin.physics import arith, beams

L = mpmath.mpf("0.002")
ANGLE = mpmath.pi / 3  # the plate's direction as fabricated
POINT = (mpmath.mpf("0.05"), mpmath.mpf("0.08"))


def arm(model: str, pin: str, extra: str = ""):
    text = f"""format = 1
name = "arm"
[[link]]
name = "base"
[[link]]
name = "arm"
[[hinge]]
name = "S"
links = ["base", "arm"]
at = [0.01, 0.02]
plate_angle = "pi/3"
length = 0.002
model = "{model}"
pin = "{pin}"
input = true
{extra}
[[point]]
name = "T"
link = "arm"
at = [0.05, 0.08]
"""
    return symkin.analyze(symkin.loads(text, "arm.toml"))


def rot(t, v):
    return (
        mpmath.cos(t) * v[0] - mpmath.sin(t) * v[1],
        mpmath.sin(t) * v[0] + mpmath.cos(t) * v[1],
    )


def expected_deviation(theta, f, g, d):
    """T's deviation: compliant (M's clamp at (f, g) in the plate frame, the arm turned by θ)
    minus rigid (the arm turned by θ about the pin d from M's clamp)."""
    u = (mpmath.cos(ANGLE), mpmath.sin(ANGLE))
    centre = (mpmath.mpf("0.01"), mpmath.mpf("0.02"))
    clamp_p = (centre[0] - L / 2 * u[0], centre[1] - L / 2 * u[1])
    clamp_m = (centre[0] + L / 2 * u[0], centre[1] + L / 2 * u[1])
    local = rot(ANGLE, (f, g))
    moved = (clamp_p[0] + local[0], clamp_p[1] + local[1])
    arm_c = rot(theta, (POINT[0] - clamp_m[0], POINT[1] - clamp_m[1]))
    pin = (clamp_m[0] - d * u[0], clamp_m[1] - d * u[1])
    arm_r = rot(theta, (POINT[0] - pin[0], POINT[1] - pin[1]))
    return (moved[0] + arm_c[0] - pin[0] - arm_r[0], moved[1] + arm_c[1] - pin[1] - arm_r[1])


@pytest.mark.parametrize("gamma, c", [("0.8517", "1.2385"), ("0.7346", "1.5164"), ("0.9", "1.1")])
@pytest.mark.parametrize("theta", ["1e-6", "0.01", "0.4"])
def test_prbm_pin_sits_gamma_l_over_c_theta_from_m_clamp(gamma, c, theta):
    an = arm("prbm", "prbm", f"gamma = {gamma}\nc_theta = {c}")
    result = symkin.evaluate(an, {"S": theta}, "exact")
    with mpmath.workdps(50):
        t, gm, ct = mpmath.mpf(theta), mpmath.mpf(gamma), mpmath.mpf(c)
        big = t / ct
        want = expected_deviation(
            t, L * (1 - gm * (1 - mpmath.cos(big))), gm * L * mpmath.sin(big), gm * L / ct
        )
        dev = result.points["T"].deviation
        assert math.hypot(dev[0] - want[0], dev[1] - want[1]) < 1e-13 * float(mpmath.hypot(*want))


def test_elastica_force_pin_sits_two_thirds_of_the_plate_from_m_clamp():
    # The tip-force cantilever's tip, from the physics integrator (a different code path from the
    # model's elliptic-integral form): find the load that gives tip angle θ, read (x, y).
    an = arm("elastica_force", "prbm")
    for theta in ("0.01", "0.5"):
        result = symkin.evaluate(an, {"S": theta}, "exact")
        with mpmath.workdps(30):
            t = mpmath.mpf(theta)

            def tip(k0, alpha):
                return beams.shoot(
                    arith.mp_array([k0]), arith.mp_array([0]), arith.mp_array([alpha]), tol=1e-33
                )

            # no moment at the tip, tip angle θ: k0 and the load index α
            k0, alpha = mpmath.findroot(
                lambda k, a: (tip(k, a).omega[0], tip(k, a).psi[0] - t), (2 * t, 2 * t)
            )
            end = tip(k0, alpha)
            want = expected_deviation(t, L * end.x[0], L * end.y[0], 2 * L / 3)
        dev = result.points["T"].deviation
        assert math.hypot(dev[0] - want[0], dev[1] - want[1]) < 1e-10 * float(mpmath.hypot(*want))


@pytest.mark.parametrize("model", ["prbm", "elastica_force"])
def test_the_order_l_theta_term_vanishes_with_the_models_pin(model):
    # Against the midpoint pin |ΔR| ≈ c l θ; against the model's pin |ΔR| = O(l θ²).
    midpoint, own = arm(model, "midpoint"), arm(model, "prbm")
    size = {}
    for name, an in (("midpoint", midpoint), ("prbm", own)):
        size[name] = [
            math.hypot(*symkin.evaluate(an, {"S": t}, "exact").points["T"].deviation)
            for t in (1e-3, 1e-4)
        ]
    assert size["midpoint"][0] / size["midpoint"][1] == pytest.approx(10, rel=1e-3)
    assert size["prbm"][0] / size["prbm"][1] == pytest.approx(100, rel=1e-2)
    assert size["prbm"][0] < 1e-2 * size["midpoint"][0]


@pytest.mark.parametrize("model", ["circular_arc", "small_deflection", "rigid"])
def test_models_pivoting_at_the_midpoint_are_unchanged(model):
    a, b = arm(model, "midpoint"), arm(model, "prbm")
    for theta in (0.01, 0.3):
        assert (
            symkin.evaluate(a, {"S": theta}, "exact").points["T"].deviation
            == symkin.evaluate(b, {"S": theta}, "exact").points["T"].deviation
        )
