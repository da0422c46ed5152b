"""Cheaper variants of a derivation: the speed/accuracy choices a user can trade (docs/levels.md,
"Variants").

A variant is a generated level (paper, first_order, exact; with the plates' stiffness also loaded,
the PHYSICAL levels, in the file's models only), a hinge model choice and a precision:

- model ``file``: the mechanism's own models (the most faithful);
- ``prbm`` / ``small_deflection``: those models in place of circular_arc and elastica_force;
- ``taylorN``: each hinge's Δf, Δg replaced by its Taylor polynomial of degree N in θ
  (circular arc: Δf/l = θ²/12 - θ⁴/80 + ..., Δg/l = θ³/24 - θ⁵/360 + ...);
- precision ``float64`` or ``float32`` (numpy only).

The plate length enters Δz linearly, so its Taylor series is the level: ``first_order`` is the
first-order term in l/L, ``exact`` all orders.
"""

from __future__ import annotations

import dataclasses
import functools
from dataclasses import dataclass

import mpmath
import sympy as sp

from ..core.levels import LEVELS as LEVEL_TABLE
from ..graph.structure import build
from ..model import hinges as hinge_models
from ..model import special
from ..model.hinges import THETA
from ..model.mechanism import Mechanism
from .analysis import Analysis

#: The levels a variant can take: generated ones (a variant is timed in C and numpy), kinematic.
LEVELS = tuple(lv.name for lv in LEVEL_TABLE if lv.generated and not lv.needs_stiffness)
#: The generated physical levels: variants of files with the plates' stiffness (the file's models).
PHYSICAL = tuple(lv.name for lv in LEVEL_TABLE if lv.generated and lv.needs_stiffness)
FAITHFUL_MODELS = ("circular_arc", "elastica_force")
MODEL_CHOICES = ("file", "taylor2", "taylor3", "taylor4", "taylor6", "prbm", "small_deflection")
PRBM_DEFAULT = (("c_theta", sp.Rational("1.2385")), ("gamma", sp.Rational("0.8517")))


@dataclass(frozen=True, order=True)
class Variant:
    """One speed/accuracy choice."""

    level: str
    model: str = "file"
    precision: str = "float64"

    @property
    def name(self) -> str:
        parts = [self.level]
        if self.model != "file":
            parts.append(self.model)
        if self.precision != "float64":
            parts.append("f32")
        return "/".join(parts)

    @classmethod
    def parse(cls, text: str) -> Variant:
        parts = text.split("/")
        level, model, precision = parts[0], "file", "float64"
        for part in parts[1:]:
            if part == "f32":
                precision = "float32"
            else:
                model = part
        if not (
            (level in LEVELS and model in MODEL_CHOICES) or (level in PHYSICAL and model == "file")
        ):
            raise ValueError(f"unknown variant '{text}'")
        return cls(level, model, precision)


def default_variants(stiffness: bool = False) -> list[Variant]:
    """Every kinematic level with every model choice in float64, and the file's models in
    float32; with the plates' `stiffness`, the physical levels too (the file's models)."""
    out = [Variant(lv, m) for m in MODEL_CHOICES for lv in LEVELS]
    out += [Variant(lv, "file", "float32") for lv in LEVELS]
    if stiffness:
        out += [
            Variant(lv, "file", precision)
            for lv in PHYSICAL
            for precision in ("float64", "float32")
        ]
    return out


def substituted(mech: Mechanism, model: str) -> Mechanism:
    """The mechanism with `model` (prbm or small_deflection) in place of the faithful models."""
    if model not in ("prbm", "small_deflection"):
        return mech
    params = PRBM_DEFAULT if model == "prbm" else ()
    hinges = tuple(
        dataclasses.replace(h, model=model, model_params=params)
        if h.model in FAITHFUL_MODELS
        else h
        for h in mech.hinges
    )
    return dataclasses.replace(mech, hinges=hinges)


def truncated(degree: int):
    """A plate-function provider whose Δf, Δg are Taylor polynomials of `degree` in θ."""

    def provider(hinge):
        pf = hinge_models.plate_functions(hinge)
        df, dg = (_taylor(e, degree) for e in (pf.df, pf.dg))
        return dataclasses.replace(pf, df=df, dg=dg, f=pf.f_rigid + df, g=pf.g_rigid + dg)

    return provider


@functools.lru_cache(maxsize=1024)
def _taylor(expr: sp.Expr, degree: int) -> sp.Expr:
    """Taylor polynomial of `expr` in θ: symbolic where sympy can, else numeric (mpmath, 40
    digits) coefficients of the expression with its parameters at their values. Kept per
    expression and degree: sympy's series is most of a truncated variant's derivation, and the
    plates of one model (every hinge of a file, every variant chosen again) share it."""
    numeric_only = any(
        type(f).__name__.startswith(("elastica", "carlson")) for f in expr.atoms(sp.Function)
    )
    if not numeric_only:
        series = sp.series(expr, THETA, 0, degree + 1).removeO()
        if not series.has(sp.nan) and series.is_polynomial(THETA):
            return sp.expand(series)
    # Elastica kernels have no symbolic series: differentiate numerically at high precision,
    # keeping the (symbolic) plate length as a factor.
    length = next(iter(expr.free_symbols - {THETA}), None)
    unit = expr.subs(length, 1) if length is not None else expr
    fn = sp.lambdify(THETA, unit, modules=[special.mpmath_namespace(), "mpmath"])
    with mpmath.workdps(40):
        coeffs = mpmath.taylor(fn, 0, degree)
    poly = sum(sp.Float(str(c), 30) * THETA**k for k, c in enumerate(coeffs) if abs(c) > 1e-30)
    return sp.expand(poly * (length if length is not None else 1))


def analysis_for(mech: Mechanism, variant: Variant, points=None) -> Analysis:
    """The Analysis that derives `variant` of `mech`."""
    mech_v = substituted(mech, variant.model)
    plate = truncated(int(variant.model[6:])) if variant.model.startswith("taylor") else None
    return Analysis(build(mech_v), points, plate)
