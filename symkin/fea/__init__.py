"""Finite-element verification (docs/fea.md): a CalculiX model of a mechanism in one
configuration, and its deviations beside symkin's physical levels.

    setup = symkin.fea.prepare("examples/four_bar.toml", {"A0": 0.2})
    deck = symkin.fea.write_deck(setup, symkin.fea.Mesh(40, 4, 0.8))   # the .inp, its readout
    result = symkin.fea.compare(setup, deck)              # runs ccx, then equilibrium, loaded

`symkin fea` (symkin.fea.command) is the command line over these.
"""

from __future__ import annotations

import dataclasses
import math
import os
import tempfile
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path

from . import ccx
from ._symkin import AssemblyError, InputError, Mechanism, Point, analyze, evaluate, load
from .deck import DEFAULT_MESH, Configuration, Deck, Mesh, anchors, configuration, parse_mesh, write
from .material import DEFAULT_LAW, LAWS, parse_law

#: The levels the FE deviation is compared with.
LEVELS = ("equilibrium", "loaded")

Vec = tuple[float, float]


@dataclass(frozen=True)
class Setup:
    """A mechanism at one input: its analysis (for the physical levels), the parsed inputs and
    parameters, and the deck's numbers with the rigid linkage's pose."""

    mechanism: Mechanism
    analysis: object
    inputs: dict[str, float]
    params: dict[str, float]
    overrides: dict[str, object]
    conf: Configuration


def prepare(
    mechanism: Mechanism | str | Path,
    inputs: Mapping[str, object],
    params: Mapping[str, object] | None = None,
) -> Setup:
    """Read the mechanism, solve the rigid linkage at `inputs` (names -> angles in radians,
    numbers or expression strings) and gather the deck's numbers. Bad inputs raise InputError,
    an input the rigid linkage cannot reach AssemblyError."""
    mech = mechanism if isinstance(mechanism, Mechanism) else load(mechanism)
    sprung = next((a for a in mech.actuators if a.spring is not None), None)
    if sprung is not None:
        # the deck prescribes a stroke rigidly: a series spring would need a spring element
        raise InputError(
            f"symkin fea does not model an actuator's series spring yet (actuator "
            f"'{sprung.name}' has spring)",
            file=mech.path,
            entry=f"[[actuator]] #{sprung.index + 1} '{sprung.name}'",
            hint="compare the actual stroke symkin eval --level equilibrium reports: remove "
            "'spring' and give that stroke as the input",
        )
    plan = anchors(mech)
    # A force actuator's rigid pose is the rigid linkage's at the stroke the force produces:
    # `equilibrium`'s here (the FE's own stroke corrects it after the run, see `compare`).
    kinematic, forces = _as_strokes(mech), {}
    # a structure's rigid pose is the as-fabricated one whatever loads it (its force actuators'
    # strokes are 0 there), and only the physical levels evaluate it (docs/levels.md)
    rigid_level = "loaded" if mech.is_structure else "paper"
    if mech.is_structure:
        kinematic = mech
    if any(a.drive == "force" for a in mech.actuators):
        eq = evaluate(analyze(mech), inputs, level="equilibrium", params=params)
        forces = {a.name: float(eq.inputs[a.name]) for a in mech.actuators if a.drive == "force"}
        inputs = {
            **eq.inputs,
            **{n: 0.0 if mech.is_structure else float(eq.actuators[n].stroke) for n in forces},
        }
    # The rigid linkage's pose of every link's own reference node: as extra points of the
    # mechanism, evaluated at the `paper` level (its rigid part is every level's).
    taken = {p.name for p in mech.points}
    extra = []
    for link, anchor in plan.items():
        if anchor.parent is None and anchor.point is None:
            name = f"fea_reference_{link}"
            while name in taken:
                name += "_"
            taken.add(name)
            extra.append(Point(name, len(mech.points) + len(extra), link, anchor.at))
            plan[link] = dataclasses.replace(anchor, point=name)
    with_refs = dataclasses.replace(kinematic, points=mech.points + tuple(extra))
    rigid = evaluate(analyze(with_refs), inputs, level=rigid_level, params=params)
    conf = configuration(
        mech,
        rigid.inputs,
        rigid.params,
        plan,
        {name: p.rigid for name, p in rigid.points.items()},
        {name: r.rigid for name, r in rigid.links.items()},
        forces,
    )
    given = {**rigid.inputs, **forces}  # what the levels take: a force actuator's force
    return Setup(mech, analyze(mech), given, dict(rigid.params), dict(params or {}), conf)


def _as_strokes(mech: Mechanism) -> Mechanism:
    """`mech` with every actuator a stroke: the rigid linkage of a force-driven one."""
    strokes = tuple(dataclasses.replace(a, drive="stroke") for a in mech.actuators)
    return dataclasses.replace(mech, actuators=strokes) if mech.actuators else mech


def write_deck(
    setup: Setup,
    mesh: Mesh = DEFAULT_MESH,
    released: tuple[str, ...] = (),
    law: str = DEFAULT_LAW,
) -> Deck:
    """The CalculiX deck of the set-up mechanism, `mesh` elements per plate, the plates of the
    finite-strain `law` (fea.material: "svk" or "neo-hookean"); `released` input hinges are left
    free (the deviation is then taken against the rigid linkage at their given angle)."""
    return write(setup.conf, mesh, released, law)


def save(content: str | bytes, folder: str | Path, name: str, suffix: str = ".inp") -> Path:
    """Write `content` to folder/name+suffix all or nothing: a temporary file in the folder,
    renamed into place."""
    target = Path(folder)
    if target.exists() and not target.is_dir():
        raise InputError(
            f"'{folder}' is a file, not a folder",
            entry="-o",
            hint="give a folder (it is created if missing)",
        )
    try:
        target.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=f".{name}.", suffix=".tmp", dir=target)
        try:
            with os.fdopen(fd, "wb") as f:
                f.write(content.encode("utf-8") if isinstance(content, str) else content)
            os.replace(tmp, target / f"{name}{suffix}")
        except BaseException:
            os.unlink(tmp)
            raise
    except OSError as exc:
        raise InputError(
            f"cannot write into '{folder}' ({exc.strerror or exc})",
            entry="-o",
            hint="choose a folder you can write to",
        ) from None
    return target / f"{name}{suffix}"


def deviations(deck: Deck, run: ccx.Run) -> dict[str, Vec]:
    """Each point's FE deviation from the rigid linkage, in the file's unit. A link's
    reference node deviates by its auxiliary node's (u_REF - u_rigid), or, when it is a pin, by
    its parent link's deviation at the pin; a point adds the rigid rotation of its arm by the
    rotation's deviation dphi, R(phi_rigid)(R(dphi) - I) arm, written without cancellation."""
    links = {r.link: r for r in deck.links}

    def at(link: str, where: Vec) -> Vec:
        if link == deck.ground:
            return (0.0, 0.0)
        r = links[link]
        du, dv, dphi = run.displacements[r.node]
        base = at(r.parent, r.ref_at) if r.parent is not None else (du, dv)
        arm = (where[0] - r.ref_at[0], where[1] - r.ref_at[1])
        # R(dphi) - I = [[h, -s], [s, h]] with h = cos dphi - 1 = -2 sin^2(dphi/2)
        h, s = -2 * math.sin(dphi / 2) ** 2, math.sin(dphi)
        ax, ay = h * arm[0] - s * arm[1], s * arm[0] + h * arm[1]
        c, sr = math.cos(r.angle), math.sin(r.angle)
        return (base[0] + c * ax - sr * ay, base[1] + sr * ax + c * ay)

    out = {}
    for t in deck.targets:
        d = at(t.link, t.at)
        out[t.name] = (d[0] / deck.scale, d[1] / deck.scale)
    return out


def strokes(deck: Deck, run: ccx.Run) -> dict[str, float]:
    """Each actuator's stroke in the FE solution (file unit): the displacement of its point
    (its link's reference node) along its direction, the deck's rigid one plus the printed
    deviation at full precision."""
    links = {r.link: r for r in deck.links}
    out = {}
    for d in deck.drives:
        du, dv, _ = run.displacements[links[d.link].node]
        rigid = d.stroke if d.rigid is None else d.rigid
        out[d.name] = (rigid + d.direction[0] * du + d.direction[1] * dv) / deck.scale
    return out


def rigid_shift(setup: Setup, produced: Mapping[str, float]) -> dict[str, Vec]:
    """Per point, how far the rigid linkage at the `produced` strokes of the force actuators
    (file unit) lies from the deck's rigid pose (at `equilibrium`'s strokes); subtracted from
    a deviation against the deck's pose, it gives the deviation at the produced strokes."""
    forces = {d.name: d for d in setup.conf.drives if d.drive == "force"}
    if not forces or setup.mechanism.is_structure:  # a structure's rigid pose stays put
        return {}
    base = {k: v for k, v in setup.inputs.items() if k not in forces}
    kinematic = analyze(_as_strokes(setup.mechanism))
    at_deck = evaluate(
        kinematic,
        {**base, **{n: d.stroke / setup.conf.scale for n, d in forces.items()}},
        level="paper",
        params=setup.overrides,
    )
    at_fe = evaluate(
        kinematic, {**base, **{n: produced[n] for n in forces}}, "paper", params=setup.overrides
    )
    return {
        name: (
            p.rigid[0] - at_deck.points[name].rigid[0],
            p.rigid[1] - at_deck.points[name].rigid[1],
        )
        for name, p in at_fe.points.items()
    }


@dataclass(frozen=True)
class Comparison:
    """FE deviations beside the physical levels' (file unit), per point; a level that could not
    be evaluated holds its error message instead."""

    setup: Setup
    mesh: Mesh
    fea: dict[str, Vec]
    levels: dict[str, dict[str, Vec]]
    failed: dict[str, str]
    ccx_seconds: float
    ccx_cpu_seconds: float
    deck: Deck
    notes: tuple[str, ...] = field(default=())
    strokes: dict[str, float] = field(default_factory=dict)  # per actuator: the FE's stroke
    level_strokes: dict[str, float] = field(default_factory=dict)  # and equilibrium's
    printed: str = field(default="", repr=False)  # ccx's .dat (a frequency step's eigenvalues)

    def difference(self, point: str, level: str) -> float | None:
        """|dR_level - dR_fea| / |dR_fea| (None where the level failed or dR_fea is 0)."""
        if level not in self.levels:
            return None
        a, b = self.fea[point], self.levels[level][point]
        norm = math.hypot(*a)
        return math.hypot(b[0] - a[0], b[1] - a[1]) / norm if norm else None

    def as_json(self) -> dict:
        points = {}
        for p, dev in self.fea.items():
            entry: dict = {"fea": list(dev)}
            for level in LEVELS:
                entry[level] = list(self.levels[level][p]) if level in self.levels else None
            entry["difference"] = {level: self.difference(p, level) for level in LEVELS}
            points[p] = entry
        out = {
            "points": points,
            "mesh": [self.mesh.along, self.mesh.across],
            "grading": self.mesh.grading,
            "law": self.deck.law,
            "ccx_seconds": self.ccx_seconds,
            "ccx_cpu_seconds": self.ccx_cpu_seconds,
            "inputs": dict(self.setup.inputs),
            "nodes": self.deck.nodes,
            "elements": self.deck.elements,
        }
        if self.strokes:
            out["actuators"] = {
                name: {"fea": s, "equilibrium": self.level_strokes.get(name)}
                for name, s in self.strokes.items()
            }
        if self.failed:
            out["failed"] = dict(self.failed)
        return out


def levels(setup: Setup) -> tuple[dict[str, dict[str, Vec]], dict[str, str]]:
    """The `equilibrium` and `loaded` deviations of the points (file unit); a level that cannot
    be evaluated (AssemblyError) is reported by its message instead."""
    out, failed = {}, {}
    for level in LEVELS:
        try:
            ev = evaluate(setup.analysis, setup.inputs, level=level, params=setup.overrides)
        except AssemblyError as exc:
            failed[level] = str(exc)
            continue
        except InputError as exc:  # `loaded` takes no actuators and no notches yet
            notched = any(h.profile != "uniform" for h in setup.mechanism.hinges)
            if not setup.mechanism.actuators and not (level == "loaded" and notched):
                raise
            failed[level] = str(exc)
            continue
        out[level] = {name: tuple(p.deviation) for name, p in ev.points.items()}
    return out, failed


def level_strokes(setup: Setup) -> dict[str, float]:
    """`equilibrium`'s stroke of each actuator (file unit): a force actuator's produced one."""
    if not setup.mechanism.actuators:
        return {}
    ev = evaluate(setup.analysis, setup.inputs, level="equilibrium", params=setup.overrides)
    return {name: float(a.stroke) for name, a in ev.actuators.items()}


def compare(
    setup: Setup,
    deck: Deck,
    progress: Callable[[str], None] | None = None,
    threads: int | None = None,
    keep: str | Path | None = None,
) -> Comparison:
    """Run ccx on `deck` and set its deviations beside `equilibrium` and `loaded`; with
    `keep`, ccx's results (<name>.frd for cgx, <name>.dat) are written into that folder."""
    ccx.executable()
    values, failed = levels(setup)
    name = setup.mechanism.name
    try:
        result = ccx.run(deck, name, progress, threads)
    except ccx.Failed as exc:
        if keep is None:
            raise
        log = save(exc.log, keep, name, ".log")
        raise AssemblyError(
            f"{exc}; ccx's output is in {log}. A smaller input, smaller loads "
            "or a finer mesh may converge"
        ) from None
    if keep is not None:
        save(result.results, keep, name, ".frd")
        save(result.printed, keep, name, ".dat")
    fe = deviations(deck, result)
    produced = strokes(deck, result)
    for point, shift in rigid_shift(setup, produced).items():
        fe[point] = (fe[point][0] - shift[0], fe[point][1] - shift[1])
    return Comparison(
        setup,
        deck.mesh,
        fe,
        values,
        failed,
        result.seconds,
        result.cpu_seconds,
        deck,
        plate_notes(setup),
        produced,
        level_strokes(setup) if "equilibrium" in values else {},
        result.printed,
    )


def plate_notes(setup: Setup) -> tuple[str, ...]:
    """What the comparison should be read with: plates the levels bend with E (b < 5 t) while
    the continuum is always in plane strain (E/(1 - nu^2))."""
    narrow = [p.hinge for p in setup.conf.plates if p.width < 5 * p.thickness and p.nu]
    if not narrow:
        return ()
    return (
        f"plates {', '.join(narrow)} are narrower than 5 thicknesses: symkin's levels bend "
        "them with E, the plane-strain continuum with E/(1 - nu^2)",
    )


__all__ = [
    "DEFAULT_LAW",
    "DEFAULT_MESH",
    "LAWS",
    "LEVELS",
    "Comparison",
    "Deck",
    "Mesh",
    "Setup",
    "compare",
    "deviations",
    "parse_law",
    "parse_mesh",
    "prepare",
    "rigid_shift",
    "save",
    "strokes",
    "write_deck",
]
