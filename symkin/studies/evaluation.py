"""One configuration evaluated (`symkin eval`): the derivation with mpmath, or the generated code.

The `sympy` backend evaluates the expressions of :class:`~symkin.kinematics.analysis.Analysis`
with mpmath at `dps` digits (40 by default), so its float64 results are correctly rounded
references for the generated evaluators (symkin.studies.mpmath_evaluator: the kinematic levels;
symkin.studies.physical: `loaded` and `equilibrium`). The `numpy` and `c` backends run the
generated evaluators (symkin.studies.generated); when one of them cannot assemble a
configuration, the mpmath evaluation is asked why, so every backend fails with the same exit
code (3) and the same message naming the loop (docs/cli.md). A mechanism driven by actuators is
evaluated at the surrogate hinges' angles that reach the strokes (symkin.studies.actuators). The
level, inputs and parameters are parsed once, at the entry, into a
:class:`~symkin.studies.configuration.Configuration` that every level and backend takes."""

from __future__ import annotations

import dataclasses
import warnings
from collections.abc import Callable, Mapping
from typing import NoReturn

import mpmath
import sympy as sp

from ..core import backends, levels
from ..core.errors import AssemblyError, InputError, PlausibilityWarning
from ..kinematics.analysis import Analysis
from ..model.mechanism import Mechanism
from ..physics.equilibrium import units_hint
from ..physics.stiffness import plate_stiffness
from . import generated, mpmath_sensitivity
from .actuators import check_actuated_level, stroke_angles, stroke_sensitivity
from .configuration import Configuration, configure, parameter_floats
from .mpmath_evaluator import MpmathEvaluator, evaluator_of
from .physical import equilibrium, loaded
from .results import Evaluation, LinkResult, PointResult

#: The mpmath evaluation of the derivation, then the generated-code backends (the table).
BACKENDS = backends.NAMES


def evaluate(
    analysis: Analysis,
    inputs: Mapping[str, object],
    level: str | None = None,
    params: Mapping[str, object] | None = None,
    backend: str = "sympy",
    dps: int = 40,
    sensitivity: bool = False,
) -> Evaluation:
    """Evaluate one configuration at `level` through `backend` (sympy: mpmath at `dps` digits);
    with `sensitivity`, also the derivatives by every parameter and input
    (docs/sensitivity.md); `level` None: the mechanism's default (levels.default_for)."""
    mech = analysis.mechanism
    caps = backends.get(backend)  # an unknown backend: exit 2, naming the choices
    level = levels.choose(mech, level, caps.generated and backend).name
    if sensitivity and not levels.get(level).sensitivity:
        having = [lv.name for lv in levels.LEVELS if lv.generated and lv.sensitivity]
        raise InputError(
            f"the {level} level has no sensitivities",
            file=mech.path,
            entry="--sensitivity",
            hint="ask for them at " + ", ".join(having) + " (docs/sensitivity.md)",
        )
    # what the backend cannot do is refused before the values are read
    if not levels.get(level).needs_stiffness:
        mech.refuse_structure(level=level)
    if mech.actuators:
        check_actuated_level(mech, level, backend, sensitivity)
    if caps.generated:
        generated.check_level(level, caps)
        if levels.get(level).needs_stiffness:
            # the generated `loaded` takes notches whose keys are numbers, in numpy (the C's
            # takes uniform plates): refused here (exit 2, naming the hinge), not left to a plan
            # derived without the level
            from ..codegen.loaded import generated_notches

            generated_notches(mech, backend)
            plate_stiffness(mech, level, notches=True)
    result = _dispatch(
        analysis, configure(analysis, inputs, level, params), backend, dps, sensitivity
    )
    _plausible(result, mech)
    return result


#: A buckling factor below this says the loads are far beyond what the plates carry: a warning
#: naming the factor and the units to check (docs/physics.md, "Overloads and buckling").
FAR_BEYOND_BUCKLING = 0.1


def _plausible(result: Evaluation, mech: Mechanism) -> None:
    """Warn (one line on the command line) where the loads are far beyond buckling."""
    factor = result.buckling
    if factor is None or not factor < FAR_BEYOND_BUCKLING:
        return
    times = f"{1 / factor:.4g} times" if factor > 0 else "beyond"
    warnings.warn(
        f"{mech.path}: the loads are {times} the first buckling load of the mechanism (its "
        f"buckling factor {factor:.4g}"
        + (f", hinge '{result.buckling_hinge}'" if result.buckling_hinge else "")
        + f"): {units_hint(mech.units)} (docs/physics.md)",
        PlausibilityWarning,
        stacklevel=3,
    )


def _dispatch(
    analysis: Analysis, config: Configuration, backend: str, dps: int, sensitivity: bool
) -> Evaluation:
    """:func:`evaluate` at a configuration parsed once."""
    if analysis.mechanism.actuators:
        return _actuated(analysis, config, backend, dps, sensitivity)
    return _evaluate(analysis, config, backend, dps, sensitivity)


def _evaluate(
    analysis: Analysis, config: Configuration, backend: str, dps: int, sensitivity: bool
) -> Evaluation:
    """:func:`evaluate` with every input a hinge angle (the actuators' surrogates included)."""
    if not backends.get(backend).generated:
        return SOLVERS[config.level.solver](analysis, config, dps, sensitivity)
    return _generated(analysis, config, backend, sensitivity)


def _kinematic(
    ev: MpmathEvaluator, config: Configuration, dps: int, sensitivity: bool = False
) -> Evaluation:
    """A kinematic level in mpmath at `dps` digits (docs/levels.md); with `sensitivity`, the
    derivatives by every parameter and input (docs/sensitivity.md)."""
    an, level = ev.an, config.level.name
    with mpmath.workdps(dps):
        state = ev.state(config, dps)
        points = {}
        for name, (rig, dev) in ev.point_values(state).items():
            points[name] = PointResult(
                (float(rig[0]), float(rig[1])),
                (float(rig[0] + dev[0]), float(rig[1] + dev[1])),
                (float(dev[0]), float(dev[1])),
            )
        theta, delta, ivals = state.theta, state.delta, state.inputs
        args, values = ev.arguments(state)
        links = ev.links(an, level, "", args, values)
        names = {a: ev.kin.hinges[a].name for a in ev.kin.hinges}
        return Evaluation(
            level=level,
            backend="sympy",
            inputs={names[a]: float(ivals[a]) for a in sorted(ivals)},
            angles_rigid={names[a]: float(theta[a]) for a in sorted(theta)},
            angles_compliant={names[a]: float(theta[a] + delta.get(a, 0)) for a in sorted(theta)},
            points=points,
            dyads=tuple(state.dyads),
            params=parameter_floats(ev.mechanism, state.exact_params),
            overrides=config.overrides,
            links=links,
            sensitivity=mpmath_sensitivity.of(ev, state) if sensitivity else None,
        )


def _actuated(
    analysis: Analysis, config: Configuration, backend: str, dps: int, sensitivity: bool
) -> Evaluation:
    """One configuration of a mechanism driven by stroke actuators (docs/levels.md,
    "Actuators"): the rigid linkage and the compliant mechanism each at the strokes. Each
    actuator's surrogate hinge takes the angle at which the rigid point of action has moved by
    the stroke along the line of action, and, separately, the (compliant) angle at which the
    compliant point has; the deviation is compliant - rigid, each taken at its own angle."""
    mech = analysis.mechanism
    if backends.get(backend).generated:  # the generated module solves the strokes itself
        return _generated(analysis, config, backend, sensitivity)
    if config.level.solver != "kinematic":  # the physical levels take the strokes themselves
        return SOLVERS[config.level.solver](analysis, config, dps, sensitivity)
    given = config.drives
    strokes = list(config.strokes.values())
    solver = evaluator_of(analysis)
    rigid = stroke_angles(solver, config, strokes, dps, compliant=False)
    compliant = stroke_angles(solver, config, strokes, dps, compliant=True, start=rigid)

    def run(angles, with_rates=sensitivity):
        # each angle the double its dps + 10 digits round to, as an input given as text
        at = config.with_angles({s: float(mpmath.nstr(v, dps + 10)) for s, v in angles.items()})
        return _evaluate(analysis, at, backend, dps, with_rates)

    ev_r, ev_c = run(rigid), run(compliant)
    rates = None
    if sensitivity:
        rest = run(dict.fromkeys(rigid, mpmath.mpf(0)))
        rates = stroke_sensitivity(config, ev_r, ev_c, rest)
    hidden = {a.point for a in mech.actuators}
    points = {}
    for name, c in ev_c.points.items():
        if name in hidden:
            continue
        r = ev_r.points[name]
        # compliant - rigid, each at its own surrogate angles: the rigid shift between the two
        # angles plus the deviation at the compliant ones
        dev = tuple(c.rigid[i] - r.rigid[i] + c.deviation[i] for i in range(2))
        points[name] = PointResult(r.rigid, c.compliant, dev)
    links = {
        name: LinkResult(
            ev_r.links[name].rigid,
            c.compliant,
            c.rigid - ev_r.links[name].rigid + c.deviation,
        )
        for name, c in ev_c.links.items()
    }
    return dataclasses.replace(
        ev_c,
        inputs={k: float(sp.N(v, 20)) for k, v in given.items()},
        angles_rigid=dict(ev_r.angles_rigid),
        points=points,
        links=links,
        dyads=ev_r.dyads,
        sensitivity=rates,
    )


def _generated(
    analysis: Analysis, config: Configuration, backend: str, sensitivity: bool = False
) -> Evaluation:
    """One configuration through a generated-code `backend` (symkin.studies.generated); where
    it cannot solve it, the sympy backend's error."""
    try:
        return generated.evaluate(analysis, config, backend, sensitivity)
    except generated.Unsolved:
        pass
    _explain(analysis, config, sensitivity)


def _explain(analysis: Analysis, config: Configuration, sensitivity: bool = False) -> NoReturn:
    """Raise the sympy backend's error for a configuration a generated evaluator refused."""
    _dispatch(analysis, config, "sympy", 40, sensitivity)
    raise AssemblyError(
        f"{analysis.mechanism.path}: the generated evaluator could not solve this "
        "configuration (no convergence in float64), although the 40-digit "
        "derivation can"
    )


#: How the 40-digit evaluation solves each kind of level (core/levels, Level.solver): a level
#: with a solve of its own is a row here and its row in the level table.
SOLVERS: dict[str, Callable[[Analysis, Configuration, int, bool], Evaluation]] = {
    "kinematic": lambda an, config, dps, sens: _kinematic(evaluator_of(an), config, dps, sens),
    "reduced": loaded,
    "beams": lambda an, config, dps, sens: equilibrium(an, config),
}
