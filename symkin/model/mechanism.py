"""Mechanism file reader and validator (docs/file-format.md, `format = 1`).

`load(path)` returns an immutable :class:`Mechanism` or raises :class:`InputError` naming the file,
the line, the entry and the fix. Nothing in the file is executed: TOML is parsed by `tomllib` and
expression strings by the whitelist parser of :mod:`symkin.expressions`.
"""

from __future__ import annotations

import csv
import dataclasses
import io
import keyword
import math
import os
import re
import stat
import sys
import tomllib
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path

import mpmath
import numpy as np
import sympy as sp

from ..core.errors import InputError, suggest
from . import expressions
from .hinges import (
    BEAMS,
    HINGE_KEYS,
    MODEL_KEYS,
    MODELS,
    PINS,
    PLATE_LENGTH,
    PRBM_PRESETS,
    THETA,
    ModelParameter,
    ModelSpec,
    pivot_distance,
)

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
LINK_KEYS = ("name",)
POINT_KEYS = ("name", "link", "at")
LOAD_KEYS = ("point", "link", "at", "force", "moment")
ACTUATOR_KEYS = ("name", "link", "at", "direction", "drive")
#: How an actuator drives its link (docs/file-format.md, "Actuators"): a prescribed displacement
#: of its point along its line of action (file unit), or a force along it (N).
DRIVES = ("stroke", "force")
#: The file's length unit (`units`), in metres: geometry, lengths, thickness, width and load points
#: are in it; E is in Pa, forces in N, moments in N·m (docs/physics.md).
UNITS: dict[str, sp.Rational] = {
    "m": sp.Integer(1),
    "mm": sp.Rational(1, 10**3),
    "um": sp.Rational(1, 10**6),
}
#: The keys a physical level needs on every hinge that is not a `rigid` pin.
STIFFNESS_REQUIRED = ("E", "thickness", "width")
#: Poisson's ratio when a hinge gives none (docs/physics.md).
DEFAULT_NU = sp.Rational(3, 10)
#: The value rules of the stiffness keys: (holds for the value, what is wrong, how to fix it); the
#: test's result counts by its truth (a sympy Boolean for a sympy number).
STIFFNESS_RULES: dict[str, tuple[Callable[[sp.Expr], object], str, str]] = {
    "E": (
        lambda v: v > 0,
        "Young's modulus must be positive (Pa)",
        "give E in Pa, e.g. E = 210e9 for steel",
    ),
    "thickness": (
        lambda v: v > 0,
        "plate thickness must be positive",
        "give the thickness in the file's length unit",
    ),
    "width": (
        lambda v: v > 0,
        "plate width must be positive",
        "give the out-of-plane width in the file's length unit",
    ),
    "nu": (
        lambda v: 0 <= v < sp.Rational(1, 2),
        "Poisson's ratio must be in [0, 0.5)",
        "e.g. nu = 0.3 for steel",
    ),
    "allowable_stress": (
        lambda v: v > 0,
        "the allowable stress must be positive (Pa)",
        "give allowable_stress in Pa, e.g. allowable_stress = 300e6 (a steel's yield stress "
        "over a safety margin)",
    ),
}
DEFAULT_KEYS = tuple(k for k in HINGE_KEYS if k not in ("name", "links", "at")) + MODEL_KEYS
DEFAULT_MODEL = "circular_arc"


@dataclass(frozen=True)
class Parameter:
    """A named symbol; `expr` is its default in terms of earlier parameters, `value` that number."""

    name: str
    symbol: sp.Symbol
    expr: sp.Expr
    value: sp.Expr
    line: int | None = None


@dataclass(frozen=True)
class Link:
    name: str
    index: int  # position among the file's [[link]] entries
    line: int | None = None


@dataclass(frozen=True)
class Hinge:
    """A flexure hinge joining links[0] = P and links[1] = M (the plate runs from P to M)."""

    name: str
    index: int
    links: tuple[str, str]
    at: tuple[sp.Expr, sp.Expr]
    plate_angle: sp.Expr
    length: sp.Expr
    model: str
    model_params: tuple[tuple[str, object], ...] = ()
    input: bool = False
    line: int | None = None
    pin: str = "midpoint"  # where the rigid reference pin sits (hinge_models.PINS)
    E: sp.Expr | None = None  # Young's modulus, Pa (None: not given)
    thickness: sp.Expr | None = None  # plate thickness, file unit
    width: sp.Expr | None = None  # out-of-plane width, file unit
    nu: sp.Expr = DEFAULT_NU  # Poisson's ratio
    beam: str = BEAMS[0]  # the plate's beam theory at the physical levels (hinges.BEAMS)
    # the plate's allowable stress, Pa (None: not given): `safety` at the physical levels
    allowable_stress: sp.Expr | None = None
    # the plate's profile (model.sections.PROFILES: "uniform", thickness `thickness` throughout)
    # and its parameters, by name
    profile: str = "uniform"
    profile_params: tuple[tuple[str, object], ...] = ()

    def param(self, key: str, default: object = None) -> object:
        return dict(self.model_params).get(key, default)

    @property
    def is_plate(self) -> bool:
        """A `rigid` hinge stays an ideal pin at the physical levels; every other one is a plate."""
        return self.model != "rigid"


@dataclass(frozen=True)
class Point:
    name: str
    index: int
    link: str
    at: tuple[sp.Expr, sp.Expr]
    line: int | None = None


@dataclass(frozen=True)
class Load:
    """A dead load on a link (docs/physics.md): force (N, frame axes) at `at` (the as-fabricated
    absolute position, file unit) and a moment (N·m, counter-clockwise)."""

    index: int
    link: str
    at: tuple[sp.Expr, sp.Expr]
    force: tuple[sp.Expr, sp.Expr]
    moment: sp.Expr
    point: str | None = None  # the named [[point]] it acts on, if it names one
    line: int | None = None

    @property
    def label(self) -> str:
        """How reports name it: `[[load]] #k` (on point P)."""
        return f"[[load]] #{self.index + 1}" + (f" on '{self.point}'" if self.point else "")


@dataclass(frozen=True)
class Actuator:
    """An actuator between the frame and `link` (docs/file-format.md, "Actuators"): it moves the
    link's point `at` (as fabricated, file unit) along the unit `direction` (frame axes) by a
    prescribed stroke (file unit) or pushes it with a force (N). `surrogate` is the hinge whose
    angle the stroke fixes (chosen by the reader): the kinematics take that hinge as an input
    and find its angle from the stroke (docs/levels.md, "Actuators")."""

    name: str
    index: int
    link: str
    at: tuple[sp.Expr, sp.Expr]
    direction: tuple[sp.Expr, sp.Expr]
    drive: str
    surrogate: str
    line: int | None = None

    @property
    def point(self) -> str:
        """The name of the hidden point at `at` the evaluators track (no file name can clash:
        names are identifiers, this one holds a '@')."""
        return f"@{self.name}"


@dataclass(frozen=True)
class Mechanism:
    """A validated mechanism file: names, exact numbers and sympy expressions, in file order."""

    path: str
    name: str
    ground: str
    parameters: tuple[Parameter, ...]
    links: tuple[Link, ...]
    hinges: tuple[Hinge, ...]
    points: tuple[Point, ...]
    chords: tuple[str, ...] | None = None
    basic_chain: tuple[str, ...] | None = None
    units: str = "m"
    loads: tuple[Load, ...] = ()
    actuators: tuple[Actuator, ...] = ()

    @property
    def unit_scale(self) -> sp.Rational:
        """Metres per file length unit."""
        return UNITS[self.units]

    @property
    def inputs(self) -> tuple[str, ...]:
        """Names of the hinges whose angle the kinematics take as given, in file order: the
        input hinges and the actuators' surrogate hinges (see :attr:`drives`)."""
        return tuple(h.name for h in self.hinges if h.input)

    @property
    def surrogates(self) -> tuple[str, ...]:
        """The hinges whose angles the actuators' strokes fix, in actuator order."""
        return tuple(a.surrogate for a in self.actuators)

    @property
    def drives(self) -> tuple[str, ...]:
        """What the user gives (`--input`): the input hinges of the file, then the actuators,
        each in file order."""
        hinges = tuple(n for n in self.inputs if n not in self.surrogates)
        return hinges + tuple(a.name for a in self.actuators)

    def actuator(self, name: str) -> Actuator:
        return next(a for a in self.actuators if a.name == name)

    def stroke_spans(self) -> dict[str, float]:
        """Each stroke actuator's default half range (file unit), where a sweep or a report
        plots it: 1e-3 of the distance of its point of action from the frame's origin (a
        piezo stack's stroke is about 1e-3 of its length); --range / --input set another."""
        values = self.defaults
        return {
            a.name: 1e-3
            * float(expressions.substitute(sp.sqrt(a.at[0] ** 2 + a.at[1] ** 2), values))
            for a in self.actuators
            if a.drive == "stroke"
        }

    def refuse_actuators(self, what: str) -> None:
        """Bad input (exit 2, naming the first actuator) where `what` does not take actuators
        yet; `symkin eval` at the kinematic levels does (docs/levels.md, "Actuators")."""
        if self.actuators:
            a = self.actuators[0]
            raise InputError(
                f"{what} does not take actuators yet (actuator '{a.name}')",
                file=self.path,
                entry=f"[[actuator]] #{a.index + 1} '{a.name}'",
                hint="evaluate it with symkin eval (a stroke at --level paper, first_order or "
                "exact; a stroke or a force at equilibrium), or derive --emit numpy,c",
            )

    @cached_property
    def closure_rank(self) -> ClosureRank | None:
        """See :func:`closure_rank`."""
        return _closure_rank(self)

    @property
    def grubler(self) -> int:
        """Grübler's count 3n - 2m (n moving links, m revolute hinges)."""
        return 3 * (len(self.links) - 1) - 2 * len(self.hinges)

    @property
    def mobility(self) -> int:
        """The mobility: 3n minus the rank of the closure Jacobian at the as-fabricated pose
        (:func:`closure_rank`); Grübler's count unless some loops are redundant
        (docs/levels.md, "Redundant loops")."""
        rank = closure_rank(self)
        return self.grubler if rank is None else rank.mobility

    @property
    def redundant(self) -> int:
        """How many closure equations are dependent at the as-fabricated pose (0: none)."""
        return self.mobility - self.grubler

    @property
    def loop_count(self) -> int:
        """Number of independent loops m - n."""
        return len(self.hinges) - (len(self.links) - 1)

    @property
    def defaults(self) -> dict[sp.Symbol, sp.Expr]:
        """Exact default value of every parameter symbol."""
        return {p.symbol: p.value for p in self.parameters}

    @property
    def has_stiffness(self) -> bool:
        """Every plate has E, thickness and width: the data the physical levels need (a mechanism
        with `rigid` pins only needs none)."""
        return all(
            getattr(h, key) is not None
            for h in self.hinges
            if h.is_plate
            for key in STIFFNESS_REQUIRED
        )

    def hinge(self, name: str) -> Hinge:
        return next(h for h in self.hinges if h.name == name)

    def link(self, name: str) -> Link:
        return next(lk for lk in self.links if lk.name == name)

    def point(self, name: str) -> Point:
        """The named point, or an actuator's point of action by its hidden name
        (:attr:`Actuator.point`)."""
        for p in self.points:
            if p.name == name:
                return p
        a = next(a for a in self.actuators if a.point == name)
        return Point(a.point, len(self.points) + a.index, a.link, a.at, a.line)

    def check_points(self, names: Sequence[str]) -> None:
        """Every name of `names` (a --points list) is a point of the file, else bad input."""
        known = [p.name for p in self.points]
        for name in names:
            if name not in known:
                raise InputError(
                    f"unknown point '{name}'",
                    file=self.path,
                    entry="--points",
                    hint="points: " + ", ".join(known),
                )


def load(path: str | Path) -> Mechanism:
    """Read and validate a mechanism file; raise InputError (exit 2) on anything wrong with it."""
    path = Path(path)
    shown = str(path)
    try:
        raw = path.read_bytes()
    except OSError as exc:
        raise InputError(
            f"cannot read the file ({exc.strerror or exc})", file=shown, hint="check the path"
        ) from None
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


MAX_NAME = 64
MAX_TABLE_BYTES = 1 << 20


def _is_float(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


C_KEYWORDS = frozenset(
    [
        "auto",
        "break",
        "case",
        "char",
        "const",
        "continue",
        "default",
        "do",
        "double",
        "else",
        "enum",
        "extern",
        "float",
        "for",
        "goto",
        "if",
        "inline",
        "int",
        "long",
        "register",
        "restrict",
        "return",
        "short",
        "signed",
        "sizeof",
        "static",
        "struct",
        "switch",
        "typedef",
        "union",
        "unsigned",
        "void",
        "volatile",
        "while",
    ]
)
#: modules whose names a mechanism may not take: the generated module imports them, and a file
#: <name>.py beside a script would shadow them
SHADOWED = frozenset(sys.stdlib_module_names) | {"numpy", "symkin", "mpmath", "sympy"}


def name_problem(name: str, longest: int = MAX_NAME) -> tuple[str, str] | None:
    """(what is wrong, how to fix it) when `name` cannot name generated files and C functions,
    else None."""
    if len(name) > longest:
        return (
            f"name is {len(name)} characters long, more than {longest}",
            f"use at most {longest} characters: it names the generated files and the C functions",
        )
    if not expressions.IDENTIFIER.match(name) or name.startswith("_"):
        return (
            f"name '{name}' is not identifier-safe",
            "use letters, digits and '_' only, starting with a letter",
        )
    if keyword.iskeyword(name) or name in C_KEYWORDS or name in SHADOWED:
        return (
            f"name '{name}' is a Python or C keyword or the name of a module the generated "
            f"code imports",
            f'rename it, e.g. name = "{name}_mechanism"',
        )
    return None


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


def _entry(kind: str, i: int, table: Mapping[str, object]) -> str:
    """How an error names the i-th [[kind]] entry: by number, and by name once it has one."""
    name = table.get("name")
    return f"[[{kind}]] #{i + 1}" + (f" '{name}'" if isinstance(name, str) and name else "")


def _short(value: object) -> str:
    """A number as an error message shows it: 6 significant digits, not sympy's 30."""
    try:
        return f"{float(value):.6g}"  # type: ignore[arg-type]
    except (TypeError, ValueError):
        return str(value)


def _line_from_toml_error(message: str) -> int | None:
    match = re.search(r"line (\d+)", message)
    return int(match.group(1)) if match else None


class _Locator:
    """Finds the line of an entry in the TOML text (tomllib keeps no positions)."""

    def __init__(self, text: str) -> None:
        self.lines = text.splitlines()

    def header(self, array: str, index: int) -> int | None:
        pattern = re.compile(r"\s*\[\[\s*" + re.escape(array) + r"\s*\]\]")
        hits = [i + 1 for i, line in enumerate(self.lines) if pattern.match(line)]
        return hits[index] if index < len(hits) else None

    def key(self, key: str, table: str | None = None, after: int | None = None) -> int | None:
        start = after or 0
        if table is not None:
            pattern = re.compile(r"\s*\[\s*" + re.escape(table) + r"\s*\]")
            start = next((i + 1 for i, line in enumerate(self.lines) if pattern.match(line)), 0)
        keypat = re.compile(r"\s*[\"']?" + re.escape(key) + r"[\"']?\s*=")
        for i in range(start, len(self.lines)):
            if i > start and table is not None and self.lines[i].lstrip().startswith("["):
                break
            if keypat.match(self.lines[i]):
                return i + 1
        return None


class _Reader:
    """One pass over the parsed TOML, building the Mechanism and raising on the first problem."""

    def __init__(self, text: str, file: str, base_dir: Path) -> None:
        self.file = file
        self.base_dir = base_dir
        self.where = _Locator(text)
        self.names: dict[str, sp.Expr] = {}
        self.defaults: dict[sp.Symbol, sp.Expr] = {}

    # -- helpers -------------------------------------------------------------------------------
    def error(
        self,
        message: str,
        entry: str | None = None,
        line: int | None = None,
        hint: str | None = None,
    ) -> InputError:
        return InputError(message, file=self.file, line=line, entry=entry, hint=hint)

    def check_keys(
        self, table: Mapping[str, object], allowed: Sequence[str], entry: str, line: int | None
    ) -> None:
        for key in table:
            if key not in allowed:
                near = suggest(key, allowed)
                raise self.error(
                    f"unknown key '{key}'",
                    entry,
                    line if line is not None else self.where.key(key),
                    near or "allowed keys: " + ", ".join(allowed),
                )

    def expr(
        self,
        value: object,
        entry: str,
        key: str,
        line: int | None,
        names: Mapping[str, sp.Expr] | None = None,
    ) -> sp.Expr:
        """A number or an expression string, as an exact sympy expression."""
        try:
            if isinstance(value, str):
                return expressions.parse(
                    value, self.names if names is None else names, self.defaults
                )
            return expressions.number(value)  # type: ignore[arg-type]
        except expressions.ExpressionError as exc:
            raise self.error(
                f"'{key}': {exc}", entry, line, "use a number or an expression over the parameters"
            ) from None

    def finite(self, expr: sp.Expr, entry: str, key: str, line: int | None) -> sp.Expr:
        """Check that `expr` evaluates to a finite real number with the default parameters."""
        try:
            value = expressions.numeric(expr, self.defaults)
        except expressions.NotReal as exc:
            raise self.error(
                f"'{key}' does not evaluate to a finite real number ({exc})",
                entry,
                line,
                "change the expression or the parameters it uses",
            ) from None
        if abs(value) > expressions.FLOAT64_MAX:
            raise self.error(
                f"'{key}' evaluates to {mpmath.nstr(value, 6)}, beyond a float64 "
                "(|value| < 1.8e308), the generated code's number format",
                entry,
                line,
                "change the expression or the parameters it uses",
            )
        return sp.Float(value, expressions.NUMERIC_DPS)

    def text(self, table: Mapping[str, object], key: str, entry: str, line: int | None) -> str:
        """The non-empty string at `key`; missing or anything else is bad input."""
        if key not in table:
            raise self.error(f"missing required key '{key}'", entry, line, f'add {key} = "..."')
        value = table[key]
        if not isinstance(value, str) or not value.strip():
            raise self.error(
                f"'{key}' must be a non-empty string, got {value!r}",
                entry,
                line,
                f'write {key} = "..." (quoted text, not empty)',
            )
        return value

    def array_of_tables(self, data: Mapping[str, object], key: str) -> list[Mapping[str, object]]:
        value = data.get(key, [])
        if not isinstance(value, list) or not all(isinstance(t, dict) for t in value):
            raise self.error(
                f"'{key}' must be an array of tables written as [[{key}]]",
                f"[[{key}]]",
                self.where.key(key),
                f"write each entry as a [[{key}]] table (docs/file-format.md)",
            )
        return value

    def unique(self, kind: str, names: list[str], lines: list[int | None]) -> None:
        seen: dict[str, int] = {}
        for i, name in enumerate(names):
            if name in seen:
                raise self.error(
                    f"duplicate {kind} name '{name}' (also {kind} #{seen[name] + 1})",
                    f"[[{kind}]] #{i + 1} '{name}'",
                    lines[i],
                    f"give every {kind} its own name",
                )
            seen[name] = i

    def vector(
        self, value: object, entry: str, key: str, line: int | None
    ) -> tuple[sp.Expr, sp.Expr]:
        if not isinstance(value, list) or len(value) != 2:
            raise self.error(
                f"'{key}' must be a list of two coordinates [x, y], got {value!r}",
                entry,
                line,
                f"write {key} = [x, y] with two numbers or expressions",
            )
        vec = (self.expr(value[0], entry, key, line), self.expr(value[1], entry, key, line))
        for v in vec:
            self.finite(v, entry, key, line)
        return vec

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
            entry = _entry("link", i, table)
            self.check_keys(table, LINK_KEYS, entry, line)
            out.append(Link(self.text(table, "name", entry, line), i, line))
        self.unique("link", [lk.name for lk in out], [lk.line for lk in out])
        return tuple(out)

    def hinges(
        self,
        tables: list[Mapping[str, object]],
        defaults: Mapping[str, object],
        link_names: list[str],
    ) -> tuple[Hinge, ...]:
        if not tables:
            raise self.error(
                "a mechanism needs at least one [[hinge]]",
                "[[hinge]]",
                None,
                "add [[hinge]] tables with name, links and at (docs/file-format.md)",
            )
        out = [self.hinge(i, table, defaults, link_names) for i, table in enumerate(tables)]
        self.unique("hinge", [h.name for h in out], [h.line for h in out])
        return tuple(out)

    def hinge(
        self,
        i: int,
        table: Mapping[str, object],
        defaults: Mapping[str, object],
        link_names: list[str],
    ) -> Hinge:
        line = self.where.header("hinge", i)
        entry = f"[[hinge]] #{i + 1}"
        name = self.text(table, "name", entry, line)
        entry = f"[[hinge]] #{i + 1} '{name}'"
        model = table.get("model", defaults.get("model", DEFAULT_MODEL))
        if not isinstance(model, str):
            raise self.error(
                f"'model' must be a model name string, got {model!r}"[:200],
                entry,
                line,
                "models: " + ", ".join(MODELS),
            )
        if model not in MODELS:
            raise self.error(
                f"unknown hinge model {model!r}",
                entry,
                line,
                suggest(str(model), MODELS) or "models: " + ", ".join(MODELS),
            )
        spec = MODELS[model]
        allowed = HINGE_KEYS + tuple(p.name for p in spec.parameters)
        for key in table:
            if key not in allowed and key in MODEL_KEYS:
                raise self.error(
                    f"'{key}' is not a parameter of model '{model}'",
                    entry,
                    line,
                    f"remove it, or choose a model that takes '{key}'",
                )
        self.check_keys(table, allowed, entry, line)
        links = table.get("links")
        if (
            not isinstance(links, list)
            or len(links) != 2
            or not all(isinstance(x, str) for x in links)
        ):
            raise self.error(
                "'links' must name the two links it joins",
                entry,
                line,
                'write e.g. links = ["frame", "crank"]: two [[link]] names',
            )
        for link in links:
            if link not in link_names:
                raise self.error(
                    f"links names an unknown link '{link}'",
                    entry,
                    line,
                    suggest(link, link_names) or "declare it as a [[link]]",
                )
        if links[0] == links[1]:
            raise self.error(
                f"joins the link '{links[0]}' to itself",
                entry,
                line,
                "a hinge joins two different links",
            )
        if "at" not in table:
            raise self.error(
                "missing required key 'at'",
                entry,
                line,
                "add at = [x, y], the plate's midpoint in the as-fabricated pose",
            )
        at = self.vector(table["at"], entry, "at", line)
        merged = {**defaults, **table}
        where = self.origin("plate_angle", table, entry, line)
        plate_angle = self.expr(merged.get("plate_angle", 0), where[0], "plate_angle", where[1])
        self.finite(plate_angle, where[0], "plate_angle", where[1])
        if "length" not in merged:
            raise self.error(
                "no plate length", entry, line, "set length in the hinge or in [defaults]"
            )
        where = self.origin("length", table, entry, line)
        length = self.expr(merged["length"], where[0], "length", where[1])
        if not self.finite(length, where[0], "length", where[1]) > 0:
            raise self.error(
                f"plate length must be positive, got {length}",
                *where,
                "give the plate a positive length",
            )
        is_input = merged.get("input", False)
        if not isinstance(is_input, bool):
            raise self.error(
                f"'input' must be true or false, got {is_input!r}",
                entry,
                line,
                "write input = true or input = false",
            )
        params = self.model_params(spec, table, defaults, entry, line, length)
        pin = merged.get("pin", "midpoint")
        if pin not in PINS:
            raise self.error(
                f"'pin' must be one of {', '.join(PINS)}, got {pin!r}",
                entry,
                line,
                'pin = "midpoint" (the paper\'s rigid pin) or "prbm" (the '
                "model's pseudo-rigid-body pivot)",
            )
        stiffness = self.stiffness(table, merged, entry, line, length)
        beam = merged.get("beam", BEAMS[0])
        if beam not in BEAMS:
            raise self.error(
                f"'beam' must be one of {', '.join(BEAMS)}, got {beam!r}"[:200],
                entry,
                line,
                'beam = "reissner" (stretches and shears, the default) or "elastica" '
                "(inextensible, shear-free), docs/physics.md",
            )
        return Hinge(
            name,
            i,
            (links[0], links[1]),
            at,
            plate_angle,
            length,
            model,
            params,
            is_input,
            line,
            pin,
            **stiffness,
            beam=beam,
        )

    def origin(
        self, key: str, table: Mapping[str, object], entry: str, line: int | None
    ) -> tuple[str, int | None]:
        """Where a hinge's `key` was given: the hinge (`entry`, `line`) or, when the hinge does
        not give it, [defaults] and the key's line there (the place an error sends the user)."""
        if key in table:
            return entry, line
        return "[defaults]", self.where.key(key, "defaults")

    def stiffness(
        self,
        table: Mapping[str, object],
        merged: Mapping[str, object],
        entry: str,
        line: int | None,
        length: sp.Expr,
    ) -> dict[str, sp.Expr]:
        """E, thickness, width, nu, allowable_stress of a hinge (docs/physics.md; `table` the
        hinge's own keys, `merged` with [defaults]), each checked where given: E > 0, 0 <
        thickness < length, width > 0, 0 <= nu < 0.5, allowable_stress > 0 (with the default
        parameters)."""
        out: dict[str, sp.Expr] = {}
        for key, (ok, message, hint) in STIFFNESS_RULES.items():
            if key not in merged:
                continue
            where = self.origin(key, table, entry, line)
            expr = self.expr(merged[key], where[0], key, where[1])
            value = self.finite(expr, where[0], key, where[1])
            if not ok(value):
                raise self.error(f"{message}, got {key} = {_short(value)}", *where, hint)
            out[key] = expr
        if "thickness" in out:
            t = self.finite(out["thickness"], entry, "thickness", line)
            lval = self.finite(length, entry, "length", line)
            if not t < lval:
                raise self.error(
                    f"thickness {_short(t)} is not smaller than the plate length {_short(lval)}",
                    entry,
                    line,
                    "a flexure plate is thin: make thickness < length (about length/10 or less)",
                )
        return out

    def model_params(
        self,
        spec: ModelSpec,
        table: Mapping[str, object],
        defaults: Mapping[str, object],
        entry: str,
        line: int | None,
        length: sp.Expr,
    ) -> tuple[tuple[str, object], ...]:
        values: dict[str, object] = {}
        given = {k: v for k, v in defaults.items() if spec.parameter(k)}
        given.update({k: v for k, v in table.items() if spec.parameter(k)})
        if spec.name == "prbm" and "preset" in given:
            preset = given["preset"]
            if not isinstance(preset, str) or preset not in PRBM_PRESETS:
                raise self.error(
                    f"unknown prbm preset {preset!r}",
                    entry,
                    line,
                    "presets: " + ", ".join(sorted(PRBM_PRESETS)),
                )
            given = {
                **PRBM_PRESETS[preset],
                **{k: v for k, v in given.items() if k in table or k not in PRBM_PRESETS[preset]},
            }
        for p in spec.parameters:
            if p.name not in given:
                if p.required:
                    raise self.error(
                        f"model '{spec.name}' needs '{p.name}'",
                        entry,
                        line,
                        f"add {p.name} = ... to the hinge",
                    )
                if p.default is None:
                    continue
                raw = p.default
            else:
                raw = given[p.name]
            values[p.name] = self.model_value(p, raw, entry, line)
        if spec.name == "table":
            file, degree = values["file"], values["degree"]
            assert isinstance(file, str) and isinstance(degree, int)  # model_value checked them
            values["rows"] = self.table_rows(file, degree, entry, line)
        if spec.name == "expr":
            self.check_expr_model(values["f"], values["g"], entry, line, length)
        return tuple(sorted(values.items()))

    def model_value(self, p: ModelParameter, raw: object, entry: str, line: int | None) -> object:
        if p.kind in ("number", "fraction"):
            value = self.expr(raw, entry, p.name, line)
            num = self.finite(value, entry, p.name, line)
            ok = num > 0 and (p.kind == "number" or num <= 1)
            if not ok:
                rng = "in (0, 1]" if p.kind == "fraction" else "positive"
                raise self.error(
                    f"'{p.name}' must be {rng}, got {_short(num)}",
                    entry,
                    line,
                    f"give {p.name} a value {rng}",
                )
            return value
        if p.kind == "choice":
            if not isinstance(raw, str) or raw not in p.choices:
                raise self.error(
                    f"'{p.name}' must be one of {', '.join(p.choices)}, got {raw!r}",
                    entry,
                    line,
                    f'write {p.name} = "{p.choices[0]}" or another of these',
                )
            return raw
        if p.kind == "int":
            if isinstance(raw, bool) or not isinstance(raw, int) or not 1 <= raw <= 12:
                raise self.error(
                    f"'{p.name}' must be an integer from 1 to 12, got {raw!r}",
                    entry,
                    line,
                    f"write {p.name} = an integer from 1 to 12",
                )
            return raw
        if p.kind == "text":
            if not isinstance(raw, str) or not raw:
                raise self.error(
                    f"'{p.name}' must be a file name string, got {raw!r}",
                    entry,
                    line,
                    f'write {p.name} = "name.csv", a file beside the mechanism',
                )
            return raw
        # "expr": an expression in theta, l and the parameters
        names = {**self.names, "theta": THETA, "l": PLATE_LENGTH}
        if not isinstance(raw, str):
            raise self.error(
                f"'{p.name}' must be an expression string in theta and l",
                entry,
                line,
                f'write {p.name} = "..." with an expression in theta and l',
            )
        return self.expr(raw, entry, p.name, line, names)

    def check_expr_model(
        self, f: sp.Expr, g: sp.Expr, entry: str, line: int | None, length: sp.Expr
    ) -> None:
        """The plate must be straight at θ = 0: f(0) = l, g(0) = 0 (the as-fabricated pose)."""
        subs = {**self.defaults, PLATE_LENGTH: length.subs(self.defaults)}
        lval = sp.N(subs[PLATE_LENGTH], 30)
        for key, expr, want in (("f", f, lval), ("g", g, 0)):
            at0 = sp.N(expr.subs(subs).subs(THETA, sp.Rational(1, 10**12)), 30)
            if not (at0.is_real and at0.is_finite) or abs(at0 - want) > 1e-6 * lval:
                raise self.error(
                    f"expression model gives {key}(0) = {_short(at0)}, expected {_short(want)}",
                    entry,
                    line,
                    "at theta = 0 the plate is straight: f(0) = l and g(0) = 0",
                )

    def table_rows(
        self, name: str, degree: int, entry: str, line: int | None
    ) -> tuple[tuple[float, ...], ...]:
        content = self.table_text(name, entry, line)
        rows: list[tuple[float, ...]] = []
        for k, row in enumerate(csv.reader(io.StringIO(content)), start=1):
            if not row or not "".join(row).strip() or row[0].lstrip().startswith("#"):
                continue
            try:
                values = [float(x) for x in row]
            except ValueError:
                if not rows and k == 1:
                    continue  # a header row
                bad = next((x for x in row if not _is_float(x)), "")
                shown = bad if len(bad) <= 40 else bad[:37] + "..."
                raise self.error(
                    f"{name}:{k}: not a number: {shown!r}",
                    entry,
                    line,
                    "each row is theta, f/l, g/l",
                ) from None
            if len(values) != 3 or not all(math.isfinite(v) for v in values):
                raise self.error(
                    f"{name}:{k}: need three finite numbers theta, f/l, g/l",
                    entry,
                    line,
                    f"correct row {k} of {name}",
                )
            rows.append(tuple(values))
        if len({r[0] for r in rows}) < degree + 1:
            raise self.error(
                f"table '{name}' has {len(rows)} rows with distinct theta; a degree "
                f"{degree} fit needs at least {degree + 1}",
                entry,
                line,
                "add rows or lower 'degree'",
            )
        return tuple(rows)

    def table_text(self, name: str, entry: str, line: int | None) -> str:
        """The text of a table file: a regular file inside the mechanism's folder (relative
        path, no '..', symbolic links resolved inside it too), at most MAX_TABLE_BYTES."""
        hint = "give a CSV path relative to the mechanism file, inside its folder"
        rel = Path(name)
        if rel.is_absolute() or ".." in rel.parts:
            raise self.error(
                f"table file '{name}' must be inside the mechanism's folder "
                "(a relative path without '..')",
                entry,
                line,
                hint,
            )
        base = self.base_dir.resolve()
        path = (base / rel).resolve()
        if path != base and base not in path.parents:
            raise self.error(
                f"table file '{name}' leads outside the mechanism's folder (a symbolic link)",
                entry,
                line,
                hint,
            )
        try:
            info = os.stat(path)
        except OSError as exc:
            raise self.error(
                f"cannot read table file '{name}' ({exc.strerror or exc})", entry, line, hint
            ) from None
        if not stat.S_ISREG(info.st_mode):
            raise self.error(f"table file '{name}' is not a regular file", entry, line, hint)
        if info.st_size > MAX_TABLE_BYTES:
            raise self.error(
                f"table file '{name}' is larger than {MAX_TABLE_BYTES} bytes",
                entry,
                line,
                "a table needs a few hundred rows at most",
            )
        try:
            with open(path, "rb") as f:
                raw = f.read(MAX_TABLE_BYTES + 1)
            if len(raw) > MAX_TABLE_BYTES:
                raise self.error(
                    f"table file '{name}' is larger than {MAX_TABLE_BYTES} bytes",
                    entry,
                    line,
                    "a table needs a few hundred rows at most",
                )
            return raw.decode("utf-8")
        except (OSError, UnicodeDecodeError) as exc:
            reason = getattr(exc, "strerror", None) or type(exc).__name__
            raise self.error(
                f"cannot read table file '{name}' ({reason})", entry, line, hint
            ) from None

    def points(
        self, tables: list[Mapping[str, object]], link_names: list[str]
    ) -> tuple[Point, ...]:
        out = []
        for i, table in enumerate(tables):
            line = self.where.header("point", i)
            entry = _entry("point", i, table)
            self.check_keys(table, POINT_KEYS, entry, line)
            name = self.text(table, "name", entry, line)
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
            entry = _entry("actuator", i, table)
            self.check_keys(table, ACTUATOR_KEYS, entry, line)
            name = self.text(table, "name", entry, line)
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
                    f"'direction' is the zero vector {_short(table['direction'])}: it gives "
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
            out.append(Actuator(name, i, link, at, direction, drive, "", line))
        return tuple(out)

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
        if dof < 1:
            raise self.error(
                f"the mechanism cannot move: Grübler mobility {formula}",
                "[[hinge]]",
                None,
                "remove hinges or add links",
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


def surrogate_hinges(mech: Mechanism) -> tuple[str, ...] | Actuator:
    """One hinge per actuator whose angle its stroke fixes: with the input hinges and the other
    surrogates it fixes the pose (the rank of the closure Jacobian reaches 3n), so the
    kinematics solve the rigid linkage from those angles and the strokes fix the surrogates'
    angles by a regular small system (docs/levels.md, "Actuators"). Hinges on the actuated
    link come first, then hinges on the frame, each in file order. Returns the actuator that
    does not drive the mechanism (its row adds nothing to the rank) instead, if one does not."""
    found = _jacobian_rows(mech)
    if found is None:
        return tuple(h.name for h in mech.hinges if not h.input)[: len(mech.actuators)]
    constraints, turn_of, actuator_row, full = (
        found.constraints,
        found.turn_of,
        found.actuator_row,
        found.full,
    )
    with mpmath.workdps(30):
        held = constraints + [turn_of(h) for h in mech.hinges if h.input]
        rows = held + [actuator_row(a) for a in mech.actuators]
        if _rank(rows) < full:
            for a in mech.actuators:
                others = [actuator_row(b) for b in mech.actuators if b is not a]
                if _rank(held + others) == _rank(rows):
                    return a
            return mech.actuators[0]
        linked = {a.link for a in mech.actuators}
        order = sorted(
            (h for h in mech.hinges if not h.input),
            key=lambda h: 0 if linked & set(h.links) else 1 if mech.ground in h.links else 2,
        )
        chosen: list[str] = []
        rank = _rank(held)
        for h in order:
            if len(chosen) == len(mech.actuators):
                break
            trial = _rank(held + [turn_of(h)])
            if trial > rank:
                held, rank = held + [turn_of(h)], trial
                chosen.append(h.name)
    if len(chosen) < len(mech.actuators):  # no hinge left that the strokes could stand for
        return mech.actuators[len(chosen)]
    return tuple(chosen)


@dataclass(frozen=True)
class _RigidRows:
    """The rigid linkage's constraint rows at the as-fabricated pose, in 30-digit numbers: 2
    per hinge (its pin at the rigid reference) by the 3n pose velocities of the moving links,
    the rotation column scaled by `size` (the largest pin coordinate)."""

    constraints: list[list[mpmath.mpf]]
    pins: list[tuple[mpmath.mpf, mpmath.mpf]]
    size: mpmath.mpf
    column: dict[str, int]  # a moving link's first column
    values: Mapping[sp.Symbol, sp.Expr]

    @property
    def full(self) -> int:
        """3n: the rank that fixes the pose."""
        return 3 * len(self.column)

    def turn_of(self, h: Hinge) -> list[mpmath.mpf]:
        """The row holding hinge h's relative rotation (an input)."""
        row = [mpmath.mpf(0)] * self.full
        for link, sign in ((h.links[1], 1), (h.links[0], -1)):
            if link in self.column:
                row[self.column[link] + 2] = sign
        return row

    def actuator_row(self, a: Actuator) -> list[mpmath.mpf]:
        """The rate of actuator a's stroke, d·v(at) = d·(v + ω × at), ω scaled as above."""
        row = [mpmath.mpf(0)] * self.full
        j = self.column[a.link]
        with mpmath.workdps(30):
            parts = [_mp(e, self.values) for e in (*a.direction, *a.at)]
            # the reader has checked `at` and `direction` finite before the rank is taken
            dx, dy, x, y = (mpmath.mpf(0) if v is None else v for v in parts)
            row[j], row[j + 1], row[j + 2] = dx, dy, (dy * x - dx * y) / self.size
        return row


def _jacobian_rows(mech: Mechanism) -> _RigidRows | None:
    """The rigid linkage's rows at the as-fabricated pose (None: values not finite)."""
    values = mech.defaults
    moving = [lk.name for lk in mech.links if lk.name != mech.ground]
    column = {name: 3 * k for k, name in enumerate(moving)}
    pins: list[tuple[mpmath.mpf, mpmath.mpf]] = []
    with mpmath.workdps(30):
        for h in mech.hinges:
            shift = h.length / 2 - pivot_distance(h)
            x, y = (
                _mp(h.at[i] + shift * f(h.plate_angle), values)
                for i, f in enumerate((sp.cos, sp.sin))
            )
            if x is None or y is None:
                return None
            pins.append((x, y))
        size = max((abs(c) for pin in pins for c in pin), default=mpmath.mpf(0)) or mpmath.mpf(1)
        constraints = []
        for h, pin in zip(mech.hinges, pins):
            out = [[mpmath.mpf(0)] * (3 * len(moving)) for _ in range(2)]
            for link, sign in ((h.links[1], 1), (h.links[0], -1)):
                if link in column:
                    j = column[link]
                    out[0][j], out[0][j + 2] = sign, -sign * pin[1] / size
                    out[1][j + 1], out[1][j + 2] = sign, sign * pin[0] / size
            constraints += out
    return _RigidRows(constraints, pins, size, column, values)


@dataclass(frozen=True)
class ClosureRank:
    """The rank of the closure Jacobian of the rigid linkage at the as-fabricated pose."""

    rank: int  # of J_c: 2 rows per hinge, 3 columns per moving link
    mobility: int  # 3n - rank
    dependent: tuple[str, ...]  # inputs whose angle the others (and the loops) already fix
    candidates: tuple[str, ...]  # other hinges that would fix the pose in their place
    collinear: bool = False  # those hinges' pins lie on one line: a toggle position


def closure_rank(mech: Mechanism) -> ClosureRank | None:
    """Rank of J_c, the Jacobian of the 2m pin constraints of the rigid linkage (each hinge a
    pin at its rigid reference, :func:`~symkin.model.hinges.pivot_distance`) by the 3n pose
    velocities of the moving links at the as-fabricated pose and the file's parameter values
    (None when those values are not finite numbers: the value checks report them). The
    mobility is 3n - rank (docs/levels.md): Grübler's 3n - 2m when the 2m constraints are
    independent, more when some are redundant (a parallelogram with a third leg has 0 and 1).
    With the inputs' rows (each holds its hinge's relative rotation) the rank must reach 3n:
    an input whose row adds nothing is dependent. Computed once per mechanism."""
    return mech.closure_rank


def _closure_rank(mech: Mechanism) -> ClosureRank | None:
    found = _jacobian_rows(mech)
    if found is None:
        return None
    constraints, pins, size, turn_of = found.constraints, found.pins, found.size, found.turn_of
    with mpmath.workdps(30):
        rank = _rank(constraints)
        full = found.full
        inputs = [h for h in mech.hinges if h.input]
        with_inputs = constraints + [turn_of(h) for h in inputs]
        dependent: tuple[str, ...] = ()
        candidates: tuple[str, ...] = ()
        collinear = False
        if inputs and rank + len(inputs) == full and _rank(with_inputs) < full:
            total = _rank(with_inputs)
            dependent = tuple(
                h.name
                for h in inputs
                if _rank(constraints + [turn_of(g) for g in inputs if g is not h]) == total
            )
            # the hinges the remaining free motion turns (the null space of J_c and the inputs)
            matrix = np.array([[float(x) for x in r] for r in with_inputs])
            _, sigma, vt = np.linalg.svd(matrix)
            null = vt[int(np.sum(sigma > 1e-8 * sigma[0])) :]
            turns = np.array([[float(x) for x in turn_of(h)] for h in mech.hinges]) @ null.T
            motion = np.abs(turns).max(axis=1) if null.size else np.zeros(len(mech.hinges))
            candidates = tuple(
                h.name
                for h, turn in zip(mech.hinges, motion)
                if not h.input and turn > 1e-6 * max(motion.max(), 1e-300)
            )
            free = [pin for h, pin in zip(mech.hinges, pins) if h.name in candidates]
            collinear = len(free) >= 3 and all(
                abs(
                    (b[0] - free[0][0]) * (free[1][1] - free[0][1])
                    - (b[1] - free[0][1]) * (free[1][0] - free[0][0])
                )
                <= mpmath.mpf(10) ** -12 * size**2
                for b in free[2:]
            )
    return ClosureRank(rank, full - rank, dependent, candidates, collinear)


def _rank(rows: list[list[mpmath.mpf]]) -> int:
    """Numerical rank of a matrix of 30-digit numbers: singular values above 1e-8 of the
    largest in float64 count at once; the smaller ones are settled by a 30-digit SVD (rank
    deficient below 1e-20 of the largest), which costs seconds on large matrices and is only
    needed near a singular pose or for redundant constraints."""
    if not rows or not rows[0]:
        return 0
    sigma = np.linalg.svd(np.array([[float(x) for x in r] for r in rows]), compute_uv=False)
    if not sigma.size or sigma[0] == 0:
        return 0
    if sigma[-1] > 1e-8 * sigma[0]:
        return int(sigma.size)
    exact = mpmath.svd_r(mpmath.matrix(rows), compute_uv=False)
    top = max(exact)
    return sum(1 for x in exact if x > mpmath.mpf(10) ** -20 * top)


def _mp(expr: sp.Expr, values: Mapping[sp.Symbol, sp.Expr]) -> mpmath.mpf | None:
    """`expr` at the parameter values, 30 digits; None when it is not a finite real number."""
    value = sp.N(expressions.substitute(expr, values), 30)
    if not (value.is_real and value.is_finite):
        return None
    return mpmath.mpf(str(value))


def check_values(
    mech: Mechanism, values: Mapping[sp.Symbol, sp.Expr], option: str | None = None
) -> None:
    """Every numeric rule of the file at these parameter values: finite coordinates and angles,
    positive plate lengths, model parameters in range, and plates shorter than the links between
    them (on every link, two hinge centres lie farther apart than half the sum of the plate
    lengths; plates that cross always break this). `option` names the command-line option that
    set the values (e.g. "--param"); None means the file's own defaults."""
    with mpmath.workdps(30):

        def fail(message: str, entry: str, line: int | None, hint: str) -> InputError:
            if option is None:
                return InputError(message, file=mech.path, line=line, entry=entry, hint=hint)
            return InputError(
                f"with these values, {entry}: {message}",
                file=mech.path,
                entry=option,
                hint="choose values that keep the mechanism valid: " + hint,
            )

        centres = {}
        for h in mech.hinges:
            entry = f"[[hinge]] '{h.name}'"
            x, y = (_mp(v, values) for v in h.at)
            angle = _mp(h.plate_angle, values)
            length = _mp(h.length, values)
            if x is None or y is None or angle is None:
                raise fail(
                    "'at' or 'plate_angle' is not a finite number",
                    entry,
                    h.line,
                    "keep coordinates and angles finite",
                )
            if length is None or not length > 0:
                shown = "not finite" if length is None else mpmath.nstr(length, 6)
                raise fail(
                    f"plate length must be positive, got {shown}",
                    entry,
                    h.line,
                    "give the plate a positive length",
                )
            for key, raw in h.model_params:
                spec = MODELS[h.model].parameter(key)
                if spec is None or spec.kind not in ("number", "fraction"):
                    continue
                value = _mp(raw, values)
                if value is None or not value > 0 or (spec.kind == "fraction" and value > 1):
                    rng = "in (0, 1]" if spec.kind == "fraction" else "positive"
                    raise fail(
                        f"'{key}' must be {rng}, got "
                        f"{'not finite' if value is None else mpmath.nstr(value, 6)}",
                        entry,
                        h.line,
                        f"keep '{key}' {rng}",
                    )
            for key, (ok, message, hint) in STIFFNESS_RULES.items():
                raw = getattr(h, key)
                value = None if raw is None else sp.N(expressions.substitute(raw, values), 30)
                if value is not None and not (value.is_real and value.is_finite and ok(value)):
                    raise fail(f"{message}, got {key} = {_short(value)}", entry, h.line, hint)
            if h.thickness is not None and not _mp(h.thickness, values) < length:
                raise fail(
                    f"thickness {mpmath.nstr(_mp(h.thickness, values), 6)} is not smaller "
                    f"than the plate length {mpmath.nstr(length, 6)}",
                    entry,
                    h.line,
                    "a flexure plate is thin: make thickness < length",
                )
            centres[h.name] = ((x, y), length)
        for load in mech.loads:
            if None in [_mp(v, values) for v in (*load.force, load.moment)]:
                raise fail(
                    "'force' or 'moment' is not a finite number",
                    load.label,
                    load.line,
                    "keep loads finite",
                )
        for p in mech.points:
            if None in [_mp(v, values) for v in p.at]:
                raise fail(
                    "'at' is not a finite number",
                    f"[[point]] '{p.name}'",
                    p.line,
                    "keep coordinates finite",
                )
        for act in mech.actuators:
            if None in [_mp(v, values) for v in (*act.at, *act.direction)]:
                raise fail(
                    "'at' or 'direction' is not a finite number",
                    f"[[actuator]] '{act.name}'",
                    act.line,
                    "keep the point of action and the line of action finite",
                )
        for link in mech.links:
            on_link = [h for h in mech.hinges if link.name in h.links]
            for i, a in enumerate(on_link):
                for b in on_link[i + 1 :]:
                    (pa, la), (pb, lb) = centres[a.name], centres[b.name]
                    gap = mpmath.hypot(pa[0] - pb[0], pa[1] - pb[1])
                    if not gap > (la + lb) / 2:
                        raise fail(
                            f"its plate and the plate of hinge '{b.name}' reach past each "
                            f"other on link '{link.name}': their centres are "
                            f"{mpmath.nstr(gap, 6)} apart, less than half the sum of the "
                            f"plate lengths, {mpmath.nstr((la + lb) / 2, 6)}",
                            f"[[hinge]] '{a.name}'",
                            a.line,
                            "shorten the plates or move the hinges apart: on every link "
                            "the plates must be shorter than the link between them",
                        )
