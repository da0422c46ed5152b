"""The deviation levels (docs/levels.md): one table that every layer reads.

A level is how faithfully the compliant mechanism is modelled. Its `name` is what a user types
(`--level`, the numpy module's `LEVELS`, the JSON), its `code` the generated C's `level`
argument. The command line, the evaluators, the templates, `tradeoff`, the tests and the
benchmarks take names and codes from :data:`LEVELS` only; adding a level is one row here, its
math (analysis, evaluation) and one block per template.
"""

from __future__ import annotations

from dataclasses import dataclass

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
#: The level `eval` and the generated `evaluate` use when none is given.
DEFAULT = "exact"

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
