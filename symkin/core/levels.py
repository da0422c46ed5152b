"""The deviation levels (docs/levels.md): one table that every layer reads.

A level is how faithfully the compliant mechanism is modelled. Its `name` is what a user types
(`--level`, the numpy module's `LEVELS`, the JSON), its `code` the generated C's `level`
argument. The command line, the evaluators, the templates, `tradeoff`, the tests and the
benchmarks take names and codes from :data:`LEVELS` only; adding a level is one row here, its
math (analysis, evaluation) and one block per template.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Protocol

from .errors import InputError


@dataclass(frozen=True)
class Level:
    """One row of the level table."""

    name: str  # --level, numpy LEVELS, JSON "level"
    code: int  # the generated C's `level` argument
    title: str  # how reports and plots name it
    needs_delta: bool  # compliant angles differ from rigid ones: the loops are solved
    equation: str = ""  # the paper's equation it restates, e.g. "(4.8)"
    needs_stiffness: bool = False  # needs E, thickness and width of every compliant plate
    generated: bool = True  # the generated C and numpy hold it; else mpmath only
    sensitivity: bool = True  # closed-form derivatives by the parameters (docs/sensitivity.md)
    #: how the 40-digit evaluation solves it (symkin.studies.evaluation's SOLVERS): "kinematic"
    #: (the loops, the deviation of the paper's sections 3-5), "reduced" (Newton on the reduced
    #: equilibrium, symkin.physics.reduced) or "beams" (the plates as beams, physics.equilibrium)
    solver: str = "kinematic"
    shares: str = ""  # the level whose loop solver and deviation routine it runs,
    # with constants of its own

    @property
    def routine(self) -> str:
        """The name of its loop solver and deviation routine in generated code."""
        return self.shares or self.name

    @property
    def label(self) -> str:
        """The title with the paper's equation, for legends: 'paper (4.8)'."""
        return f"{self.title} {self.equation}" if self.equation else self.title


#: Every level, in order of fidelity. Codes are unique and never change once given (a retired
#: level's stays in RESERVED): a new level takes the next free code wherever it sits in fidelity.
LEVELS: tuple[Level, ...] = (
    Level("paper", 0, "paper", needs_delta=False, equation="(4.8)"),
    Level("first_order", 1, "first order", needs_delta=True),
    Level("exact", 2, "exact", needs_delta=True),
    # The physical levels (docs/physics.md): the plates' stiffness and the file's loads.
    # Code 5 was `loaded_refined` (a second pass of the old linearised statics), retired when
    # `loaded` became Newton on the reduced equilibrium: it stays reserved, never given again.
    Level("loaded", 3, "loaded", needs_delta=True, needs_stiffness=True, solver="reduced"),
    Level(
        "equilibrium",
        4,
        "equilibrium",
        needs_delta=False,
        needs_stiffness=True,
        generated=False,
        sensitivity=False,
        solver="beams",
    ),
)
#: Codes of retired levels, by their old name: never given to a new level.
RESERVED: dict[str, int] = {"loaded_refined": 5}
#: The closed-form physical level: Newton on the reduced equilibrium (symkin.physics.reduced),
#: the plates by their closed-form relation (symkin.physics.plate_relation).
LOADED: tuple[str, ...] = ("loaded",)

NAMES: tuple[str, ...] = tuple(lv.name for lv in LEVELS)
#: The levels the generated C and numpy evaluators can hold (`derive --levels`).
GENERATED: tuple[str, ...] = tuple(lv.name for lv in LEVELS if lv.generated)
#: The default level where the file's data allows forces (:func:`default_for`): the
#: closed-form physical level; else the kinematic model's own loop closure.
PHYSICAL_DEFAULT = "loaded"
KINEMATIC_DEFAULT = "exact"

_BY_NAME = {lv.name: lv for lv in LEVELS}


def get(name: str, entry: str = "--level") -> Level:
    """The level called `name`; an unknown name is bad input (exit 2) naming the choices."""
    try:
        return _BY_NAME[name]
    except KeyError:
        retired = " (retired: `loaded` replaces it)" if name in RESERVED else ""
        raise InputError(
            f"unknown level '{name}'{retired}", entry=entry, hint="levels: " + ", ".join(NAMES)
        ) from None


def reference(stiffness: bool = False) -> Level:
    """The most faithful level the data allows: what accuracy is measured against."""
    return [lv for lv in LEVELS if stiffness or not lv.needs_stiffness][-1]


class LevelWarning(UserWarning):
    """A kinematic level asked for on a file whose plates all have stiffness data: it ignores
    the plates' forces (the command line prints it as one line)."""


class _Mechanism(Protocol):
    """What :func:`default_for` reads of a mechanism (symkin.model.mechanism.Mechanism)."""

    @property
    def hinges(self) -> Sequence[Any]: ...

    @property
    def has_stiffness(self) -> bool: ...

    @property
    def redundant(self) -> int: ...


@dataclass(frozen=True)
class Choice:
    """The level a command runs and why: `reason` is what the text output prints in
    parentheses after the level's name (docs/levels.md, "The default level")."""

    name: str
    reason: str
    default: bool  # picked by the file's data, not asked for

    @property
    def line(self) -> str:
        """The text output's line: 'level: loaded (default: every plate has E, ...)'."""
        return f"level: {self.name} ({self.reason})"


#: The generated backends whose `loaded` takes notch hinges (docs/levels.md; the C's takes
#: uniform plates).
NOTCH_BACKENDS = ("numpy",)


def first_notch(mechanism: Any) -> Any | None:
    """The file's first notch hinge (a plate whose `profile` is not uniform), or None."""
    plates = (h for h in mechanism.hinges if h.is_plate)
    return next((h for h in plates if getattr(h, "profile", "uniform") != "uniform"), None)


def loaded_by_default(mechanism: Any) -> bool:
    """Whether the generated evaluators' derivation holds `loaded` when no level is named
    (symkin.codegen.plan, and graph.pruning's force paths with it): every plate has its
    stiffness, and no notch reads the file's parameters (:func:`parametric_notch`)."""
    return bool(mechanism.has_stiffness) and parametric_notch(mechanism) is None


def parametric_notch(mechanism: Any) -> tuple[Any, str, tuple[str, ...]] | None:
    """The first notch hinge whose keys read the file's parameters, with that key and the
    parameters' names, or None: the generated `loaded` folds a notch's section in as numbers
    (docs/levels.md), so such a notch leaves that level to the sympy backend."""
    import sympy as sp  # the level table is read before any expression is: import it late

    free = {p.symbol for p in getattr(mechanism, "parameters", ())}
    for h in mechanism.hinges:
        if not h.is_plate or getattr(h, "profile", "uniform") == "uniform":
            continue
        keys = {k: getattr(h, k) for k in ("length", "thickness", "width", "E", "nu")}
        keys.update(dict(h.profile_params))
        for key, value in keys.items():
            found = sp.sympify(value).free_symbols & free if value is not None else set()
            if found:
                return h, key, tuple(sorted(map(str, found)))
    return None


def default_for(mechanism: _Mechanism, generated: bool | str = False) -> Choice:
    """The level `eval`, `tolerance`, `sweep`, `symkin.evaluate`, `symkin.compile` and the
    generated evaluators use when none is given (docs/levels.md, "The default level"): `loaded`
    where every plate (every hinge that is not `rigid`) has E, thickness and width, else
    `exact`; and `exact` where the loaded level refuses the file as a whole (a redundant
    mechanism whose plates are all inextensible elastica: the forces its redundant loops carry
    are undetermined, docs/physics.md), so that a default run never fails for the level's sake.
    Notch hinges take `loaded` like plates (docs/physics.md, "Notch hinges at `loaded`"), in
    the generated evaluators too where `generated` names a backend of NOTCH_BACKENDS (numpy);
    `exact` for another generated backend (the C's `loaded` takes uniform plates) or True (a
    generated backend not named)."""
    plates = [h for h in mechanism.hinges if h.is_plate]
    if not mechanism.has_stiffness:
        keys = ("E", "thickness", "width")
        h, key = next((h, k) for h in plates for k in keys if getattr(h, k) is None)
        return Choice(
            KINEMATIC_DEFAULT,
            f"default: not every plate has E, thickness and width (hinge '{h.name}' has no "
            f"{key}), so no forces",
            default=True,
        )
    if mechanism.redundant and not any(h.beam == "reissner" for h in plates):
        return Choice(
            KINEMATIC_DEFAULT,
            "default: the loaded level cannot solve a redundant mechanism whose plates are all "
            'inextensible (beam = "elastica")',
            default=True,
        )
    notch = first_notch(mechanism)
    if generated and generated not in NOTCH_BACKENDS and notch is not None:
        which = f"{generated} " if isinstance(generated, str) else ""
        return Choice(
            KINEMATIC_DEFAULT,
            f"default: the generated {which}evaluators' loaded takes uniform plates (hinge "
            f"'{notch.name}' is {notch.profile}); --backend numpy or sympy takes it",
            default=True,
        )
    reads = parametric_notch(mechanism) if generated and notch is not None else None
    if reads is not None:
        h, key, names = reads
        return Choice(
            KINEMATIC_DEFAULT,
            f"default: the generated evaluators' loaded takes a notch's keys as numbers (hinge "
            f"'{h.name}': its {key} reads {', '.join(names)}); --backend sympy takes it",
            default=True,
        )
    if not plates:  # nothing bends: the physical level, as the rule says, at no extra cost
        return Choice(PHYSICAL_DEFAULT, "default: every hinge is a rigid pin, no plate", True)
    return Choice(PHYSICAL_DEFAULT, "default: every plate has E, thickness and width", True)


def choose(mechanism: _Mechanism, level: str | None, generated: bool | str = False) -> Choice:
    """The level `level` names (asked for; an unknown name is bad input, exit 2), or the
    mechanism's default (:func:`default_for`, for the `generated` evaluators) when it is None."""
    if level is None:
        return default_for(mechanism, generated)
    return Choice(get(level).name, "asked for", default=False)


def ignores_forces(mechanism: _Mechanism, choice: Choice) -> str:
    """The warning for a kinematic level asked for on a file whose plates all have stiffness
    data (the default would be physical): it ignores the plates' forces; "" otherwise."""
    if choice.default or get(choice.name).needs_stiffness:
        return ""
    if default_for(mechanism).name != PHYSICAL_DEFAULT:
        return ""
    return (
        f"--level {choice.name} ignores the plates' forces (every plate has E, thickness and "
        "width); --level loaded includes them"
    )
