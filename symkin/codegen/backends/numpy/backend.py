"""numpy backend: a module `<name>.py` that imports only numpy and the standard library
(docs/generated-code.md)."""

from __future__ import annotations

from ...plan import Plan
from ..common import Backend
from . import kernels
from .printer import NumpyPrinter


class NumpyBackend(Backend):
    printer_class = NumpyPrinter
    printer_settings = {**Backend.printer_settings, "fully_qualified_modules": True}
    templates = ("numpy/module.py.j2",)
    kernel_source = staticmethod(kernels.source)


def emit(plan: Plan, source: str, dtype: str = "float64") -> str:
    """The numpy module's text; `dtype` float32 gives the single-precision variant."""
    (module,) = NumpyBackend().render(plan, source, dtype)
    return module
