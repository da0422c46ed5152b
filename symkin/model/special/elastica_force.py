"""The elastica of a cantilever under a transverse tip force, as functions of its tip angle θ
(|θ| < π/2; s = sin θ, c = cos θ, q = s^2), and the Carlson integrals that evaluate it:

    A(q) = R_F(1 - s, 1 + s, c^2) = ∫_0^1 dv / sqrt(1 - q (1 - v^2)^2)
    C(q) = c^2/3 R_D(1 - s, 1 + s, c^2) = ∫_0^1 v^2 dv / sqrt(1 - q (1 - v^2)^2)
    A1(q) = (A - 1)/q  (Taylor series in q below q = Q_SERIES)

    elastica_x = x_tip/l = 1/A            elastica_y = y_tip/l = s (1 - C/A)
    elastica_dx = x/l - cos^2(θ/2) = q (1/(2(1 + c)) - A1/A)
    elastica_dy = y/l - sin(θ)/2   = s (1/2 - C/A)
    elastica_dx_d1 = d elastica_dx/dθ = s (1/2 - (A + C - A1)/(2 c A^2))
    elastica_dy_d1 = d elastica_dy/dθ = c/2 (1 + q (A + C - A1)/(c^2 A)) C/A

The load is α = P l^2/(EI) = 2 s A^2.  These follow from the first integral of the elastica
φ'' = -α cos φ (φ(0) = 0, φ'(1) = 0) with the substitution sin φ = s (1 - v^2); they are the
Bisshopp-Drucker elliptic-integral solution in Carlson's symmetric form (``rewrite("elliptic")``
gives the Legendre form with sympy's elliptic_f / elliptic_e).  The float algorithm (helpers
`carlson_rf`, `carlson_rd`, `elastica_core`, then each output's formula) is written out by each
backend; out of the domain it gives NaN (C, numpy) or raises :class:`DomainError` (Python).
"""

from __future__ import annotations

import math
from fractions import Fraction

import mpmath
import sympy as sp
from sympy.core.function import ArgumentIndexError

from .kernels import _from_mp, _to_mp
from .registry import UNIT_ROUNDOFF, DomainError, register

#: The elastica under a purely transverse tip force reaches tip angles |θ| < π/2 only.
ELASTICA_LIMIT = sp.pi / 2
#: The largest double below π/2: float code refuses |θ| beyond it.
HALF_PI_FLOAT = math.pi / 2
#: Below q = sin^2 θ = Q_SERIES, A1 = (A - 1)/q comes from its Taylor series.
Q_SERIES = 0.25

#: Carlson's stopping constants (3r)^(-1/6) for R_F and (r/4)^(-1/6) for R_D, r = 2^-53.
RF_STOP = (3 * UNIT_ROUNDOFF) ** (-1 / 6)
RD_STOP = (UNIT_ROUNDOFF / 4) ** (-1 / 6)
RF_DOC = "Carlson's R_F(x, y, z), x, y, z >= 0 (at most one zero): duplication (Carlson 1995)"
RD_DOC = "Carlson's R_D(x, y, z), x, y >= 0 (at most one zero), z > 0: duplication (Carlson 1995)"

#: What each output is, in plain text (for comments and docstrings of generated code).
OUTPUTS = {
    "elastica_x": "x_tip/l = 1/A",
    "elastica_y": "y_tip/l = s (1 - C/A)",
    "elastica_dx": "x_tip/l - cos^2(t/2) = q (1/(2(1+c)) - A1/A)",
    "elastica_dy": "y_tip/l - sin(t)/2 = s (1/2 - C/A)",
    "elastica_dx_d1": "d elastica_dx/dt = s (1/2 - (A + C - A1)/(2 c A^2))",
    "elastica_dy_d1": "d elastica_dy/dt = c/2 (1 + q (A + C - A1)/(c^2 A)) C/A",
}


def _elastica_a_coeffs(n: int) -> list[Fraction]:
    """Exact Taylor coefficients of A(q) = ∫_0^1 (1 - q (1-v^2)^2)^(-1/2) dv:
    A_k = binom(2k, k)/4^k * ∫_0^1 (1 - v^2)^(2k) dv,
    with ∫_0^1 (1 - v^2)^m dv = 4^m m!^2/(2m+1)!."""
    out = []
    for k in range(n):
        a = Fraction(math.comb(2 * k, k), 4**k)
        m = 2 * k
        beta = Fraction(4**m * math.factorial(m) ** 2, math.factorial(2 * m + 1))
        out.append(a * beta)
    return out


def _elastica_a1_series() -> list[float]:
    """Float Taylor coefficients of A1(q), as many as make the first dropped term at
    q = Q_SERIES smaller than 2^-53 times A1's lower bound 4/15."""
    coeffs = _elastica_a_coeffs(200)[1:]  # A1(q) = sum_k A_(k+1) q^k, A1 >= 4/15
    bound = Fraction(4, 15) * Fraction(UNIT_ROUNDOFF)
    qt = Fraction(Q_SERIES)
    n = 1
    while coeffs[n] * qt**n >= bound:
        n += 1
    return [float(c) for c in coeffs[:n]]


#: Float Taylor coefficients of A1(q) = (A - 1)/q in q, used below Q_SERIES.
A1_SERIES = _elastica_a1_series()


# -- high precision (mpmath) -----------------------------------------------------------------------


def _elastica_mp(name: str, t, prec: int):
    """Value of elastica function `name` at mpmath real t, correct to about `prec` bits."""
    if not abs(t) < mpmath.pi / 2:
        raise DomainError(
            f"elastica_force: tip angle |theta| = {mpmath.nstr(abs(t), 8)} is not "
            "below pi/2, the largest tip angle a transverse end force can produce"
        )
    if t == 0:
        return {"elastica_x": mpmath.mpf(1), "elastica_dy_d1": mpmath.mpf(1) / 6}.get(
            name, mpmath.mpf(0)
        )
    # A - 1 ~ 4q/15 and the rigid terms cancel to O(q): guard bits for that loss and for 1/c
    lost = max(0, 2 * int(-mpmath.log(abs(t), 2)) + 2) if abs(t) < 1 else 0
    near = mpmath.pi / 2 - abs(t)
    lost += max(0, int(-mpmath.log(near, 2)) + 2) if near < 1 else 0
    wp = prec + 40 + lost
    with mpmath.workprec(wp):
        t = mpmath.mpf(t)
        s, c = mpmath.sin(t), mpmath.cos(t)
        q, z = s * s, c * c
        y = 1 + abs(s)
        x = z / y
        A = mpmath.elliprf(x, y, z)
        C = z * mpmath.elliprd(x, y, z) / 3
        A1 = (A - 1) / q
        value = {
            "elastica_x": lambda: 1 / A,
            "elastica_y": lambda: s * (1 - C / A),
            "elastica_dx": lambda: q * (1 / (2 * (1 + c)) - A1 / A),
            "elastica_dy": lambda: s * (mpmath.mpf(1) / 2 - C / A),
            "elastica_dx_d1": lambda: s * (mpmath.mpf(1) / 2 - (A + C - A1) / (2 * c * A * A)),
            "elastica_dy_d1": lambda: c / 2 * (1 + q * (A + C - A1) / (z * A)) * C / A,
        }[name]()
    with mpmath.workprec(prec):
        return +value


def _elastica_mpmath_function(name: str):
    def impl(t):
        t = mpmath.mpmathify(t)
        return _elastica_mp(name, t, mpmath.mp.prec)

    impl.__name__ = name
    return impl


register("carlson_rf", None, mpmath.elliprf)
register("carlson_rd", None, mpmath.elliprd)
register("elastica_core", None, None, ("carlson_rf", "carlson_rd"))


# -- sympy classes ---------------------------------------------------------------------------------


def _check_elastica_domain(t: sp.Expr) -> None:
    """Raise DomainError for a number t with |t| >= π/2 (or not real)."""
    if not t.is_number:
        return
    if t.is_extended_real is False:
        raise DomainError(f"elastica_force: tip angle {t} is not real")
    beyond = (sp.Abs(t) - ELASTICA_LIMIT).is_nonnegative
    if beyond:
        raise DomainError(
            f"elastica_force: tip angle |theta| = {sp.N(sp.Abs(t), 8)} reaches "
            "pi/2, the largest tip angle a purely transverse end force can "
            "produce (the load would be infinite)"
        )


def _legendre_xy(t: sp.Expr) -> tuple[sp.Expr, sp.Expr]:
    """Bisshopp-Drucker tip position (x/l, y/l) in Legendre form, any sign of t (|t| < π/2):
    m = (1 + s)/2, ψ0 = asin(1/sqrt(1 + s)), sqrt(α) = K(m) - F(ψ0|m),
    x/l = sqrt(2 s/α), y/l = 1 - 2 (E(m) - E(ψ0|m))/sqrt(α), s = |sin t|, y odd in t."""
    s = sp.Abs(sp.sin(t))
    m = (1 + s) / 2
    psi0 = sp.asin(1 / sp.sqrt(1 + s))
    root_alpha = sp.elliptic_k(m) - sp.elliptic_f(psi0, m)
    x = sp.sqrt(2 * s) / root_alpha
    y = sp.sign(t) * (1 - 2 * (sp.elliptic_e(m) - sp.elliptic_e(psi0, m)) / root_alpha)
    return x, y


def _closed_d1(name: str, t: sp.Expr, X: sp.Expr, Y: sp.Expr) -> sp.Expr:
    """The first derivatives as algebraic functions of θ, X = x/l and Y = y/l (exact, but with
    cancellation at small θ: used only for second derivatives and the Legendre rewrite)."""
    s, c = sp.sin(t), sp.cos(t)
    q = s**2
    A = 1 / X
    C = A * (1 - Y / s)
    A1 = (A - 1) / q
    if name == "elastica_dx_d1":
        return s * (sp.Rational(1, 2) - (A + C - A1) / (2 * c * A**2))
    return c / 2 * (1 + q * (A + C - A1) / (c**2 * A)) * C / A


class ElasticaFunction(sp.Function):
    """Base of the tip-force elastica functions of the tip angle θ (|θ| < π/2; see module doc)."""

    nargs = 1
    _parity = 1  # +1 even, -1 odd in θ
    _at_zero = sp.S.Zero

    @classmethod
    def eval(cls, t):
        if t.is_zero:
            return cls._at_zero
        if t.is_number:
            _check_elastica_domain(t)
            if t.is_Float:
                value = _elastica_mp(cls.__name__, _to_mp(t, t._prec + 10), t._prec)
                return _from_mp(value, t._prec)
        if t.could_extract_minus_sign():
            return cls._parity * cls(-t)
        return None

    def _eval_evalf(self, prec):
        t = self.args[0]
        if not t.is_number:
            return None
        _check_elastica_domain(t)
        try:
            tv = _to_mp(t, prec + 80)
        except (TypeError, ValueError, AttributeError):
            return None
        if isinstance(tv, mpmath.mpc):
            if tv.imag != 0:
                raise DomainError(f"elastica_force: tip angle {t} is not real")
            tv = tv.real
        return _from_mp(_elastica_mp(type(self).__name__, tv, prec), prec)

    def _eval_is_real(self):
        return self.args[0].is_extended_real or None

    def _eval_rewrite_as_elliptic(self, t, **kwargs):
        X, Y = _legendre_xy(t)
        name = type(self).__name__
        if name == "elastica_x":
            return X
        if name == "elastica_y":
            return Y
        if name == "elastica_dx":
            return X - sp.cos(t / 2) ** 2
        if name == "elastica_dy":
            return Y - sp.sin(t) / 2
        return _closed_d1(name, t, X, Y)

    _eval_rewrite_as_elementary = _eval_rewrite_as_elliptic
    _eval_rewrite_as_elliptic_f = _eval_rewrite_as_elliptic


class elastica_x(ElasticaFunction):
    """x_tip/l of the tip-force elastica (even in θ): 1/R_F(1-|s|, 1+|s|, c^2)."""

    _parity = 1
    _at_zero = sp.S.One

    def fdiff(self, argindex=1):
        if argindex != 1:
            raise ArgumentIndexError(self, argindex)
        t = self.args[0]
        return elastica_dx_d1(t) - sp.sin(t) / 2


class elastica_y(ElasticaFunction):
    """y_tip/l of the tip-force elastica (odd in θ): s (1 - C/A)."""

    _parity = -1

    def fdiff(self, argindex=1):
        if argindex != 1:
            raise ArgumentIndexError(self, argindex)
        t = self.args[0]
        return elastica_dy_d1(t) + sp.cos(t) / 2


class elastica_dx(ElasticaFunction):
    """x_tip/l - cos^2(θ/2) (even, O(θ^2): -θ^2/60 + ...), cancellation-free."""

    _parity = 1

    def fdiff(self, argindex=1):
        if argindex != 1:
            raise ArgumentIndexError(self, argindex)
        return elastica_dx_d1(self.args[0])


class elastica_dy(ElasticaFunction):
    """y_tip/l - sin(θ)/2 (odd, θ/6 + ...), cancellation-free."""

    _parity = -1

    def fdiff(self, argindex=1):
        if argindex != 1:
            raise ArgumentIndexError(self, argindex)
        return elastica_dy_d1(self.args[0])


class _ElasticaD1(ElasticaFunction):
    def fdiff(self, argindex=1):
        """Second derivative: exact (from the algebraic form in X, Y), but not cancellation-free
        at small θ in float64."""
        if argindex != 1:
            raise ArgumentIndexError(self, argindex)
        d = sp.Dummy("t", real=True)
        expr = _closed_d1(type(self).__name__, d, elastica_x(d), elastica_y(d))
        return sp.diff(expr, d).subs(d, self.args[0])


class elastica_dx_d1(_ElasticaD1):
    """d/dθ elastica_dx (odd, -θ/30 + ...), cancellation-free."""

    _parity = -1


class elastica_dy_d1(_ElasticaD1):
    """d/dθ elastica_dy (even, 1/6 + ...), cancellation-free."""

    _parity = 1
    _at_zero = sp.Rational(1, 6)


ELASTICA_FUNCTIONS = (
    elastica_x,
    elastica_y,
    elastica_dx,
    elastica_dy,
    elastica_dx_d1,
    elastica_dy_d1,
)
for _cls in ELASTICA_FUNCTIONS:
    register(_cls.__name__, _cls, _elastica_mpmath_function(_cls.__name__), ("elastica_core",))


def elastica_load(theta: sp.Expr) -> sp.Expr:
    """The load α = P l^2/(EI) that bends the plate to tip angle θ: 2 sin θ / X_e(θ)^2."""
    return 2 * sp.sin(theta) / elastica_x(theta) ** 2
