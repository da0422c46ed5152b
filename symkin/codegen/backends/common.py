"""What the generated-code backends share: the template context of a plan, the routines as
template data, the 'generated, do not edit' header.

A backend is a :class:`Backend` subclass that only sets attributes (its printer, its templates,
where its kernels' source comes from), PyDy style; the templates in `templates/<lang>/` do the
rest.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from typing import ClassVar

import sympy as sp
from sympy.printing.codeprinter import CodePrinter

from ...core import levels
from ...model import special
from ..plan import Plan, ScenePlan
from ..routines import Routine
from ..templating import render, runtime


class Backend:
    """Renders a plan with one language's printer and templates."""

    printer_class: ClassVar[type[CodePrinter]]
    #: sums printed in sympy's own (canonical, hash-independent) argument order: sorting the terms
    #: of every sum for print (order="lex") costs a numeric evaluation of each term, a tenth of
    #: a large mechanism's derivation, and a compiler reads them in any order
    printer_settings: ClassVar[dict] = {"order": "none"}
    templates: ClassVar[tuple[str, ...]]  # paths under templates/
    kernel_source: ClassVar[Callable[[str], str]]  # a special function's definition
    runtime: ClassVar[str]  # the runtime the generated files hold, under templates/
    routine_prefix: ClassVar[str]  # the generated name of routine r: prefix + r

    def __init__(self) -> None:
        self.printer = self.printer_class(dict(self.printer_settings))

    def render(self, plan: Plan, source: str, precision: str = "float64") -> list[str]:
        """Every template of the backend rendered for `plan` (generated from file `source`) in
        `precision` (float64 or float32)."""
        clash = {self.routine_prefix + r for r in plan.routines} & defined_names(
            runtime(self.runtime, None)
        )
        if clash:
            raise ValueError(f"routines named like the runtime's functions: {sorted(clash)}")
        context = self.context(plan, source, precision)
        return [render(template, **context) for template in self.templates]

    def counted(self, plan: Plan) -> Plan:
        """The plan whose routines' operation counts the header prints: the derived ones, whose
        counts a kept plan holds (a backend that rewrites routines to emit them says so)."""
        return plan

    def context(self, plan: Plan, source: str, precision: str = "float64") -> dict:
        """The template variables: the plan's fields, printed, and the solver's settings."""
        derived = self.counted(plan).routines.values()
        return {
            "header": header_lines(self.counted(plan), source),
            "name": plan.name,
            "NAME": plan.name.upper(),
            "inputs": list(plan.inputs),
            "fixed": [(i, repr(v)) for i, v in plan.fixed],
            "pruned_inputs": list(plan.pruned_inputs),
            "hinges": list(plan.hinges),
            "points": list(plan.points),
            "shown_points": list(plan.shown_points),
            "drives": list(plan.drives),
            "actuators": list(plan.actuators),
            "forces": list(plan.forces),
            "springs": list(plan.springs),
            "actuator_tables": actuator_tables(plan),
            "links": list(plan.reported_links),
            "levels": plan.levels,
            "all_levels": levels.LEVELS,
            "parameters": parameter_rows(plan, self.printer),
            "limits": [(i, repr(limit)) for i, limit in plan.limits],
            "n_theta": len(plan.hinges),
            "input_index": list(plan.input_index),
            "unknown_index": list(plan.unknown_index),
            "k": len(plan.unknown_index),
            "n_dyads": plan.n_dyads,
            "closed_form": plan.closed_form,
            "needs_loops": plan.needs_loops,
            "loops_for_links": plan.loops_for_links,
            # the loop solvers are emitted: some point or the links need them
            "solves": plan.needs_loops or plan.loops_for_links,
            "dtype": precision,
            "solver": plan.solver,
            "tol": plan.solver.tolerances(precision),
            "sensitivity": plan.sensitivity,
            "chain": plan.chain,
            "stages": [lv.name for lv in plan.levels if plan.stage(lv)],
            "n_params": len(plan.parameters),
            "n_vars": len(plan.parameters) + len(plan.inputs),
            "default_level": default_level(plan),
            "default_code": levels.get(default_level(plan)).code,
            "default_sensitivity_level": default_sensitivity_level(plan),
            "loaded": plan.loaded,
            # the loaded level's and the stroke solves' rules (symkin.core.settings): the C
            # evaluator's at float64's epsilon; the numpy module scales `stroke_eps` by its own
            "loaded_rules": plan.solver.loaded.rules() if plan.loaded else {},
            "stroke_rules": plan.solver.strokes.rules(),
            "loaded_levels": [lv for lv in plan.levels if lv.name in levels.LOADED],
            # the loaded level's sensitivity routines: per variant the offsets of their blocks
            "loaded_sens": [
                offsets(plan, f"loaded_sens{g}", LOADED_SENS_BLOCKS)
                for g in (1, 2)
                if f"loaded_sens{g}" in plan.routines
            ],
            # the loaded level's report routines: per variant the offsets of their blocks
            "loaded_report": [
                offsets(plan, f"loaded_report{g}", LOADED_REPORT_BLOCKS)
                for g in (1, 2)
                if f"loaded_report{g}" in plan.routines
            ],
            # a routine the backend rewrote (not the derived one) prints no count: counting
            # it would undo what a kept plan saves (codegen/plan_cache.py)
            "routines": [
                routine_data(r, self.printer, counted=any(r is d for d in derived))
                for r in plan.routines.values()
            ],
            "have": set(plan.routines),
            "blocks": {
                name: {b.name: (b.offset, b.rows, b.cols) for b in r.blocks}
                for name, r in plan.routines.items()
            },
            "level_rows": level_rows(plan),
            "limit_rows": [
                (i, plan.unknown_index.index(i) if i in plan.unknown_index else -1, repr(lim))
                for i, lim in plan.limits
            ],
            "sens_rigid": offsets(plan, "sens_rigid", ("A", "dG_dv", "dR_dtheta", "dR_dv")),
            "out_size": max(len(r.outputs) for r in plan.routines.values()) + 1,
            "rest": tuple((plan.unknown_index[j], tuple(reads)) for j, reads in plan.rest),
            "rest_table": [
                v for j, reads in plan.rest for v in (plan.unknown_index[j], len(reads), *reads)
            ],
            # the rigid closure's rows that are loops' angle sums (the winding rule)
            "angular_rows": list(plan.angular) or list(range(0, len(plan.unknown_index), 3)),
            "dropped": plan.dropped,
            "kernels": [type(self).kernel_source(n) for n in special_functions(plan)],
        }


def parameter_rows(plan: Plan, printer: CodePrinter) -> list[dict]:
    """The plan's parameters as template data: name, symbol, default (printed) and value."""
    return [
        {
            "name": p.name,
            "symbol": p.symbol.name,
            "expr": printer.doprint(p.default),
            "value": repr(p.value),
        }
        for p in plan.parameters
    ]


#: The closure each level's loop solver runs: its linear routine (A, r: the first-order delta) and
#: its Newton routine (F, dF/ddelta; None: the first-order delta is the level's).
CLOSURES = {
    "first_order": ("linear", None),
    "exact": ("linear", "newton"),
}
#: The blocks of a level's sensitivity routine (symkin.codegen.plan), in order.
SENS_BLOCKS = ("M", "dE_dtheta", "dE_dv", "dD_dtheta", "dD_ddelta", "dD_dv")
#: The blocks of the loaded level's (symkin.codegen.loaded_sens), in order.
LOADED_SENS_BLOCKS = (
    "dR_dtheta",
    "dR_dp",
    "din_dtheta",
    "din_dp",
    "dD_dx",
    "dD_dtheta",
    "dD_dp",
    "dD_dout",
)


#: The blocks of the loaded level's report routines (symkin.codegen.loaded), in order.
LOADED_REPORT_BLOCKS = ("dR_dv", "din_dv", "y", "dy_dx", "dy_dv", "dy_dout", "stress")


def level_rows(plan: Plan) -> list[dict]:
    """What the runtimes run at each generated level: its deviation routine, the routines of the
    closure it solves for delta (None where it solves none, or the loops need no solving),
    `loaded` (1: the runtime's reduced-equilibrium driver solves it and writes its deviation,
    docs/runtime.md; 0 otherwise) and its sensitivity routine with the offsets of its blocks
    (`stage`: it goes through the closure solved for delta)."""
    rows = []
    for lv in plan.levels:
        linear, newton = CLOSURES.get(lv.routine, (None, None)) if lv.needs_delta else (None, None)
        if not (plan.needs_loops or plan.loops_for_links) or not {linear, newton} - {None} <= set(
            plan.routines
        ):
            linear = newton = None
        loaded = lv.name in levels.LOADED
        sens = f"sens_{lv.name}" if lv.sensitivity and f"sens_{lv.name}" in plan.routines else None
        # `loaded`: its driver's own (templates/*/reduced_sens.*) over loaded_sens<g>
        rates = loaded and lv.sensitivity and "loaded_sens1" in plan.routines
        rows.append(
            {
                "name": lv.name,
                "code": lv.code,
                "dev": "loaded_deviation" if loaded else f"dev_{lv.routine}",
                "linear": linear,
                "newton": newton,
                "loaded": int(loaded),
                "sens": sens,
                "rates": rates,
                "stage": sens is not None and "M" in _names(plan, sens),
                "blocks": offsets(plan, sens, SENS_BLOCKS) if sens else {},
            }
        )
    return rows


def _names(plan: Plan, routine: str) -> set[str]:
    return {b.name for b in plan.routines[routine].blocks}


def offsets(plan: Plan, routine: str, names: tuple[str, ...]) -> dict[str, int]:
    """Where the blocks `names` of `routine` start, as the runtimes read them (0 for a block
    the routine lacks: the runtimes do not read it then); {} when there is no such routine."""
    if routine not in plan.routines:
        return {}
    have = {b.name: b.offset for b in plan.routines[routine].blocks}
    return {n: have.get(n, 0) for n in names}


def defined_names(text: str) -> set[str]:
    """The names a runtime's text defines at its top level: C functions and types, Python
    functions, classes and constants."""
    return set(
        re.findall(r"^(?:static|typedef)\b[^(;=\n]*?\b(\w+)\s*[(;]", text, re.M)
        + re.findall(r"^(?:def|class)\s+(\w+)", text, re.M)
        + re.findall(r"^(\w+)\s*=", text, re.M)
        + re.findall(r"^\}\s*(\w+);", text, re.M)
    )


def default_level(plan: Plan) -> str:
    """The level a generated evaluator uses when none is given (DEFAULT_LEVEL,
    <NAME>_DEFAULT_LEVEL): the plan's, the mechanism's default when generated
    (docs/generated-code.md)."""
    return plan.default_level


def default_sensitivity_level(plan: Plan) -> str:
    """The level `sensitivity` and `sensitivity_full` use when none is given: the default level
    where it has sensitivities, else `exact` where it has, else the most faithful that has."""
    having = [row["name"] for row in level_rows(plan) if row["sens"] or row["rates"]]
    wanted = (plan.default_level, levels.KINEMATIC_DEFAULT)
    return next((n for n in wanted if n in having), having[-1] if having else plan.default_level)


def routine_data(routine: Routine, printer: CodePrinter, counted: bool = True) -> dict:
    """Template data of one routine: its arguments (and whether it reads them), the entries it
    unpacks ('_' for unread ones), its assignments and outputs, printed; its operation count
    where `counted` (None otherwise)."""
    free: set[sp.Symbol] = set()
    for e in [e for _, e in routine.assignments] + list(routine.outputs):
        free |= sp.sympify(e).free_symbols
    used = [bool(set(a.symbols) & free) for a in routine.arguments]
    return {
        "name": routine.name,
        "doc": routine.doc,
        "ops": routine.ops if counted else None,
        "args": [(a.name, u) for a, u in zip(routine.arguments, used)],
        "unpack": [
            (a.name, [s.name if s in free else "_" for s in a.symbols])
            for a, u in zip(routine.arguments, used)
            if u
        ],
        "lines": [(s.name, printer.doprint(e)) for s, e in routine.assignments],
        "outputs": [printer.doprint(sp.sympify(e)) for e in routine.outputs],
    }


def special_functions(plan: Plan) -> list[str]:
    """Names of the special functions the routines call and the helpers those call, every
    helper before its callers (deterministic)."""
    exprs = [
        e for r in plan.routines.values() for e in [*(e for _, e in r.assignments), *r.outputs]
    ]
    return special.with_dependencies(special.used_names(*exprs))


def comment_safe(text: str) -> str:
    """Text that can sit in any comment or docstring: printable ASCII without quotes, backslashes
    or '*' (so it can neither close a docstring or a C comment nor splice a comment line)."""
    return "".join(ch if 32 <= ord(ch) < 127 and ch not in '"\\`*' else "?" for ch in text)


def _no_inputs(plan: Plan) -> str:
    """The header's word for an evaluator without inputs: a structure's, or every input held."""
    return "none (all held by --fix)" if plan.fixed else "none (a structure)"


def header_lines(plan: Plan, source: str) -> list[str]:
    """The 'generated, do not edit' header, the mechanism summary and the op counts."""
    n, m = len(plan.links) - 1, len(plan.hinges)
    lines = [
        f"Generated by symkin from {source} - do not edit.",
        f"Mechanism '{plan.name}': {n + 1} links, {m} hinges, {m - n} loop(s); "
        f"inputs {', '.join(plan.drives or plan.inputs) or _no_inputs(plan)}"
        + (
            " (actuators; their strokes fix the angles of "
            + ", ".join(f"{a[1]} ({a[0]})" for a in plan.actuators)
            + ")"
            if plan.actuators
            else ""
        )
        + ".",
        f"Points: {', '.join(plan.shown_points) or 'none'}; "
        f"levels: {', '.join(lv.name for lv in plan.levels)}.",
        "Rigid solution: "
        + (
            "closed form (dyads)"
            if plan.closed_form
            else "Newton with continuation (not all groups are dyads)"
        )
        + ".",
        "Operation counts after CSE: "
        + ", ".join(f"{k} {r.ops}" for k, r in plan.routines.items())
        + ".",
    ]
    lines += list(plan.notes)
    return [comment_safe(line) for line in lines]


def scene_context(plan: ScenePlan) -> dict:
    """The template variables of a scene evaluator (docs/scene.md): where each group's inputs,
    parameters and points sit in the scene's arrays."""
    inputs, points = list(plan.inputs), list(plan.points)
    params = [name for name, _ in plan.parameters]
    header = [
        f"Generated by symkin from {plan.source} and the scene {plan.scene} - do not edit.",
        f"Scene evaluator '{plan.name}': inputs {', '.join(inputs)}; points "
        f"{', '.join(points)}; over {len(plan.groups)} evaluator(s):",
    ]
    header += [
        f"  {g.name}: variant {g.variant} ({g.precision}), points {', '.join(g.points)}, "
        f"cost {g.cost}"
        for g in plan.groups
    ]
    if plan.fixed:
        header.append(
            "Fixed inputs, folded into the evaluators: "
            + ", ".join(f"{h} = {v!r} rad" for h, v in plan.fixed)
            + "."
        )
    header += list(plan.notes)
    return {
        "header": [comment_safe(line) for line in header],
        "name": plan.name,
        "NAME": plan.name.upper(),
        "inputs": inputs,
        "points": points,
        # with actuators the inputs' text names their units (a stroke, a force)
        "input_units": ", ".join(f"{n} in {u}" for n, u in plan.actuators),
        "ignored": list(plan.ignored),
        "parameters": [{"name": n, "value": repr(v)} for n, v in plan.parameters],
        "fixed": [(h, repr(v)) for h, v in plan.fixed],
        "groups": [
            {
                "name": g.name,
                "NAME": g.name.upper(),
                "variant": g.variant,
                "level": g.level.name,
                "code": g.level.code,
                "precision": g.precision,
                "inputs": list(g.inputs),
                "points": list(g.points),
                "input_at": [inputs.index(h) for h in g.inputs],
                "param_at": [params.index(p) for p in g.parameters],
                "point_at": [points.index(p) for p in g.points],
            }
            for g in plan.groups
        ],
        "variants": {p: g.variant for g in plan.groups for p in g.points},
    }


def actuator_tables(plan: Plan) -> dict | None:
    """The C tables of a mechanism's actuators (templates/c/actuators.c, sk_actuators): per
    kinematic input its public input's position or -1 - a (the surrogate of actuator a), per
    actuator its point's position among the points and its stroke's among the public inputs, its
    direction, the positions of the reported points and each one's force's place (-1: a stroke).
    None without actuators."""
    if not plan.actuators:
        return None
    drives, names = list(plan.drives), [a[0] for a in plan.actuators]
    surrogates = {a[1]: k for k, a in enumerate(plan.actuators)}
    return {
        "drive_of": [drives.index(n) if n in drives else -1 - surrogates[n] for n in plan.inputs],
        "point": [plan.points.index(a[2]) for a in plan.actuators],
        "stroke": [drives.index(n) for n in names],
        "direction": [repr(float(c)) for a in plan.actuators for c in a[3]],
        "shown": [plan.points.index(p) for p in plan.shown_points],
        # per actuator: its force's place among the forces (after theta's angles), or -1
        "force": [plan.forces.index(n) if n in plan.forces else -1 for n in names],
        # per actuator: 1 where a series spring makes its stroke at loaded the actual one
        "spring": [int(n in plan.springs) for n in names],
    }
