"""The physical levels in the `sympy` backend (docs/physics.md): `loaded`, the reduced
equilibrium (symkin.physics.reduced) reported on the rigid linkage solved in mpmath, and
`equilibrium`, the plates as geometrically exact beams (symkin.physics.equilibrium); their
reported loads, stiffness, stresses and buckling, and every physical level's model error."""

from __future__ import annotations

import dataclasses
import functools
import math
import weakref
from collections.abc import Mapping

import mpmath
import numpy as np
import sympy as sp

from ..codegen import plan_cache
from ..codegen.backends.numpy.kernels import float64_namespace
from ..core.errors import AssemblyError, InputError
from ..core.settings import SOLVER
from ..kinematics.analysis import Analysis
from ..model import special
from ..model.mechanism import Mechanism
from ..physics import equilibrium as physical_equilibrium
from ..physics import model_error as physical_model_error
from ..physics import reduced, reduced_reported
from ..physics.result import HingeLoad
from . import mpmath_sensitivity
from .actuators import ReachError, reach_note, stroke_angles
from .configuration import Configuration, configure, parameter_floats
from .mpmath_evaluator import MpmathEvaluator, State, evaluator_of
from .results import Evaluation, LinkResult, PointResult


def loaded(
    analysis: Analysis, config: Configuration, dps: int = 40, sensitivity: bool = False
) -> Evaluation:
    """The `loaded` level (docs/physics.md) at `config` (symkin.studies.configuration): the
    reduced equilibrium in mpmath, reported on the rigid linkage solved at `dps` digits; with
    `sensitivity`, its derivatives by every parameter and input (docs/sensitivity.md)."""
    return _loaded(evaluator_of(analysis), config, dps, sensitivity)


def equilibrium(analysis: Analysis, config: Configuration, extra_digits: int = 0) -> Evaluation:
    """The `equilibrium` level (docs/physics.md) at `config`: the plates as geometrically exact
    beams (each hinge's `beam`), solved numerically to its own error estimate; `extra_digits`
    raises the working precision (to check it)."""
    return _equilibrium(evaluator_of(analysis), config, extra_digits)


def _loaded(
    ev: MpmathEvaluator,
    config: Configuration,
    dps: int,
    sensitivity: bool = False,
) -> Evaluation:
    """The `loaded` level (docs/physics.md): the reduced equilibrium (symkin.physics.reduced)
    in mpmath, its deviations, angle deviations, hinge loads and energy put on the rigid
    linkage solved at `dps` digits; a configuration it refuses (no convergence, a plate
    near buckling, the truncation estimate with two half plates) is exit 3."""
    an, mech = ev.an, ev.mechanism
    if an.redundant and not any(h.beam == "reissner" for h in mech.hinges if h.is_plate):
        # as at equilibrium: inextensible plates leave a redundant loop's self-stress
        # undetermined (the relation's quartic terms alone would fix it, meaninglessly)
        raise AssemblyError(
            f"{mech.path}: the loaded level cannot solve this redundant mechanism "
            f"({len(an.dropped)} redundant closure constraint(s)): its plates are "
            "inextensible elastica, which leave the forces the redundant loops carry along "
            'the plates undetermined; give them beam = "reissner" (docs/levels.md)'
        )
    answer = solve_reduced(an, config, backend="sympy")
    if answer.refused:
        # loads far beyond buckling: by what factor, and the units to check (no other level
        # solves them either); else the level that may
        raise AssemblyError(
            f"{mech.path}: the loaded level refuses this configuration: {answer.refused} "
            "(docs/physics.md)" + (_overloaded(ev, config) or "; ask for --level equilibrium")
        )
    exact_params = config.params
    names = {a: h.name for a, h in ev.kin.hinges.items()}
    hidden = {a.point for a in mech.actuators}
    acting: dict[str, sp.Expr] = {}
    if mech.actuators:
        # the rigid linkage at the strokes (a force actuator's: the one it produced)
        acting = config.strokes
        found = stroke_angles(
            ev,
            config,
            [sp.Float(answer.strokes[a.name], 17) for a in mech.actuators],
            dps,
            compliant=False,
        )
        # each angle the double its dps + 5 digits round to, as an input given as text
        at_strokes = {n: float(mpmath.nstr(v, dps + 5)) for n, v in found.items()}
        given = config.with_angles(at_strokes).angles
    else:
        given = config.angles
    args = [*an.params, *an.thetas]
    with mpmath.workdps(dps):
        pvals = [mpmath.mpf(sp.N(exact_params[s], dps + 5)) for s in an.params]
        ivals = {a: mpmath.mpf(sp.N(v, dps + 5)) for a, v in given.items()}
        theta, dyads = ev.rigid_angles(pvals, ivals)
        at = [*pvals, *(theta[a] for a in sorted(theta))]
        points = {}
        for p in an.points:
            if p.name in hidden:
                continue
            rig = ev.fn(f"rigid(theta):{p.name}", list(an.point_rigid(p.name)), args)(*at)
            dev = answer.deviations[p.name]
            points[p.name] = PointResult(
                (float(rig[0]), float(rig[1])),
                (float(rig[0] + dev[0]), float(rig[1] + dev[1])),
                (float(dev[0]), float(dev[1])),
            )
        # the links' rotations: the rigid one from the rigid angles, the deviation from the
        # solution's angle deviations, as at equilibrium
        deltas = [mpmath.mpf(answer.angle_deviations[names[a]]) for a in ev.kin.unknowns]
        links = ev.links(an, "exact", "equilibrium:", [*args, *an.deltas], at + deltas)
        if mech.actuators:
            links = ev.turned_surrogates(links, answer.angle_deviations)
        scale = mpmath.mpf(sp.N(mech.unit_scale, dps))
        hinges = {
            names[a]: HingeLoad(
                (answer.hinge_loads[names[a]][0], answer.hinge_loads[names[a]][1]),
                float(answer.hinge_loads[names[a]][2] * scale),
            )
            for a in sorted(names)
        }
        result = Evaluation(
            level="loaded",
            backend="sympy",
            inputs={names[a]: float(ivals[a]) for a in sorted(ivals) if names[a] in mech.drives}
            | {n: float(sp.N(v, 20)) for n, v in acting.items()},
            angles_rigid={names[a]: float(theta[a]) for a in sorted(theta)},
            angles_compliant={
                names[a]: float(theta[a] + answer.angle_deviations[names[a]]) for a in sorted(theta)
            },
            points=points,
            dyads=tuple(dyads),
            params=parameter_floats(mech, exact_params),
            overrides=config.overrides,
            hinges=hinges,
            energy=float(answer.energy * scale),
            links=links,
            units=mech.units,
            **_reported_fields(answer, float(scale)),
        )
        if answer.unreached:
            if sensitivity:
                raise AssemblyError(
                    f"{mech.path}: no deviation to differentiate: {answer.unreached}"
                )
            return result.beyond_reach(answer.unreached)
        if sensitivity:
            state = State("loaded", exact_params, pvals, ivals, theta, {}, dyads)
            result = dataclasses.replace(
                result, sensitivity=mpmath_sensitivity.of(ev, state, answer)
            )
    return with_model_error(result, mech, exact_params)


def _overloaded(ev: MpmathEvaluator, config: Configuration) -> str:
    """Where `loaded` refuses a configuration whose loads (and force actuators) are beyond the
    plates' first buckling load (its linearised estimate, symkin.physics.equilibrium.overload),
    by what factor, and the file's units to check (docs/physics.md, "Overloads and buckling");
    else ""."""
    mech = ev.mechanism
    if not mech.loads and not any(a.drive == "force" for a in mech.actuators):
        return ""
    names = {a: h.name for a, h in ev.kin.hinges.items()}
    driven = {a.name for a in mech.actuators}
    inputs = {names[a]: v for a, v in config.angles.items()}
    inputs |= {n: v for n, v in config.drives.items() if n in driven}
    try:
        first = physical_equilibrium.overload(mech, config.params, inputs)
    except (AssemblyError, ArithmeticError, ValueError, np.linalg.LinAlgError):
        return ""
    if not first.factor < 1:
        return ""
    return (
        f"; the loads are {1 / first.factor:.4g} times the first buckling load of the plates "
        f"(hinge '{first.hinge}', at the as-fabricated pose: a linearised estimate): "
        + physical_equilibrium.units_hint(mech.units)
    )


def _equilibrium(
    ev: MpmathEvaluator,
    config: Configuration,
    extra_digits: int = 0,
) -> Evaluation:
    """The `equilibrium` level (symkin.physics.equilibrium), against this rigid linkage."""
    an, mech = ev.an, ev.mechanism
    names = {a: h.name for a, h in ev.kin.hinges.items()}
    labels = {n: a for a, n in names.items()}
    driven = {a.name for a in mech.actuators}
    given = config.angles
    acting = {n: v for n, v in config.drives.items() if n in driven}
    exact_params = config.params
    args = [*an.params, *an.thetas]

    unreached: dict[str, float] = {}  # the strokes forces produced that no rigid pose reaches

    def rigid(dps: int, strokes: Mapping[str, object]) -> tuple[dict, dict] | None:
        """Rigid hinge angles and point positions at `dps` digits (exit 3 out of range), the
        actuators at `strokes` (docs/levels.md, "Actuators"); None beyond the rigid reach of a
        force actuator's stroke (docs/physics.md, "Beyond the rigid reach")."""
        surrogates = {}
        if mech.actuators:
            try:
                found = stroke_angles(
                    ev,
                    config,
                    [sp.N(sp.sympify(strokes[a.name]), dps + 5) for a in mech.actuators],
                    dps,
                    compliant=False,
                )
            except ReachError:
                if not any(a.drive == "force" for a in mech.actuators):
                    raise
                unreached.update(
                    {a.name: float(sp.N(sp.sympify(strokes[a.name]), 20)) for a in mech.actuators}
                )
                return None
            unreached.clear()
            surrogates = {labels[n]: v for n, v in found.items()}
        with mpmath.workdps(dps):
            pvals = [mpmath.mpf(sp.N(exact_params[s], dps + 5)) for s in an.params]
            ivals = {a: mpmath.mpf(sp.N(v, dps + 5)) for a, v in given.items()}
            ivals |= {a: mpmath.mpf(v) for a, v in surrogates.items()}
            theta, _ = ev.rigid_angles(pvals, ivals)
            at = [*pvals, *(theta[a] for a in sorted(theta))]
            return (
                {names[a]: v for a, v in theta.items()},
                {
                    p.name: ev.fn(f"rigid(theta):{p.name}", list(an.point_rigid(p.name)), args)(*at)
                    for p in an.points
                },
            )

    try:
        res = physical_equilibrium.solve(
            ev.mechanism,
            exact_params,
            {names[a]: v for a, v in given.items()} | acting,
            rigid,
            extra_digits,
        )
    except np.linalg.LinAlgError:
        if not an.redundant:
            raise
        # Inextensible plates cannot share a redundant loop's force along themselves: the
        # split is undetermined and the equilibrium equations singular (docs/levels.md).
        raise AssemblyError(
            f"{ev.mechanism.path}: the equilibrium level cannot solve this redundant "
            f"mechanism ({len(an.dropped)} redundant closure constraint(s)): its plates "
            "are inextensible elastica, which leave the forces the redundant loops carry "
            "along the plates undetermined (a singular system)"
        ) from None
    buckling, buckling_note = None, None
    if ev.mechanism.loads or any(a.drive == "force" for a in mech.actuators):
        # a side output: when the search cannot finish, the equilibrium is reported all the same,
        # the factor null with the reason (docs/physics.md, "Overloads and buckling": a side
        # output fails alone);
        # bounded by its steps alone, not by the clock, so the same command gives the same bytes
        try:
            buckling = physical_equilibrium.buckling_factor(
                ev.mechanism,
                exact_params,
                {names[a]: v for a, v in given.items()} | acting,
                seconds=math.inf,
            )
        except AssemblyError as exc:
            buckling_note = str(exc).removeprefix(f"{mech.path}: ")
    order = [names[a] for a in sorted(names)]
    with mpmath.workdps(20):
        # The links' rotations: the rigid one from the rigid angles, the deviation from the
        # solution's angle deviations (docs/physics.md).
        values = [
            *(mpmath.mpf(sp.N(exact_params[s], 25)) for s in an.params),
            *(mpmath.mpf(res.angles_rigid[names[a]]) for a in sorted(names)),
            *(mpmath.mpf(res.angle_deviations[names[a]]) for a in ev.kin.unknowns),
        ]
        if unreached:
            # no reference: the links' compliant rotations as the rigid ones of the compliant
            # angles (no deviation)
            values = [
                *(mpmath.mpf(sp.N(exact_params[s], 25)) for s in an.params),
                *(mpmath.mpf(res.angles_compliant[names[a]]) for a in sorted(names)),
                *(mpmath.mpf(0) for _ in ev.kin.unknowns),
            ]
        links = ev.links(an, "exact", "equilibrium:", [*args, *an.deltas], values)
        if mech.actuators and not unreached:
            links = ev.turned_surrogates(links, res.angle_deviations)
        if unreached:
            links = {n: LinkResult(math.nan, r.rigid, math.nan) for n, r in links.items()}
    result = Evaluation(
        level="equilibrium",
        backend="sympy",
        inputs={names[a]: float(sp.N(given[a], 20)) for a in sorted(given)}
        | {n: float(sp.N(v, 20)) for n, v in acting.items()},
        angles_rigid={n: res.angles_rigid[n] for n in order},
        angles_compliant={n: res.angles_compliant[n] for n in order},
        points={
            n: PointResult(*res.points[n])
            for n in res.points
            if n not in {a.point for a in mech.actuators}
        },
        # the rigid linkage's dyads: with actuators, at its surrogates' angles
        dyads=()
        if unreached
        else ev.dyad_states(
            config.with_angles({n: res.angles_rigid[n] for n in mech.inputs})
            if mech.actuators
            else config
        ),
        params=parameter_floats(ev.mechanism, exact_params),
        overrides=config.overrides,
        hinges={n: res.hinges[n] for n in order},
        energy=res.energy,
        error_estimate=res.error_estimate,
        links=links,
        actuation=res.inputs,
        actuators=res.actuators,
        stiffness={
            n: k for n, k in res.stiffness.items() if n not in {a.point for a in mech.actuators}
        },
        compliance={
            n: c for n, c in res.compliance.items() if n not in {a.point for a in mech.actuators}
        },
        plates={h.name: res.plates[h.name] for h in mech.hinges if h.name in res.plates},
        buckling=None if buckling is None else buckling.factor,
        buckling_hinge=None if buckling is None else buckling.hinge,
        buckling_note=buckling_note,
        units=ev.mechanism.units,
    )
    if unreached:
        produced = {a.name: unreached[a.name] for a in mech.actuators if a.drive == "force"}
        return dataclasses.replace(result, error_estimate=None).beyond_reach(reach_note(produced))
    return with_model_error(result, ev.mechanism, exact_params)


#: The reduced-equilibrium solvers already derived, by analysis (and by its content,
#: plan_cache.in_memory), then by (parameters, backend, segments).
_REDUCED: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def _float_modules() -> list:
    """lambdify's modules for float64 code with symkin's kernels (taken after a derivation)."""
    return [float64_namespace(), "math"]


def reduced_equilibrium(
    analysis: Analysis,
    inputs: Mapping[str, object],
    params: Mapping[str, object] | None = None,
    backend: str = "numpy",
    segments: int | None = None,
) -> reduced.Answer:
    """The reduced equilibrium (symkin.physics.reduced, the `loaded` level's solver) at one
    configuration: `backend` "numpy" (the numpy backend's float64 kernels) or
    "sympy" (mpmath); `segments` 1 or 2 half plates per plate, by default 1 and 2 where the
    truncation estimate refuses one. The derivation is kept per analysis, parameter values,
    backend and segments."""
    if backend not in ("numpy", "sympy"):
        raise InputError(f"unknown backend '{backend}'", hint="backends: numpy, sympy")
    return solve_reduced(analysis, configure(analysis, inputs, "loaded", params), backend, segments)


def solve_reduced(
    analysis: Analysis, config: Configuration, backend: str, segments: int | None = None
) -> reduced.Answer:
    """:func:`reduced_equilibrium` at a configuration parsed once
    (symkin.studies.configuration)."""
    mech = analysis.mechanism
    exact_params = config.params
    solvers = _REDUCED.get(analysis)
    if solvers is None:
        # an analysis of the same file (mechanism, points, hinge models) shares them
        solvers = _REDUCED[analysis] = plan_cache.in_memory(
            analysis, {"for": "reduced_equilibrium"}, dict, dict
        )

    def solver(count: int) -> reduced.Reduced:
        values = tuple(sorted((str(k), str(v)) for k, v in exact_params.items()))
        key = (values, backend, count)
        if key not in solvers:
            modules = _float_modules if backend == "numpy" else None
            other = solvers.get((values, "sympy" if backend == "numpy" else "numpy", count))
            if other is not None:  # the other backend's derivation, lambdified anew
                modules = modules or (lambda: [special.mpmath_namespace(), "mpmath"])
                solvers[key] = other.twin(backend, modules)
            else:
                solvers[key] = reduced.Reduced(analysis.kin, exact_params, modules, count)
        return solvers[key]

    ev = evaluator_of(analysis)
    hinges = config.hinges
    strokes: dict[str, object] = {}
    forces: dict[str, float] = {}
    for a in mech.actuators:
        if a.drive == "stroke":
            strokes[a.name] = config.drives[a.name]
        else:  # first against the as-fabricated pose, then at the stroke it produced
            strokes[a.name], forces[a.name] = 0, float(sp.N(config.drives[a.name], 20))

    def run(strokes: Mapping[str, object]) -> reduced.Answer:
        @functools.cache
        def rigid(scale: float) -> dict:
            scaled = config.with_angles({k: scale * float(v) for k, v in hinges.items()})
            if mech.actuators:
                found = stroke_angles(
                    ev,
                    scaled,
                    [scale * sp.N(sp.sympify(strokes[a.name]), 25) for a in mech.actuators],
                    20,
                    compliant=False,
                )
                # each angle the double its 25 digits round to, as an input given as text
                scaled = scaled.with_angles(
                    {n: float(mpmath.nstr(v, 25)) for n, v in found.items()}
                )
            angles = scaled.angles
            with mpmath.workdps(30):
                pvals = [mpmath.mpf(sp.N(exact_params[s], 35)) for s in analysis.params]
                ivals = {a: mpmath.mpf(sp.N(v, 35)) for a, v in angles.items()}
                theta, _ = ev.rigid_angles(pvals, ivals)
            # a structure's strokes: arguments beside the angles, scaled as the inputs are
            placed = {
                a.name: scale * float(sp.N(sp.sympify(strokes[a.name]), 20))
                for a in mech.actuators
                if a.drive == "stroke" and mech.is_structure
            }
            return {a: float(v) for a, v in theta.items()} | forces | placed

        answer = solver(segments or 1).solve(rigid)
        # a notch is not chained from half plates: its refusal stands
        notched = solver(1).notched if segments in (None, 1) else False
        if segments is None and answer.refused.startswith(reduced.TRUNCATION) and not notched:
            answer = solver(2).solve(rigid)
        answer.strokes = {n: float(sp.N(sp.sympify(v), 20)) for n, v in strokes.items()}
        return answer

    answer = run(strokes)
    # a force actuator: the rigid reference at the stroke the force produced (the compliant
    # mechanism's pose does not depend on the reference; one more solve expresses it against
    # the new one, whose point of action then has no deviation along d)
    for _ in range(SOLVER.strokes.reference_rounds):
        if not forces or answer.refused or mech.is_structure:  # its reference stays put
            break
        assert answer.solver is not None
        along = {
            n: v for n, v in answer.solver.along(answer.x, answer.theta).items() if n in forces
        }
        if max(abs(v) for v in along.values()) <= SOLVER.strokes.reference * answer.solver.L:
            break
        strokes = strokes | {n: answer.strokes[n] + v for n, v in along.items()}
        try:
            answer = run(strokes)
        except ReachError:
            # beyond the rigid reach (docs/physics.md, "Beyond the rigid reach"): the compliant
            # pose stands, against the last reference reached; the deviations have none
            answer.unreached = reach_note({n: float(strokes[n]) for n in along})
            break
    return answer


#: The Evaluation fields `loaded` reports beyond the deviations (docs/physics.md).
REPORTED = (
    "actuation",
    "actuators",
    "stiffness",
    "compliance",
    "plates",
    "buckling",
    "buckling_note",
)


def _reported_fields(answer: reduced.Answer, scale: float) -> dict:
    """`loaded`'s input moments and stiffness, point stiffness and compliance, plate stress and
    buckling factor as Evaluation fields (symkin.physics.reduced_reported); the buckling
    search's solves in float64 (an mpmath one is seconds per solve)."""
    assert answer.solver is not None
    search = answer.solver.twin("float64", _float_modules)
    rep = reduced_reported.report(answer, scale, search=search)
    hidden = {a.point for a in answer.solver.kin.mechanism.actuators}
    return {
        "actuation": rep.inputs,
        "actuators": rep.actuators,
        "stiffness": {n: k for n, k in rep.stiffness.items() if n not in hidden},
        "compliance": {n: c for n, c in rep.compliance.items() if n not in hidden},
        "plates": {  # in the file's order, as equilibrium's
            h.name: rep.plates[h.name]
            for h in answer.solver.kin.mechanism.hinges
            if h.name in rep.plates
        },
        "buckling": rep.buckling,
        "buckling_note": rep.buckling_note,
    }


def with_model_error(
    result: Evaluation, mechanism: Mechanism, values: Mapping[sp.Symbol, sp.Expr]
) -> Evaluation:
    """`result`, at a physical level, with its model error per point
    (symkin.physics.model_error; docs/physics.md): `values` the exact parameter values."""
    found = physical_model_error.estimate(
        mechanism,
        values,
        result.level,
        physical_model_error.level_stretches(mechanism, result.level),
        {name: link.compliant for name, link in result.links.items()},
        result.angles_compliant,
        result.hinges,
        {name: p.deviation for name, p in result.points.items()},
    )
    return dataclasses.replace(result, model_error=found.total, model_error_parts=found.parts)
