"""The natural frequencies in CalculiX (docs/fea.md, "Natural frequencies"): the deck of
symkin.fea.deck with the links' masses on their rigid bodies and a frequency step after the
static one, and its frequencies beside `symkin modes` at both physical levels.

A link's mass is a `MASS` element at its centre, a member node of its rigid body. ccx 2.20 has
no rotary inertia for a rigid body, so a link with an inertia I gets two point masses m/2 at its
centre ± √(I/m) along x instead of one: the same mass, centre and inertia about the centre.
The plates are massless (a negligible density, NEGLIGIBLE) unless given one. The frequency
step is a `*STEP, PERTURBATION` after the NLGEOM static step: about its end, with the static
step's boundary conditions (every input held, a stroke actuator at its stroke, a force actuator
at its force) and the plates' stresses (their geometric stiffness). It comes last: a static
step after it would start again from the undeformed shape.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import sympy as sp

from . import LEVELS, Comparison, Setup, compare
from ._symkin import AssemblyError, InputError, natural_modes
from .deck import DEFAULT_MESH, Deck, LinkBody, Mesh, _Writer, number, printable

#: The plates' density (kg/m³) standing for massless plates: a singular mass matrix breaks ccx's
#: eigensolver (ARPACK: "info=-9999" when as many modes are asked as the links have degrees of
#: freedom with mass), so the plates get this, 1e-15 of steel's: their own modes lie some 1e7
#: times above those of real plates, their mass changes the links' frequencies by 1e-15.
NEGLIGIBLE = 1e-12
#: A mode this many times above the lowest is one of the plates' negligible mass (above), not
#: of a link's: there is one when the links have fewer free degrees of freedom than ccx is asked
#: for (a direction held rigidly, say by a stroke).
SPURIOUS = 1e5
#: Modes of this mass-weighted MAC or more may be the same mode (pair).
MATCH = 0.8
#: An FE mode pairs with one of symkin's only if at least this share of its modal mass is the
#: links' (with the plates' density, their own modes carry most of theirs).
SHARE = 0.5
#: Steel's density (kg/m³), the one docs/fea.md measured the plates' own mass with.
STEEL = 7850.0
#: The heading of a mode's printed displacements in ccx's .dat.
MODE = re.compile(r"E I G E N V A L U E\s+N U M B E R\s+(\d+)")
#: The eigenvalue table of ccx's .dat: mode, ω², ω, f (Hz), the imaginary part.
EIGENVALUE = re.compile(
    r"^\s*(\d+)\s+(\S+E[+-]\d+)\s+(\S+E[+-]\d+)\s+(\S+E[+-]\d+)\s+(\S+E[+-]\d+)\s*$"
)


@dataclass(frozen=True)
class LinkMass:
    """A massive link in the deck's units (kg, kg·m², m): its mass, its inertia about its
    centre and the centre as fabricated."""

    link: str
    mass: float
    inertia: float
    centre: tuple[float, float]


def link_masses(setup: Setup) -> tuple[LinkMass, ...]:
    """The moving links' masses at the set-up parameter values; bad input (exit 2) when no link
    has one."""
    mech = setup.mechanism
    given = dict(setup.conf.params)
    subs = {p.symbol: sp.Float(repr(given[p.name]), 30) for p in mech.parameters}

    def value(expr: object) -> float:
        return float(sp.N(sp.sympify(expr).xreplace(subs), 30))

    out = []
    for lk in mech.links:
        if not lk.massive or lk.name == mech.ground:
            continue
        assert lk.mass is not None and lk.centre is not None
        scale = setup.conf.scale
        centre = (value(lk.centre[0]) * scale, value(lk.centre[1]) * scale)
        out.append(LinkMass(lk.name, value(lk.mass), value(lk.inertia or 0), centre))
    if not out:
        raise InputError(
            "no link has a mass: the natural frequencies need the masses that oscillate",
            file=mech.path,
            entry="--modes",
            hint="add mass = ... (kg) and centre = [x, y] (file unit) to the moving links "
            "that carry mass, e.g. the stage (docs/file-format.md, '[[link]]')",
        )
    return tuple(out)


@dataclass(frozen=True)
class ModalDeck:
    """A deck with a frequency step: `requested` eigenvalues asked of ccx, `count` wanted."""

    deck: Deck
    masses: tuple[LinkMass, ...]
    count: int
    requested: int
    density: float  # the plates', kg/m³


class _FrequencyWriter(_Writer):
    """symkin.fea.deck's writer with mass elements on the rigid bodies, the plates' density and
    a frequency step after the static one."""

    def __init__(
        self,
        conf,
        mesh: Mesh,
        released: frozenset[str],
        masses: Sequence[LinkMass],
        requested: int,
        density: float,
    ) -> None:
        super().__init__(conf, mesh, released)
        self.masses = masses
        self.requested = requested
        self.density = density
        self.mass_cards: list[str] = []

    def bodies(self) -> None:
        super().bodies()
        element = self.elements  # the mass elements after the plates' (not counted in them)
        for k, lm in enumerate(self.masses, start=1):
            name = printable(lm.link)
            arm = math.sqrt(lm.inertia / lm.mass) if lm.inertia > 0 else 0.0
            places = [(lm.centre, lm.mass)]
            what = f"link '{name}': its mass {number(lm.mass)} kg at its centre"
            if arm:
                x, y = lm.centre
                places = [((x - arm, y), lm.mass / 2), ((x + arm, y), lm.mass / 2)]
                what += (
                    f" and its inertia {number(lm.inertia)} kg m^2: two halves at the centre "
                    f"-/+ {number(arm)} m along x"
                )
            lines = [f"** {what}"]
            for j, (at, mass) in enumerate(places, start=1):
                node = self.node(at, comment=f"link '{name}': a point mass (a member node)")
                self.member(lm.link, node)
                element += 1
                lines += [f"*ELEMENT, TYPE=MASS, ELSET=MASS{k}_{j}", f"{element}, {node}"]
                self.mass_cards += [f"*MASS, ELSET=MASS{k}_{j}", number(mass)]
            self.element_lines += lines

    def materials(self) -> list[str]:
        out = []
        for line in super().materials():
            if line.startswith("*SOLID SECTION"):
                out += ["*DENSITY", number(self.density or NEGLIGIBLE)]
            out.append(line)
        return [*out, "** the links' masses", *self.mass_cards]

    def step(self, inputs_bc: list[str], loads: list[str], bodies: list[LinkBody]) -> list[str]:
        plates = (
            "massless plates" if not self.density else f"plates of {number(self.density)} kg/m^3"
        )
        return super().step(inputs_bc, loads, bodies) + [
            f"** the natural frequencies about the end of the static step ({plates}): every "
            "input and stroke held, the forces kept, the plates' stresses in the stiffness "
            "(ccx leaves out the rigid bodies' geometric stiffness); last, since a static "
            "step after it would start again from the undeformed shape",
            "*STEP, PERTURBATION",
            "*FREQUENCY",
            str(self.requested),
            "*END STEP",
        ]


def write(
    setup: Setup,
    mesh: Mesh = DEFAULT_MESH,
    count: int = 3,
    density: float = 0.0,
    released: Sequence[str] = (),
) -> ModalDeck:
    """The deck of `setup` with the links' masses and a frequency step for the `count` lowest
    modes, the plates of `density` kg/m³ (0: massless, as symkin's model). Massless plates
    leave at most two translations and a rotation (with an inertia) per massive link; ccx is
    asked for no more."""
    if count < 1:
        raise InputError(
            f"--modes {count}: at least one mode",
            file=setup.mechanism.path,
            entry="--modes",
            hint="--modes 3",
        )
    if not (math.isfinite(density) and density >= 0):
        raise InputError(
            f"--plate-density {density}: a density is finite and at least 0",
            file=setup.mechanism.path,
            entry="--plate-density",
            hint=f"kg/m^3, e.g. --plate-density {STEEL:g} for steel (0: massless plates)",
        )
    masses = link_masses(setup)
    freedoms = sum(2 + (m.inertia > 0) for m in masses)
    requested = count if density else min(count, freedoms)
    writer = _FrequencyWriter(setup.conf, mesh, frozenset(released), masses, requested, density)
    return ModalDeck(writer.write(), masses, count, requested, density)


def eigenvalues(printed: str) -> list[float]:
    """ω² (rad²/s²) of each mode in ccx's .dat, in its order."""
    start = printed.find("E I G E N V A L U E   O U T P U T")
    if start < 0:
        return []
    out = []
    for line in printed[start:].splitlines()[1:]:
        m = EIGENVALUE.match(line)
        if m:
            out.append(float(m.group(2)))
        elif out and line.strip():
            break
    return out


def mode_blocks(printed: str) -> list[dict[int, tuple[float, float, float]]]:
    """Each mode's printed displacements (the DEVIATION nodes: per link the reference node's
    and the rotation's), in ccx's order."""
    start = printed.find("E I G E N V A L U E   O U T P U T")
    out: list[dict[int, tuple[float, float, float]]] = []
    for line in printed[start:].splitlines() if start >= 0 else ():
        if MODE.search(line):
            out.append({})
            continue
        parts = line.split()
        if out and len(parts) == 4 and parts[0].isdigit():
            out[-1][int(parts[0])] = (float(parts[1]), float(parts[2]), float(parts[3]))
    return out


def centre_motions(modal: ModalDeck, block: Mapping[int, Sequence[float]]) -> list[float]:
    """A mode's motion of each massive link's centre and its rotation (dx, dy in m, dφ), from
    its printed auxiliary nodes: the reference node's translation (a pinned link's: its
    parent's at the pin) plus the rotation times the centre's arm, turned by the link's rigid
    angle (linear: the mode is small)."""
    deck = modal.deck
    links = {r.link: r for r in deck.links}

    def at(link: str, where: tuple[float, float]) -> tuple[float, float]:
        if link == deck.ground:
            return (0.0, 0.0)
        r = links[link]
        du, dv, dphi = block[r.node]
        base = at(r.parent, r.ref_at) if r.parent is not None else (du, dv)
        ax, ay = where[0] - r.ref_at[0], where[1] - r.ref_at[1]
        c, sn = math.cos(r.angle), math.sin(r.angle)
        wx, wy = c * ax - sn * ay, sn * ax + c * ay
        return (base[0] - dphi * wy, base[1] + dphi * wx)

    out: list[float] = []
    for lm in modal.masses:
        out += [*at(lm.link, lm.centre), block[links[lm.link].node][2]]
    return out


@dataclass(frozen=True)
class Mode:
    """A natural mode: its frequency (Hz) and its massive links' centre motions [dx, dy (m),
    dφ] per link, in the order of ModalDeck.masses."""

    frequency: float
    shape: list[float]
    share: float | None = None  # FE: the massive links' share of the mode's mass (ccx
    # normalises a mode to unit modal mass, so this is its shape's M-norm over the links)


def fe_modes(modal: ModalDeck, printed: str) -> list[Mode]:
    """The FE's natural modes, lowest first, at most `modal.count`: with massless plates the
    modes of their negligible mass left out (SPURIOUS)."""
    values = eigenvalues(printed)
    if not values:
        raise AssemblyError("ccx printed no eigenvalues for the frequency step")
    blocks = mode_blocks(printed)
    weights = [w for m in modal.masses for w in (m.mass, m.mass, m.inertia)]
    found = []
    for k, v in enumerate(values):
        if v <= 0:
            continue
        shape = centre_motions(modal, blocks[k]) if k < len(blocks) else []
        share = sum(w * x * x for w, x in zip(weights, shape)) if shape else None
        found.append(Mode(math.sqrt(v) / (2 * math.pi), shape, share))
    found.sort(key=lambda m: m.frequency)
    if modal.density == 0 and found:
        found = [m for m in found if m.frequency <= SPURIOUS * found[0].frequency]
    return found[: modal.count]


def frequencies(modal: ModalDeck, printed: str) -> list[float]:
    """The FE's natural frequencies (Hz), as fe_modes."""
    return [m.frequency for m in fe_modes(modal, printed)]


def mac(a: Sequence[float], b: Sequence[float], weights: Sequence[float]) -> float:
    """The mass-weighted modal assurance criterion (a'Mb)²/((a'Ma)(b'Mb)), 0 to 1 (1: the same
    shape); 0 when either shape has no motion with mass."""
    ab = sum(w * x * y for w, x, y in zip(weights, a, b))
    aa = sum(w * x * x for w, x in zip(weights, a))
    bb = sum(w * y * y for w, y in zip(weights, b))
    return ab * ab / (aa * bb) if aa > 0 and bb > 0 else 0.0


def pair(
    fe: Sequence[Mode], level: Sequence[Mode], weights: Sequence[float]
) -> list[tuple[int | None, float | None]]:
    """For each FE mode, the level's mode of the same shape and their MAC, (None, None) where
    none is. Candidates: a MAC of at least MATCH, and an FE mode whose mass sits mostly in the
    links (share at least SHARE: not a plate's own mode, in which a massless link may still
    move alike); each mode paired once, the pairs nearest in frequency first."""
    candidates = sorted(
        (abs(math.log(a.frequency / b.frequency)), k, j, score)
        for k, a in enumerate(fe)
        for j, b in enumerate(level)
        if (a.share is None or a.share >= SHARE)
        and (score := mac(a.shape, b.shape, weights)) >= MATCH
    )
    out: list[tuple[int | None, float | None]] = [(None, None)] * len(fe)
    used: set[int] = set()
    for _, k, j, score in candidates:
        if j in used or out[k][0] is not None:
            continue
        out[k] = (j, score)
        used.add(j)
    return out


@dataclass(frozen=True)
class ModalComparison:
    """The FE's modes beside those of `symkin modes` at each physical level (a level that
    cannot give them holds its message under `failed`), each FE mode paired with the level's
    mode of the same shape."""

    fea: list[Mode]
    levels: dict[str, list[Mode]]
    failed: dict[str, str]
    modal: ModalDeck
    notes: tuple[str, ...] = ()

    def pairs(self, level: str) -> list[tuple[int | None, float | None]]:
        weights = [w for m in self.modal.masses for w in (m.mass, m.mass, m.inertia)]
        return pair(self.fea, self.levels.get(level, []), weights)

    def difference(self, k: int, level: str) -> float | None:
        """(f_level - f_fea)/f_fea of FE mode k (from 0) and the level's mode of its shape;
        None where the level has none."""
        j = self.pairs(level)[k][0] if k < len(self.fea) else None
        if j is None:
            return None
        return (self.levels[level][j].frequency - self.fea[k].frequency) / self.fea[k].frequency

    def as_json(self) -> dict:
        out: dict = {
            "count": self.modal.count,
            "plate_density": self.modal.density,
            "fea": [m.frequency for m in self.fea],
            "fea_link_share": [m.share for m in self.fea],
        }
        for level in LEVELS:
            out[level] = [m.frequency for m in self.levels[level]] if level in self.levels else None
        out["pairs"] = {
            level: [
                None if j is None else {"mode": j + 1, "mac": score}
                for j, score in self.pairs(level)
            ]
            if level in self.levels
            else None
            for level in LEVELS
        }
        out["difference"] = {
            level: [self.difference(k, level) for k in range(len(self.fea))]
            if level in self.levels
            else None
            for level in LEVELS
        }
        if self.failed:
            out["failed"] = dict(self.failed)
        if self.notes:
            out["notes"] = list(self.notes)
        return out


def symkin_modes(
    setup: Setup, count: int, masses: Sequence[LinkMass]
) -> tuple[dict[str, list[Mode]], dict[str, str]]:
    """`symkin modes` at both physical levels and the set-up configuration, their shapes in
    the FE's units (m, rad) at the massive links' centres."""
    out, failed = {}, {}
    scale = setup.conf.scale
    for level in LEVELS:
        try:
            found = natural_modes(setup.mechanism, setup.inputs, level, setup.overrides, count)
        except AssemblyError as exc:
            failed[level] = str(exc)
            continue
        out[level] = [
            Mode(
                f,
                [
                    v
                    for m in masses
                    for v in (
                        links[m.link][0] * scale,
                        links[m.link][1] * scale,
                        links[m.link][2],
                    )
                ],
            )
            for f, links in zip(found.frequencies, found.links)
        ]
    return out, failed


def compare_modes(
    setup: Setup,
    modal: ModalDeck,
    progress: Callable[[str], None] | None = None,
    threads: int | None = None,
    keep: str | Path | None = None,
) -> tuple[Comparison, ModalComparison]:
    """Run ccx on the modal deck: the static comparison (symkin.fea.compare) and the
    frequencies beside symkin's."""
    static = compare(setup, modal.deck, progress, threads, keep)
    levels, failed = symkin_modes(setup, modal.count, modal.masses)
    found = fe_modes(modal, static.printed)
    return static, ModalComparison(found, levels, failed, modal, loaded_note(setup))


def loaded_note(setup: Setup) -> tuple[str, ...]:
    """ccx's frequency step takes the plates' stresses into the stiffness but not the rigid
    bodies' geometric stiffness (the loads and loop forces the rigid links carry as they turn):
    a loaded mechanism whose softening sits in its links is not softened there (docs/fea.md)."""
    conf = setup.conf
    forces = [ld.label for ld in conf.loads if ld.force != (0.0, 0.0) or ld.moment]
    forces += [f"actuator '{d.name}'" for d in conf.drives if d.drive == "force" and d.force]
    if not forces:
        return ()
    return (
        f"loaded ({', '.join(forces)}): ccx's frequency step leaves out the geometric stiffness "
        "of the rigid links, so a load that softens the mechanism through its links (a "
        "preloaded stage on rigid legs) does not soften the FE's frequencies (docs/fea.md)",
    )


def text(result: ModalComparison) -> str:
    """The frequencies as a table: per FE mode its frequency and, per level, the level's mode of
    the same shape (its number, frequency and relative difference); then the levels' modes of
    no FE mode's shape."""
    modal = result.modal
    plates = (
        "massless plates (as symkin's model)"
        if not modal.density
        else f"plates of {modal.density:g} kg/m^3 (symkin's are massless: their own modes have "
        "no symkin mode)"
    )
    levels = [level for level in LEVELS if level in result.levels]
    head = f"{'mode':<6} {'fea (Hz)':>14} {'in links':>9}" + "".join(
        f" {level + ': mode (Hz)':>31} {'difference':>11}" for level in levels
    )
    lines = [
        f"natural frequencies, every input held; {plates}",
        f"each FE mode beside the level's mode of its shape (mass-weighted MAC >= {MATCH:g}, "
        f"'in links' >= {100 * SHARE:g} %: the links' share of the FE mode's modal mass); "
        "difference = (f - f_fea)/f_fea",
        head,
    ]
    pairs = {level: result.pairs(level) for level in levels}
    for k, mode in enumerate(result.fea):
        share = "-" if mode.share is None else f"{100 * mode.share:.1f} %"
        line = f"{k + 1:<6} {mode.frequency:>14.7g} {share:>9}"
        for level in levels:
            j, _ = pairs[level][k]
            if j is None:
                line += f" {'-':>14} {'':>16} {'':>11}"
                continue
            d = result.difference(k, level)
            f = result.levels[level][j].frequency
            line += f" {'mode ' + str(j + 1):>14} {f:>16.7g} {f'{100 * d:+.3f} %':>11}"
        lines.append(line)
    for level in levels:
        matched = {j for j, _ in pairs[level]}
        for j, mode in enumerate(result.levels[level]):
            if j not in matched:
                lines.append(
                    f"{level} mode {j + 1} ({mode.frequency:.7g} Hz): no FE mode of its shape "
                    "among those found (ask for more with --modes)"
                )
    for level, message in result.failed.items():
        lines.append(f"{level}: no frequencies ({message})")
    lines += [f"note: {n}" for n in result.notes]
    return "\n".join(line.rstrip() for line in lines) + "\n"
