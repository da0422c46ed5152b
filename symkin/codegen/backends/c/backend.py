"""C99 backend: `<name>.h` / `<name>.c`, libm only, no allocation, no globals but constants
(docs/generated-code.md)."""

from __future__ import annotations

from ...plan import Plan, ScenePlan
from ...templating import render
from ..common import Backend, scene_context
from . import kernels
from .printer import CPrinter


class CBackend(Backend):
    printer_class = CPrinter
    templates = ("c/header.h.j2", "c/source.c.j2")
    kernel_source = staticmethod(kernels.source)
    runtime = "c/runtime.c"
    routine_prefix = "sk_"

    def context(self, plan: Plan, source: str, precision: str = "float64") -> dict:
        """The common context and the runtime's sections the evaluator runs."""
        return {**super().context(plan, source, precision), "features": features(plan)}


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
