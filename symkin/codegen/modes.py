"""The routines of the generated numpy module's `modes()` (docs/generated-code.md, "Natural
frequencies in generated code"; docs/physics.md, "Natural frequencies"), for files whose moving
links carry mass and whose evaluator has the `loaded` level's report:

    loaded_modes<g>   x, theta, plates, params  -> with v a virtual load (F_x, F_y, M) at every
                                                   massive link's centre of mass (hidden points)
                                                   and y every centre's then every shown point's
                                                   (dx, dy, dphi): dR/dv, din/dv, dy/dx, dy/dv,
                                                   dy/d(plates) at v = 0, the pieces the
                                                   implicit-function theorem assembles into the
                                                   compliance (as loaded_report<g>'s,
                                                   symkin.codegen.loaded)
    modes_data        params                    -> per massive link (mass kg, inertia kg m²), then
                                                   the as-fabricated (x, y) of every point, centre
                                                   and hinge, then every hinge's length (the span
                                                   a pure rotation is judged by,
                                                   symkin.physics.modes.span_of)

The runtime (templates/numpy/modes.py) solves the eigenproblem of symkin.physics.modes.solve on
every configuration at once.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import sympy as sp

from ..model.derivatives import jacobian
from ..model.mechanism import Mechanism
from ..physics import reduced
from ..physics.modes import CENTRE, massive_links
from .routines import Argument, Routine, flatten, layout

#: The blocks of the loaded_modes<g> routines, in order.
MODES_BLOCKS = ("dR_dv", "din_dv", "dy_dx", "dy_dv", "dy_dout")


@dataclass(frozen=True)
class ModesPlan:
    """What the generated `modes()` reads: the massive links (file order; their centres are the
    routines' first points), the shown points after them, the spans' coordinates."""

    links: tuple[str, ...]
    points: tuple[str, ...]
    coordinates: int  # (x, y) pairs in modes_data after the masses
    lengths: int  # hinge lengths after them


def modes_routine(
    r: reduced.Reduced, shown: Sequence[str], x: Argument, theta: Argument, plates, params, sub
) -> Routine:
    """loaded_modes<g> of `r` (a Reduced whose mechanism holds the centres' hidden points)."""
    se = r._se
    ordered = sorted(r.points)
    centres = [CENTRE + lk.name for lk in massive_links(r.kin.mechanism)]
    first = len(r.inputs) + len(r.acts)
    virtual = r.extra[first:]
    every = r._reported(se)

    def at(values, name):
        k = 3 * ordered.index(name)
        return list(values[k : k + 3])

    by = [v for c in centres for v in at(virtual, c)]
    ys = sp.Matrix([v for name in (*centres, *shown) for v in at(every[first:], name)])
    residual = sp.Matrix(r._rows(se))
    moving = sp.Matrix([v for a, j, *_ in r.segs for v in se["pf"][a, j]])
    zero = dict.fromkeys(r.extra, sp.S.Zero)
    blocks = [
        ("dR_dv", jacobian(residual, by)),
        ("din_dv", jacobian(moving, by)),
        ("dy_dx", jacobian(ys, r.x)),
        ("dy_dv", jacobian(ys, by)),
        ("dy_dout", jacobian(ys, list(plates.symbols))),
    ]
    exprs = [sub(sp.sympify(e).xreplace(zero)) for _, m in blocks for e in flatten(m.tolist())]
    g = r.segments
    return Routine(
        f"loaded_modes{g}",
        (x, theta, plates, params),
        (),
        tuple(exprs),
        f"loaded ({g} half plate(s) per plate), the natural frequencies' compliance: dR/dv, "
        "din/dv, dy/dx, dy/dv, dy/dout (v: virtual loads at the massive links' centres, y: the "
        "centres' and the points' (dx, dy, dphi))",
        layout(*((name, *m.shape) for name, m in blocks)),
    )


def modes_data(
    mech: Mechanism, params: Argument, shown: Sequence[str]
) -> tuple[Routine, ModesPlan]:
    """modes_data (the masses, inertias and the span's coordinates over the parameters) and the
    plan's modes table."""
    massive = massive_links(mech)
    outs: list[sp.Expr] = []
    for lk in massive:
        outs += [sp.sympify(lk.mass), sp.sympify(lk.inertia or 0)]
    coordinates = [p.at for p in mech.points] + [lk.centre for lk in massive]
    coordinates += [h.at for h in mech.hinges]
    outs += [sp.sympify(c) for at in coordinates for c in at]  # type: ignore[union-attr]
    outs += [sp.sympify(h.length) for h in mech.hinges]
    routine = Routine(
        "modes_data",
        (params,),
        (),
        tuple(outs),
        "the massive links' masses and inertias, the as-fabricated coordinates of every point, "
        "centre of mass and hinge, every hinge's length",
        layout(
            ("masses", len(massive), 2),
            ("coordinates", len(coordinates), 2),
            ("lengths", len(mech.hinges), 1),
        ),
    )
    plan = ModesPlan(
        tuple(lk.name for lk in massive), tuple(shown), len(coordinates), len(mech.hinges)
    )
    return routine, plan
