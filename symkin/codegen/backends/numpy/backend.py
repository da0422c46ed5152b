"""numpy backend: a module `<name>.py` that imports only numpy and the standard library
(docs/generated-code.md)."""

from __future__ import annotations

from typing import ClassVar

from ...plan import Plan, ScenePlan
from ...templating import render
from ..common import Backend, parameter_rows, scene_context
from . import kernels
from .printer import NumpyPrinter


class NumpyBackend(Backend):
    printer_class = NumpyPrinter
    printer_settings: ClassVar[dict] = {**Backend.printer_settings, "fully_qualified_modules": True}
    templates = ("numpy/module.py.j2",)
    kernel_source = staticmethod(kernels.source)
    runtime = "numpy/runtime.py"
    routine_prefix = "_"


def emit(plan: Plan, source: str, dtype: str = "float64") -> str:
    """The numpy module's text; `dtype` float32 gives the single-precision variant."""
    (module,) = NumpyBackend().render(plan, source, dtype)
    return module


def emit_parameters(plan: Plan, dtype: str = "float64") -> str:
    """The module's parameters alone (templates/numpy/parameters.py.j2): its PARAMETERS and its
    `parameters`, from the same template text as the module's, without the routines."""
    printer = NumpyBackend().printer
    return render(
        "numpy/parameters.py.j2",
        name=plan.name,
        parameters=parameter_rows(plan, printer),
        dtype=dtype,
    )


def emit_scene(plan: ScenePlan) -> str:
    """The scene evaluator's module (docs/scene.md)."""
    return render("numpy/scene.py.j2", **scene_context(plan))
