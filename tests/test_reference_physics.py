"""Validate the physical reference (tests/reference_physics.py) against independent truths.

The reference is the oracle for symkin's ``equilibrium`` and ``loaded`` levels, so it is checked
here only against results that do not come from symkin: closed forms (circular arc under a pure
end moment, the clamped–guided plate, Euler's buckling loads), published elastica tables
(Bisshopp & Drucker 1945; Mattiasson 1981), energy consistency (the actuator torque is the
derivative of the potential energy with respect to the input angle), and its two methods against
each other — (a) Taylor-series shooting of the exact elastica in a force formulation and (b)
Hencky chains in a potential-energy formulation extrapolated over the segment count — which share
no mechanics, only the geometry reader and the rigid pin linkage.

Measured agreement of (a) and (b) on the deviation of the coupler point (relative, this run's
code, levels N = 16..128): four-bar 2e-27..5e-20 for l = 0.2, 1, 5 mm and A0 = 0.02..0.3; 5e-20
at the corner l/L = 1e-3, A0 = 0.5 and 6e-17 at l/L = 0.2; six-bar 6e-21; with a load on C 1e-21;
plates of different thickness 3e-22. (b)'s own Richardson estimate is more cautious (1e-13..1e-21).

Kinematic circular-arc model (level exact, tests/reference_solver.py) against the elastica,
four-bar without loads, relative gap |ΔR_arc − ΔR_elastica| / |ΔR_elastica| at point C, measured
with this reference:

    l \\ A0     0.02     0.05     0.1      0.3
    0.2 mm    4.01 %   1.73 %   0.97 %   0.49 %
    1 mm     18.05 %   8.28 %   4.72 %   2.39 %
    5 mm     56.37 %  32.91 %  20.50 %  10.92 %

which reproduces the published side measurements (18 / 8 / 4.7 / 2.4 % at 1 mm; 56 → 11 % at
5 mm; 4 → 0.5 % at 0.2 mm).
"""

from __future__ import annotations

import mpmath
import pytest
from conftest import EXAMPLES
from reference_physics import (
    ChainEquilibrium,
    ContinuationError,
    Equilibrium,
    InstabilityError,
    Load,
    point_load,
)
from reference_solver import Reference

import symkin

STEEL = (210e9, 5e-3, "l/10")  # E (Pa), width (m), thickness = l/10

# one plate of length L from the ground (clamp at the origin) to a free link "tip"; the input
# hinge A is either held (an angle) or released (None)
CANTILEVER = """
format = 1
name = "cantilever"
[parameters]
L = 1
[[link]]
name = "ground"
[[link]]
name = "tip"
[[hinge]]
name = "A"
links = ["ground", "tip"]
at = ["L/2", 0]
length = "L"
input = true
[[point]]
name = "T"
link = "tip"
at = ["L", 0]
"""
UNIT = (12, 1, 1)  # EI = 12·1·1³/12 = 1


@pytest.fixture(scope="module")
def cantilever():
    return symkin.loads(CANTILEVER)


@pytest.fixture(scope="module")
def four_bar():
    return symkin.load(EXAMPLES / "four_bar.toml")


def norm(v):
    return mpmath.sqrt(v[0] ** 2 + v[1] ** 2)


def rel(got, want) -> float:
    with mpmath.workdps(60):
        return float(norm((got[0] - want[0], got[1] - want[1])) / norm(want))


def rel_scalar(got, want) -> float:
    with mpmath.workdps(60):
        return float(abs(got - want) / abs(want))


# ---- pure end moment: the exact circular arc ------------------------------------------------
@pytest.mark.parametrize("method", [Equilibrium, ChainEquilibrium])
@pytest.mark.parametrize("theta", ["0.01", "0.3", "-1.2"])
def test_pure_moment_bends_the_plate_into_a_circular_arc(cantilever, method, theta):
    """An input plate with nothing else acting carries only its end moment: the M clamp sits at
    (l sinθ/θ, l(1 − cosθ)/θ), the moment is EI·θ/l (= the actuator torque), the energy
    EI·θ²/(2l); the deviation from the midpoint pin is |d|(cos θ/2, sin θ/2) with
    |d|/l = 2 sin(θ/2)/θ − cos(θ/2)."""
    L, t = "3e-3", "L/10"
    res = method(cantilever, (210e9, 5e-3, t), params={"L": L}).solve({"A": theta})
    tol = 1e-25 if method is Equilibrium else 1e-11
    with mpmath.workdps(60):
        l, th = mpmath.mpf(L), mpmath.mpf(theta)
        EI = mpmath.mpf("210e9") * mpmath.mpf("5e-3") * (l / 10) ** 3 / 12
        tip = (l * mpmath.sin(th) / th, l * 2 * mpmath.sin(th / 2) ** 2 / th)
        d = l * (2 * mpmath.sin(th / 2) / th - mpmath.cos(th / 2))
        dev = (d * mpmath.cos(th / 2), d * mpmath.sin(th / 2))
        assert rel(res["points"]["T"]["compliant"], tip) < tol
        assert rel(res["points"]["T"]["deviation"], dev) < tol
        assert rel_scalar(res["hinges"]["A"]["moment"], EI * th / l) < tol
        assert rel_scalar(res["actuators"]["A"], EI * th / l) < tol
        assert rel_scalar(res["energy"], EI * th**2 / (2 * l)) < tol
        assert norm(res["hinges"]["A"]["force"]) < tol * EI / l**2


@pytest.mark.parametrize("method", [Equilibrium, ChainEquilibrium])
def test_dead_moment_on_a_free_link_bends_the_plate_into_a_circular_arc(cantilever, method):
    """A CCW load moment Mz on the released tip link: θ = Mz·l/EI exactly, the arc again, and the
    link passes Mz to the plate (moment +Mz at the M end). EI = 1, l = 1."""
    res = method(cantilever, UNIT, loads=[Load("tip", (1, 0), (0, 0), "0.7")]).solve({"A": None})
    tol = 1e-25 if method is Equilibrium else 1e-11
    with mpmath.workdps(50):
        th = mpmath.mpf("0.7")
        assert abs(res["angles"]["A"] - th) < tol
        assert (
            rel(res["points"]["T"]["compliant"], (mpmath.sin(th) / th, (1 - mpmath.cos(th)) / th))
            < tol
        )
        assert abs(res["hinges"]["A"]["moment"] - th) < tol


def test_small_combined_end_loads_follow_linear_beam_theory(cantilever):
    """Released cantilever, transverse V and moment M at the tip (both ~1e-3 EI/l): end rotation
    (M l + V l²/2)/EI and sideways deflection (M l²/2 + V l³/3)/EI, up to O(load²)."""
    V, M = mpmath.mpf("1e-3"), mpmath.mpf("-2e-3")
    res = Equilibrium(cantilever, UNIT, loads=[Load("tip", (1, 0), (0, V), M)]).solve({"A": None})
    theta, dy = res["angles"]["A"], res["points"]["T"]["compliant"][1]
    assert rel_scalar(theta, M + V / 2) < 1e-5
    assert rel_scalar(dy, M / 2 + V / 3) < 1e-5


# ---- cantilever under a transverse end force: published elastica tables ---------------------
BISSHOPP_DRUCKER = [
    # α = F L²/EI, tip angle (deg), 1 − x/L, y/L  (Bisshopp & Drucker 1945)
    (1, "26.4335196", "0.0564332363", "0.301720774"),
    (2, "44.790966", "0.160641721", "0.49345748"),
    (5, "69.6354637", "0.387628361", "0.713791524"),
]


def half_unit(text: str) -> float:
    """Half a unit in the last digit given."""
    decimals = len(text.split(".")[1]) if "." in text else 0
    return 0.5 * 10.0**-decimals


@pytest.mark.parametrize("method", [Equilibrium, ChainEquilibrium])
@pytest.mark.parametrize("alpha, angle, dx, dy", BISSHOPP_DRUCKER)
def test_cantilever_matches_bisshopp_drucker(cantilever, method, alpha, angle, dx, dy):
    """Released input (no actuator), dead transverse force F at the tip, α = F·L²/EI."""
    load = Load("tip", (1, 0), (0, alpha))
    res = method(cantilever, UNIT, loads=[load]).solve({"A": None})
    x, y = res["points"]["T"]["compliant"]
    deg = res["angles"]["A"] * 180 / mpmath.pi
    assert abs(float(deg) - float(angle)) <= half_unit(angle)
    assert abs(float(1 - x) - float(dx)) <= half_unit(dx)
    assert abs(float(y) - float(dy)) <= half_unit(dy)
    # the link holds the load: it exerts +F on the plate, and no moment at a free tip
    assert abs(float(res["hinges"]["A"]["force"][1]) - alpha) < 1e-20
    assert abs(float(res["hinges"]["A"]["moment"])) < 1e-11


@pytest.mark.parametrize("method", [Equilibrium, ChainEquilibrium])
def test_cantilever_matches_mattiasson_at_load_index_10(cantilever, method):
    res = method(cantilever, UNIT, loads=[Load("tip", (1, 0), (0, 10))]).solve({"A": None})
    x, y = res["points"]["T"]["compliant"]
    assert abs(float(y) - 0.81061) <= 0.5e-5
    assert abs(float(1 - x) - 0.55500) <= 0.5e-5
    assert abs(float(res["angles"]["A"]) - 1.430286) <= 0.5e-6


# ---- clamped–guided plate: the small-load limit --------------------------------------------
@pytest.mark.parametrize("method", [Equilibrium, ChainEquilibrium])
def test_clamped_guided_plate_small_load_limit(cantilever, method):
    """Input held at 0 (end rotation fixed), transverse V at the M clamp: the end moves sideways
    by V l³/(12 EI) and shortens by 3δ²/(5l); the M end carries the moment −V l/2 (the moment
    is antisymmetric), held by the actuator. Nonlinear corrections are O(α²), α = V l²/EI."""
    errs = []
    for alpha in ("1e-3", "2e-3"):
        res = method(cantilever, UNIT, loads=[Load("tip", (1, 0), (0, alpha))]).solve({"A": 0})
        a = mpmath.mpf(alpha)
        dx, dy = res["points"]["T"]["deviation"]
        delta = a / 12
        errs.append(rel_scalar(dy, delta))
        assert rel_scalar(dy, delta) < 1e-5
        assert rel_scalar(dx, -3 * delta**2 / 5) < 1e-4
        assert rel_scalar(res["hinges"]["A"]["moment"], -a / 2) < 1e-5
        assert rel_scalar(res["actuators"]["A"], -a / 2) < 1e-5
    # the residual is the quadratic nonlinear correction, not a numerical floor
    assert 3.5 < errs[1] / errs[0] < 4.5


# ---- energy consistency ----------------------------------------------------------------------
@pytest.mark.parametrize(
    "method, loaded", [(Equilibrium, False), (Equilibrium, True), (ChainEquilibrium, False)]
)
def test_actuator_torque_is_the_derivative_of_the_potential(four_bar, method, loaded):
    """τ = d(E − W)/dθ_input, W the work of the dead loads (central differences, step 1e-6)."""
    q, h = mpmath.mpf("0.2"), mpmath.mpf("1e-6")
    loads = [point_load(four_bar, "C", ("0.5", "-1"))] if loaded else []
    solver = method(four_bar, STEEL, loads=loads)

    def potential(res):
        with mpmath.workdps(res["dps"]):
            c = res["points"]["C"]["compliant"]
            c0 = (mpmath.mpf("0.06"), mpmath.mpf("0.09"))
            work = mpmath.mpf("0.5") * (c[0] - c0[0]) - (c[1] - c0[1]) if loaded else 0
            return res["energy"] - work

    mid = solver.solve({"A0": q})
    plus = solver.solve({"A0": q + h})
    minus = solver.solve({"A0": q - h})
    with mpmath.workdps(50):
        derivative = (potential(plus) - potential(minus)) / (2 * h)
        assert rel_scalar(derivative, mid["actuators"]["A0"]) < 1e-9


# ---- the two methods agree ------------------------------------------------------------------
def assert_methods_agree(mech, stiffness, inputs, loads=(), params=None, tol=1e-11):
    a = Equilibrium(mech, stiffness, loads=loads, params=params).solve(inputs)
    b = ChainEquilibrium(mech, stiffness, loads=loads, params=params).solve(inputs)
    for name, p in a["points"].items():
        err = rel(b["points"][name]["deviation"], p["deviation"])
        assert err < tol, (name, err)
        # (b)'s Richardson estimate bounds the measured difference, and is itself small
        assert err <= 10 * b["error_estimate"] + 1e-18
    assert b["error_estimate"] < 100 * tol
    assert a["error_estimate"] < 1e-20
    for h, v in a["hinges"].items():
        scale = norm(v["force"]) * mpmath.mpf(1e-3) + abs(v["moment"])  # N·m, lever 1 mm
        assert abs(b["hinges"][h]["moment"] - v["moment"]) < tol * scale
        assert norm([b["hinges"][h]["force"][k] - v["force"][k] for k in range(2)]) < tol * (
            norm(v["force"]) + abs(v["moment"]) / mpmath.mpf(1e-3)
        )
    assert rel_scalar(b["energy"], a["energy"]) < tol
    for h, v in a["actuators"].items():
        assert rel_scalar(b["actuators"][h], v) < tol
    return a, b


@pytest.mark.parametrize("l", ["0.2e-3", "1e-3", "5e-3"])
@pytest.mark.parametrize("q", ["0.02", "0.1", "0.3"])
def test_methods_agree_on_the_four_bar(four_bar, l, q):
    assert_methods_agree(four_bar, STEEL, {"A0": q}, params={"l": l})


@pytest.mark.parametrize(
    "l, q", [("1e-4", "0.01"), ("1e-4", "0.5"), ("2e-2", "0.01"), ("2e-2", "0.5")]
)
def test_methods_agree_at_the_corners_of_the_accuracy_range(four_bar, l, q):
    """l/L from 1e-3 to 0.2 (L = 0.1 m, the frame), input angle 0.01 to 0.5 rad."""
    assert_methods_agree(four_bar, STEEL, {"A0": q}, params={"l": l})


def test_methods_agree_with_plates_of_different_thickness(four_bar):
    stiffness = {
        "A0": (210e9, 5e-3, "l/10"),
        "A": (210e9, 5e-3, "l/20"),
        "B0": (70e9, 8e-3, "l/8"),
        "B": (210e9, 5e-3, "l/15"),
    }
    assert_methods_agree(four_bar, stiffness, {"A0": "0.1"})


def test_methods_agree_with_a_load_on_the_coupler_point(four_bar):
    """(0.5, −1) N at C moves C by ~1 µm (half the unloaded deviation at A0 = 0.1); the plates'
    Euler loads are ~800 N, far away."""
    load = [point_load(four_bar, "C", ("0.5", "-1"))]
    a, _ = assert_methods_agree(four_bar, STEEL, {"A0": "0.1"}, loads=load)
    free = Equilibrium(four_bar, STEEL).solve({"A0": "0.1"})
    moved = rel(a["points"]["C"]["deviation"], free["points"]["C"]["deviation"])
    assert 0.2 < moved < 1


def test_methods_agree_with_a_pin(four_bar):
    """A `rigid` hinge stays an ideal pin: zero moment, and its force is a Lagrange multiplier
    in (b) and an unknown of the balance in (a)."""
    text = (
        (EXAMPLES / "four_bar.toml")
        .read_text()
        .replace(
            'at = [0.085, 0.068]\nplate_angle = "0"',
            'at = [0.085, 0.068]\nplate_angle = "0"\nmodel = "rigid"',
        )
    )
    mech = symkin.loads(text)
    assert mech.hinge("B").model == "rigid"
    stiffness = dict.fromkeys(("A0", "A", "B0"), STEEL)
    a, _ = assert_methods_agree(
        mech, stiffness, {"A0": "0.2"}, loads=[point_load(mech, "C", (0, "-1"))]
    )
    assert a["hinges"]["B"]["moment"] == 0 and norm(a["hinges"]["B"]["force"]) > 0.1


def test_methods_agree_on_the_stephenson_six_bar():
    mech = symkin.load(EXAMPLES / "stephenson_six_bar.toml")
    assert_methods_agree(mech, STEEL, {"O_A": "0.2"})


# ---- plausibility against the published side measurements ----------------------------------
@pytest.mark.parametrize(
    "l, q, published",
    [
        ("1e-3", "0.02", 0.18),
        ("1e-3", "0.05", 0.08),
        ("1e-3", "0.1", 0.047),
        ("1e-3", "0.3", 0.024),
        ("5e-3", "0.02", 0.56),
        ("5e-3", "0.3", 0.11),
        ("0.2e-3", "0.02", 0.04),
        ("0.2e-3", "0.3", 0.005),
    ],
)
def test_kinematic_gap_matches_the_published_measurements(four_bar, l, q, published):
    """Relative gap between the circular-arc exact deviation and the elastica's (no loads)."""
    elastica = Equilibrium(four_bar, STEEL, params={"l": l}).solve({"A0": q})
    arc = Reference(four_bar, {"l": l}).deviation({"A0": q})
    gap = rel(arc["points"]["C"]["deviation"], elastica["points"]["C"]["deviation"])
    assert published / 1.5 < gap < published * 1.5


def test_no_input_and_no_load_is_the_as_fabricated_pose(four_bar):
    """Nothing moves: the deviation and the energy are zero up to rounding at 40 digits."""
    res = Equilibrium(four_bar, STEEL).solve({"A0": 0})
    assert norm(res["points"]["C"]["deviation"]) < 1e-38 and abs(res["energy"]) < 1e-45
    assert all(abs(h["moment"]) < 1e-38 for h in res["hinges"].values())


# ---- the plate integrator and the extensible variant -----------------------------------------
@pytest.mark.parametrize("eps", ["0", "0.01"])
def test_plate_integrator_matches_an_independent_ode_solver(eps):
    """shoot() (fixed-point Taylor series, variational equations) against mpmath.odefun on a
    strongly bent, loaded plate; its Jacobian against central differences."""
    from reference_physics import shoot

    with mpmath.workdps(40):
        u0, mu0, fx, fy = (mpmath.mpf(v) for v in ("0.7", "0.9", "2.5", "-3"))
        e = mpmath.mpf(eps)
        out, jac, energy, _ = shoot(u0, mu0, fx, fy, 160, True, True, eps=e)
        args = (u0, mu0, fx, fy)
        for j in range(4):
            h = mpmath.mpf("1e-15")
            plus = shoot(*[a + h * (i == j) for i, a in enumerate(args)], 160, False, eps=e)[0]
            minus = shoot(*[a - h * (i == j) for i, a in enumerate(args)], 160, False, eps=e)[0]
            for i in range(4):
                assert abs((plus[i] - minus[i]) / (2 * h) - jac[i][j]) < 1e-20
    with mpmath.workdps(20):

        def rhs(s, y):
            u, mu = y[0], y[1]
            c, sn = mpmath.cos(u), mpmath.sin(u)
            n_t = fx * c + fy * sn
            grow = 1 + e * n_t
            return [mu, grow * (fx * sn - fy * c), grow * c, grow * sn, mu**2 + e * n_t**2]

        end = mpmath.odefun(rhs, 0, [u0, mu0, 0, 0, 0])(1)
        for got, want in zip((out[0], out[3], out[1], out[2], energy), end):
            assert abs(got - want) < 1e-16


@pytest.mark.parametrize("force", ["3", "-1.5"])
def test_extensible_plate_under_axial_load_stretches_by_n_l_over_ea(cantilever, force):
    """A straight plate under an axial end force F stays straight and stretches by F·l/EA
    (below Euler's load in compression); the energy is F²l/(2EA). EI = 1, EA = 12."""
    res = Equilibrium(
        cantilever, UNIT, loads=[Load("tip", (1, 0), (force, 0))], extensible=True
    ).solve({"A": None})
    f = mpmath.mpf(force)
    dx, dy = res["points"]["T"]["deviation"]
    assert abs(dx - f / 12) < 1e-25 and abs(dy) < 1e-25
    assert abs(res["energy"] - f**2 / 24) < 1e-25
    with pytest.raises(NotImplementedError):
        ChainEquilibrium(cantilever, UNIT, extensible=True)


def test_extensible_actuator_torque_is_the_derivative_of_the_potential(four_bar):
    q, h = mpmath.mpf("0.2"), mpmath.mpf("1e-6")
    solver = Equilibrium(
        four_bar, STEEL, loads=[point_load(four_bar, "C", ("0.5", "-1"))], extensible=True
    )

    def potential(res):
        c = res["points"]["C"]["compliant"]
        return res["energy"] - (
            mpmath.mpf("0.5") * (c[0] - mpmath.mpf("0.06")) - (c[1] - mpmath.mpf("0.09"))
        )

    with mpmath.workdps(50):
        mid = solver.solve({"A0": q})
        derivative = (
            potential(solver.solve({"A0": q + h})) - potential(solver.solve({"A0": q - h}))
        ) / (2 * h)
        assert rel_scalar(derivative, mid["actuators"]["A0"]) < 1e-9


# ---- loss of stability ----------------------------------------------------------------------
@pytest.mark.parametrize("method, tol", [(Equilibrium, 1e-5), (ChainEquilibrium, 1e-2)])
@pytest.mark.parametrize("held, euler", [(None, 0.25), ("0", 1.0)])
def test_axial_compression_beyond_euler_raises(cantilever, method, tol, held, euler):
    """Axial dead load P = 12 EI/L² at the tip: the free cantilever buckles at π²EI/(4L²), the
    clamped–guided one (input held) at π²EI/L². The error names the plate and the load factor
    reached ≈ P_cr / P; (b)'s 16-segment chain buckles O(h²) early. Below P_cr nothing raises."""
    p_cr = euler * float(mpmath.pi**2)
    solver = method(cantilever, UNIT, loads=[Load("tip", (1, 0), (-12, 0))])
    with pytest.raises(InstabilityError) as info:
        solver.solve({"A": held})
    assert info.value.hinge == "A"
    assert abs(info.value.load_factor - p_cr / 12) < tol * p_cr / 12
    assert "A" in str(info.value) and "load factor" in str(info.value)
    solver.solve({"A": held}, load_factor=0.95 * p_cr / 12)


def test_continuation_error_is_a_physics_error():
    assert issubclass(InstabilityError, ContinuationError)
