"""C99 source of symkin's special functions (:mod:`symkin.model.special`), beside the C backend.

Every function is ``static double symkin_<name>(double)`` (the Carlson helpers take three
arguments, `symkin_elastica_core` fills an array); out of its domain it returns NaN. The
kernels' source is written from their language-neutral float algorithm; the elastica and its
Carlson helpers are written out here, as the numpy backend writes its own.
"""

from __future__ import annotations

from collections.abc import Iterable
from functools import cache

from ....model.special import axial, registry
from ....model.special.elastica_force import (
    A1_SERIES,
    HALF_PI_FLOAT,
    OUTPUTS,
    Q_SERIES,
    RD_DOC,
    RD_STOP,
    RF_DOC,
    RF_STOP,
)
from ....model.special.kernels import StableKernel
from ...literals import (
    estrin,
    estrin_powers,
    far_names,
    far_text,
    h_doc,
    horner,
    horner2,
    literal,
    near_doc,
    near_names,
    near_text,
    recurrence,
    x_power,
)


def support(names: Iterable[str]) -> str:
    """The C99 definitions needed to call the functions `names`, helpers first."""
    return "\n".join(source(n) for n in registry.with_dependencies(names))


@cache
def source(name: str) -> str:
    """The C99 definition of one registered function or helper."""
    if name in _FIXED:
        return _FIXED[name]
    if name in OUTPUTS:
        return _elastica_output(name)
    if name == "bcol_h":
        return _bcol_h()
    cls = registry.FUNCTIONS[name]
    if issubclass(cls, axial.AxialKernel):
        return _axial(cls)
    if issubclass(cls, axial.AxialAt):
        return _axial_at(cls)
    if not issubclass(cls, StableKernel):
        raise KeyError(f"no C source for '{name}'")
    return _kernel(cls)


def _axial(cls: type[axial.AxialKernel]) -> str:
    """A beam-column kernel: its `_at` form at h = bcol_h(p)."""
    name = cls.__name__
    return (
        f"/* {cls.definition}. */\n"
        f"static double symkin_{name}(double p)\n"
        "{\n"
        f"    return symkin_{name}_at(p, symkin_bcol_h(p));\n"
        "}\n"
    )


def _axial_at(cls: type[axial.AxialAt]) -> str:
    """A beam-column kernel at (p, h = bcol_h(p)): its near form on the near interval, its far
    form from NEAR_HIGH on, else its closed form at t = h; NaN at and beyond the buckling load
    p = -pi^2. The near form's shared values come before the branch: inlined into one routine
    (the plate relation's), the compiler computes them once for all its kernels."""
    kernel = cls.kernel
    form = kernel.near_form()
    num, den = kernel.float_closed()
    closed = f"({horner2(num, 'h', 'p')}) / ({horner2(den, 'h', 'p')})"
    names = "".join(f"    const double {n} = {v};\n" for n, v in near_names(form))
    far = "".join(f"        const double {n} = {v};\n" for n, v in far_names())
    return (
        f"/* {kernel.definition}, at h = bcol_h(p): {near_doc(form)}, from there on in u, "
        "tanh(u) and sech(u)^2, below in p and t = T(p). */\n"
        f"static double symkin_{cls.__name__}(double p, double h)\n"
        "{\n"
        + names
        + f"    if (p > {literal(axial.NEAR_LOW)} && p < {literal(axial.NEAR_HIGH)}) {{\n"
        f"        return {near_text(form)};\n"
        "    }\n"
        f"    if (p >= {literal(axial.NEAR_HIGH)}) {{\n"
        + far
        + f"        return {far_text(kernel.far_form())};\n"
        "    }\n"
        f"    if (!(p > {literal(axial.BUCKLING)})) return NAN;\n"
        f"    return {closed};\n"
        "}\n"
    )


def _bcol_h() -> str:
    """h(p): T's near form on the near interval, 1 - tanh(u) = 2e/(1 + e), e = exp(-sqrt(p)),
    from NEAR_HIGH on, tan(v)/v below."""
    form = axial.t_near_form()
    return (
        f"/* {h_doc()}: {near_doc(form)}. */\n"
        "static double symkin_bcol_h(double p)\n"
        "{\n"
        "    double u;\n"
        f"    if (p > {literal(axial.NEAR_LOW)} && p < {literal(axial.NEAR_HIGH)}) {{\n"
        + "".join(f"        const double {n} = {v};\n" for n, v in near_names(form))
        + f"        return {near_text(form)};\n"
        "    }\n"
        f"    if (p >= {literal(axial.NEAR_HIGH)}) {{\n"
        "        const double e = exp(-sqrt(p));\n"
        "        return 2.0 * e / (1.0 + e);\n"
        "    }\n"
        "    u = 0.5 * sqrt(-p);\n"
        "    return tan(u) / u;\n"
        "}\n"
    )


def _kernel(cls: type[StableKernel]) -> str:
    """A kernel's float algorithm: Taylor series below its threshold, else the recurrence."""
    name = cls.__name__
    coeffs, n = cls.float_series()
    threshold = literal(cls.threshold)
    doc = (
        f"{cls.definition}; Taylor series ({n} terms, Estrin's form) for |x| < {threshold}, "
        f"else the nested elementary formula"
    )
    base = {
        "sinc": "sin(x) / x",
        "cosr1": "-2.0 * (sin(0.5 * x) / x) * (sin(0.5 * x) / x)",
        "sinc_minus_cos": "sin(x) / x - cos(x)",
    }[cls.float_base]
    steps = "".join(f"    {step};\n" for step in recurrence(cls.float_subtract, "x2"))
    series, top = estrin(coeffs, "x2", x_power)
    powers = "".join(
        f"        const double {n} = {v};\n" for n, v in estrin_powers(top, "x2", x_power)
    )
    return (
        f"/* {name}(x): {doc}. */\n"
        f"static double symkin_{name}(double x)\n"
        "{\n"
        "    const double x2 = x * x;\n"
        "    double b;\n"
        f"    if (fabs(x) < {threshold}) {{\n" + powers + f"        return {series};\n"
        "    }\n"
        f"    b = {base};\n" + steps + "    return b;\n"
        "}\n"
    )


# The float constants of the algorithms, as literals.
_A1 = horner(A1_SERIES, "q")
_QS = literal(Q_SERIES)
_RF_Q = literal(RF_STOP)
_RD_Q = literal(RD_STOP)

_CARLSON_RF = f"""/* {RF_DOC}. */
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
"""

_CARLSON_RD = f"""/* {RD_DOC}. */
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
"""

_ELASTICA_CORE = f"""/* Tip-force elastica at tip angle t (|t| < pi/2): v = (s, c, q, A, C, A1),
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
    v[5] = q < {_QS} ? {_A1} : (A - 1.0) / q;
}}
"""

#: Each output of the elastica in terms of v = (s, c, q, A, C, A1) from symkin_elastica_core.
_OUTPUTS = {
    "elastica_x": "1.0 / v[3]",
    "elastica_y": "v[0] * (1.0 - v[4] / v[3])",
    "elastica_dx": "v[2] * (0.5 / (1.0 + v[1]) - v[5] / v[3])",
    "elastica_dy": "v[0] * (0.5 - v[4] / v[3])",
    "elastica_dx_d1": "v[0] * (0.5 - (v[3] + v[4] - v[5]) / (2.0 * v[1] * v[3] * v[3]))",
    "elastica_dy_d1": (
        "0.5 * v[1] * (1.0 + v[2] * (v[3] + v[4] - v[5]) / (v[1] * v[1] * v[3])) * v[4] / v[3]"
    ),
}


def _elastica_output(name: str) -> str:
    return (
        f"/* Tip-force elastica: {OUTPUTS[name]}; NaN for |t| >= pi/2. */\n"
        f"static double symkin_{name}(double t)\n{{\n    double v[6];\n"
        f"    if (!(fabs(t) <= {literal(HALF_PI_FLOAT)})) return NAN;\n"
        f"    symkin_elastica_core(t, v);\n    return {_OUTPUTS[name]};\n}}\n"
    )


_FIXED = {
    "carlson_rf": _CARLSON_RF,
    "carlson_rd": _CARLSON_RD,
    "elastica_core": _ELASTICA_CORE,
}
