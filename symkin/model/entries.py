"""The entries of a mechanism file as the reader returns them (docs/file-format.md): a parameter,
a link, a hinge with its plate data, a point, a load and an actuator, each immutable, and the
rules of the hinges' stiffness keys the reader and :func:`~.mechanism.check_values` apply.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import sympy as sp

from .hinges import BEAMS

#: How an actuator drives its link (docs/file-format.md, "Actuators"): a prescribed displacement
#: of its point along its line of action (file unit), or a force along it (N).
DRIVES = ("stroke", "force")
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


def short(value: object) -> str:
    """A number as an error message shows it: 6 significant digits, not sympy's 30."""
    try:
        return f"{float(value):.6g}"  # type: ignore[arg-type]
    except (TypeError, ValueError):
        return str(value)


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
    """A rigid body; `mass` (kg), `inertia` (kg·m², about the centre of mass) and `centre` (the
    centre of mass as fabricated, file unit) for the natural frequencies (docs/physics.md,
    "Natural frequencies"): None where the file gives no mass (a massless link)."""

    name: str
    index: int  # position among the file's [[link]] entries
    line: int | None = None
    mass: sp.Expr | None = None
    inertia: sp.Expr | None = None  # None: 0 (a point mass)
    centre: tuple[sp.Expr, sp.Expr] | None = None

    @property
    def massive(self) -> bool:
        return self.mass is not None


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
    # whether a notch's beam carries the continuum correction (model.notch_correction)
    continuum_correction: bool = True

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
    and find its angle from the stroke (docs/levels.md, "Actuators"). `spring` (N per file
    unit; stroke actuators only, None: ideal) puts a spring in series with the stroke: the
    input is then the free stroke commanded, and at the physical levels the actual stroke is
    the command less force/spring (docs/physics.md, "Actuators at loaded")."""

    name: str
    index: int
    link: str
    at: tuple[sp.Expr, sp.Expr]
    direction: tuple[sp.Expr, sp.Expr]
    drive: str
    surrogate: str
    line: int | None = None
    spring: sp.Expr | None = None

    @property
    def point(self) -> str:
        """The name of the hidden point at `at` the evaluators track (no file name can clash:
        names are identifiers, this one holds a '@')."""
        return f"@{self.name}"
