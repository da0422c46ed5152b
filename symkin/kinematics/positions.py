"""Kinematics of the rigid and the compliant mechanism (paper §3–§5), as sympy expressions.

Frames: every link frame is parallel to the absolute frame in the as-fabricated pose and has its
origin C_i at the absolute origin, so q*_a = 0, the paper's q_a is the hinge rotation from the
as-fabricated pose, and c_ia is the as-fabricated absolute position of hinge a's clamp on link i.
φ_i, the rotation of link i, is the sum of the (paper-oriented) hinge angles on the direct path
[s_0, s_i]. A hinge whose file order is [i-(a), i+(a)] has paper angle q_a = -θ_a.

The rigid position of a point fixed in link k is Σ_i Rot(φ_i) W_i with constant vectors W_i between
hinge pins (an ideal revolute at the plate midpoint, or at the model's pseudo-rigid-body pivot
when the hinge says pin = "prbm"); the compliant one adds Σ Δz_b over the direct path (4.7)–(4.8).
Loop closure (5.1)/(5.3) for the chord c reads
    Σ_b Φ_cb q_b = 0,     Σ_i Rot(φ_i) V^c_i + Σ_b Φ_cb Δz_b = 0,   V^c_i = Σ_b S_ib Φ_cb centre_b.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import sympy as sp

from ..core import vectors as V
from ..core.vectors import Vec
from ..graph.structure import Structure
from ..model.entries import Hinge
from ..model.hinges import THETA, plate_functions


@dataclass(frozen=True)
class HingeGeometry:
    """One hinge in the labeled mechanism: its plate, its model and its orientation."""

    label: int
    hinge: Hinge
    P: int  # label of the file's links[0]: the plate frame is fixed in P
    M: int  # label of links[1]
    sign: int  # +1 when P = i+(a): paper angle q_a = sign * θ_a
    centre: Vec  # the rigid reference pin (the plate midpoint unless pin = "prbm")
    angle: sp.Expr
    length: sp.Expr
    f: sp.Expr  # model functions of THETA (plate length substituted)
    g: sp.Expr
    df: sp.Expr  # f - f_rigid, g - g_rigid in cancellation-free form
    dg: sp.Expr
    limit: sp.Expr | None = None  # |θ| < limit: the model's (elastica_force π/2), else π for
    #                                 any plate (it cannot bend further); None for a rigid pin
    midpoint: Vec | None = None  # the plate midpoint `at` when the pin sits elsewhere

    @property
    def name(self) -> str:
        return self.hinge.name

    @property
    def is_input(self) -> bool:
        return self.hinge.input

    @property
    def u(self) -> Vec:
        return V.unit(self.angle)

    def clamp(self, link: int) -> Vec:
        """As-fabricated position of the plate end fixed in `link` (P's end or M's end)."""
        half = V.scale(self.length / 2, self.u)
        mid = self.centre if self.midpoint is None else self.midpoint
        return V.sub(mid, half) if link == self.P else V.add(mid, half)

    def delta_z(self, theta: sp.Expr, phi_p: sp.Expr) -> Vec:
        """Paper-oriented Δz_a (3.3): z_a - z_a^r at hinge angle θ, with P rotated by phi_p."""
        local = V.add(
            V.scale(self.df.subs(THETA, theta), self.u),
            V.scale(self.dg.subs(THETA, theta), V.perp(self.u)),
        )
        return V.scale(self.sign, V.rot(phi_p, local))

    def z(self, theta: sp.Expr, phi_p: sp.Expr, rigid: bool = False) -> Vec:
        """Paper-oriented hinge vector z_a = C_{i+(a)a} -> C_{i-(a)a} (3.1)/(3.2)."""
        if rigid:
            f = self.length / 2 * (1 + sp.cos(theta))
            g = self.length / 2 * sp.sin(theta)
        else:
            f, g = self.f.subs(THETA, theta), self.g.subs(THETA, theta)
        local = V.add(V.scale(f, self.u), V.scale(g, V.perp(self.u)))
        return V.scale(self.sign, V.rot(phi_p, local))


class Kinematics:
    """Symbolic kinematics of a labeled mechanism: link rotations, point positions, loop closure."""

    def __init__(self, structure: Structure, plate=None) -> None:
        """`plate(hinge) -> PlateFunctions` overrides the hinge models (variants use it)."""
        self.structure = s = structure
        plate_of = plate or plate_functions
        mech = s.mechanism
        self.mechanism = mech
        label = {name: i for i, name in enumerate(s.links)}
        self.theta = {a: sp.Symbol(f"theta_{a}", real=True) for a in range(1, s.m + 1)}
        self.delta = {a: sp.Symbol(f"delta_{a}", real=True) for a in range(1, s.m + 1)}
        hinges = {}
        for a, name in enumerate(s.hinges, start=1):
            h = mech.hinge(name)
            plate = plate_of(h)
            P, M = label[h.links[0]], label[h.links[1]]
            centre, midpoint = h.at, None
            if plate.pivot is not None:  # the pin sits d from M's clamp, not at `at`
                midpoint = h.at
                centre = V.add(h.at, V.scale(h.length / 2 - plate.pivot, V.unit(h.plate_angle)))
            hinges[a] = HingeGeometry(
                a,
                h,
                P,
                M,
                1 if s.i_plus[a - 1] == P else -1,
                centre,
                h.plate_angle,
                h.length,
                plate.f,
                plate.g,
                plate.df,
                plate.dg,
                plate_limit(h.model, plate.limit),
                midpoint,
            )
        self.hinges = hinges
        self.inputs = tuple(a for a in hinges if hinges[a].is_input)
        self.unknowns = tuple(a for a in hinges if not hinges[a].is_input)

    # -- geometry in the paper's terms ---------------------------------------------------------
    def c_vector(self, link: int, a: int) -> Vec:
        """c_ia: hinge point C_ia (the plate end fixed in `link`) from C_i (the origin), as
        fabricated."""
        h = self.hinges[a]
        if link not in (h.P, h.M):
            raise ValueError(f"hinge {a} does not touch link {link}")
        return h.clamp(link)

    def plate_data(self, a: int) -> dict[str, sp.Expr]:
        """Plate frame data of hinge a: α+ and α- (angles of e_1^{i±(a)a} in the link frames),
        the as-fabricated angle q*_a = α+ - α- (zero: link frames are parallel when fabricated),
        the plate length and the clamp vectors c_{i+(a)a}, c_{i-(a)a}."""
        s, h = self.structure, self.hinges[a]
        alpha = h.angle if h.sign > 0 else h.angle + sp.pi
        return {
            "alpha_plus": alpha,
            "alpha_minus": alpha,
            "q_star": sp.Integer(0),
            "length": h.length,
            "c_plus": self.c_vector(s.i_plus[a - 1], a),
            "c_minus": self.c_vector(s.i_minus[a - 1], a),
        }

    # -- angles ----------------------------------------------------------------------------------
    def q(self, a: int, angles: dict[int, sp.Expr] | None = None) -> sp.Expr:
        """Paper-oriented angle of hinge a (q_a = sign * θ_a)."""
        theta = (angles or self.theta)[a]
        return self.hinges[a].sign * theta

    def phi(self, link: int, angles: dict[int, sp.Expr] | None = None) -> sp.Expr:
        """Rotation of `link` from the as-fabricated pose: Σ q_b over the direct path."""
        return sp.Add(*(self.q(b, angles) for b in self.structure.tree_path(link)))

    # -- positions -------------------------------------------------------------------------------
    def weights(self, link: int, point: Vec) -> dict[int, Vec]:
        """W_i such that the rigid position of `point` (fixed in `link`) is Σ Rot(φ_i) W_i."""
        path = self.structure.tree_path(link)
        out: dict[int, Vec] = {}
        previous: Vec = V.ZERO
        for i, b in zip((0,) + path, path):
            out[i] = V.sub(self.hinges[b].centre, previous)
            previous = self.hinges[b].centre
        out[link] = V.sub(point, previous)
        return out

    def loop_weights(self, chord: int) -> dict[int, Vec]:
        """V^c_i = Σ_b S_ib Φ_cb centre_b: the rigid part of the loop of `chord` is Σ Rot(φ_i)
        V_i."""
        s = self.structure
        row = s.loops[chord - s.n - 1]
        out: dict[int, Vec] = {}
        for b in range(1, s.m + 1):
            coeff = int(row[b - 1])
            if coeff:
                centre = V.scale(coeff, self.hinges[b].centre)
                for i, sign in ((s.i_plus[b - 1], 1), (s.i_minus[b - 1], -1)):
                    out[i] = V.add(out.get(i, V.ZERO), V.scale(sign, centre))
        return out

    def rigid_position(
        self, link: int, point: Vec, angles: dict[int, sp.Expr] | None = None
    ) -> Vec:
        """Rigid position Σ Rot(φ_i) W_i of a point fixed in `link`."""
        return V.add(*(V.rot(self.phi(i, angles), w) for i, w in self.weights(link, point).items()))

    def path_deviation(self, link: int, angles: dict[int, sp.Expr] | None = None) -> Vec:
        """Σ Δz_b over the direct path to `link` (4.8) at the given hinge angles."""
        angles = angles or self.theta
        terms = [
            self.hinges[b].delta_z(angles[b], self.phi(self.hinges[b].P, angles))
            for b in self.structure.tree_path(link)
        ]
        return V.add(*terms) if terms else V.ZERO

    # -- loop closure ----------------------------------------------------------------------------
    @cached_property
    def chords(self) -> tuple[int, ...]:
        return tuple(range(self.structure.n + 1, self.structure.m + 1))

    def angular_closure(self, chord: int, angles: dict[int, sp.Expr] | None = None) -> sp.Expr:
        """(5.1): Σ_b Φ_cb q_b for the loop of `chord` (zero when the loop closes)."""
        row = self.structure.loops[chord - self.structure.n - 1]
        return sp.Add(
            *(
                int(row[b - 1]) * self.q(b, angles)
                for b in range(1, self.structure.m + 1)
                if row[b - 1]
            )
        )

    def positional_closure(
        self, chord: int, angles: dict[int, sp.Expr] | None = None, rigid: bool = False
    ) -> Vec:
        """(5.3) in full: Σ_i Rot(φ_i) V^c_i + Σ_b Φ_cb Δz_b (the Δz part dropped when rigid)."""
        angles = angles or self.theta
        rigid_part = [V.rot(self.phi(i, angles), w) for i, w in self.loop_weights(chord).items()]
        if rigid:
            return V.add(*rigid_part)
        return V.add(*rigid_part, self.loop_deviation(chord, angles))

    def loop_deviation(self, chord: int, angles: dict[int, sp.Expr] | None = None) -> Vec:
        """Φ_c Δz: the plate deviations summed around the loop of `chord` (left side of 5.3)."""
        angles = angles or self.theta
        row = self.structure.loops[chord - self.structure.n - 1]
        terms = [
            V.scale(
                int(row[b - 1]),
                self.hinges[b].delta_z(angles[b], self.phi(self.hinges[b].P, angles)),
            )
            for b in range(1, self.structure.m + 1)
            if row[b - 1]
        ]
        return V.add(*terms)


def plate_limit(model: str, model_limit: sp.Expr | None) -> sp.Expr | None:
    """|θ| bound of a hinge: its model's own limit, else π for any plate (a plate bent through
    more than a half turn is not a flexure hinge); a rigid pin turns freely."""
    if model_limit is not None:
        return model_limit
    return None if model == "rigid" else sp.pi


def c_symbol(i: int, a: int) -> sp.Symbol:
    """Abstract hinge-point vector c_ia (the paper's notation), for the matrix forms."""
    return sp.Symbol(f"c_{{{i},{a}}}")


def z_symbol(a: int) -> sp.Symbol:
    """Abstract hinge vector z_a."""
    return sp.Symbol(f"z_{{{a}}}")


def paper_matrices(structure: Structure) -> tuple[sp.Matrix, sp.Matrix]:
    """J = (S_ia c_ia) (4.3) and J* = (S+_ia z_a) (4.4), over abstract vector symbols."""
    s = structure
    J = sp.zeros(s.n + 1, s.m)
    Jstar = sp.zeros(s.n + 1, s.m)
    for i in range(s.n + 1):
        for a in range(1, s.m + 1):
            if s.incidence[i, a - 1]:
                J[i, a - 1] = int(s.incidence[i, a - 1]) * c_symbol(i, a)
            if s.incidence_plus[i, a - 1]:
                Jstar[i, a - 1] = z_symbol(a)
    return J, Jstar


def paper_positions(structure: Structure) -> sp.Matrix:
    """R = -Ψᵀ (J + J*)ᵀ 1_{n+1} (4.7): link positions over the abstract c_ia and z_a."""
    J, Jstar = paper_matrices(structure)
    psi = sp.Matrix(structure.paths.tolist())
    return -psi.T * (J + Jstar).T * sp.ones(structure.n + 1, 1)
