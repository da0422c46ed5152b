"""Rigid position solution: Assur-group (dyad) decomposition solved in closed form
(docs/levels.md, "Rigid solution"; it replaces the paper's angle elimination of section 5).

Links joined by input hinges are welded into bodies (their relative angle is given). Starting from
the ground's body, a dyad is a pair of unknown bodies joined by one hinge, each hinged once to a
known body (an RRR group): its middle joint is the intersection of two circles, written with atan2
and the assembly mode (branch) taken from the as-fabricated pose. Groups that are not dyads (a
triad, say) are left to a Newton solve with continuation from the as-fabricated pose.
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

from ..core import vectors as V
from ..core.errors import InputError
from ..core.vectors import Vec
from .positions import Kinematics


@dataclass(frozen=True)
class Dyad:
    """An RRR dyad: bodies B1 (hinges h1, h2) and B2 (hinges h2, h3); h1, h3 on known bodies."""

    index: int
    bodies: tuple[tuple[int, ...], tuple[int, ...]]
    hinges: tuple[int, int, int]
    chord: int  # the fundamental loop this dyad closes
    branch: int  # +1: the middle joint lies left of h1 -> h3 (as fabricated)
    reach: sp.Symbol  # (h/d)^2; negative: the loop cannot close (out of the assembly range)
    margin: sp.Symbol  # |sin| of the angle at the middle joint: 0 at a toggle position


@dataclass(frozen=True)
class RigidSolution:
    """Named assignments giving every link rotation φ_i in closed form, when dyads cover all."""

    assignments: tuple[tuple[sp.Symbol, sp.Expr], ...]
    phi: dict[int, sp.Expr] | None  # None: no closed form, solve numerically
    dyads: tuple[Dyad, ...]
    # non-input hinge -> the input hinges its closed-form angle reads: with all of them zero
    # the angle is exactly zero (the formulas round to noise there); None without closed form
    depends: dict[int, frozenset[int]] | None = None

    @property
    def closed_form(self) -> bool:
        return self.phi is not None


class _Bodies:
    """Links welded by input hinges, each body with its links' rotations and local positions."""

    def __init__(self, kin: Kinematics) -> None:
        s = kin.structure
        self.kin = kin
        self.body_of: dict[int, int] = {}
        self.rho: dict[int, sp.Expr] = {}
        self.pivot: dict[int, tuple[Vec, Vec]] = {}  # link -> (as-fabricated pivot, local pivot)
        for root in range(s.n + 1):
            if root in self.body_of:
                continue
            self.body_of[root] = root
            self.rho[root] = sp.Integer(0)
            self.pivot[root] = (V.ZERO, V.ZERO)
            frontier = [root]
            while frontier:
                link = frontier.pop(0)
                for a in kin.inputs:
                    h = kin.hinges[a]
                    if link in (h.P, h.M):
                        other = h.M if link == h.P else h.P
                        if other in self.body_of:
                            continue
                        self.body_of[other] = root
                        turn = kin.theta[a] if link == h.P else -kin.theta[a]
                        self.rho[other] = self.rho[link] + turn
                        self.pivot[other] = (h.centre, self.local(link, h.centre))
                        frontier.append(other)

    def members(self, body: int) -> tuple[int, ...]:
        return tuple(sorted(k for k, b in self.body_of.items() if b == body))

    def local(self, link: int, point: Vec) -> Vec:
        """Position of `point` (fixed in `link`) in its body's root frame."""
        fab, loc = self.pivot[link]
        return V.add(loc, V.rot(self.rho[link], V.sub(point, fab)))


def solve(kin: Kinematics) -> RigidSolution:
    """Decompose into dyads and write the closed-form rigid solution as named assignments."""
    s = kin.structure
    bodies = _Bodies(kin)
    defaults = kin.mechanism.defaults
    # known body -> (rotation of its root, anchor in the root frame, anchor's absolute position)
    known: dict[int, tuple[sp.Expr, Vec, Vec]] = {0: (sp.Integer(0), V.ZERO, V.ZERO)}
    assignments: list[tuple[sp.Symbol, sp.Expr]] = []
    dyads: list[Dyad] = []

    def absolute(link: int, point: Vec) -> Vec:
        phi, anchor_local, anchor_abs = known[bodies.body_of[link]]
        return V.add(anchor_abs, V.rot(phi, V.sub(bodies.local(link, point), anchor_local)))

    def assign(name: str, expr: sp.Expr) -> sp.Symbol:
        symbol = sp.Symbol(name, real=True)
        assignments.append((symbol, expr))
        return symbol

    def hinges_between(body: int, others: set[int]) -> list[int]:
        """Non-input hinges joining `body` to one of the bodies `others`."""
        out = []
        for a in kin.unknowns:
            pb, mb = bodies.body_of[kin.hinges[a].P], bodies.body_of[kin.hinges[a].M]
            if (pb == body and mb in others and mb != body) or (
                mb == body and pb in others and pb != body
            ):
                out.append(a)
        return out

    progress = True
    while progress and len(known) < len(set(bodies.body_of.values())):
        progress = False
        for h2 in kin.unknowns:
            hinge = kin.hinges[h2]
            b1, b2 = bodies.body_of[hinge.P], bodies.body_of[hinge.M]
            if b1 == b2 or b1 in known or b2 in known:
                continue
            to_known1 = hinges_between(b1, set(known))
            to_known2 = hinges_between(b2, set(known))
            if len(to_known1) != 1 or len(to_known2) != 1 or len(hinges_between(b1, {b2})) != 1:
                continue
            h1, h3 = to_known1[0], to_known2[0]
            k = len(dyads) + 1
            dyads.append(
                _dyad(kin, bodies, k, (b1, b2), (h1, h2, h3), absolute, assign, known, defaults)
            )
            progress = True
            break
        if progress:
            continue
        # A redundant link (a third parallel leg): one unknown body hinged to known bodies at
        # two or more hinges. The line between two of those hinges fixes its rotation; the
        # other constraints (the distance between them, any further hinge) are the dropped rows
        # of the closure, checked at the solution (symkin.core.settings, step 4).
        for body in sorted(set(bodies.body_of.values()) - set(known)):
            ties = hinges_between(body, set(known))
            if len(ties) >= 2:
                _bar(kin, bodies, body, ties[:2], absolute, assign, known)
                progress = True
                break

    if len(known) < len(set(bodies.body_of.values())):
        return RigidSolution(tuple(assignments), None, tuple(dyads))
    phi = {}
    for link in range(s.n + 1):
        root_phi = known[bodies.body_of[link]][0]
        phi[link] = root_phi + bodies.rho[link]
    inputs = {kin.theta[a]: a for a in kin.inputs}
    reads: dict[sp.Symbol, frozenset[int]] = {}

    def depends(expr: sp.Expr) -> frozenset[int]:
        out: set[int] = set()
        for symbol in sp.sympify(expr).free_symbols:
            out |= {inputs[symbol]} if symbol in inputs else reads.get(symbol, frozenset())
        return frozenset(out)

    for symbol, expr in assignments:
        reads[symbol] = depends(expr)
    return RigidSolution(
        tuple(assignments),
        phi,
        tuple(dyads),
        {a: depends(phi[kin.hinges[a].M] - phi[kin.hinges[a].P]) for a in kin.unknowns},
    )


def _dyad(
    kin: Kinematics,
    bodies: _Bodies,
    k: int,
    pair: tuple[int, int],
    hinges: tuple[int, int, int],
    absolute,
    assign,
    known: dict,
    defaults: dict,
) -> Dyad:
    """Closed-form RRR dyad; adds its named assignments and marks both bodies known."""
    b1, b2 = pair
    h1, h2, h3 = (kin.hinges[a] for a in hinges)
    on1 = lambda h: h.P if bodies.body_of[h.P] == b1 else h.M  # noqa: E731
    on2 = lambda h: h.P if bodies.body_of[h.P] == b2 else h.M  # noqa: E731
    known1 = lambda h: h.M if bodies.body_of[h.P] == b1 else h.P  # noqa: E731
    known2 = lambda h: h.M if bodies.body_of[h.P] == b2 else h.P  # noqa: E731
    # As-fabricated branch: which side of the line h1 -> h3 the middle joint h2 lies on.
    side = V.cross(V.sub(h3.centre, h1.centre), V.sub(h2.centre, h1.centre)).subs(defaults)
    side = sp.N(side, 30)
    names = f"{h1.name}, {h2.name}, {h3.name}"
    if abs(side) < 1e-12 * max(
        1e-300,
        float(sp.N(V.dot(V.sub(h3.centre, h1.centre), V.sub(h3.centre, h1.centre)).subs(defaults))),
    ):
        raise InputError(
            f"the hinges {names} are collinear in the as-fabricated pose: a toggle "
            "position, where the assembly mode is undefined",
            file=kin.mechanism.path,
            entry=f"[[hinge]] '{h2.name}'",
            hint="move the middle hinge off the line through the other two",
        )
    branch = 1 if side > 0 else -1
    # Body-local geometry: lengths of the two dyad members (may depend on welded inputs).
    l1a, l1b = bodies.local(on1(h1), h1.centre), bodies.local(on1(h2), h2.centre)
    l2b, l2c = bodies.local(on2(h2), h2.centre), bodies.local(on2(h3), h3.centre)
    r1sq = sp.expand(V.dot(V.sub(l1b, l1a), V.sub(l1b, l1a)))
    r2sq = sp.expand(V.dot(V.sub(l2b, l2c), V.sub(l2b, l2c)))
    ax, ay = absolute(known1(h1), h1.centre)
    cx, cy = absolute(known2(h3), h3.centre)
    A = (assign(f"dyad{k}_ax", ax), assign(f"dyad{k}_ay", ay))
    C = (assign(f"dyad{k}_cx", cx), assign(f"dyad{k}_cy", cy))
    d = V.sub(C, A)
    dsq = assign(f"dyad{k}_dsq", V.dot(d, d))
    along = assign(f"dyad{k}_along", (r1sq - r2sq + dsq) / (2 * dsq))  # a/d
    reach = assign(f"dyad{k}_reach", r1sq / dsq - along**2)  # (h/d)^2
    across = assign(f"dyad{k}_across", branch * sp.sqrt(reach))  # ±h/d
    B = (
        assign(f"dyad{k}_bx", A[0] + along * d[0] - across * d[1]),
        assign(f"dyad{k}_by", A[1] + along * d[1] + across * d[0]),
    )
    margin = assign(f"dyad{k}_margin", dsq * sp.Abs(across) / sp.sqrt(r1sq * r2sq))
    v1, w1 = V.sub(l1b, l1a), V.sub(B, A)
    v2, w2 = V.sub(l2b, l2c), V.sub(B, C)
    phi1 = assign(f"dyad{k}_phi1", sp.atan2(V.cross(v1, w1), V.dot(v1, w1)))
    phi2 = assign(f"dyad{k}_phi2", sp.atan2(V.cross(v2, w2), V.dot(v2, w2)))
    known[b1] = (phi1, l1a, A)
    known[b2] = (phi2, l2c, C)
    chord = _closing_chord(kin, {a.label for a in (h1, h2, h3)})
    return Dyad(
        k,
        (bodies.members(b1), bodies.members(b2)),
        (h1.label, h2.label, h3.label),
        chord,
        branch,
        reach,
        margin,
    )


def _bar(
    kin: Kinematics,
    bodies: _Bodies,
    body: int,
    hinges: list[int],
    absolute,
    assign,
    known: dict,
) -> None:
    """Place an unknown body by two of its hinges to known bodies: its rotation turns the
    as-fabricated line between them onto their present line (atan2); marks the body known."""
    h1, h3 = (kin.hinges[a] for a in hinges)
    own = lambda h: h.P if bodies.body_of[h.P] == body else h.M  # noqa: E731
    other = lambda h: h.M if bodies.body_of[h.P] == body else h.P  # noqa: E731
    la, lc = bodies.local(own(h1), h1.centre), bodies.local(own(h3), h3.centre)
    ax, ay = absolute(other(h1), h1.centre)
    cx, cy = absolute(other(h3), h3.centre)
    k = body
    A = (assign(f"bar{k}_ax", ax), assign(f"bar{k}_ay", ay))
    C = (assign(f"bar{k}_cx", cx), assign(f"bar{k}_cy", cy))
    v, w = V.sub(lc, la), V.sub(C, A)
    phi = assign(f"bar{k}_phi", sp.atan2(V.cross(v, w), V.dot(v, w)))
    known[body] = (phi, la, A)


def _closing_chord(kin: Kinematics, hinges: set[int]) -> int:
    """The chord whose fundamental loop holds most of `hinges` (first such, by label)."""
    best = max(kin.chords, key=lambda c: (len(hinges & set(kin.structure.loop_hinges(c))), -c))
    return best
