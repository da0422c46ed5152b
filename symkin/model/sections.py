"""A hinge's section: what every level and report needs from a plate's material and shape
(docs/physics.md, "Units and stiffness"; docs/architecture.md, "A new profile").

A plate runs from P's clamp (x = 0) to M's clamp (x = l) along its straight, as-fabricated centre
line. Its profile gives the thickness T(x) (file unit) over the width b; the material gives E, ν.
From these one object answers, in the file's length unit u with s metres per u (the physics runs
in the file's unit: EI_u = EI/s², docs/physics.md):

- the stiffness along the axis, EI(x) = E'·b·T(x)³·s²/12, EA(x) = E'·b·T(x)·s² and the shear
  stiffness κGA(x) = κ·G·b·T(x)·s² (Timoshenko's κ = 5/6 of a rectangle, G = E/(2(1 + ν)),
  E' = E/(1 − ν²) for a plate at least WIDE thicknesses wide, which bends in plane strain);
- the compliance integrals of the plate clamped at P and loaded at M's end (:class:`Compliance`):
  rotation and deflection under an end moment and an end force, stretch and shear;
- the kinematic shape under a pure moment: the curvature is κ(x) = θ·φ(x)/l with φ ∝ 1/EI(x)
  normalised to ∫φ dx/l = 1, and M's clamp sits at f = ∫cos Φ dx, g = ∫sin Φ dx, Φ(x) the angle
  turned up to x (the circular arc of model.hinges for a uniform plate);
- the largest normal stress of the straight plate under end loads (N, V, M), |N|/A + |M(x)| c/I;
- the outline the finite-element mesher cuts, T(x) and its polygon.

A profile is a subclass of :class:`Section` that gives its `pieces`: T(x) on each interval where
it is smooth; model.profiles holds them by name (one row per profile), a hinge names its profile
(`Hinge.profile`, "uniform" by default) and model.profiles.section_of builds its section.
Everything a subclass does not override follows from T(x): sympy integrals where the derivation
needs symbols, mpmath quadrature where the solvers need numbers. :class:`UniformPlate` overrides
them with the closed forms the code has always used, so its numbers are those of before, to the
bit.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable, Mapping
from dataclasses import dataclass, fields, replace
from functools import cached_property
from typing import Any, ClassVar

import mpmath
import sympy as sp

from . import special as _special

#: A plate at least this many thicknesses wide bends in plane strain: E' = E/(1 − ν²).
WIDE = 5
#: Timoshenko's shear coefficient of a rectangular section.
SHEAR_COEFFICIENT = sp.Rational(5, 6)
#: Working precision (decimal digits) of the numbers the solvers take: sympy's evaluation and the
#: quadratures, before the result is rounded to float64.
DIGITS = 20
#: Samples per smooth piece where the largest stress of a profile without a closed form is sought
#: (both ends of every piece exact; an interior maximum refined by a parabola).
STRESS_SAMPLES = 64

#: The position along the plate, from P's clamp (file unit).
X = sp.Symbol("x", real=True)


def number(expr: Any, values: Mapping[sp.Symbol, sp.Expr]) -> float:
    """A sympy expression at parameter `values`, evaluated at DIGITS digits, as a float. One with
    integrals in it (a notch's shear factor while its parameters are symbols) is kept by its
    text (_INTEGRALS): sympy evaluates each by its own quadrature, tens of seconds, and alike
    hinges ask for the same."""
    at = sp.sympify(expr).xreplace(values)
    if not (isinstance(at, sp.Basic) and at.has(sp.Integral)):  # values may map to Python numbers
        return float(sp.N(at, DIGITS))
    key = sp.srepr(at)
    if key not in _INTEGRALS:
        if len(_INTEGRALS) >= INTEGRALS_KEPT:
            del _INTEGRALS[next(iter(_INTEGRALS))]  # the oldest
        _INTEGRALS[key] = float(sp.N(at, DIGITS))
    return _INTEGRALS[key]


#: number()'s values of expressions with integrals, by their text: the INTEGRALS_KEPT latest.
_INTEGRALS: dict[str, float] = {}
INTEGRALS_KEPT = 1024


@dataclass(frozen=True)
class Compliance:
    """End compliances of a plate clamped at P (x = 0) and loaded at M's end (x = l) by an end
    force (N along the plate, V across it) and an end moment M, small deflections (file unit and
    the unit's stiffness, like EI):

        theta_M = ∫ dx/EI,  theta_F = y_M = ∫ (l − x) dx/EI,  y_F = ∫ (l − x)² dx/EI,
        x_N = ∫ dx/EA,  y_V = ∫ dx/κGA.

    M's end turns by theta_M M + theta_F V and moves across by y_M M + y_F V + y_V V and along by
    x_N N. sympy expressions or floats, as the section's method that made them."""

    theta_M: Any
    theta_F: Any
    y_F: Any
    x_N: Any
    y_V: Any

    @property
    def y_M(self) -> Any:
        """The deflection per end moment, theta_F (Maxwell–Betti)."""
        return self.theta_F

    def guided(self) -> Any:
        """Bending deflection per end force with M's end kept parallel to P's (clamped–guided,
        the end moment −theta_F V/theta_M holding its rotation at zero): y_F − theta_F²/theta_M."""
        return self.y_F - self.theta_F**2 / self.theta_M


@dataclass(frozen=True)
class RelationTerms:
    """How a plate's mixed potential at `loaded` departs from the uniform plate's
    (physics.plate_relation.notch_relation; docs/physics.md, "Notch hinges at `loaded`"), in
    units of the span l and EI₀ = l/∫dx/EI (the uniform plate of the same rotation compliance),
    ξ = x/l, a(ξ) = EI₀/EI normalised to ∫a dξ = 1 and Ψ̃(ξ) = ∫₀^ξ a − 1/2:

    - `alpha` = 12 m₂, m₂ = ∫Ψ̃² dξ: the bending angle's chord shortening per θ² (1/12 for a
      uniform plate), so the rotation stiffness's first change with the axial load index p is
      exact (U's θ²/(2T(α p)));
    - `lam` = √(12 c_y), c_y = ∫(ξ − 1/2)² a dξ: the deflection across per lateral load index
      with the end rotation held (1/12 uniform), U's lateral terms taking f·lam;
    - `beta` = 10 s₁/c_y, s₁ = ∫φ² dξ, φ(ξ) = ∫₀^ξ a(η)(1/2 − η) dη: the lateral shape's chord
      shortening per f² (1/120 uniform), so the lateral compliance's first change with p is exact
      (U's S(β p)) and its pole, p = −π²/β, is Rayleigh's sway buckling load of the profile;
    - `series`: the pure-moment chord's terms (−1)^k ĉ_k/(2k)!, k = 1..K (model.notches: its
      deviation from the centre pin's path is D(θ)/l = Σ_k (−1)^k θ^{2k} ĉ_k/(2k)!);
    - `rotation`, `lateral`: the weights of the kernels' terms beyond their first order in p
      (T's and S's), so that the rotation stiffness 1 + m₂ p − q p² and the lateral compliance
      c_y − s₁ p + r₂ p² are the profile's to second order (model.notches._second_order): 0 for
      a pin with rigid arms, whose stiffness is linear in p.

    All are 1 for a uniform plate, whose section gives no terms (its relation is the uniform
    one, exact in p)."""

    alpha: float
    beta: float
    lam: float
    series: tuple[sp.Float, ...]
    rotation: float = 1.0
    lateral: float = 1.0

    def deviation(self, theta: Any) -> sp.Expr:
        """D(θ)/l: the pure-moment chord beyond the centre pin's path, in Horner form in θ²."""
        square = theta**2
        acc: sp.Expr = self.series[-1]
        for term in reversed(self.series[:-1]):
            acc = term + square * acc
        return square * acc


@dataclass(frozen=True)
class Section(ABC):
    """One hinge's plate: its profile T(x) over the width and its material. Fields are sympy
    expressions in the file's parameters (length, thickness, width in the file unit, E in Pa);
    `scale` is the unit's size in metres. `thickness` is the profile's nominal thickness: the one
    that decides plane strain (b ≥ WIDE·thickness) and that reports name."""

    hinge: str
    length: sp.Expr
    thickness: sp.Expr
    width: sp.Expr
    E: sp.Expr
    nu: sp.Expr
    scale: sp.Expr

    #: The profile's name in the registry (model.profiles.PROFILES).
    profile: ClassVar[str] = ""
    #: Whether T(x) is the same everywhere: the levels whose plates are uniform beams take only
    #: these (physics.stiffness.plate_stiffness).
    uniform: ClassVar[bool] = False

    @classmethod
    def from_hinge(cls, hinge: Any, scale: Any) -> Section:
        """The section of a mechanism.Hinge whose profile this is (`scale`: metres per file
        unit). A profile with parameters of its own reads them from `hinge.profile_params`."""
        return cls(
            hinge.name,
            sp.sympify(hinge.length),
            sp.sympify(hinge.thickness),
            sp.sympify(hinge.width),
            sp.sympify(hinge.E),
            sp.sympify(hinge.nu),
            sp.sympify(scale),
        )

    # -- the profile -----------------------------------------------------------------------------

    @abstractmethod
    def pieces(self) -> tuple[tuple[sp.Expr, sp.Expr, sp.Expr], ...]:
        """The profile: (start, end, T) per piece from P's clamp (0) to M's (l), T the thickness
        on it as a smooth expression in :data:`X` (file unit)."""

    def breaks(self) -> tuple[sp.Expr, ...]:
        """Where T(x) is not smooth: the ends of the pieces inside (0, l)."""
        return tuple(end for _, end, _ in self.pieces()[:-1])

    def depth(self, x: Any) -> sp.Expr:
        """T(x), the thickness at x (file unit): the first piece whose end is beyond x."""
        parts = self.pieces()
        if len(parts) == 1:
            return parts[0][2].xreplace({X: x})
        return sp.Piecewise(
            *((t.xreplace({X: x}), x < end) for _, end, t in parts[:-1]),
            (parts[-1][2].xreplace({X: x}), True),
        )

    def at(self, values: Mapping[sp.Symbol, sp.Expr]) -> Section:
        """The same section with the file's parameters replaced by `values`."""
        return replace(
            self,
            **{
                f.name: sp.sympify(getattr(self, f.name)).xreplace(values)
                for f in fields(self)
                if f.name != "hinge"
            },
        )

    # -- stiffness along the axis ----------------------------------------------------------------

    def modulus(self) -> sp.Expr:
        """E' = E/(1 − ν²) when width ≥ WIDE·thickness (plane strain), else E."""
        return sp.Piecewise(
            (self.E / (1 - self.nu**2), self.width >= WIDE * self.thickness), (self.E, True)
        )

    def _area(self, t: Any) -> sp.Expr:
        """b·T·s²: the area in m² of a section of thickness T, times the unit's 1/s²."""
        return self.width * t * self.scale**2

    def _EI(self, t: Any) -> sp.Expr:
        return self.modulus() * self._area(t) * t**2 / 12

    def _EA(self, t: Any) -> sp.Expr:
        return self.modulus() * self._area(t)

    def _kGA(self, t: Any) -> sp.Expr:
        return SHEAR_COEFFICIENT * self.E / (2 * (1 + self.nu)) * self._area(t)

    def EI(self, x: Any) -> sp.Expr:
        """Bending stiffness at x, N·u²."""
        return self._EI(self.depth(x))

    def EA(self, x: Any) -> sp.Expr:
        """Axial stiffness at x, N."""
        return self._EA(self.depth(x))

    def kGA(self, x: Any) -> sp.Expr:
        """Shear stiffness at x, N."""
        return self._kGA(self.depth(x))

    def slender_squared(self) -> sp.Expr:
        """(t/l)² = 12 EI/(EA l²) at the nominal thickness: the reported strain's fibre
        distance, |ψ'| t/(2l) + |f_N| (t/l)²/12 (physics.reported.plate_stress)."""
        return 12 * self._EI(self.thickness) / (self._EA(self.thickness) * self.length**2)

    # -- compliance integrals --------------------------------------------------------------------

    def _integrands(self) -> tuple[Callable[[Any, Any], Any], ...]:
        """The compliances' integrands as functions of (x, T(x)), Compliance's order."""
        l = self.length
        return (
            lambda x, t: 1 / self._EI(t),
            lambda x, t: (l - x) / self._EI(t),
            lambda x, t: (l - x) ** 2 / self._EI(t),
            lambda x, t: 1 / self._EA(t),
            lambda x, t: 1 / self._kGA(t),
        )

    def integral(self, integrand: Callable[[Any, Any], Any]) -> sp.Expr:
        """∫₀ˡ integrand(x, T(x)) dx in sympy, piece by piece."""
        return sp.Add(*(sp.integrate(integrand(X, t), (X, a, b)) for a, b, t in self.pieces()))

    def quad(
        self, integrand: Callable[[Any, Any], Any], values: Mapping[sp.Symbol, sp.Expr]
    ) -> mpmath.mpf:
        """∫₀ˡ integrand(x, T(x)) dx at parameter `values` by mpmath's quadrature, piece by
        piece, at DIGITS digits."""
        total = mpmath.mpf(0)
        with mpmath.workdps(DIGITS + 5):
            for a, b, t in self.at(values).pieces():
                f = sp.lambdify(X, integrand(X, t).xreplace(values), "mpmath")
                total += mpmath.quad(f, [mpmath.mpf(sp.N(e, DIGITS + 5)) for e in (a, b)])
        return total

    def compliance(self) -> Compliance:
        """The compliance integrals as sympy expressions (sympy's integrals, piece by piece)."""
        return Compliance(*(self.integral(f) for f in self._integrands()))

    def compliance_numbers(self, values: Mapping[sp.Symbol, sp.Expr]) -> Compliance:
        """The compliance integrals at parameter `values`, as floats (quadrature)."""
        return Compliance(*(float(self.quad(f, values)) for f in self._integrands()))

    def relation_terms(self, values: Mapping[sp.Symbol, sp.Expr]) -> RelationTerms | None:
        """What `loaded`'s plate relation needs beyond EI, l, ε_a and ε_s at parameter `values`
        (:class:`RelationTerms`); None: the uniform plate's relation (exact in p) serves."""
        if self.uniform:
            return None
        raise ValueError(
            f"profile {self.profile!r}: --level loaded needs its relation terms "
            "(docs/architecture.md, 'A new profile')"
        )

    # -- the kinematic shape under a pure moment -------------------------------------------------

    def shape(self, theta: Any) -> tuple[sp.Expr, sp.Expr]:
        """(f, g): M's clamp in P's plate frame when a pure moment turns M by `theta`. The
        curvature is theta·φ(x)/l, φ ∝ 1/EI(x) with ∫φ dx/l = 1. Closed in sympy where T is
        constant on every piece (arcs joined end to end); a profile whose T varies within a
        piece overrides it (a series in θ, say)."""
        total = self.integral(lambda x, t: 1 / self._EI(t))
        turned = f = g = sp.S.Zero
        for a, b, t in self.pieces():
            if t.has(X):
                raise ValueError(
                    f"profile {self.profile!r}: T varies within ({a}, {b}): give shape() a form"
                )
            rate = theta / (self._EI(t) * total)  # dΦ/dx on this piece
            end = turned + rate * (b - a)
            f += (sp.sin(end) - sp.sin(turned)) / rate
            g += (sp.cos(turned) - sp.cos(end)) / rate
            turned = end
        return f, g

    def shape_numbers(
        self, theta: float, values: Mapping[sp.Symbol, sp.Expr]
    ) -> tuple[float, float]:
        """(f, g) at parameter `values` by quadrature: Φ(x) = θ ∫₀ˣ dx/EI / ∫₀ˡ dx/EI."""
        with mpmath.workdps(DIGITS + 5):
            parts = [
                (
                    mpmath.mpf(sp.N(a, DIGITS + 5)),
                    mpmath.mpf(sp.N(b, DIGITS + 5)),
                    sp.lambdify(X, (1 / self._EI(t)).xreplace(values), "mpmath"),
                )
                for a, b, t in self.at(values).pieces()
            ]
            weights = [mpmath.quad(inv, [a, b]) for a, b, inv in parts]
            total = sum(weights)
            f = g = mpmath.mpf(0)
            before = mpmath.mpf(0)
            for (a, b, inv), w in zip(parts, weights, strict=True):

                def turned(x: Any, a: Any = a, inv: Any = inv, before: Any = before) -> Any:
                    return theta * (before + mpmath.quad(inv, [a, x])) / total

                f += mpmath.quad(lambda x, turned=turned: mpmath.cos(turned(x)), [a, b])
                g += mpmath.quad(lambda x, turned=turned: mpmath.sin(turned(x)), [a, b])
                before += w
            return float(f), float(g)

    # -- stress ----------------------------------------------------------------------------------

    def largest_stress(
        self,
        loads: tuple[float, float, float],
        values: Mapping[sp.Symbol, sp.Expr],
    ) -> tuple[float, float]:
        """The largest normal stress (Pa) along the straight plate under the end loads (N, V,
        M) = (force along the plate, across it (N), moment (N·m)) that M's end carries, small
        deflections, and where (x/l): |N|/A + |m(x)| c/I with A = b T s², c = T s/2,
        I = b T³ s⁴/12 and m(x) = M + V (l − x) s. Both ends of every piece (its own T there),
        STRESS_SAMPLES points in between, an interior maximum refined by a parabola."""
        normal, across, moment = loads
        at = self.at(values)
        l, b, s = (number(v, {}) for v in (at.length, at.width, at.scale))
        best, where = -1.0, 0.0
        for lo, hi, t in at.pieces():
            depth = sp.lambdify(X, t, "math")
            a, c = number(lo, {}), number(hi, {})
            xs = [a + (c - a) * k / STRESS_SAMPLES for k in range(STRESS_SAMPLES + 1)]
            vals = []
            for x in xs:
                h = float(depth(x))
                arm = moment + across * (l - x) * s
                vals.append(abs(normal) / (b * h * s**2) + abs(arm) * 6 / (b * h**2 * s**3))
            j = max(range(len(vals)), key=vals.__getitem__)
            value, pos = vals[j], xs[j]
            if 0 < j < len(vals) - 1:
                lo3, mid, hi3 = vals[j - 1], vals[j], vals[j + 1]
                bend = lo3 - 2 * mid + hi3
                if bend < 0:
                    shift = (lo3 - hi3) / (2 * bend)
                    value = mid - (lo3 - hi3) * shift / 4
                    pos = xs[j] + shift * (c - a) / STRESS_SAMPLES
            if value > best:
                best, where = value, pos / l
        return best, where

    # -- the outline -----------------------------------------------------------------------------

    def thickness_function(self, values: Mapping[sp.Symbol, sp.Expr]) -> Callable[[float], float]:
        """T(x) at parameter `values` as a float function of x (file unit), for the mesher."""
        depth: Callable[[float], float] = sp.lambdify(X, self.at(values).depth(X), "math")
        return depth

    def outline(
        self, values: Mapping[sp.Symbol, sp.Expr], samples: int = 16
    ) -> list[tuple[float, float]]:
        """The plate's outline in P's plate frame (file unit), counter-clockwise from P's clamp
        at the lower face: y = −T(x)/2 from x = 0 to l, then the upper face back; `samples`
        points per piece, a step in T drawn at its break."""
        lower: list[tuple[float, float]] = []
        for lo, hi, t in self.at(values).pieces():
            depth = sp.lambdify(X, t, "math")
            a, c = number(lo, {}), number(hi, {})
            for k in range(samples + 1):
                x = a + (c - a) * k / samples
                lower.append((x, -float(depth(x)) / 2))
        return lower + [(x, -y) for x, y in reversed(lower)]


@dataclass(frozen=True)
class UniformPlate(Section):
    """A plate of one thickness t: EI = E'·b·t³/12 (times s²), the closed-form compliances
    l/EI, l²/(2EI), l³/(3EI), l/EA, l/κGA, the circular arc under a pure moment (model.hinges)
    and the largest stress at one of the clamps."""

    profile: ClassVar[str] = "uniform"
    uniform: ClassVar[bool] = True

    def pieces(self) -> tuple[tuple[sp.Expr, sp.Expr, sp.Expr], ...]:
        return ((sp.S.Zero, self.length, self.thickness),)

    def EI(self, x: Any = None) -> sp.Expr:
        """E'·b·t³·s²/12 everywhere."""
        return self._EI(self.thickness)

    def EA(self, x: Any = None) -> sp.Expr:
        """E'·b·t·s² everywhere."""
        return self._EA(self.thickness)

    def kGA(self, x: Any = None) -> sp.Expr:
        """κ·G·b·t·s² everywhere."""
        return self._kGA(self.thickness)

    def compliance(self) -> Compliance:
        l, ei = self.length, self.EI()
        return Compliance(l / ei, l**2 / (2 * ei), l**3 / (3 * ei), l / self.EA(), l / self.kGA())

    def guided(self) -> sp.Expr:
        """l³/(12 EI), the clamped–guided deflection per end force."""
        return self.length**3 / (12 * self.EI())

    def compliance_numbers(self, values: Mapping[sp.Symbol, sp.Expr]) -> Compliance:
        c = self.compliance()
        return Compliance(
            *(number(getattr(c, k), values) for k in ("theta_M", "theta_F", "y_F", "x_N", "y_V"))
        )

    def shape(self, theta: Any) -> tuple[sp.Expr, sp.Expr]:
        """The circular arc, written as model.hinges writes it: f = l sin θ/θ, g = l (1 − cos θ)/θ
        through the kernels sinr(0), cosr(1) (exact at θ = 0)."""
        return self.length * _special.sinr(0)(theta), -self.length * theta * _special.cosr(1)(theta)

    def largest_stress(
        self,
        loads: tuple[float, float, float],
        values: Mapping[sp.Symbol, sp.Expr],
    ) -> tuple[float, float]:
        """|N|/A + max(|M|, |M + V l s|) c/I: the moment is linear along the plate, largest at a
        clamp (P's where both are equal)."""
        normal, across, moment = loads
        l, t, b, s = (
            number(v, values) for v in (self.length, self.thickness, self.width, self.scale)
        )
        at_p, at_m = abs(moment + across * l * s), abs(moment)
        arm, where = (at_p, 0.0) if at_p >= at_m else (at_m, 1.0)
        return abs(normal) / (b * t * s**2) + arm * 6 / (b * t**2 * s**3), where


@dataclass(frozen=True)
class SectionNumbers:
    """A section at parameter values, as the solvers and estimates take it: floats, each the
    sympy expression at DIGITS digits (so that a number is the same wherever it is read), with
    the displacements of M's end under end loads (file unit). `length`, `t` (the nominal
    thickness), `b`, `nu`; EI, EA, κGA at P's clamp (a uniform plate's everywhere)."""

    section: Section
    values: Mapping[sp.Symbol, sp.Expr]
    length: float
    t: float
    b: float
    nu: float
    EI: float
    EA: float
    kGA: float

    @classmethod
    def of(cls, section: Section, values: Mapping[sp.Symbol, sp.Expr]) -> SectionNumbers:
        kind = UniformNumbers if section.uniform else cls
        return kind(
            section,
            values,
            *(
                number(v, values)
                for v in (
                    section.length,
                    section.thickness,
                    section.width,
                    section.nu,
                    section.EI(sp.S.Zero),
                    section.EA(sp.S.Zero),
                    section.kGA(sp.S.Zero),
                )
            ),
        )

    @cached_property
    def compliance(self) -> Compliance:
        """The compliance integrals at the values (quadrature, once)."""
        return self.section.compliance_numbers(self.values)

    def stretch(self, normal: float) -> float:
        """M's end along the plate under the normal force (N): N ∫dx/EA."""
        return float(normal * self.compliance.x_N)

    def shear(self, across: float) -> float:
        """M's end across the plate from the shear strain under a force V (N): V ∫dx/κGA."""
        return float(across * self.compliance.y_V)

    def guided(self, across: float) -> float:
        """M's end across the plate from bending, M's end kept parallel: V (y_F − θ_F²/θ_M)."""
        return float(across * self.compliance.guided())

    def centre_line(self, coefficient: float, theta: float, moment: float) -> float:
        """−c ∫ T² κ² dx: the centre line's change of length when a bending moment linear along
        the plate turns M by `theta` and is `moment` (N·u) at M's end, κ = m(x)/EI(x); the moment
        at P's end follows from θ = ∫κ dx."""
        sec, values = self.section, self.values
        l = sec.length
        weight = (lambda x: 1 - x / l, lambda x: x / l)  # m(x) = m_P w0 + m_M w1

        def q(i: int, j: int) -> float:
            return float(
                sec.quad(lambda x, t: t**2 * weight[i](x) * weight[j](x) / sec._EI(t) ** 2, values)
            )

        a0 = float(sec.quad(lambda x, t: weight[0](x) / sec._EI(t), values))
        a1 = float(sec.quad(lambda x, t: weight[1](x) / sec._EI(t), values))
        m_p = (theta - moment * a1) / a0
        squares = m_p**2 * q(0, 0) + 2 * m_p * moment * q(0, 1) + moment**2 * q(1, 1)
        return -coefficient * squares


@dataclass(frozen=True)
class UniformNumbers(SectionNumbers):
    """The uniform plate's numbers: the closed forms, in the order of operations the level code
    has always used (the model error's numbers stay the same to the bit)."""

    def stretch(self, normal: float) -> float:
        return normal * self.length / self.EA

    def shear(self, across: float) -> float:
        return across * self.length / self.kGA

    def guided(self, across: float) -> float:
        return across * self.length**3 / (12 * self.EI)

    def centre_line(self, coefficient: float, theta: float, moment: float) -> float:
        # curvature at the two clamps: M's from its end moment, P's from θ = l (κ_P + κ_M)/2
        kappa_m = moment / self.EI
        kappa_p = 2 * theta / self.length - kappa_m
        squares = self.length * (kappa_p**2 + kappa_p * kappa_m + kappa_m**2) / 3  # ∫ κ² dx
        return -coefficient * self.t**2 * squares
