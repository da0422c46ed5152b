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

Float algorithm (written out by each backend), in two parts so that one transcendental serves
every kernel of a plate: `bcol_<kernel>_at(p, h)` takes h = `bcol_h(p)`, and `bcol_<kernel>(p)`
is `bcol_<kernel>_at(p, bcol_h(p))`. On the near interval NEAR_LOW < p < NEAR_HIGH, where the
closed forms cancel, each kernel (and T itself, h there) is an economised polynomial with its
poles divided out,

    K(p) = p^j P(p - NEAR_CENTRE) / ((p + pi^2)^m (p + 4 pi^2)^n)

(j its order of zero at 0, m and n its pole orders at T = infinity and T = 0; the next
singularity, -9 pi^2, is far, so 12 to 15 terms reach 2^-55). From NEAR_HIGH on, where T ->
2/sqrt(p) makes the closed forms' leading terms cancel, the far form: the closed form in
u = sqrt(p)/2, tanh(u) and sech(u)^2 with the cancelling part summed exactly (FarForm), from
h = 1 - tanh(u). Below NEAR_LOW the rational closed form at h = T(p). NaN (C, numpy) or
DomainError (Python) for p <= -pi^2. mpmath evaluates the exact series at high precision near 0
and the closed form with guard bits elsewhere.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from fractions import Fraction
from functools import cache

import mpmath
import sympy as sp
from sympy.core.function import ArgumentIndexError

from . import axial_forms
from .kernels import _from_mp, _to_mp, evalf_by_mp, horner_mp
from .registry import FUNCTIONS, DomainError, register

#: The symbols of the closed forms: the axial load index and T(p).
P, TT = sp.symbols("p t")
#: T'(p) in terms of p and T (the exact series handle p near 0).
T_PRIME = ((1 - TT) / P - TT**2 / 4) / 2
#: The plate's sway buckling load: every kernel's pole (p = -pi^2).
BUCKLING = -(math.pi**2)
#: The near interval of the float algorithm: below it the closed forms in p and T lose at most
#: 7e-15 down to p = -8 (measured against mpmath, tests/test_beam_column_kernels.py), above it
#: the far forms (the closed forms in p and T cancel towards 0, 6e-12 at p = 2, and as
#: T -> 2/sqrt(p), 4e-12 at p = 60).
NEAR_LOW, NEAR_HIGH = -4.0, 16.0
NEAR_CENTRE = 0.5 * (NEAR_LOW + NEAR_HIGH)
#: The poles the near polynomials divide out, pi^2 and 4 pi^2, as the doubles nearest them.
PI2, FOUR_PI2 = 9.869604401089358, 39.47841760435743
#: Chebyshev nodes of a near fit (the fits keep 12 to 15 terms).
NEAR_NODES = 40

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


@cache
def _t_power(k: int, n: int) -> tuple[Fraction, ...]:
    """n Taylor coefficients of T(p)^k (kept: every kernel's series takes the same powers)."""
    if k == 0:
        return (Fraction(1),) + (Fraction(0),) * (n - 1)
    return tuple(_mul(list(_t_power(k - 1, n)), list(t_series(n)), n))


def _poly_series(expr: sp.Expr, n: int) -> list[Fraction]:
    """n Taylor coefficients of a polynomial in (p, T) with T's series put in."""
    poly = sp.Poly(sp.expand(expr), P, TT)
    out = [Fraction(0)] * n
    for (ip, it), c in poly.terms():
        c = sp.Rational(c)
        c = Fraction(int(c.p), int(c.q))
        for j, v in enumerate(_t_power(it, n)[: n - ip]):
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


@cache
def _mp_coefficients(cls: type[AxialKernel], prec: int) -> tuple[mpmath.mpf, ...]:
    """The Taylor coefficients `_mp_value` sums at `prec` bits, highest power first, as mpf at
    its working precision (kept per precision: converting them is most of an evaluation)."""
    n = int(prec / 4.3) + 12 + 4 * cls.order
    with mpmath.workprec(prec + 20):
        return tuple(mpmath.mpf(c.numerator) / c.denominator for c in reversed(cls.coefficients(n)))


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
    def near_form(cls) -> NearForm:
        """The economised form the float algorithm uses on the near interval."""
        return _near_form(cls.base, cls.order)

    @classmethod
    def far_form(cls) -> FarForm:
        """The form the float algorithm uses from NEAR_HIGH on (no cancellation as T -> 0)."""
        return _far(cls.base, cls.order)

    @classmethod
    def float_closed(cls) -> tuple[list[list[float]], list[list[float]]]:
        """The closed form as numerator and denominator polynomials: per power of T (from 0),
        the coefficients of p^0, p^1, ... (integers, exact in float64), for the float
        algorithm's nested Horner form."""
        kept = axial_forms.CLOSED.get((cls.base, cls.order))
        return kept if kept is not None else _float_closed(cls.closed())

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
            return horner_mp(_mp_coefficients(cls, prec), p, prec + 20)
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


@dataclass(frozen=True)
class NearForm:
    """A kernel on the near interval: p^zero P(p - NEAR_CENTRE) / ((p + pi^2)^poles[0]
    (p + 4 pi^2)^poles[1]), P's float coefficients from p^0."""

    coeffs: tuple[float, ...]
    zero: int
    poles: tuple[int, int]


def _orders(closed: sp.Expr) -> tuple[int, int]:
    """The pole orders of a closed form at T = infinity (p = -pi^2) and T = 0 (p = -4 pi^2): the
    excess of the numerator's highest and the denominator's lowest power of T."""
    num, den = _float_closed(closed)

    def low(rows: list[list[float]]) -> int:
        return next(i for i, r in enumerate(rows) if any(r))

    return max(0, len(num) - len(den)), max(0, low(den) - low(num))


def near_fit(f, zero: int, poles: tuple[int, int]) -> NearForm:
    """The economised polynomial of g(p) = f(p) (p + pi^2)^m (p + 4 pi^2)^n / p^zero on the near
    interval (f an mpmath function): Chebyshev interpolation at NEAR_NODES nodes at 40 digits,
    cut where the dropped coefficients sum below 2^-55 of min |g| on the nodes, then written in
    powers of p - NEAR_CENTRE."""
    m, n = poles
    with mpmath.workdps(40):
        centre = mpmath.mpf(NEAR_CENTRE)
        half = (mpmath.mpf(NEAR_HIGH) - NEAR_LOW) / 2
        pi2 = mpmath.pi**2
        angles = [mpmath.pi * (i + mpmath.mpf(1) / 2) / NEAR_NODES for i in range(NEAR_NODES)]
        gs = []
        for a in angles:
            p = centre + half * mpmath.cos(a)
            gs.append(f(p) * (p + pi2) ** m * (p + 4 * pi2) ** n / p**zero)
        cheb = [
            2 * mpmath.fsum(g * mpmath.cos(k * a) for g, a in zip(gs, angles)) / NEAR_NODES
            for k in range(NEAR_NODES)
        ]
        cheb[0] /= 2
        bound = mpmath.ldexp(min(abs(g) for g in gs), -55)
        size = NEAR_NODES
        while size > 1 and mpmath.fsum(abs(c) for c in cheb[size - 1 :]) <= bound:
            size -= 1
        if size == NEAR_NODES:  # pragma: no cover - the coefficients fall about 30-fold a term
            raise ValueError("a near fit needs more nodes")
        # sum_k c_k T_k(d/half) in powers of d: T_k's monomial coefficients, scaled by half^-i
        mono = [mpmath.mpf(0)] * size
        for k, c in enumerate(cheb[:size]):
            for i, t in enumerate(_chebyshev_monomial(k)):
                mono[i] += c * t / half**i
        return NearForm(tuple(float(c) for c in mono), zero, poles)


@cache
def _chebyshev_monomial(k: int) -> tuple[int, ...]:
    """The integer coefficients of T_k(x) in powers of x."""
    if k == 0:
        return (1,)
    if k == 1:
        return (0, 1)
    a, b = _chebyshev_monomial(k - 2), _chebyshev_monomial(k - 1)
    out = [0] * (k + 1)
    for i, v in enumerate(b):
        out[i + 1] += 2 * v
    for i, v in enumerate(a):
        out[i] -= v
    return tuple(out)


@cache
def _near_form(base: str, order: int) -> NearForm:
    kept = axial_forms.NEAR.get((base, order))
    return NearForm(*kept) if kept is not None else _fit_near(base, order)


def _fit_near(base: str, order: int) -> NearForm:
    cls = kernel(base, order)
    zero = next(i for i, c in enumerate(cls.coefficients(4)) if c != 0)
    closed = _mp_closed(base, order)

    def value(p):
        # the nodes keep |p| > 0.1, where 320 bits leave the closed form's cancellation far
        # below the fit's 40 digits
        with mpmath.workprec(320):
            return closed(p, _mp_t(p))

    return near_fit(value, zero, _orders(cls.closed()))


@cache
def t_near_form() -> NearForm:
    """T(p) on the near interval (a simple pole at -pi^2, no zero)."""
    return NearForm(*axial_forms.T_NEAR)


def _fit_t_near() -> NearForm:
    return near_fit(lambda p: _mp_t(p) if p else mpmath.mpf(1), 0, (1, 0))


#: The symbols of the far forms: u = sqrt(p)/2, tanh(u) and sech(u)^2.
U, TAU, SIGMA = sp.symbols("u tau sigma")


@dataclass(frozen=True)
class FarForm:
    """A kernel from NEAR_HIGH on, in u = sqrt(p)/2, tau = tanh(u), sigma = 1 - tau^2:
    (S_n (1 + tau) - sigma B_n) / (S_d (1 + tau) - sigma B_d), each of S, B given per power of
    sigma (from 0) as the coefficients of u^0, u^1, ... (integers, exact in float64)."""

    num: tuple[list[list[float]], list[list[float]]]
    den: tuple[list[list[float]], list[list[float]]]


def _far_form(closed: sp.Expr) -> FarForm:
    """The closed form with p = 4u^2, T = tau/u, over a common power of u, each part A + tau B
    by tau^2 = 1 - sigma and written (A + B) - sigma B/(1 + tau) (as 1 - tau = sigma/(1 + tau)):
    A + B is exact where tau -> 1 made the closed form's terms cancel."""
    num, den = sp.fraction(sp.cancel(sp.together(closed)))
    parts = [sp.expand(e.subs({P: 4 * U**2, TT: TAU / U})) for e in (num, den)]
    low = min(sp.Poly(sp.expand(e * U**100), U).monoms()[-1][0] for e in parts) - 100
    out = []
    for e in parts:
        poly = sp.Poly(sp.expand(e * U ** max(0, -low)), TAU)
        even, odd = sp.S.Zero, sp.S.Zero
        for (k,), c in poly.terms():
            term = c * (1 - SIGMA) ** (k // 2)
            if k % 2:
                odd += term
            else:
                even += term
        out.append((_rows(sp.expand(even + odd)), _rows(sp.expand(odd))))
    return FarForm(out[0], out[1])


def _rows(expr: sp.Expr) -> list[list[float]]:
    """A polynomial in (SIGMA, U) as float rows per power of SIGMA (exact integers)."""
    if expr == 0:
        return [[0.0]]
    poly = sp.Poly(expr, SIGMA, U)
    rows = [[0.0] * (poly.degree(U) + 1) for _ in range(poly.degree(SIGMA) + 1)]
    for (i, j), c in poly.terms():
        if not (c.is_Integer and abs(c) < 2**53):
            raise ValueError(f"coefficient {c} of a far form is not an exact float")
        rows[i][j] = float(c)
    return rows


@cache
def _far(base: str, order: int) -> FarForm:
    kept = axial_forms.FAR.get((base, order))
    return FarForm(*kept) if kept is not None else _far_form(closed_form(base, order))


#: The kernels whose float forms symkin.model.special.axial_forms keeps: every base kernel and
#: its first two p-derivatives (those the plate relations use).
KEPT_ORDERS = 3


def forms_source() -> str:
    """The text of symkin/model/special/axial_forms.py: every kept kernel's float forms computed
    afresh (the Chebyshev fits at 40 digits, the far and closed forms' exact polynomials; 1-3 s,
    which every process that emits or lambdifies the kernels paid before they were kept).
    tests/test_axial_forms.py holds the file to it; `pytest tests/test_axial_forms.py --update`
    writes it. Floats are written by repr: they read back bit for bit."""
    keys = [(b, k) for b in BASES for k in range(KEPT_ORDERS)]

    def near(f: NearForm) -> str:
        return repr((tuple(map(float, f.coeffs)), int(f.zero), tuple(map(int, f.poles))))

    def rows(parts) -> str:
        return repr(tuple([[float(v) for v in row] for row in part] for part in parts))

    lines = [
        '"""The beam-column kernels\' float forms, as symkin.model.special.axial computes them',
        "(near_fit, _far_form, _float_closed): kept so that no process computes them again.",
        "",
        "Generated by symkin.model.special.axial.forms_source() - do not edit; tests/",
        "test_axial_forms.py checks it and rewrites it with --update.",
        '"""',
        "",
        "NEAR = {",
        *(f"    {key!r}: {near(_fit_near(*key))}," for key in keys),
        "}",
        "FAR = {",
        *(
            f"    {key!r}: ({rows(f.num)}, {rows(f.den)}),"
            for key in keys
            for f in [_far_form(closed_form(*key))]
        ),
        "}",
        "CLOSED = {",
        *(f"    {key!r}: {rows(_float_closed(kernel(*key).closed()))}," for key in keys),
        "}",
        f"T_NEAR = {near(_fit_t_near())}",
        "",
    ]
    return "\n".join(lines)


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


def kernel(base: str, order: int = 0) -> type:
    """The kernel class of the `order`-th p-derivative of the base kernel `base` (BASES): one
    class per (base, order) however the order is written (kernel("s") is kernel("s", 0))."""
    if base not in BASES:
        raise ValueError(f"no beam-column kernel '{base}' (kernels: {', '.join(BASES)})")
    return _kernel(base, int(order))


@cache
def _kernel(base: str, order: int) -> type:
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
    at = _kernel_at(cls)
    register(name, cls, cls._mpmath_function(), ("bcol_h", at.__name__))
    globals()[name] = cls
    return cls


class AxialAt(sp.Function):
    """Base of a beam-column kernel at (p, h), h = bcol_h(p) given: what generated code calls so
    that one transcendental serves every kernel of a plate (symkin.codegen.plate). Subclasses
    set `kernel`, the one-argument kernel class whose value this is."""

    nargs = 2
    kernel: type = AxialKernel

    def _eval_evalf(self, prec):
        return self.kernel(self.args[0])._eval_evalf(prec)

    def _eval_is_real(self):
        return self.args[0].is_extended_real or None


def _kernel_at(cls: type) -> type:
    """The two-argument class `<kernel>_at(p, h)` of a kernel class, registered."""
    name = f"{cls.__name__}_at"
    at = type(
        name,
        (AxialAt,),
        {
            "kernel": cls,
            "__doc__": f"{cls.definition}, at p and h = bcol_h(p) (symkin.model.special.axial).",
            "__module__": __name__,
        },
    )
    value = cls._mpmath_function()

    def impl(p, h, _value=value):
        return _value(p)

    impl.__name__ = name
    register(name, at, impl)
    globals()[name] = at
    return at


def kernel_at(base: str, order: int = 0) -> type:
    """The class `<kernel>_at(p, h)` of the `order`-th p-derivative of `base`."""
    return FUNCTIONS[kernel(base, order).__name__ + "_at"]


def _mp_h_function(p):
    """h(p), the kernels' shared value, at the current mpmath precision: T(p) below NEAR_HIGH,
    q = 1 - tanh(sqrt(p)/2) from it on."""
    p = mpmath.mpmathify(p)
    if p == 0:
        return mpmath.mpf(1)
    if not p > -(mpmath.pi**2):
        raise DomainError(f"bcol_h({p}): the axial load index must exceed -pi^2")
    if p >= NEAR_HIGH:
        e = mpmath.exp(-mpmath.sqrt(p))
        return 2 * e / (1 + e)
    return _mp_t(p)


class bcol_h(sp.Function):  # lower case: the registered name, as generated code spells it
    """The value every `<kernel>_at(p, h)` takes: T(p) = tanh(u)/u, u = sqrt(p)/2 (tan below 0,
    1 at 0) for p < NEAR_HIGH; from NEAR_HIGH on q = 1 - tanh(u), which carries 1 - tanh(u) and
    sech(u)^2 = q (2 - q) to full relative accuracy, where T(p) cannot."""

    nargs = 1

    @classmethod
    def eval(cls, x):
        if x.is_zero:
            return sp.S.One
        return None

    @classmethod
    def _mp_value(cls, p, prec: int):
        with mpmath.workprec(prec):
            return _mp_h_function(p)

    def _eval_evalf(self, prec):
        return evalf_by_mp(self, prec)

    def _eval_is_real(self):
        return self.args[0].is_extended_real or None


register("bcol_h", bcol_h, _mp_h_function)

# The kernels the plate relation and its Jacobian use (and their second derivatives, for a
# Jacobian's derivative), created and registered at import.
for _b in BASES:
    for _order in range(3):
        kernel(_b, _order)


def __getattr__(name: str) -> type:
    """The beam-column kernels made on demand (bcol_<base>[_d<k>][_at]) by name: a pickled
    expression (a plan kept by symkin.codegen.plan_cache) names its kernels' classes."""
    stem = name[: -len("_at")] if name.endswith("_at") else name
    if stem.startswith("bcol_"):
        base, _, order = stem[len("bcol_") :].partition("_d")
        if base in BASES and (not order or (order.isascii() and order.isdecimal())):
            kernel(base, int(order or 0))  # made (once), and its _at class with it
            if name in globals():  # bcol_s_d0 is not a name: bcol_s is
                return globals()[name]
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
