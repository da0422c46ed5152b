"""`symkin modes`: the natural frequencies and mode shapes of a mechanism whose links carry mass,
about the equilibrium of a physical level at one configuration (docs/physics.md, "Natural
frequencies"; the eigenproblem is symkin.physics.modes).

Every input is held: an input hinge at its angle, a stroke actuator at its stroke (one with a
`spring` at its command: the spring's give is in the stroke's row of the level's equations, so
their Jacobian's compliance has the spring acting, docs/physics.md "A stroke actuator with a
spring"), a force actuator at its force. The level gives the compliance of virtual loads at the
links' centres of mass (hidden points added to the mechanism, `CENTRE` + the link's name) and at
the file's points: `loaded` through its reported rates (symkin.physics.reduced_reported's point
stiffness, every pair of points), `equilibrium` through its Jacobian at the float64 solution of
its continuation (symkin.physics.reported's).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
import sympy as sp

from ..core.errors import AssemblyError, InputError
from ..graph.structure import build
from ..kinematics.analysis import Analysis
from ..model.expressions import substitute
from ..model.mechanism import Mechanism
from ..physics import equilibrium as physical_equilibrium
from ..physics import modes as physical_modes
from ..physics.stiffness import plate_stiffness
from .configuration import Configuration, configure, parameter_floats
from .physical import solve_reduced

#: The levels whose tangent stiffness the modes take.
LEVELS = ("loaded", "equilibrium")
#: Who computes them: the derivation (float64 eigen-solve of its 40-digit compliance), or the
#: generated numpy module's modes() (docs/generated-code.md).
BACKENDS = ("sympy", "numpy")
#: How the hidden point at a link's centre of mass is named (no file name holds a '@').
CENTRE = physical_modes.CENTRE


@dataclass(frozen=True)
class ModesResult:
    """The natural modes at one configuration, lowest first: frequencies (Hz) and, per mode,
    each massive link's centre displacement and rotation [dx, dy, dφ] and each point's [dx, dy]
    (file unit, rad), normalised (symkin.physics.modes.solve)."""

    level: str
    inputs: dict[str, float]
    params: dict[str, float]
    units: str
    frequencies: list[float]
    links: list[dict[str, tuple[float, float, float]]]
    points: list[dict[str, tuple[float, float]]]

    def as_json(self) -> dict:
        """The contract's JSON: level, frequencies and modes (links and points)."""
        return {
            "level": self.level,
            "frequencies": self.frequencies,
            "modes": [
                {
                    "links": {n: list(v) for n, v in links.items()},
                    "points": {n: list(v) for n, v in points.items()},
                }
                for links, points in zip(self.links, self.points)
            ],
        }


def with_centres(mech: Mechanism) -> tuple[Mechanism, list[str]]:
    """`mech` with a hidden point at every massive link's centre, and their names; bad input
    (exit 2) when no moving link has a mass."""
    if not physical_modes.massive_links(mech):
        raise InputError(
            "no link has a mass: the natural frequencies need the masses that oscillate",
            file=mech.path,
            entry="[[link]]",
            hint="add mass = ... (kg) and centre = [x, y] (file unit) to the moving links "
            "that carry mass, e.g. the stage (docs/file-format.md, '[[link]]')",
        )
    return physical_modes.with_centre_points(mech)


def modes(
    mech: Mechanism,
    inputs: Mapping[str, object],
    level: str = "loaded",
    params: Mapping[str, object] | None = None,
    count: int | None = None,
    backend: str = "sympy",
) -> ModesResult:
    """The `count` lowest natural modes (all when None) of `mech` at `inputs` (every input, as
    `symkin eval` takes them) and `params`, about the equilibrium of `level` (loaded or
    equilibrium); `backend` "numpy": by the generated numpy module's modes() (`loaded` alone,
    docs/generated-code.md)."""
    if backend not in BACKENDS:
        raise InputError(
            f"--backend {backend}: natural frequencies are computed by " + " or ".join(BACKENDS),
            file=mech.path,
            entry="--backend",
            hint="--backend sympy (default) or numpy",
        )
    if backend == "numpy" and level != "loaded":
        raise InputError(
            f"the numpy module's modes() are those of the loaded level, not {level}",
            file=mech.path,
            entry="--backend",
            hint="--level loaded with --backend numpy, or --backend sympy",
        )
    if level not in LEVELS:
        raise InputError(
            f"natural frequencies need a physical level, not '{level}'",
            file=mech.path,
            entry="--level",
            hint="--level loaded (default) or equilibrium",
        )
    if count is not None and count < 1:
        raise InputError(
            f"--count {count}: at least one mode", file=mech.path, entry="--count", hint="--count 3"
        )
    augmented, centres = with_centres(mech)
    if backend == "numpy":
        return _numpy(mech, inputs, params, count)
    analysis = Analysis(build(augmented))
    config = configure(analysis, inputs, level, params)
    values = config.params
    names = centres + [p.name for p in mech.points]
    if level == "loaded":
        compliance = _loaded(analysis, config, names)
    else:
        compliance = _equilibrium(augmented, config, names)
    massive = [lk for lk in mech.links if lk.massive and lk.name != mech.ground]

    def num(expr: object) -> float:
        return float(sp.N(substitute(sp.sympify(expr), values), 20))

    masses = [(num(lk.mass), num(lk.inertia or 0)) for lk in massive]
    where = {p.name: (num(p.at[0]), num(p.at[1])) for p in augmented.points}
    where |= {h.name: (num(h.at[0]), num(h.at[1])) for h in mech.hinges}
    span = physical_modes.span_of(where, max(num(h.length) for h in mech.hinges))
    found = physical_modes.solve(compliance, masses, float(mech.unit_scale), span, count=count)
    links, points = [], []
    for mode in found:
        v = [float(x) for x in mode.shape]
        links.append(
            {lk.name: (v[3 * k], v[3 * k + 1], v[3 * k + 2]) for k, lk in enumerate(massive)}
        )
        first = 3 * len(massive)
        points.append(
            {p.name: (v[first + 3 * k], v[first + 3 * k + 1]) for k, p in enumerate(mech.points)}
        )
    return ModesResult(
        level=level,
        inputs={n: float(sp.N(v, 20)) for n, v in config.drives.items()},
        params=parameter_floats(mech, values),
        units=mech.units,
        frequencies=[m.frequency for m in found],
        links=links,
        points=points,
    )


def _numpy(
    mech: Mechanism, inputs: Mapping[str, object], params: Mapping[str, object] | None, count
) -> ModesResult:
    """modes() at `loaded` by the generated numpy module (symkin.codegen.modes), the inputs and
    parameters parsed and checked as the sympy path's."""
    from ..codegen import pipeline

    analysis = Analysis(build(mech))
    config = configure(analysis, inputs, "loaded", params)
    massive = physical_modes.massive_links(mech)
    plan = pipeline.plan_covering(analysis, "loaded", levels=["loaded"], sensitivity=False)
    module = pipeline.evaluator(plan, "numpy", mech.path)
    given = {p.name: float(sp.N(config.params[p.symbol], 20)) for p in mech.parameters}
    x = {n: float(sp.N(config.drives[n], 20)) for n in module.INPUTS}
    found = module.modes(x, params=given, count=count or 3 * len(massive))
    if not bool(found["ok"]):
        raise AssemblyError(
            f"{mech.path}: the numpy module's modes() have no answer at this configuration: "
            "the loaded level does not solve it, or the tangent stiffness with the inputs held "
            "is not positive (the loads beyond buckling); --backend sympy says which"
        )
    frequencies, links, points = [], [], []
    for k, f in enumerate(found["frequencies"]):
        if not np.isfinite(f):
            continue  # held rigidly: an infinite frequency (the sympy path leaves it out)
        frequencies.append(float(f))
        links.append(
            {lk.name: tuple(float(v) for v in found["links"][lk.name][k]) for lk in massive}
        )
        points.append(
            {name: tuple(float(v) for v in found["points"][name][k]) for name in found["points"]}
        )
    return ModesResult(
        level="loaded",
        inputs={n: float(sp.N(v, 20)) for n, v in config.drives.items()},
        params=parameter_floats(mech, config.params),
        units=mech.units,
        frequencies=frequencies,
        links=links,
        points=points,
    )


def _loaded(analysis: Analysis, config: Configuration, names: list[str]):
    """The compliance of the points `names` at the `loaded` level's solution (40-digit
    derivation, symkin.studies.physical.solve_reduced)."""
    mech = analysis.mechanism
    if analysis.redundant and not any(h.beam == "reissner" for h in mech.hinges if h.is_plate):
        raise AssemblyError(
            f"{mech.path}: the loaded level cannot solve this redundant mechanism with "
            'inextensible elastica plates; give them beam = "reissner" (docs/levels.md)'
        )
    answer = solve_reduced(analysis, config, backend="sympy")
    if answer.refused:
        raise AssemblyError(
            f"{mech.path}: the loaded level refuses this configuration: {answer.refused} "
            "(docs/physics.md); ask for --level equilibrium"
        )
    red = answer.solver
    assert red is not None
    _, rates = red.reported(answer.x, answer.theta)
    first = len(red.inputs) + len(red.acts)
    return physical_modes.loaded_compliance(rates, first, sorted(red.points), names)


def _equilibrium(mech: Mechanism, config: Configuration, names: list[str]):
    """The compliance of the points `names` at the `equilibrium` level's float64 solution
    (symkin.physics.equilibrium's continuation and Jacobian)."""
    kin = config.analysis.kin
    acts = {a.name for a in mech.actuators}
    given = {kin.hinges[a].name: v for a, v in config.angles.items()}
    given |= {n: v for n, v in config.drives.items() if n in acts}
    system = physical_equilibrium.build(
        mech, config.params, given, plate_stiffness(mech, "equilibrium"), _float
    )
    try:
        u, _ = physical_equilibrium.continuation(system, "the equilibrium", mech.path, mech.units)
        jac = system.jacobian(u, 1.0, physical_equilibrium.RULES.series_tol)[0]
        return physical_modes.equilibrium_compliance(system, u, jac, names)
    except np.linalg.LinAlgError:
        # as symkin eval: inextensible plates leave a redundant loop's forces undetermined
        raise AssemblyError(
            f"{mech.path}: the equilibrium level cannot solve this mechanism: its equations "
            "are singular (a redundant loop of inextensible elastica plates, docs/levels.md)"
        ) from None


def _float(expr: object) -> float:
    value = float(sp.N(expr, 20))
    if not math.isfinite(value):
        raise AssemblyError(f"a value is not finite: {expr}")
    return value
