"""The plate relation (symkin.physics.plate_relation) as a routine of generated code: the
per-plate kernel of the Newton level (docs/physics.md, "The Newton level"), its three outputs
and their nine partials by (θ, p, f), which the mechanism's Jacobian takes by the chain rule.

    plate_relation<order>  in = (theta, p, f, e_a, e_s)  ->  values (along, across, omega),
                                                             partials (3 x 3, row-major)
"""

from __future__ import annotations

from functools import cache

import sympy as sp

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
    memo: dict = {}
    outputs = tuple(float_literals(e, memo) for e in values + partials)
    routine = Routine(
        f"plate_relation{order}",
        (Argument("in", SYMBOLS),),
        (),
        outputs,
        f"one plate's relation at order {order}: (along, across, omega) and their partials by "
        "(theta, p, f)",
        layout(("values", 3, 1), ("partials", 3, 3)),
    )
    return optimize(routine)
