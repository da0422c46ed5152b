"""How symkin solves its loops: one set of settings that the mpmath evaluation, the generated C
and numpy evaluators and the benchmarks' drivers all read (docs/numerics.md).

The algorithm, in every arithmetic:

0. the closure's rows: 3 per loop (the angular closure, then x and y). When the loops are
   redundant (a parallelogram with a third leg: more rows than non-input hinges, docs/levels.md),
   the rows kept are chosen once, at the as-fabricated pose and the file's parameter values, by
   a rank-revealing (pivoted Gram–Schmidt) pass: the angular rows first, then the positional
   ones, each kept when it is independent of those kept before. Every solve below runs on the
   kept rows (a square system); the dropped rows are checked after it (step 4);
1. rigid angles: the closed-form dyads when the linkage decomposes into them (a redundant link,
   hinged to two bodies already placed, takes its rotation from the line between those hinges);
   a closed-form angle whose inputs are all zero is exactly zero (the formulas round to noise
   there, which the redundancy check of step 4 would compare with noise);
   otherwise Newton on the rigid closure relative to the as-fabricated pose, with continuation:
   the inputs go from 0 to their values in ``continuation_steps`` equal steps, each solved from
   the previous pose until a Newton step is at most ``rigid`` (radians) in size, at most
   ``rigid_iterations`` steps; a step that does not converge means the input cannot be reached.
   The rigid test is absolute in radians (an angle is its own scale), so it accepts an angle of
   exactly zero. The rigid Newton tracks every angle continuously: its angular residuals are
   never wrapped.
   **Winding rule** (every backend, the same test): the closed-form dyads give each angle only
   modulo 2π (wrapped into (−π, π]), which hides a plate turned through more than half a turn
   on the way from the as-fabricated pose (the four-bar at A0 = −3: hinge A at +3.35, wrapped
   to −2.93). Along that path every loop's rotations sum to zero, so the rigid angles are
   accepted only when every loop's angular closure Σ_a Φ_ka θ_a (the angular rows of the
   rigid residual) is below ``winding`` in magnitude; a sum of ±2π means a hinge left
   (−π, π]: the input cannot be reached (exit 3). Then every hinge, rigid and compliant, must
   stay below its model's limit (π at most). Inputs themselves are bounded by π (larger values,
   1e8 or 1e16 included, are refused before any arithmetic), so no reduction modulo 2π of a
   huge number is ever needed. Known gap: two hinges of one loop wrapping in opposite
   directions at once cancel in the sum and pass, in every backend alike;
2. ``polish`` Newton steps on that closure: the dyad formulas lose the relative accuracy of
   small angles to cancellation in floating point (none in mpmath);
3. δ: the first-order linear system A δ = −Φ Δz (`first_order`), then for `exact` (and the
   `loaded` closure) Newton on the compliant closure F(δ) = 0 from there, at most
   ``exact_iterations`` steps. **Stopping rule** (every backend, the same test): at the iterate
   δ_k, with F = F(δ_k), J = ∂F/∂δ and the step s = J⁻¹F, δ_{k+1} = δ_k − s has converged when

   a. |s| ≤ ``converged`` · |δ_{k+1}| (max norms): quadratic convergence, the next step would
      be below rounding; or
   b. every row r has |F_r| ≤ ``residual`` · (S_r + Σ_j |J_rj| |δ_k,j|): the residual is at the
      rounding level of its own terms, so the step was rounding noise. S_r = Σ_b |Φ_cb|
      (|Δz_b,x| + |Δz_b,y|) is the size of the plate deviations in the row (Φ Δz, the first-order
      right-hand side, summed without its cancellation; at the `loaded` level Δz holds the
      plates' force compliance too), evaluated once at the rigid pose; Σ_j |J_rj| |δ_j| is the
      size of the links' terms. Zero for both at once is accepted (0 ≤ 0). This is the test a
      symmetric mechanism needs: in a parallelogram δ = 0 exactly (every compliant hinge angle
      equals the rigid one), the iterate is rounding noise, and no test relative to |δ| can
      pass; the scale comes from the plate and link lengths instead; or
   c. the step has stalled at the rounding floor: at least ``stall_ratio`` times the previous
      one and at most ``stalled`` times |δ_{k+1}|.

   Otherwise, after ``exact_iterations`` steps, the loop whose row has the largest ratio
   |F_r| / (S_r + Σ_j |J_rj| |δ_j|) is named in the refusal (exit 3). Test (b) cannot stop a
   converging iteration early: it holds only where |F| is already within ``residual`` of its
   terms, and the step taken there leaves an error of the order of its square;
4. redundant loops: every dropped row (step 0) must vanish at the solution to ``consistent``
   times the size of its terms (the rigid rows: Σ_i |φ_i| (|V_ix| + |V_iy|); the first-order and
   exact rows: the S_r and links' terms of (3b)); otherwise the loops contradict each other at
   these inputs (the rigid linkage locks, or the plates' model shapes cannot close a redundant
   loop without elastic deformation, which only the physical level `equilibrium` models) and the
   configuration is refused (exit 3), naming the loop. ``consistent`` is the same in float64
   and mpmath, so the backends refuse alike.
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
    residual: float  # a residual within this fraction of its terms' size is rounding noise
    consistent: float  # a redundant (dropped) row must vanish to this fraction of its terms


@dataclass(frozen=True)
class SolverSettings:
    """Continuation, iteration caps and tolerances of every solver symkin runs."""

    continuation_step: float = 0.05  # largest input change per continuation step (rad)
    rigid_iterations: int = 30  # Newton cap per continuation step
    exact_iterations: int = 40  # Newton cap of the exact level
    stall_ratio: float = 0.5  # a step this fraction of the previous one has stalled
    winding: float = math.pi  # a loop's angle sum this large: a hinge wrapped (no assembly)
    # residual: about 1000 units of rounding (a plate's kernel and a sum of a few terms round
    # to a few units; the margin covers long loops)
    float64: Tolerances = Tolerances(
        rigid=1e-10, converged=1e-8, stalled=1e-12, polish=1, residual=2e-13, consistent=1e-8
    )
    float32: Tolerances = Tolerances(
        rigid=1e-4, converged=3e-4, stalled=1e-5, polish=1, residual=1e-4, consistent=1e-3
    )

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
            residual=10.0 ** (3 - dps),
            # the float64 evaluators' test: the sympy backend refuses what they refuse
            consistent=self.float64.consistent,
        )


#: The settings every solver reads.
SOLVER = SolverSettings()
