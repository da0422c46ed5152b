"""A plate as a geometrically exact, inextensible Euler–Bernoulli beam (the elastica), shot from its
clamped P end with its end loads known (docs/physics.md).

In the plate frame fixed in P (origin at P's clamp, x along the straight plate) and with s the arc
length over the plate length l (0..1), the tangent angle ψ(s) obeys

    x' = cos ψ,   y' = sin ψ,   ψ(0) = 0,   ψ'(0) = k0,   ψ'' = λx sin ψ − λy cos ψ,

where (λx, λy) = n l²/EI is the constant force n that link M exerts on the plate at its M end and
k0 = m(0) l/EI the bending moment at the P end: EI ψ'/l = m(s) = M_M + (r(l) − r(s)) × n, so the
moment link M exerts at the M end is M_M = EI ψ'(1)/l.

The solution is a Taylor series in s, restarted at a few equal steps so the series converges fast:
with p_k, S_k, C_k the coefficients of ψ, sin ψ, cos ψ,

    k S_k = Σ_{j=1..k} j p_j C_{k-j},   k C_k = −Σ_{j=1..k} j p_j S_{k-j},
    (k+1)(k+2) p_{k+2} = λx S_k − λy C_k,

summed until the terms fall below `tol` (the truncation error), at any working precision: the same
code runs on float64, complex128 (Jacobians by the complex step) and mpmath arrays.
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

    x, y: M's clamp; psi: its rotation θ; omega: ψ'(1) = M_M l/EI; energy: ∫ψ'² ds, so that the
    elastic energy is EI/(2l) · energy (None unless asked for); tail: the largest neglected
    series term (the truncation error)."""

    x: np.ndarray
    y: np.ndarray
    psi: np.ndarray
    omega: np.ndarray
    energy: np.ndarray | None
    tail: float


def shoot(k0, lx, ly, tol: float, energy: bool = False) -> PlateEnd:
    """Integrate the elastica of every element of the (broadcast) arrays k0, λx, λy over s =
    0..1."""
    k0, lx, ly = np.broadcast_arrays(*(np.asarray(v) for v in (k0, lx, ly)))
    rate = arith.magnitude(abs(k0.real) + arith.sqrt(abs(lx.real) + abs(ly.real)))
    steps = arith.steps_for(rate)
    while True:
        result = _steps(k0, lx, ly, steps, tol, energy)
        if result is not None:
            return result
        steps *= 2


def _steps(k0, lx, ly, steps: int, tol: float, energy: bool) -> PlateEnd | None:
    h = mpmath.mpf(1) / steps if arith.is_mp(k0) else 1 / steps
    zero = k0 * 0
    psi, om, x, y = zero, k0, zero, zero
    work = zero if energy else None
    tail = 0.0
    for _ in range(steps):
        series = _series(psi, om, lx, ly, h, tol)
        if series is None:
            return None
        p, S, C, last = series
        tail = max(tail, last)
        hk = [h**k for k in range(2 * len(p) + 1)]
        x = x + sum(C[k] * hk[k + 1] / (k + 1) for k in range(len(C)))
        y = y + sum(S[k] * hk[k + 1] / (k + 1) for k in range(len(S)))
        psi_end = sum(p[k] * hk[k] for k in range(len(p)))
        om_end = sum(k * p[k] * hk[k - 1] for k in range(1, len(p)))
        if energy:
            w = [(k + 1) * p[k + 1] for k in range(len(p) - 1)]  # ψ'(σ) = Σ w_k σ^k
            work = work + sum(
                w[i] * w[j] * hk[i + j + 1] / (i + j + 1)
                for i in range(len(w))
                for j in range(len(w))
            )
        psi, om = psi_end, om_end
    return PlateEnd(x, y, psi, om, work, tail)


def _series(psi0, om0, lx, ly, h, tol: float):
    """Taylor coefficients of ψ, sin ψ, cos ψ on one step of length h, until they are below tol."""
    p = [psi0, om0]
    S, C = [arith.sin(psi0)], [arith.cos(psi0)]
    small = 0
    for k in range(MAX_TERMS):
        if k:
            jp = [j * p[j] for j in range(1, k + 1)]
            S.append(sum(jp[j - 1] * C[k - j] for j in range(1, k + 1)) / k)
            C.append(-sum(jp[j - 1] * S[k - j] for j in range(1, k + 1)) / k)
        p.append((lx * S[k] - ly * C[k]) / ((k + 1) * (k + 2)))
        size = max(
            arith.magnitude(p[k + 2]) * float(h) ** (k + 1) * (k + 2),
            arith.magnitude(S[k]) * float(h) ** (k + 1),
            arith.magnitude(C[k]) * float(h) ** (k + 1),
        )
        small = small + 1 if size < tol else 0
        if small == 3:
            return p, S, C, size
    return None
