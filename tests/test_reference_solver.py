"""Validate the independent reference solver (tests/reference_solver.py) against closed forms.

The reference is the oracle for symkin's derivation, so it is checked here only against results
derived by hand: composition of hinge transforms along open chains (complex numbers, circular-arc
chord geometry), the circle-intersection position solution of a four-bar, and the closed-form
deviation of a single circular-arc hinge.
"""

from __future__ import annotations

import math
import os
import sys

import mpmath
import pytest
import sympy as sp

import symkin

sys.path.insert(0, os.path.dirname(__file__))
from reference_solver import (
    Reference,
    ReferenceAssemblyError,
    ReferenceModelError,
)

EXAMPLES = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "examples")
DPS = 40
TOL = mpmath.mpf("1e-30")


def example(name):
    return symkin.load(os.path.join(EXAMPLES, name + ".toml"))


def from_text(tmp_path, text, name="mech.toml"):
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return symkin.load(path)


def num(mech, expr):
    """A file number as an mpf at the current precision (independent of the reference)."""
    return mpmath.mpf(sp.Float(sp.N(sp.sympify(expr).subs(mech.defaults), DPS + 20), DPS + 20))


def cnum(mech, xy):
    return mpmath.mpc(num(mech, xy[0]), num(mech, xy[1]))


# ---- closed forms -----------------------------------------------------------------------------
def chord(model, length, alpha, theta):
    """Vector from P's clamp to M's clamp in P's as-fabricated orientation (complex).

    circular_arc: an arc of length l turning by θ has radius l/θ; its chord has length
    2 (l/θ) sin(θ/2) and leaves the arc's start at half the turning angle, direction α + θ/2.
    rigid: half a plate to the pin at the midpoint, then the other half rotated by θ.
    """
    e = mpmath.expj(alpha)
    if model == "rigid":
        return length / 2 * e + mpmath.expj(theta) * length / 2 * e
    assert model == "circular_arc"
    if theta == 0:
        return length * e
    return 2 * length / theta * mpmath.sin(theta / 2) * mpmath.expj(alpha + theta / 2)


def hinge_numbers(mech, h):
    at = cnum(mech, h.at)
    alpha = num(mech, h.plate_angle)
    length = num(mech, h.length)
    u = mpmath.expj(alpha)
    return at - length / 2 * u, at + length / 2 * u, alpha, length


def across(mech, h, known_link, pose, theta, model):
    """Pose (z, φ) of the other link of hinge h, given the pose of `known_link`; a pose maps an
    as-fabricated point p to z + e^{iφ} p."""
    cp0, cm0, alpha, length = hinge_numbers(mech, h)
    z, phi = pose
    c = chord(model, length, alpha, theta)
    if known_link == h.links[0]:  # P known: M = P rotated by θ
        clamp_m = z + mpmath.expj(phi) * cp0 + mpmath.expj(phi) * c
        phi_m = phi + theta
        return clamp_m - mpmath.expj(phi_m) * cm0, phi_m
    assert known_link == h.links[1]  # M known: P = M rotated by −θ
    phi_p = phi - theta
    clamp_p = z + mpmath.expj(phi) * cm0 - mpmath.expj(phi_p) * c
    return clamp_p - mpmath.expj(phi_p) * cp0, phi_p


def place(pose, p0):
    return pose[0] + mpmath.expj(pose[1]) * p0


def four_bar_closed_form(mech, q, sigma=None):
    """Rigid four-bar (examples/four_bar.toml numbering) by circle intersection.

    A(q) = A0 + e^{iq}(A − A0); B(q) is on the circle |B − B0| = r and |B − A(q)| = c. With
    d = |A(q) − B0|, e = (A(q) − B0)/d: B = B0 + (a + iσh) e, a = (d² + r² − c²)/(2d),
    h = √(r² − a²). σ = ±1 is the branch; None picks the as-fabricated one (B(0) = B).
    Returns (rocker angle θ_B0, coupler angle, A(q), B(q), C(q), σ)."""
    A0, A, B0, B = (cnum(mech, mech.hinge(n).at) for n in ("A0", "A", "B0", "B"))
    C = cnum(mech, mech.point("C").at)
    r, c = abs(B - B0), abs(B - A)

    def solve(qq, s):
        Aq = A0 + mpmath.expj(qq) * (A - A0)
        d = abs(Aq - B0)
        e = (Aq - B0) / d
        a = (d * d + r * r - c * c) / (2 * d)
        h2 = r * r - a * a
        if h2 < 0:
            raise ValueError("out of range")
        return Aq, B0 + (a + 1j * s * mpmath.sqrt(h2)) * e

    if sigma is None:
        sigma = min((1, -1), key=lambda s: abs(solve(0, s)[1] - B))
        assert abs(solve(0, sigma)[1] - B) < TOL
    Aq, Bq = solve(q, sigma)
    rocker = mpmath.arg((Bq - B0) / (B - B0))
    coupler = mpmath.arg((Bq - Aq) / (B - A))
    Cq = Aq + mpmath.expj(coupler) * (C - A)
    return rocker, coupler, Aq, Bq, Cq, sigma


def cross(a, b):
    return a.real * b.imag - a.imag * b.real


# ---- (1) serial arm --------------------------------------------------------------------------
ARM = """
format = 1
name = "arm"
ground = "base"
[parameters]
l = 4e-3
[defaults]
model = "circular_arc"
length = "l"
[[link]]
name = "base"
[[link]]
name = "l1"
[[link]]
name = "l2"
[[hinge]]
name = "H1"
links = ["base", "l1"]
at = [0.01, 0.02]
plate_angle = "pi/3"
input = true
[[hinge]]
name = "H2"
links = {H2_LINKS}
at = [0.06, 0.03]
plate_angle = "-0.4"
length = "1.5*l"
input = true
[[point]]
name = "T"
link = "l2"
at = [0.1, 0.05]
[[point]]
name = "Q"
link = "l1"
at = [0.03, -0.01]
"""


@pytest.mark.parametrize("reverse", [False, True], ids=["P-to-M", "M-to-P"])
@pytest.mark.parametrize("q1,q2", [("0.7", "-1.1"), ("-0.25", "0.4"), ("1e-9", "2e-9")])
def test_serial_arm_matches_composed_transforms(tmp_path, reverse, q1, q2):
    links = '["l2", "l1"]' if reverse else '["l1", "l2"]'
    mech = from_text(tmp_path, ARM.replace("{H2_LINKS}", links))
    ref = Reference(mech)
    for model in ("circular_arc", "rigid"):
        sol = ref.solve({"H1": q1, "H2": q2}, model_override=None if model != "rigid" else "rigid")
        with mpmath.workdps(DPS):
            t1, t2 = mpmath.mpf(q1), mpmath.mpf(q2)
            base = (mpmath.mpc(0), mpmath.mpf(0))
            pose1 = across(mech, mech.hinge("H1"), "base", base, t1, model)
            pose2 = across(mech, mech.hinge("H2"), "l1", pose1, t2, model)
            for link, pose in (("l1", pose1), ("l2", pose2)):
                x, y, phi = sol["poses"][link]
                assert abs(mpmath.mpc(x, y) - pose[0]) < TOL
                assert abs(phi - pose[1]) < TOL
            for name, pose in (("T", pose2), ("Q", pose1)):
                want = place(pose, cnum(mech, mech.point(name).at))
                got = mpmath.mpc(*sol["points"][name])
                assert abs(got - want) < TOL, (model, name, got - want)
            assert abs(sol["angles"]["H1"] - t1) < TOL
            assert abs(sol["angles"]["H2"] - t2) < TOL


# ---- (2) rigid four-bar against circle intersection -----------------------------------------
@pytest.mark.parametrize("q", ["0.3", "-0.8", "1.7", "3.5", "6.0"])
def test_rigid_four_bar_matches_circle_intersection(q):
    mech = example("four_bar")
    sol = Reference(mech).solve({"A0": q}, model_override="rigid")
    with mpmath.workdps(DPS):
        rocker, coupler, _, _, Cq, _ = four_bar_closed_form(mech, mpmath.mpf(q))
        assert abs(sol["angles"]["B0"] - rocker) < TOL
        assert abs(sol["poses"]["rocker"][2] - rocker) < TOL
        assert abs(sol["poses"]["coupler"][2] - coupler) < TOL
        assert abs(sol["angles"]["A"] - (coupler - mpmath.mpf(q))) < TOL
        assert abs(sol["angles"]["B"] - (rocker - coupler)) < TOL
        assert abs(mpmath.mpc(*sol["points"]["C"]) - Cq) < TOL


# ---- (3) continuation keeps the as-fabricated branch -----------------------------------------
@pytest.mark.parametrize("q", ["0.5", "-0.5"])
def test_four_bar_branch_is_kept(q):
    mech = example("four_bar")
    ref = Reference(mech)
    _A0, A, B0, B = (cnum(mech, mech.hinge(n).at) for n in ("A0", "A", "B0", "B"))
    with mpmath.workdps(DPS):
        sign0 = mpmath.sign(cross(B - A, B0 - A))
        _, _, _, _, C_here, sigma = four_bar_closed_form(mech, mpmath.mpf(q))
        _, _, _, _, C_mirror, _ = four_bar_closed_form(mech, mpmath.mpf(q), -sigma)
        assert abs(C_here - C_mirror) > mpmath.mpf("0.01")
    for model in ("rigid", None):
        sol = ref.solve({"A0": q}, model_override=model)
        with mpmath.workdps(DPS):

            def at(link, p0):
                x, y, phi = sol["poses"][link]
                return mpmath.mpc(x, y) + mpmath.expj(phi) * p0

            Aq, Bq = at("crank", A), at("coupler", B)
            assert mpmath.sign(cross(Bq - Aq, B0 - Aq)) == sign0
            C = mpmath.mpc(*sol["points"]["C"])
            if model == "rigid":
                assert abs(C - C_here) < TOL
            else:  # within plate-size effects of the rigid C
                assert abs(C - C_here) < mpmath.mpf("1e-4") < abs(C - C_mirror)


# ---- (4) out of the assembly range -----------------------------------------------------------
NON_GRASHOF = """
format = 1
name = "non_grashof"
[parameters]
l = 1e-3
[defaults]
model = "circular_arc"
length = "l"
[[link]]
name = "frame"
[[link]]
name = "crank"
[[link]]
name = "coupler"
[[link]]
name = "rocker"
[[hinge]]
name = "A0"
links = ["frame", "crank"]
at = [0.0, 0.0]
plate_angle = "pi/2"
input = true
[[hinge]]
name = "A"
links = ["crank", "coupler"]
at = ["0.06*cos(pi/3)", "0.06*sin(pi/3)"]
[[hinge]]
name = "B0"
links = ["frame", "rocker"]
at = [0.1, 0.0]
plate_angle = "pi/2"
[[hinge]]
name = "B"
links = ["coupler", "rocker"]
at = [0.09, 0.07]
[[point]]
name = "C"
link = "coupler"
at = [0.06, 0.09]
"""


def test_non_grashof_four_bar_input_range(tmp_path):
    # ground g = 0.1, crank a = 0.06, coupler c = |B − A| ≈ 0.0626, rocker r = |B − B0| ≈ 0.0707:
    # s + l = 0.16 > p + q ≈ 0.133, non-Grashof. The crank reaches the toggle (coupler and rocker
    # in line, |A − B0| = c + r) at ψ = ±acos((a² + g² − (c + r)²) / (2ag)) from the ground line;
    # it starts at ψ = π/3, so θ_A0 ∈ [−ψmax − π/3, ψmax − π/3].
    mech = from_text(tmp_path, NON_GRASHOF)
    ref = Reference(mech)
    with mpmath.workdps(DPS):
        A0, A, B0, B = (cnum(mech, mech.hinge(n).at) for n in ("A0", "A", "B0", "B"))
        a, g, c, r = abs(A - A0), abs(B0 - A0), abs(B - A), abs(B - B0)
        assert a + g > c + r  # non-Grashof
        psi = mpmath.acos((a * a + g * g - (c + r) ** 2) / (2 * a * g))
        q_max, q_min = psi - mpmath.pi / 3, -psi - mpmath.pi / 3
        rocker = {}
        cases = {}
        # the rigid range is checked to 1e-3 rad; the compliant one differs by ~0.01 rad (the
        # hinge angles reach 1.5..3.2 rad at the toggles, where the arc and the pin differ by a
        # good fraction of l), so it gets wider margins
        for model, margin in (("rigid", mpmath.mpf("1e-3")), (None, mpmath.mpf("0.1"))):
            cases[model] = (
                (q_max - margin / 2, q_min + margin / 2),
                (q_max + margin, q_min - margin, mpmath.mpf(2)),
            )
            rocker[model] = [four_bar_closed_form(mech, q)[0] for q in cases[model][0]]
    for model, (inside, outside) in cases.items():
        for q, want in zip(inside, rocker[model]):
            sol = ref.solve({"A0": q}, model_override=model)
            with mpmath.workdps(DPS):
                assert abs(sol["angles"]["A0"] - q) < TOL
                if model == "rigid":
                    assert abs(sol["angles"]["B0"] - want) < TOL
        for q in outside:
            with pytest.raises(ReferenceAssemblyError, match="cannot continue"):
                ref.solve({"A0": q}, model_override=model)


def test_branch_kept_near_toggle_with_large_steps(tmp_path):
    # 1e-5 rad from the toggles, even with continuation steps as large as the whole range, the
    # safeguards (det J sign, correction size) keep the as-fabricated branch; without them the
    # max_step=3 runs land on another solution (rocker off by ~2π, checked when writing this).
    mech = from_text(tmp_path, NON_GRASHOF)
    ref = Reference(mech)
    with mpmath.workdps(DPS):
        A0, A, B0, B = (cnum(mech, mech.hinge(n).at) for n in ("A0", "A", "B0", "B"))
        a, g, c, r = abs(A - A0), abs(B0 - A0), abs(B - A), abs(B - B0)
        psi = mpmath.acos((a * a + g * g - (c + r) ** 2) / (2 * a * g))
        qs = (psi - mpmath.pi / 3 - mpmath.mpf("1e-5"), -psi - mpmath.pi / 3 + mpmath.mpf("1e-5"))
        want = [four_bar_closed_form(mech, q)[0] for q in qs]
    for max_step in (0.05, 1.0, 3.0):
        for q, rocker in zip(qs, want):
            sol = ref.solve({"A0": q}, model_override="rigid", max_step=max_step)
            with mpmath.workdps(DPS):
                assert abs(sol["angles"]["B0"] - rocker) < mpmath.mpf("1e-25")


def test_nine_bar_stops_at_its_dyad_limit():
    """Along q = t·(0.05, 0.03, −0.02, 0.04) the links b1..b4 are an open chain fixed by the four
    inputs; the dyads G-H-I (b5, b6) and C-D-E (b7, b8) close only while the distance between
    their end hinges stays within [| |XY| − |YZ| |, |XY| + |YZ|]. The first t* where one of them
    fails is the end of the rigid assembly range: the reference must stop exactly there."""
    mech = example("nine_bar_platform")
    direction = {"O": "0.05", "A": "0.03", "B": "-0.02", "K": "0.04"}
    with mpmath.workdps(DPS):
        at = {n: cnum(mech, mech.hinge(n).at) for n in ("G", "H", "I", "C", "D", "E")}

        def chain(t):
            poses, pose, link = {}, (mpmath.mpc(0), mpmath.mpf(0)), mech.ground
            for name in ("O", "A", "B", "K"):
                h = mech.hinge(name)
                pose = across(mech, h, link, pose, t * mpmath.mpf(direction[name]), "rigid")
                link = h.links[1]
                poses[link] = pose
            return poses

        def gaps(t):  # all must be ≤ 0 for the mechanism to assemble
            poses = chain(t)
            out = []
            for x, y, z, link in (("G", "H", "I", "b4"), ("C", "D", "E", "b3")):
                dist = abs(place(poses[link], at[x]) - at[z])
                a, b = abs(at[x] - at[y]), abs(at[y] - at[z])
                out += [dist - (a + b), abs(a - b) - dist]
            return out

        assert max(gaps(0)) < 0
        t, step = mpmath.mpf(0), mpmath.mpf("0.05")
        while max(gaps(t + step)) < 0:
            t += step
            assert t < 20, "no assembly limit found"
        k = max(range(4), key=lambda i: gaps(t + step)[i])
        t_star = mpmath.findroot(lambda s: gaps(s)[k], (t, t + step), solver="anderson")
        near = {n: mpmath.mpf(v) * (t_star - mpmath.mpf("1e-3")) for n, v in direction.items()}
        beyond = {n: mpmath.mpf(v) * (t_star + mpmath.mpf("1e-3")) for n, v in direction.items()}
    ref = Reference(mech)
    ref.solve(near, model_override="rigid")
    with pytest.raises(ReferenceAssemblyError, match="cannot continue"):
        ref.solve(beyond, model_override="rigid")


# ---- (5) single circular-arc hinge: closed-form deviation ------------------------------------
ONE_HINGE = """
format = 1
name = "one_hinge"
ground = "base"
[parameters]
l = 2e-3
[[link]]
name = "base"
[[link]]
name = "arm"
[[hinge]]
name = "H"
links = ["base", "arm"]
at = [0.02, -0.01]
plate_angle = "0.7"
length = "l"
model = "circular_arc"
input = true
[[point]]
name = "T"
link = "arm"
at = [0.09, 0.04]
[[point]]
name = "S"
link = "arm"
at = [-0.03, 0.05]
"""


@pytest.mark.parametrize("theta", ["1e-7", "0.3", "-0.3"])
def test_single_hinge_deviation_closed_form(tmp_path, theta):
    # Deviation = (f − f_rigid) u + (g − g_rigid) u⊥, the same for every point of the arm, and
    # l sinθ/θ − l(1 + cosθ)/2 = l(2 sin(θ/2)/θ − cos(θ/2)) cos(θ/2),
    # l(1 − cosθ)/θ − l sinθ/2 = l(2 sin(θ/2)/θ − cos(θ/2)) sin(θ/2):
    # ΔR = l (2 sin(θ/2)/θ − cos(θ/2)) (cos(α + θ/2), sin(α + θ/2)).
    mech = from_text(tmp_path, ONE_HINGE)
    d = Reference(mech).deviation({"H": theta})
    with mpmath.workdps(d["dps"]):
        t = mpmath.mpf(theta)
        l, alpha = mpmath.mpf("2e-3"), mpmath.mpf("0.7")
        mag = l * (2 * mpmath.sin(t / 2) / t - mpmath.cos(t / 2))
        want = (mag * mpmath.cos(alpha + t / 2), mag * mpmath.sin(alpha + t / 2))
        for name in ("T", "S"):
            dev = d["points"][name]["deviation"]
            err = max(abs(dev[0] - want[0]), abs(dev[1] - want[1]))
            assert err < abs(mag) * mpmath.mpf("1e-20"), (name, err, mag)
    if theta == "1e-7":  # |ΔR| ≈ lθ²/12 ≈ 2e-18: 17 digits lost, dps raised
        assert d["dps"] > DPS and d["digits"] >= 20


# ---- precision: tiny plates -------------------------------------------------------------------
def test_tiny_plates_raise_precision():
    mech = example("four_bar")
    ref = Reference(mech, params={"l": "1e-20"})
    d = ref.deviation({"A0": "0.2"})
    assert d["dps"] > DPS and d["digits"] >= 20
    high = ref.deviation({"A0": "0.2"}, dps=100)
    with mpmath.workdps(100):
        a, b = d["points"]["C"]["deviation"], high["points"]["C"]["deviation"]
        assert abs(a[0] - b[0]) + abs(a[1] - b[1]) < mpmath.mpf("1e-20") * abs(mpmath.mpc(*b))
        # the deviation is linear in l for small plates (second-order term ~ l/0.1 relative)
        base = Reference(mech, params={"l": "1e-10"}).deviation({"A0": "0.2"})["points"]["C"]
        ratio = mpmath.mpc(*b) / mpmath.mpc(*base["deviation"]) * mpmath.mpf("1e-10") / 1e-20
        assert abs(ratio - 1) < mpmath.mpf("1e-7")


# ---- the examples assemble, deviations are small and nonzero --------------------------------
EXAMPLE_INPUTS = [
    ("four_bar", {"A0": "0.2"}),
    ("stephenson_six_bar", {"O_A": "0.2"}),
    ("nine_bar_platform", {"O": "0.05", "A": "0.03", "B": "-0.02", "K": "0.04"}),
]


@pytest.mark.parametrize("name,inputs", EXAMPLE_INPUTS, ids=[n for n, _ in EXAMPLE_INPUTS])
def test_examples_assemble_with_small_deviation(name, inputs):
    # Bound: each hinge displaces M's clamp by |Δz_a| = |(f − f_rigid, g − g_rigid)| at its
    # angle (for circular arcs ≈ lθ²/12, for the PRBM hinge first order in θ); the loops pass
    # these on with factors of order one (link-length ratios), so |ΔR| ≤ 5 Σ|Δz_a| (measured
    # ratios 0.85, 0.44, 0.013) and |ΔR| < 0.1 l at these angles (measured 0.008 l at most).
    mech = example(name)
    ref = Reference(mech)
    d = ref.deviation(inputs)
    assert d["digits"] >= 20
    with mpmath.workdps(d["dps"]):
        total = mpmath.mpf(0)
        for h in mech.hinges:
            th = d["angles"]["rigid"][h.name]
            fc, gc, _, _ = ref.fg(h.name, th, dps=d["dps"])
            fr, gr, _, _ = ref.fg(h.name, th, model_override="rigid", dps=d["dps"])
            total += mpmath.hypot(fc - fr, gc - gr)
        l = num(mech, mech.hinges[0].length)
        for q_name, q in inputs.items():
            for which in ("rigid", "compliant"):
                assert abs(d["angles"][which][q_name] - mpmath.mpf(q)) < TOL
        for p, v in d["points"].items():
            dev = mpmath.hypot(*v["deviation"])
            assert 1e-3 * total < dev <= 5 * total, (p, dev, total)
            assert dev < l / 10


def test_nine_bar_point_on_input_chain_is_open_chain_exact():
    # F is on b2; b1 and b2 are fixed by the input hinges O and A alone, so F (rigid and
    # compliant) follows from composing the two hinge transforms.
    mech = example("nine_bar_platform")
    inputs = dict(EXAMPLE_INPUTS[2][1])
    d = Reference(mech).deviation(inputs)
    with mpmath.workdps(DPS):
        F0 = cnum(mech, mech.point("F").at)
        out = {}
        for model in ("rigid", "circular_arc"):
            pose = (mpmath.mpc(0), mpmath.mpf(0))
            pose = across(mech, mech.hinge("O"), "frame", pose, mpmath.mpf(inputs["O"]), model)
            pose = across(mech, mech.hinge("A"), "b1", pose, mpmath.mpf(inputs["A"]), model)
            out[model] = place(pose, F0)
        got = d["points"]["F"]
        assert abs(mpmath.mpc(*got["rigid"]) - out["rigid"]) < TOL
        assert abs(mpmath.mpc(*got["compliant"]) - out["circular_arc"]) < TOL
        assert abs(mpmath.mpc(*got["deviation"]) - (out["circular_arc"] - out["rigid"])) < TOL


# ---- model plumbing ---------------------------------------------------------------------------
def test_zero_inputs_give_the_as_fabricated_pose():
    for name, inputs in EXAMPLE_INPUTS:
        sol = Reference(example(name)).solve(dict.fromkeys(inputs, 0))
        for x, y, phi in sol["poses"].values():
            assert max(abs(x), abs(y), abs(phi)) < TOL


def test_expr_model_equals_circular_arc(tmp_path):
    with open(os.path.join(EXAMPLES, "four_bar.toml"), encoding="utf-8") as fh:
        text = fh.read()
    text = text.replace(
        'model = "circular_arc"',
        'model = "expr"\nf = "l*sin(theta)/theta"\ng = "l*(1 - cos(theta))/theta"',
    )
    mech = from_text(tmp_path, text)
    assert all(h.model == "expr" for h in mech.hinges)
    a = Reference(mech).deviation({"A0": "0.2"})["points"]["C"]["deviation"]
    b = Reference(example("four_bar")).deviation({"A0": "0.2"})["points"]["C"]["deviation"]
    with mpmath.workdps(DPS):
        assert abs(a[0] - b[0]) + abs(a[1] - b[1]) < mpmath.mpf("1e-32")


@pytest.mark.parametrize(
    "model", ["rigid", "circular_arc", "small_deflection", "prbm", "elastica_force"]
)
def test_model_derivatives(model):
    ref = Reference(example("four_bar"))
    dps = 30
    with mpmath.workdps(dps):
        for theta in ("0", "1e-12", "0.4", "-0.9"):
            t = mpmath.mpf(theta)
            _f, _g, df, dg = ref.fg("A", t, model_override=model, dps=dps)
            # mpmath.diff raises the working precision: evaluate the model at that precision
            num_df, num_dg = (
                mpmath.diff(lambda s: ref.fg("A", s, model_override=model, dps=mpmath.mp.dps)[k], t)
                for k in (0, 1)
            )
            assert abs(df - num_df) < mpmath.mpf("1e-25") and abs(dg - num_dg) < mpmath.mpf("1e-25")
        f0, g0, _, _ = ref.fg("A", 0, model_override=model, dps=dps)
        assert abs(f0 - mpmath.mpf("1e-3")) < mpmath.mpf("1e-28") and abs(g0) < mpmath.mpf("1e-28")


def test_jacobian_matches_finite_differences():
    mech = example("stephenson_six_bar")
    ref = Reference(mech)
    with mpmath.workdps(DPS):
        hinges, _, _ = ref._setup(None, DPS)
        X = [
            mpmath.mpf(k % 7 - 3) / 97 * (mpmath.mpf("0.01") if k % 3 != 2 else 1)
            for k in range(ref.n_unknowns)
        ]
        q = {"O_A": mpmath.mpf("0.1")}
        _, J = ref._system(X, q, hinges)
        h = mpmath.mpf("1e-15")
        for j in range(ref.n_unknowns):
            up = list(X)
            up[j] += h
            dn = list(X)
            dn[j] -= h
            Fu, _ = ref._system(up, q, hinges)
            Fd, _ = ref._system(dn, q, hinges)
            for i in range(len(Fu)):
                assert abs((Fu[i] - Fd[i]) / (2 * h) - J[i][j]) < mpmath.mpf("1e-25")


def test_elastica_force_against_ode_shooting():
    """Shoot the elastica φ'' = −α cos φ (s ∈ [0, 1], φ(0) = 0) on (α, φ'(0)) so that
    φ'(1) = 0 (no tip moment) and φ(1) = θ; the tip (x(1), y(1)) is (f/l, g/l)."""
    from scipy.integrate import solve_ivp
    from scipy.optimize import fsolve

    def tip(params):
        alpha, k0 = params
        sol = solve_ivp(
            lambda s, y: [y[1], -alpha * math.cos(y[0]), math.cos(y[0]), math.sin(y[0])],
            (0, 1),
            [0.0, k0, 0.0, 0.0],
            rtol=1e-12,
            atol=1e-13,
        )
        return sol.y[:, -1]

    ref = Reference(example("four_bar"))
    for theta in (0.05, 0.5, -1.0):

        def eqs(p):
            phi1, k1, _, _ = tip(p)
            return [k1, phi1 - theta]

        alpha, k0 = fsolve(eqs, [2 * theta, 2 * theta], xtol=1e-13)
        _, _, x1, y1 = tip((alpha, k0))
        f, g, _, _ = ref.fg("A", theta, model_override="elastica_force", dps=25)
        assert abs(float(f) / 1e-3 - x1) < 1e-9 and abs(float(g) / 1e-3 - y1) < 1e-9
    with pytest.raises(ReferenceModelError):
        ref.fg("A", 1.6, model_override="elastica_force")


def test_elastica_force_four_bar_solves():
    ref = Reference(example("four_bar"))
    sol = ref.solve({"A0": "0.2"}, model_override="elastica_force", dps=20)
    rigid = ref.solve({"A0": "0.2"}, model_override="rigid", dps=20)
    with mpmath.workdps(20):
        dev = abs(mpmath.mpc(*sol["points"]["C"]) - mpmath.mpc(*rigid["points"]["C"]))
        assert 0 < dev < mpmath.mpf("1e-4")


def test_bad_requests():
    ref = Reference(example("four_bar"))
    with pytest.raises(KeyError):
        ref.solve({"A": "0.1"})
    with pytest.raises(ValueError):
        ref.solve({"A0": "0.1"}, model_override="table")
    with pytest.raises(KeyError):
        Reference(example("four_bar"), params={"nope": 1})
