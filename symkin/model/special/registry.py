"""The registry of symkin's special functions: every function by name, with its mpmath
implementation and the helpers its float algorithm calls.

A name is what generated code calls: each backend maps it to its own spelling in its printer
(`symkin_<name>` in C, `<name>` in numpy) and keeps the float source text beside itself
(:mod:`symkin.codegen.backends.c.kernels`, :mod:`symkin.codegen.backends.numpy.kernels`).
Helpers (`carlson_rf`, `carlson_rd`, `elastica_core`) have a name and an implementation but no
sympy class.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable

import sympy as sp

#: Unit roundoff of IEEE double: float series are cut where the first dropped term is below it.
UNIT_ROUNDOFF = 2.0**-53

#: sympy classes by name (kernels are created on demand, e.g. sinr(7), and registered then).
FUNCTIONS: dict[str, type] = {}
#: mpmath implementations at the current mpmath precision, helpers included (for lambdify).
MPMATH: dict[str, Callable] = {}
#: Helpers each function's float algorithm calls (C and numpy define them first).
DEPENDS: dict[str, tuple[str, ...]] = {}


class DomainError(ValueError):
    """An argument outside a function's domain (e.g. an elastica tip angle |θ| >= π/2).

    A ValueError, so callers that validate user input can turn it into an InputError."""


def register(
    name: str, cls: type | None, mpmath_impl: Callable | None, depends: tuple[str, ...] = ()
) -> None:
    """Record a function (or, with `cls` None, a helper) under `name`."""
    if cls is not None:
        FUNCTIONS[name] = cls
    if mpmath_impl is not None:
        MPMATH[name] = mpmath_impl
    DEPENDS[name] = depends


def names() -> list[str]:
    """Every registered name, helpers included (sorted)."""
    return sorted(DEPENDS)


def is_special(expr: sp.Basic) -> bool:
    """Whether `expr` is an application of one of symkin's special functions."""
    return FUNCTIONS.get(type(expr).__name__) is type(expr)


def used_names(*exprs: sp.Expr) -> list[str]:
    """Names of the special functions appearing in `exprs` (sorted)."""
    found = set()
    for e in exprs:
        for f in sp.sympify(e).atoms(sp.Function):
            if is_special(f):
                found.add(type(f).__name__)
    return sorted(found)


def with_dependencies(wanted: Iterable[str]) -> list[str]:
    """`wanted` and the helpers they call, every helper before its callers (deterministic)."""
    order: list[str] = []

    def visit(n: str) -> None:
        if n in order:
            return
        for d in DEPENDS.get(n, ()):
            visit(d)
        order.append(n)

    for n in sorted(set(wanted)):
        visit(n)
    return order


def mpmath_namespace() -> dict:
    """Module dict for ``sympy.lambdify(..., modules=[mpmath_namespace(), "mpmath"])``."""
    return dict(MPMATH)
