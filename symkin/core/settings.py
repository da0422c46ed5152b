"""How symkin solves its loops: one set of settings that the mpmath evaluation, the generated C
and numpy evaluators and the benchmarks' drivers all read (docs/numerics.md). The `loaded`
level's Newton, continuation, refusals and buckling search (LoadedSettings) and the stroke
actuators' solves (StrokeSettings) are in the same table; every rule that depends on the working
precision is a multiple of its machine epsilon ε (docs/numerics.md, "The solver table"). No
runtime file holds a solver number of its own (tests/test_solver_settings.py).

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
2. the polish: Newton on that closure from the rigid start until a step is at most
   ``converged`` times the largest unknown angle (a zero step at zero angles included) or
   stalls (the exact level's rule (3c)), at most ``polish`` steps. The dyad formulas and the
   continuation's absolute test leave each angle an absolute error of about ε (float64) or
   10⁻⁴⁰ (40 digits), which is no relative accuracy at all for an input of 1e-32; each step
   shrinks that error by a factor near ε (the closure is nearly linear there, and its residual,
   written relative to the as-fabricated pose, rounds relative to the angles), so a tiny input
   takes a few steps more (float64: 3 at 1e-32, 5 at 1e-100) and an input of ordinary size
   stops after the first, as before. A polish that reaches the cap is accepted as it stands, and
   a singular Jacobian at a step refuses the configuration in float64 (C, numpy) while the
   40-digit backend keeps the angles it has (an exact toggle only). Every backend runs the same
   rule otherwise (docs/numerics.md, "Tiny angles");
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
from dataclasses import dataclass, field, fields

#: float64's machine epsilon (2⁻⁵²): the precision-dependent rules below are multiples of an
#: arithmetic's ε, written as their float64 value over EPS64 so that k·EPS64 is that value
#: exactly (a power of two scales without rounding)
EPS64 = 2.0**-52
#: float32's machine epsilon (2⁻²³)
EPS32 = 2.0**-23


def mpmath_eps(dps: int) -> float:
    """mpmath's ε at `dps` decimal digits: 2^(1 − prec), prec its working bits (mpmath.mp.eps)."""
    import mpmath.libmp

    return 2.0 ** (1 - mpmath.libmp.dps_to_prec(dps))


@dataclass(frozen=True)
class Tolerances:
    """The stopping rules of one arithmetic (float64, float32 or mpmath at some precision)."""

    rigid: float  # a rigid Newton step at most this (radians) ends a continuation step
    converged: float  # an exact-level step at most this times |δ| ends the iteration
    stalled: float  # a stalled exact-level step at most this times |δ| ends it too
    polish: int  # at most this many Newton steps polish the rigid start (rule 2)
    residual: float  # a residual within this fraction of its terms' size is rounding noise
    consistent: float  # a redundant (dropped) row must vanish to this fraction of its terms


@dataclass(frozen=True)
class Ulps:
    """The precision-dependent stopping rules of the loops in units of the arithmetic's ε
    (Tolerances' fields of the same names: k·ε)."""

    rigid: float
    converged: float
    stalled: float
    residual: float

    def at(self, eps: float, polish: int, consistent: float) -> Tolerances:
        """The rules at ε = eps, with the precision's polish steps and redundancy test."""
        return Tolerances(
            rigid=self.rigid * eps,
            converged=self.converged * eps,
            stalled=self.stalled * eps,
            polish=polish,
            residual=self.residual * eps,
            consistent=consistent,
        )


@dataclass(frozen=True)
class LoadedSettings:
    """The `loaded` level's reduced equilibrium (docs/physics.md, "The Newton level"): its
    Newton, continuation, refusals and buckling search, as symkin.physics.reduced and
    reduced_reported run them in Python and templates/c/reduced*.c, templates/numpy/reduced*.py
    in the generated evaluators (which read them from the plan: rules()). Fields ending in
    `_eps` are multiples of float64's ε (every backend runs this level in float64)."""

    # Newton (sk_red_newton; symkin.physics.reduced_solver's _red_newton, Python's and numpy's)
    tol_eps: float = 1e-12 / EPS64  # a step at most this·ε times the largest unknown: converged
    max_iter: int = 12  # Newton steps at most per solve
    max_turn: float = 0.2  # a step turning a hinge by more (rad) hands over to continuation
    stall_after: int = 3  # the stall test applies after this many steps ...
    stall_ratio: float = 0.5  # ... to a step at least this fraction of the previous one ...
    stalled_eps: float = 1e-9 / EPS64  # ... and at most this·ε times the largest unknown
    # chord steps (every backend): after a step below `chord` times the largest unknown
    # the next reuse its J while each shrinks the step by `chord_shrink` or more; a chord step
    # below tol converges where its size times the contraction is below chord_error_eps·ε times
    # the largest unknown (a Newton step leaves its square, below rounding)
    chord: float = 1e-3
    chord_shrink: float = 0.1
    chord_error_eps: float = 1e-15 / EPS64
    # continuation in the load factor s (inputs and loads scaled together) where Newton fails
    first_step: float = 0.25  # the first step in s
    step_growth: float = 1.5  # an accepted step grows the next by this ...
    largest_step: float = 0.5  # ... up to this
    step_cut: float = 0.5  # a refused step is retried this much shorter ...
    smallest_step: float = 1e-3  # ... until below this: no convergence
    # refusals
    p_limit: float = 0.9  # a plate's compression at this fraction of its sway buckling load
    est_factor: float = 3.0  # the order-4 error is about est_factor·e24² (against equilibrium)
    est_limit: float = 0.01  # refused above this estimated error
    # e24 measures each point's change against its own deviation, but at least est_share of the
    # largest point deviation (a point near the centre of a link's rotation barely moves: its
    # own deviation says nothing of the plates' truncation) and est_size_eps·ε times the
    # mechanism's size L (every point at rest but for rounding, e.g. alone at a hub's centre)
    est_share: float = 0.1
    est_size_eps: float = 1e-13 / EPS64
    # the report (symkin.physics.reported, reduced_reported; reduced_report.c / .py)
    sections: int = 64  # sections per plate where the stress is sampled (one RK4 step each)
    # a point's compliance C scaled by the plates' L and F this ill-conditioned (1-norm) is
    # singular: then K = C⁻¹ is null (C's entries within its 1-norm/singular of zero are 0) or C
    # is, whichever side is the outlier (symkin.physics.reported.stiffness_and_compliance)
    singular: float = 1e12
    # the buckling search along the load factor (from 1)
    buckling_limit: float = 10.0  # stops at this factor on the file's loads (as equilibrium's)
    buckling_step: float = 0.5  # its first step in the factor
    buckling_growth: float = 2.0  # an accepted step doubles the next ...
    buckling_largest: float = 3.0  # ... up to this
    buckling_cut: float = 0.5  # a failed Newton halves the step
    buckling_locate: float = 1e-10  # a sign change or limit point located to this relative width

    def rules(self, eps: float = EPS64) -> dict[str, float | int]:
        """Every rule as the runtimes take it (the `_eps` ones times eps, named without it)."""
        out: dict[str, float | int] = {}
        for f in fields(self):
            value = getattr(self, f.name)
            if f.name.endswith("_eps"):
                out[f.name[: -len("_eps")]] = value * eps
            else:
                out[f.name] = value
        return out


@dataclass(frozen=True)
class StrokeSettings:
    """The stroke actuators' solves (docs/levels.md, "Actuators"), written once for Python
    (symkin.studies.stroke_solver: the sympy backend's solve in mpmath and the generated numpy
    modules') and once in C (templates/c/actuators.c): Newton on the strokes in the surrogate
    hinges' angles, its Jacobian by forward differences of step √ε once, then secant (Broyden)
    updates, the compliant solve from the rigid one's Jacobian (numpy and C)."""

    iterations: int = 40  # Newton steps at most
    # a fresh Jacobian's step halved at most this often while it grows the residual ...
    halvings: int = 40
    cut: float = 0.5  # ... by this factor
    tolerance_eps: float = 64.0  # strokes met to this·ε of the points of action's largest place
    floor: float = 1e-300  # that coordinate at least this (a mechanism at the origin)
    # a met stroke whose residual is above this·ε of that coordinate takes one more step (kept
    # where it shrinks the residual): the secant steps stop nearer the rounding, as Newton's
    # quadratic last step did
    polish_eps: float = 1.0
    # ... and a step from an updated (secant) Jacobian is kept where it shrinks the residual to
    # this fraction of it; else the Jacobian is made afresh by differences
    secant: float = 0.5
    # a force actuator's rigid reference (symkin.studies.physical, "Actuators at loaded"):
    # solved again at most this often, until its point moves along its line by at most
    # reference_eps·ε of the mechanism's size L
    reference_rounds: int = 3
    reference_eps: float = 1e-14 / EPS64

    @property
    def reference(self) -> float:
        """reference_eps at float64's ε (the loaded level's solver runs in float64)."""
        return self.reference_eps * EPS64

    def rules(self, eps: float = EPS64) -> dict[str, float | int]:
        """The generated evaluators' rules at ε = eps (in float64: the C evaluator's)."""
        return {
            "iterations": self.iterations,
            "halvings": self.halvings,
            "cut": self.cut,
            "tolerance": self.tolerance_eps * eps,
            "floor": self.floor,
            "step": math.sqrt(eps),
            "polish": self.polish_eps * eps,
            "secant": self.secant,
        }

    def precision_rules(self, precision: str) -> dict[str, float | int]:
        """The rules of a generated numpy module of `precision` ('float64' or 'float32')."""
        return self.rules({"float64": EPS64, "float32": EPS32}[precision])

    def mpmath_rules(self, dps: int) -> dict[str, float | int]:
        """The rules of the sympy backend's solve at `dps` digits (symkin.studies.actuators):
        at mpmath's ε there, but no finer than float64's, since the surrogate angles reach the
        evaluation as inputs, which hold a double."""
        return self.rules(max(EPS64, mpmath_eps(dps)))


@dataclass(frozen=True)
class EquilibriumSettings:
    """The `equilibrium` level's continuation, Newton, polish and buckling search
    (symkin.physics.equilibrium; Python alone, float64 then mpmath; docs/physics.md)."""

    # continuation along the load factor t (follow, continuation)
    min_step: float = 1e-7  # the smallest step in t before it gives up
    max_turn: float = 0.05  # the largest input-angle change per step (rad)
    first_step: float = 0.25  # the largest step in t when no input turns
    step_growth: float = 1.5  # an accepted step grows the next by this (up to the largest)
    step_cut: float = 0.5  # a refused step is retried this much shorter
    approach: float = 0.5  # at most this fraction of the way to J's extrapolated singularity
    singular_ratio: float = 1e-8  # J's smallest over largest singular value: singular below
    # the budget: most steps (accepted or not) and most seconds (wall clock) before it gives up
    # with exit 3 (a solve takes 0.1–1 s and a few dozen steps); the buckling search has
    # buckling_budget times the seconds
    max_steps: int = 1000
    time_budget: float = 20.0
    buckling_budget: float = 2.0
    # a Newton iterate whose plates need loads rate_growth times larger (in the series' rate,
    # |k0| + √|λ|) than where Newton started, plus rate_margin (a buckling plate stays below
    # it), is rejected: far off the path, its Taylor series would need ever more steps
    rate_growth: float = 4.0
    rate_margin: float = 20.0
    # the corrector jumped: it moved farther than the predictor's step plus this times
    # (1 + the largest unknown)
    jump: float = 1e-9
    # Newton in float64 (_newton): at most `newton_iterations` steps; converged below
    # newton_tol_eps·ε times (1 + the largest unknown), or stalled: at least stall_ratio of the
    # previous step and below stalled_eps·ε (absolute); diverged above `diverged`
    newton_iterations: int = 12
    newton_tol_eps: float = 1e-14 / EPS64
    stall_ratio: float = 0.5
    stalled_eps: float = 1e-9 / EPS64
    diverged: float = 1e3
    # the plates' Taylor series are summed to this (beams.shoot's tol) in float64
    series_tol: float = 1e-18
    # polish in mpmath at base_digits + (digits the deviation loses against the positions),
    # at most max_digits (then the caller's extra): at most polish_iterations steps, stopping
    # below 10^(polish_digits − dps); the series to 10^(−dps − polish_guard); the error
    # estimate's rounding term 10^(rounding_digits − dps) of the span (docs/physics.md)
    base_digits: int = 24
    max_digits: int = 400
    # inputs below tiny_input (rad) raise the digits to 2 log10(1/θ) + tiny_guard lost at least
    tiny_input: float = 1e-4
    tiny_guard: int = 8
    polish_iterations: int = 8
    polish_digits: int = 6
    polish_guard: int = 3
    rounding_digits: int = 8
    # buckling: the linearised estimate's central difference (this over the tangent's largest
    # entry) and the imaginary part of an eigenvalue taken for rounding (relative); the search
    # for a singular tangent stiffness stops at buckling_limit on the file's loads. Loads
    # beyond the estimate are probed: following them stops once a plate strains strain_limit
    # (bending plus stretch: no elastic flexure survives it, and the beams' linear law no
    # longer holds) or after probe_steps accepted steps (a deterministic budget); loads
    # gross_overload times the estimate are refused without a probe: a slip of units (the
    # estimate is rough: 0.6 of Euler's load for a column, up to twice a snap-through's limit
    # point, and a load that bends the plates from the start may have none)
    tangent_step: float = 1e-4
    real_eigenvalue: float = 1e-6
    buckling_limit: float = 10.0
    strain_limit: float = 0.1
    probe_steps: int = 30
    gross_overload: float = 10.0

    @property
    def newton_tol(self) -> float:
        return self.newton_tol_eps * EPS64

    @property
    def stalled(self) -> float:
        return self.stalled_eps * EPS64


@dataclass(frozen=True)
class ModesSettings:
    """The natural frequencies (symkin.physics.modes; docs/physics.md, "Natural
    frequencies"): the eigenproblem of the condensed compliance, in float64."""

    # an eigenvalue of M^½ C M^½ (1/ω²) this small against the largest is a direction the
    # mechanism holds rigidly (infinite frequency: left out); one this negative, an unstable
    # equilibrium (a negative tangent stiffness)
    rigid: float = 1e-12
    # a mode whose largest centre translation is below this times its largest rotation times
    # the mechanism's span is a pure rotation (normalised to 1 rad)
    pure_rotation: float = 1e-9
    # the C evaluator's eigen-solve (templates/c/modes.c, cyclic Jacobi): at most this many
    # sweeps; an off-diagonal entry at most jacobi_eps ε times the geometric mean of its two
    # diagonal entries is zero (each eigenvalue to its own relative accuracy)
    jacobi_sweeps: int = 30
    jacobi_eps: float = 1.0

    def c_rules(self, eps: float = EPS64) -> dict[str, float | int]:
        """The C evaluator's Jacobi rules at ε = eps: SK_MODES_SWEEPS, SK_MODES_TOL."""
        return {"sweeps": self.jacobi_sweeps, "tol": self.jacobi_eps * eps}


@dataclass(frozen=True)
class SolverSettings:
    """Continuation, iteration caps and tolerances of every solver symkin runs: one table that
    the plan hands to the generated evaluators and the Python evaluation reads
    (docs/numerics.md, "The solver table")."""

    continuation_step: float = 0.05  # largest input change per continuation step (rad)
    rigid_iterations: int = 30  # Newton cap per continuation step
    exact_iterations: int = 40  # Newton cap of the exact level
    stall_ratio: float = 0.5  # a step this fraction of the previous one has stalled
    winding: float = math.pi  # a loop's angle sum this large: a hinge wrapped (no assembly)
    # the loops' stopping rules in units of ε: float64's and mpmath's (at any precision) ...
    # (residual: about 1000 units of rounding: a plate's kernel and a sum of a few terms round
    # to a few units; the margin covers long loops)
    ulps: Ulps = Ulps(
        rigid=1e-10 / EPS64, converged=1e-8 / EPS64, stalled=1e-12 / EPS64, residual=2e-13 / EPS64
    )
    # ... and float32's (its ε is coarse: the steps stop further above it)
    ulps32: Ulps = Ulps(
        rigid=1e-4 / EPS32, converged=3e-4 / EPS32, stalled=1e-5 / EPS32, residual=1e-4 / EPS32
    )
    # the polish's cap (rule 2): measured, float64 stops after 1 step at ordinary inputs, 3 at
    # 1e-32, 5 at 1e-100 to 1e-300; 8 leaves a margin (a polish at the cap is accepted)
    polish: int = 8
    polish_mpmath: int = 8
    # a dropped row's test is the same in float64 and mpmath: the sympy backend refuses what
    # the float64 evaluators refuse
    consistent: float = 1e-8
    consistent32: float = 1e-3
    loaded: LoadedSettings = field(default_factory=LoadedSettings)
    strokes: StrokeSettings = field(default_factory=StrokeSettings)
    equilibrium: EquilibriumSettings = field(default_factory=EquilibriumSettings)
    modes: ModesSettings = field(default_factory=ModesSettings)

    @property
    def float64(self) -> Tolerances:
        return self.ulps.at(EPS64, self.polish, self.consistent)

    @property
    def float32(self) -> Tolerances:
        return self.ulps32.at(EPS32, self.polish, self.consistent32)

    def continuation_steps(self, largest_input: float) -> int:
        """Steps from the as-fabricated pose to inputs whose largest magnitude is given."""
        return max(1, math.ceil(largest_input / self.continuation_step))

    def tolerances(self, precision: str) -> Tolerances:
        """The rules of the generated evaluators: 'float64' or 'float32'."""
        return {"float64": self.float64, "float32": self.float32}[precision]

    def mpmath(self, dps: int) -> Tolerances:
        """The rules at `dps` decimal digits: float64's multiples of ε at mpmath's ε."""
        return self.ulps.at(mpmath_eps(dps), self.polish_mpmath, self.consistent)

    def loop_rules(self, tol: Tolerances) -> dict[str, tuple[int | float, ...]]:
        """The loops' three Newton rules at the arithmetic's `tol`, as the arguments of the
        shared Newton's _Rule (symkin.kinematics.loop_newton: iterations, tolerance, converged,
        stalled, stall_ratio, residual): the rigid continuation's (rule 1: an absolute step),
        the polish's (rule 2) and the exact level's (rule 3). The generated numpy modules and the
        40-digit evaluation both take them from here."""
        return {
            "rigid": (self.rigid_iterations, tol.rigid),
            "polish": (tol.polish, 0.0, tol.converged, tol.stalled, self.stall_ratio),
            "exact": (
                self.exact_iterations,
                0.0,
                tol.converged,
                tol.stalled,
                self.stall_ratio,
                tol.residual,
            ),
        }


#: The settings every solver reads.
SOLVER = SolverSettings()
