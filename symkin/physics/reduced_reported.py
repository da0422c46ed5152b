"""What the `loaded` level reports beyond the deviations (docs/physics.md, "What loaded
reports"), from the reduced equilibrium's solution (symkin.physics.reduced) and its Jacobian J:
the quantities `equilibrium` reports (symkin.physics.reported), in the same units.

- every input's actuator moment (a tree hinge's moment balance of the links beyond it, an input
  chord's plate moment less its μ) and dM/dθ: the input enters as its compliant angle beyond
  the rigid one, δ_in (zero at the solution; the equations depend on the compliant angles only),
  so dM/dθ = dM/dδ_in along dx = −J⁻¹ ∂R/∂δ_in, the other inputs held;
- every point's 3×3 compliance C = d(ΔX, ΔY, Δφ)/d(Fx, Fy, M) of a virtual load at the point (it
  enters the tree forces and the moment balances), the inputs held, and its stiffness K = C⁻¹,
  either None where it does not exist (symkin.physics.reported.stiffness_and_compliance);
- every plate's largest normal stress along it: its end loads (the solution's force and moment
  at M's clamp, carried to P's clamp by the plate's moment balance) shot along the plate as a
  geometrically exact beam (symkin.physics.reported.plate_stress);
- the buckling factor: continuation in the load factor t from 1 with the inputs held, until
  det J changes sign, a plate reaches its sway buckling load or Newton cannot go on (a limit
  point), located by bisection; math.inf when none up to RULES.buckling_limit.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import sympy as sp

from ..core import vectors as V
from ..core.settings import SOLVER
from ..model.expressions import substitute
from . import section_beams
from .reduced import Answer, Reduced
from .reduced_solver import _red_buckling
from .reported import plate_stress, section_stress, stiffness_and_compliance
from .result import ActuatorLoad, InputLoad, PlateStress
from .stiffness import plate_stiffness

#: The buckling search's rules (symkin.core.settings.LoadedSettings: buckling_*): it stops at
#: buckling_limit on the file's loads and locates to buckling_locate; the generated runtimes'.
RULES = SOLVER.loaded


@dataclass(frozen=True)
class Report:
    """What `loaded` reports beyond the deviations (symkin.physics.result's types)."""

    inputs: dict[str, InputLoad]
    actuators: dict[str, ActuatorLoad]
    stiffness: dict[str, list | None]
    compliance: dict[str, list | None]
    plates: dict[str, PlateStress]
    buckling: float | None  # None: the file has no loads, or the search failed (the note)
    buckling_note: str | None = None  # why the buckling search could not finish


def report(
    answer: Answer, scale: float, buckling: bool = True, search: Reduced | None = None
) -> Report:
    """The reported quantities at a solved `answer` (not refused); `scale` metres per file
    unit; `buckling` False skips the search (the loads' factor is then None); `search` the
    solver the buckling search runs on (by default the answer's)."""
    red = answer.solver
    assert red is not None
    theta = answer.theta
    values, rates = red.reported(answer.x, theta)
    names = {a: h.name for a, h in red.hinges.items()}
    inputs = {}
    for k, a in enumerate(red.inputs):
        inputs[names[a]] = InputLoad(
            float(theta[a]), float(values[k]) * scale, float(rates[k, k]) * scale
        )
    actuators = {}
    for k, (name, *_, drive) in enumerate(red.acts):
        j = len(red.inputs) + k
        value, rate = float(values[j]), float(rates[j, j])
        reference = answer.strokes.get(name, 0.0)
        spring = red.springs[k]
        if drive == "stroke" and spring is not None:  # the command less the spring's give
            actual = reference - value / float(spring)
            actuators[name] = ActuatorLoad(actual, value, rate, reference)
        elif drive == "stroke":
            actuators[name] = ActuatorLoad(reference, value, rate)
        else:  # the stroke beyond the reference's, and its rate by the force
            stiff = 1 / rate if rate != 0 else math.inf
            actuators[name] = ActuatorLoad(reference + value, float(theta[name]), stiff)
    stiffness: dict[str, list | None] = {}
    compliance: dict[str, list | None] = {}
    first = len(red.inputs) + len(red.acts)
    # the scales to judge C's conditioning by (a lone hinge has no distance between hinges)
    L = max(red.L, red.lmin)
    F = max([float(d["EI"]) / (float(d["l"]) * L) for d in red.plate.values()] or [1.0])
    for k, name in enumerate(sorted(red.points)):
        link = red.points[name][0]
        rows = slice(first + 3 * k, first + 3 * k + 3)
        if link == 0:  # a point of the frame does not move
            stiffness[name], compliance[name] = None, np.zeros((3, 3)).tolist()
        else:
            stiffness[name], compliance[name] = stiffness_and_compliance(rates[rows, rows], L, F)
    loaded = red.loads or red.forces  # a force actuator is a load (scaled with the file's)
    factor, note = None, None
    if buckling and loaded:
        # a side output: its failure loses nothing else (docs/physics.md, "Overloads and
        # buckling": side outputs never lose the main answer); the search is bounded by its
        # steps, so the same input fails the same
        try:
            factor = buckling_factor(answer, solver=search)
        except (ArithmeticError, ValueError, np.linalg.LinAlgError) as exc:
            note = f"the buckling search failed ({type(exc).__name__}: {exc})"
    return Report(inputs, actuators, stiffness, compliance, plates(answer), factor, note)


def plates(answer: Answer) -> dict[str, PlateStress]:
    """Every plate's largest stress from its end loads at the solution."""
    red = answer.solver
    assert red is not None
    mech = red.kin.mechanism
    values = red._values_subs
    stiff = plate_stiffness(mech, "loaded", notches=True)
    hinge = {h.name: h for h in mech.hinges}
    clamps = red.clamps(answer.x, answer.theta)
    out = {}
    for a, (px, py, mx, my, turn) in clamps.items():
        name = red.hinges[a].name
        d = red.plate[a]
        ei, length = float(d["EI"]), float(d["l"])
        nx, ny, mom = answer.hinge_loads[name]
        # the moment P exerts on the plate at P's clamp, from the plate's moment balance
        m_p = mom + V.cross((mx - px, my - py), (nx, ny))
        lx, ly = V.rot(-(turn + float(d["alpha"])), (nx * length**2 / ei, ny * length**2 / ei))
        s = stiff[name]
        reissner = s.stretches
        slender = math.sqrt(float(sp.N(substitute(s.section.slender_squared(), values), 20)))
        h = hinge[name]
        limit = None
        if h.allowable_stress is not None:
            limit = float(sp.N(substitute(h.allowable_stress, values), 20))
        if d["terms"] is not None:  # a notch: the shot of equilibrium's stress, K_t
            # (docs/physics.md, "Notch hinges at `equilibrium`") under the same end loads
            grid = section_beams.grid_of(s.section, values, reissner)
            ratio = ei / float(grid.EI0)  # the loads in units of the grid's EI₀
            kt = float(sp.N(substitute(s.section.stress_factor(), values), 20))
            out[name] = section_stress(
                (m_p * length / float(grid.EI0), float(lx) * ratio, float(ly) * ratio),
                grid,
                kt,
                float(sp.N(substitute(s.section.modulus(), values), 20)),
                limit,
            )
            continue
        out[name] = plate_stress(
            (m_p * length / ei, float(lx), float(ly)),
            float(d["ea"]) if reissner else None,
            float(d["es"]) if reissner else None,
            slender,
            float(sp.N(substitute(s.section.modulus(), values), 20)),
            limit,
        )
    return out


def buckling_factor(answer: Answer, solver: Reduced | None = None) -> float:
    """The smallest factor t ≥ 1 on the file's loads, the inputs held, at which det J changes
    sign, a plate reaches its sway buckling load (the plate relation's pole) or the path ends
    in a limit point (Newton fails ever closer to it); math.inf when none up to
    RULES.buckling_limit: the shared solver's search (symkin.physics.reduced_solver's
    _red_buckling, the generated numpy modules' too) on a batch of one. `solver`: the answer's
    derivation in other kernels (float64: tens of solves)."""
    red = solver or answer.solver
    assert red is not None
    sy = red.system
    x = np.asarray(answer.x, dtype=float)[:, None]
    with np.errstate(all="ignore"):  # NaN where an evaluation failed: a failed step
        return float(_red_buckling(sy, x, sy.column(answer.theta), [])[0])
