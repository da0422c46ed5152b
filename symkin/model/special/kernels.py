"""Cancellation-free kernels of the hinge models (docs/numerics.md): sympy functions that are
even, entire and O(1) at the origin, so a float64 evaluation keeps full relative accuracy for
every argument, however small.

    sinr_n(x) = (sin x - sum_{k<n} (-1)^k x^(2k+1)/(2k+1)!) / x^(2n+1)      n >= 0
    cosr_n(x) = (cos x - sum_{k<n} (-1)^k x^(2k)/(2k)!) / x^(2n)            n >= 1
    arck(x)   = (sin x - x cos x) / x^3                                      (the circular arc's K)

so sinr_0 = sinc, -sinr_1(x) = (x - sin x)/x^3, -cosr_1(x) = (1 - cos x)/x^2, and
1 - cos x = -x^2 cosr_1(x), sin x - x = x^3 sinr_1(x).  Their derivatives stay in the family and
are cancellation-free too:

    sinr_n'(x) = x (cosr_{n+1}(x) - (2n+1) sinr_{n+1}(x))
    cosr_n'(x) = -x (sinr_n(x) + 2n cosr_{n+1}(x))
    arck'(x)   = x (sinr_1(x) + 3 cosr_2(x) - 3 sinr_2(x))

Float algorithm of a kernel (language-neutral data here, written out by each backend): for |x|
below a threshold T, the Taylor series in x^2 (Estrin's form) with as many terms as make the first
dropped term smaller than 2^-53 times the smallest value of the kernel on [0, T]; above T the
elementary formula, evaluated by the nested recurrence b <- (b - a_j)/x^2, whose cancellation at
|x| >= T costs at most a few units in the last place.  mpmath evaluates them at any precision.
"""

from __future__ import annotations

import math
from functools import cache

import mpmath
import sympy as sp
from mpmath.libmp import fzero, mpf_add, mpf_mul, round_nearest
from sympy.core.function import ArgumentIndexError

from .registry import UNIT_ROUNDOFF, register


def _to_mp(expr: sp.Expr, prec: int):
    """mpmath value of a numeric sympy expression at `prec` bits (mpf or mpc)."""
    return expr._to_mpmath(prec)


def _from_mp(value, prec: int) -> sp.Expr:
    return sp.Expr._from_mpmath(value, prec)


def evalf_by_mp(f: sp.Function, prec: int) -> sp.Expr | None:
    """sympy's evalf of a one-argument kernel `f` through its class's ``_mp_value(x, prec)``
    (20 guard bits on the argument); None where the argument is not a number."""
    x = f.args[0]
    if not x.is_number:
        return None
    try:
        xv = _to_mp(x, prec + 20)
    except (TypeError, ValueError, AttributeError):
        return None
    return _from_mp(f._mp_value(xv, prec), prec)


def horner_mp(coeffs: tuple, x, wp: int, even: bool = False):
    """sum c_k y^k by Horner's rule at `wp` bits, y = x (x^2 with `even`, rounded at `wp` too),
    `coeffs` (mpf) highest power first, x mpf or mpc. For a real x on mpmath's raw values
    (libmp): the roundings of mpf's own operators, without their dispatch, which was most of a
    kernel's evaluation in the `sympy` backend."""
    if isinstance(x, mpmath.mpf):
        v, total = x._mpf_, fzero
        if even:
            v = mpf_mul(v, v, wp, round_nearest)
        for c in coeffs:
            total = mpf_add(mpf_mul(total, v, wp, round_nearest), c._mpf_, wp, round_nearest)
        return mpmath.mp.make_mpf(total)
    with mpmath.workprec(wp):
        y = x * x if even else x
        total = mpmath.mpf(0)
        for c in coeffs:
            total = total * y + c
        return +total


class StableKernel(sp.Function):
    """Base of the even, entire kernels: exact Taylor coefficients, a stable float algorithm.

    A subclass defines ``coeff(k)`` (the exact coefficient of x^(2k)), ``elementary(x)``, the
    float algorithm (``threshold``, ``float_base`` and ``float_subtract``) and ``_fdiff_expr(x)``.
    The algorithm is language-neutral data; each backend writes it in its own language."""

    nargs = 1
    threshold: float = 1.0  # |x| below: the Taylor series of float_series()
    float_base = "sinc"  # "sinc", "cosr1" or "sinc_minus_cos": b before the steps
    float_subtract: tuple = ()  # exact constants a_j of the recurrence b <- (b - a_j)/x^2
    definition = ""  # one line of plain text, for comments in generated code

    # -- exact data ------------------------------------------------------------------------------
    @classmethod
    def coeff(cls, k: int) -> sp.Rational:  # pragma: no cover - abstract
        raise NotImplementedError

    @classmethod
    def elementary(cls, x: sp.Expr) -> sp.Expr:  # pragma: no cover - abstract
        raise NotImplementedError

    @classmethod
    def _fdiff_expr(cls, x: sp.Expr) -> sp.Expr:  # pragma: no cover - abstract
        raise NotImplementedError

    # -- sympy protocol --------------------------------------------------------------------------
    @classmethod
    def eval(cls, x):
        if x.is_zero:
            return cls.coeff(0)
        if x.could_extract_minus_sign():
            return cls(-x)
        if x.is_Float:
            return _from_mp(cls._mp_value(_to_mp(x, x._prec + 10), x._prec), x._prec)
        return None

    def fdiff(self, argindex=1):
        if argindex != 1:
            raise ArgumentIndexError(self, argindex)
        return self._fdiff_expr(self.args[0])

    def _eval_evalf(self, prec):
        return evalf_by_mp(self, prec)

    def _eval_rewrite_as_elementary(self, x, **kwargs):
        return self.elementary(x)

    _eval_rewrite_as_sin = _eval_rewrite_as_elementary
    _eval_rewrite_as_cos = _eval_rewrite_as_elementary

    def _eval_is_real(self):
        return self.args[0].is_extended_real or None

    def _eval_is_finite(self):
        if self.args[0].is_finite:
            return True
        return None

    @classmethod
    def taylor_term(cls, n, x, *previous_terms):
        if n < 0 or n % 2:
            return sp.S.Zero
        return cls.coeff(n // 2) * sp.sympify(x) ** n

    def _eval_as_leading_term(self, x, logx=None, cdir=0):
        arg = self.args[0].as_leading_term(x, logx=logx, cdir=cdir)
        if arg.subs(x, 0) == 0:
            return self.coeff(0)
        return self.func(arg)

    # -- numerics --------------------------------------------------------------------------------
    @classmethod
    def float_series(cls) -> tuple[list[float], int]:
        """Float Taylor coefficients (of x^0, x^2, ...) used below the threshold, and their
        number N: the first dropped term |c_N| T^(2N) is below 2^-53 times a lower bound of the
        kernel on [0, T]."""
        return _float_series(cls)

    @classmethod
    def _mp_value(cls, x, prec: int):
        """Value at `prec` bits, for mpmath argument x (mpf or mpc): series for |x| <= 2, else the
        elementary formula with guard bits (checked by a second evaluation)."""
        if abs(x) <= 2:
            return horner_mp(_mp_coefficients(cls, prec), x, prec + 20, even=True)
        guard = 40 + 8 * len(cls.float_subtract)
        while True:
            with mpmath.workprec(prec + guard):
                v1 = cls._mp_direct(x)
            with mpmath.workprec(prec + 2 * guard):
                v2 = cls._mp_direct(x)
            if v2 == 0 or abs(v1 - v2) <= mpmath.ldexp(abs(v2), -(prec + 4)):
                with mpmath.workprec(prec):
                    return +v2
            guard *= 2
            if guard > 20000:  # pragma: no cover - cannot happen for finite x
                raise ValueError(f"{cls.__name__}({x}): no convergence")

    @classmethod
    def _mp_direct(cls, x):
        if cls.float_base == "sinc":
            b = mpmath.sin(x) / x
        elif cls.float_base == "cosr1":
            h = mpmath.sin(x / 2) / x
            b = -2 * h * h
        else:
            b = mpmath.sin(x) / x - mpmath.cos(x)
        x2 = x * x
        for a in cls.float_subtract:
            b = (b - mpmath.mpf(a.p) / a.q) / x2
        return b

    @classmethod
    def _mpmath_function(cls):
        def impl(x, _cls=cls):
            x = mpmath.mpmathify(x)
            if x == 0:
                c = _cls.coeff(0)
                return mpmath.mpf(c.p) / c.q
            return _cls._mp_value(x, mpmath.mp.prec)

        impl.__name__ = cls.__name__
        return impl


@cache
def _mp_coefficients(cls, prec: int) -> tuple:
    """The Taylor coefficients (of x^0, x^2, ...) `_mp_value` sums for |x| <= 2 at `prec` bits,
    highest power first, as mpf at its working precision (converting them was most of an
    evaluation): as many as make the tail, sum_(k>=N) |c_k| 4^k, below 2^-(prec+16) times a
    lower bound of the kernel on [0, 2]."""
    bound = mpmath.ldexp(_kernel_min_on(cls, 2.0), -(prec + 16))
    n = 2
    while _tail(cls, n, 4) > bound:
        n += 1
    with mpmath.workprec(prec + 20):
        return tuple(mpmath.mpf(c.p) / c.q for c in (cls.coeff(k) for k in reversed(range(n))))


def _tail(cls, n: int, x2: int) -> mpmath.mpf:
    """An upper bound of sum_(k>=n) |c_k| x2^k for n >= 2, x2 <= 4: the kernels' factorial
    coefficients shrink by |c_(k+1)/c_k| <= 1/((2k+2)(2k+3)) (arck's by 1/((2k+2)(2k+5))), so from
    k = 2 on a term is less than half the one before, and the tail less than twice its first."""
    c = abs(cls.coeff(n)) * x2**n
    return mpmath.mpf(2 * c.p) / c.q


def _kernel_min_on(cls, T: float) -> float:
    """A lower bound of |kernel| on [0, T] from its series (c_0 minus the other terms)."""
    c0 = abs(float(cls.coeff(0)))
    rest = sum(abs(float(cls.coeff(k))) * T ** (2 * k) for k in range(1, 60))
    return max(c0 - rest, 0.0) or c0 * 1e-3


@cache
def _float_series(cls) -> tuple[list[float], int]:
    T = cls.threshold
    bound = UNIT_ROUNDOFF * _kernel_min_on(cls, T)
    n = 1
    while abs(float(cls.coeff(n))) * T ** (2 * n) >= bound:
        n += 1
    return [float(cls.coeff(k)) for k in range(n)], n


# Thresholds T (|x| below: series).  Chosen by measurement against mpmath at 200 bits over
# 1e-8 <= |x| <= 8 (tests/test_hinge_models.py re-checks it): with these, the worst float64 error
# is <= 3 ulp for sinr0..3, cosr1..3, <= 8 ulp for sinr4, cosr4 and arck (near its zero at 4.49).
_SINR_THRESHOLD = {0: 1.0, 1: 2.0, 2: 3.0, 3: 4.5, 4: 5.0}
_COSR_THRESHOLD = {1: 1.0, 2: 3.0, 3: 4.0, 4: 5.0}


def _default_threshold(n: int) -> float:
    return 5.0 + 0.5 * (n - 4)


def sinr(n: int) -> type:
    """The kernel class sinr_n, one class per order however it is written (sinr(3.0) is sinr(3))."""
    return _sinr(int(n))


@cache
def _sinr(n: int) -> type:
    """The kernel class sinr_n: (sin x - its Taylor polynomial through x^(2n-1)) / x^(2n+1)."""
    n = int(n)
    if n < 0:
        raise ValueError("sinr order must be >= 0")

    @classmethod
    def coeff(cls, k):
        return sp.Rational((-1) ** (n + k), math.factorial(2 * n + 2 * k + 1))

    @classmethod
    def elementary(cls, x):
        poly = sum(
            sp.Rational((-1) ** k, math.factorial(2 * k + 1)) * x ** (2 * k + 1) for k in range(n)
        )
        return (sp.sin(x) - poly) / x ** (2 * n + 1)

    @classmethod
    def fdiff_expr(cls, x):
        return x * (cosr(n + 1)(x) - (2 * n + 1) * sinr(n + 1)(x))

    name = f"sinr{n}"
    definition = (
        f"sinr{n}(x) = (sin x - sum_(k<{n}) (-1)^k x^(2k+1)/(2k+1)!) / x^{2 * n + 1}"
        if n
        else "sinr0(x) = sin(x)/x"
    )
    cls = type(
        name,
        (StableKernel,),
        {
            "coeff": coeff,
            "elementary": elementary,
            "_fdiff_expr": fdiff_expr,
            "threshold": _SINR_THRESHOLD.get(n, _default_threshold(n)),
            "float_base": "sinc",
            "float_subtract": tuple(
                sp.Rational((-1) ** k, math.factorial(2 * k + 1)) for k in range(n)
            ),
            "definition": definition,
            "__doc__": definition + " (an even entire kernel; see symkin.model.special.kernels).",
            "__module__": __name__,
        },
    )
    register(name, cls, cls._mpmath_function())
    globals()[name] = cls  # importable by name (pickling, lambdify printers)
    return cls


def cosr(n: int) -> type:
    """The kernel class cosr_n, one class per order however it is written (cosr(3.0) is cosr(3))."""
    return _cosr(int(n))


@cache
def _cosr(n: int) -> type:
    """The kernel class cosr_n: (cos x - its Taylor polynomial through x^(2n-2)) / x^(2n)."""
    n = int(n)
    if n < 1:
        raise ValueError("cosr order must be >= 1")

    @classmethod
    def coeff(cls, k):
        return sp.Rational((-1) ** (n + k), math.factorial(2 * n + 2 * k))

    @classmethod
    def elementary(cls, x):
        poly = sum(sp.Rational((-1) ** k, math.factorial(2 * k)) * x ** (2 * k) for k in range(n))
        return (sp.cos(x) - poly) / x ** (2 * n)

    @classmethod
    def fdiff_expr(cls, x):
        return -x * (sinr(n)(x) + 2 * n * cosr(n + 1)(x))

    name = f"cosr{n}"
    definition = f"cosr{n}(x) = (cos x - sum_(k<{n}) (-1)^k x^(2k)/(2k)!) / x^{2 * n}"
    cls = type(
        name,
        (StableKernel,),
        {
            "coeff": coeff,
            "elementary": elementary,
            "_fdiff_expr": fdiff_expr,
            "threshold": _COSR_THRESHOLD.get(n, _default_threshold(n)),
            "float_base": "cosr1",  # cosr1(x) = -2 (sin(x/2)/x)^2: no cancellation anywhere
            "float_subtract": tuple(
                sp.Rational((-1) ** k, math.factorial(2 * k)) for k in range(1, n)
            ),
            "definition": definition,
            "__doc__": definition + " (an even entire kernel; see symkin.model.special.kernels).",
            "__module__": __name__,
        },
    )
    register(name, cls, cls._mpmath_function())
    globals()[name] = cls
    return cls


class arck(StableKernel):
    """K(x) = (sin x - x cos x)/x^3 = 1/3 - x^2/30 + ...: the circular arc's deviation kernel.

    With u = θ/2 the arc's clamp lies l u^2 K(u) (cos u, sin u) from the rigid hinge's."""

    threshold = 1.5
    float_base = "sinc_minus_cos"
    float_subtract = (sp.Integer(0),)
    definition = "arck(x) = (sin x - x cos x)/x^3"

    @classmethod
    def coeff(cls, k):
        return sp.Rational((-1) ** k * (2 * k + 2), math.factorial(2 * k + 3))

    @classmethod
    def elementary(cls, x):
        return (sp.sin(x) - x * sp.cos(x)) / x**3

    @classmethod
    def _fdiff_expr(cls, x):
        return x * (sinr(1)(x) + 3 * cosr(2)(x) - 3 * sinr(2)(x))


register("arck", arck, arck._mpmath_function())

# The kernels the hinge models use, created (and registered) at import.
for _n in range(5):
    sinr(_n)
    if _n:
        cosr(_n)


def __getattr__(name: str) -> type:
    """The kernels made on demand (sinr<n>, cosr<n>) by name: a pickled expression (a plan kept
    by symkin.codegen.plan_cache) names its kernels' classes, made again here."""
    for prefix, make in (("sinr", sinr), ("cosr", cosr)):
        order = name[len(prefix) :]
        if name.startswith(prefix) and order.isascii() and order.isdecimal():
            try:
                return make(int(order))
            except ValueError:  # an order the family does not have (cosr0)
                break
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
