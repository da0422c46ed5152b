"""Notch hinges (symkin.model.notches; docs/file-format.md, "Notch hinges"): the three profiles'
thickness against the contract's formulas, the file reader's `profile` key and its refusals, the
`pure_moment` model against an independent nested mpmath quadrature of the bent notch, its
equality with the circular arc on a uniform plate, the thin-notch limit, and a notch four-bar
and parallelogram through every backend.

The references are written out here: T(x) by the formulas of docs/file-format.md, the turned
angle Ψ(x) = ∫₀ˣ T⁻³ / ∫₀ˡ T⁻³ and f = ∫cos θΨ, g = ∫sin θΨ by mpmath.quad at DPS digits."""

from __future__ import annotations

import math

import mpmath
import pytest
import sympy as sp
from evaluators import BACKENDS, GENERATED, Generated, require

import symkin
from symkin.core.errors import InputError
from symkin.model import hinges, notches, profiles

HEADER = """format = 1
name = "notch"
ground = "frame"
[parameters]
R = 1e-3
[defaults]
{defaults}
[[link]]
name = "frame"
[[link]]
name = "crank"
[[link]]
name = "coupler"
[[link]]
name = "rocker"
"""
FOUR_BAR = """
[[hinge]]
name = "A0"
links = ["frame", "crank"]
at = [0.0, 0.0]
plate_angle = "pi/2"
input = true
{a0}
[[hinge]]
name = "A"
links = ["crank", "coupler"]
at = [0.015, 0.026]
plate_angle = "60*deg"
[[hinge]]
name = "B0"
links = ["frame", "rocker"]
at = [0.1, 0.0]
plate_angle = "pi/2"
[[hinge]]
name = "B"
links = ["coupler", "rocker"]
at = [0.085, 0.068]
plate_angle = "0"
[[point]]
name = "C"
link = "coupler"
at = [0.06, 0.09]
"""
PARALLELOGRAM = """
[[hinge]]
name = "F1"
links = ["frame", "crank"]
at = [0.0, 0.0]
plate_angle = "pi/2"
input = true
[[hinge]]
name = "S1"
links = ["crank", "coupler"]
at = [0.0, 0.04]
plate_angle = "pi/2"
[[hinge]]
name = "F2"
links = ["frame", "rocker"]
at = [0.03, 0.0]
plate_angle = "pi/2"
[[hinge]]
name = "S2"
links = ["rocker", "coupler"]
at = [0.03, 0.04]
plate_angle = "pi/2"
[[point]]
name = "P"
link = "coupler"
at = [0.015, 0.05]
"""
#: Digits of the references' nested quadratures (enough for the 1e-14 compared).
DPS = 24
NOTCH_DEFAULTS = 'profile = "circular"\nradius = "R"\nthickness = "R/10"\nwidth = 5e-3\nE = 210e9'


def four_bar(defaults=NOTCH_DEFAULTS, a0="", name="notch.toml"):
    return symkin.loads(HEADER.format(defaults=defaults) + FOUR_BAR.format(a0=a0), name)


def parallelogram(defaults=NOTCH_DEFAULTS):
    return symkin.loads(HEADER.format(defaults=defaults) + PARALLELOGRAM, "para.toml")


# -- the profiles' thickness ----------------------------------------------------------------------


def mp(v):
    """A number at the working precision (a decimal string read now, not a float's digits)."""
    return mpmath.mpf(str(v))


def circular_t(x, r, t):
    r, t = mp(r), mp(t)
    u = x - r  # from the centre
    return t + 2 * (r - mpmath.sqrt(max(r**2 - u**2, 0)))  # 0 at the clamps


def elliptical_t(x, a, c, t):
    a, c, t = mp(a), mp(c), mp(t)
    u = x - a
    return t + 2 * c * (1 - mpmath.sqrt(max(1 - u**2 / a**2, 0)))


def filleted_t(x, l, r, t):
    l, r, t = mp(l), mp(r), mp(t)
    u = abs(x - l / 2)
    if u <= l / 2 - r:
        return t
    return t + 2 * (r - mpmath.sqrt(max(r**2 - (u - l / 2 + r) ** 2, 0)))


CASES = {
    "circular": ("radius = 2e-3\nthickness = 1e-4", lambda x: circular_t(x, 2e-3, 1e-4), 4e-3),
    "elliptical": (
        "semi_axis = 3e-3\ndepth = 1e-3\nthickness = 2e-4",
        lambda x: elliptical_t(x, 3e-3, 1e-3, 2e-4),
        6e-3,
    ),
    "corner_filleted": (
        "length = 5e-3\nfillet = 1e-3\nthickness = 1e-4",
        lambda x: filleted_t(x, 5e-3, 1e-3, 1e-4),
        5e-3,
    ),
}


@pytest.mark.parametrize("profile", sorted(CASES))
def test_profile_thickness_span_and_centre(profile):
    """T(x) of each profile against the formulas of docs/file-format.md, its span the hinge's
    length, its centre at `at` (the plate's midpoint: the clamps at ±span/2 along the axis)."""
    keys, reference, span = CASES[profile]
    mech = four_bar(defaults=f'profile = "{profile}"\n{keys}\nwidth = 5e-3\nE = 210e9')
    h = mech.hinge("A")
    assert h.profile == profile and h.model == "pure_moment"
    assert float(h.length) == pytest.approx(span, rel=1e-15)
    sec = profiles.section_of(h, 1)
    depth = sec.thickness_function({})
    for k in range(41):
        x = span * k / 40
        assert depth(x) == pytest.approx(float(reference(mpmath.mpf(x))), rel=1e-12)
    an = symkin.analyze(mech)
    geo = next(g for g in an.kin.hinges.values() if g.name == "A")
    c = (mpmath.cos(mpmath.pi / 3), mpmath.sin(mpmath.pi / 3))
    p_clamp, m_clamp = (geo.clamp(geo.P), geo.clamp(geo.M))
    for clamp, sign in ((p_clamp, -1), (m_clamp, 1)):
        for i, at in enumerate((0.015, 0.026)):
            assert float(sp.N(clamp[i])) == pytest.approx(at + sign * span / 2 * float(c[i]))


# -- the reader ------------------------------------------------------------------------------------


def refused(text_defaults, a0="", match=()):
    with pytest.raises(InputError) as err:
        four_bar(defaults=text_defaults, a0=a0, name="bad_notch.toml")
    text = str(err.value)
    assert err.value.exit_code == 2 and "bad_notch.toml" in text and "fix:" in text
    for m in match:
        assert m in text, text
    return text


def test_reader_refusals_name_file_hinge_key_and_fix():
    base = 'width = 5e-3\nE = 210e9\nlength = 1e-3\nthickness = 1e-4\nmodel = "circular_arc"'
    # a key of another profile, `length` on a circular notch (its span is 2·radius)
    refused(
        base, 'profile = "circular"\nradius = 1e-3\nlength = 2e-3', ("'A0'", "'length'", "2·radius")
    )
    refused(base, "radius = 1e-3", ("'A0'", "'radius'", 'profile = "circular"'))
    refused(base, 'profile = "elliptical"\nsemi_axis = 1e-3\nfillet = 1e-4', ("'fillet'",))
    # missing keys
    refused(base, 'profile = "circular"', ("'A0'", "needs 'radius'"))
    refused(base, 'profile = "elliptical"\nsemi_axis = 1e-3', ("needs 'depth'",))
    refused(
        "width = 5e-3\nlength = 1e-3", 'profile = "circular"\nradius = 1e-3', ("needs 'thickness'",)
    )
    # T(x) ≤ 0: a thickness that is not positive
    refused(base, 'profile = "circular"\nradius = 1e-3\nthickness = -1e-5', ("'thickness'", "T(x)"))
    refused(base, 'profile = "circular"\nradius = 0', ("'radius'", "positive"))
    # a uniform plate's model written on a notch
    refused(base, 'profile = "circular"\nradius = 1e-3\nmodel = "prbm"', ("'prbm'", "pure_moment"))
    refused(base, 'profile = "circular"\nradius = 1e-3\nmodel = "circular_arc"', ("circular_arc",))
    # fillets that do not fit, an unknown profile
    refused(base, 'profile = "corner_filleted"\nfillet = 6e-4', ("fillet", "length/2"))
    refused(base, 'profile = "circlar"', ("circlar", "circular"))


def test_defaults_serve_the_profiles_that_take_them():
    """[defaults]' length and circular_arc keep serving the plates; the notch takes its own keys
    and pure_moment; a hinge's own model `rigid`, `table` or `expr` stays available."""
    base = 'width = 5e-3\nE = 210e9\nlength = 1e-3\nthickness = 1e-4\nmodel = "circular_arc"'
    mech = four_bar(base, 'profile = "circular"\nradius = 2e-3')
    a0, a = mech.hinge("A0"), mech.hinge("A")
    assert (a0.profile, a0.model, float(a0.length)) == ("circular", "pure_moment", 4e-3)
    assert dict(a0.profile_params) == {"radius": sp.Float(2e-3)} or float(
        dict(a0.profile_params)["radius"]
    ) == pytest.approx(2e-3)
    assert (a.profile, a.model, float(a.length)) == ("uniform", "circular_arc", 1e-3)
    rigid = four_bar(base, 'profile = "circular"\nradius = 2e-3\nmodel = "rigid"').hinge("A0")
    assert rigid.model == "rigid" and float(rigid.length) == pytest.approx(4e-3)


def test_check_prints_profile_and_span():
    from symkin.cli.output import check_text
    from symkin.graph.structure import build

    text = check_text(build(four_bar()))
    assert "A0  s0 -> s1  pure_moment  profile circular, span 2*R" in text
    base = "width = 5e-3\nE = 210e9\nlength = 1e-3\nthickness = 1e-4"
    text = check_text(build(four_bar(base)))
    assert "A  s1 -> s2  circular_arc  profile uniform, span 1/1000" in text


# -- the pure-moment shape -------------------------------------------------------------------------


class Bent:
    """A notch bent by a pure moment, by nested quadrature of its own T(x) at DPS digits."""

    def __init__(self, depth, span, cuts):
        self.depth = depth
        with mpmath.workdps(DPS):
            self.l = mp(span)
            self.cuts = sorted(mp(c) for c in cuts)
            self.memo: dict = {}  # Ψ at the outer quadrature's nodes (the same for every θ)
            self.total = self.quad(lambda x: self.depth(x) ** -3, 0, self.l)

    def quad(self, f, a, b):
        pts = [a] + [c for c in self.cuts if a < c < b] + [b]
        return mpmath.quad(f, pts)

    def psi(self, x):
        if x not in self.memo:
            self.memo[x] = self.quad(lambda y: self.depth(y) ** -3, 0, x) / self.total
        return self.memo[x]

    def fg(self, theta):
        with mpmath.workdps(DPS):
            f = self.quad(lambda x: mpmath.cos(theta * self.psi(x)), 0, self.l)
            g = self.quad(lambda x: mpmath.sin(theta * self.psi(x)), 0, self.l)
        return f, g

    def c1(self):
        """ĉ_1 = ∫(Ψ̃² − 1/4) dx / l."""
        with mpmath.workdps(DPS):
            return self.quad(lambda x: (self.psi(x) - 0.5) ** 2 - 0.25, 0, self.l) / self.l


def notch_functions(mech, name):
    return hinges.plate_functions(mech.hinge(name))


@pytest.mark.parametrize("profile", sorted(CASES))
def test_pure_moment_against_nested_quadrature(profile):
    """f, g of the pure-moment model against the bent notch's nested quadrature at θ from 1e-6
    to π; the deviation from the centre pin df, dg to 1e-14 relative down to θ = 1e-6 (no
    cancellation), the first coefficient to 20 digits."""
    keys, reference, span = CASES[profile]
    mech = four_bar(defaults=f'profile = "{profile}"\n{keys}\nwidth = 5e-3\nE = 210e9')
    pf = notch_functions(mech, "A")
    mid = sp.Rational(str(span)) / 2
    cuts = [mid * sp.Rational(9, 10), mid, mid * sp.Rational(11, 10)]
    if profile == "corner_filleted":
        cuts += [sp.Rational(1, 1000), sp.Rational(4, 1000)]
    cuts = [sp.N(c, 50) for c in cuts]
    bent = Bent(lambda x: reference(x), span, cuts)
    sec = profiles.section_of(mech.hinge("A"), 1)
    assert float(notches.coefficients(sec)[0]) == pytest.approx(float(bent.c1()), rel=1e-20)
    t = hinges.THETA
    for theta in ("1e-6", "0.05", "-1.5", "3.14159"):
        with mpmath.workdps(DPS):
            th = mp(theta)
        f, g = bent.fg(th)
        half = th / 2
        with mpmath.workdps(DPS):
            df_ref = f - bent.l * mpmath.cos(half) ** 2
            dg_ref = g - bent.l * mpmath.sin(half) * mpmath.cos(half)
        with mpmath.workdps(DPS):
            got = [sp.N(e.xreplace({t: sp.Float(theta, 40)}), 40) for e in (pf.df, pf.dg, pf.f)]
        assert float(got[0]) == pytest.approx(float(df_ref), rel=1e-14)
        assert float(got[1]) == pytest.approx(float(dg_ref), rel=1e-14)
        assert float(got[2]) == pytest.approx(float(f), rel=1e-15)
        # float64, as the generated code evaluates it
        fn = sp.lambdify(t, pf.df, "math")
        assert fn(float(theta)) == pytest.approx(float(df_ref), rel=1e-13)


def test_pure_moment_on_a_uniform_plate_is_the_circular_arc_to_the_bit():
    base = "width = 5e-3\nE = 210e9\nlength = 1e-3\nthickness = 1e-4"
    arc = four_bar(base).hinge("A")
    pure = four_bar(base + '\nmodel = "pure_moment"').hinge("A")
    assert arc.model == "circular_arc" and pure.model == "pure_moment"
    a, b = hinges.plate_functions(arc), hinges.plate_functions(pure)
    for key in ("f", "g", "df", "dg", "f_rigid", "g_rigid"):
        assert sp.srepr(getattr(a, key)) == sp.srepr(getattr(b, key))
    assert hinges.pivot_distance(pure) == hinges.pivot_distance(arc)


def test_thin_notch_limit_of_the_shape():
    """As t/R → 0 the notch turns about its centre: ĉ_1 → κ √(t/R), κ = (1/4)∫₀^∞ (F² − 1) ds
    with F(s) = ∫₀^s (1 + σ²)⁻³ dσ/(3π/16) (the neck's profile t(1 + x²/(R t))): its closed
    form s/(4(1 + s²)²) + 3s/(8(1 + s²)) + (3/8) atan s, over 3π/16."""
    with mpmath.workdps(30):

        def big_f(s):
            q = 1 + s**2
            return (s / (4 * q**2) + 3 * s / (8 * q) + 3 * mpmath.atan(s) / 8) / (
                3 * mpmath.pi / 16
            )

        # 1 − F ≈ (16/(15π)) s⁻⁵: beyond s = 1e4 the integrand leaves below 1e-17
        kappa = mpmath.quad(lambda s: big_f(s) ** 2 - 1, [0, 1, 10, 100, 1000, 10**4]) / 4
    errors = []
    for ratio in (1e-2, 1e-4):
        sec = notches.CircularNotch("A", sp.Integer(2), sp.Float(ratio, 30), 1, 1, 0, 1, 1)
        c1 = float(notches.coefficients(sec)[0])
        errors.append(abs(c1 / math.sqrt(ratio) / float(kappa) - 1))
    assert errors[0] < 1e-2 and errors[1] < 1e-4 and errors[1] < errors[0] / 50, errors


# -- mechanisms through every backend -------------------------------------------------------------


def test_notch_parallelogram_translates_by_twice_the_centre_deviation():
    """A parallelogram of four circular notches (t/R = 0.1): the stage translates, deviating
    from the rigid one by 2 D(q) (−sin q/2, cos q/2), D(q) = ∫cos qΨ̃ − l cos(q/2) by quadrature."""
    mech = parallelogram()
    an = symkin.analyze(mech)
    bent = Bent(lambda x: circular_t(x, "1e-3", "1e-4"), "2e-3", ["9e-4", "1e-3", "1.1e-3"])
    for q in ("0.02", "0.05"):
        ev = symkin.evaluate(an, {"F1": q}, level="exact")
        dev = ev.points["P"].deviation
        with mpmath.workdps(DPS):
            qm = mp(q)
            f, _ = bent.fg(qm)
            # D(q) from f = cos(q/2) C(q): C = f/cos(q/2)
            d = f / mpmath.cos(qm / 2) - bent.l * mpmath.cos(qm / 2)
        want = (-2 * d * mpmath.sin(qm / 2), 2 * d * mpmath.cos(qm / 2))
        assert float(dev[0]) == pytest.approx(float(want[0]), rel=1e-9)
        assert float(dev[1]) == pytest.approx(float(want[1]), rel=1e-9)


@pytest.mark.parametrize("build", [four_bar, parallelogram], ids=["four_bar", "parallelogram"])
def test_notch_mechanisms_agree_in_every_backend(build):
    mech = build()
    gen = Generated(mech=mech, sensitivity=False, levels=("paper", "first_order", "exact"))
    name = mech.inputs[0]
    an = gen.analysis
    for q in ("0.02", "0.05", "-0.3"):
        for level in ("first_order", "exact"):
            ref = symkin.evaluate(an, {name: q}, level=level)
            want = {p: tuple(float(v) for v in ref.points[p].deviation) for p in ref.points}
            for backend in GENERATED:
                require(backend)
                got = gen.run(backend, {name: q}, level)
                for p, (x, y) in want.items():
                    scale = math.hypot(x, y)
                    assert math.hypot(got[p][0] - x, got[p][1] - y) <= 1e-9 * scale, (backend, p)
    assert "sympy" in BACKENDS
