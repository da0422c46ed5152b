"""A notch as a beam whose section varies (symkin.physics.section_beams) and at `equilibrium`:
the shot against an independent scipy shooting of the same variable-section Reissner beam, the
linear compliances against mpmath quadrature of the Euler–Bernoulli integrals at 40 digits, the
thin-notch limit of Paros & Weisbord, a single notch held at an angle (a pure moment: the
`pure_moment` shape), the stress with its K_t, and the generated `loaded` refusing a notch
(`loaded` itself takes notches: tests/test_notch_loaded.py)."""

from __future__ import annotations

import math

import mpmath
import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp
from test_notches import four_bar

import symkin
from symkin.core.errors import InputError
from symkin.model import notches
from symkin.physics.section_beams import SectionGrid, shoot_profile

B, E, NU = 5e-3, 210e9, 0.3
EP = E / (1 - NU**2)  # b ≥ 5 t: plane strain
G = E / (2 * (1 + NU))


def circular(radius, thickness, continuum=False):
    """The plain beam by default (continuum_correction = false): these tests check the shot
    and the integrals; the correction's tests ask for it."""
    r, t = sp.Rational(str(radius)), sp.Rational(str(thickness))
    return notches.CircularNotch(
        "N", 2 * r, t, sp.Rational(str(B)), sp.Integer(int(E)), sp.Rational(3, 10), 1, r,
        continuum=continuum,
    )  # fmt: skip


def depth(x, r, t):
    """T(x) of a circular notch, x from P's clamp (float)."""
    return t + 2 * (r - math.sqrt(max(r * r - (x - r) ** 2, 0.0)))


def reference_shot(r, t, k0, lx, ly, ei0, stretches=True):
    """ψ, μ, x, y at M's end by scipy's DOP853 (rtol 1e-13), the two halves apart."""
    l = 2 * r

    def rates(s, y):
        psi, mu, _, _ = y
        tt = depth(s * l, r, t)
        a = ei0 / (EP * B * tt**3 / 12)
        ep = ei0 / (EP * B * tt * l * l) if stretches else 0.0
        ga = ei0 / (5 / 6 * G * B * tt * l * l) if stretches else 0.0
        c, si = math.cos(psi), math.sin(psi)
        fn, fq = lx * c + ly * si, ly * c - lx * si
        return [a * mu, -fq * (1 + (ep - ga) * fn), (1 + ep * fn) * c - ga * fq * si,
                (1 + ep * fn) * si + ga * fq * c]  # fmt: skip

    y = [0.0, k0, 0.0, 0.0]
    for lo, hi in ((0.0, 0.5), (0.5, 1.0)):
        y = solve_ivp(rates, [lo, hi], y, rtol=1e-13, atol=1e-16, method="DOP853").y[:, -1]
    return y


@pytest.mark.parametrize("ratio", [0.02, 0.1, 0.5])
def test_shot_against_an_independent_shooting(ratio):
    """Under an end moment and an end force (large rotation: ψ about 0.3 rad), ψ, μ, x, y of the
    notch's Runge–Kutta shot within 1e-9 of scipy's shooting of the same equations."""
    r, t = 1e-3, 1e-3 * ratio
    grid = SectionGrid.of(circular(r, t), {}, True)
    for k0, lx, ly in ((0.3, 0.0, 0.0), (0.05, 0.3, -0.8), (-0.2, -1.5, 0.6)):
        end = shoot_profile(np.array(k0), np.array(lx), np.array(ly), grid)
        want = reference_shot(r, t, k0, lx, ly, float(grid.EI0))
        for got, ref in zip((end.psi, end.omega, end.x, end.y), want, strict=True):
            assert float(got) == pytest.approx(ref, rel=1e-9, abs=1e-12)


def eb_integrals(r, t):
    """∫dx/EI, ∫(l − x)dx/EI, ∫(l − x)²dx/EI of the circular notch at 40 digits (mpmath)."""
    with mpmath.workdps(40):
        r, t = mpmath.mpf(r), mpmath.mpf(t)
        l = 2 * r
        modulus = mpmath.mpf(210) * 10**9 / (1 - mpmath.mpf("0.3") ** 2)

        def ei(x):
            thick = t + 2 * (r - mpmath.sqrt(r**2 - (x - r) ** 2))
            return modulus * mpmath.mpf("5e-3") * thick**3 / 12

        cuts = [0, r * 0.9, r, r * 1.1, l]
        return tuple(mpmath.quad(lambda x, n=n: (l - x) ** n / ei(x), cuts) for n in (0, 1, 2))


@pytest.mark.parametrize("ratio", [0.05, 0.2])
def test_linear_compliances_are_the_euler_bernoulli_integrals(ratio):
    """An end moment M turns M's end by M ∫dx/EI; a small end force V (elastica: no stretch or
    shear) moves it across by V ∫(l − x)²/EI dx and turns it by V ∫(l − x)/EI dx; and the
    section's own compliance integrals (quadrature, and sympy's Integral evaluated) agree."""
    r, t = "1e-3", str(1e-3 * ratio)
    rf, tf = float(r), float(t)
    theta_m, theta_f, y_f = eb_integrals(r, t)
    sec = circular(rf, tf)
    grid = SectionGrid.of(sec, {}, False)
    ei0, l = float(grid.EI0), 2 * rf
    moment = 1e-9
    end = shoot_profile(np.array(moment * l / ei0), np.array(0.0), np.array(0.0), grid)
    assert float(end.psi) / moment == pytest.approx(float(theta_m), rel=1e-10)
    force = 1e-9
    load = force * l * l / ei0
    end = shoot_profile(np.array(load), np.array(0.0), np.array(load), grid)
    assert float(end.y) * l / force == pytest.approx(float(y_f), rel=1e-9)
    assert float(end.psi) / force == pytest.approx(float(theta_f), rel=1e-9)
    numbers = sec.compliance_numbers({})
    assert numbers.theta_M == pytest.approx(float(theta_m), rel=1e-14)
    assert numbers.theta_F == pytest.approx(float(theta_f), rel=1e-14)
    assert numbers.y_F == pytest.approx(float(y_f), rel=1e-14)
    symbolic = sec.compliance()
    assert float(sp.N(symbolic.theta_M, 20)) == pytest.approx(float(theta_m), rel=1e-15)


def test_thin_notch_limit_is_paros_weisbord():
    """C_θM → 9π√R/(2 E' b t^{5/2}) as t/R → 0 (Paros & Weisbord 1965), the relative gap
    shrinking with t/R."""
    gaps = []
    for ratio in (1e-2, 1e-3, 1e-4):
        r, t = 1e-3, 1e-3 * ratio
        c = circular(r, t).compliance_numbers({}).theta_M
        pw = 9 * math.pi * math.sqrt(r) / (2 * EP * B * t**2.5)
        gaps.append(abs(c / pw - 1))
    # measured: the gap is t/(8R) to 1e-3 of itself
    for ratio, gap in zip((1e-2, 1e-3, 1e-4), gaps, strict=True):
        assert gap == pytest.approx(ratio / 8, rel=3e-3), gaps


def single_notch(beam="elastica", extra=""):
    return symkin.loads(single_notch_text(beam, extra), "single.toml")


def single_notch_text(beam="elastica", extra=""):
    return f"""format = 1
name = "single"
ground = "frame"
[[link]]
name = "frame"
[[link]]
name = "arm"
[[hinge]]
name = "N"
links = ["frame", "arm"]
at = [0.0, 0.0]
plate_angle = "30*deg"
input = true
profile = "circular"
radius = 1e-3
thickness = 1e-4
width = 5e-3
E = 210e9
beam = "{beam}"
{extra}
[[point]]
name = "P"
link = "arm"
at = [0.02, 0.01]
"""


def test_a_notch_held_at_an_angle_bends_as_pure_moment():
    """One notch, input held at θ: the only load is the end moment that holds it, so the
    inextensible beam's M clamp sits where the pure-moment model puts it (a 45-digit series
    against a Runge–Kutta shot): the point's deviation agrees with `exact` to 1e-6 (the shot's
    3e-11 of the span is 2e-7 of this second-order deviation, l θ²/50)."""
    an = symkin.analyze(single_notch())
    for q in ("0.05", "-0.3"):
        result = symkin.evaluate(an, {"N": q}, level="equilibrium")
        eq = result.points["P"].deviation
        ex = symkin.evaluate(an, {"N": q}, level="exact").points["P"].deviation
        size = math.hypot(*ex)
        gap = math.hypot(eq[0] - ex[0], eq[1] - ex[1])
        assert gap <= 1e-6 * size
        # the reported error estimate covers the shot's discretisation
        assert result.error_estimate >= gap / size


def test_notch_four_bar_at_equilibrium_and_its_stress():
    """The notch four-bar solves at equilibrium, its deviation near the kinematic one (the loop
    forces add little to a notch); every hinge's largest stress is at its neck, and the input
    hinge's strain there is K_t = (1 + t/(2R))^(9/20) times the neck's bending strain of its
    angle under a moment, θ t/(2 EI_neck ∫dx/EI) (∫dx/EI by 40-digit quadrature), within 5 %
    (the loop force adds the rest)."""
    mech = four_bar()
    an = symkin.analyze(mech)
    ev = symkin.evaluate(an, {"A0": "0.05"}, level="equilibrium")
    ex = symkin.evaluate(an, {"A0": "0.05"}, level="exact")
    dev, kin = ev.points["C"].deviation, ex.points["C"].deviation
    assert math.hypot(*dev) == pytest.approx(math.hypot(*kin), rel=0.2)
    r, t = 1e-3, 1e-4
    kt = (1 + t / (2 * r)) ** 0.45
    theta_m, _, _ = eb_integrals("1e-3", "1e-4")
    for plate in ev.plates.values():
        assert plate.section == pytest.approx(0.5, abs=0.01)  # the neck
    angle = abs(ev.angles_compliant["A0"])
    neck = angle / (EP * B * t**3 / 12 * float(theta_m)) * t / 2
    assert ev.plates["A0"].strain / kt == pytest.approx(neck, rel=0.05)


def test_a_notch_file_derives_its_kinematic_levels():
    """A file whose notches read a parameter (R) derives the kinematic levels: the generated
    `loaded` folds a notch's section in as numbers. Its default level there is `exact`, saying
    why; asked for `loaded`, the derivation refuses, naming the hinge and the parameter."""
    from symkin.codegen import pipeline
    from symkin.core import levels

    mech = four_bar()
    an = symkin.analyze(mech)
    plan, _ = pipeline.build(an, "numpy", mech.path, sensitivity=False)
    assert [lv.name for lv in plan.levels] == ["paper", "first_order", "exact"]
    choice = levels.default_for(mech, "numpy")
    assert choice.name == "exact" and "reads R" in choice.reason
    assert levels.default_for(mech).name == "loaded"  # the sympy backend takes it
    with pytest.raises(InputError, match="reads the parameter\\(s\\) R") as raised:
        pipeline.build(an, "numpy", mech.path, sensitivity=False, levels=("loaded",))
    assert "A0" in str(raised.value)


def test_notch_parallelogram_at_equilibrium_translates():
    """Four circular notches (t/R = 0.1) in a parallelogram at 0.05 rad: the stage turns by
    less than 1e-4 of the input (its legs are equal), and it rises by the kinematic deviation
    within 10 % (the legs' loop forces add a sideways shift the kinematic level leaves out)."""
    from test_notches import parallelogram

    an = symkin.analyze(parallelogram())
    ev = symkin.evaluate(an, {"F1": "0.05"}, level="equilibrium")
    ex = symkin.evaluate(an, {"F1": "0.05"}, level="exact")
    assert abs(ev.links["coupler"].deviation) < 1e-4 * 0.05
    assert ev.points["P"].deviation[1] == pytest.approx(ex.points["P"].deviation[1], rel=0.1)


def timoshenko_shear(r, t):
    """∫dx/κGA of the circular notch at 40 digits (κ = 5/6, G = E/(2(1 + ν)))."""
    with mpmath.workdps(40):
        r, t = mpmath.mpf(r), mpmath.mpf(t)
        g = mpmath.mpf(210) * 10**9 / (2 * (1 + mpmath.mpf("0.3")))

        def kga(x):
            return (
                mpmath.mpf(5)
                / 6
                * g
                * mpmath.mpf("5e-3")
                * (t + 2 * (r - mpmath.sqrt(r**2 - (x - r) ** 2)))
            )

        return mpmath.quad(lambda x: 1 / kga(x), [0, r * 0.9, r, r * 1.1, 2 * r])


def notch_compliances(ratio, extra):
    """C_θM and C_yF of the single notch of a file (R = 1 mm, t = ratio·R, Reissner) as
    `equilibrium` shoots it: its section from the file, an end moment and a small end force."""
    from symkin.model.profiles import section_of
    from symkin.physics.section_beams import grid_of

    text = single_notch_text("reissner", extra).replace(
        "thickness = 1e-4", f"thickness = {ratio}e-3"
    )
    mech = symkin.loads(text, "single.toml")
    hinge = next(h for h in mech.hinges if h.name == "N")
    grid = grid_of(section_of(hinge, mech.unit_scale), {}, True)
    ei0, l = float(grid.EI0), 2e-3
    moment = 1e-9
    end = shoot_profile(np.array(moment * l / ei0), np.array(0.0), np.array(0.0), grid)
    c_theta = float(end.psi) / moment
    force = 1e-9
    load = force * l * l / ei0
    end = shoot_profile(np.array(load), np.array(0.0), np.array(load), grid)
    return c_theta, float(end.y) * l / force


@pytest.mark.parametrize("ratio", [0.05, 0.1, 0.2])
def test_the_corrected_notch_is_the_calculix_continuum(ratio):
    """With the continuum correction (the default), a single circular notch's C_θM and C_yF as
    `equilibrium` shoots it are the committed CalculiX runs' (benchmarks/results-notch.json: FE
    over the beam integrals, times the integrals by mpmath here) within 0.3 %; with
    `continuum_correction = false` they are the Euler–Bernoulli ∫dx/EI and the Timoshenko
    ∫(l − x)²dx/EI + ∫dx/κGA to 1e-9."""
    import json

    from conftest import ROOT

    runs = json.loads((ROOT / "benchmarks" / "results-notch.json").read_text())["circular"]
    fe = next(row["ratio"] for row in runs if row["t/R"] == ratio)
    theta_m, _, y_f = eb_integrals("1e-3", str(1e-3 * ratio))
    timoshenko = float(y_f + timoshenko_shear("1e-3", str(1e-3 * ratio)))
    c_theta, c_y = notch_compliances(ratio, "")
    assert c_theta == pytest.approx(float(theta_m) * fe["theta_M"], rel=3e-3)
    assert c_y == pytest.approx(timoshenko * fe["y_F_timoshenko"], rel=3e-3)
    # the correction is what closes the gap: the plain beam misses the FE by 1.9-6.7 %
    c_theta, c_y = notch_compliances(ratio, "continuum_correction = false")
    assert c_theta == pytest.approx(float(theta_m), rel=1e-9)
    assert c_y == pytest.approx(timoshenko, rel=1e-9)
    assert abs(c_theta / (float(theta_m) * fe["theta_M"]) - 1) > 0.015


@pytest.mark.parametrize(
    ("extra", "match"),
    [
        ('continuum_correction = "no"', "must be true or false"),
        ("continuum_correction = 0", "must be true or false"),
    ],
)
def test_continuum_correction_key_is_checked(extra, match):
    with pytest.raises(InputError, match=match) as err:
        single_notch("reissner", extra)
    assert "continuum_correction = false" in str(err.value)


def test_continuum_correction_on_a_uniform_plate_exits_2():
    text = single_notch_text("reissner").replace(
        'profile = "circular"\nradius = 1e-3\n', "length = 2e-3\n"
    )
    symkin.loads(text, "single.toml")  # the plate itself reads
    bad = text.replace('beam = "reissner"', 'beam = "reissner"\ncontinuum_correction = false')
    with pytest.raises(InputError, match="notch hinges only") as err:
        symkin.loads(bad, "single.toml")
    assert "remove continuum_correction" in str(err.value)


def test_a_notch_model_error_says_what_the_corrected_beam_leaves():
    """`model_error` of a notch: after the correction, the fit's residual on the compliances
    (against the CalculiX runs: it covers the corrected beam's gap), the uncorrected beam's own
    gap without it, and the corner-filleted plates' 1.7 %; on a single notch held at 0.05 rad
    (t/R = 0.1, no load: no compliance part) the error of its centre's drift, 0.6 % of the
    beam's drift θ∫₀^R(R − x)dx/EI / ∫dx/EI (docs/physics.md's table: 0.5 % at t/R = 0.05,
    0.8 % at 0.2, linear between) moves the arm, and the point, across by that."""
    import json

    from conftest import ROOT

    from symkin.model import notch_correction as nc

    runs = json.loads((ROOT / "benchmarks" / "results-notch.json").read_text())["circular"]
    for row in runs:
        tau, fe = row["t/R"], row["ratio"]
        theta_m, _, y_f = eb_integrals("1e-3", str(1e-3 * tau))
        shear = timoshenko_shear("1e-3", str(1e-3 * tau))
        sec = circular(1e-3, 1e-3 * tau, continuum=True).compliance_numbers({})
        gaps = (
            abs(sec.theta_M / (float(theta_m) * fe["theta_M"]) - 1),
            abs((sec.y_F + sec.y_V) / (float(y_f + shear) * fe["y_F_timoshenko"]) - 1),
        )
        assert max(gaps) <= nc.remaining("circular", tau, True) * 1.01
        plain = max(fe["theta_M"], fe["y_F_timoshenko"]) - 1
        assert nc.remaining("circular", tau, False) == pytest.approx(plain, rel=0.05)
    assert nc.remaining("corner_filleted", 0, True) >= 0.0168  # y_F FE/Timoshenko, r = 0.5
    an = symkin.analyze(symkin.loads(single_notch_text("reissner"), "single.toml"))
    theta = 0.05
    ev = symkin.evaluate(an, {"N": str(theta)}, level="equilibrium")
    with mpmath.workdps(30):
        r, t = mpmath.mpf("1e-3"), mpmath.mpf("1e-4")

        def inv(x):
            return 1 / (t + 2 * (r - mpmath.sqrt(r**2 - (x - r) ** 2))) ** 3

        drift = mpmath.quad(lambda x: (r - x) * inv(x), [0, r * 0.9, r]) / mpmath.quad(
            inv, [0, r * 0.9, r, r * 1.1, 2 * r]
        )
    want = 0.006 * theta * float(drift) / math.hypot(*ev.points["P"].deviation)
    assert ev.model_error_parts["P"]["notch"] == pytest.approx(want, rel=0.02)
    assert ev.model_error["P"] >= want


def test_alike_notches_share_their_integrals_and_grids_only():
    """Notch.quad and section_beams.grid_of keep their work by the section's geometry and
    material, not its hinge: two hinges alike share it (each grid named by its own hinge), a
    notch one micrometre thicker does not."""
    import dataclasses

    from symkin.physics import section_beams

    one = circular(1e-3, 1e-4)
    twin = dataclasses.replace(one, hinge="M")
    thicker = circular(1e-3, 1.01e-4)
    got = [s.quad(lambda x, t, s=s: 1 / s._EI(t), {}) for s in (one, twin, thicker)]
    assert got[1] is got[0]
    assert float(got[0]) == pytest.approx(float(eb_integrals("1e-3", "1e-4")[0]), rel=1e-14)
    assert float(got[2]) == pytest.approx(float(eb_integrals("1e-3", "1.01e-4")[0]), rel=1e-14)
    grids = [section_beams.grid_of(s, {}, False) for s in (one, twin)]
    assert [g.hinge for g in grids] == ["N", "M"]
    assert grids[1].samples is grids[0].samples
