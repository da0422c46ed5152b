"""C99 backend: `<name>.h` / `<name>.c`, libm only, no allocation, no globals but constants
(docs/generated-code.md)."""

from __future__ import annotations

import dataclasses

from ....model import special
from ...plan import Plan, ScenePlan
from ...routines import Routine, hoist
from ...templating import render
from ..common import Backend, routine_data, scene_context
from . import kernels
from .printer import CPrinter


class CBackend(Backend):
    printer_class = CPrinter
    templates = ("c/header.h.j2", "c/source.c.j2")
    kernel_source = staticmethod(kernels.source)
    runtime = "c/runtime.c"
    routine_prefix = "sk_"

    def render(self, plan: Plan, source: str, precision: str = "float64") -> list[str]:
        """The header and source of `plan`; with force actuators without the `loaded` level's
        sensitivity routines (their theta holds the forces too), which the numpy runtime alone
        assembles with the forces' (templates/numpy/reduced_actuators_sens.py); the natural
        frequencies' routines only with the `loaded` report, whose pieces <name>_modes shares
        (docs/generated-code.md, "Natural frequencies in generated code")."""
        unused: set[str] = set()
        if plan.loaded is None or plan.loaded.modes is None or plan.loaded.report is None:
            unused |= {"loaded_modes1", "loaded_modes2", "modes_data"}  # no <name>_modes
        if plan.forces:
            unused |= {"loaded_sens1", "loaded_sens2", "plate_eps4"}
        if unused & set(plan.routines) or "newton" in plan.routines:
            routines = {}
            for k, r in plan.routines.items():
                if k == "newton":
                    # the exact closure's Newton loop: its terms of theta and the parameters
                    # alone once per solve (<name>_pre), only delta's in the loop
                    pre, loop = hoist(r, "delta")
                    routines[pre.name] = pre
                    routines[k] = loop
                elif k not in unused:
                    routines[k] = r
            # the header's operation counts are the derived routines', counted with the plan
            # (a kept plan is emitted again without counting: codegen/plan_cache.py)
            self._counted = plan
            plan = dataclasses.replace(plan, routines=routines)
        return super().render(plan, source, precision)

    def context(self, plan: Plan, source: str, precision: str = "float64") -> dict:
        """The common context and the runtime's sections the evaluator runs."""
        return {**super().context(plan, source, precision), "features": features(plan)}

    def counted(self, plan: Plan) -> Plan:
        """The plan as derived, before render's rewriting (the hoisted Newton: its counts are
        the derived routine's, kept with the plan)."""
        return getattr(self, "_counted", plan)


def features(plan: Plan) -> list[str]:
    """The optional sections of templates/c/runtime.c that `plan`'s evaluator runs
    (docs/runtime.md)."""
    loops = bool(plan.unknown_index)
    return [
        name
        for name, used in (
            ("SK_LOOPS", loops),
            ("SK_CLOSED_FORM", loops and plan.closed_form),
            ("SK_CONTINUATION", loops and not plan.closed_form),
            ("SK_LOADED", plan.loaded is not None),
            # the loaded level's implicit-function theorem at its solution: its sensitivities
            # (templates/c/reduced_sens.c) or its report (reduced_report.c)
            (
                "SK_LOADED_IFT",
                plan.loaded is not None
                and ("loaded_sens1" in plan.routines or "loaded_report1" in plan.routines),
            ),
            # actuators at loaded: the unknowns' own theta indices (templates/c/reduced.c)
            ("SK_ACT_LOADED", plan.loaded is not None and bool(plan.actuators)),
            # force actuators at loaded: their forces after the rigid angles in theta
            ("SK_ACT_FORCES", plan.loaded is not None and bool(plan.forces)),
            # stroke actuators at loaded with the level's sensitivities
            # (templates/c/actuators.c's sk_actuated_loaded_rates)
            (
                "SK_ACT_SENS",
                plan.loaded is not None
                and bool(plan.actuators)
                and "loaded_sens1" in plan.routines,
            ),
            # actuators at loaded with the level's report: the actuators' rows
            # (templates/c/actuators.c's sk_actuated_report)
            (
                "SK_ACT_REPORT",
                plan.loaded is not None
                and bool(plan.actuators)
                and "loaded_report1" in plan.routines,
            ),
            # stroke actuators with a series spring and the loaded report: the actual stroke
            (
                "SK_ACT_SPRINGS",
                plan.loaded is not None
                and bool(plan.springs)
                and "loaded_report1" in plan.routines,
            ),
            ("SK_LINKS", bool(plan.reported_links)),
            ("SK_SENSITIVITY", plan.sensitivity),
        )
        if used
    ]


def emit(plan: Plan, source: str) -> tuple[str, str]:
    """The header and source texts."""
    header, code = CBackend().render(plan, source)
    return header, code


def emit_scene(plan: ScenePlan) -> tuple[str, str]:
    """The scene evaluator's header and source (docs/scene.md)."""
    context = scene_context(plan)
    return render("c/scene.h.j2", **context), render("c/scene.c.j2", **context)


def standalone(routine: Routine) -> str:
    """One routine as a self-contained C99 function ``static void sk_<name>(const double *in,
    ..., double *out)`` preceded by the special functions it calls (for the runtime's own
    kernels, e.g. the plate relation of the Newton level)."""
    printer = CPrinter()
    data = routine_data(routine, printer)
    exprs = [e for _, e in routine.assignments] + list(routine.outputs)
    support = kernels.support(special.used_names(*exprs))
    args = "".join(f"const double *{a}, " for a, _ in data["args"])
    lines = [f"/* {data['doc']} ({data['ops']} operations) */"]
    lines.append(f"static void sk_{data['name']}({args}double *out)\n{{")
    lines += [f"    (void){a};" for a, used in data["args"] if not used]
    for arg, names in data["unpack"]:
        lines += [f"    const double {s} = {arg}[{k}];" for k, s in enumerate(names) if s != "_"]
    lines += [f"    const double {s} = {e};" for s, e in data["lines"]]
    lines += [f"    out[{k}] = {o};" for k, o in enumerate(data["outputs"])]
    return support + "\n" + "\n".join(lines) + "\n}\n"
