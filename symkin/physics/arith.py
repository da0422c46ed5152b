"""Element-wise arithmetic for the physics solvers, on numpy arrays of one of three kinds.

float64 (continuation), complex128 (the same code differentiated by the complex step, which gives
Jacobians to full float64 accuracy because it subtracts nothing) and object arrays of mpmath mpf
(the final polish at the working precision). The solvers are written once over these arrays.
"""

from __future__ import annotations

import math

import mpmath
import numpy as np

#: Size of the complex step: complex arrays hold value + i·COMPLEX_STEP·derivative, far below any
#: unknown's scale, so the derivative is exact to float64 (nothing is subtracted).
COMPLEX_STEP = 1e-200

_MP_SIN = np.frompyfunc(mpmath.sin, 1, 1)
_MP_COS = np.frompyfunc(mpmath.cos, 1, 1)
_MP_SQRT = np.frompyfunc(mpmath.sqrt, 1, 1)


def is_mp(a: np.ndarray) -> bool:
    return np.asarray(a).dtype == object


def sin(a: np.ndarray) -> np.ndarray:
    return _MP_SIN(a) if is_mp(a) else np.sin(a)


def cos(a: np.ndarray) -> np.ndarray:
    return _MP_COS(a) if is_mp(a) else np.cos(a)


def sqrt(a: np.ndarray) -> np.ndarray:
    return _MP_SQRT(a) if is_mp(a) else np.sqrt(a)


def magnitude(a) -> float:
    """Largest |element| as a Python float (0 for an empty array); for a complex array the
    larger of the values and the derivatives it carries (imaginary part / COMPLEX_STEP)."""
    a = np.asarray(a)
    if a.size == 0:
        return 0.0
    if is_mp(a):
        return float(max(abs(v) for v in a.flat))
    if np.iscomplexobj(a):
        return float(max(np.max(np.abs(a.real)), np.max(np.abs(a.imag)) / COMPLEX_STEP))
    return float(np.max(np.abs(a)))


def mp_array(values, dps: int | None = None) -> np.ndarray:
    """An object array of mpf from floats, mpf or exact sympy numbers."""
    import sympy as sp

    def conv(v):
        if isinstance(v, sp.Basic):
            return mpmath.mpf(sp.N(v, (dps or mpmath.mp.dps) + 5))
        return mpmath.mpf(v)

    flat = [conv(v) for v in np.ravel(np.asarray(values, dtype=object))]
    out = np.empty(len(flat), dtype=object)
    out[:] = flat
    return out.reshape(np.shape(np.asarray(values, dtype=object)))


def steps_for(rate: float, per_unit: float = 2.0) -> int:
    """Number of equal steps so that rate * step <= 1/per_unit."""
    return max(1, math.ceil(rate * per_unit))
