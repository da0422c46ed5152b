"""One plate's closed-form mixed relation: given its compliant end rotation θ and the force link
M exerts on it, where M's clamp sits beyond the circular arc and the moment at M's end
(docs/physics.md, "The plate relation").

Units: plate length 1, EI = 1. The force is taken in the plate's mid-frame (P's plate frame
turned by θ/2, x along the chord of the circular arc): p = N l²/EI along it (tension > 0),
f = V l²/EI across. The relation comes from the plate's mixed potential

    U = -p (1 + D6(θ)) - ε_a p²/2 - ε_s f²/2 + θ²/(2 T(p̃)) - f̃² S(p̃)/2
        + θ² f̃² E1(p̃) + f̃⁴ E2(p̃) + θ⁴ E3(p̃),        p̃ = g p, f̃ = g f, g = 1 + (ε_a - ε_s) p

(exact in p, the beam-column shape ψ₁ put into the stationary functional: error O(ε⁶) in U,
fourth order in the bending angle and the lateral load; D6(θ) = sinc(θ/2) - (1 - θ²/24 +
θ⁴/1920) the arc's chord beyond its θ⁴ term; ε_a = EI/(EA l²), ε_s = EI/(κGA l²) the Reissner
plate's stretch and shear, zero for the elastica, entering through Haringx's g). By the envelope
theorem X = -∂U/∂p, Y = -∂U/∂f and ω = ∂U/∂θ - X f/2 + Y p/2 (turning θ turns the mid-frame in
which (p, f) are held). U is the stationary value of the elastic energy less the end force's work
p X + f Y at fixed θ, so the plate's elastic energy is U + p X + f Y (:func:`energy`). The kernels
are symkin.model.special.axial's.
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

from ..model.special import sinr
from ..model.special.axial import kernel


@dataclass(frozen=True)
class PlateRelation:
    """The outputs, in the mid-frame, units of l and EI/l."""

    along: sp.Expr  # M's clamp beyond the circular arc's end, along the arc's chord
    across: sp.Expr  # ... and across it
    omega: sp.Expr  # the moment link M exerts on the plate at its M end


def d6_prime(theta: sp.Expr) -> sp.Expr:
    """d/dθ of D6(θ) = w⁶ sinr3(w), w = θ/2 (O(θ⁵), no cancellation)."""
    w = sp.Dummy("w")
    return (sp.diff(w**6 * sinr(3)(w), w) / 2).subs(w, theta / 2)


def relation(
    theta: sp.Expr,
    p: sp.Expr,
    f: sp.Expr,
    ea: sp.Expr = 0,
    es: sp.Expr = 0,
    order: int = 4,
) -> PlateRelation:
    """The plate relation at compliant end rotation `theta` and load indices (p, f); `order` 2
    drops the quartic terms E1 = E2 = E3 = 0 (the truncation estimate's relation)."""
    de = ea - es
    g = 1 + de * p
    g1 = 1 + 2 * de * p  # dp̃/dp
    pt, ft = g * p, g * f
    s, w, a = kernel("s")(pt), kernel("w")(pt), kernel("a")(pt)
    if order == 4:
        e1, e2, e3 = kernel("e1")(pt), kernel("e2")(pt), kernel("e3")(pt)
        e1p, e2p, e3c = kernel("e1", 1)(pt), kernel("e2", 1)(pt), kernel("e3c")(pt)
    elif order == 2:
        e1 = e2 = e3 = e1p = e2p = e3c = sp.S.Zero
    else:
        raise ValueError("order must be 2 or 4")
    t2 = theta**2
    inner = ft * s - 2 * t2 * ft * e1 - 4 * ft**3 * e2  # -∂(U's f̃ terms)/∂f̃
    across = es * f + g * inner
    along = (
        ea * p
        + t2 * (g1 * a - 2 * de * p / 24)
        - t2**2 * (g1 * e3c - 2 * de * p / 1920)
        - g1 * (ft**2 * w + t2 * ft**2 * e1p + ft**4 * e2p)
        + de * f * inner
    )
    dudt = -p * d6_prime(theta) + theta * kernel("invt")(pt) + 2 * theta * ft**2 * e1
    dudt += 4 * theta * t2 * e3
    chord = sinr(0)(theta / 2) + along  # X: the arc's chord sin(w)/w plus `along`
    omega = dudt - chord * f / 2 + across * p / 2
    return PlateRelation(along, across, omega)


def energy(
    theta: sp.Expr,
    p: sp.Expr,
    f: sp.Expr,
    ea: sp.Expr = 0,
    es: sp.Expr = 0,
    order: int = 4,
) -> sp.Expr:
    """The plate's elastic energy (units EI/l) at the relation's state: U + p X + f Y, the mixed
    potential plus the end force's work; the arc's chord 1 + D6 is taken out of p X by hand, so
    no O(p) terms cancel."""
    rel = relation(theta, p, f, ea, es, order)
    de = ea - es
    g = 1 + de * p
    pt, ft = g * p, g * f
    t2 = theta**2
    # p (X - 1 - D6(θ)), X = sinc(θ/2) + along and 1 + D6 = sinc(θ/2) + θ²/24 - θ⁴/1920
    work = p * (rel.along - t2 / 24 + t2**2 / 1920) + f * rel.across
    u = -ea * p**2 / 2 - es * f**2 / 2 + t2 * kernel("invt")(pt) / 2 - ft**2 * kernel("s")(pt) / 2
    if order == 4:
        u += t2 * ft**2 * kernel("e1")(pt) + ft**4 * kernel("e2")(pt) + t2**2 * kernel("e3")(pt)
    return work + u
