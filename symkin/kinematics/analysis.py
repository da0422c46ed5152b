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
from functools import cache, cached_property

import sympy as sp

from ..core import levels
from ..core import vectors as V
from ..graph.structure import Structure
from ..model.hinges import THETA
from . import dyads as rigid_solver
from .positions import Kinematics


class Analysis:
    """The symbolic deviation of a mechanism's points at every level."""

    def __init__(
        self, structure: Structure, points: Sequence[str] | None = None, plate=None
    ) -> None:
        self.structure = structure
        self.mechanism = mech = structure.mechanism
        self.kin = kin = Kinematics(structure, plate)
        self.rigid = rigid_solver.solve(kin)
        mech.check_points(points or ())
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
        return sp.Add(
            *(
                kin.hinges[b].sign * kin.delta[b]
                for b in self.structure.tree_path(link)
                if b in kin.unknowns
            )
        )

    @cached_property
    def residual(self) -> sp.Matrix:
        """Exact compliant loop closure in δ: angular rows, then x, y rows per loop."""
        kin = self.kin
        angles = self.compliant_angles()
        rows: list[sp.Expr] = []
        for c in kin.chords:
            rows.append(kin.angular_closure(c, {a: angles[a] - kin.theta[a] for a in angles}))
            rigid_part = [
                V.rot(kin.phi(i), V.rot_minus_identity(self.delta_phi(i), w))
                for i, w in kin.loop_weights(c).items()
            ]
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
            rows.extend(
                V.add(
                    *(V.rot_minus_identity(kin.phi(i), w) for i, w in kin.loop_weights(c).items())
                )
            )
        return sp.Matrix(rows)

    @cached_property
    def jacobian(self) -> sp.Matrix:
        """∂F/∂δ of the exact closure, built from its structure rather than by differentiating
        (:meth:`closure_partials`, form exact)."""
        return self.closure_partials("exact", "delta", self.kin.unknowns)

    @cached_property
    def linear_system(self) -> tuple[sp.Matrix, sp.Matrix]:
        """(A, r): the first-order closure A δ + r = 0; A is the rigid loop Jacobian at δ = 0,
        r = Φ Δz at the rigid pose."""
        rows_r: list[sp.Expr] = []
        for c in self.kin.chords:
            rows_r.append(sp.Integer(0))
            rows_r.extend(self.kin.loop_deviation(c))
        return self.closure_partials("first_order", "delta", self.kin.unknowns), sp.Matrix(rows_r)

    # -- partial derivatives from the structure ----------------------------------------------------
    #
    # Every quantity symkin solves for or reports has one shape: a sum over links of a rotated
    # constant vector U_i plus a sum of plate deviations c_b Δz_b. Loops take U_i = V^c_i and
    # c_b = Φ_cb, a point fixed in link k takes U_i = W_i and c_b = 1 on the direct path. The
    # forms differ in what the links contribute:
    #
    #   rigid        Σ Rot(φ_i) U_i  (or Σ (Rot(φ_i) - I) U_i: the same derivatives); no plates
    #   paper        Σ c_b Δz_b(θ_b, φ_P)                                          (4.8)
    #   first_order  Σ δφ_i Rot(φ_i) J U_i + Σ c_b Δz_b(θ_b, φ_P)
    #   exact        Σ Rot(φ_i)(Rot(δφ_i) - I) U_i + Σ c_b Δz_b(θ_b + δ_b, φ_P + δφ_P)
    #
    # with J = Rot(π/2) and φ_i = Σ s_a θ_a, δφ_i = Σ s_a δ_a over the direct path of link i.
    # Their partial derivatives by a hinge angle θ_a or a difference δ_a follow term by term
    # (below), stay free of cancellation (an O(l) quantity has O(l) derivatives written as such)
    # and cost no symbolic differentiation of large expressions; by a parameter p, only the
    # constant vectors U_i and the plates' Δz_b are differentiated, each a small expression.

    def chain_partials(
        self,
        weights: dict[int, V.Vec],
        plates: dict[int, int],
        form: str,
        wrt: str,
        columns: Sequence,
        relative: bool = False,
    ) -> list[V.Vec]:
        """∂X/∂θ_a (wrt 'theta'), ∂X/∂δ_a (wrt 'delta') for every hinge a of `columns`, or
        ∂X/∂p (wrt 'param') for every parameter symbol p of `columns`, X the quantity of `form`
        with link vectors `weights` and plate coefficients `plates` (`relative`: the rigid form
        is Σ (Rot(φ_i) - I) U_i, the closure relative to the as-fabricated pose)."""
        kin, s = self.kin, self.structure
        exact = form == "exact"
        col = {a: k for k, a in enumerate(columns)}
        # Terms are collected and summed once: adding them one by one re-flattens the growing
        # sum each time (quadratic in the number of links on a long loop).
        out: list[tuple[list[sp.Expr], list[sp.Expr]]] = [([], []) for _ in columns]

        def add(a, vec: V.Vec) -> None:
            out[col[a]][0].append(vec[0])
            out[col[a]][1].append(vec[1])

        if wrt == "param":
            self._parameter_partials(weights, plates, form, columns, relative, add)
        elif form != "paper":
            for i, w in weights.items():
                hits = [a for a in s.tree_path(i) if a in col]
                if not hits:
                    continue
                if form == "rigid" or (form == "first_order" and wrt == "delta"):
                    d = V.rot(kin.phi(i), V.perp(w))
                elif form == "first_order":
                    d = V.scale(-self.delta_phi(i), V.rot(kin.phi(i), w))
                elif wrt == "delta":
                    d = V.rot(kin.phi(i) + self.delta_phi(i), V.perp(w))
                else:
                    d = V.rot(kin.phi(i), V.perp(V.rot_minus_identity(self.delta_phi(i), w)))
                for a in hits:
                    add(a, V.scale(kin.hinges[a].sign, d))
        if form != "rigid" and (wrt == "theta" or (exact and wrt == "delta")):
            angles = self.compliant_angles() if exact else kin.theta
            for b, coeff in plates.items():
                h = kin.hinges[b]
                phi_p = kin.phi(h.P) + (self.delta_phi(h.P) if exact else 0)
                dz = h.delta_z(angles[b], phi_p)
                for a in s.tree_path(h.P):
                    if a in col:
                        add(a, V.scale(coeff * kin.hinges[a].sign, V.perp(dz)))
                if b in col:
                    rate = V.add(
                        V.scale(_theta_derivative(h.df).subs(THETA, angles[b]), h.u),
                        V.scale(_theta_derivative(h.dg).subs(THETA, angles[b]), V.perp(h.u)),
                    )
                    add(b, V.scale(coeff * h.sign, V.rot(phi_p, rate)))
        return [(sp.Add(*x), sp.Add(*y)) for x, y in out]

    def _parameter_partials(
        self,
        weights: dict[int, V.Vec],
        plates: dict[int, int],
        form: str,
        params: Sequence[sp.Symbol],
        relative: bool,
        add,
    ) -> None:
        """chain_partials by the parameters: the link terms are linear in U_i, so they take
        ∂U_i/∂p in place of U_i; each plate contributes ∂Δz_b/∂p."""
        kin, exact = self.kin, form == "exact"
        for i, w in weights.items():
            free = sp.sympify(w[0]).free_symbols | sp.sympify(w[1]).free_symbols
            for p in params:
                if p not in free:
                    continue
                dw = (sp.diff(w[0], p), sp.diff(w[1], p))
                if form == "rigid":
                    d = V.rot_minus_identity(kin.phi(i), dw) if relative else V.rot(kin.phi(i), dw)
                elif form == "first_order":
                    d = V.scale(self.delta_phi(i), V.rot(kin.phi(i), V.perp(dw)))
                elif exact:
                    d = V.rot(kin.phi(i), V.rot_minus_identity(self.delta_phi(i), dw))
                else:
                    continue
                add(p, d)
        if form == "rigid":
            return
        angles = self.compliant_angles() if exact else kin.theta
        for b, coeff in plates.items():
            h = kin.hinges[b]
            phi_p = kin.phi(h.P) + (self.delta_phi(h.P) if exact else 0)
            dz = h.delta_z(angles[b], phi_p)
            free = dz[0].free_symbols | dz[1].free_symbols
            for p in params:
                if p in free:
                    add(p, V.scale(coeff, (sp.diff(dz[0], p), sp.diff(dz[1], p))))

    def closure_partials(self, form: str, wrt: str, columns: Sequence) -> sp.Matrix:
        """Partial derivatives of the loop closure of `form` (rigid: the rigid closure relative
        to the as-fabricated pose; first_order: A δ + r; exact: the residual F) by θ_a or δ_a,
        a in `columns`: an angular row (5.1), then x, y rows (5.3) per loop."""
        kin, s = self.kin, self.structure
        rows: list[list[sp.Expr]] = []
        for c in kin.chords:
            loop = s.loops[c - s.n - 1]
            # (5.1) is linear: Σ Φ_cb s_b θ_b (rigid) or Σ Φ_cb s_b δ_b (the others)
            angular = [
                sp.Integer(int(loop[a - 1]) * kin.hinges[a].sign)
                if wrt != "param" and (wrt == "delta") != (form == "rigid")
                else sp.Integer(0)
                for a in columns
            ]
            plates = {b: int(loop[b - 1]) for b in range(1, s.m + 1) if loop[b - 1]}
            vecs = self.chain_partials(
                kin.loop_weights(c), plates, form, wrt, columns, relative=True
            )
            rows.extend([angular, [v[0] for v in vecs], [v[1] for v in vecs]])
        return sp.Matrix(rows) if rows else sp.zeros(0, len(columns))

    def point_partials(self, name: str, form: str, wrt: str, columns: Sequence) -> sp.Matrix:
        """2 × len(columns): partial derivatives of the named point's rigid position (form
        rigid) or of its deviation at the level `form` by θ_a or δ_a, a in `columns`."""
        point = self.mechanism.point(name)
        k = self.link[point.link]
        plates = dict.fromkeys(self.structure.tree_path(k), 1)
        vecs = self.chain_partials(self.kin.weights(k, point.at), plates, form, wrt, columns)
        return sp.Matrix([[v[0] for v in vecs], [v[1] for v in vecs]]) if vecs else sp.zeros(2, 0)

    def point_deviation(self, name: str, level: str) -> V.Vec:
        """ΔX of the named point at `level`, in θ (rigid angles), δ and the parameters."""
        kin = self.kin
        point = self.mechanism.point(name)
        k = self.link[point.link]
        if level == "paper":
            return kin.path_deviation(k)
        weights = kin.weights(k, point.at)
        if level == "first_order":
            lin = [
                V.scale(self.delta_phi(i), V.rot(kin.phi(i), V.perp(w))) for i, w in weights.items()
            ]
            return V.add(*lin, kin.path_deviation(k))
        exact = [
            V.rot(kin.phi(i), V.rot_minus_identity(self.delta_phi(i), w))
            for i, w in weights.items()
        ]
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


@cache
def _theta_derivative(expr: sp.Expr) -> sp.Expr:
    """d/dθ of a hinge model's Δf or Δg (its kernels differentiate into stable kernels)."""
    return sp.diff(expr, THETA)
