"""Jacobians of large sympy expressions, sympy's own derivatives computed once per subexpression.

sympy's `diff` walks a row again for every subexpression it differentiates (each node builds a
`Derivative`, asks for its free symbols and canonicalises the result), so a deep expression costs
quadratic time, and a subexpression shared by many rows (a plate's frame angle, a link's force)
is differentiated once per row. :func:`jacobian` applies sympy's own rules (Add, Mul's Leibniz
rule, Pow, a Function's chain rule through its `fdiff`) node by node with every node's derivative
and free symbols kept, and hands any other node to sympy's `diff`: the entries are the
expressions `diff` gives (tests/test_derivatives.py compares them), in a fraction of the time.
"""

from __future__ import annotations

from collections.abc import Iterable

import sympy as sp
from sympy.core.function import ArgumentIndexError
from sympy.ntheory.multinomial import multinomial_coefficients_iterator

_FUNCTION_RULE = sp.Function._eval_derivative


class _Rules:
    """One Jacobian's memo: free symbols by node, derivatives by (node, symbol)."""

    def __init__(self) -> None:
        self.free: dict[sp.Basic, frozenset] = {}
        self.held: dict[sp.Basic, bool] = {}
        self.done: dict[tuple[sp.Basic, sp.Symbol], sp.Expr] = {}

    def symbols(self, e: sp.Basic) -> frozenset:
        """e.free_symbols, by the union over the arguments of the nodes the rules know."""
        found = self.free.get(e)
        if found is None:
            if e.is_Symbol:
                found = frozenset((e,))
            elif isinstance(e, (sp.Add, sp.Mul, sp.Pow, sp.Function)):
                found = frozenset().union(*(self.symbols(a) for a in e.args))
            else:
                found = frozenset(e.free_symbols)
            self.free[e] = found
        return found

    def unevaluated(self, e: sp.Basic) -> bool:
        """Whether e holds a Derivative or Subs (which diff canonicalises)."""
        found = self.held.get(e)
        if found is None:
            found = isinstance(e, (sp.Derivative, sp.Subs)) or any(
                self.unevaluated(a) for a in e.args
            )
            self.held[e] = found
        return found

    def diff(self, e: sp.Basic, s: sp.Symbol) -> sp.Expr:
        """e.diff(s)."""
        key = (e, s)
        found = self.done.get(key)
        if found is not None:
            return found
        if s not in self.symbols(e):
            found = sp.S.Zero
        elif self.unevaluated(e):  # diff canonicalises every Derivative in its result: let it
            found = e.diff(s)
        elif e.is_Symbol:
            found = sp.S.One  # e is s: it holds s
        elif isinstance(e, sp.Add):  # Add._eval_derivative
            found = e.func(*[self.diff(a, s) for a in e.args])
        elif isinstance(e, sp.Mul):  # Mul._eval_derivative_n_times, n = 1 (Leibniz)
            args = list(e.args)
            terms = []
            # its terms in its order (the multinomial coefficients of n = 1: c = 1, one k = 1)
            for ks, c in multinomial_coefficients_iterator(len(args), 1):
                i = ks.index(1)
                d = self.diff(args[i], s)
                terms.append(c * sp.Mul(*(args[:i] + [d] + args[i + 1 :])))
            found = sp.Add(*terms)
        elif isinstance(e, sp.Pow):  # Pow._eval_derivative
            dbase, dexp = self.diff(e.base, s), self.diff(e.exp, s)
            found = e * (dexp * sp.log(e.base) + dbase * e.exp / e.base)
        elif isinstance(e, sp.Function) and type(e)._eval_derivative is _FUNCTION_RULE:
            parts = []
            for i, a in enumerate(e.args, 1):  # Function._eval_derivative
                da = self.diff(a, s)
                if da.is_zero:
                    continue
                try:
                    df = e.fdiff(i)
                except ArgumentIndexError:
                    df = sp.Function.fdiff(e, i)
                parts.append(df * da)
            found = sp.Add(*parts)
            if self.unevaluated(found):  # fdiff gave a Derivative or Subs: diff canonicalises it
                found = e.diff(s)
        else:
            found = e.diff(s)
        self.done[key] = found
        return found


def jacobian(rows: Iterable[sp.Expr], by: Iterable[sp.Symbol]) -> sp.Matrix:
    """The rows' Jacobian by the symbols `by` (Matrix.jacobian's entries, each row
    differentiated only by the symbols it holds: by hundreds of symbols, of which a row reads a
    few, most entries are zero without a walk)."""
    rows, by = list(rows), list(by)
    out = sp.zeros(len(rows), len(by))
    if not by or not rows:
        return out
    column = {s: k for k, s in enumerate(by)}
    rules = _Rules()
    for i, row in enumerate(rows):
        row = sp.sympify(row)
        for s in rules.symbols(row):
            k = column.get(s)
            if k is not None:
                out[i, k] = rules.diff(row, s)
    return out
