"""The numpy printer of generated code."""

from __future__ import annotations

from sympy.printing.numpy import NumPyPrinter

from .... import special


class NumpyPrinter(NumPyPrinter):
    """NumPyPrinter that writes every Float as its shortest round-trip decimal and calls
    symkin's special functions by their names (defined in the module from backends/numpy)."""

    def _print_Float(self, expr):  # noqa: N802
        # NumPyPrinter prints 15 digits; every Float here is a double (literals.float_literals):
        # print the shortest decimal that reads back to it exactly.
        return repr(float(expr))

    def _print_Function(self, expr):  # noqa: N802
        if special.is_special(expr):
            return f"{type(expr).__name__}({', '.join(self._print(a) for a in expr.args)})"
        return super()._print_Function(expr)
