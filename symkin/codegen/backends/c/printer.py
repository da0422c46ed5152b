"""The C99 printer of generated code."""

from __future__ import annotations

import sympy as sp
from sympy.printing.c import C99CodePrinter

from ....model import special
from ....model.precedence import FastPrecedence


class CPrinter(FastPrecedence, C99CodePrinter):
    """C99 printer without the non-standard M_PI / M_SQRT2 ... macros (strict -std=c99 has none),
    writing every Float as its shortest round-trip decimal, symkin's special functions as the
    static `symkin_<name>` of backends/c/kernels.py, a Piecewise (the plates' modulus,
    docs/physics.md) as one line of nested ternaries and a named value's cube as products."""

    def __init__(self, settings=None) -> None:
        super().__init__(settings)
        self.math_macros = {}

    def _print_Pi(self, expr):
        return "3.141592653589793238462643383279503"

    def _print_Exp1(self, expr):
        return "2.718281828459045235360287471352662"

    def _print_Float(self, expr):
        # literals.float_literals made every Float a double: print the shortest exact decimal.
        return repr(float(expr))

    def _print_Function(self, expr):
        if special.is_special(expr):
            args = ", ".join(self._print(a) for a in expr.args)
            return f"symkin_{type(expr).__name__}({args})"
        return super()._print_Function(expr)

    def _print_Pow(self, expr):
        # x*x*x, not pow(x, 3): the compilers turn pow(x, 2) into x*x themselves but call pow
        # for a cube, ten times the cost (within an ulp of it: two roundings, not one)
        if expr.exp == 3 and isinstance(expr.base, sp.Symbol):
            b = self._print(expr.base)
            return f"({b}*{b}*{b})"
        return super()._print_Pow(expr)

    def _print_Piecewise(self, expr):
        if expr.args[-1].cond != True:  # noqa: E712 - sympy's BooleanTrue
            raise ValueError("a Piecewise in generated code needs a default (True) branch")
        text = self._print(expr.args[-1].expr)
        for e, c in reversed(expr.args[:-1]):
            text = f"(({self._print(c)}) ? ({self._print(e)}) : ({text}))"
        return text
