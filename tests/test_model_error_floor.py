"""The model error of a point that barely moves (docs/physics.md, "Model error"): relative to its
own |ΔR| but at least a tenth of the largest point deviation and 1e-13 times the mechanism's
size, as the loaded level's truncation estimate takes it. A point at the hub's centre of the
three-leaf flexure (a structure) stays put under a moment (three-fold symmetry): its deviation is
rounding, 1e-23 m, and its model error once printed as 1.9e14 %.

References written here: the hub's turn from the plates' beam stiffness
(test_truncation_floor.hub_turn), the rim point's deviation r·turn, the mechanism's size from the
file's geometry (the hinge centres on a circle of radius r + L/2, 120 degrees apart)."""

from __future__ import annotations

import math

import pytest
from test_truncation_floor import CENTRE, HUB, hub_turn

import symkin
from symkin.physics import model_error

MOMENT = 1e-5  # the file's M
RADIUS, LENGTH = 0.005, 0.020  # the file's r and L


@pytest.fixture(scope="module", params=["loaded", "equilibrium"])
def hub(request):
    mech = symkin.loads(HUB.read_text() + CENTRE, "three_leaf.toml")
    res = symkin.evaluate(symkin.analyze(mech), {}, level=request.param)
    return mech, res


def _again(mech, res, deviations) -> dict[str, float]:
    """The estimate of `res`'s configuration with the points' deviations `deviations` (the
    absolute error terms do not depend on them: only what they are relative to)."""
    return model_error.estimate(
        mech,
        mech.defaults,
        res.level,
        model_error.level_stretches(mech, res.level),
        {name: link.compliant for name, link in res.links.items()},
        res.angles_compliant,
        res.hinges,
        deviations,
    ).total


def test_the_hubs_centre_is_judged_against_a_tenth_of_the_rim(hub):
    mech, res = hub
    rim = RADIUS * hub_turn(MOMENT)  # |ΔR| of Q on the rim (the turn is 1e-5 rad)
    assert res.points["Q"].norm == pytest.approx(rim, rel=1e-6)
    assert res.points["O"].norm < 1e-12 * rim  # rounding: the centre stays put
    error = res.model_error["O"]
    assert math.isfinite(error) and 0 < error < 0.1  # a few percent, not 1e14 %
    # the same absolute estimate at O relative to a tenth of the rim's deviation
    floor = 0.1 * rim
    judged = _again(mech, res, {"Q": res.points["Q"].deviation, "O": (floor, 0.0)})
    assert error == pytest.approx(judged["O"], rel=1e-5)
    # a point that moves by more than the floor keeps its own |ΔR|
    alone = _again(mech, res, {"Q": res.points["Q"].deviation})
    assert res.model_error["Q"] == alone["Q"]
    assert 0.001 < res.model_error["Q"] < 0.01


def test_at_rest_but_for_rounding_the_mechanisms_size_is_the_floor(hub):
    """Every point's deviation below 1e-13 L: O is judged against 1e-13 times the largest
    distance between hinge centres, √3 (r + L/2)."""
    mech, res = hub
    size = math.sqrt(3) * (RADIUS + LENGTH / 2)
    tiny = {"Q": (0.0, 1e-20), "O": (1e-30, 0.0)}
    floored = _again(mech, res, tiny)["O"]
    judged = _again(mech, res, {"Q": (0.0, 1e-20), "O": (1e-13 * size, 0.0)})["O"]
    assert math.isfinite(floored) and floored == pytest.approx(judged, rel=1e-12)
    # and the pose as fabricated, every point at rest, is still 0 (nothing to be relative to)
    assert _again(mech, res, {"Q": (0.0, 0.0), "O": (0.0, 0.0)}) == {"Q": 0.0, "O": 0.0}


def test_the_reports_table_gives_the_error_and_its_size(hub):
    """The report's table of the physical reference (report/equilibrium): O's error in percent
    and its size e times a tenth of the rim's deviation, with the sentence that says so."""
    from types import SimpleNamespace

    from symkin.report import equilibrium

    mech, res = hub
    report = SimpleNamespace(
        plan=SimpleNamespace(points=("Q", "O")), mech=mech, defaults=mech.defaults
    )
    table = equilibrium.equilibrium_table(report, res, equilibrium._scales([res]))
    rows = {row["name"]: row for row in table["points"]}
    floor = 0.1 * RADIUS * hub_turn(MOMENT)

    def number(cell: str) -> float:
        mantissa, _, power = cell.partition(r"\times 10^{")
        return float(mantissa) * 10.0 ** int(power.rstrip("}") or 0)

    assert rows["O"]["floored"] and not rows["Q"]["floored"]
    assert number(rows["O"]["error"]) == pytest.approx(
        100 * res.model_error["O"], rel=0.04
    )  # two digits
    assert number(rows["O"]["spread"]) == pytest.approx(
        res.model_error["O"] * floor, rel=0.04
    )  # two digits
    assert number(rows["Q"]["spread"]) == pytest.approx(
        res.model_error["Q"] * res.points["Q"].norm, rel=0.04
    )
