"""The CalculiX input deck of a mechanism in one configuration (docs/fea.md).

Every compliant plate is a plane-strain continuum: one layer of 20-node reduced-integration
bricks (C3D20R) of the plate's width with u_z = 0 on every node, NL elements along the plate and
NT through its thickness. Every moving link is a rigid body (`*RIGID BODY`, exact for finite
rotations under NLGEOM) made of the clamp faces of its plates, its pins, its load points and its
points; the frame's nodes are fixed. Inputs are prescribed rotations of the rigid bodies (relative
ones through an `*EQUATION`), loads are `*CLOAD`s on the links' nodes, and the step is
geometrically nonlinear, ramped from the as-fabricated pose.

The deviation of a point is read at full precision: ccx prints 7 significant digits, too few for
a 1e-6 deviation of a 0.1 m position, so an auxiliary node of each moving link is tied by
`*EQUATION` to (u_REF - u_rigid, phi - phi_rigid), where u_rigid, phi_rigid are the rigid
linkage's displacement of the link's reference node and rotation of the link, prescribed on a
constant node. `rigid` hinges are pins: a link's reference node placed on the pin. The deck is
written in SI units (metres, newtons, pascals) whatever the file's unit.
"""

from __future__ import annotations

import math
import textwrap
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field

import sympy as sp

from ._symkin import InputError, Mechanism, section_of
from .material import DEFAULT_LAW, FORCE_UNIT, NAMES, cards
from .profile_columns import columns

#: Element type of the plates: quadratic brick, reduced integration.
ELEMENT = "C3D20R"
#: Newton tolerances of ccx (*CONTROLS, PARAMETERS=FIELD: R_n, C_n): residual force and
#: solution correction relative to their averages. ccx's defaults (0.005, 0.01) may stop before
#: the deviation (1e-4 of the displacement) has converged; these cost about one more iteration.
FIELD_CONTROLS = (1e-8, 1e-8)
#: Time incrementation of the ramp (initial, minimum, maximum increment of the period 1).
INCREMENTS = (0.25, 1e-5, 0.25)
#: Most increments ccx may take.
MAX_INCREMENTS = 1000
#: Entries per data line of a node set (ccx reads at most 16).
PER_LINE = 8


@dataclass(frozen=True)
class Mesh:
    """Elements per plate: `along` the plate (NL) and `across` its thickness (NT)."""

    along: int
    across: int
    grading: float = 0.0  # 0: uniform; a in (0, 1): elements at the ends (1 - a)/(1 + a)
    # times those in the middle, along and across

    def positions(self, count: int) -> list[float]:
        """The 2 count + 1 node positions over [0, 1] of `count` quadratic elements: corners
        at xi - a sin(2 pi xi)/(2 pi) (smaller towards both ends), midside nodes halfway."""
        a = self.grading
        corners = [
            k / count - a * math.sin(2 * math.pi * k / count) / (2 * math.pi)
            for k in range(count + 1)
        ]
        corners[0], corners[-1] = 0.0, 1.0
        out = []
        for k in range(count):
            out += [corners[k], (corners[k] + corners[k + 1]) / 2]
        return out + [1.0]

    def __str__(self) -> str:
        return f"{self.along},{self.across},{self.grading:g}"


#: Converges the points' deviation to 0.01-0.03 % (the mesh study in docs/fea.md).
DEFAULT_MESH = Mesh(40, 4, 0.8)


def parse_mesh(text: str, option: str = "--mesh") -> Mesh:
    """`NL,NT` or `NL,NT,GRADING` as a Mesh (the default grading when not given); anything
    else is bad input."""
    hint = f"e.g. {option} {DEFAULT_MESH}: elements along, through the thickness, grading"
    parts = text.split(",")
    try:
        if len(parts) not in (2, 3):
            raise ValueError
        nl, nt = int(parts[0]), int(parts[1])
        grading = float(parts[2]) if len(parts) == 3 else DEFAULT_MESH.grading
    except ValueError:
        raise InputError(
            f"'{text}' is not NL,NT or NL,NT,GRADING", entry=option, hint=hint
        ) from None
    if nl < 1 or nt < 1:
        raise InputError(f"'{text}': the element counts must be positive", entry=option, hint=hint)
    if not 0 <= grading < 1:
        raise InputError(
            f"'{text}': the grading must be in [0, 1) (0: uniform)", entry=option, hint=hint
        )
    if nl * nt > 20_000:
        raise InputError(
            f"'{text}': {nl * nt} elements per plate is more than ccx solves in reasonable time",
            entry=option,
            hint=f"the default {DEFAULT_MESH} converges to about 0.03 %",
        )
    return Mesh(nl, nt, grading)


# -- numbers of the configuration ----------------------------------------------------------------

Vec = tuple[float, float]


@dataclass(frozen=True)
class Plate:
    """A compliant hinge's plate, SI units: from `start` (P's clamp) along `u` for `length`;
    `profile` its thickness at a distance from P's clamp (the outline its section gives the
    mesher, model.sections), None where it is `thickness` throughout."""

    hinge: str
    p_link: str
    m_link: str
    start: Vec
    u: Vec
    length: float
    thickness: float
    width: float
    E: float
    nu: float
    profile: Callable[[float], float] | None = None

    def depth(self, at: float) -> float:
        """The plate's thickness (m) at `at` metres from P's clamp."""
        return self.thickness if self.profile is None else self.profile(at)


@dataclass(frozen=True)
class Pin:
    """A `rigid` hinge: an ideal revolute joint at `at` (SI units) between two links."""

    hinge: str
    p_link: str
    m_link: str
    at: Vec


@dataclass(frozen=True)
class Force:
    """A dead load of the file on a link, SI units."""

    label: str
    link: str
    at: Vec
    force: Vec
    moment: float


@dataclass(frozen=True)
class Target:
    """A point whose deviation is wanted: its link and as-fabricated position (SI units)."""

    name: str
    link: str
    at: Vec


@dataclass(frozen=True)
class Drive:
    """An actuator of the file (SI units): it moves the point `at` of `link` (the link's
    reference node) along the unit `direction`, by the prescribed `stroke` (drive "stroke") or
    pushed by `force` N (drive "force"); `stroke` is then the stroke the deck's rigid pose is
    taken at. `rigid` the stroke of the deck's rigid pose where it is not `stroke`: a
    structure's, as fabricated whatever the stroke (docs/levels.md, "Structures")."""

    name: str
    link: str
    at: Vec
    direction: Vec
    drive: str
    stroke: float
    force: float = 0.0
    rigid: float | None = None


@dataclass(frozen=True)
class Reference:
    """Where a moving link's rigid body is referenced (its REF node) and the rigid linkage's
    pose of the link: `displacement` of that node and `angle`, the link's rotation. A link
    `parent`-ed by a pin turns about that pin, a node moving with the parent link."""

    link: str
    at: Vec
    why: str
    angle: float
    displacement: Vec | None = None  # own reference node only
    parent: str | None = None  # pinned: the link the pin moves with (may be the frame)
    pin: str | None = None
    shared: bool = False  # pinned: the parent's reference node is the pin


@dataclass(frozen=True)
class Configuration:
    """Everything the deck needs, as numbers: the mechanism in SI units at one input."""

    name: str
    file: str
    ground: str
    links: tuple[str, ...]
    plates: tuple[Plate, ...]
    pins: tuple[Pin, ...]
    loads: tuple[Force, ...]
    targets: tuple[Target, ...]
    references: tuple[Reference, ...]
    inputs: tuple[tuple[str, str, str, float], ...]  # (hinge, P, M, angle)
    params: tuple[tuple[str, float], ...]
    scale: float  # metres per file unit
    drives: tuple[Drive, ...] = ()


@dataclass(frozen=True)
class Anchor:
    """The symbolic plan of a moving link's reference node (file unit, over the parameters)."""

    at: tuple[sp.Expr, sp.Expr]
    why: str
    parent: str | None = None  # pinned: the link (or frame) the pin moves with
    pin: str | None = None  # the pin at `at`, if any
    point: str | None = None  # the file's point it sits on, if any
    shared: bool = False  # pinned: the parent's own reference node is the pin
    depth: int = 0  # rigid bodies between this reference node and a node
    # of its own (ccx cannot cascade more than one)


#: How deep ccx can cascade rigid bodies: a pin that is a member node of a rigid body whose
#: reference node is itself a member of another gives wrong results in ccx 2.20.
MAX_DEPTH = 1


def anchors(mech: Mechanism) -> dict[str, Anchor]:
    """Each moving link's reference node. The `rigid` hinges first: a pin joining a placed link
    (the frame, or one already referenced) to another makes the pin that one's reference, so
    the pins must form a forest. A group of pins off the frame is rooted at the first link its
    first pin names, with that pin as its own reference node, which the link across the pin
    shares. Every other link is referenced at its first point, else at its first load, else
    at the centre of the clamp face of its first plate. A loop of pins alone, or a chain of
    pins deeper than ccx can cascade, is refused."""
    out: dict[str, Anchor] = {}
    placed = {mech.ground}
    pending = [h for h in mech.hinges if h.model == "rigid"]
    while pending:
        pin = next((h for h in pending if h.links[0] in placed or h.links[1] in placed), None)
        if pin is None:  # pins off the frame: root their group
            first = pending[0]
            out[first.links[0]] = Anchor(
                first.at, f"at the pin '{printable(first.name)}'", pin=first.name
            )
            placed.add(first.links[0])
            continue
        if pin.links[0] in placed and pin.links[1] in placed:
            raise InputError(
                f"the pin closes a loop of rigid hinges (links '{pin.links[0]}' and "
                f"'{pin.links[1]}' are already joined through pins)",
                file=mech.path,
                line=pin.line,
                entry=f"[[hinge]] '{pin.name}'",
                hint="symkin fea turns each link about a pin of a link placed before it, which "
                "needs a compliant plate in every loop: give a hinge of the loop a plate model",
            )
        parent = pin.links[0] if pin.links[0] in placed else pin.links[1]
        child = pin.links[1] if parent == pin.links[0] else pin.links[0]
        up = out.get(parent)
        if up is None:  # on the frame: a fixed node
            anchor = Anchor(pin.at, f"the pin '{printable(pin.name)}'", parent, pin.name)
        elif up.pin == pin.name and up.parent is None:
            anchor = Anchor(
                pin.at,
                f"the pin '{printable(pin.name)}', shared with '{printable(parent)}'",
                parent,
                pin.name,
                shared=True,
            )
        else:
            anchor = Anchor(
                pin.at, f"the pin '{printable(pin.name)}'", parent, pin.name, depth=up.depth + 1
            )
        if anchor.depth > MAX_DEPTH:
            raise InputError(
                f"link '{child}' turns about a pin of a link that itself turns about a pin of "
                f"a third: ccx 2.20 cascades rigid bodies one level deep only, so symkin fea "
                "takes at most two pins in a row",
                file=mech.path,
                line=pin.line,
                entry=f"[[hinge]] '{pin.name}'",
                hint="give one of the rigid hinges in that chain a plate model",
            )
        out[child] = anchor
        placed.add(child)
        pending.remove(pin)
    for a in mech.actuators:
        if a.link in out:
            taken = out[a.link]
            why = f"its reference node is {taken.why}" if taken.pin else "it has two actuators"
            raise InputError(
                f"symkin fea drives an actuator's link by its reference node, and {why}",
                file=mech.path,
                line=a.line,
                entry=f"[[actuator]] #{a.index + 1} '{a.name}'",
                hint="push a link without rigid hinges, or give its rigid hinges a plate model",
            )
        out[a.link] = Anchor(a.at, f"at actuator '{printable(a.name)}'s point")
    for lk in mech.links:
        if lk.name != mech.ground and lk.name not in out:
            out[lk.name] = _own_anchor(mech, lk.name)
    return out


def _own_anchor(mech: Mechanism, link: str) -> Anchor:
    point = next((p for p in mech.points if p.link == link), None)
    if point is not None:
        return Anchor(point.at, f"at point '{printable(point.name)}'", point=point.name)
    load = next((ld for ld in mech.loads if ld.link == link), None)
    if load is not None:
        return Anchor(load.at, f"at {printable(load.label)}")
    h = next(h for h in mech.hinges if link in h.links and h.model != "rigid")
    sign = -1 if h.links[0] == link else 1
    u = (sp.cos(h.plate_angle), sp.sin(h.plate_angle))
    at = (h.at[0] + sign * h.length / 2 * u[0], h.at[1] + sign * h.length / 2 * u[1])
    return Anchor(at, f"at its clamp of plate '{printable(h.name)}'")


def _value(expr: object, subs: Mapping[sp.Symbol, sp.Expr]) -> float:
    return float(sp.N(sp.sympify(expr).xreplace(subs), 30))


def configuration(
    mech: Mechanism,
    inputs: Mapping[str, float],
    params: Mapping[str, float],
    plan: Mapping[str, Anchor],
    rigid_points: Mapping[str, Vec],
    rigid_angles: Mapping[str, float],
    forces: Mapping[str, float] | None = None,
) -> Configuration:
    """The numbers of `mech` at these parameter values (every parameter, floats) and input
    angles. `plan` holds the links' reference nodes (:func:`anchors`); `rigid_points` (file
    unit) the rigid linkage's positions of the file's points and of every own reference node,
    keyed by the point's name or, for a reference node on no point, by the link's name;
    `rigid_angles` the links' rotations. An actuator's stroke (file unit) is in `inputs`, the
    stroke the rigid pose is taken at; a force actuator's force (N) in `forces`."""
    scale = float(mech.unit_scale)
    subs = {p.symbol: sp.Float(repr(float(params[p.name])), 30) for p in mech.parameters}

    def vec(v: Sequence[object], factor: float = scale) -> Vec:
        return (_value(v[0], subs) * factor, _value(v[1], subs) * factor)

    plates, pins = [], []
    for h in mech.hinges:
        at = vec(h.at)
        if h.model == "rigid":
            pins.append(Pin(h.name, h.links[0], h.links[1], at))
            continue
        missing = [k for k in ("E", "thickness", "width") if getattr(h, k) is None]
        if missing:
            raise InputError(
                f"the plate needs '{missing[0]}' for a finite-element model",
                file=mech.path,
                line=h.line,
                entry=f"[[hinge]] '{h.name}'",
                hint=f"give {missing[0]} in the hinge or in [defaults] "
                "(E in Pa, thickness and width in the file's unit)",
            )
        angle = _value(h.plate_angle, subs)
        length = _value(h.length, subs) * scale
        u = (math.cos(angle), math.sin(angle))
        start = (at[0] - length / 2 * u[0], at[1] - length / 2 * u[1])
        section = section_of(h, mech.unit_scale)
        profile = None
        if not section.uniform:
            outline = section.thickness_function(subs)

            def profile(x: float, outline=outline) -> float:
                return float(outline(x / scale)) * scale

        plates.append(
            Plate(
                h.name,
                h.links[0],
                h.links[1],
                start,
                u,
                length,
                _value(h.thickness, subs) * scale,
                _value(h.width, subs) * scale,
                _value(h.E, subs),
                _value(h.nu, subs),
                profile,
            )
        )
    loads = tuple(
        Force(ld.label, ld.link, vec(ld.at), vec(ld.force, 1.0), _value(ld.moment, subs))
        for ld in mech.loads
        if ld.link != mech.ground
    )  # the frame: a reaction
    references = []
    for link, anchor in plan.items():
        at = vec(anchor.at)
        displacement = None
        if anchor.parent is None:
            rigid = rigid_points[anchor.point or link]
            displacement = (rigid[0] * scale - at[0], rigid[1] * scale - at[1])
        references.append(
            Reference(
                link,
                at,
                anchor.why,
                float(rigid_angles[link]),
                displacement,
                anchor.parent,
                anchor.pin,
                anchor.shared,
            )
        )
    surrogates = {a.surrogate for a in mech.actuators}  # the stroke fixes their angle
    ins = tuple(
        (h.name, h.links[0], h.links[1], float(inputs[h.name]))
        for h in mech.hinges
        if h.input and h.name not in surrogates
    )
    drives = tuple(
        Drive(
            a.name,
            a.link,
            vec(a.at),
            vec(a.direction, 1.0),
            a.drive,
            float(inputs[a.name]) * scale,
            float((forces or {}).get(a.name, 0.0)),
            0.0 if mech.is_structure else None,
        )
        for a in mech.actuators
    )
    return Configuration(
        mech.name,
        mech.path,
        mech.ground,
        tuple(lk.name for lk in mech.links),
        tuple(plates),
        tuple(pins),
        loads,
        tuple(Target(p.name, p.link, vec(p.at)) for p in mech.points),
        tuple(references),
        ins,
        tuple((p.name, float(params[p.name])) for p in mech.parameters),
        scale,
        drives,
    )


# -- the deck ------------------------------------------------------------------------------------


def number(value: float) -> str:
    """A float as ccx reads it: at most 20 characters (ccx reads fields as f20.0), 14
    significant digits, no negative zero."""
    text = f"{value:.14g}"
    return "0" if text in ("-0", "0") else text


def _wrap(line: str, width: int = 100) -> list[str]:
    """A comment line longer than `width` as several (ccx reads 132 characters a line); other
    lines as they are."""
    if not line.startswith("**") or len(line) <= width:
        return [line]
    return textwrap.wrap(
        line[2:].strip(),
        width - 3,
        initial_indent="** ",
        subsequent_indent="**   ",
        break_long_words=True,
    )


def printable(name: str) -> str:
    """A name as a comment may show it: printable ASCII, the rest as '?'."""
    return "".join(c if 32 <= ord(c) < 127 else "?" for c in name)


@dataclass
class LinkBody:
    """A moving link's rigid body as the deck numbers it."""

    ref: Reference
    ref_node: int = 0
    rot: int = 0
    members: list[int] = field(default_factory=list)
    dev: int = 0  # auxiliary node: (u_REF - u_rigid, phi - phi_rigid)
    const: int = 0  # constant node holding (u_rigid, phi_rigid)


@dataclass(frozen=True)
class LinkReadout:
    """How to read a moving link's deviation from the printed auxiliary node `node`: its dofs
    1, 2 the reference node's deviation (own reference only), dof 3 the rotation's."""

    link: str
    node: int
    ref_at: Vec
    angle: float  # the rigid linkage's rotation of the link
    parent: str | None = None  # pinned: the reference node is a pin moving with `parent`


@dataclass(frozen=True)
class Deck:
    """The deck's text and what reading its results needs."""

    text: str
    links: tuple[LinkReadout, ...]
    targets: tuple[Target, ...]
    ground: str
    nodes: int
    elements: int
    scale: float
    mesh: Mesh
    drives: tuple[Drive, ...] = ()
    law: str = DEFAULT_LAW  # the plates' finite-strain law (fea.material)


class _Writer:
    """Builds the deck's sections from a Configuration (one pass, deterministic numbering)."""

    def __init__(
        self, conf: Configuration, mesh: Mesh, released: frozenset[str], law: str = DEFAULT_LAW
    ) -> None:
        self.conf = conf
        self.mesh = mesh
        self.law = law
        self.unit = FORCE_UNIT[law]  # newtons per force unit of the deck
        self.released = released
        self.count = 0
        self.node_lines: list[str] = []
        self.body = {r.link: LinkBody(r) for r in conf.references}
        self.fixed: list[int] = []  # frame nodes: all three displacements zero
        self.planar: list[int] = []  # plate nodes not in a rigid body: u_z = 0
        self.element_lines: list[str] = []
        self.elements = 0

    def node(self, at: Vec, z: float = 0.0, comment: str | None = None) -> int:
        if comment:
            self.node_lines.append(f"** {comment}")
        self.count += 1
        self.node_lines.append(f"{self.count}, {number(at[0])}, {number(at[1])}, {number(z)}")
        return self.count

    def member(self, link: str, node: int) -> None:
        """`node` moves with `link`: a member of its rigid body, or fixed on the frame."""
        if link == self.conf.ground:
            self.fixed.append(node)
        else:
            self.body[link].members.append(node)

    # -- plates --------------------------------------------------------------------------------
    def plate(self, k: int, pl: Plate) -> None:
        """Nodes and C3D20R elements of plate k: a grid of (2 NL + 1) x (2 NT + 1) positions
        along and across, on three levels through the width (the middle one at the corners
        only); the clamp faces' nodes join P's and M's rigid bodies."""
        nl, nt = self.mesh.along, self.mesh.across
        n = (-pl.u[1], pl.u[0])
        self.node_lines.append(
            f"** plate {k} of hinge '{printable(pl.hinge)}': from the clamp in "
            f"'{printable(pl.p_link)}' to the clamp in '{printable(pl.m_link)}'"
            f", l = {number(pl.length)}, t = {number(pl.thickness)}, "
            f"b = {number(pl.width)} m"
        )
        ids: dict[tuple[int, int, int], int] = {}
        along, across = self.mesh.positions(nl), self.mesh.positions(nt)
        if pl.profile is not None:  # a notch: columns as long as a share of the local thickness
            along = [x / pl.length for x in columns(pl.depth, pl.length, nl)]
        for i in range(2 * nl + 1):
            s = pl.length * along[i]
            for j in range(2 * nt + 1):
                r = pl.depth(s) * (across[j] - 0.5)
                at = (pl.start[0] + s * pl.u[0] + r * n[0], pl.start[1] + s * pl.u[1] + r * n[1])
                for kz in range(3):
                    if (i % 2 and j % 2) or (kz == 1 and (i % 2 or j % 2)):
                        continue
                    node = self.node(at, pl.width * kz / 2)
                    ids[i, j, kz] = node
                    if i == 0:
                        self.member(pl.p_link, node)
                    elif i == 2 * nl:
                        self.member(pl.m_link, node)
                    else:
                        self.planar.append(node)
        self.element_lines += [
            f"** plate {k} of hinge '{printable(pl.hinge)}': {nl} x {nt} elements",
            f"*ELEMENT, TYPE={ELEMENT}, ELSET=PLATE{k}",
        ]
        for ei in range(nl):
            for ej in range(nt):
                i, j = 2 * ei, 2 * ej
                corners = [(i, j), (i + 2, j), (i + 2, j + 2), (i, j + 2)]
                mids = [(i + 1, j), (i + 2, j + 1), (i + 1, j + 2), (i, j + 1)]
                order = (
                    [ids[a, b, 0] for a, b in corners]
                    + [ids[a, b, 2] for a, b in corners]
                    + [ids[a, b, 0] for a, b in mids]
                    + [ids[a, b, 2] for a, b in mids]
                    + [ids[a, b, 1] for a, b in corners]
                )
                self.elements += 1
                # at most 16 entries per line: the element's last five go on the next
                line = [self.elements] + order
                self.element_lines.append(", ".join(map(str, line[:16])) + ",")
                self.element_lines.append(", ".join(map(str, line[16:])))

    # -- the deck ------------------------------------------------------------------------------
    def write(self) -> Deck:
        conf = self.conf
        for k, pl in enumerate(conf.plates, start=1):
            self.plate(k, pl)
        self.node_lines.append(
            "** the links: reference and rotation nodes, pins, load points, "
            "points, the deviation's auxiliary nodes"
        )
        self.bodies()
        loads = self.loads()
        drives_eq, drives_bc, drives_load = self.drives()
        for t in conf.targets:
            if t.link != conf.ground:
                self.member(
                    t.link,
                    self.node(
                        t.at, comment=f"point '{printable(t.name)}' on '{printable(t.link)}'"
                    ),
                )
        self.deviation_nodes()
        inputs_eq, inputs_bc = self.inputs()
        bodies = list(self.body.values())

        out = self.header()
        out += ["*NODE", *self.node_lines]
        out += self.element_lines
        out += [
            "** the plates' nodes off the clamps: plane strain, u_z = 0",
            *self.nset("PLANAR", self.planar),
        ]
        if self.fixed:
            out += [
                f"** nodes fixed in the frame '{printable(conf.ground)}': clamp faces, pins",
                *self.nset("FRAME", self.fixed),
            ]
        out += self.materials()
        for k, b in enumerate(bodies, start=1):
            out += [
                f"** link '{printable(b.ref.link)}': reference node {b.ref_node} "
                f"({b.ref.why}), rotation node {b.rot}",
                *self.nset(f"LINK{k}", b.members),
                f"*RIGID BODY, NSET=LINK{k}, REF NODE={b.ref_node}, ROT NODE={b.rot}",
            ]
        out += [
            "*BOUNDARY",
            "** in the plane: u_z = 0, the links turn about z only",
            "PLANAR, 3, 3",
        ]
        if self.fixed:
            out.append("FRAME, 1, 3")
        for b in bodies:
            if b.ref.parent is None:  # a pin follows the link it moves with
                out.append(f"{b.ref_node}, 3, 3")
            out.append(f"{b.rot}, 1, 2")
        out += inputs_eq + drives_eq
        out += self.deviation_equations(bodies)
        out += self.step(inputs_bc + drives_bc, loads + drives_load, bodies)
        links = tuple(
            LinkReadout(b.ref.link, b.dev, b.ref.at, b.ref.angle, b.ref.parent) for b in bodies
        )
        text = "\n".join(wrapped for line in out for wrapped in _wrap(line)) + "\n"
        return Deck(
            text,
            links,
            conf.targets,
            conf.ground,
            self.count,
            self.elements,
            conf.scale,
            self.mesh,
            conf.drives,
            self.law,
        )

    def materials(self) -> list[str]:
        """Each plate's material and section (a subclass adds what a frequency step needs)."""
        out = []
        for k, pl in enumerate(self.conf.plates, start=1):
            out += [
                f"** plate {k} ('{printable(pl.hinge)}'): E = {number(pl.E)} Pa, "
                f"nu = {number(pl.nu)}; {NAMES[self.law]} under NLGEOM",
                f"*MATERIAL, NAME=PLATE{k}",
                *cards(pl.E / self.unit, pl.nu, self.law, number),
                f"*SOLID SECTION, ELSET=PLATE{k}, MATERIAL=PLATE{k}",
            ]
        return out

    def header(self) -> list[str]:
        conf = self.conf
        inputs = ", ".join(f"{printable(h)} = {number(v)} rad" for h, _, _, v in conf.inputs)
        released = ", ".join(printable(h) for h in sorted(self.released))
        params = ", ".join(f"{printable(p)} = {number(v)}" for p, v in conf.params) or "none"
        return [
            f"** CalculiX deck written by symkin fea from {printable(conf.file)}: do not edit",
            f"** mechanism '{printable(conf.name)}'; inputs {inputs}"
            + (f" (released: {released})" if released else "")
            + f"; parameters {params}",
            f"** units: metres (the file's lengths times {number(conf.scale)}), "
            + ("newtons, pascals" if self.unit == 1 else "meganewtons, megapascals (fea.material)"),
            f"** plates: {self.mesh.along} x {self.mesh.across} {ELEMENT} elements each (along "
            f"x through the thickness, grading {self.mesh.grading:g}: the elements at the "
            "clamps and the faces smaller), one layer through the width, u_z = 0: plane strain",
            "** links: rigid bodies; the frame's nodes fixed; NLGEOM, ramped from the "
            "as-fabricated pose",
            *(
                f"** actuator '{printable(d.name)}' on '{printable(d.link)}': "
                + (
                    f"a force of {number(d.force)} N (the rigid pose at the stroke "
                    f"{number(d.stroke)} m)"
                    if d.drive == "force"
                    else f"a stroke of {number(d.stroke)} m"
                )
                for d in conf.drives
            ),
            "*HEADING",
            f"symkin fea {printable(conf.name)}",
        ]

    def drives(self) -> tuple[list[str], list[str], list[str]]:
        """The actuators on their links' reference nodes (placed at the actuator's point): a
        stroke d_x u_x + d_y u_y = s through an *EQUATION with the u_1 of a prescribed auxiliary
        node, a force a *CLOAD along d (a dead load: its direction stays)."""
        eq: list[str] = []
        bc: list[str] = []
        load: list[str] = []
        for d in self.conf.drives:
            ref = self.body[d.link].ref_node
            name, link = printable(d.name), printable(d.link)
            if d.drive == "force":
                load.append(
                    f"** actuator '{name}': pushes '{link}' at node {ref} with {number(d.force)} N "
                    f"along ({number(d.direction[0])}, {number(d.direction[1])})"
                )
                load += [
                    f"{ref}, {dof}, {number(d.force * c / self.unit)}"
                    for dof, c in ((1, d.direction[0]), (2, d.direction[1]))
                    if c
                ]
                continue
            what = (
                f"actuator '{name}': '{link}' at node {ref} moves by {number(d.stroke)} m along "
                f"({number(d.direction[0])}, {number(d.direction[1])})"
            )
            aux = self.node((0.0, 0.0), comment=f"{what}: this node's u_1")
            # the larger component first: ccx eliminates the first dof of an equation
            terms = sorted(
                ((dof, c) for dof, c in ((1, d.direction[0]), (2, d.direction[1])) if c),
                key=lambda t: -abs(t[1]),
            )
            eq += [
                f"** {what}",
                "*EQUATION",
                str(len(terms) + 1),
                ", ".join(f"{ref}, {dof}, {number(c)}" for dof, c in terms) + f", {aux}, 1, -1.",
            ]
            bc += [f"** {what}", f"{aux}, 1, 1, {number(d.stroke)}"]
        return eq, bc, load

    @staticmethod
    def nset(name: str, nodes: Sequence[int]) -> list[str]:
        lines = [f"*NSET, NSET={name}"]
        for i in range(0, len(nodes), PER_LINE):
            lines.append(", ".join(map(str, nodes[i : i + PER_LINE])) + ",")
        return lines

    def bodies(self) -> None:
        """Reference and rotation nodes in the order of the references (pins after their
        parents): a pinned link's reference node is its pin, a node moving with the parent."""
        for b in self.body.values():
            name = printable(b.ref.link)
            if b.ref.parent is None:
                b.ref_node = self.node(
                    b.ref.at, comment=f"link '{name}': reference node, {b.ref.why}"
                )
            elif b.ref.shared:
                b.ref_node = self.body[b.ref.parent].ref_node
            else:
                b.ref_node = self.node(
                    b.ref.at,
                    comment=f"pin '{printable(b.ref.pin or '')}': "
                    f"moves with '{printable(b.ref.parent)}', '{name}' turns "
                    "about it",
                )
                self.member(b.ref.parent, b.ref_node)
            b.rot = self.node(
                b.ref.at, comment=f"link '{name}': rotation node (its u_3 is the link's rotation)"
            )
        for b in self.body.values():
            if not b.members:
                b.members.append(
                    self.node(
                        b.ref.at,
                        comment=f"link '{printable(b.ref.link)}': a "
                        "member node (a rigid body needs one)",
                    )
                )

    def loads(self) -> list[str]:
        lines = []
        for ld in self.conf.loads:
            if ld.force == (0.0, 0.0) and not ld.moment:
                continue
            body = self.body[ld.link]
            lines.append(f"** {printable(ld.label)} on link '{printable(ld.link)}'")
            if ld.force != (0.0, 0.0):
                node = self.node(ld.at, comment=f"{printable(ld.label)}: where it acts")
                body.members.append(node)
                lines += [
                    f"{node}, {dof}, {number(v / self.unit)}"
                    for dof, v in ((1, ld.force[0]), (2, ld.force[1]))
                    if v
                ]
            if ld.moment:
                lines.append(f"{body.rot}, 3, {number(ld.moment / self.unit)}")
        return lines

    def deviation_nodes(self) -> None:
        """Per moving link a constant node (the rigid linkage's displacement of the reference
        node and rotation, prescribed) and an auxiliary node (the deviations)."""
        for b in self.body.values():
            name = printable(b.ref.link)
            b.const = self.node(
                b.ref.at,
                comment=f"link '{name}': the rigid linkage's "
                "displacement and rotation (prescribed)",
            )
            b.dev = self.node(
                b.ref.at,
                comment=f"link '{name}': deviation from the rigid "
                "linkage (u_REF - u_rigid, phi - phi_rigid)",
            )

    def inputs(self) -> tuple[list[str], list[str]]:
        """Prescribed relative rotations: on the rotation node when one link is the frame, else
        ROT_M - ROT_P = the u_1 of an auxiliary node."""
        eq, bc = [], []
        for hinge, p, m, angle in self.conf.inputs:
            if hinge in self.released:
                eq.append(f"** input '{printable(hinge)}' released: no actuator holds it")
                continue
            what = (
                f"input '{printable(hinge)}': '{printable(m)}' turns by {number(angle)} rad "
                f"relative to '{printable(p)}'"
            )
            if p == self.conf.ground:
                bc += [f"** {what}", f"{self.body[m].rot}, 3, 3, {number(angle)}"]
            elif m == self.conf.ground:
                bc += [f"** {what}", f"{self.body[p].rot}, 3, 3, {number(-angle)}"]
            else:
                aux = self.node((0.0, 0.0), comment=f"{what}: this node's u_1")
                eq += [
                    f"** {what}",
                    "*EQUATION",
                    "3",
                    f"{self.body[m].rot}, 3, 1., {self.body[p].rot}, 3, -1., {aux}, 1, -1.",
                ]
                bc += [f"** {what}", f"{aux}, 1, 1, {number(angle)}"]
        return eq, bc

    def deviation_equations(self, bodies: list[LinkBody]) -> list[str]:
        """DEV = (u_REF - u_rigid, phi - phi_rigid). Only independent dofs may enter an
        *EQUATION beside a rigid body: a pin's displacement is a rigid body's dependent dof, so
        a pinned link's DEV holds the rotation only (its pin's deviation is its parent's)."""
        out = []
        for b in bodies:
            own = b.ref.parent is None
            out += [
                f"** link '{printable(b.ref.link)}': node {b.dev} = "
                + ("(u_REF - u_rigid, phi - phi_rigid)" if own else "(-, -, phi - phi_rigid)"),
                "*EQUATION",
            ]
            sources = ((1, b.ref_node, 1), (2, b.ref_node, 2)) if own else ()
            for dof, node, src in (*sources, (3, b.rot, 3)):
                out += ["3", f"{b.dev}, {dof}, 1., {node}, {src}, -1., {b.const}, {dof}, 1."]
        return out

    def step(self, inputs_bc: list[str], loads: list[str], bodies: list[LinkBody]) -> list[str]:
        first, smallest, largest = INCREMENTS
        out = [
            "** one step: the inputs, the rigid linkage's pose and the loads ramped from 0",
            f"*STEP, NLGEOM, INC={MAX_INCREMENTS}",
            "*STATIC",
            f"{number(first)}, 1., {number(smallest)}, {number(largest)}",
            "*CONTROLS, PARAMETERS=FIELD",
            f"{number(FIELD_CONTROLS[0])}, {number(FIELD_CONTROLS[1])}",
            "*BOUNDARY",
            *inputs_bc,
        ]
        for b in bodies:
            out.append(f"** link '{printable(b.ref.link)}': the rigid linkage's pose")
            values = (*(b.ref.displacement or (0.0, 0.0)), b.ref.angle)
            dofs = (1, 2, 3) if b.ref.displacement is not None else (3,)
            out += [f"{b.const}, {dof}, {dof}, {number(values[dof - 1])}" for dof in dofs]
        if loads:
            out += ["*CLOAD", *loads]
        out += [
            "** for viewing (cgx): displacements and stresses at the end of the step only",
            "*NODE FILE, FREQUENCY=1000000",
            "U",
            "*EL FILE, FREQUENCY=1000000",
            "S",
            "** the deviations, at full precision",
            *self.nset("DEVIATION", [b.dev for b in bodies]),
            "*NODE PRINT, NSET=DEVIATION",
            "U",
            "*END STEP",
        ]
        return out


def write(
    conf: Configuration,
    mesh: Mesh = DEFAULT_MESH,
    released: Sequence[str] = (),
    law: str = DEFAULT_LAW,
) -> Deck:
    """The deck of `conf` with `mesh` elements per plate of the finite-strain `law`
    (fea.material); the input hinges in `released` are left free (no actuator: a cantilever under
    a load, say), the rigid linkage's pose still taken at their given angles."""
    unknown = [h for h in released if h not in {i[0] for i in conf.inputs}]
    if unknown:
        raise InputError(f"'{unknown[0]}' is not an input hinge", entry="released")
    return _Writer(conf, mesh, frozenset(released), law).write()
