"""The hinge section (symkin.model.sections): the uniform plate against its closed forms, and a
profile only this file defines (a two-step plate) against mpmath quadrature of its own
stiffness, reaching the stiffness the levels read, the model error and the FE mesher's outline.

The references here are written out independently: E' b t³ s²/12 and its integrals by hand, the
two-step plate's EI(x) as a Python function integrated by mpmath.quad."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import ClassVar

import mpmath
import pytest
import sympy as sp
from conftest import ROOT

import symkin
from symkin import fea
from symkin.core.errors import InputError
from symkin.model import profiles, sections
from symkin.physics import model_error
from symkin.physics.stiffness import plate_stiffness

EXAMPLES = ROOT / "examples"
E, NU, B, T, L, S = sp.symbols("E nu b t l s", positive=True)
V_, M_ = sp.symbols("V M", real=True)


def uniform_symbolic() -> sections.UniformPlate:
    return sections.UniformPlate("H", L, T, B, E, NU, S)


def same(a, b) -> bool:
    return sp.simplify(sp.piecewise_fold(a - b)) == 0


# -- the uniform plate: the closed forms --------------------------------------------------------


def test_uniform_plate_is_the_closed_forms():
    """EI = E' b t³ s²/12, EA = E' b t s², κGA = (5/6) E/(2(1 + ν)) b t s², E' = E/(1 − ν²)
    for b ≥ 5 t; the compliances l/EI, l²/(2EI), l³/(3EI), l/EA, l/κGA; clamped–guided
    l³/(12EI); the generic integrals of the base class agree with them."""
    sec = uniform_symbolic()
    wide = sp.Piecewise((E / (1 - NU**2), B >= 5 * T), (E, True))
    ei = wide * B * T**3 * S**2 / 12
    ea = wide * B * T * S**2
    kga = sp.Rational(5, 6) * E / (2 * (1 + NU)) * B * T * S**2
    assert sp.srepr(sec.modulus()) == sp.srepr(wide)
    for x in (sp.S.Zero, L / 3, sections.X):
        assert same(sec.EI(x), ei) and same(sec.EA(x), ea) and same(sec.kGA(x), kga)
    c = sec.compliance()
    closed = (L / ei, L**2 / (2 * ei), L**3 / (3 * ei), L / ea, L / kga)
    got = (c.theta_M, c.theta_F, c.y_F, c.x_N, c.y_V)
    assert all(same(a, b) for a, b in zip(got, closed, strict=True))
    assert same(c.guided(), L**3 / (12 * ei)) and same(sec.guided(), L**3 / (12 * ei))
    assert same(sec.slender_squared(), T**2 / L**2)  # the reported strain's (t/l)²
    generic = sections.Section.compliance(sec)  # the base class's integrals of T(x)
    keys = ("theta_M", "theta_F", "y_F", "x_N", "y_V")
    assert all(same(getattr(generic, k), getattr(c, k)) for k in keys)


def test_uniform_plate_stiffness_is_today_s_expression():
    """plate_stiffness reads the section: on every example its EI, EA, κGA are, term for term,
    the expressions E' b t³ s²/12, E' b t s², κ G b t s² written out here."""
    count = 0
    for path in sorted(EXAMPLES.glob("*.toml")):
        mech = symkin.load(path)
        if not mech.has_stiffness or any(h.profile != "uniform" for h in mech.hinges):
            continue  # a notch's section is tests/test_notch_beams.py's
        stiff = plate_stiffness(mech, "equilibrium")
        s2 = mech.unit_scale**2
        for h in mech.hinges:
            if not h.is_plate:
                continue
            wide = sp.Piecewise((h.E / (1 - h.nu**2), h.width >= 5 * h.thickness), (h.E, True))
            area = h.width * h.thickness * s2
            kga = sp.Rational(5, 6) * h.E / (2 * (1 + h.nu)) * area
            st = stiff[h.name]
            assert isinstance(st.section, sections.UniformPlate)
            assert sp.srepr(st.EI) == sp.srepr(wide * area * h.thickness**2 / 12)
            assert sp.srepr(st.EA) == sp.srepr(wide * area)
            assert sp.srepr(st.kGA) == sp.srepr(kga)
            count += 1
    assert count >= 4


def test_uniform_shape_is_the_circular_arc_and_stress_is_at_a_clamp():
    """Under a pure moment the uniform plate is the arc f = l sin θ/θ, g = l (1 − cos θ)/θ (and
    the base class's arcs joined end to end, and its quadrature, give it too); its largest
    stress from end loads is |N|/A + max(|M|, |M + V l s|) t/(2I)."""
    sec = uniform_symbolic()
    values = {L: sp.Rational(3, 1000), T: sp.Rational(1, 10000), B: sp.Rational(1, 200)}
    values |= {E: sp.Integer(200000000000), NU: sp.Rational(3, 10), S: 1}
    for theta in (sp.Rational(1, 50), sp.Rational(-7, 10), sp.Rational(3, 2)):
        f, g = sec.shape(theta)
        fc = values[L] * sp.sin(theta) / theta
        gc = values[L] * (1 - sp.cos(theta)) / theta
        assert abs(sp.N(f.xreplace(values) - fc, 30)) < 1e-25
        assert abs(sp.N(g.xreplace(values) - gc, 30)) < 1e-25
        fb, gb = sections.Section.shape(sec, theta)
        assert abs(sp.N((fb - fc).xreplace(values), 30)) < 1e-25
        assert abs(sp.N((gb - gc).xreplace(values), 30)) < 1e-25
        fq, gq = sec.shape_numbers(float(theta), values)
        assert fq == pytest.approx(float(fc), rel=1e-14)
        assert gq == pytest.approx(float(gc), rel=1e-14)
    l, t, b = 3e-3, 1e-4, 5e-3
    area, inertia = b * t, b * t**3 / 12
    for loads in ((5.0, 0.2, 1e-4), (-3.0, -0.5, 2e-3), (0.0, 1.0, -1.5e-3)):
        n, v, m = loads
        expect = abs(n) / area + max(abs(m), abs(m + v * l)) * t / (2 * inertia)
        got, where = sec.largest_stress(loads, values)
        assert got == pytest.approx(expect, rel=1e-14)
        generic, _ = sections.Section.largest_stress(sec, loads, values)
        assert generic == pytest.approx(expect, rel=1e-12)
        assert where in (0.0, 1.0)


def test_generic_numbers_agree_with_the_uniform_closed_forms():
    """SectionNumbers' quadratures (what any profile gets) on a uniform plate give the closed
    forms UniformNumbers computes: stretch, shear, guided bending and the centre line."""
    mech = symkin.load(EXAMPLES / "four_bar.toml")
    h = mech.hinges[0]
    values = {p.symbol: sp.Rational(1, 1000) for p in mech.parameters}
    sec = profiles.section_of(h, mech.unit_scale)
    closed = sections.SectionNumbers.of(sec, values)
    assert isinstance(closed, sections.UniformNumbers)
    generic = sections.SectionNumbers(sec, values, *dataclasses.astuple(closed)[2:])
    for n in (3.0, -0.4):
        assert generic.stretch(n) == pytest.approx(closed.stretch(n), rel=1e-14)
        assert generic.shear(n) == pytest.approx(closed.shear(n), rel=1e-14)
        assert generic.guided(n) == pytest.approx(closed.guided(n), rel=1e-13)
    for theta, moment in ((0.1, 1e-4), (-0.3, 0.0), (0.02, -2e-4)):
        assert generic.centre_line(0.07, theta, moment) == pytest.approx(
            closed.centre_line(0.07, theta, moment), rel=1e-13
        )


# -- a profile only this file knows: the two-step plate ---------------------------------------


@dataclass(frozen=True)
class TwoStep(sections.Section):
    """Thickness t over the first half (from P's clamp), `thickness2` over the second."""

    thickness2: sp.Expr = sp.S.One
    profile: ClassVar[str] = "two_step_test"

    @classmethod
    def from_hinge(cls, hinge, scale):
        ratio = sp.sympify(dict(hinge.profile_params)["ratio"])
        base = sections.UniformPlate.from_hinge(hinge, scale)
        fields = {f.name: getattr(base, f.name) for f in dataclasses.fields(base)}
        return cls(**fields, thickness2=base.thickness * ratio)

    def pieces(self):
        half = self.length / 2
        return ((sp.S.Zero, half, self.thickness), (half, self.length, self.thickness2))


RATIO = sp.Rational(2, 3)


@pytest.fixture
def two_step(monkeypatch):
    """The two-step profile registered for one test (the registry as it was afterwards)."""
    monkeypatch.setattr(profiles, "PROFILES", dict(profiles.PROFILES))
    profiles.register(TwoStep)
    yield TwoStep


def stepped(mech, name="A0"):
    """`mech` with hinge `name` a two-step plate (t, then 2t/3)."""
    hinges = tuple(
        dataclasses.replace(h, profile="two_step_test", profile_params=(("ratio", RATIO),))
        if h.name == name
        else h
        for h in mech.hinges
    )
    return dataclasses.replace(mech, hinges=hinges)


class Reference:
    """The two-step plate written out: EI, EA, κGA as functions of x and mpmath integrals."""

    def __init__(self, l, t1, t2, b, e, nu, s):
        self.l, self.t1, self.t2, self.b, self.s = l, t1, t2, b, s
        self.ep = e / (1 - nu**2) if b >= 5 * t1 else e
        self.g = e / (2 * (1 + nu))

    def t(self, x):
        return self.t1 if x < self.l / 2 else self.t2

    def ei(self, x):
        return self.ep * self.b * self.t(x) ** 3 * self.s**2 / 12

    def ea(self, x):
        return self.ep * self.b * self.t(x) * self.s**2

    def kga(self, x):
        return mpmath.mpf(5) / 6 * self.g * self.b * self.t(x) * self.s**2

    def quad(self, f):
        with mpmath.workdps(30):
            return mpmath.quad(f, [0, self.l / 2, self.l])


def reference_for(mech, values):
    h = next(h for h in mech.hinges if h.name == "A0")

    def num(e):
        return mpmath.mpf(str(sp.N(sp.sympify(e).xreplace(values), 40)))

    t1 = num(h.thickness)
    return Reference(num(h.length), t1, t1 * 2 / 3, num(h.width), num(h.E), num(h.nu), 1)


def test_two_step_integrals_against_quadrature(two_step):
    """The registered profile's compliance integrals (sympy, and the floats of its quadrature),
    its shape under a pure moment, its largest stress and its outline against the reference."""
    mech = stepped(symkin.load(EXAMPLES / "four_bar.toml"))
    values = {p.symbol: sp.Rational(1, 1000) for p in mech.parameters}
    sec = profiles.section_of(mech.hinges[0], mech.unit_scale)
    assert isinstance(sec, two_step) and not sec.uniform
    ref = reference_for(mech, values)
    l = ref.l
    expect = {
        "theta_M": ref.quad(lambda x: 1 / ref.ei(x)),
        "theta_F": ref.quad(lambda x: (l - x) / ref.ei(x)),
        "y_F": ref.quad(lambda x: (l - x) ** 2 / ref.ei(x)),
        "x_N": ref.quad(lambda x: 1 / ref.ea(x)),
        "y_V": ref.quad(lambda x: 1 / ref.kga(x)),
    }
    symbolic, numbers = sec.compliance(), sec.compliance_numbers(values)
    for key, value in expect.items():
        assert float(sp.N(getattr(symbolic, key).xreplace(values), 30)) == pytest.approx(
            float(value), rel=1e-14
        )
        assert getattr(numbers, key) == pytest.approx(float(value), rel=1e-14)
    guided = expect["y_F"] - expect["theta_F"] ** 2 / expect["theta_M"]
    assert numbers.guided() == pytest.approx(float(guided), rel=1e-13)
    # stiffness along the axis, both halves
    for x, at in ((l / 4, sp.Rational(1, 4000)), (3 * l / 4, sp.Rational(3, 4000))):
        assert float(sp.N(sec.EI(at).xreplace(values), 30)) == pytest.approx(
            float(ref.ei(x)), rel=1e-14
        )
    # shape: the turned angle Φ(x) = θ ∫₀ˣ dx/EI / ∫₀ˡ dx/EI, f = ∫cos Φ, g = ∫sin Φ
    for theta in (0.05, -0.4, 1.2):
        with mpmath.workdps(30):

            def turned(x, theta=theta):
                return (
                    theta
                    * mpmath.quad(lambda y: 1 / ref.ei(y), [0, min(x, l / 2), x])
                    / (expect["theta_M"])
                )

            f = ref.quad(lambda x: mpmath.cos(turned(x)))
            g = ref.quad(lambda x: mpmath.sin(turned(x)))
        fs, gs = (float(sp.N(e.xreplace(values), 30)) for e in sec.shape(sp.Float(theta, 30)))
        assert fs == pytest.approx(float(f), rel=1e-13) and gs == pytest.approx(float(g), rel=1e-13)
        fq, gq = sec.shape_numbers(theta, values)
        assert fq == pytest.approx(float(f), rel=1e-13) and gq == pytest.approx(float(g), rel=1e-13)
    # largest stress from end loads: dense sampling of |N|/A + |M + V (l − x)| t/(2I)
    for n, v, m in ((2.0, 0.5, 1e-4), (-1.0, -3.0, 4e-4), (0.0, 1.0, -1e-3)):
        samples = []
        for k in range(20001):
            x = float(l) * k / 20000
            for t in {ref.t(x), ref.t(x * (1 - 1e-12)) if k else ref.t(x)}:
                t = float(t)
                bb = float(ref.b)
                moment = m + v * (float(l) - x)
                samples.append(abs(n) / (bb * t) + abs(moment) * 6 / (bb * t**2))
        got, _ = sec.largest_stress((n, v, m), values)
        assert got == pytest.approx(max(samples), rel=1e-12)
    # the outline: the faces at ±T(x)/2, the step at the middle
    outline = sec.outline(values, samples=4)
    assert len(outline) == 2 * 2 * 5
    for x, y in outline:
        half = float(ref.t1 if x < float(l) / 2 - 1e-15 else ref.t2) / 2
        if abs(x - float(l) / 2) > 1e-15:
            assert abs(y) == pytest.approx(half, rel=1e-15)
    at_step = sorted({abs(y) for x, y in outline if abs(x - float(l) / 2) < 1e-15})
    assert at_step == pytest.approx([float(ref.t2) / 2, float(ref.t1) / 2], rel=1e-15)


def test_two_step_reaches_stiffness_model_error_and_the_mesher(two_step):
    """The levels' stiffness reads the profile (and refuses it where a level's beams are
    uniform, naming it); the model error takes its end displacements from its integrals; the
    FE deck cuts its outline."""
    mech = stepped(symkin.load(EXAMPLES / "four_bar.toml"))
    values = {p.symbol: sp.Rational(1, 1000) for p in mech.parameters}
    ref = reference_for(mech, values)
    for level in ("equilibrium", "loaded"):
        with pytest.raises(InputError, match="two_step_test") as err:
            plate_stiffness(mech, level)
        assert "A0" in str(err.value) and level in str(err.value)
    with pytest.raises(InputError, match="two_step_test"):
        symkin.evaluate(symkin.analyze(mech), {"A0": "0.1"}, level="equilibrium")
    stiff = plate_stiffness(mech, "equilibrium", uniform=False)["A0"]
    assert isinstance(stiff.section, two_step)
    theta_m = ref.quad(lambda x: 1 / ref.ei(x))
    assert float(sp.N(stiff.EI.xreplace(values), 30)) == pytest.approx(
        float(ref.l / theta_m), rel=1e-14
    )
    # the model error's plate: its stretch, shear and guided bending under end loads are the
    # profile's integrals times the loads; its centre line the reference's −c ∫ T² κ² dx
    plate = next(p for p in model_error._plates(mech, values, "equilibrium") if p.name == "A0")
    n, v, theta, moment = 2.5, -0.7, 0.08, 3e-4
    l = ref.l
    y_f = ref.quad(lambda x: (l - x) ** 2 / ref.ei(x))
    theta_f = ref.quad(lambda x: (l - x) / ref.ei(x))
    assert plate.section.stretch(n) == pytest.approx(
        float(n * ref.quad(lambda x: 1 / ref.ea(x))), rel=1e-14
    )
    assert plate.section.shear(v) == pytest.approx(
        float(v * ref.quad(lambda x: 1 / ref.kga(x))), rel=1e-14
    )
    assert plate.section.guided(v) == pytest.approx(
        float(v * (y_f - theta_f**2 / theta_m)), rel=1e-13
    )
    a0 = ref.quad(lambda x: (1 - x / l) / ref.ei(x))
    a1 = ref.quad(lambda x: x / l / ref.ei(x))
    m_p = (theta - moment * a1) / a0
    squares = ref.quad(
        lambda x: ref.t(x) ** 2 * ((m_p * (1 - x / l) + moment * x / l) / ref.ei(x)) ** 2
    )
    assert plate.section.centre_line(0.07, theta, moment) == pytest.approx(
        float(-0.07 * squares), rel=1e-12
    )
    # the mesher: every node of A0's plate lies within ±T(s)/2 of its centre line, the faces on it
    setup = fea.prepare(mech, {"A0": "0.1"})
    pl = next(p for p in setup.conf.plates if p.hinge == "A0")
    nl, nt = 8, 2
    deck = fea.write_deck(setup, fea.Mesh(nl, nt))
    lines = deck.text.splitlines()
    first = lines.index(next(x for x in lines if x.startswith("** plate 1 ")))
    last = lines.index(next(x for x in lines if x.startswith("** plate 2 ")))
    across: dict[float, list[float]] = {}
    for line in lines[first + 1 : last]:
        if line.startswith("**"):
            continue
        _, x, y, _ = (float(v) for v in line.split(","))
        dx, dy = x - pl.start[0], y - pl.start[1]
        s = dx * pl.u[0] + dy * pl.u[1]
        across.setdefault(round(s, 12), []).append(-dx * pl.u[1] + dy * pl.u[0])
    assert len(across) == 2 * nl + 1
    for s, rs in across.items():
        thick = float(ref.t(mpmath.mpf(s)))
        assert max(rs) == pytest.approx(thick / 2, rel=1e-9)
        assert min(rs) == pytest.approx(-thick / 2, rel=1e-9)
    assert math.isclose(pl.depth(0.0), float(ref.t1)) and math.isclose(
        pl.depth(pl.length), float(ref.t2)
    )


def test_an_unknown_profile_is_named():
    mech = symkin.load(EXAMPLES / "four_bar.toml")
    h = dataclasses.replace(mech.hinges[0], profile="no_such")
    with pytest.raises(ValueError, match=r"no_such.*uniform"):
        profiles.section_of(h, 1)
    assert profiles.PROFILES["uniform"] is sections.UniformPlate
