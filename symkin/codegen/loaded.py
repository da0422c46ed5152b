"""The `loaded` level's routines: the reduced equilibrium of symkin.physics.reduced
(docs/physics.md, "`loaded`: Newton on the reduced equilibrium") with the file's parameters kept as
symbols, for one and for two half plates per plate (the generated runtimes' drivers:
templates/numpy/reduced.py, templates/c/reduced.c).

    loaded_plates<g>  x, theta, params          -> per half plate (theta_c, p, f, e_a, e_s), the
                                                   plate relation's `in`; then d(theta_c, p, f)/dx
    loaded_system<g>  x, theta, plates, params  -> residual R, dR/dx at fixed plate outputs,
                                                   dR/d(plate outputs)
    loaded_res<g>     x, theta, plates, params  -> residual R alone (the drivers' chord steps and
                                                   the truncation estimate read no Jacobian)
    loaded_dev<g>     x, theta, plates, params  -> deviation x, y of every point of the file (the
                                                   plan's first: the truncation estimate reads all)

x holds the scaled unknowns then the load factor t; `plates` the plate relation's values
(along, across, omega) of every half plate; g = 1 or 2 half plates per plate.

    loaded_report<g>  x, theta, plates, params  -> what `loaded` reports beyond the deviations
                                                   (symkin.physics.reduced_reported): with v the
                                                   inputs' compliant angles beyond the rigid, each
                                                   actuator's value beyond the given (a stroke, a
                                                   force) and a virtual load (F_x, F_y, M) at every
                                                   shown point of the plan, y every input's moment,
                                                   every actuator's force (stroke) or stroke
                                                   (force) and every shown point's (dx, dy, dphi):
                                                   dR/dv, din/dv, y, dy/dx, dy/dv,
                                                   dy/d(plates) at v = 0; then per plate (k0, lx,
                                                   ly, e_a, e_s, t/l, E', allowable stress or 0),
                                                   its end loads in P's plate frame (the stress's)

    plate_values2     in = (theta, p, f, e_a, e_s)  -> plate_relation2's values (along, across,
                                                   omega) alone: the truncation estimate reads
                                                   no partials
    plate_values4     in = (theta, p, f, e_a, e_s)  -> plate_relation4's values alone, the same
                                                   arithmetic (a chord step's)
    plate_rest4       in = (theta, p, f, e_a, e_s)  -> plate_relation4's outputs where p = f = 0
                                                   (a plate that carries no force: x = 0 in a
                                                   file without loads, the unloaded state)

A notch (docs/physics.md, "Notch hinges at `loaded`") is one plate, never two halves (g = 1
alone), with its own relation (physics.plate_relation.notch_relation), its section's terms
folded in as numbers (the notch's keys must be numbers: :func:`fixed_notches`):

    notch_relation4_<k>, notch_values4_<k>, notch_values2_<k>  in -> plate_relation4's,
                                                   plate_values4's and plate_values2's outputs
                                                   of half plate k's notch

and its stress from the shot of its section (physics.section_beams) under the same end loads,
times its K_t, from the tables of :class:`NotchPlate`.
"""

from __future__ import annotations

import copy
from collections.abc import Sequence
from dataclasses import dataclass, replace
from functools import cache

import sympy as sp

from ..core import vectors as V
from ..core.errors import InputError
from ..core.levels import NOTCH_BACKENDS, first_notch, parametric_notch
from ..kinematics.analysis import Analysis
from ..model.derivatives import jacobian
from ..model.notches import Notch
from ..model.sections import RelationTerms
from ..physics import reduced, section_beams
from ..physics.modes import massive_links, with_centre_points
from ..physics.plate_relation import notch_relation, relation
from ..physics.stiffness import plate_stiffness
from .literals import float_literals
from .modes import ModesPlan, modes_data, modes_routine
from .plate import SYMBOLS, _identities, plate_routine, shared_h, squares
from .routines import Argument, Routine, flatten, layout, optimize


@dataclass(frozen=True)
class Segments:
    """The sizes of one variant (g half plates per plate) of the reduced equilibrium."""

    count: int  # g: half plates per plate
    size: int  # N: scaled unknowns (the δ of the non-input hinges, chord loads, joints' η)
    plates: int  # half plates (each a plate relation call)
    scale: tuple[float, ...]  # each unknown's scale (x = unknown / scale)


@dataclass(frozen=True)
class LoadedPlan:
    """How the generated `loaded` level runs the reduced equilibrium: per variant its sizes (its
    rules: the plan's solver settings, symkin.core.settings.LoadedSettings); the routines are
    the plan's loaded_*<g>, plate_relation4, plate_values2 and plate_rest4."""

    variants: tuple[Segments, ...]  # one, then two half plates per plate
    unknowns: int  # non-input hinges (then surrogates): the first unknowns, δ / (l_min / L)
    points: int  # points of the file the deviation routine gives (the plan's first)
    # the load factor t enters the routines (the file has loads); without, det J's sign at the
    # unloaded state is the first Newton step's (x = 0, the same matrix)
    loads: bool = True
    # what the loaded_report<g> routines report (None: not derived, symkin.codegen.loaded)
    report: Reported | None = None
    # the actuators' surrogate hinges (their position in theta): unknowns after the non-input
    # hinges' (docs/physics.md, "Actuators at loaded"); the force actuators' forces follow the
    # rigid angles in the routines' theta argument
    surrogate_index: tuple[int, ...] = ()
    forces: int = 0
    # the natural frequencies' tables (symkin.codegen.modes; None: no link has a mass)
    modes: ModesPlan | None = None
    # per half plate of the one variant a file with notches has: its notch (None: a uniform
    # plate, plate_relation4's); empty without notches
    notches: tuple[NotchPlate | None, ...] = ()
    # the mechanism's size max(L, l_min) at the file's defaults: the truncation estimate's floor
    # is est_size times it (symkin.physics.reduced_solver's _red_verdict)
    length: float = 1.0


@dataclass(frozen=True)
class NotchPlate:
    """A notch's half plate in the generated `loaded` (its routines notch_*_<index>): the sway
    factor max(α, β) of its relation's poles (symkin.physics.reduced.Reduced.compression), and
    for its stress (symkin.physics.reduced_reported.plates) K_t, EI/EI₀ (the loads' units: the
    relation's EI against the shot's EI₀) and its grid's float samples (section_beams)."""

    index: int  # the half plate's place (the routines' suffix)
    hinge: str
    factor: float
    kt: float
    ratio: float
    grid: tuple[tuple[str, tuple[float, ...]], ...]  # (key, samples) of SectionGrid.floats
    length: float  # the grid's span (file unit)


def notched(mechanism) -> bool:
    """Whether a plate of the file is a notch (model.notches)."""
    return first_notch(mechanism) is not None


def fixed_notches(mechanism) -> None:
    """The generated `loaded` folds a notch's relation terms, EI₀, EA, κGA, K_t and stress grid
    in as numbers: a notch whose keys read the file's parameters is bad input there (exit 2,
    naming the hinge and the parameters)."""
    reads = parametric_notch(mechanism)
    if reads is None:
        return
    h, key, names = reads
    raise InputError(
        "the generated evaluators' loaded level folds a notch's section in as numbers: its "
        f"{key} reads the parameter(s) {', '.join(names)}",
        file=mechanism.path,
        line=h.line,
        entry=f"[[hinge]] '{h.name}'",
        hint="give the notch's keys as numbers, or evaluate it with symkin eval --level loaded "
        "--backend sympy (docs/levels.md)",
    )


def generated_notches(mechanism, backend: str) -> None:
    """A notch file at the generated `loaded` of `backend`: bad input (exit 2, naming the hinge)
    where the backend's takes uniform plates alone or a notch's keys read parameters
    (:func:`fixed_notches`)."""
    h = first_notch(mechanism)
    if h is None:
        return
    if backend not in NOTCH_BACKENDS:  # (core.levels)
        raise InputError(
            f"the generated {backend} evaluators' loaded level takes uniform plates: the "
            f"hinge's profile is {h.profile!r}",
            file=mechanism.path,
            line=h.line,
            entry=f"[[hinge]] '{h.name}'",
            hint="use --backend numpy (its loaded takes notches) or --backend sympy "
            "(docs/levels.md)",
        )
    fixed_notches(mechanism)


def _notch_plates(r: reduced.Reduced) -> tuple[NotchPlate | None, ...]:
    """Per half plate of `r` (one per plate: a notch is not split), its NotchPlate or None."""
    mech = r.kin.mechanism
    stiff = plate_stiffness(mech, "loaded", notches=True)
    values = r._values_subs
    out: list[NotchPlate | None] = []
    for k, (a, *_) in enumerate(r.segs):
        terms = r.terms[k]
        if terms is None:
            out.append(None)
            continue
        h = r.hinges[a]
        st = stiff[h.name]
        section = st.section
        assert isinstance(section, Notch)
        grid = section_beams.grid_of(section, values, st.stretches)
        kt = float(sp.N(section.stress_factor().xreplace(values), 20))
        ratio = float(r.plate[a]["EI"]) / float(grid.EI0)
        floats = grid.floats
        keys = ("a", "eps", "gam", "depth", "axial", "ds", "nodes")
        table = tuple((key, tuple(float(v) for v in floats[key])) for key in keys)
        factor = float(max(terms.alpha, terms.beta))
        out.append(NotchPlate(k, h.name, factor, kt, ratio, table, float(grid.length)))
    return tuple(out)


def notch_routines(index: int, terms: RelationTerms) -> tuple[Routine, ...]:
    """Half plate `index`'s notch relation at order 4 (values and partials), its values alone,
    and at order 2 (values alone), as plate_relation4, plate_values4 and plate_values2."""
    th, p, f, ea, es = SYMBOLS
    out = []
    for order, partial, name in (
        (4, True, "relation4"),
        (4, False, "values4"),
        (2, False, "values2"),
    ):
        rel = notch_relation(th, p, f, ea, es, terms, order)
        values = [rel.along, rel.across, rel.omega]
        exprs = values + ([sp.diff(v, w) for v in values for w in (th, p, f)] if partial else [])
        exprs = [e.xreplace(_identities(sp.Tuple(*exprs))) for e in exprs]
        memo: dict = {}
        outputs = tuple(float_literals(e, memo) for e in shared_h(exprs))
        blocks = [("values", 3, 1)] + ([("partials", 3, 3)] if partial else [])
        routine = Routine(
            f"notch_{name}_{index}",
            (Argument("in", SYMBOLS),),
            (),
            outputs,
            f"half plate {index}'s notch relation at order {order}: (along, across, omega)"
            + (" and their partials by (theta, p, f)" if partial else ", values alone"),
            layout(*blocks),
        )
        out.append(squares(optimize(routine)))
    return tuple(out)


@dataclass(frozen=True)
class Reported:
    """What the loaded_report<g> routines' outputs are of (symkin.physics.reduced_reported)."""

    inputs: tuple[str, ...]  # the input hinges (label order): their moments' rows
    points: tuple[str, ...]  # the shown points (the plan's order): each one's 3 rows after
    frame: tuple[bool, ...]  # per point: on the frame (no stiffness)
    plates: tuple[str, ...]  # the plates (label order): the stress block's rows
    limits: tuple[bool, ...]  # per plate: an allowable stress is given
    unit_scale: float  # metres per file length unit (the moments in N m)
    L: float  # the scales C's conditioning is judged by (reduced_reported.report)
    F: float
    # the actuators (file order), their rows between the inputs' and the points': a stroke's
    # force, a force's stroke beyond the rigid reference's; and how each is driven
    actuators: tuple[str, ...] = ()
    drives: tuple[str, ...] = ()


def loaded_routines(
    analysis: Analysis,
    names: Sequence[str],
    theta: Argument,
    params: Argument,
    reported: bool = True,
) -> tuple[dict[str, Routine], LoadedPlan]:
    """The routines of the reduced equilibrium for one and two half plates per plate (parameters
    as symbols; the scales at the file's defaults), and their sizes; with `reported`, the
    loaded_report<g> routines of what the level reports beyond the deviations."""
    an = analysis
    values = {p.symbol: p.value for p in an.mechanism.parameters}
    order = list(names) + sorted(n for n in (p.name for p in an.mechanism.points) if n not in names)
    routines: dict[str, Routine] = {}
    variants = []
    angles = theta
    # links with mass: the derivation sees their centres as hidden points (symkin.codegen.modes)
    kin, modes = an.kin, None
    if reported and massive_links(an.mechanism):
        kin = copy.copy(an.kin)
        kin.mechanism = with_centre_points(an.mechanism)[0]
    has_notches = notched(an.mechanism)
    if has_notches:
        fixed_notches(an.mechanism)
    for g in (1,) if has_notches else (1, 2):
        r = reduced.Reduced(kin, values, segments=g, symbolic=True)
        s = r._s
        # the force actuators' forces after the rigid angles (Reduced.angles)
        theta = Argument(angles.name, (*angles.symbols, *r.fa))
        rename = {r.th[a]: an.kin.theta[a] for a in r.hinges}

        def sub(e, rename=rename):
            return sp.sympify(e).xreplace(rename)

        x = Argument("x", (*r.x, r.t))
        outs = tuple(v for a, j, *_ in r.segs for v in s["out"][a, j])
        plates = Argument("plates", outs)
        ins = sp.Matrix(
            [
                v
                for a, j, _, _, ea, es in r.segs
                for v in (*s["pf"][a, j], sp.sympify(ea), sp.sympify(es))
            ]
        )
        moving = sp.Matrix([v for a, j, *_ in r.segs for v in s["pf"][a, j]])
        dins = jacobian(moving, r.x)
        n, ns = r.size, len(r.segs)
        routines[f"loaded_plates{g}"] = Routine(
            f"loaded_plates{g}",
            (x, theta, params),
            (),
            tuple(sub(e) for e in (*ins, *flatten(dins.tolist()))),
            f"loaded ({g} half plate(s) per plate): every half plate's (theta, p, f, e_a, e_s) "
            "and d(theta, p, f)/dx",
            layout(("in", ns, 5), ("din_dx", 3 * ns, n)),
        )
        rows = sp.Matrix(r._rows(s))
        jx = jacobian(rows, r.x)
        jo = jacobian(rows, outs)
        routines[f"loaded_system{g}"] = Routine(
            f"loaded_system{g}",
            (x, theta, plates, params),
            (),
            tuple(sub(e) for e in (*rows, *flatten(jx.tolist()), *flatten(jo.tolist()))),
            f"loaded ({g} half plate(s) per plate): the reduced equilibrium's residual R, dR/dx "
            "at fixed plate outputs and dR/d(plate outputs)",
            layout(("R", n, 1), ("dR_dx", n, n), ("dR_dout", n, 3 * ns)),
        )
        routines[f"loaded_res{g}"] = Routine(
            f"loaded_res{g}",
            (x, theta, plates, params),
            (),
            tuple(sub(e) for e in rows),
            f"loaded ({g} half plate(s) per plate): the reduced equilibrium's residual R alone",
            layout(("R", n, 1)),
        )
        # the actuators' hidden points of action (among `names`): on their links
        where = r.points | {
            a.point: (act[1], act[2]) for a, act in zip(an.mechanism.actuators, r.acts)
        }
        dev = [c for name in order for c in r._deviation(s, *where[name])]
        routines[f"loaded_dev{g}"] = Routine(
            f"loaded_dev{g}",
            (x, theta, plates, params),
            (),
            tuple(sub(e) for e in dev),
            f"loaded ({g} half plate(s) per plate): deviation of every point",
            layout(("deviation", 2 * len(order), 1)),
        )
        if reported:
            routines[f"loaded_report{g}"] = _report_routine(r, names, x, theta, plates, params, sub)
        if kin is not an.kin:
            shown = [p for p in names if p in r.points]
            routines[f"loaded_modes{g}"] = modes_routine(r, shown, x, theta, plates, params, sub)
            routines["modes_data"], modes = modes_data(an.mechanism, params, shown)
        variants.append(Segments(g, n, ns, tuple(float(v) for v in r.scale)))
        for k, terms in enumerate(r.terms):
            if terms is not None:
                for routine in notch_routines(k, terms):
                    routines[routine.name] = routine
    report = _reported(r, names) if reported else None
    surrogates = tuple(a - 1 for a in r.unknowns[len(an.kin.unknowns) :])
    plan = LoadedPlan(
        tuple(variants),
        len(r.unknowns),
        len(order),
        loads=bool(r.loads or r.forces),
        report=report,
        surrogate_index=surrogates,
        forces=len(r.forces),
        modes=modes,
        notches=_notch_plates(r) if has_notches else (),
        length=float(r.length),
    )
    return routines, plan


def _reported(r: reduced.Reduced, names: Sequence[str]) -> Reported:
    """The sizes and names of what loaded_report<g> gives."""
    mech = r.kin.mechanism
    names = _shown(r, names)
    hinge = {h.name: h for h in mech.hinges}
    plates = tuple(r.hinges[a].name for a in sorted(r.plate))
    L = max(r.L, r.lmin)
    F = max(
        [float(r.value(d["EI"])) / (float(r.value(d["l"])) * L) for d in r.plate.values()] or [1.0]
    )
    return Reported(
        inputs=tuple(r.hinges[a].name for a in r.inputs),
        points=tuple(names),
        frame=tuple(r.points[p][0] == 0 for p in names),
        plates=plates,
        limits=tuple(hinge[h].allowable_stress is not None for h in plates),
        unit_scale=float(mech.unit_scale),
        L=float(L),
        F=float(F),
        actuators=tuple(act[0] for act in r.acts),
        drives=tuple(act[4] for act in r.acts),
    )


def _shown(r: reduced.Reduced, names: Sequence[str]) -> list[str]:
    """The plan's points the report covers: the file's (not the actuators' points of action,
    which the plan computes beside them)."""
    return [p for p in names if p in r.points]


def _report_routine(r: reduced.Reduced, names, x, theta, plates, params, sub) -> Routine:
    """loaded_report<g>: the pieces symkin.physics.reduced.Reduced.reported assembles by the
    implicit-function theorem (its "report" function's, at the plan's points), and the plates'
    end loads in P's plate frame with what the stress formula reads (reduced_reported.plates)."""
    g = r.segments
    se = r._se
    ordered = sorted(r.points)
    names = _shown(r, names)
    # the inputs' and actuators' parameters and values first, then the points'
    first = len(r.inputs) + len(r.acts)
    virtual = r.extra[first:]
    by = list(r.extra[:first]) + [
        v for p in names for v in virtual[3 * ordered.index(p) : 3 * ordered.index(p) + 3]
    ]
    every = r._reported(se)
    ys = sp.Matrix(
        every[:first]
        + [
            v
            for p in names
            for v in every[first + 3 * ordered.index(p) : first + 3 * ordered.index(p) + 3]
        ]
    )
    rows = sp.Matrix(r._rows(se))
    moving = sp.Matrix([v for a, j, *_ in r.segs for v in se["pf"][a, j]])
    outs = list(plates.symbols)
    zero = dict.fromkeys(r.extra, sp.S.Zero)
    blocks = [
        ("dR_dv", jacobian(rows, by)),
        ("din_dv", jacobian(moving, by)),
        ("y", ys),
        ("dy_dx", jacobian(ys, r.x)),
        ("dy_dv", jacobian(ys, by)),
        ("dy_dout", jacobian(ys, outs)),
    ]
    exprs = [sub(sp.sympify(e).xreplace(zero)) for _, m in blocks for e in flatten(m.tolist())]
    # every plate's end loads at its P clamp, scaled, and its stress formula's numbers
    s = r._s
    mech = r.kin.mechanism
    stiff = plate_stiffness(mech, "loaded", notches=True)
    hinge = {h.name: h for h in mech.hinges}
    for a in sorted(r.plate):
        h = r.hinges[a]
        d = r.plate[a]
        px, py = r._position(s, h.P, tuple(r._clamp_p(a)))
        mx, my = r._position(s, h.M, r.clamp_m[a])
        turn = s["phi"][h.P] + s["dphi"][h.P]
        nx, ny = s["n"][a]
        m_p = s["mom"][a] + V.cross((mx - px, my - py), (nx, ny))
        ei, length = d["EI"], d["l"]
        lx, ly = V.rot(-(turn + d["alpha"]), (nx * length**2 / ei, ny * length**2 / ei))
        st = stiff[h.name]
        limit = hinge[h.name].allowable_stress
        exprs += [
            sub(e)
            for e in (
                m_p * length / ei,
                lx,
                ly,
                d["ea"],
                d["es"],
                sp.sqrt(st.section.slender_squared()),
                st.section.modulus(),
                sp.S.Zero if limit is None else sp.sympify(limit),
            )
        ]
    shapes = [(name, *m.shape) for name, m in blocks] + [("stress", len(r.plate), 8)]
    acts = (", the actuators' values", ", the actuators' forces or strokes") if r.acts else ("", "")
    return Routine(
        f"loaded_report{g}",
        (x, theta, plates, params),
        (),
        tuple(exprs),
        f"loaded ({g} half plate(s) per plate), what it reports: dR/dv, din/dv, y, dy/dx, dy/dv, "
        f"dy/dout (v: the inputs' angles{acts[0]} and virtual loads at the points, y: the "
        f"inputs' moments{acts[1]} and the points' (dx, dy, dphi)), then per plate (k0, lx, ly, "
        "e_a, e_s, t/l, E', allowable)",
        layout(*shapes),
    )


@cache
def rest_routine() -> Routine:
    """plate_relation4 (symkin.codegen.plate) at p = f = 0, the same 12 outputs: a few
    operations where the full relation takes hundreds, for the drivers' steps at x = 0."""
    th, p, f, ea, es = SYMBOLS
    rel = relation(th, p, f, ea, es, 4)
    values = [rel.along, rel.across, rel.omega]
    partials = [sp.diff(v, w) for v in values for w in (th, p, f)]
    memo: dict = {}
    outputs = tuple(
        float_literals(e, memo)
        for e in shared_h([sp.simplify(e.subs({p: 0, f: 0})) for e in values + partials])
    )
    routine = Routine(
        "plate_rest4",
        (Argument("in", SYMBOLS),),
        (),
        outputs,
        "one plate's relation at order 4 where it carries no force (p = f = 0): (along, across, "
        "omega) and their partials by (theta, p, f)",
        layout(("values", 3, 1), ("partials", 3, 3)),
    )
    return squares(optimize(routine))


@cache
def values2_routine() -> Routine:
    """The plate relation at order 2, its values alone (symkin.codegen.plate's plate_relation2
    without the nine partials): the truncation estimate's residual and deviation read no more."""
    th, p, f, ea, es = SYMBOLS
    rel = relation(th, p, f, ea, es, 2)
    memo: dict = {}
    outputs = tuple(float_literals(e, memo) for e in shared_h([rel.along, rel.across, rel.omega]))
    routine = Routine(
        "plate_values2",
        (Argument("in", SYMBOLS),),
        (),
        outputs,
        "one plate's relation at order 2, values alone: (along, across, omega)",
        layout(("values", 3, 1)),
    )
    return squares(optimize(routine))


@cache
def values4_routine() -> Routine:
    """plate_relation4's three values alone (symkin.codegen.plate), with the assignments they
    read: the same arithmetic, so a chord step's residual is the Newton step's."""
    full = plate_routine(4)
    needed: set = set().union(*(e.free_symbols for e in full.outputs[:3]))
    lines = []
    for s, e in reversed(full.assignments):
        if s in needed:
            lines.append((s, e))
            needed |= e.free_symbols
    return replace(
        full,
        name="plate_values4",
        assignments=tuple(reversed(lines)),
        outputs=full.outputs[:3],
        doc="one plate's relation at order 4, values alone: (along, across, omega)",
        blocks=layout(("values", 3, 1)),
    )
