"""A plate as a geometrically exact plane beam, shot from its clamped P end with its end loads known
(docs/physics.md): Reissner's beam (1972), which bends, stretches and shears linearly in its
strains, or its inextensible, shear-free limit, the elastica.

In the plate frame fixed in P (origin at P's clamp, x along the straight plate) and with s the arc
length of the undeformed plate over its length l (0..1), ψ(s) the angle of the cross-section and
(λx, λy) = n l²/EI the constant force n that link M exerts on the plate at its M end, the force's
components along and across the section's normal are f_N = λx cos ψ + λy sin ψ and
f_Q = λy cos ψ − λx sin ψ, and with ε_a = EI/(EA l²), γ_a = EI/(κGA l²) (the stretch and shear
compliances; both 0 for the elastica) and d = ε_a − γ_a:

    ψ'' = −f_Q (1 + d f_N),        ψ(0) = 0,   ψ'(0) = k0,
    r' = (1 + ε_a f_N) (cos ψ, sin ψ) + γ_a f_Q (−sin ψ, cos ψ)
       = (cos ψ, sin ψ) + γ_a λ + d f_N (cos ψ, sin ψ).

The first line is m' = −r' × n with m = EI ψ'/l: the moment link M exerts at the M end is
M_M = EI ψ'(1)/l, k0 = m(0) l/EI the bending moment at the P end; with ε_a = γ_a = 0 it is the
elastica's ψ'' = λx sin ψ − λy cos ψ. The products of f_N and f_Q are linear in cos 2ψ and
sin 2ψ, so the right-hand sides are linear combinations of four series.

The solution is a Taylor series in s, restarted at a few equal steps so the series converges fast:
with p_k, S_k, C_k the coefficients of ψ, sin ψ, cos ψ (and S2_k, C2_k those of sin 2ψ, cos 2ψ,
the same recurrences with 2ψ),

    k S_k = Σ_{j=1..k} j p_j C_{k-j},   k C_k = −Σ_{j=1..k} j p_j S_{k-j},
    (k+1)(k+2) p_{k+2} = λx S_k − λy C_k − d (λx λy C2_k + (λy² − λx²)/2 S2_k),

summed until the terms fall below `tol` (the truncation error), at any working precision: the same
code runs on float64, complex128 (Jacobians by the complex step) and mpmath arrays. The elastica
skips the 2ψ series.
"""

from __future__ import annotations

from dataclasses import dataclass

import mpmath
import numpy as np

from . import arith

#: Largest number of Taylor terms per step before the step is halved.
MAX_TERMS = 120


@dataclass(frozen=True)
class PlateEnd:
    """The M end of plates in the P plate frame, in units of l, per element of the input arrays.

    x, y: M's clamp; psi: its rotation θ; omega: ψ'(1) = M_M l/EI; energy: the elastic energy
    over EI/(2l), ∫ψ'² + ε_a f_N² + γ_a f_Q² ds (None unless asked for); tail: the largest
    neglected series term (the truncation error)."""

    x: np.ndarray
    y: np.ndarray
    psi: np.ndarray
    omega: np.ndarray
    energy: np.ndarray | None
    tail: float


def shoot(k0, lx, ly, tol: float, energy: bool = False, stretch=None, shear=None) -> PlateEnd:
    """Integrate the plates of the (broadcast) arrays k0, λx, λy over s = 0..1: Reissner beams
    with stretch compliance ε_a = EI/(EA l²) and shear compliance γ_a = EI/(κGA l²) (arrays
    broadcast with k0; 0 where a plate is an elastica), or elastica when both are None."""
    k0, lx, ly = np.broadcast_arrays(*(np.asarray(v) for v in (k0, lx, ly)))
    compliance = None
    if stretch is not None or shear is not None:
        zero = k0 * 0
        eps = zero + (0 if stretch is None else np.asarray(stretch))
        gam = zero + (0 if shear is None else np.asarray(shear))
        compliance = (eps - gam, gam)
    rate = arith.magnitude(abs(k0.real) + arith.sqrt(abs(lx.real) + abs(ly.real)))
    steps = arith.steps_for(rate)
    while True:
        result = _steps(k0, lx, ly, steps, tol, energy, compliance)
        if result is not None:
            return result
        steps *= 2


def _steps(k0, lx, ly, steps: int, tol: float, energy: bool, compliance) -> PlateEnd | None:
    exact = arith.is_mp(k0)  # mpmath numbers
    h = mpmath.mpf(1) / steps if exact else 1 / steps
    zero = k0 * 0
    psi, om, x, y = zero, k0, zero, zero
    work = zero if energy else None
    tail = 0.0
    if compliance is not None:
        d, gam = compliance
        # the constant parts of r' and of the stretch and shear energy (per unit s)
        drift = (gam * lx + d * lx / 2, gam * ly + d * ly / 2)
        axial = gam * (lx * lx + ly * ly) + d * (lx * lx + ly * ly) / 2
    for _ in range(steps):
        series = _series(psi, om, lx, ly, h, tol, compliance)
        if series is None:
            return None
        p, S, C, S2, C2, last = series
        tail = max(tail, last)
        n = len(S)
        powers = _column([h**k for k in range(2 * n + 2)], p)
        rise = _column([h ** (k + 1) / (k + 1) for k in range(2 * n + 2)], p)  # ∫_0^h σ^k dσ
        dx, dy = C, S
        if compliance is not None:
            # r' = (cos ψ, sin ψ) + γ_a λ + d f_N (cos ψ, sin ψ), f_N (cos, sin) in 2ψ
            dx = C + d * (lx * C2 + ly * S2) / 2
            dy = S + d * (lx * S2 - ly * C2) / 2
            x = x + drift[0] * h
            y = y + drift[1] * h
        x = x + (dx * rise[:n]).sum(axis=0)
        y = y + (dy * rise[:n]).sum(axis=0)
        m = len(p)
        psi_end = (p * powers[:m]).sum(axis=0)
        slope = p[1:] * _column(list(range(1, m)), p)  # ψ'(σ) = Σ slope_k σ^k
        om_end = (slope * powers[: m - 1]).sum(axis=0)
        if energy:
            # ∫ψ'² over the step: the square's coefficients by convolution
            for k in range(2 * len(slope) - 1):
                lo, hi = max(0, k - len(slope) + 1), min(k, len(slope) - 1)
                left, right = slope[lo : hi + 1], slope[k - hi : k - lo + 1][::-1]
                square = _dots(left, right[None])[0] if exact else (left * right).sum(axis=0)
                work = work + square * rise[k]
            if compliance is not None:
                # ε_a f_N² + γ_a f_Q² = γ_a |λ|² + d f_N², f_N² linear in cos 2ψ and sin 2ψ
                work = work + axial * h
                square = d * ((lx * lx - ly * ly) / 2 * C2 + lx * ly * S2)
                work = work + (square * rise[:n]).sum(axis=0)
        psi, om = psi_end, om_end
    return PlateEnd(x, y, psi, om, work, tail)


def _column(values: list, like: np.ndarray) -> np.ndarray:
    """`values` as an array along the first axis, broadcast against the coefficients `like`
    (object dtype for mpmath numbers)."""
    out = np.array(values, dtype=object if arith.is_mp(like) else float)
    return out.reshape((len(values),) + (1,) * (np.ndim(like) - 1))


def _series(psi0, om0, lx, ly, h, tol: float, compliance):
    """Taylor coefficients of ψ, sin ψ, cos ψ (and of sin 2ψ, cos 2ψ for Reissner plates) on one
    step of length h, until they are below tol: arrays whose first axis is the power of σ."""
    shape = np.shape(psi0)
    kind = np.result_type(psi0, om0, lx, ly)
    exact = arith.is_mp(psi0)  # mpmath numbers (as _steps tells them)
    size = MAX_TERMS + 2
    reissner = compliance is not None
    p = np.zeros((size + 1, *shape), kind)
    jp = np.zeros((size + 1, *shape), kind)  # j p_j, the coefficients of ψ'
    # the trigonometric series in one array, so each term is one product and one sum for all:
    # W[0] = C (cos ψ), W[1] = S (sin ψ), and for Reissner plates W[2] = C2, W[3] = S2 (2ψ)
    w = 4 if reissner else 2
    W = np.zeros((w, size, *shape), kind)
    p[0], p[1], jp[1] = psi0, om0, om0
    W[0, 0], W[1, 0] = arith.cos(psi0), arith.sin(psi0)
    # S_k = Σ j p_j C_{k-j} / k, C_k = −Σ j p_j S_{k-j} / k (2ψ: twice): the sums of the
    # products with W are taken in W's order, so each row comes from its partner's sum
    partner = [1, 0, 3, 2][:w]
    factor = np.array([-1, 1, -2, 2][:w], dtype=kind).reshape((w,) + (1,) * len(shape))
    if reissner:
        d = compliance[0]
        W[2, 0], W[3, 0] = arith.cos(2 * psi0), arith.sin(2 * psi0)
        # f_N f_Q = λx λy cos 2ψ + (λy² − λx²)/2 sin 2ψ
        a, b = d * lx * ly, d * (ly * ly - lx * lx) / 2
        # the 2ψ series enter ψ'' and r' times d λ² and d λ: their truncation weighs that much
        force = arith.magnitude(abs(lx.real) + abs(ly.real))
        weight = arith.magnitude(d) * (force + force * force)
    small = 0
    for k in range(MAX_TERMS):
        if k:
            if exact:
                sums = _dots(jp[1 : k + 1], W[:, k - 1 :: -1][:, :k])
            else:
                sums = (jp[1 : k + 1] * W[:, k - 1 :: -1][:, :k]).sum(axis=1)
            W[:, k] = sums[partner] * factor / k
        C, S = W[0, k], W[1, k]
        rhs = lx * S - ly * C
        if reissner:
            rhs = rhs - a * W[2, k] - b * W[3, k]
        p[k + 2] = rhs / ((k + 1) * (k + 2))
        jp[k + 2] = rhs / (k + 1)
        if not small and k % 4 != 3:
            continue  # the terms are measured every fourth until one is small (they cost)
        hk = float(h) ** (k + 1)
        size = hk * arith.magnitude(np.stack([jp[k + 2], S, C]))
        if reissner:
            size = max(size, weight * hk * arith.magnitude(W[2:, k]))
        small = small + 1 if size < tol else 0
        if small == 3:
            n = k + 1
            if reissner:
                return p[: n + 2], W[1, :n], W[0, :n], W[3, :n], W[2, :n], size
            return p[: n + 2], W[1, :n], W[0, :n], None, None, size
    return None


def _dots(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Σ_j a[j] b[i, j] for every i and element, of mpmath numbers: mpmath's fdot, which sums
    the products exactly and rounds once (a third of the time of numpy's products and sum of
    mpf objects)."""
    n, rows = a.shape[0], b.shape[0]
    a2, b2 = a.reshape(n, -1), b.reshape(rows, n, -1)
    out = np.empty((rows, a2.shape[1]), dtype=object)
    for i in range(rows):
        for e in range(a2.shape[1]):
            out[i, e] = mpmath.fdot(a2[:, e], b2[i, :, e])
    return out.reshape((rows, *a.shape[1:]))
