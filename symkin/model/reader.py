"""Mechanism file reader and validator (docs/file-format.md, `format = 1`).

`load(path)` returns an immutable :class:`~.mechanism.Mechanism` or raises :class:`InputError`
naming the file, the line, the entry and the fix. Nothing in the file is executed: TOML is parsed
by `tomllib` and expression strings by the whitelist parser of :mod:`symkin.model.expressions`.
The checks of one entry are :mod:`.entry_checks`, the hinges' :mod:`.hinge_entries`; this module
reads the top level, the parameters, links, points, loads and actuators, and applies the rules
of the whole file (connected, its inputs numbering the mobility, the actuators' surrogate hinges).
"""

from __future__ import annotations

import dataclasses
import re
import tomllib
from collections.abc import Mapping, Sequence
from pathlib import Path

import sympy as sp

from ..core.errors import InputError, suggest
from ..core.files import Unreadable, read_input
from . import expressions
from .closure import surrogate_hinges
from .entries import DRIVES, Actuator, Hinge, Link, Load, Parameter, Point, short
from .entry_checks import entry_name, name_problem
from .hinge_entries import DEFAULT_KEYS, HingeEntries
from .mechanism import UNITS, Mechanism, check_values, closure_rank

FORMAT = 1
TOP_KEYS = (
    "format",
    "name",
    "ground",
    "chords",
    "basic_chain",
    "units",
    "parameters",
    "defaults",
    "link",
    "hinge",
    "point",
    "load",
    "actuator",
)
LINK_KEYS = ("name", "mass", "inertia", "centre")
POINT_KEYS = ("name", "link", "at")
LOAD_KEYS = ("point", "link", "at", "force", "moment")
ACTUATOR_KEYS = ("name", "link", "at", "direction", "drive", "spring", "stiffness")


#: The largest mechanism file read (a regular file: a FIFO or a device is refused unread).
MAX_FILE_BYTES = 1 << 20


def load(path: str | Path) -> Mechanism:
    """Read and validate a mechanism file; raise InputError (exit 2) on anything wrong with it
    (and on anything that is not a regular file of at most MAX_FILE_BYTES)."""
    path = Path(path)
    shown = str(path)
    try:
        raw = read_input(path, MAX_FILE_BYTES)
    except Unreadable as exc:
        raise InputError(exc.reason, file=shown, hint=exc.hint) from None
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise InputError(
            f"not UTF-8 text (byte {exc.start})", file=shown, hint="save the file as UTF-8"
        ) from None
    return loads(text, shown, base_dir=path.parent)


def loads(text: str, file: str = "<string>", base_dir: Path | None = None) -> Mechanism:
    """Validate a mechanism given as TOML text; `file` is the name used in error messages."""
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        line = _line_from_toml_error(str(exc))
        raise InputError(
            f"TOML syntax error: {exc}",
            file=file,
            line=line,
            hint="fix the TOML syntax at that line",
        ) from None
    except ValueError as exc:  # an integer of more than 4300 digits
        raise InputError(
            f"a TOML number with too many digits ({str(exc)[:80]})",
            file=file,
            hint="write long numbers with an exponent, e.g. 1.5e30",
        ) from None
    except RecursionError:
        raise InputError(
            "TOML nesting too deep (arrays or tables inside each other)",
            file=file,
            hint="a mechanism file needs at most a few levels of nesting",
        ) from None
    return _Reader(text, file, base_dir or Path(".")).read(data)


#: Exact parameter values up to this size; beyond, the 60-digit numeric value (a chain such as
#: c_k = c_(k-1)**2 doubles the digits of the exact value every line).
EXACT_BITS = 256
EXACT_OPS = 64


def _bounded_exact(expr: sp.Expr, defaults: Mapping[sp.Symbol, sp.Expr]) -> sp.Expr | None:
    """The exact value of a parameter's expression, or None when it is large (then the
    60-digit numeric value serves)."""
    exact = expr.xreplace({s: defaults[s] for s in expr.free_symbols if s in defaults})
    if not exact.is_number:
        return None
    if exact.is_Rational:
        return exact if max(abs(exact.p).bit_length(), exact.q.bit_length()) <= EXACT_BITS else None
    return exact if sp.count_ops(exact) <= EXACT_OPS else None


def with_points(
    mech: Mechanism, tables: Sequence[Mapping[str, object]], file: str, text: str
) -> Mechanism:
    """`mech` with further points, given as [[point]] tables (name, link, at: expressions over
    the file's parameters) of another file (a scene, docs/scene.md), validated as the file's own
    are; a name the mechanism already uses is bad input."""
    reader = _Reader(text, file, Path("."))
    reader.names = {p.name: p.symbol for p in mech.parameters}
    reader.defaults = dict(mech.defaults)
    added = reader.points(list(tables), [lk.name for lk in mech.links])
    taken = {p.name for p in mech.points}
    for p in added:
        if p.name in taken:
            raise reader.error(
                f"the mechanism already has a point '{p.name}'",
                f"[[point]] '{p.name}'",
                p.line,
                "give only its name to use the file's point, or rename it",
            )
    n = len(mech.points)
    return dataclasses.replace(
        mech,
        points=mech.points
        + tuple(dataclasses.replace(p, index=n + i) for i, p in enumerate(added)),
    )


def _line_from_toml_error(message: str) -> int | None:
    match = re.search(r"line (\d+)", message)
    return int(match.group(1)) if match else None


class _Reader(HingeEntries):
    """One pass over the parsed TOML, building the Mechanism and raising on the first problem."""

    # -- the file ------------------------------------------------------------------------------
    def read(self, data: Mapping[str, object]) -> Mechanism:
        self.check_keys(data, TOP_KEYS, "top level", None)
        fmt = data.get("format")
        if fmt is None:
            raise self.error(
                "missing required key 'format'",
                "top level",
                None,
                f"add 'format = {FORMAT}' as the first line",
            )
        if not isinstance(fmt, int) or isinstance(fmt, bool) or fmt != FORMAT:
            raise self.error(
                f"unsupported format {fmt!r}",
                "format",
                self.where.key("format"),
                f"this symkin reads format = {FORMAT}",
            )
        name = self.text(data, "name", "top level", None)
        problem = name_problem(name)
        if problem is not None:
            raise self.error(problem[0], "name", self.where.key("name"), problem[1])
        parameters = self.parameters(data.get("parameters", {}))
        defaults = self.hinge_defaults(data.get("defaults", {}))
        links = self.links(self.array_of_tables(data, "link"))
        link_names = [lk.name for lk in links]
        ground = data.get("ground", link_names[0])
        if not isinstance(ground, str) or ground not in link_names:
            raise self.error(
                f"ground {ground!r} is not a [[link]]",
                "ground",
                self.where.key("ground"),
                suggest(str(ground), link_names) or "name one of the links",
            )
        grounded = next(lk for lk in links if lk.name == ground)
        if grounded.massive:
            raise self.error(
                "the ground has a 'mass': it does not move",
                f"[[link]] #{grounded.index + 1} '{ground}'",
                grounded.line,
                "remove mass, inertia and centre from the ground link",
            )
        units = data.get("units", "m")
        if units not in UNITS:
            raise self.error(
                f"unknown length unit {units!r}",
                "units",
                self.where.key("units"),
                "units: " + ", ".join(f'"{u}"' for u in UNITS),
            )
        hinges = self.hinges(self.array_of_tables(data, "hinge"), defaults, link_names)
        points = self.points(self.array_of_tables(data, "point"), link_names)
        mech = Mechanism(
            path=self.file,
            name=name,
            ground=ground,
            parameters=parameters,
            links=links,
            hinges=hinges,
            points=points,
            chords=self.name_list(data, "chords", [h.name for h in hinges], "hinge"),
            basic_chain=self.name_list(data, "basic_chain", link_names, "link"),
            units=units,
            loads=self.loads(self.array_of_tables(data, "load"), link_names, points),
            actuators=self.actuators(
                self.array_of_tables(data, "actuator"),
                link_names,
                ground,
                parameters,
                hinges,
                points,
            ),
        )
        self.check_connected(mech)
        check_values(mech, self.defaults)
        # after the values: the rank reads the hinge positions (two pins on one spot, say)
        if mech.actuators and len(mech.drives) == mech.mobility and closure_rank(mech):
            mech = self.with_surrogates(mech)
        self.check_mobility(mech)
        return mech

    def parameters(self, table: object) -> tuple[Parameter, ...]:
        if not isinstance(table, dict):
            raise self.error(
                "[parameters] must be a table",
                "[parameters]",
                None,
                "write [parameters] on a line of its own, then name = value lines",
            )
        out = []
        for key, value in table.items():
            line = self.where.key(key, table="parameters")
            entry = f"[parameters] '{key}'"
            if not expressions.IDENTIFIER.match(key):
                raise self.error(
                    "parameter names must be identifiers",
                    entry,
                    line,
                    "use letters, digits and '_' only, not starting with a digit",
                )
            if key in expressions.RESERVED:
                raise self.error(f"'{key}' is a built-in name", entry, line, "rename the parameter")
            expr = self.expr(value, entry, key, line)
            value_ = self.finite(expr, entry, key, line)
            symbol = expressions.ParameterSymbol(key)
            exact = _bounded_exact(expr, self.defaults)
            out.append(Parameter(key, symbol, expr, exact if exact is not None else value_, line))
            self.names[key] = symbol
            self.defaults[symbol] = out[-1].value
        return tuple(out)

    def hinge_defaults(self, table: object) -> dict[str, object]:
        if not isinstance(table, dict):
            raise self.error(
                "[defaults] must be a table",
                "[defaults]",
                None,
                "write [defaults] on a line of its own, then key = value lines",
            )
        self.check_keys(table, DEFAULT_KEYS, "[defaults]", self.where.key("defaults"))
        return dict(table)

    def links(self, tables: list[Mapping[str, object]]) -> tuple[Link, ...]:
        if len(tables) < 2:
            raise self.error(
                f"a mechanism needs at least two [[link]] entries, found {len(tables)}",
                "[[link]]",
                None,
                "add the ground link and the moving links",
            )
        out = []
        for i, table in enumerate(tables):
            line = self.where.header("link", i)
            entry = entry_name("link", i, table)
            self.check_keys(table, LINK_KEYS, entry, line)
            name = self.text(table, "name", entry, line)
            out.append(self.link_mass(table, Link(name, i, line), f"[[link]] #{i + 1} '{name}'"))
        self.unique("link", [lk.name for lk in out], [lk.line for lk in out])
        return tuple(out)

    def link_mass(self, table: Mapping[str, object], link: Link, entry: str) -> Link:
        """`link` with the file's `mass`, `inertia` and `centre` (docs/file-format.md,
        "[[link]]"): a centre is required with a mass, and neither an inertia nor a centre
        means anything without one; their values are checked by check_values."""
        line = link.line
        if "mass" not in table:
            for key in ("inertia", "centre"):
                if key in table:
                    raise self.error(
                        f"'{key}' without 'mass': the link is massless",
                        entry,
                        line,
                        "add mass = ... (kg, the link with whatever it carries), or remove "
                        f"'{key}'",
                    )
            return link
        if "centre" not in table:
            raise self.error(
                "'mass' without 'centre'",
                entry,
                line,
                "add centre = [x, y], the link's centre of mass as fabricated (file unit)",
            )
        mass = self.expr(table["mass"], entry, "mass", line)
        self.finite(mass, entry, "mass", line)
        inertia = None
        if "inertia" in table:
            inertia = self.expr(table["inertia"], entry, "inertia", line)
            self.finite(inertia, entry, "inertia", line)
        centre = self.vector(table["centre"], entry, "centre", line)
        return dataclasses.replace(link, mass=mass, inertia=inertia, centre=centre)

    def points(
        self, tables: list[Mapping[str, object]], link_names: list[str]
    ) -> tuple[Point, ...]:
        out = []
        for i, table in enumerate(tables):
            line = self.where.header("point", i)
            entry = entry_name("point", i, table)
            self.check_keys(table, POINT_KEYS, entry, line)
            name = self.option_name(table, entry, line, "--points")
            entry = f"[[point]] #{i + 1} '{name}'"
            link = self.text(table, "link", entry, line)
            if link not in link_names:
                raise self.error(
                    f"point on an unknown link '{link}'",
                    entry,
                    line,
                    suggest(link, link_names) or "name one of the [[link]] entries",
                )
            if "at" not in table:
                raise self.error("missing required key 'at'", entry, line, "add at = [x, y]")
            out.append(Point(name, i, link, self.vector(table["at"], entry, "at", line), line))
        self.unique("point", [p.name for p in out], [p.line for p in out])
        return tuple(out)

    def loads(
        self, tables: list[Mapping[str, object]], link_names: list[str], points: tuple[Point, ...]
    ) -> tuple[Load, ...]:
        """[[load]] entries: on a named point, or on a link at a position; a force, a moment or
        both (docs/physics.md)."""
        out = []
        point_names = [p.name for p in points]
        for i, table in enumerate(tables):
            line = self.where.header("load", i)
            entry = f"[[load]] #{i + 1}"
            self.check_keys(table, LOAD_KEYS, entry, line)
            if "point" in table:
                if "link" in table or "at" in table:
                    raise self.error(
                        "give either 'point' or 'link' with 'at', not both",
                        entry,
                        line,
                        "remove 'link'/'at', or remove 'point'",
                    )
                name = self.text(table, "point", entry, line)
                if name not in point_names:
                    raise self.error(
                        f"load on an unknown point '{name}'",
                        entry,
                        line,
                        suggest(name, point_names)
                        or "name one of the [[point]] entries, or use link and at",
                    )
                point = next(p for p in points if p.name == name)
                link, at = point.link, point.at
            elif "link" in table:
                link = self.text(table, "link", entry, line)
                if link not in link_names:
                    raise self.error(
                        f"load on an unknown link '{link}'",
                        entry,
                        line,
                        suggest(link, link_names) or "name one of the links",
                    )
                if "at" not in table:
                    raise self.error(
                        "a load on a link needs 'at'",
                        entry,
                        line,
                        "add at = [x, y], where the load acts (as fabricated)",
                    )
                name, at = None, self.vector(table["at"], entry, "at", line)
            else:
                raise self.error(
                    "a load needs 'point', or 'link' and 'at'",
                    entry,
                    line,
                    'add point = "C" (a [[point]]) or link = ... with at = [x, y]',
                )
            if "force" not in table and "moment" not in table:
                raise self.error(
                    "a load needs a 'force', a 'moment' or both",
                    entry,
                    line,
                    "add force = [Fx, Fy] (N) and/or moment = M (N·m)",
                )
            force = (
                self.vector(table["force"], entry, "force", line)
                if "force" in table
                else (sp.Integer(0), sp.Integer(0))
            )
            moment = self.expr(table.get("moment", 0), entry, "moment", line)
            self.finite(moment, entry, "moment", line)
            out.append(Load(i, link, at, force, moment, name, line))
        return tuple(out)

    def actuators(
        self,
        tables: list[Mapping[str, object]],
        link_names: list[str],
        ground: str,
        parameters: tuple[Parameter, ...],
        hinges: tuple[Hinge, ...],
        points: tuple[Point, ...],
    ) -> tuple[Actuator, ...]:
        """[[actuator]] entries (docs/file-format.md, "Actuators"): a named stroke or force
        along a line of action on a moving link; the surrogate hinges are chosen later, with
        the mobility (:meth:`check_mobility`)."""
        out = []
        taken = {h.name: "a hinge" for h in hinges}
        taken |= {p.name: "a point" for p in points}
        taken |= {p.name: "a parameter" for p in parameters}
        for i, table in enumerate(tables):
            line = self.where.header("actuator", i)
            entry = entry_name("actuator", i, table)
            self.check_keys(table, ACTUATOR_KEYS, entry, line)
            name = self.option_name(table, entry, line, "--input")
            entry = f"[[actuator]] #{i + 1} '{name}'"
            problem = name_problem(name)
            if problem is not None:
                raise self.error(problem[0], entry, line, problem[1])
            if name in taken:
                raise self.error(
                    f"the actuator's name '{name}' is already {taken[name]}'s: an actuator "
                    "is an input, named like the input hinges",
                    entry,
                    line,
                    "give the actuator a name of its own",
                )
            taken[name] = "an actuator"
            link = self.text(table, "link", entry, line)
            if link not in link_names:
                raise self.error(
                    f"actuator on an unknown link '{link}'",
                    entry,
                    line,
                    suggest(link, link_names) or "name one of the [[link]] entries",
                )
            if link == ground:
                raise self.error(
                    f"the actuator pushes the frame '{ground}': it acts between the frame and "
                    "a moving link",
                    entry,
                    line,
                    "name the moving link it pushes in 'link'",
                )
            for key in ("at", "direction"):
                if key not in table:
                    raise self.error(
                        f"missing required key '{key}'",
                        entry,
                        line,
                        "add at = [x, y] (the point of action on the link, as fabricated)"
                        if key == "at"
                        else "add direction = [dx, dy] (the line of action, frame axes)",
                    )
            at = self.vector(table["at"], entry, "at", line)
            raw = self.vector(table["direction"], entry, "direction", line)
            size = sp.sqrt(raw[0] ** 2 + raw[1] ** 2)
            if not expressions.numeric(size, self.defaults) > 0:
                raise self.error(
                    f"'direction' is the zero vector {short(table['direction'])}: it gives "
                    "no line of action",
                    entry,
                    line,
                    "give the direction the actuator pushes, e.g. direction = [1.0, 0.0]",
                )
            drive = table.get("drive", "stroke")
            if drive not in DRIVES:
                raise self.error(
                    f"unknown drive {drive!r}",
                    entry,
                    line,
                    (
                        (suggest(str(drive), DRIVES) or "") + "; "
                        if suggest(str(drive), DRIVES)
                        else ""
                    )
                    + 'drive = "stroke" (a displacement, file unit) or "force" (N)',
                )
            direction = (raw[0] / size, raw[1] / size)
            spring = self.spring(table, drive, entry, line)
            out.append(Actuator(name, i, link, at, direction, drive, "", line, spring))
        return tuple(out)

    def spring(
        self, table: Mapping[str, object], drive: str, entry: str, line: int | None
    ) -> sp.Expr | None:
        """An actuator's `spring` (N per file unit, > 0 and finite with the default parameters;
        a number or an expression over the parameters): a stroke's series stiffness. `stiffness`
        is the same key under the name natural frequencies use (docs/file-format.md)."""
        given = [k for k in ("spring", "stiffness") if k in table]
        if not given:
            return None
        key = given[0]
        where = self.where.key(key, None, line) if line is not None else None
        if len(given) > 1:
            raise self.error(
                "'spring' and 'stiffness' are one key under two names",
                entry,
                where or line,
                "keep one of them (spring = k, N per file unit)",
            )
        if drive != "stroke":
            raise self.error(
                f"'{key}' is the stiffness in series with a stroke; a force actuator "
                "delivers its force whatever its own stiffness",
                entry,
                where or line,
                f"remove '{key}', or make the actuator drive = \"stroke\" (the spring's "
                "free stroke is then the input)",
            )
        expr = self.expr(table[key], entry, key, where or line)
        value = self.finite(expr, entry, key, where or line)
        if not value > 0:
            raise self.error(
                f"'{key}' must be positive, got {key} = {short(value)}",
                entry,
                where or line,
                f"give the actuator's stiffness in N per file unit, e.g. {key} = 2e4 "
                "(a piezo stack of 20 N/µm in a mm file)",
            )
        return expr

    def name_list(
        self, data: Mapping[str, object], key: str, known: list[str], kind: str
    ) -> tuple[str, ...] | None:
        if key not in data:
            return None
        value = data[key]
        line = self.where.key(key)
        if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
            raise self.error(
                f"'{key}' must be a list of {kind} names",
                key,
                line,
                f'write {key} = ["name", ...] with the names of [[{kind}]] entries',
            )
        for v in value:
            if v not in known:
                raise self.error(
                    f"unknown {kind} '{v}'",
                    key,
                    line,
                    suggest(v, known) or f"name one of the [[{kind}]] entries",
                )
        if len(set(value)) != len(value):
            raise self.error(f"'{key}' names a {kind} twice", key, line, "name each one once")
        return tuple(value)

    def check_connected(self, mech: Mechanism) -> None:
        reached = {mech.ground}
        frontier = [mech.ground]
        while frontier:
            link = frontier.pop()
            for h in mech.hinges:
                if link in h.links:
                    other = h.links[1] if h.links[0] == link else h.links[0]
                    if other not in reached:
                        reached.add(other)
                        frontier.append(other)
        lost = [lk for lk in mech.links if lk.name not in reached]
        if lost:
            names = ", ".join(f"'{lk.name}'" for lk in lost)
            raise self.error(
                f"the mechanism is disconnected: {names} cannot be reached from the "
                f"ground '{mech.ground}' through hinges",
                f"[[link]] '{lost[0].name}'",
                lost[0].line,
                "add the missing hinge or remove the link",
            )

    def check_mobility(self, mech: Mechanism) -> None:
        """The inputs (input hinges and actuators) number the mobility and fix the pose
        (docs/levels.md, "Redundant loops"): Grübler's count, corrected by the rank of the
        closure Jacobian at the as-fabricated pose when some loop constraints are dependent
        (the actuators' surrogate hinges, once chosen, stand for them)."""
        n, m = len(mech.links) - 1, len(mech.hinges)
        rank = closure_rank(mech)
        formula = f"3n - 2m = 3*{n} - 2*{m} = {mech.grubler}, with {mech.loop_count} loop(s)"
        if rank is not None and rank.mobility != mech.grubler:
            formula += (
                f"; the closure Jacobian at the as-fabricated pose has rank {rank.rank} of "
                f"2m = {2 * m} ({2 * m - rank.rank} redundant), so the mobility is "
                f"3n - {rank.rank} = {rank.mobility}"
            )
        dof = mech.grubler if rank is None else rank.mobility
        if dof == 0 and mech.is_structure:
            return  # a structure: loaded by its loads and force actuators, no input
        doubled = _doubled_pairs(mech)
        if doubled and (dof < 1 or len(mech.drives) != dof):
            # the likeliest cause of a mobility that does not match: a hinge on the wrong link
            a, b, pair = doubled[0]
            raise self.error(
                f"two hinges join {pair[0]} and {pair[1]}: '{a}' and '{b}' (the mobility is "
                f"{dof}, Grübler {formula}, and the inputs number {len(mech.drives)})",
                f"[[hinge]] '{b}'",
                None,
                f"check the links of '{a}' and '{b}': one of them is likely on the wrong link",
            )
        if dof < 1:
            raise self.error(
                f"the mechanism cannot move: Grübler mobility {formula}",
                "[[hinge]]",
                None,
                "remove hinges or add links"
                + (
                    "; or, if it is a structure to be loaded rather than moved, give it no "
                    "input (no input = true, force actuators only) and evaluate it at --level "
                    'loaded (docs/levels.md, "Structures")'
                    if dof == 0
                    else ""
                ),
            )
        if len(mech.drives) != dof:
            hinges = [n for n in mech.inputs if n not in mech.surrogates]
            given = ", ".join(hinges) or "none"
            what = f"{len(hinges)} input hinge(s) ({given})"
            if mech.actuators:
                names = ", ".join(a.name for a in mech.actuators)
                what += f" and {len(mech.actuators)} actuator(s) ({names})"
            raise self.error(
                f"{what} but the mobility is {dof}: Grübler {formula}",
                "input",
                None,
                f"mark exactly {dof} hinge(s) with input = true"
                + (" (the actuators count as inputs)" if mech.actuators else "")
                + (
                    "; or, if no loop is meant to be redundant, the as-fabricated pose is a "
                    "singular position (hinges in line, legs parallel): move a hinge off it"
                    if dof != mech.grubler
                    else ""
                ),
            )
        if rank is not None and rank.dependent:
            dependent = rank.dependent
            inputs = ", ".join(mech.inputs)
            free = ", ".join(rank.candidates) or "some hinges"
            if rank.collinear:
                raise self.error(
                    f"the hinges {free} are collinear in the as-fabricated pose: a toggle "
                    f"position, where the inputs ({inputs}) do not determine the pose (a "
                    "dependent input)",
                    "input",
                    None,
                    "move the middle hinge off the line through the other two",
                )
            if len(mech.inputs) == 1:
                which = f"the loops fix the angle of {dependent[0]}"
            elif len(dependent) == 1:
                which = f"the angle of {dependent[0]} follows from the other inputs'"
            else:
                which = f"one of {', '.join(dependent)} follows from the " + (
                    "other" if len(dependent) == 2 else "others"
                )
            raise self.error(
                f"the input hinges {inputs} do not determine the pose: in the as-fabricated "
                f"pose {which} (a dependent input), which leaves {free} free to move",
                "input",
                None,
                (f"mark one of {free}" if rank.candidates else "mark another hinge")
                + " as input instead of "
                + (dependent[0] if len(dependent) == 1 else f"one of {', '.join(dependent)}"),
            )

    def with_surrogates(self, mech: Mechanism) -> Mechanism:
        """Refuse actuators that do not drive the mechanism (with the input hinges they must
        fix the pose), then choose each one's surrogate hinge (:func:`surrogate_hinges`) and
        mark it as an input of the kinematics."""
        found = surrogate_hinges(mech)
        if isinstance(found, Actuator):
            others = ", ".join(n for n in mech.drives if n != found.name) or "none"
            raise self.error(
                f"the actuator '{found.name}' does not drive the mechanism: in the as-fabricated "
                f"pose its line of action is normal to every motion of its point that the other "
                f"inputs ({others}) leave free",
                f"[[actuator]] #{found.index + 1} '{found.name}'",
                found.line,
                "change its direction or its point 'at', or drive a hinge instead (input = true)",
            )
        hinges = tuple(
            dataclasses.replace(h, input=True) if h.name in found else h for h in mech.hinges
        )
        actuators = tuple(
            dataclasses.replace(a, surrogate=s) for a, s in zip(mech.actuators, found)
        )
        return dataclasses.replace(mech, hinges=hinges, actuators=actuators)


def _doubled_pairs(mech: Mechanism) -> list[tuple[str, str, tuple[str, str]]]:
    """Hinges joining a pair of links that an earlier hinge already joins: (earlier hinge,
    hinge, the pair), in file order."""
    seen: dict[frozenset[str], str] = {}
    out = []
    for h in mech.hinges:
        key = frozenset(h.links)
        if key in seen:
            out.append((seen[key], h.name, (h.links[0], h.links[1])))
        else:
            seen[key] = h.name
    return out
