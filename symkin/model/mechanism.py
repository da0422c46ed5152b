"""The mechanism a file describes, validated (docs/file-format.md): the immutable
:class:`Mechanism`, what follows from it at the as-fabricated pose (Grübler's count, the closure
rank, the mobility) and the numeric rules its values obey (:func:`check_values`, also at the
values of `--param`). :mod:`.reader` builds it from the TOML text.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from functools import cached_property
from typing import Any

import mpmath
import sympy as sp

from ..core.errors import InputError
from . import expressions
from .closure import ClosureRank, closure_rank_of, mp_at
from .entries import (
    STIFFNESS_REQUIRED,
    STIFFNESS_RULES,
    Actuator,
    Hinge,
    Link,
    Load,
    Parameter,
    Point,
    short,
)
from .hinges import MODELS

#: The file's length unit (`units`), in metres: geometry, lengths, thickness, width and load points
#: are in it; E is in Pa, forces in N, moments in N·m (docs/physics.md).
UNITS: dict[str, sp.Rational] = {
    "m": sp.Integer(1),
    "mm": sp.Rational(1, 10**3),
    "um": sp.Rational(1, 10**6),
}


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

    def refuse_structure(self, level: str | None = None, what: str | None = None) -> None:
        """Bad input (exit 2) where a structure (:attr:`is_structure`) has nothing to give: a
        kinematic `level` (its rigid linkage has no motion to compare with) or `what`, tradeoff
        (its variants are compared over the inputs' range; docs/levels.md, "Structures")."""
        if not self.is_structure:
            return
        locked = "the mechanism is a structure: its rigid linkage has no motion (mobility 0)"
        physical = (
            "ask for --level loaded (or equilibrium): the physical levels load a structure by "
            "its [[load]] entries and force actuators and move it by its stroke actuators "
            '(docs/levels.md, "Structures")'
        )
        if what is not None:
            raise InputError(
                f"{locked}, and {what} does not take structures (it compares variants over "
                "the inputs' range, and a structure's rigid linkage does not move)",
                file=self.path,
                entry="[[hinge]]",
                hint="evaluate it with symkin eval --level loaded or --level equilibrium "
                '(--backend sympy) (docs/levels.md, "Structures")',
            )
        if level is not None:
            raise InputError(
                f"{locked}, so the {level} level, which moves the rigid linkage by its "
                "inputs, has nothing to evaluate",
                file=self.path,
                entry="--level",
                hint=physical,
            )

    @cached_property
    def closure_rank(self) -> ClosureRank | None:
        """See :func:`closure_rank`."""
        return closure_rank_of(self)

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
    def is_structure(self) -> bool:
        """The rigid linkage is locked (mobility 0) and no input hinge turns it. Its loads and
        force actuators load it, its stroke actuators move their points elastically from the
        as-fabricated pose; the physical levels solve it, the kinematic levels have nothing to
        move (docs/levels.md, "Structures")."""
        return not any(h.input for h in self.hinges) and self.mobility == 0

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


def closure_rank(mech: Mechanism) -> ClosureRank | None:
    """The rank of the closure Jacobian of the rigid linkage at the as-fabricated pose
    (:func:`~.closure.closure_rank_of`), computed once per mechanism."""
    return mech.closure_rank


#: The largest magnitude of a coordinate, length, load or material value (and, for the positive
#: ones, 1/MAGNITUDE the smallest): squares and products of two stay normal float64 numbers.
MAGNITUDE = mpmath.mpf("1e150")


def check_values(
    mech: Mechanism, values: Mapping[sp.Symbol, sp.Expr], option: str | None = None
) -> None:
    """Every numeric rule of the file at these parameter values: finite coordinates and angles,
    positive plate lengths, model parameters in range (plates may sit closer together than their
    length, and may cross: :func:`crossing_plates`). `option` names the command-line option that
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

        def within(
            value: mpmath.mpf | None, key: str, entry: str, line: int | None, positive: bool
        ) -> None:
            # squares and products of two such numbers stay normal float64 numbers, in every
            # backend alike (beyond them the generated code refused, the 40-digit one did not)
            if value is None or value == 0:  # zero: the sign rules name it
                return
            size = abs(value)
            if size > MAGNITUDE or (positive and size < 1 / MAGNITUDE):
                bounds = "1e-150 to 1e150" if positive else "at most 1e150"
                raise fail(
                    f"'{key}' = {mpmath.nstr(value, 6)} is outside the magnitudes symkin "
                    f"computes with ({bounds}: their squares must stay float64 numbers)",
                    entry,
                    line,
                    f"give '{key}' a magnitude of {bounds} (choose the file's units to suit)",
                )

        for h in mech.hinges:
            entry = f"[[hinge]] '{h.name}'"
            x, y = (mp_at(v, values) for v in h.at)
            angle = mp_at(h.plate_angle, values)
            length = mp_at(h.length, values)
            for v in (x, y):
                within(v, "at", entry, h.line, positive=False)
            within(length, "length", entry, h.line, positive=True)
            if angle is not None and abs(angle) > 2 * mpmath.pi * (1 + mpmath.mpf("1e-20")):
                raise fail(
                    f"plate_angle = {mpmath.nstr(angle, 6)} rad is beyond a full turn",
                    entry,
                    h.line,
                    f"plate_angle is in radians: if degrees were meant, write "
                    f'plate_angle = "{mpmath.nstr(angle, 6)}*deg"',
                )
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
                value = mp_at(raw, values)
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
                    raise fail(f"{message}, got {key} = {short(value)}", entry, h.line, hint)
                if value is not None and key != "nu":
                    within(mpmath.mpf(str(value)), key, entry, h.line, positive=True)
            if h.thickness is not None and not mp_at(h.thickness, values) < length:
                raise fail(
                    f"thickness {mpmath.nstr(mp_at(h.thickness, values), 6)} is not smaller "
                    f"than the plate length {mpmath.nstr(length, 6)}",
                    entry,
                    h.line,
                    "a flexure plate is thin: make thickness < length",
                )
            notch_fault = _notch_fault(h, values)
            if notch_fault is not None:
                raise fail(notch_fault[0], entry, h.line, notch_fault[1])
        for load in mech.loads:
            for v in (*load.force, load.moment):
                within(mp_at(v, values), "force", load.label, load.line, positive=False)
            if None in [mp_at(v, values) for v in (*load.force, load.moment)]:
                raise fail(
                    "'force' or 'moment' is not a finite number",
                    load.label,
                    load.line,
                    "keep loads finite",
                )
        for p in mech.points:
            for v in p.at:
                within(mp_at(v, values), "at", f"[[point]] '{p.name}'", p.line, positive=False)
            if None in [mp_at(v, values) for v in p.at]:
                raise fail(
                    "'at' is not a finite number",
                    f"[[point]] '{p.name}'",
                    p.line,
                    "keep coordinates finite",
                )
        for act in mech.actuators:
            for v in act.at:
                within(mp_at(v, values), "at", f"[[actuator]] '{act.name}'", act.line, False)
            if None in [mp_at(v, values) for v in (*act.at, *act.direction)]:
                raise fail(
                    "'at' or 'direction' is not a finite number",
                    f"[[actuator]] '{act.name}'",
                    act.line,
                    "keep the point of action and the line of action finite",
                )
        for link in mech.links:
            if link.mass is not None:
                _check_mass(link, values, fail, within)


def crossing_plates(mech: Mechanism) -> list[tuple[str, str]]:
    """The pairs of plates (hinges, in file order) whose straight plates cross or overlap in
    the as-fabricated pose at the file's values: a cross-spring pivot, whose leaves lie in
    different layers. symkin accepts them (each plate is a beam of its own, with no contact
    between them); `check` names them (docs/file-format.md, "[[hinge]]")."""
    values = mech.defaults
    ends = []
    with mpmath.workdps(30):
        for h in mech.hinges:
            x, y, angle, length = (mp_at(v, values) for v in (*h.at, h.plate_angle, h.length))
            if None in (x, y, angle, length):
                return []  # the value checks report it
            assert x is not None and y is not None and angle is not None and length is not None
            u = (mpmath.cos(angle) * length / 2, mpmath.sin(angle) * length / 2)
            ends.append((h.name, (x - u[0], y - u[1]), (x + u[0], y + u[1]), length))
        out = []
        for i, (a, p0, p1, la) in enumerate(ends):
            for b, q0, q1, lb in ends[i + 1 :]:
                if _segments_meet(p0, p1, q0, q1, mpmath.mpf(10) ** -20 * max(la, lb) ** 2):
                    out.append((a, b))
    return out


#: A point of the plane, 30-digit numbers.
_Pt = tuple[mpmath.mpf, mpmath.mpf]


def _segments_meet(p0: _Pt, p1: _Pt, q0: _Pt, q1: _Pt, tiny: mpmath.mpf) -> bool:
    """Whether the segments p0-p1 and q0-q1 share a point (`tiny`: the area below which three
    points count as collinear)."""

    def cross(o: _Pt, a: _Pt, b: _Pt) -> mpmath.mpf:
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])

    def within(o: _Pt, a: _Pt, b: _Pt) -> bool:  # b on the segment o-a, given collinear
        return bool(
            min(o[0], a[0]) <= b[0] <= max(o[0], a[0])
            and min(o[1], a[1]) <= b[1] <= max(o[1], a[1])
        )

    d1, d2 = cross(q0, q1, p0), cross(q0, q1, p1)
    d3, d4 = cross(p0, p1, q0), cross(p0, p1, q1)
    if ((d1 > tiny and d2 < -tiny) or (d1 < -tiny and d2 > tiny)) and (
        (d3 > tiny and d4 < -tiny) or (d3 < -tiny and d4 > tiny)
    ):
        return True
    return (
        (abs(d1) <= tiny and within(q0, q1, p0))
        or (abs(d2) <= tiny and within(q0, q1, p1))
        or (abs(d3) <= tiny and within(p0, p1, q0))
        or (abs(d4) <= tiny and within(p0, p1, q1))
    )


def _check_mass(
    link: Link,
    values: Mapping[sp.Symbol, sp.Expr],
    fail: Callable[[str, str, int | None, str], InputError],
    within: Callable[[mpmath.mpf | None, str, str, int | None, bool], None],
) -> None:
    """A link's mass (kg, > 0), inertia (kg·m², ≥ 0) and centre (finite) at these values
    (docs/file-format.md, "[[link]]"); `fail` and `within` check_values's."""
    entry = f"[[link]] '{link.name}'"
    mass = mp_at(link.mass, values)
    if mass is None or not mass > 0:
        shown = "not finite" if mass is None else mpmath.nstr(mass, 6)
        raise fail(
            f"mass must be positive (kg), got {shown}",
            entry,
            link.line,
            "give the link's mass in kg, e.g. mass = 0.12, or remove it (a massless link)",
        )
    within(mass, "mass", entry, link.line, True)
    if link.inertia is not None:
        inertia = mp_at(link.inertia, values)
        if inertia is None or not inertia >= 0:
            shown = "not finite" if inertia is None else mpmath.nstr(inertia, 6)
            raise fail(
                f"inertia must be zero or positive (kg·m², about the centre of mass), got {shown}",
                entry,
                link.line,
                "give the inertia in kg·m² (SI, whatever the file's unit), e.g. inertia = 2e-5",
            )
        within(inertia, "inertia", entry, link.line, True)
    assert link.centre is not None
    centre = [mp_at(v, values) for v in link.centre]
    for v in centre:
        within(v, "centre", entry, link.line, False)
    if None in centre:
        raise fail(
            "'centre' is not a finite number",
            entry,
            link.line,
            "keep the centre of mass finite",
        )


def _notch_fault(hinge: Any, values: Mapping[sp.Symbol, sp.Expr]) -> tuple[str, str] | None:
    """(message, hint) when a notch whose keys are parameters (model.notch_series) has, at these
    values, a key that is not positive or a ratio outside its fitted series' range; else None."""
    params = dict(getattr(hinge, "profile_params", ()) or ())
    if not params or hinge.model != "pure_moment":
        return None
    keys = {"thickness": hinge.thickness, **params}
    if not any(sp.sympify(v).free_symbols for v in keys.values() if v is not None):
        return None
    for key, raw in keys.items():
        value = None if raw is None else mp_at(raw, values)
        if raw is not None and (value is None or not value > 0):
            shown = "not finite" if value is None else mpmath.nstr(value, 6)
            return f"notch key '{key}' must be positive, got {shown}", f"keep '{key}' positive"
    from . import notch_series
    from .profiles import section_of

    reason = notch_series.check_ratio(section_of(hinge, 1), dict(values))
    if reason is None:
        return None
    return reason, f"keep {notch_series.ratio_name(section_of(hinge, 1))} within " + (
        f"{notch_series.RANGE[0]:g}..{notch_series.RANGE[1]:g}"
    )
