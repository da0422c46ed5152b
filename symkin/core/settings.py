"""How symkin solves its loops: one set of settings that the mpmath evaluation, the generated C
and numpy evaluators and the benchmarks' drivers all read (docs/numerics.md).

The algorithm, in every arithmetic:

1. rigid angles: the closed-form dyads when the linkage decomposes into them; otherwise Newton on
   the rigid closure relative to the as-fabricated pose, with continuation: the inputs go from 0
   to their values in ``continuation_steps`` equal steps, each solved from the previous pose
   until a Newton step is at most ``rigid`` (radians) in size, at most ``rigid_iterations``
   steps; a step that does not converge means the input cannot be reached;
   The rigid Newton tracks every angle continuously: its angular residuals are never wrapped.
   **Winding rule** (every backend, the same test): the closed-form dyads give each angle only
   modulo 2π (wrapped into (−π, π]), which hides a plate turned through more than half a turn
   on the way from the as-fabricated pose (the four-bar at A0 = −3: hinge A at +3.35, wrapped
   to −2.93). Along that path every loop's rotations sum to zero, so the rigid angles are
   accepted only when every loop's angular closure Σ_a Φ_ka θ_a (the rows 0, 3, 6, ... of the
   rigid residual) is below ``winding`` in magnitude; a sum of ±2π means a hinge left
   (−π, π]: the input cannot be reached (exit 3). Then every hinge, rigid and compliant, must
   stay below its model's limit (π at most). Inputs themselves are bounded by π (larger values,
   1e8 or 1e16 included, are refused before any arithmetic), so no reduction modulo 2π of a
   huge number is ever needed. Known gap: two hinges of one loop wrapping in opposite
   directions at once cancel in the sum and pass, in every backend alike;
2. ``polish`` Newton steps on that closure: the dyad formulas lose the relative accuracy of
   small angles to cancellation in floating point (none in mpmath);
3. δ: the first-order linear system A δ = −Φ Δz (`first_order`), then for `exact` Newton on the
   compliant closure from there, at most ``exact_iterations`` steps, ending once a step is at
   most ``converged`` times |δ| (quadratic convergence: the next step would be below rounding),
   or when it has stalled at the rounding floor: a step at least ``stall_ratio`` times the
   previous one and at most ``stalled`` times |δ|.
"""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class Tolerances:
    """The stopping rules of one arithmetic (float64, float32 or mpmath at some precision)."""

    rigid: float  # a rigid Newton step at most this (radians) ends a continuation step
    converged: float  # an exact-level step at most this times |δ| ends the iteration
    stalled: float  # a stalled exact-level step at most this times |δ| ends it too
    polish: int  # Newton steps on the rigid closure after the rigid start


@dataclass(frozen=True)
class SolverSettings:
    """Continuation, iteration caps and tolerances of every solver symkin runs."""

    continuation_step: float = 0.05  # largest input change per continuation step (rad)
    rigid_iterations: int = 30  # Newton cap per continuation step
    exact_iterations: int = 40  # Newton cap of the exact level
    stall_ratio: float = 0.5  # a step this fraction of the previous one has stalled
    winding: float = math.pi  # a loop's angle sum this large: a hinge wrapped (no assembly)
    float64: Tolerances = Tolerances(rigid=1e-10, converged=1e-8, stalled=1e-12, polish=1)
    float32: Tolerances = Tolerances(rigid=1e-4, converged=3e-4, stalled=1e-5, polish=1)

    def continuation_steps(self, largest_input: float) -> int:
        """Steps from the as-fabricated pose to inputs whose largest magnitude is given."""
        return max(1, math.ceil(largest_input / self.continuation_step))

    def tolerances(self, precision: str) -> Tolerances:
        """The rules of the generated evaluators: 'float64' or 'float32'."""
        return {"float64": self.float64, "float32": self.float32}[precision]

    def mpmath(self, dps: int) -> Tolerances:
        """The rules at `dps` decimal digits: steps near the precision's own rounding floor."""
        return Tolerances(
            rigid=10.0 ** (6 - dps),
            converged=10.0 ** (4 - dps),
            stalled=10.0 ** (-(dps // 2)),
            polish=0,
        )


#: The settings every solver reads.
SOLVER = SolverSettings()
