"""A hinge whose section varies along it (a notch, model.notches) as a geometrically exact plane
beam shot from its clamped P end (docs/physics.md, "Notch hinges at equilibrium").

The equations are physics.beams' with the stiffness a function of the position s = x/l (0..1):
in units of a reference EI₀ (the uniform plate of the same rotation compliance, l/∫dx/EI), with
μ = m l/EI₀ the bending moment, λ = n l²/EI₀ the force link M exerts at the M end,
a(s) = EI₀/EI(s), ε(s) = EI₀/(EA(s) l²), γ(s) = EI₀/(κGA(s) l²) and d = ε − γ:

    ψ' = a μ,   μ' = −f_Q (1 + d f_N),
    r' = (cos ψ, sin ψ) + γ λ + d f_N (cos ψ, sin ψ),
    e' = a μ² + ε f_N² + γ f_Q²           (the energy over EI₀/(2l)),

f_N = λx cos ψ + λy sin ψ, f_Q = λy cos ψ − λx sin ψ; ε = γ = 0 for the elastica. With a = 1
they are physics.beams' equations (ψ' = μ there). The shot is classical fourth-order Runge–Kutta
on STEPS steps graded by the stiffness: the nodes divide (s + GRADE Ψ(s))/(1 + GRADE) equally,
Ψ(s) = ∫₀ˢ a / ∫₀¹ a, so the neck, where a notch bends, gets most of them. The same code runs on
float64, complex128 (the complex step) and mpmath arrays; on mpmath arrays it is the same
discretisation at more digits, so a notch's equilibrium is as accurate as the grid, not as the
working precision: measured 2e-11 relative on a circular notch with t/R = 0.02 to 0.5 against
an independent scipy shot at rtol 1e-13 (tests/test_notch_beams.py).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass
from functools import cached_property

import mpmath
import numpy as np
import sympy as sp

from ..model.sections import Section, X
from . import arith

#: Runge–Kutta steps of a notch's shot, and how strongly the grid gathers at the neck.
STEPS = 400
GRADE = 1
#: The shot's error in M's clamp, relative to the span: a bound on the 3e-11 to 2e-10 measured
#: against scipy's DOP853 at t/R = 0.02 to 0.5 (tests/test_notch_beams.py); `equilibrium` adds
#: it to its error estimate, since more working digits do not reduce it.
SHOT_ERROR = 1e-9
#: Digits of the grid's samples and of EI₀.
GRID_DIGITS = 30
#: Samples of a(s) from which the neck's width is measured.
GRID_SAMPLES = 4001


@dataclass(frozen=True)
class _Grading:
    """The shot's variable v (0..1, equal steps) and the position s(v): v = G(s) with
    G = (A + GRADE B)/(1 + GRADE), A(s) = arccos(1 − 2s)/π gathering the steps at the clamps
    (where a profile's T(x) has a square-root branch point: in v it is smooth) and
    B(s) = 1/2 + atan((s − 1/2)/w)/(2 atan(1/(2w))) at the neck, w its half-width."""

    width: mpmath.mpf

    def grade(self, s):
        w = self.width
        a = mpmath.acos(1 - 2 * s) / mpmath.pi
        b = mpmath.mpf(1) / 2 + mpmath.atan((s - mpmath.mpf(1) / 2) / w) / (
            2 * mpmath.atan(1 / (2 * w))
        )
        return (a + GRADE * b) / (1 + GRADE)

    def slope(self, s):
        """G'(s)."""
        w = self.width
        a = 1 / (mpmath.pi * mpmath.sqrt(s * (1 - s)))
        b = 1 / (w * (1 + ((s - mpmath.mpf(1) / 2) / w) ** 2) * 2 * mpmath.atan(1 / (2 * w)))
        return (a + GRADE * b) / (1 + GRADE)

    def position(self, v):
        """s(v) by bisection then Newton (G is increasing), at the working precision."""
        if v <= 0 or v >= 1:
            return mpmath.mpf(0) if v <= 0 else mpmath.mpf(1)
        lo, hi = 0.0, 1.0  # bisection in float64, then Newton at the working precision
        w, target = float(self.width), float(v)
        norm = 2 * math.atan(1 / (2 * w))
        for _ in range(48):
            mid = (lo + hi) / 2
            g = (
                math.acos(1 - 2 * mid) / math.pi + GRADE * (0.5 + math.atan((mid - 0.5) / w) / norm)
            ) / (1 + GRADE)
            lo, hi = (mid, hi) if g < target else (lo, mid)
        s = mpmath.mpf((lo + hi) / 2)
        for _ in range(4):
            s -= (self.grade(s) - v) / self.slope(s)
        return s

    def rate(self, s):
        """ds/dv = 1/G'(s) (0 at the clamps)."""
        if s <= 0 or s >= 1:
            return mpmath.mpf(0)
        return 1 / self.slope(s)


@dataclass(frozen=True)
class SectionGrid:
    """A section at parameter values, sampled for the shot: the nodes s_j and, at the nodes and
    the midpoints of the steps, a, ε, γ (mpmath numbers, 30 digits); `EI0` the reference."""

    hinge: str
    nodes: tuple
    samples: Mapping[str, tuple]  # "a", "eps", "gam", "depth", "axial", "ds" at 2N + 1 points
    EI0: mpmath.mpf  # the reference: any value serves, the shot and the loads both use it
    length: float
    stretches: bool

    @classmethod
    def of(
        cls, section: Section, values: Mapping[sp.Symbol, sp.Expr], stretches: bool
    ) -> SectionGrid:
        at = section.at(values)
        with mpmath.workdps(GRID_DIGITS):
            l = mpmath.mpf(sp.N(at.length, GRID_DIGITS + 5))
            c = section.compliance_numbers(values)
            ei0 = l / mpmath.mpf(c.theta_M)
            fn = {
                key: sp.lambdify(X, expr, "mpmath")
                for key, expr in (
                    ("EI", at.EI(X)),
                    ("EA", at.EA(X)),
                    ("kGA", at.kGA(X)),
                    ("depth", at.depth(X)),
                )
            }
            # the half-width of the neck (where a ≥ max a/2), from samples
            xs = np.linspace(0.0, 1.0, GRID_SAMPLES)
            a = np.array([float(ei0 / fn["EI"](l * mpmath.mpf(v))) for v in xs])
            width = max(float(np.count_nonzero(a >= a.max() / 2)) / (2 * GRID_SAMPLES), 1e-3)
            grading = _Grading(mpmath.mpf(width))
            vs = [mpmath.mpf(k) / (2 * STEPS) for k in range(2 * STEPS + 1)]
            points = [grading.position(v) for v in vs]
            rates = [grading.rate(s) for s in points]
            nodes = points[::2]
            samples: dict[str, list] = {
                "a": [],
                "eps": [],
                "gam": [],
                "depth": [],
                "axial": [],
                "ds": rates,
            }
            for s in points:
                x = l * s
                samples["a"].append(ei0 / fn["EI"](x))
                samples["eps"].append(ei0 / (fn["EA"](x) * l**2) if stretches else mpmath.mpf(0))
                samples["gam"].append(ei0 / (fn["kGA"](x) * l**2) if stretches else mpmath.mpf(0))
                samples["depth"].append(fn["depth"](x))
                samples["axial"].append(ei0 / (fn["EA"](x) * l**2))
        return cls(
            section.hinge,
            tuple(nodes),
            {k: tuple(v) for k, v in samples.items()},
            ei0,
            float(l),
            stretches,
        )

    @cached_property
    def floats(self) -> dict[str, np.ndarray]:
        out = {k: np.array([float(v) for v in vals]) for k, vals in self.samples.items()}
        out["nodes"] = np.array([float(v) for v in self.nodes])
        return out


@dataclass(frozen=True)
class ProfileEnd:
    """M's end of a notch in P's plate frame, in units of l (as physics.beams.PlateEnd): x, y,
    psi, omega = μ(1) = M_M l/EI₀, energy (over EI₀/(2l)) and the largest strain along the
    hinge at the nodes, |ψ'| T/(2l) + |N|/EA (`bend`, float: the largest over the array) with
    where it is (s)."""

    x: object
    y: object
    psi: object
    omega: object
    energy: object
    bend: float
    where: float


def shoot_profile(
    k0, lx, ly, grid: SectionGrid, energy: bool = False, strain: bool = False
) -> ProfileEnd:
    """Shoot one notch: k0 = μ(0) = m_P l/EI₀ and λ = n l²/EI₀ (arrays of one kind); with
    `strain`, the largest strain along it too (0 otherwise)."""
    exact = arith.is_mp(np.asarray(k0))
    get = grid.samples if exact else grid.floats
    a, depth, axial, length = get["a"], get["depth"], get["axial"], grid.length
    found = [0.0, 0.0]

    def node(psi, mu, k, s) -> None:
        psi, mu = np.real(np.asarray(psi)), np.real(np.asarray(mu))
        lxf, lyf = np.real(np.asarray(lx)), np.real(np.asarray(ly))
        if exact:
            psi, mu, lxf, lyf = (
                np.array([float(v) for v in np.ravel(w)]) for w in (psi, mu, lxf, lyf)
            )
        fn = lxf * np.cos(psi) + lyf * np.sin(psi)
        bending = np.abs(mu) * float(a[k]) * float(depth[k]) / (2 * length)
        value = float(np.max(bending + np.abs(fn) * float(axial[k])))
        if value > found[0]:
            found[:] = [value, s]

    out = _integrate(k0, lx, ly, get, exact, energy, node if strain else None, grid.nodes)
    return dataclasses.replace(out, bend=found[0], where=found[1])


def shoot_profiles(k0, lx, ly, grids: list[SectionGrid], energy: bool = False) -> ProfileEnd:
    """Shoot several notches at once: k0, λx, λy arrays whose first axis runs over `grids`
    (their grids have the same number of steps)."""
    exact = arith.is_mp(np.asarray(k0))
    shape = (len(grids),) + (1,) * (np.ndim(k0) - 1)
    get = {}
    for key in ("a", "eps", "gam", "ds"):
        rows = [g.samples[key] if exact else g.floats[key] for g in grids]
        table = np.array(rows, dtype=object if exact else float)
        get[key] = [table[:, k].reshape(shape) for k in range(table.shape[1])]
    return _integrate(k0, lx, ly, get, exact, energy, None, grids[0].nodes)


def _integrate(k0, lx, ly, get, exact: bool, energy: bool, node, nodes) -> ProfileEnd:
    """Fourth-order Runge–Kutta in the grid's variable v: the rates times ds/dv. Every product
    takes the array first: an mpf scalar first tries, and fails, to convert the object array
    (mpmath formats the array for its error: a fifth of an `equilibrium` solve measured), while
    the array's product calls the same mpf multiplication element by element."""
    a, eps, gam, ds = get["a"], get["eps"], get["gam"], get["ds"]
    zero = k0 * 0
    steps = (len(ds) - 1) // 2
    h = mpmath.mpf(1) / steps if exact else 1.0 / steps  # the step in v

    def rates(psi, mu, k):
        c, s = arith.cos(psi), arith.sin(psi)
        fn = lx * c + ly * s
        fq = ly * c - lx * s
        d = eps[k] - gam[k]
        along = 1 + fn * d
        out = [mu * a[k], -fq * along, c * along + lx * gam[k], s * along + ly * gam[k]]
        if energy:
            out.append(mu * a[k] * mu + fn * eps[k] * fn + fq * gam[k] * fq)
        return [r * ds[k] for r in out]

    state = [zero, k0 + zero, zero, zero] + ([zero] if energy else [])
    if node is not None:
        node(state[0], state[1], 0, 0.0)
    for j in range(steps):
        k = 2 * j
        r1 = rates(state[0], state[1], k)
        s2 = [v + r * (h / 2) for v, r in zip(state, r1, strict=True)]
        r2 = rates(s2[0], s2[1], k + 1)
        s3 = [v + r * (h / 2) for v, r in zip(state, r2, strict=True)]
        r3 = rates(s3[0], s3[1], k + 1)
        s4 = [v + r * h for v, r in zip(state, r3, strict=True)]
        r4 = rates(s4[0], s4[1], k + 2)
        state = [
            v + (p + 2 * q + 2 * r + w) * (h / 6)
            for v, p, q, r, w in zip(state, r1, r2, r3, r4, strict=True)
        ]
        if node is not None:
            node(state[0], state[1], k + 2, float(nodes[j + 1]))
    return ProfileEnd(
        state[2], state[3], state[0], state[1], state[4] if energy else None, 0.0, 0.0
    )


#: Grids by section, parameter values and beam (a solve builds its system two or three times).
_GRIDS: dict[tuple, SectionGrid] = {}


def grid_of(section: Section, values: Mapping[sp.Symbol, sp.Expr], stretches: bool) -> SectionGrid:
    """SectionGrid.of, once per section, parameter values and beam theory: alike hinges of a
    mechanism (or of another file) share the samples, each grid named by its own hinge."""
    at = tuple(sorted((str(k), sp.srepr(v)) for k, v in values.items()))
    key = (section, at, stretches)
    if key not in _GRIDS:
        alike = (dataclasses.replace(section, hinge=""), at, stretches)
        if alike not in _GRIDS:
            _GRIDS[alike] = SectionGrid.of(section, values, stretches)
        _GRIDS[key] = dataclasses.replace(_GRIDS[alike], hinge=section.hinge)
    return _GRIDS[key]
