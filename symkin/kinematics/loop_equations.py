"""The scalar loop-closure equations of the rigid mechanism (paper §5: (5.1), (5.4)–(5.20)).

For the fundamental loop of a chord c, :meth:`Kinematics.positional_closure` gives the rigid part
of (5.3) as a vector sum Σ_i Rot(φ_i) V^c_i over the loop's links (the ground, φ_0 = 0, gives a
constant). Writing each constant vector in polar form, V^c_i = r_i (cos β_i, sin β_i) with
r_i = |V^c_i| and β_i = atan2(V_iy, V_ix), turns it into the two scalar equations the paper writes
for its examples ((5.4), (5.7), (5.11), (5.16), (5.19)):

    Σ_i r_i cos(φ_i + β_i) = 0,        Σ_i r_i sin(φ_i + β_i) = 0.

symkin's link frames are parallel to the absolute frame in the as-fabricated pose, so φ_i is the
rotation of link i from that pose and β_i is the as-fabricated direction of the link's loop
vector; the paper's link-aligned frames measure φ_i + β_i from the link's own x axis, which is
why its equations show no β (or show the constant angles α, β of the six-bar explicitly).

Moving the term of one link j to the other side, squaring and adding eliminates φ_j
((5.10), (5.13) and the unnumbered four-bar and nine-bar forms):

    r_j² − Σ_{i≠j} r_i² = 2 Σ_{i<k; i,k≠j} r_i r_k cos(φ_i + β_i − φ_k − β_k),

and φ_j itself follows from the two equations with the quadrant kept (erratum 6):

    φ_j + β_j = atan2(−Σ_{i≠j} r_i sin(φ_i + β_i), −Σ_{i≠j} r_i cos(φ_i + β_i)).

Which link is eliminated (the rule of :func:`eliminated_link`): the loop link with the largest
label that carries a nonzero loop vector, is not the ground and whose rotation is not fixed by the
inputs alone (some hinge on its direct path [s_0, s_j] is not an input). This is the paper's choice
for the four-bar (link 3) and the nine-bar (links 6 and 8); for the six-bar the paper eliminates
links 3 and 2 instead: pass ``eliminate={6: 3, 7: 2}`` or call :meth:`LoopEquations.eliminating`.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass
from typing import NamedTuple

import sympy as sp

from .positions import Kinematics


class Term(NamedTuple):
    """One link's share of a loop: Rot(φ_i) V_i = r_i (cos(φ_i + β_i), sin(φ_i + β_i))."""

    link: int
    r: sp.Expr
    beta: sp.Expr


@dataclass(frozen=True)
class LoopEquations:
    """The closure equations of the fundamental loop of one chord, in the paper's scalar form.

    ``angular``, ``x`` and ``y`` are left-hand sides (each equation reads ``expr = 0``);
    ``squared`` and ``solved_angle`` are :class:`sympy.Eq` objects.
    """

    chord: int  # label of the chord hinge that closes the loop
    angular: sp.Expr  # (5.1): Σ_b Φ_cb q_b
    terms: tuple[Term, ...]  # (i, r_i, β_i) by link label, zero vectors left out
    phi: tuple[sp.Expr, ...]  # φ_i of each term's link (0 for the ground), same order
    x: sp.Expr  # Σ r_i cos(φ_i + β_i)
    y: sp.Expr  # Σ r_i sin(φ_i + β_i)
    eliminated: int | None  # link j whose angle `squared` eliminates
    squared: sp.Eq | None  # r_j² − Σ_{i≠j} r_i² = 2 Σ_{i<k} r_i r_k cos(...)
    solved_angle: sp.Eq | None  # φ_j + β_j = atan2(−Σ_{i≠j} r_i sin, −Σ_{i≠j} r_i cos)

    @property
    def links(self) -> tuple[int, ...]:
        """Labels of the links with a term in the loop, in label order."""
        return tuple(t.link for t in self.terms)

    def term(self, link: int) -> Term:
        for t in self.terms:
            if t.link == link:
                return t
        raise KeyError(f"link {link} has no term in the loop of chord {self.chord}")

    def angle(self, link: int) -> sp.Expr:
        """φ_i + β_i: the absolute direction of link i's loop vector."""
        k = self.links.index(link)
        return self.phi[k] + self.terms[k].beta

    def eliminating(self, link: int) -> LoopEquations:
        """The same loop with the squared form and the solved angle taken for another link."""
        squared, solved = _eliminate(self.terms, self.phi, link)
        return dataclasses.replace(self, eliminated=link, squared=squared, solved_angle=solved)

    def equations(self) -> tuple[sp.Eq, sp.Eq, sp.Eq]:
        """(5.1) and the two positional equations as ``Eq(expr, 0)``."""
        return tuple(sp.Eq(e, 0, evaluate=False) for e in (self.angular, self.x, self.y))


def polar(vector: tuple[sp.Expr, sp.Expr]) -> tuple[sp.Expr, sp.Expr] | None:
    """(r, β) of a constant vector with r = |v|, β = atan2(v_y, v_x); None for the zero vector.

    Each component is simplified on its own (a few centre coordinates, never a big expression).
    """
    vx, vy = (sp.simplify(sp.sympify(v)) for v in vector)
    if vx == 0 and vy == 0:
        return None
    r = sp.sqrt(sp.simplify(vx**2 + vy**2))
    return r, sp.atan2(vy, vx)


def fixed_links(kin: Kinematics) -> frozenset[int]:
    """Links whose rotation the inputs alone fix: every hinge on the direct path is an input.

    The ground (empty path) is among them.
    """
    return frozenset(
        i
        for i in range(kin.structure.n + 1)
        if all(kin.hinges[b].is_input for b in kin.structure.tree_path(i))
    )


def eliminated_link(kin: Kinematics, links: tuple[int, ...]) -> int | None:
    """The rule for the link the squared form eliminates (see the module docstring).

    `links` are the loop's links with a nonzero loop vector. The largest label that is not fixed
    by the inputs; when every link of the loop is fixed (a loop the inputs alone close), the
    largest non-ground label; None if the loop has no moving link at all.
    """
    fixed = fixed_links(kin)
    free = [i for i in links if i != 0 and i not in fixed]
    if free:
        return max(free)
    moving = [i for i in links if i != 0]
    return max(moving) if moving else None


def _eliminate(terms: tuple[Term, ...], phi: tuple[sp.Expr, ...], j: int) -> tuple[sp.Eq, sp.Eq]:
    links = [t.link for t in terms]
    if j not in links:
        raise ValueError(f"link {j} has no term in this loop (links {links})")
    if j == 0:
        raise ValueError("the ground's angle is zero: it cannot be eliminated")
    k_j = links.index(j)
    others = [(t, p) for k, (t, p) in enumerate(zip(terms, phi)) if k != k_j]
    r_j = terms[k_j].r
    lhs = r_j**2 - sp.Add(*(t.r**2 for t, _ in others))
    pairs = []
    for a in range(len(others)):
        for b in range(a + 1, len(others)):
            (ti, pi), (tk, pk) = others[a], others[b]
            pairs.append(ti.r * tk.r * sp.cos(pi + ti.beta - pk - tk.beta))
    rhs = 2 * sp.Add(*pairs)
    sin_sum = sp.Add(*(t.r * sp.sin(p + t.beta) for t, p in others))
    cos_sum = sp.Add(*(t.r * sp.cos(p + t.beta) for t, p in others))
    squared = sp.Eq(lhs, rhs, evaluate=False)
    solved = sp.Eq(phi[k_j] + terms[k_j].beta, sp.atan2(-sin_sum, -cos_sum), evaluate=False)
    return squared, solved


def loop_equation(kin: Kinematics, chord: int, eliminate: int | None = None) -> LoopEquations:
    """The loop equations of one chord; `eliminate` overrides the eliminated link's rule."""
    weights = kin.loop_weights(chord)
    terms: list[Term] = []
    phi: list[sp.Expr] = []
    for i in sorted(weights):
        polar_form = polar(weights[i])
        if polar_form is None:
            continue
        terms.append(Term(i, *polar_form))
        phi.append(kin.phi(i) if i != 0 else sp.Integer(0))
    x = sp.Add(*(t.r * sp.cos(p + t.beta) for t, p in zip(terms, phi)))
    y = sp.Add(*(t.r * sp.sin(p + t.beta) for t, p in zip(terms, phi)))
    j = eliminate if eliminate is not None else eliminated_link(kin, tuple(t.link for t in terms))
    squared, solved = _eliminate(tuple(terms), tuple(phi), j) if j is not None else (None, None)
    return LoopEquations(
        chord=chord,
        angular=kin.angular_closure(chord),
        terms=tuple(terms),
        phi=tuple(phi),
        x=x,
        y=y,
        eliminated=j,
        squared=squared,
        solved_angle=solved,
    )


def loop_equations(
    kin: Kinematics, eliminate: Mapping[int, int] | None = None
) -> tuple[LoopEquations, ...]:
    """Loop equations for every chord, in chord-label order.

    `eliminate` maps a chord label to the link whose angle its squared form should eliminate
    (default: :func:`eliminated_link`).
    """
    eliminate = dict(eliminate or {})
    unknown = set(eliminate) - set(kin.chords)
    if unknown:
        raise ValueError(f"not chord labels: {sorted(unknown)} (chords {list(kin.chords)})")
    return tuple(loop_equation(kin, c, eliminate.get(c)) for c in kin.chords)


def latex(eq: LoopEquations, kin: Kinematics | None = None) -> str:
    """The loop's equations as a LaTeX ``aligned`` block (one line each), for reports."""

    def tex(e: sp.Basic) -> str:
        return sp.latex(e)

    name = f"chord {eq.chord}"
    if kin is not None:
        name = f"chord {eq.chord} ({kin.hinges[eq.chord].name})"
    lines = [
        rf"&\text{{loop of {name}}}",
        rf"&{tex(eq.angular)} = 0",
        rf"&{tex(eq.x)} = 0",
        rf"&{tex(eq.y)} = 0",
    ]
    if eq.squared is not None:
        lines.append(rf"&{tex(eq.squared.lhs)} = {tex(eq.squared.rhs)}")
        lines.append(rf"&{tex(eq.solved_angle.lhs)} = {tex(eq.solved_angle.rhs)}")
    return "\\begin{aligned}\n" + " \\\\\n".join(lines) + "\n\\end{aligned}"
