"""The independent reference (tests/reference_solver.py) on redundant closures and on the zoo
(tests/mechanisms/): mobility by rank, the three-leg stage against the two-leg parallelogram,
dropped residuals, and closed forms derived by hand for the stages and the Scott–Russell."""

from __future__ import annotations

from pathlib import Path

import mpmath
import pytest
from reference_solver import Reference, ReferenceAssemblyError, load_unchecked, mobility

ZOO = Path(__file__).resolve().parent / "mechanisms"
DPS = 40
TOL = mpmath.mpf(10) ** -(DPS - 8)


def zoo(name: str):
    return load_unchecked(ZOO / f"{name}.toml")


def text_of(name: str) -> str:
    return (ZOO / f"{name}.toml").read_text(encoding="utf-8")


def from_text(tmp_path, name: str, text: str):
    path = tmp_path / f"{name}.toml"
    path.write_text(text, encoding="utf-8")
    return load_unchecked(path)


def dist(a, b):
    return max(abs(a[0] - b[0]), abs(a[1] - b[1]))


# ---- mobility -----------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "name,want",
    [
        ("parallelogram", (1, 1)),
        ("parallelogram_mm", (1, 1)),
        ("three_leg_stage", (0, 1)),
        ("double_parallelogram", (2, 2)),
        ("scott_russell", (1, 1)),
        ("roberts", (1, 1)),
        ("toggle_four_bar", (1, 1)),
        ("lever_amplifier", (1, 1)),
    ],
)
def test_zoo_mobility(name, want):
    mech = zoo(name)
    assert mobility(mech) == want
    assert mobility(mech, model_override=None) == want  # the file's models
    assert mobility(mech, model_override="prbm") == want  # pivots off the midpoints


def test_three_leg_self_stress_by_hand():
    # Independent of the rank routine. At the as-fabricated pose the legs are vertical; a leg's
    # axial force N_k weights its frame hinge's and its stage hinge's y-rows alike (the leg's y
    # and φ columns cancel: +N_k x_k from one, −N_k x_k from the other), and the stage's y and φ
    # columns vanish when Σ N_k = 0 and Σ N_k x_k = 0: legs at x = 0, w/2, w give the
    # self-stress N = (1, −2, 1). So the 12 closure rows are dependent; mpmath's own SVD shows
    # exactly one vanishing singular value (rank 11, mobility 1).
    mech = zoo("three_leg_stage")
    ref = Reference(mech)
    with mpmath.workdps(DPS):
        hinges, _, _ = ref._setup("rigid", DPS)
        X = [mpmath.mpf(0)] * ref.n_unknowns
        _, J = ref._system(X, {"F1": mpmath.mpf(0)}, hinges)
        row = {
            f"{h.name}.{c}": J[2 * k + i]
            for k, h in enumerate(mech.hinges)
            for i, c in enumerate("xy")
        }
        combo = [
            row["S1.y"][j]
            + row["F1.y"][j]
            - 2 * (row["S3.y"][j] + row["F3.y"][j])
            + row["S2.y"][j]
            + row["F2.y"][j]
            for j in range(ref.n_unknowns)
        ]
        assert max(abs(c) for c in combo) < mpmath.mpf(10) ** -(DPS - 5)
        closure = mpmath.matrix(J[: 2 * len(mech.hinges)])
        sigma = sorted(mpmath.svd_r(closure, compute_uv=False))
        assert sigma[0] < mpmath.mpf(10) ** -(DPS - 5) and sigma[1] > mpmath.mpf("1e-3")


def test_tilted_middle_leg_is_a_structure(tmp_path):
    # Move the middle leg's stage hinge 5 mm sideways: the three legs no longer are parallel,
    # the stage cannot translate: rank mobility 0, and the solver refuses one input.
    text = text_of("three_leg_stage").replace('at = ["w/2", "L"]', 'at = ["w/2 + 0.005", "L"]')
    mech = from_text(tmp_path, "tilted", text)
    assert mobility(mech) == (0, 0)
    with pytest.raises(ReferenceAssemblyError, match="not the mobility"):
        Reference(mech).solve({"F1": "0.01"}, model_override="rigid")


def test_dependent_input_refused(tmp_path):
    # Two inputs on the three-leg stage: F2's angle always equals F1's (mobility 1).
    text = text_of("three_leg_stage").replace(
        'name = "F2"\nlinks = ["frame", "right"]',
        'name = "F2"\ninput = true\nlinks = ["frame", "right"]',
    )
    mech = from_text(tmp_path, "two_inputs", text)
    assert mech.inputs == ("F1", "F2")
    with pytest.raises(ReferenceAssemblyError, match="not the mobility"):
        Reference(mech).solve({"F1": "0.01", "F2": "0.01"})


# ---- the three-leg stage moves like the parallelogram --------------------------------------------
@pytest.mark.parametrize("model", ["rigid", None, "small_deflection", "prbm"])
@pytest.mark.parametrize("q", ["0.05", "-0.1", "1e-6", "0.3"])
def test_three_legs_equal_two_legs(model, q):
    three = Reference(zoo("three_leg_stage")).solve({"F1": q}, model_override=model)
    two = Reference(zoo("parallelogram")).solve({"F1": q}, model_override=model)
    with mpmath.workdps(DPS):
        assert dist(three["points"]["P"], two["points"]["P"]) < TOL
        for link in ("left", "right", "stage"):
            assert max(abs(a - b) for a, b in zip(three["poses"][link], two["poses"][link])) < TOL
        # the middle leg turns like the others, and the stage does not turn
        assert abs(three["angles"]["F3"] - mpmath.mpf(q)) < TOL
        assert abs(three["poses"]["stage"][2]) < TOL
        # the dropped closure rows (a redundant closure) hold to dps − 10 digits
        assert three["dropped"] and not two["dropped"]
        for value in three["dropped"].values():
            assert abs(value) < mpmath.mpf(10) ** -(DPS - 10)


def test_dropped_residuals_at_higher_precision():
    sol = Reference(zoo("three_leg_stage")).solve({"F1": "0.2"}, dps=60)
    assert len(sol["dropped"]) == 1  # one self-stress, one row dropped
    with mpmath.workdps(60):
        scale = mpmath.mpf("0.05")
        for value in sol["dropped"].values():
            assert abs(value) < scale * mpmath.mpf(10) ** -(60 - 10)


def test_inconsistent_redundancy_refused(tmp_path):
    # A middle leg 0.1 mm longer than the others: the as-fabricated pose is a solution (every
    # plate straight), the first-order mobility is still 1, but the rigid linkage locks: the
    # dropped equation cannot hold away from q = 0.
    text = text_of("three_leg_stage").replace('at = ["w/2", "L"]', 'at = ["w/2", "L + 1e-4"]')
    mech = from_text(tmp_path, "long_middle", text)
    assert mobility(mech) == (0, 1)
    with pytest.raises(ReferenceAssemblyError, match="inconsistent"):
        Reference(mech).solve({"F1": "0.05"}, model_override="rigid")


# ---- closed forms -----------------------------------------------------------------------------
def stage_translation(q, L, l, f, g):
    """Translation of a parallelogram stage (legs along +y, length L between plate midpoints,
    plates of length l along the legs) when the legs turn by q, the stage-side hinges by −q and
    a plate's model gives (f, g) at ±q (f even, g odd in θ). Derived by hand: the leg's frame
    clamp goes to (−g, f − l/2), the leg turns by q, the stage plate adds f·(−sin q, cos q)
    + g·(cos q, sin q); the stage's clamp started at (0, L + l/2)."""
    dx = -(L - l + f) * mpmath.sin(q) - g * (1 - mpmath.cos(q))
    dy = f * (1 + mpmath.cos(q)) + g * mpmath.sin(q) + (L - l) * mpmath.cos(q) - L - l
    return dx, dy


def arc_deviation(q, l):
    """Compliant − rigid stage translation with circular-arc plates (f = l sin q/q,
    g = l (1 − cos q)/q): (l sin q − 2 l (1 − cos q)/q, l (2 sin q/q − 1 − cos q))."""
    return (
        l * mpmath.sin(q) - 2 * l * (1 - mpmath.cos(q)) / q,
        l * (2 * mpmath.sin(q) / q - 1 - mpmath.cos(q)),
    )


@pytest.mark.parametrize(
    "name,unit", [("parallelogram", 1), ("parallelogram_mm", 1000), ("three_leg_stage", 1)]
)
@pytest.mark.parametrize("q", ["0.08", "-0.02", "1e-5"])
def test_stage_closed_form(name, unit, q):
    mech = zoo(name)
    d = Reference(mech).deviation({"F1": q})
    with mpmath.workdps(d["dps"]):
        qq = mpmath.mpf(q)
        L, l = mpmath.mpf("0.04") * unit, mpmath.mpf("0.005") * unit
        P0 = (mpmath.mpf("0.015") * unit, mpmath.mpf("0.05") * unit)
        # rigid: the legs turn about their pins; pins give f = l/2 (1 + cos), g = l/2 sin
        rigid = (P0[0] - L * mpmath.sin(qq), P0[1] - L * (1 - mpmath.cos(qq)))
        pin = stage_translation(qq, L, l, l / 2 * (1 + mpmath.cos(qq)), l / 2 * mpmath.sin(qq))
        assert dist(pin, (rigid[0] - P0[0], rigid[1] - P0[1])) < TOL * unit
        got = d["points"]["P"]
        assert dist(got["rigid"], rigid) < TOL * unit
        arc = stage_translation(qq, L, l, l * mpmath.sin(qq) / qq, l * (1 - mpmath.cos(qq)) / qq)
        assert dist(got["compliant"], (P0[0] + arc[0], P0[1] + arc[1])) < TOL * unit
        want = arc_deviation(qq, l)
        # the deviation to 20 significant digits of its size (it is ~l q^2/6)
        size = max(abs(want[0]), abs(want[1]))
        assert dist(got["deviation"], want) < size * mpmath.mpf("1e-20")
        assert abs(want[1] - l * qq**2 / 6) < l * qq**4  # the l·θ²/6 of the header


def test_stage_other_models_closed_form():
    mech = zoo("three_leg_stage")
    ref = Reference(mech)
    q = "0.15"
    with mpmath.workdps(DPS):
        qq = mpmath.mpf(q)
        L, l = mpmath.mpf("0.04"), mpmath.mpf("0.005")
        for model in ("small_deflection", "prbm"):
            sol = ref.solve({"F1": q}, model_override=model)
            f, g, _, _ = ref.fg("F1", qq, model_override=model)
            dx, dy = stage_translation(qq, L, l, f, g)
            assert (
                dist(sol["points"]["P"], (mpmath.mpf("0.015") + dx, mpmath.mpf("0.05") + dy)) < TOL
            )


@pytest.mark.parametrize("q1,q2", [("0.05", "-0.05"), ("0.03", "0.02"), ("-0.06", "0.01")])
def test_double_parallelogram_closed_form(q1, q2):
    # The intermediate body translates like a parallelogram stage (outer legs up, input q1);
    # the inner parallelogram is the same figure turned by pi (legs down, input q2), so the
    # stage adds its translation turned by pi. Units mm: L = 40, l = 4.
    d = Reference(zoo("double_parallelogram")).deviation({"F1": q1, "I1": q2})
    with mpmath.workdps(d["dps"]):
        a, b = mpmath.mpf(q1), mpmath.mpf(q2)
        L, l = mpmath.mpf(40), mpmath.mpf(4)
        rig_m = (-L * mpmath.sin(a), -L * (1 - mpmath.cos(a)))
        rig_s = (L * (mpmath.sin(b) - mpmath.sin(a)), L * (mpmath.cos(a) - mpmath.cos(b)))
        dev_m = arc_deviation(a, l)
        inner = arc_deviation(b, l)
        dev_s = (dev_m[0] - inner[0], dev_m[1] - inner[1])
        pts = d["points"]
        assert dist(pts["M"]["rigid"], (25 + rig_m[0], 40 + rig_m[1])) < TOL * 1000
        assert dist(pts["S"]["rigid"], (25 + rig_s[0], -5 + rig_s[1])) < TOL * 1000
        assert dist(pts["M"]["deviation"], dev_m) < mpmath.mpf("1e-20") * abs(mpmath.mpc(*dev_m))
        assert dist(pts["S"]["deviation"], dev_s) < mpmath.mpf("1e-20") * max(
            abs(mpmath.mpc(*dev_s)), abs(mpmath.mpc(*dev_m))
        )
        if a == -b:  # the folded design: the y-parts cancel exactly
            assert abs(pts["S"]["deviation"][1]) < mpmath.mpf("1e-25")
            assert abs(pts["S"]["rigid"][1] + 5) < TOL * 1000


@pytest.mark.parametrize("q", ["0.01", "0.02", "-0.01"])
def test_scott_russell_rigid_closed_form(q):
    # C is the circumcentre of O, A, B (OC = CA = CB = a), so AB is a diameter and OB ⟂ OA
    # (Thales): B = sqrt(4a² − |OA|²) · (−A_y, A_x)/|OA|, with A on the slider's circle,
    # A = (2a cos φ − R sin q, −R (1 − cos q)). Units mm.
    sol = Reference(zoo("scott_russell")).solve({"RA0": q}, model_override="rigid")
    with mpmath.workdps(DPS):
        qq, a, R = mpmath.mpf(q), mpmath.mpf(20), mpmath.mpf(50)
        phi = 10 * mpmath.pi / 180
        A = (2 * a * mpmath.cos(phi) - R * mpmath.sin(qq), -R * (1 - mpmath.cos(qq)))
        r = mpmath.hypot(*A)
        k = mpmath.sqrt(4 * a * a - r * r) / r
        assert dist(sol["points"]["A_out"], A) < TOL * 100
        assert dist(sol["points"]["B"], (-k * A[1], k * A[0])) < TOL * 100


def test_toggle_four_bar_stops_at_its_toggle():
    # The file puts the coupler–rocker toggle of the rigid linkage at q* = 0.35 rad exactly.
    ref = Reference(zoo("toggle_four_bar"))
    ref.solve({"O1": "0.3499"}, model_override="rigid")
    with pytest.raises(ReferenceAssemblyError, match="cannot continue"):
        ref.solve({"O1": "0.3501"}, model_override="rigid")


@pytest.mark.parametrize(
    "name,inputs",
    [
        ("roberts", {"O1": "0.1"}),
        ("lever_amplifier", {"P0": "0.01"}),
        ("scott_russell", {"RA0": "0.02"}),
        ("toggle_four_bar", {"O1": "0.3"}),
    ],
)
def test_zoo_deviation_small_and_precise(name, inputs):
    # Every point's deviation is nonzero, below the plate length (arc deviations are ~l θ²/12
    # per plate, passed on by factors of order one), and known to 20 digits.
    mech = zoo(name)
    d = Reference(mech).deviation(inputs)
    assert d["digits"] >= 20
    with mpmath.workdps(d["dps"]):
        l = mpmath.mpf(next(p.value for p in mech.parameters if p.name == "l"))
        for p, v in d["points"].items():
            assert 0 < abs(mpmath.mpc(*v["deviation"])) < l, (p, v["deviation"])
