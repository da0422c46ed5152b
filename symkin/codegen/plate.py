"""The plate relation (symkin.physics.plate_relation) as a routine of generated code: the
per-plate kernel of the Newton level (docs/physics.md, "The Newton level"), its three outputs
and their nine partials by (θ, p, f), which the mechanism's Jacobian takes by the chain rule.
Every beam-column kernel is called as `<kernel>_at(p, t)` with one t = T(p) for all.

    plate_relation<order>  in = (theta, p, f, e_a, e_s)  ->  values (along, across, omega),
                                                             partials (3 x 3, row-major)
"""

from __future__ import annotations

from dataclasses import replace
from functools import cache

import sympy as sp

from ..model.special.axial import AxialKernel, bcol_t, kernel_at
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
    shared = {}
    for k in sp.Tuple(*values, *partials).atoms(AxialKernel):
        x = k.args[0]
        shared[k] = kernel_at(k.base, k.order)(x, bcol_t(x))
    memo: dict = {}
    outputs = tuple(float_literals(e.xreplace(shared), memo) for e in values + partials)
    routine = Routine(
        f"plate_relation{order}",
        (Argument("in", SYMBOLS),),
        (),
        outputs,
        f"one plate's relation at order {order}: (along, across, omega) and their partials by "
        "(theta, p, f)",
        layout(("values", 3, 1), ("partials", 3, 3)),
    )
    return _squares(optimize(routine))


def _squares(routine: Routine) -> Routine:
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
