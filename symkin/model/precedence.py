"""Operator precedence for symkin's code printers (generated C and numpy, lambdified functions):
sympy's own values, without building every product's negative to find them.

sympy asks a product whether it ``could_extract_minus_sign()``, which first compares the product
with its negative (for zoo*x == -zoo*x) and so builds that negative: a third of the printing of a
mechanism's equations. A Mul's leading factor decides alone, since a product differs from its
negative unless that factor is 0, zoo or nan, none of which is negative."""

from __future__ import annotations

from mpmath.libmp import fzero, mpf_lt
from sympy.core.function import Function
from sympy.core.mul import Mul
from sympy.core.numbers import Float
from sympy.printing.precedence import PRECEDENCE, precedence

_MUL, _ADD, _ATOM = PRECEDENCE["Mul"], PRECEDENCE["Add"], PRECEDENCE["Atom"]


def precedence_of(item) -> int:
    """sympy.printing.precedence.precedence(item), the same value for every item, a product's and
    a Float's found without building another expression."""
    kind = type(item)
    if kind is Mul:
        # sympy's precedence_Mul, its could_extract_minus_sign read off the leading factor
        if any(
            hasattr(a, "precedence") and isinstance(a, Function) and a.precedence < _MUL
            for a in item.args
        ):
            return _MUL
        c = item.args[0]
        return _ADD if c.is_Number and c.is_extended_negative else _MUL
    if kind is Float:
        # sympy's precedence_Float (item < 0) on the mpf: nan compares False in both
        return _ADD if mpf_lt(item._mpf_, fzero) else _ATOM
    return precedence(item)


class FastPrecedence:
    """Mixin of a sympy StrPrinter subclass: its parenthesize and _print_Add, as sympy writes
    them, with precedence_of for sympy's precedence (the same text, faster)."""

    def parenthesize(self, item, level, strict=False):
        prec = precedence_of(item)
        if prec < level or (not strict and prec <= level):
            return f"({self._print(item)})"
        return self._print(item)

    def _print_Add(self, expr, order=None):
        terms = self._as_ordered_terms(expr, order=order)
        prec = precedence_of(expr)
        out = []
        for term in terms:
            t = self._print(term)
            if t.startswith("-") and not term.is_Add:
                sign = "-"
                t = t[1:]
            else:
                sign = "+"
            if precedence_of(term) < prec or term.is_Add:
                out.extend([sign, f"({t})"])
            else:
                out.extend([sign, t])
        sign = out.pop(0)
        if sign == "+":
            sign = ""
        return sign + " ".join(out)
