"""One configuration through a generated evaluator (the `numpy` and `c` backends of
`symkin eval`, symkin.codegen.pipeline): its plan derived (or read from the cache) and loaded,
the arguments passed as doubles, its output read back into an Evaluation. The dyad states and,
at `loaded`, the plates' loads come from the `sympy` backend's derivation. A configuration the
evaluator cannot solve raises :class:`Unsolved`: symkin.studies.evaluation then asks the
mpmath evaluation why, so every backend fails with the same exit code and message."""

from __future__ import annotations

import numpy as np
import sympy as sp

from ..codegen import pipeline
from ..core import backends, levels
from ..core.errors import InputError
from ..kinematics.analysis import Analysis
from .configuration import Configuration, parameter_floats
from .mpmath_evaluator import evaluator_of
from .physical import REPORTED, loaded, with_model_error
from .results import Evaluation, LinkResult, PointResult, Sensitivity


class Unsolved(Exception):
    """The generated evaluator could not solve a configuration (its status nonzero)."""


def check_level(level: str, caps: backends.Capabilities) -> None:
    """Refuse (exit 2) a level the generated backend `caps` does not hold."""
    if level not in caps.levels:
        raise InputError(
            f"level '{level}' has no generated evaluator",
            entry="--backend",
            hint="evaluate it with --backend sympy",
        )


def evaluate(
    analysis: Analysis, config: Configuration, backend: str, sensitivity: bool = False
) -> Evaluation:
    """One configuration (its level one :func:`check_level` accepts) through a generated-code
    `backend` (symkin.codegen.pipeline); with `sensitivity`, its generated sensitivity function
    too; :class:`Unsolved` where it cannot solve the configuration."""
    kin, mech = analysis.kin, analysis.mechanism
    level_row, level = config.level, config.level.name
    if mech.actuators:
        names = list(mech.drives)
        x = [float(sp.N(config.drives[n], 20)) for n in names]
    else:
        given = config.angles
        names = [kin.hinges[a].name for a in kin.inputs]
        x = [float(sp.N(given[a], 20)) for a in kin.inputs]
    pvals = config.params
    pfloat = [float(sp.N(pvals[s], 20)) for s in analysis.params]
    # a plan derived with sensitivities or more levels serves (the same values); else the
    # kinematic levels are derived without the physical ones (the reduced equilibrium's
    # routines are most of a plan's derivation)
    scope = None
    if not level_row.needs_stiffness:
        scope = [lv.name for lv in levels.LEVELS if lv.generated and not lv.needs_stiffness]
    p = pipeline.plan_covering(analysis, level, sensitivity=sensitivity, levels=scope)
    ev = pipeline.evaluator(p, backend, analysis.mechanism.path)
    row, shape = pipeline.backend(backend), pipeline.Shape.of(p)
    hinges, pnames = shape.hinges, shape.params
    sens = None
    status, out, angles, rot = row.pose(ev, shape, x, pfloat, level)
    if status == 3:
        raise InputError(f"the {backend} evaluator rejected the arguments", entry="--input")
    # 4: beyond the rigid reach of a force actuator's stroke (docs/physics.md): the compliant
    # pose, no deviations
    beyond = status == 4 and not sensitivity
    if beyond:
        status = 0
    if status == 0 and sensitivity:
        rows = row.sensitivity_rows(ev, shape, np.array([x]), pfloat, level)
        status = int(rows[0][0])
        sens = Sensitivity.from_columns(shape.points, pnames, names, rows[2][0], rows[3][0])
    if status:
        raise Unsolved
    points = {
        n: PointResult(
            (out[6 * i], out[6 * i + 1]),
            (out[6 * i + 2], out[6 * i + 3]),
            (out[6 * i + 4], out[6 * i + 5]),
        )
        for i, n in enumerate(shape.points)
    }
    m = len(hinges)
    rigid = dict(zip(hinges, angles[:m]))
    compliant = dict(zip(hinges, angles[m:]))
    links = {n: LinkResult(*rot[3 * i : 3 * i + 3]) for i, n in enumerate(p.reported_links)}
    order = {kin.hinges[a].name: a for a in kin.hinges}
    extra = {}
    if level_row.needs_stiffness:
        # The plates' loads and energy are not in the generated evaluators' output: the
        # derivation gives them, as it gives the dyad states (docs/physics.md).
        physical = loaded(analysis, config)
        extra = {"hinges": physical.hinges, "energy": physical.energy, "units": mech.units}
        extra |= {k: getattr(physical, k) for k in REPORTED}
    result = Evaluation(
        level=level,
        backend=backend,
        inputs=dict(zip(names, x)),
        angles_rigid={h: rigid[h] for h in sorted(rigid, key=order.get)},
        angles_compliant={h: compliant[h] for h in sorted(compliant, key=order.get)},
        points=points,
        dyads=()
        if beyond
        else evaluator_of(analysis).dyad_states(
            config.with_angles({n: rigid[n] for n in mech.inputs}) if mech.actuators else config
        ),
        params=parameter_floats(analysis.mechanism, pvals),
        overrides=config.overrides,
        links=links,
        sensitivity=sens,
        **extra,
    )
    if beyond:
        # the note names the stroke the force produced, as the sympy backend's (the same solve)
        note = physical.deviation_note
        if note is None:
            raise Unsolved
        return result.beyond_reach(note)
    if level_row.needs_stiffness:
        return with_model_error(result, analysis.mechanism, pvals)
    return result
