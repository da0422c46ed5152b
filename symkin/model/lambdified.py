"""sympy.lambdify for large expressions: CSE and printing take the terms in the order sympy
stores them (deterministic, sympy's canonical argument order) instead of sorting every sum
again, which is most of lambdify's time on a mechanism's equilibrium; and
:func:`mpmath_function`, the derivation's expressions as mpmath functions without lambdify's
walks (the `sympy` backend's evaluator, symkin.studies.mpmath_evaluator)."""

from __future__ import annotations

import inspect
from collections.abc import Callable, Mapping, Sequence

import mpmath
import sympy as sp
from sympy.printing.pycode import MpmathPrinter, PythonCodePrinter

from ..core.recent import Recent
from . import special
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


class _ArgumentPrinter(FastPrecedence, MpmathPrinter):
    """lambdify's MpmathPrinter that prints each argument symbol by its position (_a0, _a1, ...).

    A parameter may share its name with an internal symbol (a class apart: other assumptions),
    so arguments are told apart by the symbol, not its name; printing them so costs nothing,
    where renaming them in the expression first (lambdify's dummify, or an xreplace) re-walks
    every expression: minutes on a ladder of 20 loops."""

    def __init__(self, names: Mapping[sp.Symbol, str], settings: dict) -> None:
        super().__init__(settings)
        self._names = names

    def _print_Symbol(self, expr: sp.Symbol) -> str:
        name = self._names.get(expr)
        return name if name is not None else super()._print_Symbol(expr)


#: The last mpmath functions printed, by their arguments and expressions: analyses of other
#: files share many (a mechanism with one plate stiffer has the same kinematics).
_FUNCTIONS: Recent[tuple, Callable] = Recent(256)


def _frozen(exprs) -> object:
    return tuple(_frozen(e) for e in exprs) if isinstance(exprs, list | tuple) else exprs


def mpmath_function(args: Sequence[sp.Symbol], exprs) -> Callable:
    """`exprs` (an expression or nested lists of them) as a Python function of `args`
    evaluated with mpmath and symkin's special functions; printed once per arguments and
    expressions (the last 256 kept)."""
    key = (tuple(args), _frozen(exprs))
    try:
        hash(key)
    except TypeError:  # e.g. a mutable matrix among them: printed every time
        return _mpmath_function(args, exprs)
    return _FUNCTIONS.get_or_make(key, lambda: _mpmath_function(args, exprs))


def _mpmath_function(args: Sequence[sp.Symbol], exprs) -> Callable:
    """`exprs` (an expression or nested lists of them) as a Python function of `args`
    evaluated with mpmath and symkin's special functions.

    What sympy.lambdify(args, exprs, modules=[mpmath_namespace(), "mpmath"]) gives, without its
    walks of every expression (dummifying, implemented-function lookup, the docstring), which
    cost more than the printing on large mechanisms. No CSE: every row is evaluated as written,
    so its rounding is what the stopping rule of symkin.core.settings (3b) was measured on."""
    names = {s: f"_a{k}" for k, s in enumerate(args)}
    namespace = {**vars(mpmath), **special.mpmath_namespace()}
    printer = _ArgumentPrinter(names, printer_settings({k: k for k in special.mpmath_namespace()}))

    def flat(e) -> list:
        return [v for x in e for v in flat(x)] if isinstance(e, list | tuple) else [e]

    def nest(e, values):
        if isinstance(e, list | tuple):
            return [nest(x, values) for x in e]
        return next(values)

    leaves = [sp.sympify(e) for e in flat(exprs)]
    shaped = nest(exprs, iter([printer.doprint(v) for v in leaves]))

    def text(e) -> str:
        return "[" + ", ".join(text(x) for x in e) + "]" if isinstance(e, list) else e

    source = f"def _f({', '.join(names.values())}):\n    return {text(shaped)}"
    local: dict = {}
    # the source is printed from sympy expressions whose every argument is renamed _aK, so no
    # name from a mechanism file reaches it (lambdify execs its source the same way)
    exec(compile(source, "<symkin-mpmath>", "exec"), namespace, local)
    return local["_f"]
