"""sympy.lambdify for large expressions: CSE and printing take the terms in the order sympy
stores them (deterministic, sympy's canonical argument order) instead of sorting every sum
again, which is most of lambdify's time on a mechanism's equilibrium."""

from __future__ import annotations

import inspect
from collections.abc import Callable, Mapping, Sequence

import sympy as sp
from sympy.printing.pycode import MpmathPrinter, PythonCodePrinter

from .precedence import FastPrecedence


def printer_settings(user_functions: Mapping[str, str]) -> dict:
    """The settings lambdify gives its printer (sympy.utilities.lambdify), with the terms of
    every sum printed as sympy stores them: sorting them again is most of the printing's cost
    on large mechanisms."""
    return {
        "fully_qualified_modules": False,
        "inline": True,
        "allow_unknown_functions": True,
        "user_functions": dict(user_functions),
        "order": "none",
    }


#: lambdify's own docstring prints the whole expression with sympy's str printer (a tenth of
#: a mechanism's lambdify): nobody reads it, so it is left out where sympy lets us (1.13 on).
NO_DOCSTRING: dict = (
    {"docstring_limit": 0} if "docstring_limit" in inspect.signature(sp.lambdify).parameters else {}
)


class _MpmathPrinter(FastPrecedence, MpmathPrinter):
    """lambdify's mpmath printer, its precedences found faster (symkin.model.precedence)."""


class _PythonPrinter(FastPrecedence, PythonCodePrinter):
    """lambdify's math printer, its precedences found faster (symkin.model.precedence)."""


def _cse(exprs):
    return sp.cse(exprs, list=False, order="none")


def lambdify(args: Sequence, exprs, modules: list, cse: bool = True) -> Callable:
    """sympy.lambdify(args, exprs, modules, cse) with its own printer for `modules` (a list of
    namespace dicts and the module names "mpmath" or "math") set to print terms unsorted."""
    names = [m for m in modules if isinstance(m, str)]
    known = all(isinstance(m, str | dict) for m in modules) and set(names) <= {"mpmath", "math"}
    if not known:  # another module, or a module object: lambdify's own printer
        return sp.lambdify(args, exprs, modules=modules, cse=_cse if cse else False, **NO_DOCSTRING)
    printer_class = _MpmathPrinter if "mpmath" in names else _PythonPrinter
    # lambdify's user functions: every name of the namespace dicts
    printer = printer_class(
        printer_settings({k: k for m in modules[::-1] if isinstance(m, dict) for k in m})
    )
    return sp.lambdify(
        args, exprs, modules=modules, cse=_cse if cse else False, printer=printer, **NO_DOCSTRING
    )
