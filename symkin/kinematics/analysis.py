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

Numbers come from :mod:`symkin.studies.evaluation` (mpmath) and the generated code
(:mod:`symkin.codegen`).
"""

from __future__ import annotations

from collections.abc import Sequence
from functools import cache, cached_property

import mpmath
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
        # each actuator's point of action, tracked as a hidden point (docs/levels.md,
        # "Actuators"): the evaluators find the strokes from its positions
        self.points += tuple(mech.point(a.point) for a in mech.actuators)
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

    # -- which closure rows are solved (redundant loops) -------------------------------------------
    #
    # Every loop gives three rows: its angular closure (5.1), then x and y (5.3). With as many
    # rows as non-input hinges the closure is square. A redundant mechanism (a parallelogram with
    # a third leg, docs/levels.md) has more rows than unknowns, some of them dependent: the rows
    # solved are chosen once, at the as-fabricated pose (symkin.core.settings, step 0), and the
    # others are checked at the solution (:meth:`consistency`). Every matrix and residual below
    # holds the solved rows only, in their order.

    @cached_property
    def rows(self) -> tuple[int, ...]:
        """Indices (3 per loop: angular, x, y) of the closure rows every solve uses."""
        total = 3 * len(self.kin.chords)
        k = len(self.kin.unknowns)
        if total <= k:
            return tuple(range(total))
        return select_rows(self._partials_all("first_order", "delta", self.kin.unknowns), k, self)

    @cached_property
    def dropped(self) -> tuple[int, ...]:
        """The closure rows left out of the solves (redundant ones): checked at the solution."""
        return tuple(r for r in range(3 * len(self.kin.chords)) if r not in self.rows)

    @property
    def redundant(self) -> bool:
        """Some loop-closure rows are dependent (more rows than non-input hinges)."""
        return bool(self.dropped)

    def row_chord(self, row: int) -> int:
        """The chord whose loop a closure row belongs to."""
        return self.kin.chords[row // 3]

    @cached_property
    def angular_rows(self) -> tuple[int, ...]:
        """Positions, among the solved rows, of the loops' angular closures (the winding rule)."""
        return tuple(k for k, r in enumerate(self.rows) if r % 3 == 0)

    def _pick(self, rows: list) -> sp.Matrix:
        return sp.Matrix([rows[r] for r in self.rows])

    def _residual_all(self) -> list[sp.Expr]:
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
        return rows

    def _rigid_residual_all(self) -> list[sp.Expr]:
        kin = self.kin
        rows: list[sp.Expr] = []
        for c in kin.chords:
            rows.append(kin.angular_closure(c))
            rows.extend(
                V.add(
                    *(V.rot_minus_identity(kin.phi(i), w) for i, w in kin.loop_weights(c).items())
                )
            )
        return rows

    @cached_property
    def residual(self) -> sp.Matrix:
        """Exact compliant loop closure in δ: angular rows, then x, y rows per loop (the solved
        rows)."""
        return self._pick(self._residual_all())

    @cached_property
    def rigid_residual(self) -> sp.Matrix:
        """Rigid loop closure relative to the as-fabricated pose, in the rigid angles θ:
        Φ q and Σ_i (Rot(φ_i) - I) V_i per loop, exact there since the fabricated pose closes
        (the solved rows)."""
        return self._pick(self._rigid_residual_all())

    # -- the size of a row's terms (the stopping rule and the redundancy check) --------------------

    def _plate_size(self, chord: int, angles: dict[int, sp.Expr] | None = None) -> sp.Expr:
        """Σ_b |Φ_cb| (|Δz_b,x| + |Δz_b,y|) around the loop of `chord` at `angles` (default the
        rigid ones): the size of Φ Δz without its cancellation."""
        kin, s = self.kin, self.structure
        angles = angles or kin.theta
        row = s.loops[chord - s.n - 1]
        terms = []
        for b in range(1, s.m + 1):
            if row[b - 1]:
                dz = kin.hinges[b].delta_z(angles[b], kin.phi(kin.hinges[b].P, angles))
                terms += [sp.Abs(dz[0]), sp.Abs(dz[1])]
        return sp.Add(*terms)

    def _link_size(self, chord: int, turn) -> sp.Expr:
        """Σ_i |turn(i)| (|V_i,x| + |V_i,y|) over the loop of `chord`: the size of its links'
        terms when link i turns by turn(i)."""
        return sp.Add(
            *(
                sp.Abs(turn(i)) * (sp.Abs(w[0]) + sp.Abs(w[1]))
                for i, w in self.kin.loop_weights(chord).items()
                if i != 0
            )
        )

    @cached_property
    def closure_scale(self) -> sp.Matrix:
        """S_r of the stopping rule (symkin.core.settings, 3b) for every solved row: the size of
        the plate deviations in it at the rigid pose (0 for an angular row)."""
        sizes = []
        for c in self.kin.chords:
            plates = self._plate_size(c)
            sizes += [sp.Integer(0), plates, plates]
        return self._pick(sizes)

    def consistency(self, form: str) -> tuple[sp.Matrix, sp.Matrix]:
        """(residual, size of its terms) of the dropped rows (redundant loops) at `form`:
        'rigid' (the rigid closure in θ), 'first_order' (A δ + r) or 'exact' (F(δ)); each row
        must vanish to SOLVER's `consistent` times its size (symkin.core.settings, step 4)."""
        return self.closure_terms(form, self.dropped)

    def closure_terms(self, form: str, rows: Sequence[int]) -> tuple[sp.Matrix, sp.Matrix]:
        """(residual, size of its terms) of the closure rows `rows` (3 per loop, every row
        counted) at `form`: 'rigid' (the rigid closure in θ, sizes Σ_i |φ_i| (|V_i,x| + |V_i,y|)
        and Σ_b |θ_b|), 'first_order' (A δ + r) or 'exact' (F(δ)), sizes of the links' terms
        with δφ_i, plus the plates' (:meth:`_plate_size`), and Σ_b |δ_b| for an angular row."""
        kin = self.kin
        if not rows:
            return sp.zeros(0, 1), sp.zeros(0, 1)
        if form == "rigid":
            residual = self._rigid_residual_all()
        elif form == "first_order":
            a = self._partials_all("first_order", "delta", kin.unknowns)
            d = sp.Matrix([kin.delta[b] for b in kin.unknowns])
            r = []
            for c in kin.chords:
                r += [sp.Integer(0), *kin.loop_deviation(c)]
            residual = list(a * d + sp.Matrix(r))
        else:
            residual = self._residual_all()
        angles = self.compliant_angles() if form == "exact" else kin.theta
        sizes = {}
        for c in sorted({self.row_chord(r) for r in rows}):
            loop = self.structure.loops[c - self.structure.n - 1]
            hinges = [b for b in range(1, len(loop) + 1) if loop[b - 1]]
            if form == "rigid":
                angular = sp.Add(*(sp.Abs(kin.theta[b]) for b in hinges))
                positional = self._link_size(c, kin.phi)
            else:
                angular = sp.Add(*(sp.Abs(kin.delta[b]) for b in hinges if b in kin.unknowns))
                positional = self._link_size(c, self.delta_phi) + self._plate_size(c, angles)
            sizes[c] = (angular, positional, positional)
        return (
            sp.Matrix([residual[r] for r in rows]),
            sp.Matrix([sizes[self.row_chord(r)][r % 3] for r in rows]),
        )

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
        return (
            self.closure_partials("first_order", "delta", self.kin.unknowns),
            self._pick(rows_r),
        )

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
        a in `columns`: an angular row (5.1), then x, y rows (5.3) per loop (the solved rows)."""
        full = self._partials_all(form, wrt, columns)
        if not self.dropped:
            return full
        return full.extract(list(self.rows), list(range(full.cols)))

    def _partials_all(self, form: str, wrt: str, columns: Sequence) -> sp.Matrix:
        """:meth:`closure_partials` with every row, redundant ones included."""
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


def select_rows(full: sp.Matrix, k: int, analysis: Analysis) -> tuple[int, ...]:
    """`k` independent rows of the closure Jacobian `full` (3 rows per loop, non-input hinges
    as columns) at the as-fabricated pose and the file's parameter values: a pivoted
    Gram–Schmidt in 30 digits on the rows scaled to unit size, the angular rows first (they are
    linear and exact), then the positional row with the largest part independent of those kept,
    until `k` are kept (symkin.core.settings, step 0). Fewer than `k` independent rows leave the
    pose undetermined (the inputs do not fix it): the rows found are returned, and the solves
    meet a singular Jacobian that the file checks refuse first."""
    at_rest = dict.fromkeys(analysis.thetas, 0)
    values = full.xreplace(at_rest).subs(analysis.mechanism.defaults)
    with mpmath.workdps(30):
        rows = []
        for i in range(values.rows):
            row = [mpmath.mpf(sp.N(e, 35)) for e in values.row(i)]
            size = max((abs(x) for x in row), default=mpmath.mpf(0))
            rows.append([x / size for x in row] if size else row)
        basis: list[list] = []
        kept: list[int] = []
        tol = mpmath.mpf(10) ** -12

        def remainder(row: list) -> list:
            out = list(row)
            for q in basis:
                dot = mpmath.fsum(a * b for a, b in zip(out, q))
                out = [a - dot * b for a, b in zip(out, q)]
            return out

        def keep(i: int, rest: list) -> None:
            norm = mpmath.sqrt(mpmath.fsum(x * x for x in rest))
            basis.append([x / norm for x in rest])
            kept.append(i)

        def norm(v: list):
            return mpmath.sqrt(mpmath.fsum(x * x for x in v))

        for i in range(0, len(rows), 3):  # the angular rows, in order
            rest = remainder(rows[i])
            if len(kept) < k and norm(rest) > tol:
                keep(i, rest)
        candidates = [i for i in range(len(rows)) if i % 3]
        while len(kept) < k and candidates:
            rests = {i: remainder(rows[i]) for i in candidates}
            best = max(candidates, key=lambda i: norm(rests[i]))  # the first of equals
            if not norm(rests[best]) > tol:
                break
            keep(best, rests[best])
            candidates.remove(best)
    return tuple(sorted(kept))


@cache
def _theta_derivative(expr: sp.Expr) -> sp.Expr:
    """d/dθ of a hinge model's Δf or Δg (its kernels differentiate into stable kernels)."""
    return sp.diff(expr, THETA)
