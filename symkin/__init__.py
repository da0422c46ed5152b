"""symkin: how far a flexure-hinge mechanism strays from its ideal rigid linkage, in closed form.

    mech = symkin.load("examples/four_bar.toml")     # validated Mechanism (names, exact numbers)
    s = symkin.structure(mech)                        # labeling and I, I+, Φ, Ψ = [T; 0]
    an = symkin.analyze(mech)                         # symbolic deviation at every level
    symkin.evaluate(an, {"A0": 0.2}, level="exact")   # one configuration, mpmath at 40 digits
    symkin.evaluate(an, {"A0": 0.2}, level="equilibrium")  # the plates as elastica
    symkin.evaluate(an, {"A0": 0.2}, level="loaded")  # Newton on the reduced equilibrium

The physical levels need E, thickness and width of the plates (docs/physics.md); their solvers
are in symkin.physics (`loaded`: symkin.physics.reduced with the closed-form plate relation).
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING

from .core.errors import AssemblyError, InputError, SymkinError
from .graph.structure import Structure
from .graph.structure import build as structure
from .model.mechanism import Mechanism
from .model.reader import load, loads

if TYPE_CHECKING:  # the heavy modules load on first use
    from .kinematics.analysis import Analysis
    from .studies.compiled import Compiled
    from .studies.results import Evaluation

__version__ = "0.1.0"


def analyze(mechanism: Mechanism | str | Path, points: list[str] | None = None) -> Analysis:
    """The :class:`symkin.kinematics.analysis.Analysis` of a mechanism (or of the file at that
    path)."""
    from .kinematics.analysis import Analysis

    mech = mechanism if isinstance(mechanism, Mechanism) else load(mechanism)
    return Analysis(structure(mech), points)


def evaluate(
    analysis: Analysis,
    inputs: Mapping[str, object],
    level: str | None = None,
    params: Mapping[str, object] | None = None,
    backend: str = "sympy",
    dps: int = 40,
    sensitivity: bool = False,
) -> Evaluation:
    """One configuration of an analysis (:func:`symkin.studies.evaluation.evaluate`): the derivation
    with mpmath at `dps` digits (backend sympy) or the generated numpy / C evaluators; with
    `sensitivity`, the derivatives by every parameter and input too (docs/sensitivity.md).
    `level` None: the mechanism's default, `loaded` where every plate has E, thickness and
    width, else `exact` (symkin.core.levels.default_for, docs/levels.md)."""
    from .studies.evaluation import evaluate as run

    return run(analysis, inputs, level, params, backend, dps, sensitivity)


def compile(
    mechanism: Mechanism | Analysis | str | Path,
    backend: str = "c",
    points: list[str] | None = None,
    levels: list[str] | None = None,
    sensitivity: bool = True,
    fixed: Mapping[str, object] | None = None,
) -> Compiled:
    """The generated evaluator of a mechanism, in memory, no files left behind
    (:func:`symkin.studies.compiled.compile`): `evaluate`, `sensitivity` and `sensitivity_full` on
    arrays of inputs, one C call each; with `points`, only what moves them (docs/pruning.md);
    `fixed` inputs (name -> angle) are held constant and folded in."""
    from .studies.compiled import compile as build_evaluator

    return build_evaluator(mechanism, backend, points, levels, sensitivity, fixed)


__all__ = [
    "AssemblyError",
    "InputError",
    "Mechanism",
    "Structure",
    "SymkinError",
    "__version__",
    "analyze",
    "compile",
    "evaluate",
    "load",
    "loads",
    "structure",
]
