"""tests/mechanisms/bridge_amplifier.toml (the benchmarks' stroke-driven, 10-plate, 3-loop
design, benchmarks/designs.py) against references written here: the piezo pushes the left
slider 10 mm above its frame hinge SL0 along +x, so the rigid slider turns by
-asin(s / 10) exactly; the independent oracle (tests/reference_solver.py) driven by the hinge SL0
at that angle gives the rigid linkage at 40 digits, and its plates (the file's model) the
compliant mechanism at the angle where the compliant point of action has moved by s (secant
method). Every backend's `exact` level agrees with both, and the block rises about
cot(4.6 deg) * 2 s = 25 s."""

from __future__ import annotations

import math
from pathlib import Path

import mpmath
import pytest
from evaluators import BACKENDS

import symkin
from tests.reference_solver import Reference

ROOT = Path(__file__).resolve().parent.parent
BRIDGE = ROOT / "tests" / "mechanisms" / "bridge_amplifier.toml"
AT = (mpmath.mpf(-30), mpmath.mpf(-10))  # the point of action on slider_left


def hinge_driven() -> Reference:
    """The oracle on the file with its actuator replaced by the input hinge SL0."""
    text = BRIDGE.read_text()
    text = text[: text.index("[[actuator]]")]
    text = text.replace(
        'at = [-30, -20]\nplate_angle = "pi/2"',
        'at = [-30, -20]\nplate_angle = "pi/2"\ninput = true',
    )
    return Reference(symkin.loads(text, "bridge_hinge.toml"))


def action_x(sol: dict) -> mpmath.mpf:
    x, _, phi = sol["poses"]["slider_left"]
    return x + mpmath.cos(phi) * AT[0] - mpmath.sin(phi) * AT[1]


def references(s: float) -> tuple[dict, dict]:
    ref = hinge_driven()
    with mpmath.workdps(40):
        q_r = -mpmath.asin(mpmath.mpf(s) / 10)
        rigid = ref.solve({"SL0": q_r}, model_override="rigid", dps=40)
        assert action_x(rigid) - AT[0] == pytest.approx(s, rel=1e-30)

        def miss(q):
            sol = ref.solve({"SL0": q}, dps=40)
            return action_x(sol) - AT[0] - mpmath.mpf(s), sol

        q0, q1 = q_r, q_r * (1 + mpmath.mpf("1e-3"))
        f0, (f1, sol) = miss(q0)[0], miss(q1)
        for _ in range(40):
            q0, q1 = q1, q1 - f1 * (q1 - q0) / (f1 - f0)
            f0, (f1, sol) = f1, miss(q1)
            if abs(f1) < mpmath.mpf(10) ** -32:
                return rigid, sol
    raise AssertionError("the reference did not reach the stroke")


def block_point(sol: dict) -> tuple:
    x, y, phi = sol["poses"]["block"]
    return (
        x + mpmath.cos(phi) * 0 - mpmath.sin(phi) * 10,
        y + mpmath.sin(phi) * 0 + mpmath.cos(phi) * 10,
    )


@pytest.mark.parametrize("s", [0.004, 0.01])
def test_bridge_exact_level_against_the_oracle(s):
    an = symkin.analyze(symkin.load(BRIDGE))
    rigid, compliant = references(s)
    pr, pc = block_point(rigid), block_point(compliant)
    dev = [float(pc[i] - pr[i]) for i in range(2)]
    size = math.hypot(*dev)
    assert size > 1e-5
    # the amplification: cot(atan(2/25)) times the sliders' closing, 2 s, to a few per cent
    assert float(pr[1] - 10) == pytest.approx(25 * s, rel=0.05)
    for backend in BACKENDS:
        p = symkin.evaluate(an, {"piezo": s}, "exact", backend=backend).points["P"]
        for i in range(2):
            assert p.rigid[i] == pytest.approx(float(pr[i]), abs=1e-13)
            assert abs(p.deviation[i] - dev[i]) <= 1e-9 * size, backend
