"""Sensitivities (docs/sensitivity.md): the partial derivatives from which every backend assembles
the total derivatives of the points' rigid positions R_P and deviations ΔR_P with respect to the
file's parameters and the inputs.

Nothing here differentiates a solver. Each level that solves for unknowns states them as the
root of a closure, and the implicit-function theorem gives their derivatives from the closure's
own Jacobian:

- rigid angles θ_u of the non-input hinges: the rigid closure relative to the as-fabricated pose
  G(θ_u; v) = 0 ((5.1)/(5.3) with every Δz = 0), Jacobian A (the first-order system's matrix):
  dθ_u/dv = Θ = -A⁻¹ ∂G/∂v;
- `first_order`: δ solves E = A δ + r = 0 (M = A); `exact`: δ solves the compliant closure
  E = F(δ) = 0 (M = ∂F/∂δ, the exact Jacobian the Newton iteration uses):
  dδ/dv = Y = -M⁻¹ (∂E/∂v + ∂E/∂θ_u Θ);
- a point's deviation D(θ, δ, v) at the level: dD/dv = ∂D/∂v + ∂D/∂θ_u Θ + ∂D/∂δ Y; its rigid
  position: dR/dv = ∂R/∂v + ∂R/∂θ_u Θ; `paper` (4.8) has no δ.

v runs over the parameters (file order), then the input angles. The partial derivatives by the hinge
angles come from the structure (:meth:`symkin.kinematics.analysis.Analysis.chain_partials`, free of
cancellation like the quantities themselves); those by the parameters from sympy.

A parameter whose default is an expression over earlier ones (`L2 = "2*l"`) follows it: the
derivative by p is the total derivative with respect to an error added to p, the parameters
defined from p moving with it. With C[j][k] = ∂(default of p_j)/∂p_k (zero unless k < j) the
totals T follow from the partial derivatives S by T_k = S_k + Σ_{j>k} C[j][k] T_j, last first.

A new level with a closed form adds its closure here (its unknowns, M, ∂E/∂θ_u, ∂E/∂v and its
deviation's partial derivatives) and the backends assemble it like the others.
"""

from __future__ import annotations

import weakref
from collections.abc import Sequence
from dataclasses import dataclass
from functools import cached_property

import sympy as sp

from ..core import levels
from .analysis import Analysis


@dataclass(frozen=True)
class Stage:
    """A closure E(y; θ_u, v) = 0 that a level solves for its unknowns y."""

    jacobian: sp.Matrix  # M = ∂E/∂y, K × K
    theta: sp.Matrix  # ∂E/∂θ_u, K × K (the rigid stage has none: zero columns)
    variables: sp.Matrix  # ∂E/∂v, K × n_v


@dataclass(frozen=True)
class Partials:
    """Partial derivatives of the requested points' outputs, two rows (x, y) per point."""

    theta: sp.Matrix  # by the non-input hinge angles θ_u: 2 n_P × K
    delta: sp.Matrix  # by δ (zero columns at levels without δ): 2 n_P × K
    variables: sp.Matrix  # by the parameters, then the inputs: 2 n_P × n_v


class Sensitivities:
    """The symbolic partial derivatives of one analysis for the named points."""

    def __init__(self, analysis: Analysis, points: Sequence[str]) -> None:
        self.analysis = analysis
        self.points = tuple(points)
        kin = analysis.kin
        self.params = analysis.params
        self.inputs = tuple(kin.theta[a] for a in kin.inputs)
        #: v: the parameters in file order, then the input angles in input order
        self.variables = self.params + self.inputs

    def _closure(self, an: Analysis, form: str) -> sp.Matrix:
        """∂E/∂v of the closure of `form`: by the parameters, then by the inputs."""
        return an.closure_partials(form, "param", self.params).row_join(
            an.closure_partials(form, "theta", an.kin.inputs)
        )

    def _point(self, an: Analysis, name: str, form: str) -> sp.Matrix:
        """∂/∂v of a point's rigid position (form rigid) or deviation at the level `form`."""
        return an.point_partials(name, form, "param", self.params).row_join(
            an.point_partials(name, form, "theta", an.kin.inputs)
        )

    @cached_property
    def rigid_stage(self) -> Stage | None:
        """The rigid angles: G = the rigid closure, M = A; None without non-input hinges."""
        an = self.analysis
        kin = an.kin
        if not kin.unknowns:
            return None
        g_v = self._closure(an, "rigid")
        return Stage(an.linear_system[0], sp.zeros(len(kin.unknowns), 0), g_v)

    @cached_property
    def rigid(self) -> Partials:
        """The rigid positions R_P."""
        an = self.analysis
        kin = an.kin
        rows_v, rows_t = [], []
        for name in self.points:
            rows_v.append(self._point(an, name, "rigid"))
            rows_t.append(an.point_partials(name, "rigid", "theta", kin.unknowns))
        return self._stacked(rows_t, None, rows_v)

    def stage(self, level: str) -> Stage | None:
        """The closure `level` solves for δ (None at levels without δ)."""
        return self._stages[level]

    def partials(self, level: str) -> Partials:
        """The deviations ΔR_P at `level`."""
        return self._partials[level]

    @cached_property
    def _stages(self) -> dict[str, Stage | None]:
        an = self.analysis
        kin = an.kin
        out: dict[str, Stage | None] = {}
        for lv in levels.LEVELS:
            if not lv.sensitivity or lv.name in levels.LOADED:
                continue  # loaded: symkin.physics.reduced_sensitivity
            if not lv.generated or not lv.needs_delta or not kin.unknowns:
                out[lv.name] = None
                continue
            # first_order: E = A δ + r, M = A; exact: E = F, M = its Jacobian (∂E/∂δ)
            if lv.name not in ("first_order", "exact"):  # pragma: no cover
                raise NotImplementedError(f"no sensitivity for level '{lv.name}'")
            jacobian = an.closure_partials(lv.name, "delta", kin.unknowns)
            out[lv.name] = Stage(
                jacobian,
                an.closure_partials(lv.name, "theta", kin.unknowns),
                self._closure(an, lv.name),
            )
        return out

    @cached_property
    def _partials(self) -> dict[str, Partials]:
        an = self.analysis
        kin = an.kin
        out: dict[str, Partials] = {}
        for lv in levels.LEVELS:
            if not lv.generated or not lv.sensitivity or lv.name in levels.LOADED:
                continue
            rows_v, rows_t, rows_d = [], [], []
            for name in self.points:
                rows_v.append(self._point(an, name, lv.name))
                rows_t.append(an.point_partials(name, lv.name, "theta", kin.unknowns))
                rows_d.append(
                    an.point_partials(name, lv.name, "delta", kin.unknowns)
                    if lv.needs_delta
                    else sp.zeros(2, len(kin.unknowns))
                )
            out[lv.name] = self._stacked(rows_t, rows_d, rows_v)
        return out

    def _stacked(self, theta: list, delta: list | None, variables: list) -> Partials:
        k = len(self.analysis.kin.unknowns)

        def stack(blocks: list, cols: int) -> sp.Matrix:
            return sp.Matrix.vstack(*blocks) if blocks else sp.zeros(0, cols)

        return Partials(
            stack(theta, k),
            stack(delta, k) if delta is not None else sp.zeros(2 * len(self.points), k),
            stack(variables, len(self.variables)),
        )


def parameter_chain(defaults: Sequence[sp.Expr], symbols: Sequence[sp.Symbol]) -> sp.Matrix:
    """C[j][k] = ∂ defaults[j] / ∂ symbols[k] (k < j; a default reads earlier parameters only):
    how an error added to parameter k moves the parameters defined from it."""
    n = len(symbols)
    out = sp.zeros(n, n)
    position = {s: k for k, s in enumerate(symbols)}
    for j, default in enumerate(defaults):
        # only the parameters the default reads (a file may have a thousand, most of them numbers)
        for s in sp.sympify(default).free_symbols:
            k = position.get(s)
            if k is not None and k < j:
                out[j, k] = sp.diff(default, s)
    return out


def total(columns: list, chain: Sequence[Sequence[object]]) -> list:
    """The totals T_k = S_k + Σ_{j>k} C[j][k] T_j of the partial-derivative columns S_k (any
    arithmetic: one entry per parameter, each a number, an array or a list of them)."""
    out = list(columns)
    for k in range(len(out) - 1, -1, -1):
        for j in range(k + 1, len(out)):
            c = chain[j][k]
            if c:
                out[k] = _axpy(c, out[j], out[k])
    return out


def _axpy(c, x, y):
    if isinstance(x, (list, tuple)):
        return type(x)(_axpy(c, a, b) for a, b in zip(x, y))
    return y + c * x


_CACHE: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def of(analysis: Analysis) -> Sensitivities:
    """The sensitivities of every point of `analysis` (kept as long as the analysis)."""
    found = _CACHE.get(analysis)
    if found is None:
        found = _CACHE[analysis] = Sensitivities(analysis, [p.name for p in analysis.points])
    return found
