"""numpy source of symkin's special functions (:mod:`symkin.model.special`), beside the numpy
backend, and its scalar twin (the `math` module only) for ``sympy.lambdify(...,
[float64_namespace(), "math"])``.

Vectorised functions return NaN out of their domain; the scalar ones raise
:class:`symkin.model.special.DomainError`. Both run the same float algorithm as the C backend's
source, and :func:`numpy_namespace` / :func:`float64_namespace` execute exactly these texts.
"""

from __future__ import annotations

import math
from functools import cache

import numpy as np

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


def source(name: str, scalar: bool = False) -> str:
    """The numpy (or, with `scalar`, the math-module) definition of one function or helper."""
    if name in _FIXED:
        return _FIXED[name][scalar].lstrip()
    if name in OUTPUTS:
        return _elastica_output(name, scalar)
    if name == "bcol_h":
        return _bcol_h(scalar)
    cls = registry.FUNCTIONS[name]
    if issubclass(cls, axial.AxialKernel):
        return _axial(cls, scalar)
    if issubclass(cls, axial.AxialAt):
        return _axial_at(cls, scalar)
    if not issubclass(cls, StableKernel):
        raise KeyError(f"no numpy source for '{name}'")
    return _kernel(cls, scalar)


def numpy_namespace() -> dict:
    """Module dict for ``sympy.lambdify(..., modules=[numpy_namespace(), "numpy"])``."""
    return {n: _compiled(n, False) for n in registry.names()}


def float64_namespace() -> dict:
    """Module dict for ``sympy.lambdify(..., modules=[float64_namespace(), "math"])``."""
    return {n: _compiled(n, True) for n in registry.names()}


# One namespace per dialect, so helpers and their callers see each other.
_NAMESPACES: tuple[dict, dict] = ({"np": np}, {"math": math, "DomainError": registry.DomainError})


@cache
def _compiled(name: str, scalar: bool):
    """The function `name` defined by executing its source text."""
    namespace = _NAMESPACES[scalar]
    for helper in registry.DEPENDS.get(name, ()):
        _compiled(helper, scalar)
    kind = "scalar" if scalar else "numpy"
    exec(compile(source(name, scalar), f"<symkin {kind} {name}>", "exec"), namespace)
    return namespace[name]


def _kernel(cls: type[StableKernel], scalar: bool) -> str:
    """A kernel's float algorithm: Taylor series below its threshold, else the recurrence."""
    name = cls.__name__
    coeffs, n = cls.float_series()
    threshold = literal(cls.threshold)
    series, top = estrin(coeffs, "x2", x_power)
    doc = (
        f"{cls.definition}; Taylor series ({n} terms, Estrin's form) for |x| < {threshold}, "
        f"else the nested elementary formula"
    )
    if scalar:
        base = {
            "sinc": "math.sin(x) / x",
            "cosr1": "-2.0 * (math.sin(0.5 * x) / x) ** 2",
            "sinc_minus_cos": "math.sin(x) / x - math.cos(x)",
        }[cls.float_base]
        return (
            f"def {name}(x):\n"
            f'    """{doc}."""\n'
            f"    x2 = x * x\n"
            f"    if abs(x) < {threshold}:\n"
            + "".join(f"        {n} = {v}\n" for n, v in estrin_powers(top, "x2", x_power))
            + f"        return {series}\n"
            f"    b = {base}\n"
            + "".join(f"    {step}\n" for step in recurrence(cls.float_subtract, "x2"))
            + "    return b\n"
        )
    base = {
        "sinc": "np.sin(xs) / xs",
        "cosr1": "-2.0 * (np.sin(0.5 * xs) / xs) ** 2",
        "sinc_minus_cos": "np.sin(xs) / xs - np.cos(xs)",
    }[cls.float_base]
    return (
        f"def {name}(x):\n"
        f'    """{doc} (vectorised)."""\n'
        f"    x = np.asarray(x, dtype=float)\n"
        f"    small = np.abs(x) < {threshold}\n"
        f"    x2 = np.where(small, x * x, 0.0)  # the series where it is used: no overflow\n"
        + "".join(f"    {n} = {v}\n" for n, v in estrin_powers(top, "x2", x_power))
        + f"    series = {series}\n"
        f"    if small.all():\n"
        f"        return series\n"
        f"    xs = np.where(small, 1.0, x)\n"
        f"    xs2 = xs * xs\n"
        f"    b = {base}\n"
        + "".join(f"    {step}\n" for step in recurrence(cls.float_subtract, "xs2"))
        + "    return np.where(small, series, b)\n"
    )


# The float constants of the algorithms, as literals.
_A1 = horner(A1_SERIES, "q")
_QS = literal(Q_SERIES)
_HP = literal(HALF_PI_FLOAT)
_RF_Q = literal(RF_STOP)
_RD_Q = literal(RD_STOP)

_SCALAR_RF = f'''
def carlson_rf(x, y, z):
    """{RF_DOC}."""
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

_SCALAR_RD = f'''
def carlson_rd(x, y, z):
    """{RD_DOC}."""
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

_NUMPY_RF = f'''
def carlson_rf(x, y, z):
    """{RF_DOC} (vectorised)."""
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

_NUMPY_RD = f'''
def carlson_rd(x, y, z):
    """{RD_DOC} (vectorised)."""
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

_SCALAR_CORE = f'''
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
        A1 = {_A1}
    else:
        A1 = (A - 1.0) / q
    return s, c, q, A, C, A1
'''

_NUMPY_CORE = f'''
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
    A1 = np.where(small, {_A1}, (A - 1.0) / qs)
    return s, c, q, A, C, A1
'''

#: Each output of the elastica in terms of (s, c, q, A, C, A1) from elastica_core.
_OUTPUTS = {
    "elastica_x": "1.0 / A",
    "elastica_y": "s * (1.0 - C / A)",
    "elastica_dx": "q * (0.5 / (1.0 + c) - A1 / A)",
    "elastica_dy": "s * (0.5 - C / A)",
    "elastica_dx_d1": "s * (0.5 - (A + C - A1) / (2.0 * c * A * A))",
    "elastica_dy_d1": "0.5 * c * (1.0 + q * (A + C - A1) / (c * c * A)) * C / A",
}


def _elastica_output(name: str, scalar: bool) -> str:
    note = "" if scalar else " (vectorised, NaN out of domain)"
    return (
        f'def {name}(t):\n    """Tip-force elastica: {OUTPUTS[name]}{note}."""\n'
        f"    s, c, q, A, C, A1 = elastica_core(t)\n    return {_OUTPUTS[name]}\n"
    )


#: name -> (numpy source, scalar source)
_FIXED = {
    "carlson_rf": (_NUMPY_RF, _SCALAR_RF),
    "carlson_rd": (_NUMPY_RD, _SCALAR_RD),
    "elastica_core": (_NUMPY_CORE, _SCALAR_CORE),
}


def _near(form: axial.NearForm, var: str, indent: str) -> str:
    """Statements that define d, r, s of a near form at `var` (C and Python share the text)."""
    return "".join(f"{indent}{n} = {v}\n" for n, v in near_names(form, var))


def _axial(cls: type[axial.AxialKernel], scalar: bool) -> str:
    """A beam-column kernel: its `_at` form at h = bcol_h(p)."""
    name = cls.__name__
    note = "" if scalar else " (vectorised)"
    return (
        f'def {name}(p):\n    """{cls.definition}{note}."""\n    return {name}_at(p, bcol_h(p))\n'
    )


def _axial_at(cls: type[axial.AxialAt], scalar: bool) -> str:
    """A beam-column kernel at (p, h = bcol_h(p)): its near form on the near interval, its far
    form from NEAR_HIGH on, else its closed form at t = h; NaN (numpy) or DomainError (scalar)
    at and beyond the buckling load p = -pi^2."""
    name = cls.__name__
    kernel = cls.kernel
    form = kernel.near_form()
    num, den = kernel.float_closed()
    closed = f"({horner2(num, 'h', 'p')}) / ({horner2(den, 'h', 'p')})"
    far = far_text(kernel.far_form())
    lo, hi = literal(axial.NEAR_LOW), literal(axial.NEAR_HIGH)
    pcr = literal(axial.BUCKLING)
    doc = (
        f"{kernel.definition}, at h = bcol_h(p): {near_doc(form)}, from there on in u, tanh(u) "
        "and sech(u)^2, below in p and t = T(p)"
    )
    if scalar:
        return (
            f"def {name}(p, h):\n"
            f'    """{doc}."""\n'
            f"    if {lo} < p < {hi}:\n"
            + _near(form, "p", "        ")
            + f"        return {near_text(form)}\n"
            f"    if p >= {hi}:\n"
            + "".join(f"        {n} = {v}\n" for n, v in far_names("math.sqrt"))
            + f"        return {far}\n"
            f"    if not p > {pcr}:\n"
            f'        raise DomainError("{name}: the axial load index must exceed -pi^2")\n'
            f"    return {closed}\n"
        )
    return (
        f"def {name}(x, h):\n"
        f'    """{doc} (vectorised)."""\n'
        f"    x = np.asarray(x, dtype=float)\n"
        f"    near = (x > {lo}) & (x < {hi})\n"
        f"    p = np.where(near, x, {literal(axial.NEAR_CENTRE)})\n"
        + _near(form, "p", "    ")
        + f"    value = {near_text(form)}\n"
        f"    if near.all():\n"
        f"        return value\n"
        f"    high = x >= {hi}\n"
        f"    p = np.where(high, x, {literal(2 * axial.NEAR_HIGH)})\n"
        f"    h0 = h\n"
        f"    h = np.where(high, h0, 0.01)\n"
        + "".join(f"    {n} = {v}\n" for n, v in far_names("np.sqrt"))
        + f"    far = {far}\n"
        f"    inside = x > {pcr}\n"
        f"    low = ~near & ~high & inside\n"
        f"    p = np.where(low, x, {literal(2 * axial.NEAR_LOW)})\n"
        f"    h = np.where(low, h0, 0.5)\n"
        f"    closed = {closed}\n"
        f"    return np.where(near, value, np.where(high, far, np.where(inside, closed, np.nan)))\n"
    )


def _bcol_h(scalar: bool) -> str:
    """h(p): T's near form on the near interval, 1 - tanh(u) = 2e/(1 + e), e = exp(-sqrt(p)),
    from NEAR_HIGH on, tan(v)/v below."""
    form = axial.t_near_form()
    lo, hi = literal(axial.NEAR_LOW), literal(axial.NEAR_HIGH)
    centre = literal(axial.NEAR_CENTRE)
    doc = f"{h_doc()}: {near_doc(form)}"
    if scalar:
        return (
            "def bcol_h(p):\n"
            f'    """{doc}."""\n'
            f"    if {lo} < p < {hi}:\n"
            + _near(form, "p", "        ")
            + f"        return {near_text(form)}\n"
            f"    if p >= {hi}:\n"
            "        e = math.exp(-math.sqrt(p))\n"
            "        return 2.0 * e / (1.0 + e)\n"
            "    u = 0.5 * math.sqrt(-p)\n"
            "    return math.tan(u) / u\n"
        )
    return (
        "def bcol_h(x):\n"
        f'    """{doc} (vectorised)."""\n'
        "    x = np.asarray(x, dtype=float)\n"
        f"    near = (x > {lo}) & (x < {hi})\n"
        f"    p = np.where(near, x, {centre})\n"
        + _near(form, "p", "    ")
        + f"    value = {near_text(form)}\n"
        "    if near.all():\n"
        "        return value\n"
        f"    high = x >= {hi}\n"
        f"    e = np.exp(-np.sqrt(np.where(high, x, {hi})))\n"
        "    u = 0.5 * np.sqrt(np.where(near | high, 1.0, np.abs(x)))\n"
        "    return np.where(near, value, np.where(high, 2.0 * e / (1.0 + e), np.tan(u) / u))\n"
    )
