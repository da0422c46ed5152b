"""The plan of a generated evaluator: its routines and the neutral data every template reads.

    rigid        inputs, params        -> φ_M - φ_P of every hinge, dyad reach and margin
                                          (closed form; absent when a group is not a dyad)
    rigid_res    theta, params         -> rigid loop closure relative to the as-fabricated pose,
                                          Σ (Rot(φ_i) - I) V_i and Φ q, then its Jacobian A
                                          (polish / continuation: one Newton system)
    linear       theta, params         -> A (rigid loop Jacobian), r = Φ Δz at the rigid pose and
                                          S, the size of Φ Δz's terms per row (the stopping
                                          rule of symkin.core.settings, 3b)
    newton       theta, delta, params  -> F, ∂F/∂δ of the exact compliant closure
    consistency_<form>                 -> redundant loops only (symkin.core.settings, step 4):
                                          the dropped closure rows and the size of their terms,
                                          rigid (theta, params), first_order and exact (theta,
                                          delta, params)
    rigid_points theta, params         -> rigid x, y of every requested point
    dev_<level>  theta, delta, params  -> deviation x, y of every requested point (a level that
                                          shares another's runs its routine; `loaded` has none:
                                          its driver writes the deviation it solved for;
                                          every level's reads delta, so the runtimes call them
                                          alike: zero where the level solves no loop)
    sens_rigid   theta, params         -> A, ∂G/∂v (G the rigid closure), ∂R/∂θ_u, ∂R/∂v
    sens_<level> theta, delta, params  -> M, ∂E/∂θ_u, ∂E/∂v of the closure E the level solves
                                          for δ (where it does), ∂D/∂θ_u, ∂D/∂δ, ∂D/∂v of the
                                          points' deviations D (symkin.kinematics.sensitivity)
    sens_chain   params                -> ∂(default of p_j)/∂p_k, when defaults read parameters
    loaded_sens<g>, plate_eps4         -> the `loaded` level's (symkin.codegen.loaded_sens)
    loaded_report<g>                   -> what `loaded` reports beyond the deviations: input
                                          moments, point stiffness, plate stress
                                          (symkin.codegen.loaded)
    links        theta, delta          -> rotation φ of every reported link and its deviation δφ

and for the `loaded` level, the reduced equilibrium (docs/physics.md, "`loaded`: Newton on the
reduced equilibrium"; symkin.codegen.loaded), for g = 1 and 2 half plates per plate; x holds its
scaled unknowns, then the load factor t, `plates` every half plate's (along, across, omega):

    loaded_plates<g>   x, theta, params         -> every half plate's (theta_c, p, f, e_a, e_s),
                                                   then d(theta_c, p, f)/dx
    loaded_system<g>   x, theta, plates, params -> residual R, dR/dx, dR/d(plates)
    loaded_res<g>      x, theta, plates, params -> residual R alone
    loaded_dev<g>      x, theta, plates, params -> deviation x, y of every point of the file
                                                   (the plan's points first)
    plate_relation4    in = (theta, p, f, e_a, e_s) -> (along, across, omega) and their partials
                                                   by (theta, p, f) (symkin.codegen.plate)
    plate_values2      in                       -> the relation at order 2, values alone (the
                                                   truncation estimate)
    plate_rest4        in                       -> plate_relation4's outputs at p = f = 0 (a plate
                                                   that carries no force: the drivers at x = 0)

Every routine's outputs are named row-major blocks (:class:`~symkin.codegen.routines.Block`):
the runtimes (templates/c/runtime.c, templates/numpy/runtime.py) read the offsets of the
composite ones (the sensitivities, the loaded level's sizes) from the generated tables and
rely on the order above for the others (A then r, F then dF/ddelta, angles then reaches,
rotations then their deviations; rigid_res: per loop its angle, then x, y, then A).

Only what the requested points and levels need is derived: a point whose direct path holds only
input hinges needs no loop solved at any level. Parameters are renamed p_0, p_1, ... so no name
from the mechanism file can clash with generated code. A :class:`Plan` is the emitters' only
input: the C and numpy backends read its fields and routines, the LaTeX report its
:class:`~symkin.codegen.derivation.Derivation`.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import sympy as sp

from ..core import levels as level_table
from ..core.errors import InputError
from ..core.levels import Level
from ..core.settings import SOLVER, SolverSettings
from ..kinematics.analysis import Analysis
from .derivation import Derivation, derivation
from .literals import float_literals, to_double
from .loaded import (
    LoadedPlan,
    loaded_routines,
    rest_routine,
    values2_routine,
    values4_routine,
)
from .loaded_sens import eps_routine, loaded_sens_routines
from .plate import plate_routine
from .routines import Argument, Block, Routine, flatten, layout, optimize


@dataclass(frozen=True)
class Parameter:
    """A file parameter as generated code sees it."""

    name: str  # the file's name (for tables and keyword arguments)
    symbol: sp.Symbol  # p_k in the routines
    default: sp.Expr  # its default over the earlier p_k, numbers as doubles
    value: float  # the default's value, correctly rounded


@dataclass(frozen=True, eq=False)
class Plan:
    """Everything a backend template needs, backend-neutral."""

    name: str  # the mechanism's identifier-safe name
    links: tuple[str, ...]  # link names by label 0..n
    hinges: tuple[str, ...]  # hinge names by label 1..m
    inputs: tuple[str, ...]  # input hinge names, the order of the `inputs` array
    input_index: tuple[int, ...]  # position of each input in θ (label - 1)
    unknown_index: tuple[int, ...]  # position in θ of each non-input hinge (the order of δ)
    parameters: tuple[Parameter, ...]
    points: tuple[str, ...]
    reported_links: tuple[str, ...]  # links whose rotation the evaluators report
    levels: tuple[Level, ...]
    limits: tuple[tuple[int, float], ...]  # (θ index, L): the hinge's model holds for |θ| < L
    n_dyads: int
    needs_loops: bool  # some requested level/point needs the loop solution
    loops_for_links: bool  # the links' rotations need it (solved when asked for)
    closed_form: bool  # rigid solution by dyads (else Newton + continuation)
    routines: dict[str, Routine]
    notes: tuple[str, ...] = ()  # e.g. the variant a tolerance chose, for the headers
    solver: SolverSettings = SOLVER  # how the generated evaluators solve the loops
    derivation: Derivation | None = None  # what a report restates (plan(..., report=True))
    loaded: LoadedPlan | None = None  # the `loaded` level's sizes and rules, when generated
    sensitivity: bool = False  # the sens_* routines are there
    chain: bool = False  # some parameter's default reads others (sens_chain)
    pruned_inputs: tuple[str, ...] = ()  # the file's inputs that move none of the points
    # (docs/pruning.md): accepted and ignored by numpy
    fixed: tuple[tuple[int, float], ...] = ()  # (θ index, angle): inputs held constant,
    # folded into the routines (docs/cli.md, --fix)
    # per non-input hinge (δ order) with a closed-form angle: the positions in `inputs` of the
    # inputs it reads, when none of them is held at a nonzero angle: with all of them zero
    # the angle is exactly zero (the formulas round to noise there)
    rest: tuple[tuple[int, tuple[int, ...]], ...] = ()
    angular: tuple[int, ...] = ()  # positions of the angular rows among the solved ones
    dropped: int = 0  # redundant closure rows left out of the solves and checked (consistency_*)
    # the actuators (docs/levels.md, "Actuators"): the evaluator's arguments are then `drives`
    # (input hinges, then actuators), and each actuator is (name, surrogate hinge, its hidden
    # point among `points`, direction as two doubles)
    drives: tuple[str, ...] = ()
    actuators: tuple[tuple[str, str, str, tuple[float, float]], ...] = ()
    # the actuators driven by a force (at the `loaded` level alone), in file order
    forces: tuple[str, ...] = ()
    # the stroke actuators with a series `spring` (their reported stroke at `loaded` is the
    # actual one, command less force/spring; docs/physics.md), in file order
    springs: tuple[str, ...] = ()
    # the level the evaluators use when none is given (DEFAULT_LEVEL, <NAME>_DEFAULT_LEVEL):
    # the mechanism's default (core.levels.default_for) when generated, else `exact` when
    # generated, else the most faithful generated
    default_level: str = level_table.KINEMATIC_DEFAULT

    @property
    def shown_points(self) -> tuple[str, ...]:
        """The points the evaluator reports: `points` without the actuators' hidden ones."""
        hidden = {a[2] for a in self.actuators}
        return tuple(p for p in self.points if p not in hidden)

    def stage(self, level: Level) -> bool:
        """Whether the sensitivity at `level` goes through a closure solved for δ."""
        return self.needs_loops and level.needs_delta


@dataclass(frozen=True)
class SceneGroup:
    """One evaluator of a scene (docs/scene.md): the points one variant computes."""

    name: str  # its generated evaluator's name
    variant: str
    level: Level
    inputs: tuple[str, ...]  # the inputs it takes, its order
    points: tuple[str, ...]  # its points, its order
    parameters: tuple[str, ...]  # its parameters, its order
    precision: str
    cost: int  # weighted operations of one evaluation


@dataclass(frozen=True)
class ScenePlan:
    """The scene evaluator over its groups' evaluators: which inputs, points and parameters go
    where."""

    name: str
    source: str  # the mechanism file's base name
    scene: str  # the scene file's base name
    inputs: tuple[str, ...]  # the scene evaluator's inputs (label order)
    points: tuple[str, ...]  # scene order
    parameters: tuple[tuple[str, float], ...]  # the file's parameters and defaults
    fixed: tuple[tuple[str, float], ...]  # inputs the scene holds
    ignored: tuple[str, ...]  # the file's free inputs that move no scene point
    groups: tuple[SceneGroup, ...]
    notes: tuple[str, ...]
    # the actuators among the inputs and their unit ("mm", "N"): their strokes or forces
    actuators: tuple[tuple[str, str], ...] = ()


def plan(
    analysis: Analysis,
    points: Sequence[str] | None = None,
    levels: Sequence[str] | None = None,
    cse: bool = True,
    notes: Sequence[str] = (),
    report: bool = False,
    links: bool | None = None,
    sensitivity: bool = True,
    fixed: Mapping[str, sp.Expr] | None = None,
    pruned_inputs: Sequence[str] = (),
    reported: bool = True,
) -> Plan:
    """Derive the routines for the requested points and levels (by default every generated level
    the file's data allows: `loaded` needs the plates' stiffness); with `report`, also the
    statement of the derivation a LaTeX report prints. `links`: report the rotation of every
    link (default: when no points are singled out; their rotations need the loops). With
    `sensitivity`, the routines of the derivatives by the parameters and inputs at the levels
    that have them (docs/sensitivity.md). `fixed` (input name -> exact angle)
    holds those inputs constant: they leave the evaluators' arguments and their values are
    folded into the routines (an evaluator with fixed inputs has no sensitivities).
    `pruned_inputs`: the file's inputs that pruning dropped (docs/pruning.md), which the numpy
    module accepts and ignores. `reported`: at the `loaded` level, the loaded_report<g>
    routines of the input moments, point stiffness and plate stress (symkin.codegen.loaded)."""
    an, kin = analysis, analysis.kin
    mech = an.mechanism
    requested = levels
    forced = any(a.drive != "stroke" for a in mech.actuators)
    hidden = {a.point for a in mech.actuators}  # the actuators' points: always computed
    names = tuple(
        p.name for p in an.points if points is None or p.name in points or p.name in hidden
    )
    # a notch (model.notches) at `loaded`: its own relation routines (symkin.codegen.loaded);
    # a notch whose keys read parameters leaves `loaded` to the sympy backend (unless asked)
    stiff = level_table.loaded_by_default(mech)
    levels = tuple(
        lv
        for lv in level_table.LEVELS
        if lv.generated
        and (lv.name in levels if levels is not None else stiff or not lv.needs_stiffness)
        # a force actuator drives the `loaded` level alone (the kinematic levels take strokes)
        and not (forced and lv.name not in level_table.LOADED)
        # a structure has no rigid motion: the physical level alone (docs/levels.md)
        and not (mech.is_structure and lv.name not in level_table.LOADED)
    )
    if mech.is_structure:
        _structure_levels(mech, requested, levels)
    if mech.actuators and not levels and (requested is not None or forced):
        act = next((a for a in mech.actuators if a.drive != "stroke"), mech.actuators[0])
        asked = ", ".join(requested) if requested is not None else "kinematic"
        raise InputError(
            f"the generated evaluators do not take this actuator at the {asked} level(s) "
            f"(actuator '{act.name}'; a force: at the loaded level alone, which needs every "
            "plate's E, thickness and width)",
            file=mech.path,
            entry=f"[[actuator]] #{act.index + 1} '{act.name}'",
            hint="ask for a level the actuator drives (a stroke: paper, first_order, exact, "
            "loaded; a force: loaded), or use `symkin eval --backend sympy`",
        )
    held = _fixed_angles(an, fixed or {})
    sensitivity = sensitivity and not held
    free = tuple(a for a in kin.inputs if a not in held)
    inputs = Argument("inputs", tuple(kin.theta[a] for a in free))
    params = Argument("params", an.params)
    theta = Argument("theta", an.thetas)
    delta = Argument("delta", an.deltas)
    moved = moved_points(an, names)
    links = points is None if links is None else links
    solves = bool(an.deltas) and any(lv.needs_delta for lv in levels)
    needs_loops = solves and bool(moved)
    loops_for_links = solves and links and not needs_loops
    routines: dict[str, Routine] = {}
    sol = an.rigid
    k, n_dyads, np2 = len(kin.unknowns), len(sol.dyads), 2 * len(names)
    if sol.closed_form and kin.unknowns:
        outs = [sol.phi[kin.hinges[a].M] - sol.phi[kin.hinges[a].P] for a in kin.unknowns]
        outs += [d.reach for d in sol.dyads] + [d.margin for d in sol.dyads]
        routines["rigid"] = Routine(
            "rigid",
            (inputs, params),
            sol.assignments,
            tuple(outs),
            "closed-form rigid solution (dyads)",
            layout(("angles", k, 1), ("reach", n_dyads, 1), ("margin", n_dyads, 1)),
        )
    if kin.unknowns:
        a_lin, r_lin = an.linear_system
        # the rigid Newton's system whole: its Jacobian A here too, so that a step reads one
        # routine, not `linear` (r and S too) beside it
        routines["rigid_res"] = Routine(
            "rigid_res",
            (theta, params),
            (),
            tuple(an.rigid_residual) + flatten(a_lin.tolist()),
            "rigid loop closure relative to the as-fabricated pose and its Jacobian A",
            layout(("residual", k, 1), ("A", k, k)),  # residual per loop: its angle, then x, y
        )
        routines["linear"] = Routine(
            "linear",
            (theta, params),
            (),
            flatten(a_lin.tolist()) + tuple(r_lin) + tuple(an.closure_scale),
            "rigid loop Jacobian A, r = Phi dz and the size S of its terms",
            layout(("A", k, k), ("r", k, 1), ("S", k, 1)),
        )
    if an.redundant:
        forms = ["rigid"] + [
            f
            for f in ("first_order", "exact")
            if (needs_loops or loops_for_links) and any(lv.name == f for lv in levels)
        ]
        for form in forms:
            residual, size = an.consistency(form)
            routines[f"consistency_{form}"] = Routine(
                f"consistency_{form}",
                (theta, params) if form == "rigid" else (theta, delta, params),
                (),
                tuple(residual) + tuple(size),
                f"redundant loops, {form}: the dropped closure rows and the size of their terms",
                layout(("residual", len(residual), 1), ("size", len(size), 1)),
            )
    if (needs_loops or loops_for_links) and any(lv.name == "exact" for lv in levels):
        routines["newton"] = Routine(
            "newton",
            (theta, delta, params),
            (),
            tuple(an.residual) + flatten(an.jacobian.tolist()),
            "exact compliant closure F(delta) and dF/ddelta",
            layout(("F", k, 1), ("J", k, k)),
        )
    routines["rigid_points"] = Routine(
        "rigid_points",
        (theta, params),
        (),
        tuple(e for n in names for e in an.point_rigid(n)),
        "rigid positions of the points",
        layout(("points", np2, 1)),
    )
    if mech.actuators:
        # where each stroke is measured from: its point of action as fabricated, from the
        # parameters alone (a fixed input folded into the routines moves the pose at zero
        # inputs; docs/levels.md, "Actuators")
        routines["action_at"] = Routine(
            "action_at",
            (params,),
            (),
            tuple(sp.sympify(c) for a in mech.actuators for c in a.at),
            "the actuators' points of action as fabricated",
            layout(("at", 2 * len(mech.actuators), 1)),
        )
    loaded, notch_relations = None, {}
    if any(lv.name in level_table.LOADED for lv in levels):
        # the reduced equilibrium (docs/physics.md, "`loaded`: Newton on the reduced equilibrium"),
        # one and two half plates per plate; the runtime's driver writes the points' deviation
        # itself (with actuators the runtimes' own drivers: templates/*/reduced_actuators.*,
        # actuators.c)
        found, loaded = loaded_routines(an, names, theta, params, reported)
        # a notch's relations are the plate relation's kind: numbers only, optimised there
        notch_relations = {k: found.pop(k) for k in [k for k in found if k.startswith("notch_")]}
        routines.update(found)
    for lv in levels:
        if f"dev_{lv.routine}" in routines or lv.name in level_table.LOADED:
            continue  # a level that shares another's deviation, or the runtime's (loaded)
        args = (theta, delta, params)
        exprs = tuple(e for n in names for e in an.point_deviation(n, lv.name))
        users = ", ".join(o.name for o in levels if o.routine == lv.routine)
        routines[f"dev_{lv.routine}"] = Routine(
            f"dev_{lv.routine}",
            args,
            (),
            exprs,
            f"deviation of the points at level {users}",
            layout(("deviation", np2, 1)),
        )
    s = an.structure
    reported = tuple(range(s.n + 1)) if links else ()
    if reported:
        routines["links"] = Routine(
            "links",
            (theta, delta),
            (),
            tuple(an.link_rotation(i) for i in reported) + tuple(an.delta_phi(i) for i in reported),
            "rotation of every link and how much further the compliant one turns",
            layout(("rotation", len(reported), 1), ("deviation", len(reported), 1)),
        )
    chain = False
    if sensitivity:
        chain = _sensitivity_routines(
            an, names, levels, needs_loops, routines, (theta, params), (theta, delta, params)
        )
    if held:
        # rigid_res and linear read θ as the rigid solve sets it (continuation scales the fixed
        # inputs from the as-fabricated pose like the others); every other routine folds them
        values = {kin.theta[a]: v for a, v in held.items()}
        routines = {
            k: r
            if k in ("rigid_res", "linear") or k.startswith("loaded_")
            else _substituted(r, values)
            for k, r in routines.items()
        }
    # Numbers reach the printers as correctly rounded doubles (exact rationals stay in mpmath).
    memo: dict = {}
    routines = {
        name: dataclasses.replace(
            r,
            assignments=tuple((s, float_literals(e, memo)) for s, e in r.assignments),
            outputs=tuple(float_literals(e, memo) for e in r.outputs),
        )
        for name, r in routines.items()
    }
    if cse:
        routines = {name: optimize(r) for name, r in routines.items()}
    rename = {s: sp.Symbol(f"p_{k}", real=True) for k, s in enumerate(an.params)}
    routines = {name: _renamed(r, rename) for name, r in routines.items()}
    if loaded is not None:
        extra = (eps_routine(),) if "loaded_sens1" in routines else ()
        relations = (plate_routine(4), values4_routine(), values2_routine(), rest_routine())
        for relation in (*relations, *extra, *notch_relations.values()):
            # its array argument renamed: `in` is a Python keyword
            routines[relation.name] = dataclasses.replace(
                relation, arguments=(Argument("plate", relation.arguments[0].symbols),)
            )
    parameters = tuple(
        Parameter(
            p.name, rename[p.symbol], float_literals(p.expr.xreplace(rename)), to_double(p.value)
        )
        for p in mech.parameters
    )
    limits = tuple(
        (a - 1, float(sp.N(h.limit, 20)))
        for a, h in sorted(kin.hinges.items())
        if h.limit is not None
    )
    result = Plan(
        name=mech.name,
        links=s.links,
        hinges=s.hinges,
        inputs=tuple(kin.hinges[a].name for a in free),
        input_index=tuple(a - 1 for a in free),
        unknown_index=tuple(a - 1 for a in kin.unknowns),
        parameters=parameters,
        points=names,
        reported_links=tuple(s.links[i] for i in reported),
        levels=levels,
        limits=limits,
        n_dyads=len(sol.dyads),
        needs_loops=needs_loops,
        loops_for_links=loops_for_links,
        closed_form=sol.closed_form,
        routines=routines,
        loaded=loaded,
        notes=tuple(notes)
        + (
            (
                "Fixed inputs, folded into the evaluator (not its arguments): "
                + ", ".join(
                    f"{kin.hinges[a].name} = {sp.sstr(v)} rad" for a, v in sorted(held.items())
                )
                + ".",
            )
            if held
            else ()
        ),
        sensitivity=sensitivity,
        chain=chain,
        pruned_inputs=tuple(pruned_inputs),
        fixed=tuple((a - 1, to_double(v)) for a, v in sorted(held.items())),
        rest=_rest(an, free, held),
        angular=an.angular_rows,
        dropped=len(an.dropped),
        default_level=_default_level(mech, levels),
        # the public inputs: the input hinges not held (a held one is folded), the actuators
        drives=tuple(n for n in mech.drives if n not in {kin.hinges[a].name for a in held})
        if mech.actuators
        else (),
        actuators=_actuators(mech, levels),
        forces=tuple(a.name for a in mech.actuators if a.drive != "stroke"),
        springs=tuple(a.name for a in mech.actuators if a.spring is not None),
    )
    return with_derivation(result, an) if report else result


def _default_level(mech, levels: Sequence[Level]) -> str:
    """The evaluators' default level: the mechanism's (core.levels.default_for) when generated,
    else `exact` when generated, else the most faithful generated (docs/generated-code.md)."""
    names = [lv.name for lv in levels]
    wanted = (level_table.default_for(mech).name, level_table.KINEMATIC_DEFAULT)
    return next((n for n in wanted if n in names), names[-1] if names else wanted[1])


def _actuators(mech, levels) -> tuple[tuple[str, str, str, tuple[float, float]], ...]:
    """The plan's actuator rows; the generated code takes a direction that is a number, and a
    force at the `loaded` level alone (bad input otherwise, naming the actuator)."""
    out = []
    loaded_only = all(lv.name in level_table.LOADED for lv in levels)
    for a in mech.actuators:
        if (a.drive != "stroke" and not loaded_only) or any(
            sp.sympify(c).free_symbols for c in a.direction
        ):
            what = "a force" if a.drive != "stroke" else "a direction over the parameters"
            raise InputError(
                f"the generated code takes stroke actuators along a fixed direction, not "
                f"{what} (actuator '{a.name}'; a force at the loaded level alone)",
                file=mech.path,
                entry=f"[[actuator]] #{a.index + 1} '{a.name}'",
                hint="evaluate it with symkin eval --backend sympy",
            )
        out.append((a.name, a.surrogate, a.point, tuple(to_double(c) for c in a.direction)))
    return tuple(out)


def _sensitivity_routines(
    an: Analysis,
    points: Sequence[str],
    levels: Sequence[Level],
    needs_loops: bool,
    routines: dict[str, Routine],
    args: tuple[Argument, ...],
    args_delta: tuple[Argument, ...],
) -> bool:
    """Add the sens_* routines (row-major matrices, in the order of the module docstring);
    True when the parameter chain routine is needed."""
    from ..kinematics.sensitivity import Sensitivities, parameter_chain

    terms = Sensitivities(an, points)
    rigid = terms.rigid
    blocks = [rigid.theta, rigid.variables]
    if terms.rigid_stage is not None:
        blocks = [terms.rigid_stage.jacobian, terms.rigid_stage.variables] + blocks
    names = ["dR_dtheta", "dR_dv"]
    if terms.rigid_stage is not None:
        names = ["A", "dG_dv", *names]
    outputs, shapes = _flat(names, blocks)
    routines["sens_rigid"] = Routine(
        "sens_rigid",
        args,
        (),
        outputs,
        "rigid stage: A, dG/dv; rigid points: dR/dtheta, dR/dv",
        shapes,
    )
    for lv in (lv for lv in levels if lv.sensitivity):
        if lv.name in level_table.LOADED:
            # the reduced equilibrium's pieces (symkin.codegen.loaded_sens); its driver
            # assembles them
            routines.update(loaded_sens_routines(an, points, *args))
            continue
        part = terms.partials(lv.name)
        stage = terms.stage(lv.name) if needs_loops and lv.needs_delta else None
        blocks = [part.theta] + ([part.delta] if stage is not None else []) + [part.variables]
        names = ["dD_dtheta"] + (["dD_ddelta"] if stage is not None else []) + ["dD_dv"]
        if stage is not None:
            blocks = [stage.jacobian, stage.theta, stage.variables] + blocks
            names = ["M", "dE_dtheta", "dE_dv", *names]
        outputs, shapes = _flat(names, blocks)
        routines[f"sens_{lv.name}"] = Routine(
            f"sens_{lv.name}",
            args_delta,
            (),
            outputs,
            f"sensitivity at level {lv.name}: "
            + ("M, dE/dtheta, dE/dv; " if stage else "")
            + "dD/dtheta, "
            + ("dD/ddelta, " if stage else "")
            + "dD/dv",
            shapes,
        )
    chain = parameter_chain([p.expr for p in an.mechanism.parameters], an.params)
    if not chain.is_zero_matrix:
        outputs, shapes = _flat(["chain"], [chain])
        routines["sens_chain"] = Routine(
            "sens_chain", args[1:], (), outputs, "d(default of p_j)/dp_k of the parameters", shapes
        )
        return True
    return False


def _flat(
    names: Sequence[str], blocks: Sequence[sp.Matrix]
) -> tuple[tuple[sp.Expr, ...], tuple[Block, ...]]:
    """The matrices' entries one after the other, row-major, and their named blocks."""
    outputs = tuple(e for b in blocks for e in flatten(b.tolist()))
    return outputs, layout(*((n, *b.shape) for n, b in zip(names, blocks, strict=True)))


def with_derivation(plan: Plan, analysis: Analysis) -> Plan:
    """`plan` with the statement of its derivation, for a report (the plan's points; the
    `loaded` level's reduced equilibrium when the plan holds it on uniform plates: the report
    states the uniform plate's relation, not a notch's)."""
    loaded = plan.loaded is not None and not plan.loaded.notches
    return dataclasses.replace(
        plan,
        derivation=derivation(analysis, plan.points, moved_points(analysis, plan.points), loaded),
    )


def moved_points(analysis: Analysis, points: Sequence[str]) -> frozenset[str]:
    """The points the loops move: those whose direct path holds a hinge that is not an input
    (the others need no loop solved at any level)."""
    an = analysis
    return frozenset(
        n
        for n in points
        if any(
            b in an.kin.unknowns
            for b in an.structure.tree_path(an.link[an.mechanism.point(n).link])
        )
    )


def _rest(
    an: Analysis, free: Sequence[int], held: Mapping[int, sp.Expr]
) -> tuple[tuple[int, tuple[int, ...]], ...]:
    """Plan.rest: for each non-input hinge of a closed-form rigid solution, the positions among
    the free inputs of the inputs its angle reads, unless it reads an input held off zero."""
    depends = an.rigid.depends
    if depends is None:
        return ()
    out = []
    for j, a in enumerate(an.kin.unknowns):
        if any(b in held and held[b] != 0 for b in depends[a]):
            continue
        out.append((j, tuple(free.index(b) for b in sorted(depends[a]) if b in free)))
    return tuple(out)


def _structure_levels(mech, requested: Sequence[str] | None, levels: tuple) -> None:
    """A structure's evaluators hold `loaded` alone and take no inputs (docs/levels.md,
    "Structures"): a kinematic level asked for (none left) is refused as `symkin eval` refuses
    it, and so is a structure with actuators (their forces and strokes are not yet arguments of
    the generated evaluators)."""
    if not levels:
        asked = [lv for lv in requested or () if lv not in level_table.LOADED]
        mech.refuse_structure(level=asked[0] if asked else level_table.DEFAULT)
    if not mech.actuators:
        return
    act = mech.actuators[0]
    entry = f"[[actuator]] #{act.index + 1} '{act.name}'"
    if act.drive == "force":
        raise InputError(
            "the generated evaluators do not take a structure's force actuators yet (actuator "
            f"'{act.name}': its force would be their input; a structure's evaluators take none)",
            file=mech.path,
            entry=entry,
            hint="load the structure by a [[load]] whose force is a parameter (--param, "
            "tolerance --vary and sweep --vary then set it), or evaluate it with symkin eval "
            '--level loaded --backend sympy (docs/levels.md, "Structures")',
        )
    raise InputError(
        "the generated evaluators do not take a structure's stroke actuators yet (actuator "
        f"'{act.name}': its stroke would be their input; a structure's evaluators take none)",
        file=mech.path,
        entry=entry,
        hint="evaluate it with symkin eval --level loaded (or equilibrium) --backend sympy "
        '(docs/levels.md, "Structures")',
    )


def _fixed_angles(an: Analysis, fixed: Mapping[str, sp.Expr]) -> dict[int, sp.Expr]:
    """Hinge label -> angle of the inputs `fixed` names; names that are not inputs, angles
    beyond a half turn and fixing every input are bad input (exit 2)."""
    kin = an.kin
    by_name = {kin.hinges[a].name: a for a in kin.inputs}
    held = {}
    for name, value in fixed.items():
        if name not in by_name:
            raise InputError(
                f"'{name}' is not an input hinge",
                file=an.mechanism.path,
                entry="--fix",
                hint="inputs: " + ", ".join(by_name),
            )
        number = sp.N(value, 30)
        if not (number.is_real and abs(number) <= sp.pi):
            raise InputError(
                f"the fixed angle {name} = {sp.sstr(value)[:40]} is not within [-pi, pi]",
                file=an.mechanism.path,
                entry="--fix",
                hint="give the input's rotation from the as-fabricated pose, rad",
            )
        held[by_name[name]] = sp.sympify(value)
    if held and len(held) == len(by_name):
        raise InputError(
            "every input is fixed",
            file=an.mechanism.path,
            entry="--fix",
            hint="leave at least one input free (a pose needs no evaluator)",
        )
    return held


def _substituted(routine: Routine, values: dict[sp.Symbol, sp.Expr]) -> Routine:
    """The routine with the symbols of `values` replaced by them (arguments unchanged)."""
    lines = tuple((s, e.xreplace(values)) for s, e in routine.assignments)
    outs = tuple(sp.sympify(e).xreplace(values) for e in routine.outputs)
    return dataclasses.replace(routine, assignments=lines, outputs=outs)


def _renamed(routine: Routine, names: dict[sp.Symbol, sp.Symbol]) -> Routine:
    """The routine with parameter symbols renamed (arguments, assignments and outputs)."""
    args = tuple(
        Argument(a.name, tuple(names.get(s, s) for s in a.symbols)) for a in routine.arguments
    )
    lines = tuple((s, e.xreplace(names)) for s, e in routine.assignments)
    outs = tuple(sp.sympify(e).xreplace(names) for e in routine.outputs)
    return dataclasses.replace(routine, arguments=args, assignments=lines, outputs=outs)
