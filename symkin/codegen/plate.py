"""The plate relation (symkin.physics.plate_relation) as a routine of generated code: the per-plate
kernel of the `loaded` level (docs/physics.md, "`loaded`: Newton on the reduced equilibrium"), its
three outputs and their nine partials by (θ, p, f), which the mechanism's Jacobian takes by the
chain rule. Every beam-column kernel is called as `<kernel>_at(p, h)` with one h = bcol_h(p) for
all.

    plate_relation<order>  in = (theta, p, f, e_a, e_s)  ->  values (along, across, omega),
                                                             partials (3 x 3, row-major)
"""

from __future__ import annotations

import math
from dataclasses import replace
from functools import cache

import sympy as sp

from ..model.special import cosr, sinr
from ..model.special.axial import AxialKernel, bcol_h, kernel, kernel_at
from ..physics.plate_relation import relation
from .literals import float_literals
from .routines import Argument, Routine, layout, optimize

#: The routine's arguments, in the order of its `in` array.
SYMBOLS = sp.symbols("theta p f e_a e_s", real=True)


@cache
def plate_routine(order: int = 4) -> Routine:
    """The CSE'd routine of the plate relation at `order` (4, or 2 for the truncation
    estimate)."""
    th, p, f, ea, es = SYMBOLS
    rel = relation(th, p, f, ea, es, order)
    values = [rel.along, rel.across, rel.omega]
    partials = [sp.diff(v, w) for v in values for w in (th, p, f)]
    identities = _identities(sp.Tuple(*values, *partials))
    exprs = [e.xreplace(identities) for e in values + partials]
    memo: dict = {}
    outputs = tuple(float_literals(e, memo) for e in shared_h(exprs))
    routine = Routine(
        f"plate_relation{order}",
        (Argument("in", SYMBOLS),),
        (),
        outputs,
        f"one plate's relation at order {order}: (along, across, omega) and their partials by "
        "(theta, p, f)",
        layout(("values", 3, 1), ("partials", 3, 3)),
    )
    return squares(optimize(routine))


def _identities(expr: sp.Expr) -> dict:
    """Six kernels of `expr` through others it calls as well, with little cancellation (checked
    in mpmath by tests/test_loaded_newton.py): S' = -2 W (from T' = (S - T^2/4)/2),
    A = p W/(3 T^2) (its definition: a product), E3' = e3c - 1/1920 (its definition; the terms
    add to at most 12 times it, near the buckling load); D6's kernels sinr4, sinr3, cosr4 by the
    recurrence k_n = c_n + x^2 k_(n+1) from sinr5 and cosr5 (the partials' own; the terms add to
    at most 1.8 times it for |x| <= 5, |theta| <= 10)."""
    out: dict = {}
    for k in expr.atoms(sinr(5), cosr(5)):
        x = k.args[0]
        if isinstance(k, sinr(5)):
            s4 = sp.Rational(1, math.factorial(9)) + x**2 * k
            out[sinr(4)(x)] = s4
            out[sinr(3)(x)] = -sp.Rational(1, math.factorial(7)) + x**2 * s4
        else:
            out[cosr(4)(x)] = sp.Rational(1, math.factorial(8)) + x**2 * k
    for k in expr.atoms(AxialKernel):
        x = k.args[0]
        if (k.base, k.order) == ("s", 1):
            out[k] = -2 * kernel("w")(x)
        elif (k.base, k.order) == ("a", 0):
            out[k] = x * kernel("w")(x) * kernel("invt")(x) ** 2 / 3
        elif (k.base, k.order) == ("e3", 1):
            out[k] = kernel("e3c")(x) - sp.Rational(1, 1920)
    return out


def shared_h(exprs: list[sp.Expr]) -> list[sp.Expr]:
    """exprs with every beam-column kernel called as `<kernel>_at(p, h)`, h = bcol_h(p) one
    value for all (the CSE keeps one call of bcol_h per argument, not one per kernel)."""
    shared = {}
    for k in sp.Tuple(*exprs).atoms(AxialKernel):
        x = k.args[0]
        shared[k] = kernel_at(k.base, k.order)(x, bcol_h(x))
    return [e.xreplace(shared) for e in exprs]


def squares(routine: Routine) -> Routine:
    """The routine with every power b^n, 4 <= n <= 7, of a named value b written through its
    square b_sq = b^2 (b_sq^2, b_sq^2 b, b_sq^3, b_sq^3 b): products the compiler keeps, not a
    call of pow (gcc turns only pow(b, 2) into a product)."""
    squares: dict[sp.Symbol, sp.Symbol] = {}

    def high(e: sp.Basic) -> bool:
        return e.is_Pow and e.base.is_Symbol and e.exp.is_Integer and 4 <= e.exp <= 7

    def split(e: sp.Pow) -> sp.Expr:
        sq = squares.setdefault(e.base, sp.Symbol(f"{e.base.name}_sq", real=True))
        return sq ** (int(e.exp) // 2) * e.base ** (int(e.exp) % 2)

    lines = [(s, e.replace(high, split)) for s, e in routine.assignments]
    outputs = tuple(e.replace(high, split) for e in routine.outputs)
    # each square right after its base (the inputs' first)
    out = [(sq, b**2) for b, sq in squares.items() if not any(b == s for s, _ in lines)]
    for s, e in lines:
        out.append((s, e))
        if s in squares:
            out.append((squares[s], s**2))
    return replace(routine, assignments=tuple(out), outputs=outputs)
