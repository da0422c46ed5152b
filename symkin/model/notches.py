"""Notch hinges (docs/file-format.md, "Notch hinges"; docs/physics.md, "Notch hinges"): the
circular, elliptical and corner-filleted profiles as sections (model.sections), and the shape of
a notch under a pure end moment as a series in θ (the `pure_moment` hinge model, model.hinges).

Each profile's thickness T(x) is symmetric about the hinge centre, the plate's midpoint
(`at`), and its span (the hinge's `length`: 2R, 2a or l) runs from P's clamp (x = 0) to M's
(x = span). Under a pure moment the curvature is θ·φ(x)/l with φ ∝ 1/T(x)³ (E' and b are the same
along the hinge), the angle turned up to x is θ·Ψ(x), Ψ(0) = 0, Ψ(l) = 1, and M's clamp sits at

    f = ∫₀ˡ cos θΨ dx,  g = ∫₀ˡ sin θΨ dx.

With Ψ̃ = Ψ − 1/2, odd about the centre for a symmetric profile, f = cos(θ/2) C(θ) and
g = sin(θ/2) C(θ), C(θ) = ∫₀ˡ cos θΨ̃ dx, while the pin at the centre gives l cos(θ/2)·(cos θ/2,
sin θ/2). The deviation is therefore (df, dg) = D(θ)·(cos θ/2, sin θ/2) with

    D(θ) = C(θ) − l cos(θ/2) = l Σ_{k≥1} (−1)^k θ^{2k}/(2k)! ĉ_k,  ĉ_k = ∫₀¹ (Ψ̃^{2k} − 4^{−k}) dξ,

every coefficient an integral of its own (no difference of nearly equal numbers at small θ:
cancellation-free, as the circular arc is). |Ψ̃| ≤ 1/2 bounds |ĉ_k| by 4^{−k}, so SERIES_TERMS
terms leave a remainder below l (θ/2)^{2K+2}/(2K+2)!: under 1e-34 l at |θ| = π, the bound of
every plate (kinematics.positions.plate_limit); the series is double precision over the whole
range a plate may turn (docs/levels.md). The ĉ_k depend on the profile's shape ratios only (t/R,
t/c, r/l and t/l): where those are numbers they are computed by graded Gauss–Legendre quadrature
at COEFFICIENT_DIGITS digits and enter the derivation as numbers, while the span l stays the
file's expression; where a ratio depends on a parameter, D(θ) is an expression of the keys
(model.notch_series).
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any, ClassVar

import mpmath
import numpy as np
import sympy as sp

from . import notch_correction, notch_series
from .sections import DIGITS, Compliance, RelationTerms, Section, X

#: Terms of the pure-moment series (θ² to θ^{2K}); see the module's docstring for the bound.
SERIES_TERMS = 17
#: Digits of the series coefficients (the sympy backend evaluates at 40).
COEFFICIENT_DIGITS = 45
#: Gauss–Legendre degree of mpmath (3·2^(d−1) nodes per interval) and the grading: intervals
#: halving towards the clamps (END_GRADING levels: T has a square-root branch point there) and
#: towards the hinge centre (CENTRE_GRADING levels: the neck, about √(t/R) of the span wide).
GAUSS_DEGREE = 4
#: Working digits of the section's moments `loaded` takes (:func:`moments`: float results).
MOMENT_DIGITS = 25
END_GRADING = 30
CENTRE_GRADING = 16


def _sqrt_gap(radius: Any, offset: Any) -> sp.Expr:
    """r − √(r² − u²): how far a circle of radius r has left its tangent at the offset u."""
    return radius - sp.sqrt(radius**2 - offset**2)


@dataclass(frozen=True)
class Notch(Section):
    """A notch: a profile symmetric about its centre, T(x) ≥ thickness, its span the hinge's
    `length`. Subclasses give their keys and span; the uniform-plate closed forms do not apply."""

    #: The profile's keys in a hinge (besides `thickness`, which every profile takes).
    keys: ClassVar[tuple[str, ...]] = ()
    #: What the span is, in words, for error messages ("2·radius").
    span_text: ClassVar[str] = ""
    #: Every profile here is symmetric about its centre (the pure-moment series needs it).
    symmetric: ClassVar[bool] = True
    #: The section's field of each key :func:`notch_correction.neck_ratio` takes.
    correction_keys: ClassVar[dict[str, str]] = {}
    #: Whether the beam carries the continuum correction (hinge key `continuum_correction`).
    continuum: bool = field(default=True, kw_only=True)

    @classmethod
    def span(cls, params: Mapping[str, sp.Expr]) -> sp.Expr:
        """The span (the hinge's `length`) from the profile's keys."""
        raise NotImplementedError

    @classmethod
    def own(cls, hinge: Any) -> dict[str, sp.Expr]:
        params = dict(hinge.profile_params)
        return {k: sp.sympify(params[k]) for k in cls.keys}

    @classmethod
    def from_hinge(cls, hinge: Any, scale: Any) -> Section:
        base = [
            sp.nan if getattr(hinge, k) is None else sp.sympify(getattr(hinge, k))
            for k in ("length", "thickness", "width", "E", "nu")
        ]
        return cls(  # type: ignore[call-arg]
            hinge.name,
            *base,
            sp.sympify(scale),
            **cls.own(hinge),
            continuum=bool(getattr(hinge, "continuum_correction", True)),
        )

    def correction(self) -> notch_correction.Correction:
        """The continuum correction of the beam's compliances (docs/physics.md, "Notch hinges:
        the continuum correction"): beam theory is 2–13 % too stiff on circular notches at
        t/R = 0.05–0.5 against a plane-strain continuum. The fit of
        :func:`~symkin.model.notch_correction.continuum_correction` at the profile's neck ratio,
        or the identity with `continuum_correction = false` (the plain beam)."""
        if not self.continuum or self.profile not in notch_correction.NOTCHES:
            return notch_correction.IDENTITY
        keys = {k: getattr(self, f) for k, f in self.correction_keys.items()}
        tau = notch_correction.neck_ratio(self.profile, self.thickness, **keys)
        return notch_correction.continuum_correction(self.profile, tau)

    def _EI(self, t: Any) -> sp.Expr:
        """E'I divided by the correction's θ_M factor: θ_M = ∫dx/EI and θ_F = y_M = ∫(l−x)dx/EI
        take the fit's factor (θ_F's is θ_M's), and the bending part of y_F with them."""
        return super()._EI(t) / self.correction().theta_M

    def _kGA(self, t: Any) -> sp.Expr:
        """κGA divided by the shear factor that makes the Timoshenko deflection
        ∫(l−x)²dx/EI + ∫dx/κGA take the fit's y_F factor, the bending part having θ_M's."""
        return super()._kGA(t) / self.shear_factor()

    def shear_factor(self) -> Any:
        """s with f_θ·B + s·S = f_y·(B + S), B = ∫(l−x)²dx/E'I and S = ∫dx/κGA of the plain
        beam: s = f_y + (f_y − f_θ)·B/S. 1 without a correction; a float once the section's
        parameters are numbers (B and S by quadrature), else an expression of their integrals."""
        fix = self.correction()
        if fix is notch_correction.IDENTITY:
            return sp.S.One
        l = self.length
        plain = (
            lambda x, t: (l - x) ** 2 / Section._EI(self, t),
            lambda x, t: 1 / Section._kGA(self, t),
        )
        free = set().union(*(sp.sympify(p).free_symbols for p in self.pieces())) - {X}
        free |= sp.sympify(l).free_symbols | sp.sympify(self.modulus()).free_symbols
        if free:
            bend, shear = (
                sp.Add(*(sp.Integral(f(X, t), (X, a, b)) for a, b, t in self.pieces()))
                for f in plain
            )
        else:
            key = sp.srepr((self.pieces(), l, self.width, self.E, self.nu, self.scale))
            if key not in _SHEAR:
                _SHEAR[key] = tuple(float(self.quad(f, {})) for f in plain)
            bend, shear = _SHEAR[key]
        return fix.y_F + (fix.y_F - fix.theta_M) * bend / shear

    def compliance_numbers(self, values: Mapping[sp.Symbol, sp.Expr]) -> Compliance:
        """The compliance integrals at `values`, on the section at those values (its shear
        factor then a number, not an expression of integrals)."""
        if values:
            return self.at(values).compliance_numbers({})
        return super().compliance_numbers(values)

    def root_radius(self) -> sp.Expr:
        """The radius of curvature of the cut where the hinge is thinnest (K_t's ρ)."""
        raise NotImplementedError

    def stress_factor(self) -> sp.Expr:
        """The notch's stress-concentration factor K_t = (1 + t/(2ρ))^(9/20) (Lobontiu,
        Compliant Mechanisms: Design of Flexure Hinges, 2002, after Peterson's and Pilkey's
        charts for a notched plate in bending; docs/physics.md), ρ the root radius."""
        return (1 + self.thickness / (2 * self.root_radius())) ** sp.Rational(9, 20)

    def quad(
        self, integrand: Callable[[Any, Any], Any], values: Mapping[sp.Symbol, sp.Expr]
    ) -> mpmath.mpf:
        """Section.quad with each piece cut at points halving towards the hinge centre: the
        neck is about √(t R) wide, too narrow for a quadrature over the whole span to see at
        small t/R (18 % off at t/R = 1e-4 without the cuts). Kept by span and integrands
        (_QUADS): a mechanism's notches are often alike, and its levels and reports ask for the
        same integrals again (1-2 s each at DIGITS)."""
        at = self.at(values)
        pieces = tuple((a, b, integrand(X, t).xreplace(values)) for a, b, t in at.pieces())
        key = sp.srepr((at.length, pieces))
        if key in _QUADS:
            return _QUADS[key]
        total = mpmath.mpf(0)
        with mpmath.workdps(DIGITS + 5):
            centre = mpmath.mpf(sp.N(at.length / 2, DIGITS + 5))
            cuts = [
                centre + side * centre * mpmath.mpf(2) ** -j
                for j in range(1, 40)
                for side in (-1, 1)
            ]
            for a, b, expr in pieces:
                f = sp.lambdify(X, expr, "mpmath")
                lo, hi = (mpmath.mpf(sp.N(e, DIGITS + 5)) for e in (a, b))
                inner = sorted({c for c in [*cuts, centre] if lo < c < hi})
                # the real part: at a node that rounds onto a fillet's end, r² − u² is a
                # rounding below zero and its root imaginary (T is real there, t + 2r)
                total += mpmath.quad(lambda x, f=f: mpmath.re(f(x)), [lo, *inner, hi])
        if len(_QUADS) >= QUADS_KEPT:
            del _QUADS[next(iter(_QUADS))]  # the oldest
        _QUADS[key] = total
        return total

    def compliance(self) -> Compliance:
        """The compliance integrals, unevaluated (sympy's Integral over each piece): sympy has
        no closed form it finds in time, and sp.N evaluates them by mpmath's quadrature at the
        precision asked for, once the parameters have values."""
        return Compliance(
            *(
                sp.Add(*(sp.Integral(f(X, t), (X, a, b)) for a, b, t in self.pieces()))
                for f in self._integrands()
            )
        )

    def relation_terms(self, values: Mapping[sp.Symbol, sp.Expr]) -> RelationTerms:
        """`loaded`'s terms of the notch at `values` (model.sections.RelationTerms): numbers of
        its shape ratios by quadrature (:func:`moments`), the continuum correction included (it
        divides EI by one factor along the hinge: a(ξ) and the shape are the plain beam's)."""
        at = self.at(values)
        m2, cy, s1, q, r2 = moments(at)
        c = coefficients(at)
        terms = tuple(
            sp.Float((-1) ** k * c[k - 1] / sp.factorial(2 * k), COEFFICIENT_DIGITS)
            for k in range(1, SERIES_TERMS + 1)
        )
        alpha, beta = 12 * m2, 10 * s1 / cy
        # the kernels' own p² terms, −(α p)²/720 and 17 (β p)²/20160 per 12 c_y, weighted to q, r₂
        rotation = 720 * q / alpha**2
        lateral = 20160 * r2 / (17 * 12 * cy * beta**2)
        return RelationTerms(alpha, beta, (12 * cy) ** 0.5, terms, rotation, lateral)

    def shape(self, theta: Any) -> tuple[sp.Expr, sp.Expr]:
        """(f, g) under a pure moment: the rigid pin at the centre plus the series deviation."""
        d = self.length * deviation_series(self, theta)
        half = theta / 2
        return (
            self.length * sp.cos(half) ** 2 + sp.cos(half) * d,
            self.length * sp.sin(half) * sp.cos(half) + sp.sin(half) * d,
        )


@dataclass(frozen=True)
class CircularNotch(Notch):
    """Right-circular notch: T(x) = t + 2(R − √(R² − u²)), u = x − R, over the span 2R."""

    radius: sp.Expr
    profile: ClassVar[str] = "circular"
    keys: ClassVar[tuple[str, ...]] = ("radius",)
    correction_keys: ClassVar[dict[str, str]] = {"radius": "radius"}
    span_text: ClassVar[str] = "2·radius"

    @classmethod
    def span(cls, params: Mapping[str, sp.Expr]) -> sp.Expr:
        return 2 * params["radius"]

    def root_radius(self) -> sp.Expr:
        return self.radius

    def pieces(self) -> tuple[tuple[sp.Expr, sp.Expr, sp.Expr], ...]:
        r = self.radius
        return ((sp.S.Zero, self.length, self.thickness + 2 * _sqrt_gap(r, X - r)),)


@dataclass(frozen=True)
class EllipticalNotch(Notch):
    """Elliptical notch: T(x) = t + 2c(1 − √(1 − u²/a²)), u = x − a, over the span 2a."""

    semi_axis: sp.Expr
    depth_c: sp.Expr
    profile: ClassVar[str] = "elliptical"
    keys: ClassVar[tuple[str, ...]] = ("semi_axis", "depth")
    correction_keys: ClassVar[dict[str, str]] = {"semi_axis": "semi_axis", "depth": "depth_c"}
    span_text: ClassVar[str] = "2·semi_axis"

    @classmethod
    def own(cls, hinge: Any) -> dict[str, sp.Expr]:
        params = dict(hinge.profile_params)
        return {
            "semi_axis": sp.sympify(params["semi_axis"]),
            "depth_c": sp.sympify(params["depth"]),
        }

    @classmethod
    def span(cls, params: Mapping[str, sp.Expr]) -> sp.Expr:
        return 2 * params["semi_axis"]

    def root_radius(self) -> sp.Expr:
        """a²/c, the ellipse's radius of curvature at the end of its minor semi-axis."""
        return self.semi_axis**2 / self.depth_c

    def pieces(self) -> tuple[tuple[sp.Expr, sp.Expr, sp.Expr], ...]:
        a, c = self.semi_axis, self.depth_c
        u = (X - a) / a
        return ((sp.S.Zero, self.length, self.thickness + 2 * c * (1 - sp.sqrt(1 - u**2))),)


@dataclass(frozen=True)
class CornerFilleted(Notch):
    """Corner-filleted plate: thickness t between two fillets of radius r at its ends, span l."""

    fillet: sp.Expr
    profile: ClassVar[str] = "corner_filleted"
    keys: ClassVar[tuple[str, ...]] = ("length", "fillet")
    span_text: ClassVar[str] = "length"

    @classmethod
    def own(cls, hinge: Any) -> dict[str, sp.Expr]:
        return {"fillet": sp.sympify(dict(hinge.profile_params)["fillet"])}

    @classmethod
    def span(cls, params: Mapping[str, sp.Expr]) -> sp.Expr:
        return params["length"]

    def root_radius(self) -> sp.Expr:
        return self.fillet

    def pieces(self) -> tuple[tuple[sp.Expr, sp.Expr, sp.Expr], ...]:
        l, r, t = self.length, self.fillet, self.thickness
        return (
            (sp.S.Zero, r, t + 2 * _sqrt_gap(r, r - X)),
            (r, l - r, t),
            (l - r, l, t + 2 * _sqrt_gap(r, X - l + r)),
        )


#: The notch profiles (model.profiles registers them).
NOTCHES: tuple[type[Notch], ...] = (CircularNotch, EllipticalNotch, CornerFilleted)


def profile_keys(profile: str) -> tuple[str, ...]:
    """The keys a hinge of `profile` takes besides `thickness` (uniform: `length`)."""
    for cls in NOTCHES:
        if cls.profile == profile:
            return cls.keys
    return ("length",)


def _normalised(section: Notch) -> tuple[tuple[Any, Any, Any], ...]:
    """The pieces in ξ = x/l ∈ [0, 1] with T/l: numbers when the shape's ratios are numbers."""
    xi = sp.Symbol("xi", real=True)
    pieces = section.pieces()
    names = set().union(*(sp.sympify(p).free_symbols for p in pieces)) - {X}
    positive = {s: sp.Dummy(s.name, positive=True) for s in names}  # lengths are positive
    l = sp.sympify(section.length).xreplace(positive)
    out = []
    for a, b, t in pieces:
        ends = [sp.simplify(sp.sympify(e).xreplace(positive) / l) for e in (a, b)]
        depth = sp.simplify(t.xreplace(positive).xreplace({X: l * xi}) / l)
        free = (depth.free_symbols - {xi}) | set().union(*(e.free_symbols for e in ends))
        if free:
            raise ValueError(
                f"the shape of the {section.profile} notch depends on "
                f"{', '.join(sorted(str(s) for s in free))} (its ratios must be numbers)"
            )
        out.append((ends[0], ends[1], sp.lambdify(xi, depth, "mpmath")))
    return tuple(out)


def _graded(a: Any, b: Any) -> list[Any]:
    """[a, b] cut into intervals halving towards both ends and towards ξ = 1/2 inside it."""
    points = {a, b}
    for end in (a, b):
        for j in range(1, END_GRADING):
            points.add(
                end + (b - a) * (mpmath.mpf(2) ** -j if end == a else -(mpmath.mpf(2) ** -j))
            )
    half = mpmath.mpf(1) / 2
    if a < half < b:
        points.add(half)
        for j in range(1, CENTRE_GRADING):
            for side in (-1, 1):
                p = half + side * mpmath.mpf(2) ** (-j - 1)
                if a < p < b:
                    points.add(p)
    return sorted(points)


def _coefficients(pieces: Any) -> tuple[sp.Float, ...]:
    """ĉ_1..ĉ_K of a normalised profile (see the module's docstring), at COEFFICIENT_DIGITS."""
    with mpmath.workdps(COEFFICIENT_DIGITS + 10):
        gauss = mpmath.calculus.quadrature.GaussLegendre(mpmath.mp)
        rule = gauss.calc_nodes(GAUSS_DEGREE, mpmath.mp.prec)  # (node, weight) on [−1, 1]
        intervals = []
        for a, b, depth in pieces:
            cuts = _graded(mpmath.mpf(sp.N(a, 60)), mpmath.mpf(sp.N(b, 60)))
            intervals += [(lo, hi, depth) for lo, hi in itertools.pairwise(cuts)]

        def weight(depth: Any, x: Any) -> Any:
            return 1 / depth(x) ** 3

        def integral(depth: Any, lo: Any, hi: Any) -> Any:
            mid, rad = (lo + hi) / 2, (hi - lo) / 2
            return rad * mpmath.fsum(w * weight(depth, mid + rad * n) for n, w in rule)

        parts = [integral(d, lo, hi) for lo, hi, d in intervals]
        total = mpmath.fsum(parts)
        sums = [mpmath.mpf(0)] * SERIES_TERMS
        before = mpmath.mpf(0)
        for (lo, hi, depth), part in zip(intervals, parts, strict=True):
            mid, rad = (lo + hi) / 2, (hi - lo) / 2
            for n, w in rule:
                x = mid + rad * n
                psi = (before + integral(depth, lo, x)) / total - mpmath.mpf(1) / 2
                sq = psi**2
                for k in range(SERIES_TERMS):
                    sums[k] += rad * w * (sq ** (k + 1) - mpmath.mpf(4) ** -(k + 1))
            before += part
        return tuple(sp.Float(mpmath.nstr(s, COEFFICIENT_DIGITS), COEFFICIENT_DIGITS) for s in sums)


def _moments(pieces: Any) -> tuple[float, float, float]:
    """(m₂, c_y, s₁) of a normalised profile (model.sections.RelationTerms): ∫Ψ̃² dξ,
    ∫(ξ − 1/2)² a dξ and ∫φ² dξ, φ(ξ) = ∫₀^ξ a (1/2 − η) dη, a = T⁻³/∫T⁻³ dξ, by the graded
    Gauss–Legendre rule of the series coefficients at MOMENT_DIGITS digits."""
    with mpmath.workdps(MOMENT_DIGITS):
        gauss = mpmath.calculus.quadrature.GaussLegendre(mpmath.mp)
        rule = gauss.calc_nodes(GAUSS_DEGREE, mpmath.mp.prec)
        half = mpmath.mpf(1) / 2
        intervals = []
        for a, b, depth in pieces:
            cuts = _graded(mpmath.mpf(sp.N(a, 40)), mpmath.mpf(sp.N(b, 40)))
            intervals += [(lo, hi, depth) for lo, hi in itertools.pairwise(cuts)]

        def integral(depth: Any, lo: Any, hi: Any, lever: bool) -> Any:
            mid, rad = (lo + hi) / 2, (hi - lo) / 2
            return rad * mpmath.fsum(
                w * (half - (mid + rad * n) if lever else 1) / depth(mid + rad * n) ** 3
                for n, w in rule
            )

        parts = [integral(d, lo, hi, False) for lo, hi, d in intervals]
        levers = [integral(d, lo, hi, True) for lo, hi, d in intervals]
        total = mpmath.fsum(parts)
        m2 = cy = s1 = mpmath.mpf(0)
        before = lever_before = mpmath.mpf(0)
        for (lo, hi, depth), part, lev in zip(intervals, parts, levers, strict=True):
            mid, rad = (lo + hi) / 2, (hi - lo) / 2
            for n, w in rule:
                x = mid + rad * n
                psi = (before + integral(depth, lo, x, False)) / total - half
                phi = (lever_before + integral(depth, lo, x, True)) / total
                m2 += rad * w * psi**2
                cy += rad * w * (x - half) ** 2 / depth(x) ** 3 / total
                s1 += rad * w * phi**2
            before += part
            lever_before += lev
        return float(m2), float(cy), float(s1)


def _second_order(pieces: Any) -> tuple[float, float]:
    """(q, r₂) of a normalised profile (model.sections.RelationTerms): the p² coefficients of
    the rotation stiffness 1 + m₂ p − q p² and the lateral compliance c_y − s₁ p + r₂ p²,

        q = ∫a (g + C)²,  g(ξ) = ∫₀^ξ Ψ̃,   C = −∫a g;
        r₂ = ∫a (G + C₂)², G(ξ) = ∫₀^ξ φ,   C₂ = −∫a G

    (the first-order corrections of the two modes' slopes under p, from −(χ'/a)' + φ₀ = 0 with
    χ(0) = χ(1) = 0; a uniform plate's are 1/720 and 17/20160). float64 on the graded intervals
    of the series, each interval's cumulative integrals by the Gauss–Legendre nodes' spectral
    integration matrix (exact for polynomials of the rule's degree)."""
    with mpmath.workdps(MOMENT_DIGITS):
        gauss = mpmath.calculus.quadrature.GaussLegendre(mpmath.mp)
        rule = gauss.calc_nodes(GAUSS_DEGREE, mpmath.mp.prec)
        nodes = np.array([float(n) for n, _ in rule])
        weights = np.array([float(w) for _, w in rule])
        cells, values = [], []
        for a, b, depth in pieces:
            cuts = _graded(mpmath.mpf(sp.N(a, 40)), mpmath.mpf(sp.N(b, 40)))
            for lo, hi in itertools.pairwise(cuts):
                mid, rad = (lo + hi) / 2, (hi - lo) / 2
                cells.append((float(mid), float(rad)))
                values.append([float(1 / depth(mid + rad * n) ** 3) for n, _ in rule])
    # S[i, j] = ∫_{-1}^{x_i} ℓ_j: the Lagrange basis through Legendre polynomials
    size = len(nodes)
    basis = np.linalg.inv(np.polynomial.legendre.legvander(nodes, size - 1))  # c[k, j]
    primitive = np.zeros((size, size))
    for k in range(size):
        unit = np.zeros(size)
        unit[k] = 1.0
        anti = np.polynomial.legendre.legint(unit, lbnd=-1)
        primitive[:, k] = np.polynomial.legendre.legval(nodes, anti)
    matrix = primitive @ basis
    mids = np.array([c[0] for c in cells])[:, None]
    rads = np.array([c[1] for c in cells])[:, None]
    x = mids + rads * nodes[None, :]
    w = rads * weights[None, :]
    a = np.array(values)
    a = a / np.sum(w * a)

    def cumulative(f: np.ndarray) -> np.ndarray:
        inner = rads * (f @ matrix.T)
        before = np.concatenate([[0.0], np.cumsum(np.sum(w * f, axis=1))[:-1]])
        return before[:, None] + inner

    psi = cumulative(a) - 0.5
    g = cumulative(psi)
    q = np.sum(w * a * (g - np.sum(w * a * g)) ** 2)
    phi = cumulative(a * (0.5 - x))
    big = cumulative(phi)
    r2 = np.sum(w * a * (big - np.sum(w * a * big)) ** 2)
    return float(q), float(r2)


def moments(section: Notch) -> tuple[float, float, float, float, float]:
    """The section's (m₂, c_y, s₁) (:func:`_moments`) and (q, r₂) (:func:`_second_order`),
    cached like its coefficients."""
    key = sp.srepr((section.profile, section.length, section.pieces()))
    if key not in _MOMENTS:
        pieces = _normalised(section)
        _MOMENTS[key] = _moments(pieces) + _second_order(pieces)
    return _MOMENTS[key]


def coefficients(section: Notch) -> tuple[sp.Expr, ...]:
    """The section's series coefficients ĉ_1..ĉ_K: numbers at COEFFICIENT_DIGITS when its shape
    ratios are numbers, else expressions of its keys (model.notch_series)."""
    key = sp.srepr((section.profile, section.length, section.pieces()))
    if key not in _CACHE:
        try:
            pieces = _normalised(section)
        except ValueError:  # a ratio depends on a parameter: ĉ_k as expressions of the keys
            _CACHE[key] = notch_series.coefficient_expressions(section, SERIES_TERMS)
        else:
            _CACHE[key] = _coefficients(pieces)
    return _CACHE[key]


#: The plain beam's ∫(l−x)²dx/E'I and ∫dx/κGA by section values (Notch.shear_factor).
_SHEAR: dict[str, tuple[float, float]] = {}

#: Notch.quad's integrals by span and integrands (an mpf each), the QUADS_KEPT latest.
_QUADS: dict[str, mpmath.mpf] = {}
QUADS_KEPT = 4096

#: (m₂, c_y, s₁) by profile, span and pieces (:func:`moments`).
_MOMENTS: dict[str, tuple[float, ...]] = {}

#: The coefficients by profile, span and pieces (they cost a few seconds at 45 digits).
_CACHE: dict[str, tuple[sp.Expr, ...]] = {}


def deviation_series(section: Section, theta: Any) -> sp.Expr:
    """D(θ)/l = Σ_k (−1)^k θ^{2k}/(2k)! ĉ_k, in Horner form in θ² (θ² times a polynomial); where
    a shape ratio depends on a parameter, the same sum in closed form over the nodes of
    model.notch_series (an expression of the keys and θ)."""
    if not isinstance(section, Notch) or not section.symmetric:
        raise ValueError(f"profile {section.profile!r}: the pure-moment series needs a notch")
    c = coefficients(section)
    if not all(ck.is_Number for ck in c):  # ratios of parameters: the lighter closed form
        return notch_series.deviation_expression(section, theta, SERIES_TERMS)
    square = theta**2
    terms = [
        sp.Float((-1) ** k * c[k - 1] / sp.factorial(2 * k), COEFFICIENT_DIGITS)
        for k in range(1, SERIES_TERMS + 1)
    ]
    acc: sp.Expr = terms[-1]
    for term in reversed(terms[:-1]):
        acc = term + square * acc
    return square * acc
