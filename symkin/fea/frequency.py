"""The natural frequencies in CalculiX (docs/fea.md, "Natural frequencies"): the deck of
symkin.fea.deck with the links' masses on their rigid bodies and a frequency step after the
static one, and its frequencies beside `symkin modes` at both physical levels.

A link's mass is a `MASS` element at its centre, a member node of its rigid body. ccx 2.20 has
no rotary inertia for a rigid body, so a link with an inertia I gets two point masses m/2 at its
centre ± √(I/m) along x instead of one: the same mass, centre and inertia about the centre.
The plates have density 0 unless asked otherwise (symkin's plates are massless). The frequency
step is a `*STEP, PERTURBATION` after the NLGEOM static step: about its end, with the static
step's boundary conditions (every input held, a stroke actuator at its stroke, a force actuator
at its force) and the plates' stresses (their geometric stiffness). It comes last: a static
step after it would start again from the undeformed shape.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable, Sequence
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
#: Steel's density (kg/m³), the one docs/fea.md measured the plates' own mass with.
STEEL = 7850.0
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
        raise InputError(f"--modes {count}: at least one mode", entry="--modes", hint="--modes 3")
    if not (math.isfinite(density) and density >= 0):
        raise InputError(
            f"--plate-density {density}: a density is finite and at least 0",
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


def frequencies(modal: ModalDeck, printed: str) -> list[float]:
    """The FE's natural frequencies (Hz), lowest first, at most `modal.count`: with massless
    plates the modes of their negligible mass left out (SPURIOUS)."""
    values = eigenvalues(printed)
    if not values:
        raise AssemblyError("ccx printed no eigenvalues for the frequency step")
    found = sorted(math.sqrt(v) / (2 * math.pi) for v in values if v > 0)
    if modal.density == 0 and found:
        found = [f for f in found if f <= SPURIOUS * found[0]]
    return found[: modal.count]


@dataclass(frozen=True)
class ModalComparison:
    """The FE's frequencies (Hz) beside those of `symkin modes` at each physical level (a
    level that cannot give them holds its message under `failed`)."""

    fea: list[float]
    levels: dict[str, list[float]]
    failed: dict[str, str]
    modal: ModalDeck
    notes: tuple[str, ...] = ()

    def difference(self, k: int, level: str) -> float | None:
        """(f_level - f_fea)/f_fea of mode k (from 0); None where either is missing, and with
        the plates' density, whose own modes come in between (mode k is then not symkin's
        mode k: compare them by their shapes, in cgx)."""
        values = self.levels.get(level, [])
        if self.modal.density or k >= len(values) or k >= len(self.fea):
            return None
        return (values[k] - self.fea[k]) / self.fea[k]

    def as_json(self) -> dict:
        count = max([len(self.fea), *(len(v) for v in self.levels.values())])
        out: dict = {
            "count": self.modal.count,
            "plate_density": self.modal.density,
            "fea": list(self.fea),
        }
        for level in LEVELS:
            out[level] = list(self.levels[level]) if level in self.levels else None
        out["difference"] = {
            level: [self.difference(k, level) for k in range(count)]
            if level in self.levels
            else None
            for level in LEVELS
        }
        if self.failed:
            out["failed"] = dict(self.failed)
        if self.notes:
            out["notes"] = list(self.notes)
        return out


def symkin_frequencies(setup: Setup, count: int) -> tuple[dict[str, list[float]], dict[str, str]]:
    """`symkin modes` at both physical levels and the set-up configuration."""
    out, failed = {}, {}
    for level in LEVELS:
        try:
            found = natural_modes(setup.mechanism, setup.inputs, level, setup.overrides, count)
        except AssemblyError as exc:
            failed[level] = str(exc)
            continue
        out[level] = list(found.frequencies)
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
    levels, failed = symkin_frequencies(setup, modal.count)
    found = frequencies(modal, static.printed)
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
    """The frequencies as a table: per mode the FE's, each level's and its relative difference."""
    modal = result.modal
    plates = (
        "massless plates (density 0, as symkin's model)"
        if not modal.density
        else f"plates of {modal.density:g} kg/m^3 (symkin's are massless; their own modes "
        "come in between, so no differences: match the modes by their shapes in the .frd)"
    )
    levels = [level for level in LEVELS if level in result.levels]
    head = f"{'mode':<6} {'fea (Hz)':>14}" + "".join(
        f" {level + ' (Hz)':>18} {'difference':>11}" for level in levels
    )
    lines = [
        f"natural frequencies, every input held; {plates}; difference = (f - f_fea)/f_fea",
        head,
    ]
    rows = max([len(result.fea), *(len(result.levels[lv]) for lv in levels)])
    for k in range(rows):
        fe = f"{result.fea[k]:.7g}" if k < len(result.fea) else "-"
        line = f"{k + 1:<6} {fe:>14}"
        for level in levels:
            values = result.levels[level]
            f = f"{values[k]:.7g}" if k < len(values) else "-"
            d = result.difference(k, level)
            line += f" {f:>18} {'' if d is None else f'{100 * d:+.3f} %':>11}"
        lines.append(line)
    for level, message in result.failed.items():
        lines.append(f"{level}: no frequencies ({message})")
    lines += [f"note: {n}" for n in result.notes]
    return "\n".join(line.rstrip() for line in lines) + "\n"
