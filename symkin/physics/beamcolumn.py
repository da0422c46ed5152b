"""A plate under end loads in linear beam theory with its axial force kept (a beam-column), as
power series in the axial load index p = N l²/EI, derived with sympy (docs/physics.md).

The plate is taken in its mid-frame: x along the chord of the circular arc it bends into under a
pure moment, which turns its ends by −θ/2 and +θ/2. With l = EI = 1, w(x) the lateral offset,
an axial force p (tension > 0) and a lateral force f at the M end:

    w'''' = p w'',   w(0) = 0,  w'(0) = −θ/2,  w'(1) = θ/2,  p w'(1) − w'''(1) = f,

solved order by order in p. By the symmetry of the bending shape, θ moves M's clamp only along the
chord, and f only across it; the series give (p⁰ terms: the clamped–guided plate, 1/12, and the
uniform bending, 1):

    lateral offset   δ = f·shear(p)                         (shear(0) = 1/12)
    end moment       M = θ·rotation(p) − f·coupling(p)      (the moment link M exerts, EI/l units)
    shortening       ½∫w'² = θ²·bending(p) + f²·bowing(p)   (bending(0) = 1/24: the arc's own)
    strain energy    ½∫w''² = θ²·strain_bending(p) + f²·strain_shear(p)   (EI/l units)

`shear` is the inverse of the beam constraint model's transverse stiffness 12 + 6p/5 − p²/700
(Awtar et al. 2007) and `rotation` the series of (√p/2)/tanh(√p/2); the tests check both.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache

import sympy as sp

#: Highest power of p kept (p³: a few per mille at |p| = 3).
ORDER = 3


@dataclass(frozen=True)
class BeamColumn:
    """Coefficients (p⁰, p¹, ...) of the series; `value(name, p)` is the truncated series."""

    shear: tuple[sp.Rational, ...]
    rotation: tuple[sp.Rational, ...]
    coupling: tuple[sp.Rational, ...]
    bending: tuple[sp.Rational, ...]
    bowing: tuple[sp.Rational, ...]
    strain_bending: tuple[sp.Rational, ...]
    strain_shear: tuple[sp.Rational, ...]

    def value(self, name: str, p: sp.Expr, first: int = 0) -> sp.Expr:
        """Σ_{k ≥ first} c_k p^k of the series `name`."""
        return sp.Add(*(c * p**k for k, c in enumerate(getattr(self, name)) if k >= first))


@cache
def series(order: int = ORDER) -> BeamColumn:
    """The beam-column series through p^order (cached: derived once per process)."""
    x, p, f, t = sp.symbols("x p f theta")
    c = sp.symbols("c0:4")
    parts: list[sp.Poly] = []
    for k in range(order + 1):
        w_k = sp.Poly(c[0] + c[1] * x + c[2] * x**2 + c[3] * x**3, x)
        if k:
            # the order-k part of w'''' = p w'': w_k'''' = w_(k-1)'', integrated from 0
            w_k += parts[-1].diff(x).diff(x).integrate().integrate().integrate().integrate()
        slope = w_k.diff(x)
        previous = parts[-1].diff(x).eval(1) if k else 0
        first = 1 if k == 0 else 0
        conditions = [
            w_k.eval(0),
            slope.eval(0) + first * t / 2,
            slope.eval(1) - first * t / 2,
            previous - slope.diff(x).diff(x).eval(1) - first * f,
        ]
        solution = sp.solve(conditions, c, dict=True)[0]
        parts.append(sp.Poly(w_k.as_expr().subs(solution), x))
    offset = sum(p**k * w.eval(1) for k, w in enumerate(parts))
    moment = sum(p**k * w.diff(x).diff(x).eval(1) for k, w in enumerate(parts))
    slope = sum((w.diff(x) * p**k for k, w in enumerate(parts)), sp.Poly(0, x))
    shortening = (slope * slope).integrate().eval(1) / 2
    curvature = slope.diff(x)
    strain = (curvature * curvature).integrate().eval(1) / 2

    def coefficients(expr: sp.Expr, of: sp.Expr) -> tuple[sp.Rational, ...]:
        expr = sp.expand(expr)
        return tuple(sp.expand(expr.coeff(p, k)).coeff(of) for k in range(order + 1))

    return BeamColumn(
        shear=coefficients(offset, f),
        rotation=coefficients(moment, t),
        coupling=tuple(-c for c in coefficients(moment, f)),
        bending=coefficients(shortening, t**2),
        bowing=coefficients(shortening, f**2),
        strain_bending=coefficients(strain, t**2),
        strain_shear=coefficients(strain, f**2),
    )
