"""C99 backend: `<name>.h` / `<name>.c`, libm only, no allocation, no globals but constants
(docs/generated-code.md)."""

from __future__ import annotations

from ...plan import Plan
from ..common import Backend
from . import kernels
from .printer import CPrinter


class CBackend(Backend):
    printer_class = CPrinter
    templates = ("c/header.h.j2", "c/source.c.j2")
    kernel_source = staticmethod(kernels.source)


def emit(plan: Plan, source: str) -> tuple[str, str]:
    """The header and source texts."""
    header, code = CBackend().render(plan, source)
    return header, code
