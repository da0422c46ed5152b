"""The numpy printer of generated code."""

from __future__ import annotations

from sympy.printing.numpy import NumPyPrinter

from ....model import special
from ....model.precedence import FastPrecedence


class NumpyPrinter(FastPrecedence, NumPyPrinter):
    """NumPyPrinter that writes every Float as its shortest round-trip decimal, calls symkin's
    special functions by their names (defined in the module from backends/numpy) and writes a
    Piecewise (the plates' modulus, docs/physics.md) as nested numpy.where in the module's
    _DTYPE, so a float32 evaluator stays in float32."""

    def _print_Float(self, expr):
        # NumPyPrinter prints 15 digits; every Float here is a double (literals.float_literals):
        # print the shortest decimal that reads back to it exactly.
        return repr(float(expr))

    def _print_Function(self, expr):
        if special.is_special(expr):
            return f"{type(expr).__name__}({', '.join(self._print(a) for a in expr.args)})"
        return super()._print_Function(expr)

    def _print_Piecewise(self, expr):
        if expr.args[-1].cond != True:  # noqa: E712 - sympy's BooleanTrue
            raise ValueError("a Piecewise in generated code needs a default (True) branch")
        text = self._print(expr.args[-1].expr)
        for e, c in reversed(expr.args[:-1]):
            text = f"numpy.where({self._print(c)}, {self._print(e)}, {text})"
        return f"_DTYPE({text})"
