"""Cancellation-free special functions for the hinge models (DESIGN.md, "Numerics").

The deviation of a compliant hinge from the ideal revolute is a small difference of large numbers.
symkin never forms that difference in floating point: it writes it with the kernels below, each an
even function that is O(1) at the origin, so a float64 evaluation keeps full relative accuracy for
every argument, however small.

Kernels (x real; all are even and entire):

    sinr_n(x) = (sin x - sum_{k<n} (-1)^k x^(2k+1)/(2k+1)!) / x^(2n+1)      n >= 0
    cosr_n(x) = (cos x - sum_{k<n} (-1)^k x^(2k)/(2k)!) / x^(2n)            n >= 1
    arck(x)   = (sin x - x cos x) / x^3                                      (the circular arc's K)

so sinr_0 = sinc, -sinr_1(x) = (x - sin x)/x^3 = S(x), -cosr_1(x) = (1 - cos x)/x^2, and
1 - cos x = -x^2 cosr_1(x), sin x - x = x^3 sinr_1(x).  Their derivatives stay in the family and
are cancellation-free too:

    sinr_n'(x) = x (cosr_{n+1}(x) - (2n+1) sinr_{n+1}(x))
    cosr_n'(x) = -x (sinr_n(x) + 2n cosr_{n+1}(x))
    arck'(x)   = x (sinr_1(x) + 3 cosr_2(x) - 3 sinr_2(x))

Elastica (a cantilever under a transverse tip force, parametrised by its tip angle θ, |θ| < π/2;
s = sin θ, c = cos θ, q = s^2):

    A(q) = R_F(1 - s, 1 + s, c^2) = ∫_0^1 dv / sqrt(1 - q (1 - v^2)^2)
    C(q) = c^2/3 R_D(1 - s, 1 + s, c^2) = ∫_0^1 v^2 dv / sqrt(1 - q (1 - v^2)^2)
    A1(q) = (A - 1)/q  (Taylor series in q below q = 0.25)

    elastica_x = x_tip/l = 1/A            elastica_y = y_tip/l = s (1 - C/A)
    elastica_dx = x/l - cos^2(θ/2) = q (1/(2(1 + c)) - A1/A)
    elastica_dy = y/l - sin(θ)/2   = s (1/2 - C/A)
    elastica_dx_d1 = d elastica_dx/dθ = s (1/2 - (A + C - A1)/(2 c A^2))
    elastica_dy_d1 = d elastica_dy/dθ = c/2 (1 + q (A + C - A1)/(c^2 A)) C/A

The load is α = P l^2/(EI) = 2 s A^2.  These follow from the first integral of the elastica
φ'' = -α cos φ (φ(0) = 0, φ'(1) = 0) with the substitution sin φ = s (1 - v^2); they are the
Bisshopp-Drucker elliptic-integral solution in Carlson's symmetric form (``rewrite("elliptic")``
gives the Legendre form with sympy's elliptic_f / elliptic_e).

Every function here has, besides its sympy class:
  * ``FLOAT64[name]``   pure-Python float64 implementation (math module only),
  * ``NUMPY[name]``     vectorised numpy implementation,
  * ``MPMATH[name]``    mpmath implementation at the current mpmath precision (for lambdify),
  * ``PYTHON_SOURCE[name]``, ``NUMPY_SOURCE[name]``, ``C_SOURCE[name]``: the same algorithm as
    source text, for generated code (the FLOAT64 and NUMPY entries are built from these texts).
    ``DEPENDS[name]`` lists helpers a C snippet calls; :func:`c_support` returns the snippets a set
    of names needs, helpers first.  C functions are ``static double symkin_<name>(double)``; out of
    the domain they return NaN (numpy: NaN; Python float64: :class:`DomainError`).

Float64 algorithm of a kernel: for |x| below a threshold T, the Taylor series in x^2 (Horner) with
as many terms as make the first dropped term smaller than 2^-53 times the smallest value of the
kernel on [0, T]; above T the elementary formula, evaluated by the nested recurrence
b <- (b - a_j)/x^2, whose cancellation at |x| >= T costs at most a few units in the last place.
"""

from __future__ import annotations

import math
from fractions import Fraction
from functools import lru_cache

import mpmath
import numpy as np
import sympy as sp
from sympy.core.function import ArgumentIndexError

__all__ = [
    "DomainError", "StableKernel", "sinr", "cosr", "arck", "sinc", "ElasticaFunction",
    "elastica_x", "elastica_y", "elastica_dx", "elastica_dy", "elastica_dx_d1", "elastica_dy_d1",
    "ELASTICA_LIMIT", "FLOAT64", "NUMPY", "MPMATH", "PYTHON_SOURCE", "NUMPY_SOURCE", "C_SOURCE",
    "DEPENDS", "c_support", "kernel_names", "expand_special", "elastica_load", "used_names",
    "ELASTICA_FUNCTIONS", "float64_namespace", "numpy_namespace", "mpmath_namespace",
]

#: Unit roundoff of IEEE double: the series are cut where the first dropped term is below it.
UNIT_ROUNDOFF = 2.0 ** -53
#: The elastica under a purely transverse tip force reaches tip angles |θ| < π/2 only.
ELASTICA_LIMIT = sp.pi / 2
_HALF_PI_FLOAT = math.pi / 2          # the largest double below π/2


class DomainError(ValueError):
    """An argument outside a function's domain (e.g. an elastica tip angle |θ| >= π/2).

    A ValueError, so callers that validate user input can turn it into an InputError."""


# Registries, filled as the classes are created (so a lazily created higher-order kernel is
# registered before any expression can contain it).
FLOAT64: dict[str, object] = {}
NUMPY: dict[str, object] = {}
MPMATH: dict[str, object] = {}
PYTHON_SOURCE: dict[str, str] = {}
NUMPY_SOURCE: dict[str, str] = {}
C_SOURCE: dict[str, str] = {}
DEPENDS: dict[str, tuple[str, ...]] = {}


def _c_float(value: float) -> str:
    """A C / Python literal that reads back as exactly `value` (shortest round-trip repr)."""
    text = repr(float(value))
    if text in ("inf", "-inf", "nan"):
        raise ValueError(f"non-finite constant {text}")
    if "." not in text and "e" not in text:
        text += ".0"
    return text


def _horner(coeffs: list[float], var: str) -> str:
    """Source text of sum coeffs[k] var^k in Horner form (valid Python and C)."""
    text = _c_float(coeffs[-1])
    for c in reversed(coeffs[:-1]):
        text = f"{_c_float(c)} + {var} * ({text})"
    return text


def _register(name: str, python_src: str, numpy_src: str, c_src: str, mp_impl,
              depends: tuple[str, ...] = ()) -> None:
    PYTHON_SOURCE[name] = python_src
    NUMPY_SOURCE[name] = numpy_src
    C_SOURCE[name] = c_src
    DEPENDS[name] = depends
    if mp_impl is not None:
        MPMATH[name] = mp_impl


# One namespace each for all float64 / numpy functions, so helpers see each other.
_PY_NS: dict[str, object] = {"math": math, "DomainError": DomainError}
_NP_NS: dict[str, object] = {"np": np}


def _exec_sources() -> None:
    """Build FLOAT64 and NUMPY from the source texts, so they run exactly that algorithm."""
    for name in PYTHON_SOURCE:
        if name not in FLOAT64:
            exec(compile(PYTHON_SOURCE[name], f"<symkin.special {name}>", "exec"), _PY_NS)
            FLOAT64[name] = _PY_NS[name]
            exec(compile(NUMPY_SOURCE[name], f"<symkin.special numpy {name}>", "exec"), _NP_NS)
            NUMPY[name] = _NP_NS[name]


def c_support(names) -> str:
    """The C99 definitions needed to call the functions `names`, dependencies first."""
    order: list[str] = []

    def visit(n: str) -> None:
        if n in order:
            return
        for d in DEPENDS.get(n, ()):
            visit(d)
        order.append(n)

    for n in sorted(set(names)):
        visit(n)
    return "\n".join(C_SOURCE[n] for n in order)


def _to_mp(expr: sp.Expr, prec: int):
    """mpmath value of a numeric sympy expression at `prec` bits (mpf or mpc)."""
    return expr._to_mpmath(prec)


def _from_mp(value, prec: int) -> sp.Expr:
    return sp.Expr._from_mpmath(value, prec)


# =============================================================================================
# Kernels
# =============================================================================================

class _RegistryPrinting:
    """Code printers call a symkin function by its registry name: symkin_<name>(x) in C (the
    definitions come from C_SOURCE), <name>(x) in Python and numpy (from *_SOURCE)."""

    def _ccode(self, printer):
        return f"symkin_{type(self).__name__}({printer._print(self.args[0])})"

    def _pythoncode(self, printer):
        return f"{type(self).__name__}({printer._print(self.args[0])})"

    _mpmathcode = _lambdacode = _numpycode = _scipycode = _cupycode = _jaxcode = _pythoncode


class StableKernel(_RegistryPrinting, sp.Function):
    """Base of the even, entire kernels: exact Taylor coefficients, a stable float algorithm.

    A subclass defines ``coeff(k)`` (the exact coefficient of x^(2k)), ``elementary(x)``, the
    float recurrence (``_base`` and ``_subtract``), ``threshold`` and ``_fdiff_expr(x)``."""

    nargs = 1
    threshold: float = 1.0
    _base = "sinc"                      # "sinc", "cosr1" or "sinc_minus_cos"
    _subtract: tuple = ()               # exact constants a_j of the recurrence b <- (b - a_j)/x^2
    _latex_symbol = r"\kappa"
    _definition = ""

    # -- exact data ------------------------------------------------------------------------------
    @classmethod
    def coeff(cls, k: int) -> sp.Rational:      # pragma: no cover - abstract
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
        x = self.args[0]
        if not x.is_number:
            return None
        try:
            xv = _to_mp(x, prec + 20)
        except (TypeError, ValueError, AttributeError):
            return None
        return _from_mp(self._mp_value(xv, prec), prec)

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

    def _latex(self, printer, exp=None):
        arg = printer._print(self.args[0])
        base = rf"{self._latex_symbol}\!\left({arg}\right)"
        return base if exp is None else rf"{self._latex_symbol}^{{{exp}}}\!\left({arg}\right)"

    # -- numerics --------------------------------------------------------------------------------
    @classmethod
    def _series_coeffs_float(cls) -> list[float]:
        return _kernel_series(cls)[0]

    @classmethod
    def numeric(cls, x: float) -> float:
        """float64 value (the FLOAT64 algorithm)."""
        return FLOAT64[cls.__name__](x)

    @classmethod
    def _mp_value(cls, x, prec: int):
        """Value at `prec` bits, for mpmath argument x (mpf or mpc): series for |x| <= 2, else the
        elementary formula with guard bits (checked by a second evaluation)."""
        if abs(x) <= 2:
            with mpmath.workprec(prec + 20):
                x2 = x * x
                total = mpmath.mpf(0)
                term_scale = mpmath.mpf(1)
                k = 0
                tol = mpmath.ldexp(1, -(prec + 12))
                while True:
                    c = cls.coeff(k)
                    term = mpmath.mpf(c.p) / c.q * term_scale
                    total += term
                    if k > 2 and abs(term) <= tol * abs(total):
                        break
                    term_scale *= x2
                    k += 1
                return +total
        guard = 40 + 8 * len(cls._subtract)
        while True:
            with mpmath.workprec(prec + guard):
                v1 = cls._mp_direct(x)
            with mpmath.workprec(prec + 2 * guard):
                v2 = cls._mp_direct(x)
            if v2 == 0 or abs(v1 - v2) <= mpmath.ldexp(abs(v2), -(prec + 4)):
                with mpmath.workprec(prec):
                    return +v2
            guard *= 2
            if guard > 20000:               # pragma: no cover - cannot happen for finite x
                raise ValueError(f"{cls.__name__}({x}): no convergence")

    @classmethod
    def _mp_direct(cls, x):
        if cls._base == "sinc":
            b = mpmath.sin(x) / x
        elif cls._base == "cosr1":
            h = mpmath.sin(x / 2) / x
            b = -2 * h * h
        else:
            b = mpmath.sin(x) / x - mpmath.cos(x)
        x2 = x * x
        for a in cls._subtract:
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


def _kernel_min_on(cls, T: float) -> float:
    """A lower bound of |kernel| on [0, T] from its series (c_0 minus the other terms)."""
    c0 = abs(float(cls.coeff(0)))
    rest = sum(abs(float(cls.coeff(k))) * T ** (2 * k) for k in range(1, 60))
    return max(c0 - rest, 0.0) or c0 * 1e-3


@lru_cache(maxsize=None)
def _kernel_series(cls) -> tuple[list[float], int]:
    """Float Taylor coefficients used below the threshold, and their number N: the first dropped
    term |c_N| T^(2N) is below 2^-53 times a lower bound of the kernel on [0, T]."""
    T = cls.threshold
    bound = UNIT_ROUNDOFF * _kernel_min_on(cls, T)
    n = 1
    while abs(float(cls.coeff(n))) * T ** (2 * n) >= bound:
        n += 1
    return [float(cls.coeff(k)) for k in range(n)], n


def _kernel_sources(cls) -> tuple[str, str, str]:
    """Python, numpy and C99 source of a kernel's float64 algorithm."""
    name = cls.__name__
    coeffs, n = _kernel_series(cls)
    T = _c_float(cls.threshold)
    subs = [float(a) for a in cls._subtract]
    series = _horner(coeffs, "x2")
    doc = (f"{cls._definition}; Taylor series ({n} terms) for |x| < {T}, "
           f"else the nested elementary formula")

    def steps(var: str, x2: str, indent: str) -> str:
        lines = []
        for a in subs:
            if a == 0:
                lines.append(f"{indent}b = b / {x2}")
            elif a > 0:
                lines.append(f"{indent}b = (b - {_c_float(a)}) / {x2}")
            else:
                lines.append(f"{indent}b = (b + {_c_float(-a)}) / {x2}")
        return "\n".join(lines)

    base_py = {"sinc": "math.sin(x) / x", "cosr1": "-2.0 * (math.sin(0.5 * x) / x) ** 2",
               "sinc_minus_cos": "math.sin(x) / x - math.cos(x)"}[cls._base]
    base_np = {"sinc": "np.sin(xs) / xs", "cosr1": "-2.0 * (np.sin(0.5 * xs) / xs) ** 2",
               "sinc_minus_cos": "np.sin(xs) / xs - np.cos(xs)"}[cls._base]
    base_c = {"sinc": "sin(x) / x", "cosr1": "-2.0 * (sin(0.5 * x) / x) * (sin(0.5 * x) / x)",
              "sinc_minus_cos": "sin(x) / x - cos(x)"}[cls._base]
    py_steps = steps("b", "x2", "    ")
    python_src = (
        f"def {name}(x):\n"
        f"    \"\"\"{doc}.\"\"\"\n"
        f"    x2 = x * x\n"
        f"    if abs(x) < {T}:\n"
        f"        return {series}\n"
        f"    b = {base_py}\n"
        + (py_steps + "\n" if py_steps else "")
        + "    return b\n")
    np_steps = steps("b", "xs2", "    ")
    numpy_src = (
        f"def {name}(x):\n"
        f"    \"\"\"{doc} (vectorised).\"\"\"\n"
        f"    x = np.asarray(x, dtype=float)\n"
        f"    x2 = x * x\n"
        f"    small = np.abs(x) < {T}\n"
        f"    series = {series}\n"
        f"    xs = np.where(small, 1.0, x)\n"
        f"    xs2 = xs * xs\n"
        f"    b = {base_np}\n"
        + (np_steps + "\n" if np_steps else "")
        + "    return np.where(small, series, b)\n")
    c_steps = "\n".join("    " + line.strip() + ";" for line in
                        steps("b", "x2", "").splitlines())
    c_src = (
        f"/* {name}(x): {doc}. */\n"
        f"static double symkin_{name}(double x)\n"
        "{\n"
        "    const double x2 = x * x;\n"
        "    double b;\n"
        f"    if (fabs(x) < {T}) {{\n"
        f"        return {series};\n"
        "    }\n"
        f"    b = {base_c};\n"
        + (c_steps + "\n" if c_steps else "")
        + "    return b;\n"
        "}\n")
    return python_src, numpy_src, c_src


def _register_kernel(cls) -> None:
    py, npy, c = _kernel_sources(cls)
    _register(cls.__name__, py, npy, c, cls._mpmath_function())
    _exec_sources()


# Thresholds T (|x| below: series).  Chosen by measurement against mpmath at 200 bits over
# 1e-8 <= |x| <= 8 (tests/test_hinge_models.py re-checks it): with these, the worst float64 error
# is <= 3 ulp for sinr0..3, cosr1..3, <= 8 ulp for sinr4, cosr4 and arck (near its zero at 4.49).
_SINR_THRESHOLD = {0: 1.0, 1: 2.0, 2: 3.0, 3: 4.5, 4: 5.0}
_COSR_THRESHOLD = {1: 1.0, 2: 3.0, 3: 4.0, 4: 5.0}


def _default_threshold(n: int) -> float:
    return 5.0 + 0.5 * (n - 4)


@lru_cache(maxsize=None)
def sinr(n: int) -> type:
    """The kernel class sinr_n: (sin x - its Taylor polynomial through x^(2n-1)) / x^(2n+1)."""
    n = int(n)
    if n < 0:
        raise ValueError("sinr order must be >= 0")

    @classmethod
    def coeff(cls, k):
        return sp.Rational((-1) ** (n + k), math.factorial(2 * n + 2 * k + 1))

    @classmethod
    def elementary(cls, x):
        poly = sum(sp.Rational((-1) ** k, math.factorial(2 * k + 1)) * x ** (2 * k + 1)
                   for k in range(n))
        return (sp.sin(x) - poly) / x ** (2 * n + 1)

    @classmethod
    def fdiff_expr(cls, x):
        return x * (cosr(n + 1)(x) - (2 * n + 1) * sinr(n + 1)(x))

    name = f"sinr{n}"
    definition = (f"sinr{n}(x) = (sin x - sum_(k<{n}) (-1)^k x^(2k+1)/(2k+1)!) / x^{2 * n + 1}"
                  if n else "sinr0(x) = sin(x)/x")
    cls = type(name, (StableKernel,), {
        "coeff": coeff, "elementary": elementary, "_fdiff_expr": fdiff_expr,
        "threshold": _SINR_THRESHOLD.get(n, _default_threshold(n)),
        "_base": "sinc",
        "_subtract": tuple(sp.Rational((-1) ** k, math.factorial(2 * k + 1)) for k in range(n)),
        "_latex_symbol": rf"\operatorname{{s}}_{{{n}}}",
        "_definition": definition,
        "__doc__": definition + " (an even entire kernel; see symkin.special).",
        "__module__": __name__,
    })
    _register_kernel(cls)
    globals()[name] = cls           # importable by name (pickling, lambdify printers)
    return cls


@lru_cache(maxsize=None)
def cosr(n: int) -> type:
    """The kernel class cosr_n: (cos x - its Taylor polynomial through x^(2n-2)) / x^(2n)."""
    n = int(n)
    if n < 1:
        raise ValueError("cosr order must be >= 1")

    @classmethod
    def coeff(cls, k):
        return sp.Rational((-1) ** (n + k), math.factorial(2 * n + 2 * k))

    @classmethod
    def elementary(cls, x):
        poly = sum(sp.Rational((-1) ** k, math.factorial(2 * k)) * x ** (2 * k)
                   for k in range(n))
        return (sp.cos(x) - poly) / x ** (2 * n)

    @classmethod
    def fdiff_expr(cls, x):
        return -x * (sinr(n)(x) + 2 * n * cosr(n + 1)(x))

    name = f"cosr{n}"
    definition = f"cosr{n}(x) = (cos x - sum_(k<{n}) (-1)^k x^(2k)/(2k)!) / x^{2 * n}"
    cls = type(name, (StableKernel,), {
        "coeff": coeff, "elementary": elementary, "_fdiff_expr": fdiff_expr,
        "threshold": _COSR_THRESHOLD.get(n, _default_threshold(n)),
        "_base": "cosr1",       # cosr1(x) = -2 (sin(x/2)/x)^2: no cancellation anywhere
        "_subtract": tuple(sp.Rational((-1) ** k, math.factorial(2 * k)) for k in range(1, n)),
        "_latex_symbol": rf"\operatorname{{c}}_{{{n}}}",
        "_definition": definition,
        "__doc__": definition + " (an even entire kernel; see symkin.special).",
        "__module__": __name__,
    })
    _register_kernel(cls)
    globals()[name] = cls
    return cls


class arck(StableKernel):
    """K(x) = (sin x - x cos x)/x^3 = 1/3 - x^2/30 + ...: the circular arc's deviation kernel.

    With u = θ/2 the arc's clamp lies l u^2 K(u) (cos u, sin u) from the rigid hinge's."""

    threshold = 1.5
    _base = "sinc_minus_cos"
    _subtract = (sp.Integer(0),)
    _latex_symbol = r"\operatorname{K}"
    _definition = "arck(x) = (sin x - x cos x)/x^3"

    @classmethod
    def coeff(cls, k):
        return sp.Rational((-1) ** k * (2 * k + 2), math.factorial(2 * k + 3))

    @classmethod
    def elementary(cls, x):
        return (sp.sin(x) - x * sp.cos(x)) / x ** 3

    @classmethod
    def _fdiff_expr(cls, x):
        return x * (sinr(1)(x) + 3 * cosr(2)(x) - 3 * sinr(2)(x))


_register_kernel(arck)

# The kernels the hinge models use, created (and registered) at import.
sinr0, sinr1, sinr2, sinr3, sinr4 = (sinr(n) for n in range(5))
cosr1, cosr2, cosr3, cosr4 = (cosr(n) for n in range(1, 5))
sinc = sinr0


def kernel_names() -> list[str]:
    """Names of the kernel functions created so far (registry keys)."""
    return [n for n in FLOAT64 if n.startswith(("sinr", "cosr")) or n == "arck"]


# =============================================================================================
# Carlson symmetric integrals (float64 helpers of the elastica)
# =============================================================================================

# =============================================================================================
# Carlson symmetric integrals (float64 helpers of the elastica)
# =============================================================================================

#: Carlson's stopping constants (3r)^(-1/6) for R_F and (r/4)^(-1/6) for R_D, r = 2^-53.
_RF_Q = _c_float((3 * UNIT_ROUNDOFF) ** (-1 / 6))
_RD_Q = _c_float((UNIT_ROUNDOFF / 4) ** (-1 / 6))

_RF_DOC = "Carlson's R_F(x, y, z), x, y, z >= 0 (at most one zero): duplication (Carlson 1995)"
_RD_DOC = "Carlson's R_D(x, y, z), x, y >= 0 (at most one zero), z > 0: duplication (Carlson 1995)"

_CARLSON_RF_PY = f'''
def carlson_rf(x, y, z):
    """{_RF_DOC}."""
    x0 = x
    y0 = y
    a0 = (x + y + z) / 3.0
    q = max(abs(a0 - x), abs(a0 - y), abs(a0 - z)) * {_RF_Q}
    an = a0
    fac = 1.0
    while fac * q >= abs(an):
        sx = math.sqrt(x)
        sy = math.sqrt(y)
        sz = math.sqrt(z)
        lam = sx * sy + sx * sz + sy * sz
        x = 0.25 * (x + lam)
        y = 0.25 * (y + lam)
        z = 0.25 * (z + lam)
        an = 0.25 * (an + lam)
        fac = 0.25 * fac
    X = fac * (a0 - x0) / an
    Y = fac * (a0 - y0) / an
    Z = -X - Y
    e2 = X * Y - Z * Z
    e3 = X * Y * Z
    return (1.0 - e2 / 10.0 + e3 / 14.0 + e2 * e2 / 24.0 - 3.0 * e2 * e3 / 44.0) / math.sqrt(an)
'''

_CARLSON_RD_PY = f'''
def carlson_rd(x, y, z):
    """{_RD_DOC}."""
    x0 = x
    y0 = y
    a0 = (x + y + 3.0 * z) / 5.0
    q = max(abs(a0 - x), abs(a0 - y), abs(a0 - z)) * {_RD_Q}
    an = a0
    fac = 1.0
    total = 0.0
    while fac * q >= abs(an):
        sx = math.sqrt(x)
        sy = math.sqrt(y)
        sz = math.sqrt(z)
        lam = sx * sy + sx * sz + sy * sz
        total = total + fac / (sz * (z + lam))
        x = 0.25 * (x + lam)
        y = 0.25 * (y + lam)
        z = 0.25 * (z + lam)
        an = 0.25 * (an + lam)
        fac = 0.25 * fac
    X = fac * (a0 - x0) / an
    Y = fac * (a0 - y0) / an
    Z = -(X + Y) / 3.0
    e2 = X * Y - 6.0 * Z * Z
    e3 = (3.0 * X * Y - 8.0 * Z * Z) * Z
    e4 = 3.0 * (X * Y - Z * Z) * Z * Z
    e5 = X * Y * Z * Z * Z
    poly = (1.0 - 3.0 * e2 / 14.0 + e3 / 6.0 + 9.0 * e2 * e2 / 88.0 - 3.0 * e4 / 22.0
            - 9.0 * e2 * e3 / 52.0 + 3.0 * e5 / 26.0)
    return fac / (an * math.sqrt(an)) * poly + 3.0 * total
'''

_CARLSON_RF_NP = f'''
def carlson_rf(x, y, z):
    """{_RF_DOC} (vectorised)."""
    x, y, z = np.broadcast_arrays(np.asarray(x, dtype=float), np.asarray(y, dtype=float),
                                  np.asarray(z, dtype=float))
    x0 = x
    y0 = y
    a0 = (x + y + z) / 3.0
    q = np.maximum(np.maximum(np.abs(a0 - x), np.abs(a0 - y)), np.abs(a0 - z)) * {_RF_Q}
    an = a0
    fac = np.ones_like(a0)
    active = fac * q >= np.abs(an)
    while np.any(active):
        sx = np.sqrt(x)
        sy = np.sqrt(y)
        sz = np.sqrt(z)
        lam = sx * sy + sx * sz + sy * sz
        x = np.where(active, 0.25 * (x + lam), x)
        y = np.where(active, 0.25 * (y + lam), y)
        z = np.where(active, 0.25 * (z + lam), z)
        an = np.where(active, 0.25 * (an + lam), an)
        fac = np.where(active, 0.25 * fac, fac)
        active = fac * q >= np.abs(an)
    X = fac * (a0 - x0) / an
    Y = fac * (a0 - y0) / an
    Z = -X - Y
    e2 = X * Y - Z * Z
    e3 = X * Y * Z
    return (1.0 - e2 / 10.0 + e3 / 14.0 + e2 * e2 / 24.0 - 3.0 * e2 * e3 / 44.0) / np.sqrt(an)
'''

_CARLSON_RD_NP = f'''
def carlson_rd(x, y, z):
    """{_RD_DOC} (vectorised)."""
    x, y, z = np.broadcast_arrays(np.asarray(x, dtype=float), np.asarray(y, dtype=float),
                                  np.asarray(z, dtype=float))
    x0 = x
    y0 = y
    a0 = (x + y + 3.0 * z) / 5.0
    q = np.maximum(np.maximum(np.abs(a0 - x), np.abs(a0 - y)), np.abs(a0 - z)) * {_RD_Q}
    an = a0
    fac = np.ones_like(a0)
    total = np.zeros_like(a0)
    active = fac * q >= np.abs(an)
    while np.any(active):
        sx = np.sqrt(x)
        sy = np.sqrt(y)
        sz = np.sqrt(z)
        lam = sx * sy + sx * sz + sy * sz
        total = np.where(active, total + fac / (sz * (z + lam)), total)
        x = np.where(active, 0.25 * (x + lam), x)
        y = np.where(active, 0.25 * (y + lam), y)
        z = np.where(active, 0.25 * (z + lam), z)
        an = np.where(active, 0.25 * (an + lam), an)
        fac = np.where(active, 0.25 * fac, fac)
        active = fac * q >= np.abs(an)
    X = fac * (a0 - x0) / an
    Y = fac * (a0 - y0) / an
    Z = -(X + Y) / 3.0
    e2 = X * Y - 6.0 * Z * Z
    e3 = (3.0 * X * Y - 8.0 * Z * Z) * Z
    e4 = 3.0 * (X * Y - Z * Z) * Z * Z
    e5 = X * Y * Z * Z * Z
    poly = (1.0 - 3.0 * e2 / 14.0 + e3 / 6.0 + 9.0 * e2 * e2 / 88.0 - 3.0 * e4 / 22.0
            - 9.0 * e2 * e3 / 52.0 + 3.0 * e5 / 26.0)
    return fac / (an * np.sqrt(an)) * poly + 3.0 * total
'''

_CARLSON_RF_C = f'''/* {_RF_DOC}. */
static double symkin_carlson_rf(double x, double y, double z)
{{
    const double x0 = x, y0 = y;
    const double a0 = (x + y + z) / 3.0;
    double q = fabs(a0 - x), an = a0, fac = 1.0, X, Y, Z, e2, e3;
    if (fabs(a0 - y) > q) q = fabs(a0 - y);
    if (fabs(a0 - z) > q) q = fabs(a0 - z);
    q *= {_RF_Q};
    while (fac * q >= fabs(an)) {{
        const double sx = sqrt(x), sy = sqrt(y), sz = sqrt(z);
        const double lam = sx * sy + sx * sz + sy * sz;
        x = 0.25 * (x + lam);
        y = 0.25 * (y + lam);
        z = 0.25 * (z + lam);
        an = 0.25 * (an + lam);
        fac = 0.25 * fac;
    }}
    X = fac * (a0 - x0) / an;
    Y = fac * (a0 - y0) / an;
    Z = -X - Y;
    e2 = X * Y - Z * Z;
    e3 = X * Y * Z;
    return (1.0 - e2 / 10.0 + e3 / 14.0 + e2 * e2 / 24.0 - 3.0 * e2 * e3 / 44.0) / sqrt(an);
}}
'''

_CARLSON_RD_C = f'''/* {_RD_DOC}. */
static double symkin_carlson_rd(double x, double y, double z)
{{
    const double x0 = x, y0 = y;
    const double a0 = (x + y + 3.0 * z) / 5.0;
    double q = fabs(a0 - x), an = a0, fac = 1.0, total = 0.0, X, Y, Z, e2, e3, e4, e5, poly;
    if (fabs(a0 - y) > q) q = fabs(a0 - y);
    if (fabs(a0 - z) > q) q = fabs(a0 - z);
    q *= {_RD_Q};
    while (fac * q >= fabs(an)) {{
        const double sx = sqrt(x), sy = sqrt(y), sz = sqrt(z);
        const double lam = sx * sy + sx * sz + sy * sz;
        total += fac / (sz * (z + lam));
        x = 0.25 * (x + lam);
        y = 0.25 * (y + lam);
        z = 0.25 * (z + lam);
        an = 0.25 * (an + lam);
        fac = 0.25 * fac;
    }}
    X = fac * (a0 - x0) / an;
    Y = fac * (a0 - y0) / an;
    Z = -(X + Y) / 3.0;
    e2 = X * Y - 6.0 * Z * Z;
    e3 = (3.0 * X * Y - 8.0 * Z * Z) * Z;
    e4 = 3.0 * (X * Y - Z * Z) * Z * Z;
    e5 = X * Y * Z * Z * Z;
    poly = 1.0 - 3.0 * e2 / 14.0 + e3 / 6.0 + 9.0 * e2 * e2 / 88.0 - 3.0 * e4 / 22.0
           - 9.0 * e2 * e3 / 52.0 + 3.0 * e5 / 26.0;
    return fac / (an * sqrt(an)) * poly + 3.0 * total;
}}
'''

_register("carlson_rf", _CARLSON_RF_PY.lstrip(), _CARLSON_RF_NP.lstrip(), _CARLSON_RF_C,
          mpmath.elliprf)
_register("carlson_rd", _CARLSON_RD_PY.lstrip(), _CARLSON_RD_NP.lstrip(), _CARLSON_RD_C,
          mpmath.elliprd)


# =============================================================================================
# Elastica: cantilever under a transverse tip force, as a function of the tip angle
# =============================================================================================

#: Below q = sin^2 θ = ELASTICA_Q_SERIES, A1 = (A - 1)/q comes from its Taylor series.
ELASTICA_Q_SERIES = 0.25


def _elastica_a_coeffs(n: int) -> list[Fraction]:
    """Exact Taylor coefficients of A(q) = ∫_0^1 (1 - q (1-v^2)^2)^(-1/2) dv:
    A_k = binom(2k, k)/4^k * ∫_0^1 (1 - v^2)^(2k) dv,
    with ∫_0^1 (1 - v^2)^m dv = 4^m m!^2/(2m+1)!."""
    out = []
    for k in range(n):
        a = Fraction(math.comb(2 * k, k), 4 ** k)
        m = 2 * k
        beta = Fraction(4 ** m * math.factorial(m) ** 2, math.factorial(2 * m + 1))
        out.append(a * beta)
    return out


def _elastica_a1_series() -> list[float]:
    coeffs = _elastica_a_coeffs(200)[1:]        # A1(q) = sum_k A_(k+1) q^k, A1 >= 4/15
    bound = Fraction(4, 15) * Fraction(UNIT_ROUNDOFF)
    qt = Fraction(ELASTICA_Q_SERIES)
    n = 1
    while coeffs[n] * qt ** n >= bound:
        n += 1
    return [float(c) for c in coeffs[:n]]


_ELASTICA_A1 = _elastica_a1_series()
_A1_HORNER = _horner(_ELASTICA_A1, "q")
_QS = _c_float(ELASTICA_Q_SERIES)
_HP = _c_float(_HALF_PI_FLOAT)

_ELASTICA_CORE_PY = f'''
def elastica_core(t):
    """(s, c, q, A, C, A1) of the tip-force elastica at tip angle t (|t| < pi/2)."""
    if not abs(t) <= {_HP}:
        raise DomainError("elastica_force: tip angle |theta| = %r reaches pi/2, the largest tip "
                          "angle a transverse end force can produce" % (abs(t),))
    s = math.sin(t)
    c = math.cos(t)
    q = s * s
    z = c * c
    y = 1.0 + abs(s)
    x = z / y
    A = carlson_rf(x, y, z)
    C = z * carlson_rd(x, y, z) / 3.0
    if q < {_QS}:
        A1 = {_A1_HORNER}
    else:
        A1 = (A - 1.0) / q
    return s, c, q, A, C, A1
'''

_ELASTICA_CORE_NP = f'''
def elastica_core(t):
    """(s, c, q, A, C, A1, ok) of the tip-force elastica (vectorised; NaN where |t| >= pi/2)."""
    t = np.asarray(t, dtype=float)
    ok = np.abs(t) <= {_HP}
    t = np.where(ok, t, np.nan)
    s = np.sin(t)
    c = np.cos(t)
    q = s * s
    z = c * c
    y = 1.0 + np.abs(s)
    x = z / y
    A = carlson_rf(x, y, z)
    C = z * carlson_rd(x, y, z) / 3.0
    small = q < {_QS}
    qs = np.where(small, 1.0, q)
    A1 = np.where(small, {_A1_HORNER}, (A - 1.0) / qs)
    return s, c, q, A, C, A1
'''

_ELASTICA_CORE_C = f'''/* Tip-force elastica at tip angle t (|t| < pi/2): v = (s, c, q, A, C, A1),
   A = R_F(1-|s|, 1+|s|, c^2), C = c^2 R_D(1-|s|, 1+|s|, c^2)/3,
   A1 = (A - 1)/q (Taylor series for q < {_QS}). */
static void symkin_elastica_core(double t, double *v)
{{
    const double s = sin(t), c = cos(t);
    const double q = s * s, z = c * c, y = 1.0 + fabs(s), x = z / y;
    const double A = symkin_carlson_rf(x, y, z);
    const double C = z * symkin_carlson_rd(x, y, z) / 3.0;
    v[0] = s;
    v[1] = c;
    v[2] = q;
    v[3] = A;
    v[4] = C;
    v[5] = q < {_QS} ? {_A1_HORNER} : (A - 1.0) / q;
}}
'''

_register("elastica_core", _ELASTICA_CORE_PY.lstrip(), _ELASTICA_CORE_NP.lstrip(),
          _ELASTICA_CORE_C, None, ("carlson_rf", "carlson_rd"))

#: name -> (python/numpy expression of (s, c, q, A, C, A1), C expression of v[0..5], docs)
_ELASTICA_OUTPUTS = {
    "elastica_x": ("1.0 / A", "1.0 / v[3]", "x_tip/l = 1/A"),
    "elastica_y": ("s * (1.0 - C / A)", "v[0] * (1.0 - v[4] / v[3])", "y_tip/l = s (1 - C/A)"),
    "elastica_dx": ("q * (0.5 / (1.0 + c) - A1 / A)",
                    "v[2] * (0.5 / (1.0 + v[1]) - v[5] / v[3])",
                    "x_tip/l - cos^2(t/2) = q (1/(2(1+c)) - A1/A)"),
    "elastica_dy": ("s * (0.5 - C / A)", "v[0] * (0.5 - v[4] / v[3])",
                    "y_tip/l - sin(t)/2 = s (1/2 - C/A)"),
    "elastica_dx_d1": ("s * (0.5 - (A + C - A1) / (2.0 * c * A * A))",
                       "v[0] * (0.5 - (v[3] + v[4] - v[5]) / (2.0 * v[1] * v[3] * v[3]))",
                       "d elastica_dx/dt = s (1/2 - (A + C - A1)/(2 c A^2))"),
    "elastica_dy_d1": ("0.5 * c * (1.0 + q * (A + C - A1) / (c * c * A)) * C / A",
                       "0.5 * v[1] * (1.0 + v[2] * (v[3] + v[4] - v[5]) / (v[1] * v[1] * v[3]))"
                       " * v[4] / v[3]",
                       "d elastica_dy/dt = c/2 (1 + q (A + C - A1)/(c^2 A)) C/A"),
}


# -- high precision (mpmath) -----------------------------------------------------------------------

def _elastica_mp(name: str, t, prec: int):
    """Value of elastica function `name` at mpmath real t, correct to about `prec` bits."""
    if not abs(t) < mpmath.pi / 2:
        raise DomainError(f"elastica_force: tip angle |theta| = {mpmath.nstr(abs(t), 8)} is not "
                          "below pi/2, the largest tip angle a transverse end force can produce")
    if t == 0:
        return {"elastica_x": mpmath.mpf(1), "elastica_dy_d1": mpmath.mpf(1) / 6}.get(
            name, mpmath.mpf(0))
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


for _name, (_py, _cc, _doc) in _ELASTICA_OUTPUTS.items():
    _register(
        _name,
        f'def {_name}(t):\n    """Tip-force elastica: {_doc}."""\n'
        f"    s, c, q, A, C, A1 = elastica_core(t)\n    return {_py}\n",
        f'def {_name}(t):\n    """Tip-force elastica: {_doc} (vectorised, NaN out of domain)."""\n'
        f"    s, c, q, A, C, A1 = elastica_core(t)\n    return {_py}\n",
        f"/* Tip-force elastica: {_doc}; NaN for |t| >= pi/2. */\n"
        f"static double symkin_{_name}(double t)\n{{\n    double v[6];\n"
        f"    if (!(fabs(t) <= {_HP})) return NAN;\n"
        f"    symkin_elastica_core(t, v);\n    return {_cc};\n}}\n",
        _elastica_mpmath_function(_name), ("elastica_core",))
_exec_sources()


# -- sympy classes ---------------------------------------------------------------------------------

def _check_elastica_domain(t: sp.Expr) -> None:
    """Raise DomainError for a number t with |t| >= π/2 (or not real)."""
    if not t.is_number:
        return
    if t.is_extended_real is False:
        raise DomainError(f"elastica_force: tip angle {t} is not real")
    beyond = (sp.Abs(t) - ELASTICA_LIMIT).is_nonnegative
    if beyond:
        raise DomainError(f"elastica_force: tip angle |theta| = {sp.N(sp.Abs(t), 8)} reaches "
                          "pi/2, the largest tip angle a purely transverse end force can "
                          "produce (the load would be infinite)")


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
    q = s ** 2
    A = 1 / X
    C = A * (1 - Y / s)
    A1 = (A - 1) / q
    if name == "elastica_dx_d1":
        return s * (sp.Rational(1, 2) - (A + C - A1) / (2 * c * A ** 2))
    return c / 2 * (1 + q * (A + C - A1) / (c ** 2 * A)) * C / A


class ElasticaFunction(_RegistryPrinting, sp.Function):
    """Base of the tip-force elastica functions of the tip angle θ (|θ| < π/2; see module doc)."""

    nargs = 1
    _parity = 1                  # +1 even, -1 odd in θ
    _at_zero = sp.S.Zero
    _latex_symbol = r"\xi"

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

    def _latex(self, printer, exp=None):
        arg = printer._print(self.args[0])
        base = rf"{self._latex_symbol}\!\left({arg}\right)"
        return base if exp is None else rf"\left({base}\right)^{{{exp}}}"

    @classmethod
    def numeric(cls, t: float) -> float:
        """float64 value (the FLOAT64 algorithm); DomainError for |t| >= π/2."""
        return FLOAT64[cls.__name__](t)


class elastica_x(ElasticaFunction):
    """x_tip/l of the tip-force elastica (even in θ): 1/R_F(1-|s|, 1+|s|, c^2)."""

    _parity = 1
    _at_zero = sp.S.One
    _latex_symbol = r"X_{e}"

    def fdiff(self, argindex=1):
        if argindex != 1:
            raise ArgumentIndexError(self, argindex)
        t = self.args[0]
        return elastica_dx_d1(t) - sp.sin(t) / 2


class elastica_y(ElasticaFunction):
    """y_tip/l of the tip-force elastica (odd in θ): s (1 - C/A)."""

    _parity = -1
    _latex_symbol = r"Y_{e}"

    def fdiff(self, argindex=1):
        if argindex != 1:
            raise ArgumentIndexError(self, argindex)
        t = self.args[0]
        return elastica_dy_d1(t) + sp.cos(t) / 2


class elastica_dx(ElasticaFunction):
    """x_tip/l - cos^2(θ/2) (even, O(θ^2): -θ^2/60 + ...), cancellation-free."""

    _parity = 1
    _latex_symbol = r"\Delta X_{e}"

    def fdiff(self, argindex=1):
        if argindex != 1:
            raise ArgumentIndexError(self, argindex)
        return elastica_dx_d1(self.args[0])


class elastica_dy(ElasticaFunction):
    """y_tip/l - sin(θ)/2 (odd, θ/6 + ...), cancellation-free."""

    _parity = -1
    _latex_symbol = r"\Delta Y_{e}"

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
    _latex_symbol = r"\Delta X_{e}'"


class elastica_dy_d1(_ElasticaD1):
    """d/dθ elastica_dy (even, 1/6 + ...), cancellation-free."""

    _parity = 1
    _at_zero = sp.Rational(1, 6)
    _latex_symbol = r"\Delta Y_{e}'"


ELASTICA_FUNCTIONS = (elastica_x, elastica_y, elastica_dx, elastica_dy, elastica_dx_d1,
                      elastica_dy_d1)


def elastica_load(theta: sp.Expr) -> sp.Expr:
    """The load α = P l^2/(EI) that bends the plate to tip angle θ: 2 sin θ / X_e(θ)^2."""
    return 2 * sp.sin(theta) / elastica_x(theta) ** 2


def expand_special(expr: sp.Expr) -> sp.Expr:
    """`expr` with every symkin special function written out (kernels: elementary; elastica:
    Legendre elliptic integrals)."""
    return expr.rewrite("elementary")


def numpy_namespace() -> dict:
    """Module dict for ``sympy.lambdify(..., modules=[numpy_namespace(), "numpy"])``."""
    return dict(NUMPY)


def float64_namespace() -> dict:
    """Module dict for ``sympy.lambdify(..., modules=[float64_namespace(), "math"])``."""
    return dict(FLOAT64)


def mpmath_namespace() -> dict:
    """Module dict for ``sympy.lambdify(..., modules=[mpmath_namespace(), "mpmath"])``."""
    return {k: v for k, v in MPMATH.items() if v is not None}


def used_names(*exprs: sp.Expr) -> list[str]:
    """Registry names of the symkin special functions appearing in `exprs` (sorted); pass them to
    :func:`c_support` for the C definitions a generated file needs."""
    names = set()
    for e in exprs:
        for f in sp.sympify(e).atoms(sp.Function):
            if isinstance(f, (StableKernel, ElasticaFunction)):
                names.add(type(f).__name__)
    return sorted(names)
