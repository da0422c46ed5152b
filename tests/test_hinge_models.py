"""Hinge models (docs/file-format.md) and the cancellation-free special functions behind them.

Every reference here is computed independently of the code under test, with mpmath at 90 digits
straight from the models' defining formulas in docs/file-format.md (the deviation as the plain
difference f - f_rigid, which 90 digits make harmless), and for the elastica from the first
integral of the elastica ODE by quadrature, cross-checked against a shooting solution of the ODE
itself.
"""

from __future__ import annotations

import math
import os
import shutil
import subprocess

import mpmath as mp
import numpy as np
import pytest
import sympy as sp
from evaluators import require_compiler

from symkin.codegen.backends.c import kernels as c_kernels
from symkin.codegen.backends.c.printer import CPrinter
from symkin.codegen.backends.numpy import kernels as np_kernels
from symkin.model import hinges as hm
from symkin.model import special
from symkin.model.entries import Hinge
from symkin.model.hinges import PLATE_LENGTH, THETA

DPS = 90  # reference precision (digits)
F64_TOL = 1e-12  # required float64 relative accuracy of df, dg and derivatives
ULP = 2.0**-52

GAMMA, CTHETA = sp.Rational("0.8517"), sp.Rational("1.2385")
MOMENT = (sp.Rational("0.7346"), sp.Rational("1.5164"))


def hinge(model: str, params: tuple = (), length: sp.Expr = sp.S.One) -> Hinge:
    return Hinge(
        "H",
        0,
        ("P", "M"),
        (sp.Integer(0), sp.Integer(0)),
        sp.Integer(0),
        length,
        model,
        tuple(sorted(params)),
    )


PRBM = (("c_theta", CTHETA), ("gamma", GAMMA))
PRBM_MOMENT = (("c_theta", MOMENT[1]), ("gamma", MOMENT[0]))

# θ grids: from 1e-12 to each model's limit
SMALL = [1e-12, 3e-11, 1e-10, 1e-8, 1e-6, 1e-4, 1e-3, 1e-2]
GRID = {
    "circular_arc": SMALL
    + [0.1, 0.3, 0.5, 0.9, 1.2, 1.5, 2.0, 2.5, 3.0, 4.0, 5.0, 6.0, -0.7, -1e-9],
    "small_deflection": SMALL + [0.1, 0.5, 1.0, 2.0, 3.0, 5.0, -0.4, -1e-7],
    "prbm": SMALL + [0.1, 0.3, 0.6, 1.0, 1.5, 2.0, 2.5, 3.0, -0.5, -1e-9],
    "prbm_moment": SMALL + [0.1, 0.5, 1.0, 2.0, 3.0],
    "elastica_force": SMALL
    + [0.05, 0.1, 0.3, 0.5, 0.52, 0.7, 0.9, 1.2, 1.4, 1.5, 1.55, 1.569, -0.6, -1e-9],
}
MODELS = {
    "circular_arc": ("circular_arc", ()),
    "small_deflection": ("small_deflection", ()),
    "prbm": ("prbm", PRBM),
    "prbm_moment": ("prbm", PRBM_MOMENT),
    "elastica_force": ("elastica_force", ()),
}


# =============================================================================================
# Independent references (l = 1)
# =============================================================================================


def _rigid(t):
    return (1 + mp.cos(t)) / 2, mp.sin(t) / 2, -mp.sin(t) / 2, mp.cos(t) / 2


def _elastica_integrals(t):
    """Tip of the cantilever elastica with tip angle t > 0 under a transverse end force, from the
    first integral of EI φ'' = -P cos φ (φ(0) = 0, φ'(L) = 0):  φ'^2 = 2α (sin t - sin φ), so
    ds = dφ / sqrt(2α (sin t - sin φ)).  With sin φ = sin t (1 - v^2), w = 1 - v^2, q = sin^2 t:
        L-normalised:  1 = sqrt(2 sin t/α) ∫_0^1 dv/sqrt(1 - q w^2)          (length)
        x/L = 1/A,   y/L = sin t · B/A,   A = ∫ dv/sqrt(1 - q w^2),  B = ∫ w dv/sqrt(1 - q w^2).
    Returns x, y, x', y' (d/dt, by differentiating under the integral) and α = 2 sin t A^2."""
    s, c = mp.sin(t), mp.cos(t)
    q = s * s
    pts = [0, mp.sqrt(1 - q) if q < 1 else 0, 1]
    pts = sorted(set(pts))

    def integral(fun):
        return mp.quad(fun, pts)

    A = integral(lambda v: 1 / mp.sqrt(1 - q * (1 - v * v) ** 2))
    B = integral(lambda v: (1 - v * v) / mp.sqrt(1 - q * (1 - v * v) ** 2))
    Aq = integral(lambda v: (1 - v * v) ** 2 / (1 - q * (1 - v * v) ** 2) ** 1.5) / 2
    Bq = integral(lambda v: (1 - v * v) ** 3 / (1 - q * (1 - v * v) ** 2) ** 1.5) / 2
    dq = 2 * s * c
    x, y = 1 / A, s * B / A
    dx = -Aq * dq / A**2
    dy = c * B / A + s * dq * (Bq * A - B * Aq) / A**2
    return x, y, dx, dy, 2 * s * A * A


def reference(key: str, theta: float):
    """(f, g, df, dg, f', g', df', dg') at θ for l = 1, mpmath at DPS digits."""
    with mp.workdps(DPS + 2 * max(0, int(-math.log10(abs(theta))))):
        t = mp.mpf(theta)  # the double θ exactly
        fr, gr, dfr, dgr = _rigid(t)
        if key == "circular_arc":
            f, g = mp.sin(t) / t, (1 - mp.cos(t)) / t
            df_ = (t * mp.cos(t) - mp.sin(t)) / t**2
            dg_ = (t * mp.sin(t) - (1 - mp.cos(t))) / t**2
        elif key == "small_deflection":
            f, g, df_, dg_ = mp.mpf(1), t / 2, mp.mpf(0), mp.mpf(1) / 2
        elif key in ("prbm", "prbm_moment"):
            gamma, c = (GAMMA, CTHETA) if key == "prbm" else MOMENT
            gamma, c = mp.mpf(gamma.p) / gamma.q, mp.mpf(c.p) / c.q
            big = t / c
            f, g = 1 - gamma * (1 - mp.cos(big)), gamma * mp.sin(big)
            df_, dg_ = -gamma * mp.sin(big) / c, gamma * mp.cos(big) / c
        elif key == "elastica_force":
            sign = 1 if t > 0 else -1
            x, y, dx, dy, _ = _elastica_integrals(abs(t))
            f, g, df_, dg_ = x, sign * y, sign * dx, dy
        else:  # pragma: no cover
            raise KeyError(key)
        return [f, g, f - fr, g - gr, df_, dg_, df_ - dfr, dg_ - dgr]


_REF_CACHE: dict = {}


def ref(key, theta):
    if (key, theta) not in _REF_CACHE:
        _REF_CACHE[key, theta] = reference(key, theta)
    return _REF_CACHE[key, theta]


def _mp(v):
    return mp.mpf(float(v)) if isinstance(v, np.generic) else mp.mpf(v)


def rel(a, b) -> float:
    b = _mp(b)
    if b == 0:
        return float(abs(_mp(a)))
    return float(abs((_mp(a) - b) / b))


def plate(key, length=sp.S.One):
    model, params = MODELS[key]
    return hm.plate_functions(hinge(model, params, length))


def expressions(pf):
    ddf, ddg = pf.derivatives()
    return [pf.f, pf.g, pf.df, pf.dg, sp.diff(pf.f, THETA), sp.diff(pf.g, THETA), ddf, ddg]


NAMES = ["f", "g", "df", "dg", "f'", "g'", "df'", "dg'"]


# =============================================================================================
# Kernels
# =============================================================================================

X = sp.Symbol("x", real=True)
#: definitions typed independently of special.py
KERNEL_DEFS = {
    "sinr0": sp.sin(X) / X,
    "sinr1": (sp.sin(X) - X) / X**3,
    "sinr2": (sp.sin(X) - X + X**3 / 6) / X**5,
    "sinr3": (sp.sin(X) - X + X**3 / 6 - X**5 / 120) / X**7,
    "cosr1": (sp.cos(X) - 1) / X**2,
    "cosr2": (sp.cos(X) - 1 + X**2 / 2) / X**4,
    "cosr3": (sp.cos(X) - 1 + X**2 / 2 - X**4 / 24) / X**6,
    "arck": (sp.sin(X) - X * sp.cos(X)) / X**3,
}


def kernel_class(name):
    return {"arck": special.arck}.get(name) or (
        special.sinr(int(name[4:])) if name.startswith("sinr") else special.cosr(int(name[4:]))
    )


@pytest.mark.parametrize("name", sorted(KERNEL_DEFS))
def test_kernel_rewrite_derivative_series(name):
    cls = kernel_class(name)
    definition = KERNEL_DEFS[name]
    assert sp.simplify(cls(X).rewrite("elementary") - definition) == 0
    # derivative: the family form equals the derivative of the definition
    d = sp.diff(cls(X), X)
    assert not d.has(sp.Derivative)
    assert sp.simplify(d.rewrite("elementary") - sp.diff(definition, X)) == 0
    # value and Taylor series at 0 (exact), and the limit of the definition
    assert cls(0) == sp.limit(definition, X, 0)
    assert sp.series(cls(X), X, 0, 8) == sp.series(definition, X, 0, 8)
    assert d.subs(X, 0) == 0
    # parity and LaTeX
    assert cls(-X) == cls(X)
    assert sp.latex(cls(X)).startswith(r"\operatorname")


@pytest.mark.parametrize("name", sorted(KERNEL_DEFS))
def test_kernel_evalf_high_precision(name):
    cls = kernel_class(name)
    for x in ["1e-40", "1e-12", "3e-5", "0.3", "1.7", "2.9", "4.4", "7.5"]:
        xv = sp.Rational(x)
        got = cls(xv).evalf(40)
        with mp.workdps(80 + 7 * max(0, -int(math.log10(float(xv))))):  # cancellation
            want = sp.lambdify(X, KERNEL_DEFS[name], "mpmath")(mp.mpf(xv.p) / xv.q)
        assert rel(got, want) < 1e-38, (name, x)
    # a complex argument takes the series' other branch (mpc)
    z = sp.Rational(3, 10) + sp.Rational(1, 5) * sp.I
    with mp.workdps(80):
        v = cls(z).evalf(40)
        got = mp.mpc(str(sp.re(v)), str(sp.im(v)))
        want = sp.lambdify(X, KERNEL_DEFS[name], "mpmath")(mp.mpc("0.3", "0.2"))
        assert abs(got - want) <= 1e-38 * abs(want), name
    # Float arguments evaluate at their own precision
    assert isinstance(cls(sp.Float("0.25", 30)), sp.Float)


@pytest.mark.parametrize("name", sorted(KERNEL_DEFS))
def test_kernel_float64_numpy_mpmath(name):
    cls = kernel_class(name)
    xs = np.concatenate([[1e-300, 1e-160, 1e-20], np.logspace(-8, 0, 41), np.linspace(1, 8, 141)])
    f64, fnp = np_kernels.float64_namespace()[name], np_kernels.numpy_namespace()[name]
    fmp = special.mpmath_namespace()[name]
    vec = fnp(xs)
    worst = 0.0
    for x, v in zip(xs, vec):
        with mp.workdps(90 + 7 * max(0, math.ceil(-math.log10(x)))):  # the definition cancels
            want = (
                sp.lambdify(X, KERNEL_DEFS[name], "mpmath")(mp.mpf(x))
                if x > 1e-30
                else mp.mpf(cls.coeff(0).p) / cls.coeff(0).q
            )
            if abs(want) < 1e-3 * abs(float(cls.coeff(0))):
                continue  # next to a zero of the kernel
            err = max(rel(f64(float(x)), want), rel(float(v), want), rel(f64(-float(x)), want))
            worst = max(worst, err)
            assert rel(fmp(mp.mpf(x)), want) < 1e-55
    assert worst < 10 * ULP, (name, worst / ULP)
    assert f64(0.0) == float(cls.coeff(0))


def test_kernel_series_threshold_rule():
    """The first dropped Taylor term at the threshold is below the unit roundoff."""
    for name in KERNEL_DEFS:
        cls = kernel_class(name)
        _coeffs, n = cls.float_series()
        dropped = abs(float(cls.coeff(n))) * cls.threshold ** (2 * n)
        assert dropped < 2.0**-53 * abs(float(cls.coeff(0)))


def test_higher_order_kernels_are_created_lazily():
    cls = special.sinr(7)
    assert "sinr7" in np_kernels.float64_namespace()
    assert "symkin_sinr7(" in c_kernels.source("sinr7")
    assert cls(0) == sp.Rational(-1, math.factorial(15))
    d = sp.diff(cls(X), X)  # creates cosr8, sinr8
    assert {"cosr8", "sinr8"} <= set(np_kernels.float64_namespace())
    assert abs(
        np_kernels.float64_namespace()["sinr7"](0.5) - float(cls(sp.Rational(1, 2)).evalf(20))
    ) < 1e-15 * abs(float(cls.coeff(0)))
    assert d.subs(X, 0) == 0


# =============================================================================================
# Models: symbolic identities
# =============================================================================================


@pytest.mark.parametrize("key", ["circular_arc", "small_deflection", "prbm", "prbm_moment"])
def test_deviation_rewrites_to_difference(key):
    pf = plate(key)
    model, params = MODELS[key]
    t = THETA
    f_def = {"circular_arc": sp.sin(t) / t, "small_deflection": sp.Integer(1)}.get(model)
    g_def = {"circular_arc": (1 - sp.cos(t)) / t, "small_deflection": t / 2}.get(model)
    if model == "prbm":
        gamma, c = dict(params)["gamma"], dict(params)["c_theta"]
        f_def, g_def = 1 - gamma * (1 - sp.cos(t / c)), gamma * sp.sin(t / c)
    assert sp.simplify(special.expand_special(pf.f) - f_def) == 0
    assert sp.simplify(special.expand_special(pf.g) - g_def) == 0
    f_r, g_r = (1 + sp.cos(t)) / 2, sp.sin(t) / 2
    assert sp.simplify(pf.f_rigid - f_r) == 0 and sp.simplify(pf.g_rigid - g_r) == 0
    for dev, whole, rigid in ((pf.df, f_def, f_r), (pf.dg, g_def, g_r)):
        diff = special.expand_special(dev) - (whole - rigid)
        assert sp.simplify(sp.expand_trig(sp.expand(diff))) == 0


def test_rigid_model_is_exactly_rigid():
    pf = hm.plate_functions(hinge("rigid", (), sp.Symbol("L", positive=True)))
    assert pf.df == 0 and pf.dg == 0
    assert sp.simplify(pf.f - pf.f_rigid) == 0 and pf.stable


def test_limits_at_zero():
    """Value and derivative at θ -> 0 and the leading series terms (docs/numerics.md: circular arc
    dx/l = θ²/12 - θ⁴/80, dy/l = θ³/24 - θ⁵/360)."""
    t = THETA
    circ = plate("circular_arc")
    assert sp.expand(sp.series(circ.df, t, 0, 6).removeO()) == t**2 / 12 - t**4 / 80
    assert sp.expand(sp.series(circ.dg, t, 0, 6).removeO()) == t**3 / 24 - t**5 / 360
    small = plate("small_deflection")
    assert sp.expand(sp.series(small.df, t, 0, 5).removeO()) == t**2 / 4 - t**4 / 48
    assert sp.expand(sp.series(small.dg, t, 0, 6).removeO()) == t**3 / 12 - t**5 / 240
    pr = plate("prbm")
    k_f = sp.Rational(1, 4) - GAMMA / (2 * CTHETA**2)
    k_g = GAMMA / CTHETA - sp.Rational(1, 2)
    assert sp.simplify(sp.series(pr.df, t, 0, 3).removeO() - k_f * t**2) == 0
    assert sp.series(pr.dg, t, 0, 2).removeO() == k_g * t
    expected_d1 = {
        "circular_arc": 0,
        "small_deflection": 0,
        "prbm": k_g,
        "elastica_force": sp.Rational(1, 6),
    }
    for key, slope in expected_d1.items():
        pf = plate(key)
        ddf, ddg = pf.derivatives()
        assert pf.df.subs(t, 0) == 0 and pf.dg.subs(t, 0) == 0, key
        assert pf.f.subs(t, 0) == 1 and pf.g.subs(t, 0) == 0, key
        assert ddf.subs(t, 0) == 0, key
        assert ddg.subs(t, 0) == slope, key
    # elastica: linear beam theory at small tip angle: y/l = 2θ/3, x/l = 1 - 4θ²/15,
    # so df/l = -θ²/60 and dg/l = θ/6 (+ O(θ³))
    el = plate("elastica_force")
    tiny = sp.Rational(1, 10**8)
    assert abs(el.df.subs(t, tiny).evalf(30) / tiny**2 + sp.Rational(1, 60)) < 1e-15
    assert abs(el.dg.subs(t, tiny).evalf(30) / tiny - sp.Rational(1, 6)) < 1e-15
    assert abs(el.g.subs(t, tiny).evalf(30) / tiny - sp.Rational(2, 3)) < 1e-15
    assert abs((1 - el.f.subs(t, tiny).evalf(30)) / tiny**2 - sp.Rational(4, 15)) < 1e-15


def test_elastica_carlson_equals_legendre_rewrite():
    """The Carlson-form evaluation equals the Bisshopp-Drucker Legendre form (sympy elliptic_f,
    elliptic_e) that rewrite("elliptic") gives, including the derivatives' closed forms."""
    for cls in special.ELASTICA_FUNCTIONS:
        legendre = cls(THETA).rewrite("elliptic")
        assert legendre.has(sp.elliptic_f) or legendre.has(sp.elliptic_k)
        for tv in ["0.05", "0.7", "-1.3"]:
            t = sp.Rational(tv)
            got = cls(t).evalf(30)
            want = legendre.subs(THETA, t).evalf(30)
            assert abs(got - want) <= 1e-27 * max(abs(want), 1e-3), (cls, tv)
    # d/dθ of the Legendre x, y equals the cancellation-free first derivatives
    for tv in ["0.3", "1.1"]:
        t = sp.Rational(tv)
        for dev, d1 in (
            (special.elastica_dx, special.elastica_dx_d1),
            (special.elastica_dy, special.elastica_dy_d1),
        ):
            want = sp.diff(dev(THETA).rewrite("elliptic"), THETA).subs(THETA, t).evalf(30)
            assert abs(d1(t).evalf(30) - want) < 1e-27
    # second derivatives (exact closed form) against numerical differentiation
    with mp.workdps(40):
        for cls in (special.elastica_dx_d1, special.elastica_dy_d1):
            d2 = sp.diff(cls(THETA), THETA).subs(THETA, sp.Rational(1, 2)).evalf(30)
            num = mp.diff(special.mpmath_namespace()[cls.__name__], mp.mpf("0.5"))
            assert abs(d2 - sp.Float(num, 40)) < 1e-25


def test_elastica_parity_and_domain():
    t = sp.Rational(3, 10)
    e = special
    assert e.elastica_x(-t) == e.elastica_x(t) and e.elastica_y(-t) == -e.elastica_y(t)
    assert e.elastica_dx(-THETA) == e.elastica_dx(THETA)
    assert e.elastica_dy(-THETA) == -e.elastica_dy(THETA)
    assert e.elastica_dx_d1(-THETA) == -e.elastica_dx_d1(THETA)
    assert e.elastica_dy_d1(-THETA) == e.elastica_dy_d1(THETA)
    pf = plate("elastica_force")
    assert pf.limit == sp.pi / 2
    for bad in (sp.pi / 2, -sp.pi / 2, sp.Rational(8, 5), sp.Float(2.0)):
        with pytest.raises(special.DomainError):
            pf.df.subs(THETA, bad)
        assert issubclass(special.DomainError, ValueError)
    with pytest.raises(special.DomainError, match="pi/2"):
        np_kernels.float64_namespace()["elastica_dx"](1.5707963267948968)
    with pytest.raises(special.DomainError):
        np_kernels.float64_namespace()["elastica_y"](-2.0)
    with pytest.raises(special.DomainError):
        special.mpmath_namespace()["elastica_x"](mp.mpf(2))
    vector = np_kernels.numpy_namespace()["elastica_dx"]
    assert np.isnan(vector(np.array([0.1, 1.6, np.nan]))[1:]).all()
    assert pf.df.subs(THETA, sp.Rational(3, 2)).is_finite
    # the largest double below π/2 is still inside the domain
    assert 0 < np_kernels.float64_namespace()["elastica_x"](math.pi / 2) < 0.2


def test_length_substitution_and_special_names():
    ell = sp.Symbol("l_A", positive=True)  # a mechanism parameter
    pf = hm.plate_functions(hinge("circular_arc", (), 2 * ell))
    assert not pf.df.has(PLATE_LENGTH) and pf.df.has(ell)
    unit = plate("circular_arc")
    assert sp.simplify(pf.df - 2 * ell * unit.df) == 0
    assert set(special.used_names(pf.f, pf.g, pf.df, pf.dg)) >= {"arck", "sinr0", "cosr1"}
    pe = plate("elastica_force")
    elastica = special.used_names(pe.f, pe.g, pe.df, pe.dg, *pe.derivatives())
    assert elastica == sorted(c.__name__ for c in special.ELASTICA_FUNCTIONS)
    src = c_kernels.support(elastica)
    assert src.index("symkin_carlson_rf(") < src.index("symkin_elastica_core(")
    assert src.index("symkin_elastica_core(") < src.index("symkin_elastica_dx(")


def test_prbm_symbolic_parameters_and_presets():
    gamma, cth = sp.symbols("gamma c_theta", positive=True)
    pf = hm.plate_functions(hinge("prbm", (("c_theta", cth), ("gamma", gamma))))
    assert pf.df.has(gamma) and pf.dg.has(cth)
    num = pf.df.subs({gamma: GAMMA, cth: CTHETA, THETA: sp.Rational(1, 3)}).evalf(30)
    assert abs(num - plate("prbm").df.subs(THETA, sp.Rational(1, 3)).evalf(30)) < 1e-29
    assert hm.PRBM_PRESETS["force"] == {"gamma": "0.8517", "c_theta": "1.2385"}


# =============================================================================================
# Models: numerical accuracy against the independent references
# =============================================================================================


@pytest.mark.parametrize("key", sorted(MODELS))
def test_evalf_30_digits(key):
    """sympy evalf at 30 digits of f, g, df, dg and their θ-derivatives (relative 1e-27)."""
    exprs = expressions(plate(key))
    for theta in GRID[key]:
        want = ref(key, theta)
        t = sp.Rational(theta)  # the double θ exactly
        for name, e, w in zip(NAMES, exprs, want):
            got = e.subs(THETA, t).evalf(30)
            if w == 0:
                assert got == 0, (key, theta, name)
                continue
            assert rel(got, w) < 1e-27, (key, theta, name, got, w)


FLOAT64_WORST: dict = {}


@pytest.mark.parametrize("key", sorted(MODELS))
def test_float64_lambdify(key):
    """df, dg and d/dθ lambdified with the float64 ("math") and numpy kernels of backends/numpy:
    relative error <= 1e-12 (measured: a few 1e-15, see FLOAT64_WORST)."""
    pf = plate(key)
    ddf, ddg = pf.derivatives()
    exprs = [pf.f, pf.g, pf.df, pf.dg, ddf, ddg]
    want_idx = [0, 1, 2, 3, 6, 7]
    scalar = sp.lambdify(THETA, exprs, modules=[np_kernels.float64_namespace(), "math"])
    vector = sp.lambdify(THETA, exprs, modules=[np_kernels.numpy_namespace(), "numpy"])
    grid = GRID[key]
    vec = [np.broadcast_to(v, (len(grid),)) for v in vector(np.array(grid))]
    worst = {}
    for i, theta in enumerate(grid):
        want = ref(key, theta)
        got = scalar(theta)
        for j, (g, k) in enumerate(zip(got, want_idx)):
            if want[k] == 0:
                assert g == 0 and vec[j][i] == 0
                continue
            err = max(rel(g, want[k]), rel(vec[j][i], want[k]))
            worst[NAMES[k]] = max(worst.get(NAMES[k], 0.0), err)
            assert err <= F64_TOL, (key, theta, NAMES[k], err)
    FLOAT64_WORST[key] = worst
    # the kernels keep the deviation well below the required 1e-12: a few hundred ulp at most
    assert max(worst.values()) < 200 * ULP, worst


@pytest.mark.parametrize("key", sorted(MODELS))
def test_mpmath_lambdify(key):
    """lambdify with special.mpmath_namespace() at 30 digits."""
    pf = plate(key)
    fn = sp.lambdify(
        THETA, [pf.df, pf.dg, *pf.derivatives()], modules=[special.mpmath_namespace(), "mpmath"]
    )
    with mp.workdps(30):
        for theta in GRID[key][::3]:
            want = ref(key, theta)
            for got, w in zip(fn(mp.mpf(theta)), [want[2], want[3], want[6], want[7]]):
                if w != 0:
                    assert rel(got, w) < 1e-26, (key, theta)


def test_scaled_length():
    """A tiny plate (l = 1e-6 in exact rational form) scales the deviation exactly."""
    key = "circular_arc"
    pf = plate(key, sp.Rational(1, 10**6))
    fn = sp.lambdify(THETA, [pf.df, pf.dg], modules=[np_kernels.float64_namespace(), "math"])
    for theta in (1e-10, 0.3):
        want = ref(key, theta)
        got = fn(theta)
        assert rel(got[0], want[2] * mp.mpf(10) ** -6) < 1e-14
        assert rel(got[1], want[3] * mp.mpf(10) ** -6) < 1e-14


# =============================================================================================
# Published values
# =============================================================================================

#: Circular arc (plate under a pure end moment), tip position per unit length, as printed to five
#: decimals: x/l = sin θ/θ, y/l = (1 - cos θ)/θ.
ARC_TABLE = {
    10: (0.99493, 0.08705),
    30: (0.95493, 0.25587),
    90: (0.63662, 0.63662),
    120: (0.41350, 0.71620),
}


def test_circular_arc_published_tip_positions():
    pf = plate("circular_arc")
    fn = sp.lambdify(THETA, [pf.f, pf.g], modules=[np_kernels.float64_namespace(), "math"])
    for deg, (x, y) in ARC_TABLE.items():
        t = math.radians(deg)
        fx, gy = fn(t)
        assert abs(fx - x) < 6e-6 and abs(gy - y) < 6e-6, deg
        ex = pf.f.subs(THETA, sp.pi * deg / 180).evalf(30)
        assert abs(ex - x) < 6e-6


#: Cantilever under a transverse end force P, α = P L²/(EI): tip angle θ0 (rad), horizontal
#: shortening Δ/L = 1 - x/L and vertical deflection δ/L = y/L.
#: Literature (Bisshopp & Drucker 1945, Q. Appl. Math. 3, 272; tabulated to five digits e.g. by
#: Mattiasson 1981): α = 1: δ/L 0.30172, Δ/L 0.05643, θ0 0.46135 (26.43°); α = 2: 0.49346,
#: 0.16064, 0.78175; α = 5: 0.71379, 0.38763, 1.21537.
BD_PUBLISHED = {
    1: (0.46135, 0.05643, 0.30172),
    2: (0.78175, 0.16064, 0.49346),
    5: (1.21537, 0.38763, 0.71379),
}
#: Our own independent solution: mpmath.odefun (Taylor method, 30 digits) on the shooting problem
#: φ'' = -α cos φ, φ(0) = 0, φ'(1) = 0 (these are its first 15 digits).
BD_ODE = {
    1: ("0.461351949711879", "0.0564332362833769", "0.301720773799814"),
    2: ("0.781749831556543", "0.160641720825167", "0.493457480396712"),
    5: ("1.21536811761168", "0.387628360724430", "0.713791523611913"),
}


def _shoot(alpha: float):
    """Shooting solution of the elastica ODE in float64 (scipy DOP853, rtol 1e-13)."""
    from scipy import integrate, optimize  # a test dependency (pyproject's `test` extra)

    def rhs(_, u):
        return [u[1], -alpha * math.cos(u[0]), math.cos(u[0]), math.sin(u[0])]

    def end(k0):
        sol = integrate.solve_ivp(
            rhs, (0.0, 1.0), [0.0, k0, 0.0, 0.0], method="DOP853", rtol=1e-13, atol=1e-15
        )
        return sol.y[:, -1]

    k0 = optimize.brentq(lambda k: end(k)[1], 0.0, alpha, xtol=1e-15, rtol=1e-15)
    phi, _, x, y = end(k0)
    return phi, x, y


@pytest.mark.parametrize("alpha", sorted(BD_PUBLISHED))
def test_bisshopp_drucker_tip_positions(alpha):
    theta, x, y = _shoot(float(alpha))
    th_pub, dx_pub, dy_pub = BD_PUBLISHED[alpha]
    th_ode, dx_ode, dy_ode = (float(v) for v in BD_ODE[alpha])
    # the float64 shooting agrees with the 30-digit odefun solution and with the literature
    assert abs(theta - th_ode) < 1e-10 and abs((1 - x) - dx_ode) < 1e-10 and abs(y - dy_ode) < 1e-10
    assert abs(theta - th_pub) < 1e-5 and abs((1 - x) - dx_pub) < 1e-5 and abs(y - dy_pub) < 1e-5
    # the model, given the tip angle, reproduces the tip position and the load
    pf = plate("elastica_force")
    t = sp.Rational(th_ode)
    fx, gy = pf.f.subs(THETA, t).evalf(30), pf.g.subs(THETA, t).evalf(30)
    assert abs(fx - (1 - sp.Rational(dx_ode))) < 1e-14 and abs(gy - sp.Rational(dy_ode)) < 1e-14
    assert abs(special.elastica_load(t).evalf(30) - alpha) < 1e-13
    f64 = sp.lambdify(THETA, [pf.f, pf.g], modules=[np_kernels.float64_namespace(), "math"])
    got = f64(theta)
    assert abs(got[0] - x) < 1e-11 and abs(got[1] - y) < 1e-11


def test_elastica_reference_matches_ode():
    """The quadrature reference (first integral) agrees with the ODE shooting solution."""
    for alpha in (0.3, 3.0):
        theta, x, y = _shoot(alpha)
        with mp.workdps(30):
            xr, yr, _, _, ar = _elastica_integrals(mp.mpf(theta))
        assert abs(xr - x) < 1e-11 and abs(yr - y) < 1e-11 and abs(ar - alpha) < 1e-10


# =============================================================================================
# Table and expression models
# =============================================================================================


def _arc_rows(n=25, span=1.2):
    rows = []
    for k in range(n):
        t = -span + 2 * span * k / (n - 1)
        f = math.sin(t) / t if t else 1.0
        g = (1 - math.cos(t)) / t if t else 0.0
        rows.append((t, f, g))
    return tuple(rows)


def test_table_fit_residuals_and_accuracy():
    rows = _arc_rows()
    h = hinge("table", (("degree", 6), ("file", "arc.csv"), ("rows", rows)))
    pf = hm.plate_functions(h)
    fit = pf.fit
    assert fit.degree == 6 and fit.rows == len(rows) and fit.theta_range == (-1.2, 1.2)
    th = np.array([r[0] for r in rows])
    res_f = np.array([r[1] for r in rows]) - np.polynomial.polynomial.polyval(th, fit.coeffs_f)
    assert math.isclose(fit.rms_f, float(np.sqrt(np.mean(res_f**2))), rel_tol=1e-9)
    assert math.isclose(fit.max_f, float(np.max(np.abs(res_f))), rel_tol=1e-9)
    assert 0 < max(fit.rms_f, fit.rms_g) <= max(fit.max_f, fit.max_g) < 1e-4
    # f, g are the fitted polynomials; df, dg their exact differences from the rigid hinge
    t = sp.Rational(7, 10)
    assert (
        abs(pf.f.subs(THETA, t) - sum(sp.Rational(c) * t**k for k, c in enumerate(fit.coeffs_f)))
        == 0
    )
    for dev, whole, rigid in ((pf.df, pf.f, pf.f_rigid), (pf.dg, pf.g, pf.g_rigid)):
        assert sp.simplify(special.expand_special(dev) - (whole - rigid)) == 0
    # float64 df, dg to full relative accuracy down to tiny θ (reference: the exact polynomial
    # minus the rigid functions at 90 digits)
    fn = sp.lambdify(
        THETA, [pf.df, pf.dg, *pf.derivatives()], modules=[np_kernels.float64_namespace(), "math"]
    )
    with mp.workdps(DPS):
        cf = [mp.mpf(c) for c in fit.coeffs_f]
        cg = [mp.mpf(c) for c in fit.coeffs_g]
        for theta in [1e-12, 1e-9, 1e-6, 1e-3, 0.1, 0.5, 1.0, 1.2, -0.3]:
            tt = mp.mpf(theta)
            want = [
                mp.polyval(cf[::-1], tt) - (1 + mp.cos(tt)) / 2,
                mp.polyval(cg[::-1], tt) - mp.sin(tt) / 2,
                mp.polyval([k * c for k, c in enumerate(cf)][:0:-1], tt) + mp.sin(tt) / 2,
                mp.polyval([k * c for k, c in enumerate(cg)][:0:-1], tt) - mp.cos(tt) / 2,
            ]
            for got, w in zip(fn(theta), want):
                assert rel(got, w) < F64_TOL, theta


def test_expr_model():
    ell = sp.Symbol("L", positive=True)
    h = hinge(
        "expr",
        (
            ("f", PLATE_LENGTH * sp.cos(THETA / 2) ** 2 + PLATE_LENGTH * THETA**2),
            ("g", PLATE_LENGTH * sp.sin(THETA) / 2),
        ),
        3 * ell,
    )
    pf = hm.plate_functions(h)
    assert not pf.stable
    assert sp.simplify(pf.df - 3 * ell * THETA**2) == 0 and sp.simplify(pf.dg) == 0


# =============================================================================================
# Generated-code snippets: C99 and numpy run the same algorithm as FLOAT64
# =============================================================================================


def test_c_snippets_compile_and_agree(tmp_path):
    require_compiler()
    cc = shutil.which(os.environ.get("CC", "cc"))
    f64 = np_kernels.float64_namespace()
    # the beam-column kernels' `_at(p, t)` forms take two arguments: the one-argument kernels
    # call them (tests/test_beam_column_kernels.py checks those on a dense grid)
    helpers = ("carlson_rf", "carlson_rd", "elastica_core")
    names = [n for n in f64 if n not in helpers and not n.endswith("_at")]
    xs = [1e-300, 1e-12, 3e-7, 0.01, 0.24, 0.5, 0.9, 1.3, 1.55, -0.8, 2.2, 4.7, 7.5]
    calls = "\n".join(
        f'    for (i = 0; i < n; ++i) printf("%s %.17g\\n", "{n}", symkin_{n}(xs[i]));'
        for n in names
    )
    driver = (
        "#include <math.h>\n#include <stdio.h>\n"
        + c_kernels.support(names)
        + "\nint main(void)\n{\n    static const double xs[] = {"
        + ", ".join(repr(x) for x in xs)
        + "};\n    const int n = "
        + str(len(xs))
        + ";\n    int i;\n"
        + calls
        + "\n    return 0;\n}\n"
    )
    src = tmp_path / "kernels.c"
    src.write_text(driver)
    exe = tmp_path / "kernels"
    subprocess.run(
        [
            cc,
            "-std=c99",
            "-pedantic",
            "-Wall",
            "-Wextra",
            "-Werror",
            "-O2",
            str(src),
            "-o",
            str(exe),
            "-lm",
        ],
        check=True,
        capture_output=True,
    )
    out = subprocess.run([str(exe)], check=True, capture_output=True, text=True).stdout.split("\n")
    lines = iter(out)
    for name in names:
        for x in xs:
            label, value = next(lines).split()
            assert label == name
            value = float(value)
            try:
                want = f64[name](x)
            except special.DomainError:
                assert math.isnan(value), (name, x)
                continue
            assert value == want or abs(value - want) <= 4 * ULP * abs(want), (name, x)


def test_model_expressions_in_generated_c(tmp_path):
    """The C backend's printing of df, dg and their derivatives (calling symkin_<kernel>(...))
    compiles with the kernels' C source and meets the float64 accuracy bound."""
    require_compiler()
    cc = shutil.which(os.environ.get("CC", "cc"))
    keys = sorted(MODELS)
    names, funcs = set(), []
    for key in keys:
        pf = plate(key)
        exprs = [pf.df, pf.dg, *pf.derivatives()]
        names.update(special.used_names(*exprs))  # only what is called: -Werror=unused
        for j, e in enumerate(exprs):
            funcs.append(
                f"static double {key}_{j}(double theta)\n{{\n"
                f"    return {CPrinter().doprint(e)};\n}}\n"
            )
    thetas = [1e-12, 1e-7, 0.01, 0.3, 1.0, 1.5, -0.4]
    body = "\n".join(
        f'    for (i = 0; i < n; ++i) printf("%.17g\\n", {key}_{j}(ts[i]));'
        for key in keys
        for j in range(4)
    )
    src = tmp_path / "models.c"
    src.write_text(
        "#include <math.h>\n#include <stdio.h>\n"
        + c_kernels.support(names)
        + "\n".join(funcs)
        + "\nint main(void)\n{\n    static const double ts[] = {"
        + ", ".join(repr(t) for t in thetas)
        + "};\n    const int n = "
        + str(len(thetas))
        + ";\n    int i;\n"
        + body
        + "\n    return 0;\n}\n"
    )
    exe = tmp_path / "models"
    subprocess.run(
        [
            cc,
            "-std=c99",
            "-pedantic",
            "-Wall",
            "-Wextra",
            "-Werror",
            "-O2",
            str(src),
            "-o",
            str(exe),
            "-lm",
        ],
        check=True,
        capture_output=True,
    )
    values = iter(
        float(v)
        for v in subprocess.run(
            [str(exe)], check=True, capture_output=True, text=True
        ).stdout.split()
    )
    for key in keys:
        for j, k in enumerate([2, 3, 6, 7]):
            for theta in thetas:
                got, want = next(values), ref(key, theta)[k]
                assert (got == 0 and want == 0) or rel(got, want) <= F64_TOL, (key, j, theta)
