"""The symbolic deviation of the characteristic points at every level (docs/levels.md).

The compliant pose is written as the rigid one plus a difference: θ^c_a = θ^r_a + δ_a for every
hinge that is not an input. All levels are sympy expressions in the rigid angles θ, the
differences δ and the parameters:

- ``paper``: ΔX = Σ Δz_b over the direct path to the point's link, at the rigid angles (4.8).
- ``first_order``: δ from the loop closure (5.1)/(5.3) linearised about the rigid pose (the
  rigid loop Jacobian times δ equals -Φ Δz), then ΔX = Σ δφ_i Rot(φ_i) J W_i + Σ Δz_b.
- ``exact``: δ from the full compliant loop closure, written as
  Σ_i Rot(φ_i)(Rot(δφ_i) - I) V_i + Φ Δz(θ + δ) = 0, which holds no rigid part that could cancel,
  with its closed-form Jacobian; ΔX = Σ_i Rot(φ_i)(Rot(δφ_i) - I) W_i + Σ Δz_b.

Numbers come from :mod:`symkin.evaluation` (mpmath) and the generated code (:mod:`symkin.codegen`).
"""

from __future__ import annotations

from collections.abc import Sequence
from functools import cached_property, lru_cache

import sympy as sp

from . import levels
from . import rigid as rigid_solver
from . import vectors as V
from .errors import InputError
from .hinge_models import THETA
from .kinematics import Kinematics
from .structure import Structure


class Analysis:
    """The symbolic deviation of a mechanism's points at every level."""

    def __init__(self, structure: Structure, points: Sequence[str] | None = None,
                 plate=None) -> None:
        self.structure = structure
        self.mechanism = mech = structure.mechanism
        self.kin = kin = Kinematics(structure, plate)
        self.rigid = rigid_solver.solve(kin)
        names = [p.name for p in mech.points]
        for p in points or ():
            if p not in names:
                raise InputError(f"unknown point '{p}'", file=mech.path, entry="--points",
                                 hint="points: " + ", ".join(names))
        self.points = tuple(p for p in mech.points if points is None or p.name in points)
        self.link = {name: i for i, name in enumerate(structure.links)}
        self.params = tuple(p.symbol for p in mech.parameters)
        self.thetas = tuple(kin.theta[a] for a in range(1, structure.m + 1))
        self.deltas = tuple(kin.delta[a] for a in kin.unknowns)

    # -- symbolic pieces ---------------------------------------------------------------------------
    def compliant_angles(self) -> dict[int, sp.Expr]:
        kin = self.kin
        return {a: kin.theta[a] + (kin.delta[a] if a in kin.unknowns else 0) for a in kin.theta}

    def delta_phi(self, link: int) -> sp.Expr:
        """δφ_link = Σ of the paper-oriented δ over the direct path (inputs have δ = 0)."""
        kin = self.kin
        return sp.Add(*(kin.hinges[b].sign * kin.delta[b] for b in
                        self.structure.tree_path(link) if b in kin.unknowns))

    @cached_property
    def residual(self) -> sp.Matrix:
        """Exact compliant loop closure in δ: angular rows, then x, y rows per loop."""
        kin = self.kin
        angles = self.compliant_angles()
        rows: list[sp.Expr] = []
        for c in kin.chords:
            rows.append(kin.angular_closure(c, {a: angles[a] - kin.theta[a] for a in angles}))
            rigid_part = [V.rot(kin.phi(i), V.rot_minus_identity(self.delta_phi(i), w))
                          for i, w in kin.loop_weights(c).items()]
            rows.extend(V.add(*rigid_part, kin.loop_deviation(c, angles)))
        return sp.Matrix(rows)

    @cached_property
    def rigid_residual(self) -> sp.Matrix:
        """Rigid loop closure relative to the as-fabricated pose, in the rigid angles θ:
        Φ q and Σ_i (Rot(φ_i) - I) V_i per loop, exact there since the fabricated pose closes."""
        kin = self.kin
        rows: list[sp.Expr] = []
        for c in kin.chords:
            rows.append(kin.angular_closure(c))
            rows.extend(V.add(*(V.rot_minus_identity(kin.phi(i), w)
                                for i, w in kin.loop_weights(c).items())))
        return sp.Matrix(rows)

    @cached_property
    def jacobian(self) -> sp.Matrix:
        """∂F/∂δ of the exact closure, built from its structure rather than by differentiating:
        rigid part: column a gets s_a Rot(φ_i + δφ_i) J V_i from each link i whose path holds a;
        plates: Δz_b gives its model derivative (a = b) and J Δz_b (a on the path of P_b)."""
        return self._closure_jacobian(exact=True)

    @cached_property
    def linear_system(self) -> tuple[sp.Matrix, sp.Matrix]:
        """(A, r): the first-order closure A δ + r = 0; A is the rigid loop Jacobian at δ = 0,
        r = Φ Δz at the rigid pose."""
        rows_r: list[sp.Expr] = []
        for c in self.kin.chords:
            rows_r.append(sp.Integer(0))
            rows_r.extend(self.kin.loop_deviation(c))
        return self._closure_jacobian(exact=False), sp.Matrix(rows_r)

    def _closure_jacobian(self, exact: bool) -> sp.Matrix:
        kin, s = self.kin, self.structure
        col = {a: k for k, a in enumerate(kin.unknowns)}
        on_path = {i: set(s.tree_path(i)) & set(col) for i in range(s.n + 1)}
        angles = self.compliant_angles() if exact else kin.theta
        rows: list[list[sp.Expr]] = []
        for c in kin.chords:
            loop = s.loops[c - s.n - 1]
            angular = [sp.Integer(0)] * len(col)
            px, py = [sp.Integer(0)] * len(col), [sp.Integer(0)] * len(col)

            def add(a: int, vec: V.Vec) -> None:
                px[col[a]] += vec[0]
                py[col[a]] += vec[1]

            for b in range(1, s.m + 1):
                if loop[b - 1] and b in col:
                    angular[col[b]] += int(loop[b - 1]) * kin.hinges[b].sign
            for i, w in kin.loop_weights(c).items():
                turn = kin.phi(i) + (self.delta_phi(i) if exact else 0)
                d = V.rot(turn, V.perp(w))
                for a in on_path[i]:
                    add(a, V.scale(kin.hinges[a].sign, d))
            if exact:
                for b in range(1, s.m + 1):
                    coeff = int(loop[b - 1])
                    if not coeff:
                        continue
                    h = kin.hinges[b]
                    phi_p = kin.phi(h.P) + self.delta_phi(h.P)
                    dz = h.delta_z(angles[b], phi_p)
                    for a in on_path[h.P]:
                        add(a, V.scale(coeff * kin.hinges[a].sign, V.perp(dz)))
                    if b in col:
                        rate = V.add(V.scale(_theta_derivative(h.df).subs(THETA, angles[b]), h.u),
                                     V.scale(_theta_derivative(h.dg).subs(THETA, angles[b]),
                                             V.perp(h.u)))
                        add(b, V.scale(coeff * h.sign, V.rot(phi_p, rate)))
            rows.extend([angular, px, py])
        return sp.Matrix(rows) if rows else sp.zeros(0, len(col))

    def point_deviation(self, name: str, level: str) -> V.Vec:
        """ΔX of the named point at `level`, in θ (rigid angles), δ and the parameters."""
        kin = self.kin
        point = self.mechanism.point(name)
        k = self.link[point.link]
        if level == "paper":
            return kin.path_deviation(k)
        weights = kin.weights(k, point.at)
        if level == "first_order":
            lin = [V.scale(self.delta_phi(i), V.rot(kin.phi(i), V.perp(w)))
                   for i, w in weights.items()]
            return V.add(*lin, kin.path_deviation(k))
        exact = [V.rot(kin.phi(i), V.rot_minus_identity(self.delta_phi(i), w))
                 for i, w in weights.items()]
        return V.add(*exact, kin.path_deviation(k, self.compliant_angles()))

    def link_rotation(self, link: int) -> sp.Expr:
        """Rotation φ of `link` from the as-fabricated pose in the rigid mechanism: Σ q_b over the
        direct path [s_0, s_link] (the sum behind J* in (4.7))."""
        return self.kin.phi(link)

    def link_deviation(self, link: int, level: str) -> sp.Expr:
        """δφ of `link`: how much further the compliant link turns, Σ ± δ_b over its direct path,
        written from δ itself (never a difference of two rotations); zero where the level keeps
        the rigid angles (`paper`)."""
        return self.delta_phi(link) if levels.get(level).needs_delta else sp.Integer(0)

    def point_rigid(self, name: str) -> V.Vec:
        point = self.mechanism.point(name)
        return self.kin.rigid_position(self.link[point.link], point.at)


@lru_cache(maxsize=None)
def _theta_derivative(expr: sp.Expr) -> sp.Expr:
    """d/dθ of a hinge model's Δf or Δg (its kernels differentiate into stable kernels)."""
    return sp.diff(expr, THETA)

