"""Hinge models (docs/file-format.md): the names the file may use, the parameters each one takes,
and the model functions.

A model gives (f(θ), g(θ)), the position of M's clamp in the plate frame fixed in P (the paper's
(3.2); the ideal revolute is (3.1)). The registry (MODELS, PRBM_PRESETS, HINGE_KEYS, MODEL_KEYS)
is what the reader needs to validate a file; :func:`plate_functions` gives a hinge's f, g and
its deviation from the ideal revolute df = f - f_rigid, dg = g - g_rigid (3.3) as sympy
expressions in THETA, the deviation written with the cancellation-free kernels of
:mod:`symkin.model.special` so that float64 keeps full relative accuracy for tiny θ
(docs/numerics.md).
"""

from __future__ import annotations

import dataclasses as _dc
import functools as _functools
import math as _math
from dataclasses import dataclass

import numpy as _np
import sympy as _sp

from . import special as _special

#: The hinge angle θ and the plate length l, the variables of every model's f(θ), g(θ) (and of
#: `expr` models' expressions).
THETA = _sp.Symbol("theta", real=True)
PLATE_LENGTH = _sp.Symbol("l", positive=True)

#: PRBM presets (Howell): characteristic radius factor γ and stiffness/angle factor c_θ.
PRBM_PRESETS: dict[str, dict[str, str]] = {
    "force": {"gamma": "0.8517", "c_theta": "1.2385"},
    "moment": {"gamma": "0.7346", "c_theta": "1.5164"},
}


@dataclass(frozen=True)
class ModelParameter:
    """One model parameter: its kind decides how the reader checks and stores it."""

    name: str
    kind: str  # "number" (expression > 0), "fraction" (0 < x <= 1), "choice", "text", "int", "expr"
    required: bool = False
    choices: tuple[str, ...] = ()
    default: object = None


@dataclass(frozen=True)
class ModelSpec:
    """A hinge model's name, its parameters and a one-line description for reports."""

    name: str
    parameters: tuple[ModelParameter, ...]
    description: str

    def parameter(self, key: str) -> ModelParameter | None:
        return next((p for p in self.parameters if p.name == key), None)


MODELS: dict[str, ModelSpec] = {
    spec.name: spec
    for spec in (
        ModelSpec("rigid", (), "ideal revolute joint at the plate's midpoint (eq. 3.1)"),
        ModelSpec("circular_arc", (), "plate bent into a circular arc by a pure end moment"),
        ModelSpec(
            "pure_moment",
            (),
            "hinge bent by a pure end moment, curvature along it proportional to 1/I(x): the "
            "circular arc of a uniform plate, a series in theta for a notch (model.notches)",
        ),
        ModelSpec(
            "prbm",
            (
                ModelParameter("gamma", "fraction", default=PRBM_PRESETS["force"]["gamma"]),
                ModelParameter("c_theta", "number", default=PRBM_PRESETS["force"]["c_theta"]),
                ModelParameter("preset", "choice", choices=tuple(sorted(PRBM_PRESETS))),
            ),
            "pseudo-rigid-body model: a pin at distance (1 - gamma) l from P's clamp; its "
            "first-order pivot is gamma l/c_theta from M's clamp, so against the midpoint pin it "
            'deviates by O(l theta) unless pin = "prbm"',
        ),
        ModelSpec("small_deflection", (), "linear beam theory: f = l, g = l theta / 2"),
        ModelSpec(
            "elastica_force",
            (),
            "cantilever elastica under a transverse end force (Bisshopp-Drucker); its "
            "first-order pivot is 2 l/3 from M's clamp, so against the midpoint pin it "
            'deviates by O(l theta) unless pin = "prbm"',
        ),
        ModelSpec(
            "table",
            (
                ModelParameter("file", "text", required=True),
                ModelParameter("degree", "int", default=3),
            ),
            "polynomial fit of measured (theta, f/l, g/l) rows",
        ),
        ModelSpec(
            "expr",
            (
                ModelParameter("f", "expr", required=True),
                ModelParameter("g", "expr", required=True),
            ),
            "user expressions in theta, l and the parameters",
        ),
    )
}

#: Hinge keys that are not model parameters: geometry, model, input, where the rigid reference
#: pin sits (`pin`), and the plate's stiffness data and beam theory (docs/physics.md).
HINGE_KEYS = (
    "name",
    "links",
    "at",
    "plate_angle",
    "length",
    "model",
    "input",
    "pin",
    "E",
    "thickness",
    "width",
    "nu",
    "beam",
    "allowable_stress",
)
#: Values of the `beam` key, the default first: a geometrically exact beam that stretches and
#: shears (Reissner 1972), or the inextensible, shear-free elastica (docs/physics.md).
BEAMS = ("reissner", "elastica")
#: Values of the `pin` key: the rigid reference pin at the plate midpoint (the paper's R_a), or at
#: the pivot of the model's pseudo-rigid-body equivalent (see :func:`pivot_distance`).
PINS = ("midpoint", "prbm")
#: The models of a uniform plate only: a hinge of another profile refuses them (its default is
#: `pure_moment`; `rigid`, `table` and `expr` take any profile, their l the span).
UNIFORM_MODELS = ("circular_arc", "prbm", "small_deflection", "elastica_force")
#: Every key a model may take, over all models (allowed in [defaults]).
MODEL_KEYS = tuple(sorted({p.name for spec in MODELS.values() for p in spec.parameters}))


# =============================================================================================
# Model functions f(θ), g(θ) and their cancellation-free deviations from the rigid hinge
# =============================================================================================


@dataclass(frozen=True)
class TableFit:
    """Least-squares polynomial fit of a `table` hinge's rows (numpy.polynomial, power basis).

    Residuals are of f/l and g/l at the rows (dimensionless): RMS and max |residual|."""

    degree: int
    coeffs_f: tuple[float, ...]  # f/l = sum coeffs_f[k] θ^k
    coeffs_g: tuple[float, ...]  # g/l = sum coeffs_g[k] θ^k
    rms_f: float
    max_f: float
    rms_g: float
    max_g: float
    theta_range: tuple[float, float]  # the rows' θ span: the fit is data only inside it
    rows: int


@dataclass(frozen=True)
class PlateFunctions:
    """A hinge model's functions of THETA with the plate length substituted (docs/file-format.md).

    f, g:        position of M's clamp in the plate frame fixed in P.
    df, dg:      f - f_rigid, g - g_rigid, in cancellation-free form when `stable` is True: a
                 float64 evaluation (the kernels as every backend writes them) keeps full
                 relative accuracy for every θ down to 1e-300 and up to `limit`.
    f_rigid, g_rigid: the ideal revolute the hinge is compared with: a pin at distance `pivot`
                 from M's clamp, (l - d) + d cos θ, d sin θ; at the plate midpoint (d = l/2,
                 the paper's (3.1)) unless the hinge says pin = "prbm".
    limit:       models defined only for |θ| < limit (elastica_force: π/2), else None.
    fit:         the table model's fit and its residuals, else None.
    pivot:       d, the rigid pin's distance from M's clamp along the straight plate (None: l/2).
    """

    model: str
    length: _sp.Expr
    f: _sp.Expr
    g: _sp.Expr
    df: _sp.Expr
    dg: _sp.Expr
    f_rigid: _sp.Expr
    g_rigid: _sp.Expr
    limit: _sp.Expr | None = None
    stable: bool = True
    fit: TableFit | None = None
    pivot: _sp.Expr | None = None

    def derivatives(self) -> tuple[_sp.Expr, _sp.Expr]:
        """(d df/dθ, d dg/dθ), through the kernels' stable derivatives."""
        t = THETA
        return _sp.diff(self.df, t), _sp.diff(self.dg, t)


def pivot_distance(hinge) -> _sp.Expr:
    """d, the distance of the hinge's rigid reference pin from M's clamp along the straight plate.

    `pin = "midpoint"`: l/2, the paper's R_a.  `pin = "prbm"`: the pivot of the model's own
    pseudo-rigid-body equivalent, the pin whose motion agrees with the model's to first order in θ,
    d = g'(0): l/2 for rigid, circular_arc and small_deflection; γ l/c_θ for prbm (not γ l: link
    M turns by θ = c_θ Θ, so the pin that moves M's clamp along the model's first-order path sits
    γ l/c_θ from it); 2 l/3 for elastica_force (the cantilever's tip under an end force moves
    y = 2 l θ/3); the fit's linear coefficient times l for table; g'(0) for expr.  Against a pin
    elsewhere the model carries an O(l θ) deviation (docs/physics.md)."""
    l = hinge.length
    pin = getattr(hinge, "pin", "midpoint")  # stand-in hinges of the reports have none
    if pin == "midpoint" or hinge.model in (
        "rigid",
        "circular_arc",
        "small_deflection",
        "pure_moment",
    ):
        return l / 2
    if hinge.model == "prbm":
        gamma, c = _prbm_constants(hinge)
        return gamma * l / c
    if hinge.model == "elastica_force":
        return 2 * l / 3
    t = THETA
    return _sp.limit(_sp.diff(_midpoint_functions(hinge).g, t), t, 0)


def _prbm_constants(hinge) -> tuple[_sp.Expr, _sp.Expr]:
    gamma = _sp.sympify(hinge.param("gamma", _sp.Rational(PRBM_PRESETS["force"]["gamma"])))
    c = _sp.sympify(hinge.param("c_theta", _sp.Rational(PRBM_PRESETS["force"]["c_theta"])))
    return gamma, c


def plate_functions(hinge, shape: str | None = None) -> PlateFunctions:
    """f, g, df = f - f_rigid, dg = g - g_rigid of `hinge` (a mechanism.Hinge) as sympy
    expressions in THETA, with the plate length replaced by ``hinge.length``; the rigid reference
    is the pin of :func:`pivot_distance`. `shape` (a model without parameters, e.g.
    "circular_arc") replaces the hinge's model for f and g but keeps its pin."""
    own = hinge if shape is None else _dc.replace(hinge, model=shape, model_params=())
    base = _midpoint_functions(own)
    d = pivot_distance(hinge)
    l = hinge.length
    if _sp.simplify(d - l / 2) == 0:
        return base
    t = THETA
    # Pin at d instead of l/2: f_rigid moves by (l/2 - d)(1 - cos θ), with 1 - cos θ = -θ² c1(θ)
    # (no cancellation: both parts of df are O(θ²)); g_rigid by (d - l/2) sin θ, which cancels
    # the model's own O(θ) term, so dg needs each model's exact form.
    f_rigid = l - d + d * _sp.cos(t)
    g_rigid = d * _sp.sin(t)
    df = base.df - (d - l / 2) * t**2 * _special.cosr(1)(t)
    stable = base.stable
    if own.model != hinge.model:
        dg = base.dg - (d - l / 2) * _sp.sin(t)  # the shape's own O(θ) term stays: no cancellation
    elif hinge.model == "prbm":
        # γ l sin(θ/c) - (γ l/c) sin θ = γ l θ³ (s1(θ/c)/c³ - s1(θ)/c)
        gamma, c = _prbm_constants(hinge)
        sinr1 = _special.sinr(1)
        dg = gamma * l * t**3 * (sinr1(t / c) / c**3 - sinr1(t) / c)
    else:
        dg = base.dg - (d - l / 2) * _sp.sin(t)  # a plain difference: loses ε/θ² in float64
        stable = False
    return PlateFunctions(
        base.model, l, base.f, base.g, df, dg, f_rigid, g_rigid, base.limit, stable, base.fit, d
    )


def _midpoint_functions(hinge) -> PlateFunctions:
    """The model's f, g and its deviation from the pin at the plate midpoint (eq. 3.1, 3.3)."""
    model = hinge.model
    if model not in MODELS:
        raise ValueError(f"unknown hinge model {model!r}")
    t = THETA
    l = hinge.length
    f_rigid = l * (1 + _sp.cos(t)) / 2
    g_rigid = l * _sp.sin(t) / 2
    sinr, cosr = _special.sinr, _special.cosr
    if model == "rigid":
        return PlateFunctions(model, l, f_rigid, g_rigid, _sp.S.Zero, _sp.S.Zero, f_rigid, g_rigid)
    if model == "pure_moment" and getattr(hinge, "profile", "uniform") != "uniform":
        # a notch: the rigid pin at its centre plus D(θ)(cos θ/2, sin θ/2), D a series in θ²
        from .notches import deviation_series
        from .profiles import section_of

        u = t / 2
        dev = l * deviation_series(section_of(hinge, 1), t)
        df, dg = _sp.cos(u) * dev, _sp.sin(u) * dev
        return PlateFunctions(model, l, f_rigid + df, g_rigid + dg, df, dg, f_rigid, g_rigid)
    if model in ("circular_arc", "pure_moment"):
        # f = l sin θ/θ, g = l (1 - cos θ)/θ; deviation l u^2 K(u) (cos u, sin u), u = θ/2
        u = t / 2
        f = l * sinr(0)(t)
        g = -l * t * cosr(1)(t)
        df = l * _sp.cos(u) * u**2 * _special.arck(u)
        dg = l * _sp.sin(u) * u**2 * _special.arck(u)
        return PlateFunctions(model, l, f, g, df, dg, f_rigid, g_rigid)
    if model == "small_deflection":
        # f = l, g = l θ/2; df = l sin^2(θ/2) = -l θ^2/2 c1(θ), dg = l (θ - sin θ)/2
        return PlateFunctions(
            model,
            l,
            l,
            l * t / 2,
            -l * t**2 / 2 * cosr(1)(t),
            -l * t**3 / 2 * sinr(1)(t),
            f_rigid,
            g_rigid,
        )
    if model == "prbm":
        gamma, c = _prbm_constants(hinge)
        big = t / c
        f = l * (1 + gamma * big**2 * cosr(1)(big))
        g = gamma * l * _sp.sin(big)
        # df/l = sin^2(θ/2) - 2γ sin^2(Θ/2) = (a - b)(a + b), a = sin u, b = sqrt(2γ) sin(u/c),
        # u = θ/2, k = sqrt(2γ)/c:  a - b = u [(1 - k) + u^2 (s1(u) - k/c^2 s1(u/c))],
        # 1 - k = (c^2 - 2γ)/(c (c + sqrt(2γ))) (exact when γ, c are numbers).
        # dg/l = γ sin Θ - sin(θ)/2 = θ [(2γ - c)/(2c) + θ^2 (γ/c^3 s1(Θ) - s1(θ)/2)].
        u = t / 2
        root = _sp.sqrt(2 * gamma)
        one_minus_k = (c**2 - 2 * gamma) / (c * (c + root))
        a_minus_b = u * (one_minus_k + u**2 * (sinr(1)(u) - root / c**3 * sinr(1)(u / c)))
        a_plus_b = _sp.sin(u) + root * _sp.sin(u / c)
        df = l * a_minus_b * a_plus_b
        k_g = (2 * gamma - c) / (2 * c)
        dg = l * t * (k_g + t**2 * (gamma / c**3 * sinr(1)(big) - sinr(1)(t) / 2))
        return PlateFunctions(model, l, f, g, df, dg, f_rigid, g_rigid)
    if model == "elastica_force":
        e = _special
        return PlateFunctions(
            model,
            l,
            l * e.elastica_x(t),
            l * e.elastica_y(t),
            l * e.elastica_dx(t),
            l * e.elastica_dy(t),
            f_rigid,
            g_rigid,
            limit=e.ELASTICA_LIMIT,
        )
    if model == "table":
        return _table_functions(hinge, t, l, f_rigid, g_rigid)
    # "expr": the user's own functions; the deviation is a plain difference
    ell = PLATE_LENGTH
    f = removable_at_zero(_sp.sympify(hinge.param("f")).subs(ell, l), t)
    g = removable_at_zero(_sp.sympify(hinge.param("g")).subs(ell, l), t)
    return PlateFunctions(model, l, f, g, f - f_rigid, g - g_rigid, f_rigid, g_rigid, stable=False)


#: Below this |θ| an expression with a removable singularity at θ = 0 is its Taylor polynomial
#: (of degree REMOVABLE_DEGREE: the next term is below 1e-20 of the value there).
REMOVABLE_BELOW = _sp.Rational(1, 1000)
REMOVABLE_DEGREE = 8


@_functools.lru_cache(maxsize=256)
def removable_at_zero(expr: _sp.Expr, t: _sp.Symbol) -> _sp.Expr:
    """`expr`, or, where it cannot be evaluated at θ = 0 itself (sin θ/θ: 0/0), `expr` for
    |θ| ≥ REMOVABLE_BELOW and its Taylor polynomial at 0 below: every backend evaluates it, and
    its derivatives, at θ = 0 by the limit (docs/file-format.md, `expr`). A pole at 0 (a negative
    power in the series) raises ValueError: the reader refuses it, naming the key."""
    if not _sp.sympify(expr).subs(t, 0).has(_sp.nan, _sp.zoo, _sp.oo, -_sp.oo):
        return expr
    poly = _sp.series(expr, t, 0, REMOVABLE_DEGREE + 1).removeO()
    if any(
        term.as_coeff_exponent(t)[1] < 0 or term.has(_sp.nan, _sp.zoo, _sp.oo)
        for term in _sp.Add.make_args(_sp.expand(poly))
    ):
        raise ValueError("it has a pole at theta = 0")
    return _sp.Piecewise((poly, _sp.Abs(t) < REMOVABLE_BELOW), (expr, True))


def _table_functions(hinge, t, l, f_rigid, g_rigid) -> PlateFunctions:
    """Polynomial fit p(θ) ≈ f/l, r(θ) ≈ g/l; deviations with the rigid Taylor terms subtracted
    exactly, coefficient by coefficient:
        cos^2(θ/2) = 1/2 + 1/2 sum_{k<n} (-1)^k θ^(2k)/(2k)! + θ^(2n)/2 c_n(θ),   2n > degree
        sin(θ)/2  = 1/2 sum_{k<m} (-1)^k θ^(2k+1)/(2k+1)! + θ^(2m+1)/2 s_m(θ),    2m+1 > degree
    so df/l = sum (p_k - ρ_k) θ^k - θ^(2n)/2 c_n(θ) with exact rational coefficients."""
    rows = hinge.param("rows")
    degree = int(hinge.param("degree", 3))
    if not rows:
        raise ValueError(f"hinge '{hinge.name}': table model without rows")
    th = _np.array([r[0] for r in rows], dtype=float)
    fl = _np.array([r[1] for r in rows], dtype=float)
    gl = _np.array([r[2] for r in rows], dtype=float)

    def fit(values):
        poly = _np.polynomial.Polynomial.fit(th, values, degree).convert()
        coef = _np.zeros(degree + 1)
        coef[: len(poly.coef)] = poly.coef
        resid = values - _np.polynomial.polynomial.polyval(th, coef)
        return coef, float(_np.sqrt(_np.mean(resid**2))), float(_np.max(_np.abs(resid)))

    cf, rms_f, max_f = fit(fl)
    cg, rms_g, max_g = fit(gl)
    n = degree // 2 + 1
    m = (degree + 1) // 2
    rho = {0: _sp.Integer(1)}
    for k in range(1, n):
        rho[2 * k] = _sp.Rational((-1) ** k, 2 * _math.factorial(2 * k))
    sigma = {2 * k + 1: _sp.Rational((-1) ** k, 2 * _math.factorial(2 * k + 1)) for k in range(m)}
    p = [_sp.Rational(float(c)) for c in cf]
    r = [_sp.Rational(float(c)) for c in cg]
    top_f = max(degree, 2 * n - 2)
    top_g = max(degree, 2 * m - 1)
    coef_df = [(p[k] if k <= degree else 0) - rho.get(k, 0) for k in range(top_f + 1)]
    coef_dg = [(r[k] if k <= degree else 0) - sigma.get(k, 0) for k in range(top_g + 1)]
    poly = lambda cs: _sp.Add(*(c * t**k for k, c in enumerate(cs)))  # noqa: E731
    f = l * poly(p)
    g = l * poly(r)
    df = l * (poly(coef_df) - t ** (2 * n) / 2 * _special.cosr(n)(t))
    dg = l * (poly(coef_dg) - t ** (2 * m + 1) / 2 * _special.sinr(m)(t))
    table_fit = TableFit(
        degree,
        tuple(float(c) for c in cf),
        tuple(float(c) for c in cg),
        rms_f,
        max_f,
        rms_g,
        max_g,
        (float(th.min()), float(th.max())),
        len(rows),
    )
    return PlateFunctions("table", l, f, g, df, dg, f_rigid, g_rigid, fit=table_fit)
