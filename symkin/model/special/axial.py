"""Kernels of the axial load index p = N l^2/EI of a plate (the beam-column under an end force,
docs/physics.md): functions of p that are rational in p and

    T(p) = tanh(u)/u, u = sqrt(p)/2 (p > 0);   tan(v)/v, v = sqrt(-p)/2 (p < 0);   T(0) = 1,

each with a removable singularity at p = 0 and its pole at the plate's sway buckling load
p = -pi^2. The base kernels are those of the plate's mixed potential carried to fourth order in
the bending angle and the lateral load (Timoshenko & Gere, Theory of Elastic Stability, ch. 1,
for the beam-column; the quartic terms by the stationarity of the potential, "2n+1" rule):

    invt = 1/T                       s   = (1 - T)/p               w = (12 s - T^2)/(16 p)
    a    = p w/(3 T^2)               e1, e2, e3 (the quartic energy's coefficients)
    e3c  = e3' + 1/1920

Their derivatives stay in the family because T' = ((1 - T)/p - T^2/4)/2 is rational in p and T:
`bcol_<base>_d<k>` is the k-th p-derivative, created on demand like sinr(n).

Float algorithm (written out by each backend): for |p| < P_SERIES the Taylor series (exact
rational coefficients from the series of tanh(x)/x, Horner in p), else the rational closed form
at T(p); NaN (C, numpy) or DomainError (Python) for p <= -pi^2. mpmath evaluates the series at
high precision near 0 and the closed form with guard bits elsewhere.
"""

from __future__ import annotations

import math
from fractions import Fraction
from functools import cache

import mpmath
import sympy as sp
from sympy.core.function import ArgumentIndexError

from .kernels import _from_mp, _to_mp, evalf_by_mp
from .registry import DomainError, register

#: The symbols of the closed forms: the axial load index and T(p).
P, TT = sp.symbols("p t")
#: T'(p) in terms of p and T (the series branch handles p near 0).
T_PRIME = ((1 - TT) / P - TT**2 / 4) / 2
#: Series below this |p| (radius of convergence pi^2: a term shrinks by P_SERIES/pi^2 ~ 0.2).
P_SERIES = 2.0
#: Exact coefficients from which a float series is cut (FLOAT_TERMS * log10(P_SERIES/pi^2) is
#: about -33: room for the growth of a derivative's coefficients).
FLOAT_TERMS = 48
#: The plate's sway buckling load: every kernel's pole (p = -pi^2).
BUCKLING = -(math.pi**2)

_S = (1 - TT) / P
_W = (12 * _S - TT**2) / (16 * P)
_E1 = (TT**4 * P**2 - 4 * TT**3 * P + 8 * TT**2 * P + 48 * TT - 48) / (512 * TT**2 * P**2)
_E2 = -(TT**4 * P**2 - 4 * TT**3 * P + 24 * TT**2 * P + 240 * TT - 240) / (1024 * P**3)
_E3 = -(3 * TT**4 * P**2 + 20 * TT**3 * P - 24 * TT**2 * P - 48 * TT + 48) / (3072 * TT**4 * P)


def _d(expr: sp.Expr) -> sp.Expr:
    """d/dp of a rational function of (p, T): the chain rule through T' (still rational)."""
    return sp.cancel(sp.together(sp.diff(expr, P) + sp.diff(expr, TT) * T_PRIME))


#: The base kernels: closed form in (p, t) (e3c's derivative is taken on first use, as every
#: closed form is simplified then: importing stays cheap) and one line of plain text.
BASES: dict[str, tuple[sp.Expr, str]] = {
    "invt": (1 / TT, "1/T(p)"),
    "s": (_S, "(1 - T)/p"),
    "w": (_W, "(12 (1 - T)/p - T^2)/(16 p)"),
    "a": (P * _W / (3 * TT**2), "p w(p)/(3 T^2)"),
    "e1": (_E1, "(T^4p^2 - 4T^3p + 8T^2p + 48T - 48)/(512 T^2 p^2)"),
    "e2": (_E2, "-(T^4p^2 - 4T^3p + 24T^2p + 240T - 240)/(1024 p^3)"),
    "e3": (_E3, "-(3T^4p^2 + 20T^3p - 24T^2p - 48T + 48)/(3072 T^4 p)"),
    "e3c": (sp.S.Zero, "e3'(p) + 1/1920"),
}


@cache
def closed_form(base: str, order: int) -> sp.Expr:
    """The closed form in (P, TT) of the `order`-th p-derivative of the base kernel."""
    if order:
        return _d(closed_form(base, order - 1))
    if base == "e3c":
        return sp.cancel(_d(_E3) + sp.Rational(1, 1920))
    return sp.cancel(sp.together(BASES[base][0]))


@cache
def t_series(n: int) -> tuple[Fraction, ...]:
    """The first n Taylor coefficients in p of T(p) = tanh(x)/x, x^2 = p/4:
    tanh(x)/x = sum_{m>=1} 4^m (4^m - 1) B_2m x^(2m-2)/(2m)!."""
    out = []
    for m in range(1, n + 1):
        c = sp.Rational(4**m * (4**m - 1)) * sp.bernoulli(2 * m) / sp.factorial(2 * m)
        c = c / sp.Integer(4) ** (m - 1)
        out.append(Fraction(int(c.p), int(c.q)))
    return tuple(out)


def _mul(a: list[Fraction], b: list[Fraction], n: int) -> list[Fraction]:
    out = [Fraction(0)] * n
    for i, x in enumerate(a[:n]):
        if x:
            for j, y in enumerate(b[: n - i]):
                out[i + j] += x * y
    return out


def _poly_series(expr: sp.Expr, n: int) -> list[Fraction]:
    """n Taylor coefficients of a polynomial in (p, T) with T's series put in."""
    poly = sp.Poly(sp.expand(expr), P, TT)
    t = list(t_series(n))
    powers = {0: [Fraction(1)] + [Fraction(0)] * (n - 1)}
    out = [Fraction(0)] * n
    for (ip, it), c in poly.terms():
        for k in range(max(powers) + 1, it + 1):
            powers[k] = _mul(powers[k - 1], t, n)
        c = sp.Rational(c)
        c = Fraction(int(c.p), int(c.q))
        for j, v in enumerate(powers[it][: n - ip]):
            out[j + ip] += c * v
    return out


@cache
def series_of(expr: sp.Expr, n: int) -> tuple[Fraction, ...]:
    """The first n exact Taylor coefficients in p of a rational function of (p, T) that is
    regular at p = 0 (ValueError if it has a pole there)."""
    num, den = sp.fraction(sp.cancel(sp.together(expr)))
    extra = 16  # the denominator's leading zeros (a power of p) shift the numerator
    a = _poly_series(num, n + extra)
    b = _poly_series(den, n + extra)
    shift = next(i for i, v in enumerate(b) if v != 0)
    if any(a[:shift]):
        raise ValueError(f"{expr} has a pole at p = 0")
    a, b = a[shift:], b[shift:]
    out: list[Fraction] = []
    for k in range(n):
        v = a[k] - sum(out[j] * b[k - j] for j in range(max(0, k - len(b) + 1), k))
        out.append(v / b[0])
    return tuple(out)


def _mp_t(p):
    """T(p) in mpmath at the working precision (p != 0)."""
    if p > 0:
        u = mpmath.sqrt(p) / 2
        return mpmath.tanh(u) / u
    v = mpmath.sqrt(-p) / 2
    return mpmath.tan(v) / v


class AxialKernel(sp.Function):
    """Base of the beam-column kernels: a rational closed form in (p, T(p)), exact Taylor
    coefficients at p = 0, the derivative in the family. Subclasses set `base`, `order`,
    and `definition`; the closed form in the symbols P, TT is `closed()`."""

    nargs = 1
    base = ""
    order = 0
    definition = ""

    @classmethod
    def closed(cls) -> sp.Expr:
        """The closed form in the symbols P and TT."""
        return closed_form(cls.base, cls.order)

    @classmethod
    def coeff(cls, k: int) -> sp.Rational:
        """The exact Taylor coefficient of p^k."""
        c = cls.coefficients(k + 1)[k]
        return sp.Rational(c.numerator, c.denominator)

    @classmethod
    def coefficients(cls, n: int) -> tuple[Fraction, ...]:
        """The first n exact Taylor coefficients (computed in blocks of 16, cached)."""
        return series_of(cls.closed(), 16 * ((n + 15) // 16))[:n]

    @classmethod
    def float_series(cls) -> list[float]:
        """The float coefficients of the series the float algorithm uses below P_SERIES: cut
        where every further term is below 2^-54 of the largest term at |p| = P_SERIES (13 to 31
        terms: the kernels whose pole is at -pi^2 need the most, those of 1/T, entire up to
        -4 pi^2, the fewest)."""
        return _float_series(cls.base, cls.order)

    @classmethod
    def float_closed(cls) -> tuple[list[list[float]], list[list[float]]]:
        """The closed form as numerator and denominator polynomials: per power of T (from 0),
        the coefficients of p^0, p^1, ... (integers, exact in float64), for the float
        algorithm's nested Horner form."""
        return _float_closed(cls.closed())

    @classmethod
    def eval(cls, x):
        if x.is_zero:
            return cls.coeff(0)
        if x.is_Float:
            return _from_mp(cls._mp_value(_to_mp(x, x._prec + 10), x._prec), x._prec)
        return None

    def fdiff(self, argindex=1):
        if argindex != 1:
            raise ArgumentIndexError(self, argindex)
        return kernel(self.base, self.order + 1)(self.args[0])

    def _eval_evalf(self, prec):
        return evalf_by_mp(self, prec)

    def _eval_is_real(self):
        return self.args[0].is_extended_real or None

    @classmethod
    def _mp_value(cls, p, prec: int):
        """Value at `prec` bits for an mpf p > -pi^2: the series for |p| <= 1/2 (a term shrinks
        by at least 1/(2 pi^2)), else the closed form with guard bits, checked by a second
        evaluation (it cancels near p = 0)."""
        if not p > -(mpmath.pi**2):
            raise DomainError(f"{cls.__name__}({p}): the axial load index must exceed -pi^2")
        if abs(p) <= 0.5:
            with mpmath.workprec(prec + 20):
                n = int(prec / 4.3) + 12 + 4 * cls.order
                cs = cls.coefficients(n)
                total = mpmath.mpf(0)
                for c in reversed(cs):
                    total = total * p + mpmath.mpf(c.numerator) / c.denominator
                return +total
        f = _mp_closed(cls.base, cls.order)
        guard = 64
        while True:
            with mpmath.workprec(prec + guard):
                v1 = f(p, _mp_t(p))
            with mpmath.workprec(prec + 2 * guard):
                v2 = f(p, _mp_t(p))
            if v2 == 0 or abs(v1 - v2) <= mpmath.ldexp(abs(v2), -(prec + 4)):
                with mpmath.workprec(prec):
                    return +v2
            guard *= 2
            if guard > 20000:  # pragma: no cover - cannot happen for finite p
                raise ValueError(f"{cls.__name__}({p}): no convergence")

    @classmethod
    def _mpmath_function(cls):
        def impl(p, _cls=cls):
            p = mpmath.mpmathify(p)
            if p == 0:
                c = _cls.coefficients(1)[0]
                return mpmath.mpf(c.numerator) / c.denominator
            return _cls._mp_value(p, mpmath.mp.prec)

        impl.__name__ = cls.__name__
        return impl


@cache
def _float_series(base: str, order: int) -> list[float]:
    cs = [float(c) for c in kernel(base, order).coefficients(FLOAT_TERMS)]
    terms = [abs(c) * P_SERIES**j for j, c in enumerate(cs)]
    bound = 2.0**-54 * max(terms)
    n = len(cs)
    while n > 1 and terms[n - 1] <= bound:
        n -= 1
    if n == len(cs):  # pragma: no cover - the coefficients fall by about P_SERIES/pi^2
        raise ValueError(f"{kernel(base, order).__name__}: its series needs more terms")
    return cs[:n]


@cache
def _float_closed(expr: sp.Expr) -> tuple[list[list[float]], list[list[float]]]:
    num, den = sp.fraction(sp.cancel(sp.together(expr)))
    out = []
    for part in (num, den):
        poly = sp.Poly(sp.expand(part), TT, P)
        rows = [[0.0] * (poly.degree(P) + 1) for _ in range(poly.degree(TT) + 1)]
        for (it, ip), c in poly.terms():
            if not (c.is_Integer and abs(c) < 2**53):
                raise ValueError(f"coefficient {c} of {expr} is not an exact float")
            rows[it][ip] = float(c)
        out.append(rows)
    return out[0], out[1]


@cache
def _mp_closed(base: str, order: int):
    return sp.lambdify((P, TT), closed_form(base, order), "mpmath")


@cache
def kernel(base: str, order: int = 0) -> type:
    """The kernel class of the `order`-th p-derivative of the base kernel `base` (BASES)."""
    if base not in BASES:
        raise ValueError(f"no beam-column kernel '{base}' (kernels: {', '.join(BASES)})")
    order = int(order)
    if order < 0:
        raise ValueError("derivative order must be >= 0")
    name = f"bcol_{base}" + (f"_d{order}" if order else "")
    what = BASES[base][1]
    definition = f"{name}(p) = " + (f"d^{order}/dp^{order} of " if order else "") + what
    cls = type(
        name,
        (AxialKernel,),
        {
            "base": base,
            "order": order,
            "definition": definition,
            "__doc__": definition + " (a beam-column kernel; see symkin.model.special.axial).",
            "__module__": __name__,
        },
    )
    register(name, cls, cls._mpmath_function(), ("bcol_t",))
    globals()[name] = cls
    return cls


def _mp_t_function(p):
    """T(p) at the current mpmath precision (the helper of the float algorithm)."""
    p = mpmath.mpmathify(p)
    if p == 0:
        return mpmath.mpf(1)
    if not p > -(mpmath.pi**2):
        raise DomainError(f"bcol_t({p}): the axial load index must exceed -pi^2")
    return _mp_t(p)


register("bcol_t", None, _mp_t_function)

# The kernels the plate relation and its Jacobian use (and their second derivatives, for a
# Jacobian's derivative), created and registered at import.
for _b in BASES:
    for _order in range(3):
        kernel(_b, _order)
