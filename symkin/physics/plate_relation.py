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
which (p, f) are held). A notch (:func:`notch_relation`) takes the same potential with its own
pure-moment chord and its section's moments in the kernels' arguments (docs/physics.md, "Notch
hinges at `loaded`"). U is the stationary value of the elastic energy less the end force's work
p X + f Y at fixed θ, so the plate's elastic energy is U + p X + f Y (:func:`energy`). The kernels
are symkin.model.special.axial's.
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

from ..model.sections import RelationTerms
from ..model.special import arck, sinr
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


def _notch_parts(
    theta: sp.Expr, p: sp.Expr, f: sp.Expr, ea: sp.Expr, es: sp.Expr, terms: RelationTerms, order
) -> tuple[sp.Expr, ...]:
    """The notch's kernels and the pieces its outputs and energy share (:func:`notch_relation`)."""
    if order not in (2, 4):
        raise ValueError("order must be 2 or 4")
    de = ea - es
    g = 1 + de * p
    g1 = 1 + 2 * de * p
    pa, pb = terms.alpha * g * p, terms.beta * g * p  # the rotation's and the lateral mode's
    load = terms.lam * g * f  # F = λ f̃: the lateral load of the uniform plate of its compliance
    e1 = e2 = sp.S.Zero
    if order == 4:
        e1, e2 = kernel("e1")(pb), kernel("e2")(pb)
    t2 = theta**2
    inner = load * _lateral(pb, terms) - 2 * t2 * load * e1 - 4 * load**3 * e2
    return de, g, g1, pa, pb, load, e1, e2, t2, inner


def _rotation(pa: sp.Expr, terms: RelationTerms) -> sp.Expr:
    """K = (1 − w)(1 + α p̃/12) + w/T(α p̃), w = terms.rotation: the rotation stiffness over
    EI₀/l, 1 + m₂ p̃ − q p̃² + ... (pa = α p̃)."""
    w = terms.rotation
    return (1 - w) * (1 + pa / 12) + w * kernel("invt")(pa)


def _lateral(pb: sp.Expr, terms: RelationTerms) -> sp.Expr:
    """Ŝ = (1 − w)(1/12 − β p̃/120) + w S(β p̃), w = terms.lateral: the lateral compliance over
    c_y l³/EI₀ times 1/12, to second order in p̃ the profile's (pb = β p̃)."""
    w = terms.lateral
    return (1 - w) * (sp.Rational(1, 12) - pb / 120) + w * kernel("s")(pb)


def notch_relation(
    theta: sp.Expr,
    p: sp.Expr,
    f: sp.Expr,
    ea: sp.Expr,
    es: sp.Expr,
    terms: RelationTerms,
    order: int = 4,
) -> PlateRelation:
    """A notch's relation (units: its span l and EI₀ = l/∫dx/EI; `terms` its section's,
    model.sections.RelationTerms), M's clamp again beyond the circular arc of the span. From

        U = -p (C(θ) + α θ²/24) - ε_a p²/2 - ε_s f²/2 + θ² K(p̃)/2 - F² Ŝ(p̃)/2
            + θ² F² E1(β p̃) + F⁴ E2(β p̃),        F = λ f̃,

    K = (1 − w_r)(1 + α p̃/12) + w_r/T(α p̃), Ŝ = (1 − w_l)(1/12 − β p̃/120) + w_l S(β p̃),

    C(θ) = cos(θ/2) + D(θ)/l the notch's chord under a pure moment (exact at p = f = 0: the
    energy of a pure moment is θ²/2 for any profile), α, β, λ, w_r, w_l the section's moments:
    the linear compliances are the section's integrals and each one's change with p is exact to
    second order; the higher orders in p and the quartic terms are the equivalent uniform
    plate's. With all terms 1 and the arc's chord it is :func:`relation` without its θ⁴ E3
    term."""
    de, g, g1, pa, pb, load, e1, _, t2, inner = _notch_parts(theta, p, f, ea, es, terms, order)
    e1p = e2p = sp.S.Zero
    if order == 4:
        e1p, e2p = kernel("e1", 1)(pb), kernel("e2", 1)(pb)
    half = theta / 2
    # the notch's chord beyond the arc's: D(θ)/l - (sinc(θ/2) - cos(θ/2))
    kinematic = terms.deviation(theta) - half**2 * arck(half)
    across = es * f + g * terms.lam * inner
    wr, wl = terms.rotation, terms.lateral
    shortening = wl * kernel("w")(pb) + (1 - wl) / 240  # −Ŝ'/(2β)
    along = (
        kinematic
        + ea * p
        + terms.alpha * t2 * (wr * g1 * kernel("a")(pa) - 2 * de * p / 24)
        - terms.beta * g1 * (load**2 * shortening + t2 * load**2 * e1p + load**4 * e2p)
        + de * f * terms.lam * inner
    )
    chord_rate = -sp.sin(half) / 2 + sp.diff(terms.deviation(theta), theta)  # dC/dθ
    dudt = -p * (chord_rate + terms.alpha * theta / 12) + theta * _rotation(pa, terms)
    dudt += 2 * theta * load**2 * e1
    chord = sinr(0)(half) + along
    omega = dudt - chord * f / 2 + across * p / 2
    return PlateRelation(along, across, omega)


def notch_energy(
    theta: sp.Expr,
    p: sp.Expr,
    f: sp.Expr,
    ea: sp.Expr,
    es: sp.Expr,
    terms: RelationTerms,
    order: int = 4,
) -> sp.Expr:
    """A notch's elastic energy (units EI₀/l) at its relation's state: U + p X + f Y, the
    chord C(θ) + α θ²/24 taken out of p X by hand (:func:`energy`'s)."""
    rel = notch_relation(theta, p, f, ea, es, terms, order)
    _, _, _, pa, pb, load, e1, e2, t2, _ = _notch_parts(theta, p, f, ea, es, terms, order)
    half = theta / 2
    kinematic = terms.deviation(theta) - half**2 * arck(half)
    work = p * (rel.along - kinematic - terms.alpha * t2 / 24) + f * rel.across
    u = -ea * p**2 / 2 - es * f**2 / 2 + t2 * _rotation(pa, terms) / 2
    u += -(load**2) * _lateral(pb, terms) / 2 + t2 * load**2 * e1 + load**4 * e2
    return work + u
