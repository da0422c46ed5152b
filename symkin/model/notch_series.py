"""The pure-moment series coefficients ĉ_k of a notch as expressions of its shape ratios
(docs/levels.md, "Notch hinges"): the path taken when a ratio (t/R, t/c, t/r or r/l) depends on
a parameter, so that the generated C and numpy take R and t as parameters and `tolerance`,
`sweep` and the sensitivities vary them (docs/file-format.md, "Notch hinges").

Every profile's flank is a circular arc in an angle φ: x = R sin φ with T = t + 2R(1 − cos φ)
(circular), x = a sin φ with T = t + 2c(1 − cos φ) (elliptical, R → c) and a fillet of radius r
beyond a uniform middle (corner-filleted). With τ = t/R, σ = √(τ/(τ + 4)) and s = tan(φ/2) =
σ tan β, the angle turned up to φ is elementary,

    ∫₀^φ R cos φ' dφ'/T³ = 2 P(β)/(R² τ^{5/2} √(τ + 4)),
    P(β) = 3/8 (1 − σ⁴) β + (1 + σ⁴) sin 2β/4 + (1 − σ⁴) sin 4β/32,

so Ψ̃ = Ψ − 1/2 is a closed form of β. The outer integral ĉ_k = ∫₀¹ (Ψ̃^{2k} − 4^{−k}) dξ runs
over d(sin φ) in w with s = σ sinh w (β = atan(sinh w)): the neck, √(Rt) wide, is a unit
of w, and the integrand is analytic in the strip |Im w| < π/2 (its branch points s = ±iσ and
poles s = ±i both sit on its edges) over 0 ≤ w ≤ asinh(1/σ), so NODES fixed Gauss–Legendre
nodes in w converge geometrically at every τ. Each ĉ_k is then an explicit expression of the
ratios (sinh, atan, square roots): measured against 40-digit nested quadrature
(tests/test_notch_parameters.py) within 3e-15 relative for k ≤ 8 and 2e-12 for k = 17 at
t/R ≥ 0.005; at t/R = 1e-3 ĉ_1..ĉ_3 to double precision, k ≤ 8 within 2e-13 and k > 8 within
6e-11; double precision for every k beyond t/R = 0.02. The deviation, ĉ_1's at small θ and
(θ^{2k}/(2k)!)-weighted beyond, keeps 1e-14 relative at t/R ≥ 1e-3 over |θ| ≤ π.
Where the ratios are numbers the 45-digit graded quadrature of model.notches stays in use.
"""

from __future__ import annotations

from functools import cache
from typing import Any

import sympy as sp

#: Gauss–Legendre nodes in w of the outer integral (see the module's docstring for the error).
NODES = 40
#: Digits of the nodes and weights (the sympy backend evaluates at 40).
NODE_DIGITS = 45


@cache
def _rule() -> tuple[tuple[sp.Float, sp.Float], ...]:
    """The NODES Gauss–Legendre nodes on [0, 1] and their weights, at NODE_DIGITS digits, half of
    them: the other half mirrors them (w = W(1 ± x)/2)."""
    from sympy.integrals.quadrature import gauss_legendre

    x, w = gauss_legendre(NODES, NODE_DIGITS + 5)
    return tuple(
        (sp.Float((1 + xi) / 2, NODE_DIGITS), sp.Float(wi / 2, NODE_DIGITS))
        for xi, wi in zip(x, w, strict=True)
    )


def _flank(tau: sp.Expr) -> tuple[sp.Expr, list[tuple[sp.Expr, sp.Expr]]]:
    """One circular flank of neck ratio τ = t/R, radius 1: its whole ∫dx/T³ from the neck to
    its end and, at the nodes, (weight in x = sin φ, ∫dx/T³ from the neck up to the node)."""
    sigma = sp.sqrt(tau / (tau + 4))
    scale = 2 / (tau ** sp.Rational(5, 2) * sp.sqrt(tau + 4))
    q = sigma**4

    def angle(S: sp.Expr) -> sp.Expr:
        C2 = 1 + S**2
        p = (
            sp.Rational(3, 8) * (1 - q) * sp.atan(S)
            + (1 + q) * S / (2 * C2)
            + (1 - q) * S * (1 - S**2) / (8 * C2**2)
        )
        return scale * p

    end = sp.asinh(1 / sigma)
    nodes = []
    for x, w in _rule():
        at = end * x
        S = sp.sinh(at)
        s = sigma * S
        weight = end * w * 2 * (1 - s**2) / (1 + s**2) ** 2 * sigma * sp.cosh(at)
        nodes.append((weight, angle(S)))
    return angle(1 / sigma), nodes


def _series(middle: sp.Expr, tau: sp.Expr, terms: int) -> tuple[sp.Expr, ...]:
    """ĉ_1..ĉ_terms of a half notch: a uniform middle of length `middle` (in fillet radii, 0 for
    a circular or elliptical notch) and a circular flank of ratio τ beyond it, radius 1."""
    whole, nodes = _flank(tau)
    middle_turn = middle / tau**3  # ∫dx/T³ over the middle
    half = 2 * (middle_turn + whole)  # Ψ̃ = (∫₀ˣ dx/T³)/(2 × the half's) about the centre
    psi_m = middle_turn / half
    psis = [((middle_turn + turn) / half, weight) for weight, turn in nodes]
    out = []
    for k in range(1, terms + 1):
        quarter = sp.Rational(1, 4**k)
        flank = sp.Add(*(weight * (psi ** (2 * k) - quarter) for psi, weight in psis))
        mid = middle * (psi_m ** (2 * k) / (2 * k + 1) - quarter) if middle != 0 else 0
        out.append((mid + flank) / (middle + 1))
    return tuple(out)


def _deviation(middle: sp.Expr, tau: sp.Expr, theta: Any, terms: int) -> sp.Expr:
    """D(θ)/l of a half notch as in :func:`_series`: the flank's ∫(cos θΨ̃ − cos θ/2) on the
    nodes, each term 2 sin(θ(1/2 + Ψ̃)/2) sin(θ(1/2 − Ψ̃)/2) ≥ 0 (no cancellation at small θ),
    the uniform middle (Ψ̃ linear) by its series in θ² of `terms` terms."""
    whole, nodes = _flank(tau)
    middle_turn = middle / tau**3
    half = 2 * (middle_turn + whole)
    flank = sp.Add(
        *(
            2 * weight
            * sp.sin(theta * (middle_turn + turn + half / 2) / (2 * half))
            * sp.sin(theta * (whole - turn) / (2 * half))
            for weight, turn in nodes
        )
    )  # fmt: skip
    if middle == 0:
        return flank
    psi_m, square = middle_turn / half, theta**2
    acc: sp.Expr = sp.S.Zero
    for k in range(terms, 0, -1):
        c = psi_m ** (2 * k) / (2 * k + 1) - sp.Rational(1, 4**k)
        acc = sp.Rational((-1) ** k, sp.factorial(2 * k)) * c + square * acc
    return (middle * square * acc + flank) / (middle + 1)


def _ratios(section: Any) -> tuple[sp.Expr, sp.Expr]:
    """(the uniform middle in fillet radii, τ) of a notch section (model.notches)."""
    t = sp.sympify(section.thickness)
    if section.profile == "circular":
        return sp.S.Zero, t / sp.sympify(section.radius)
    if section.profile == "elliptical":
        return sp.S.Zero, t / sp.sympify(section.depth_c)
    if section.profile == "corner_filleted":
        r = sp.sympify(section.fillet)
        return sp.sympify(section.length) / (2 * r) - 1, t / r
    raise ValueError(f"profile {section.profile!r}: no closed-form series")


def deviation_expression(section: Any, theta: Any, terms: int) -> sp.Expr:
    """D(θ)/l of a notch section as an expression of its keys and θ: the same quadrature as
    :func:`coefficient_expressions`, summed over k in closed form (Σ_k of the series is
    cos θΨ̃ − cos θ/2 at each node), so 40 terms instead of 17 × 40."""
    return _deviation(*_ratios(section), theta, terms)


def coefficient_expressions(section: Any, terms: int) -> tuple[sp.Expr, ...]:
    """ĉ_1..ĉ_terms of a notch section (model.notches) as expressions of its keys."""
    return _series(*_ratios(section), terms)
