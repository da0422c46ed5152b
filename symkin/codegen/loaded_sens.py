"""The `loaded` level's sensitivity routines (docs/sensitivity.md; the pieces of
symkin.physics.reduced_sensitivity), for one and two half plates per plate:

    loaded_sens<g>  x, theta, plates, params -> dR/dtheta, dR/dp, din/dtheta, din/dp, dD/dx,
                                                dD/dtheta, dD/dp, dD/dout (theta: every hinge;
                                                in: every half plate's (theta_c, p, f, e_a, e_s);
                                                D: the plan's points' deviations)
    plate_eps4      in                       -> d(along, across, omega)/d(e_a, e_s) of the plate
                                                relation at order 4 (3 x 2)

The generated drivers (templates/c/reduced_sens.c, templates/numpy/reduced_sens.py) assemble
them with the solution's Jacobian.
"""

from __future__ import annotations

from collections.abc import Sequence
from functools import cache

import sympy as sp

from ..kinematics.analysis import Analysis
from ..physics import reduced
from ..physics.reduced_sensitivity import eps_relation, partials
from .literals import float_literals
from .loaded import notched
from .plate import SYMBOLS
from .routines import Argument, Routine, flatten, layout, optimize


def loaded_sens_routines(
    analysis: Analysis, names: Sequence[str], theta: Argument, params: Argument
) -> dict[str, Routine]:
    """loaded_sens1 and loaded_sens2 (parameters as symbols, scales at the file's defaults, as
    symbol.codegen.loaded's routines; theta: the force actuators' forces after the angles)."""
    an = analysis
    values = {p.symbol: p.value for p in an.mechanism.parameters}
    out = {}
    angles = theta
    for g in (1,) if notched(an.mechanism) else (1, 2):
        r = reduced.Reduced(an.kin, values, segments=g, symbolic=True)
        theta = Argument(angles.name, (*angles.symbols, *r.fa))
        s = r._s
        rename = {r.th[a]: an.kin.theta[a] for a in r.hinges}
        outs = tuple(v for a, j, *_ in r.segs for v in s["out"][a, j])
        blocks = partials(r, an.params, names).blocks()
        out[f"loaded_sens{g}"] = Routine(
            f"loaded_sens{g}",
            (Argument("x", (*r.x, r.t)), theta, Argument("plates", outs), params),
            (),
            tuple(sp.sympify(e).xreplace(rename) for _, m in blocks for e in flatten(m.tolist())),
            f"loaded ({g} half plate(s) per plate), sensitivities: dR/dtheta, dR/dp, "
            "din/dtheta, din/dp, dD/dx, dD/dtheta, dD/dp, dD/dout",
            layout(*((name, *m.shape) for name, m in blocks)),
        )
    return out


@cache
def eps_routine() -> Routine:
    """The plate relation's partials by e_a and e_s (the stretching and shear numbers), which
    read the parameters: the sensitivities' chain rule needs them."""
    symbols, exprs = eps_relation()
    memo: dict = {}
    subs = dict(zip(symbols, SYMBOLS, strict=True))
    outputs = tuple(float_literals(sp.sympify(e).xreplace(subs), memo) for e in exprs)
    routine = Routine(
        "plate_eps4",
        (Argument("in", SYMBOLS),),
        (),
        outputs,
        "one plate's relation at order 4: d(along, across, omega)/d(e_a, e_s)",
        layout(("partials", 3, 2)),
    )
    return optimize(routine)
