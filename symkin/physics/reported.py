"""What the `equilibrium` level reports beyond the deviations (docs/physics.md, "What equilibrium
reports"), from a converged solution u of symkin.physics.equilibrium's System and its Jacobian J:

- every input hinge's actuator moment (an unknown of the system) and its stiffness dM/dθ: the
  input's row of R(u) = 0 is φ_M − φ_P − θ = 0, so du/dθ = J⁻¹ e_row and dM/dθ is the moment
  unknown's entry, the other inputs held (their rows stay);
- every point's 3×3 compliance C = d(ΔX, ΔY, Δφ)/d(Fx, Fy, M) under a virtual load at the point
  (it enters the point's link's balance rows only) and its tangent stiffness K = C⁻¹, the inputs
  held: the equilibrium's own Jacobian, with the loads' and the plates' geometric stiffness;
  either is None where it does not exist (:func:`stiffness_and_compliance`);
- every plate's largest normal stress along it, |N|/A + |M| t/(2I) = E'(|ψ'| t/(2l) + |f_N| t²/
  (12 l²)) in the plate's scaled loads, the plate shot again (symkin.physics.beams) to sections
  along it (a sub-plate of length σl has loads k0 σ, λ σ² and compliances over σ²).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any, Protocol

import numpy as np

from ..core.settings import SOLVER
from . import beams, section_beams
from .result import ActuatorLoad, InputLoad, PlateStress
from .stiffness_rule import _stiffness_compliance


class System(Protocol):
    """What these functions read of symkin.physics.equilibrium.System (which imports this
    module): its hinges, the unknowns' index and size, the points, the scales and `place`."""

    hinges: Sequence[Any]
    index: dict
    size: int
    points: dict
    L: Any
    F: Any

    def place(self, u: np.ndarray, i: int, p0: tuple) -> tuple: ...


#: Sections per plate where the stress is sampled (both ends exact; an interior maximum, e.g. of
#: a buckled plate, is refined by a parabola through the three samples around it), and how
#: ill-conditioned a point's scaled compliance is singular (:func:`stiffness_and_compliance`)
#: (symkin.core.settings.LoadedSettings: sections, singular; `loaded`'s reports read them too).
SECTIONS = SOLVER.loaded.sections
SINGULAR = SOLVER.loaded.singular


def _rows(system: System) -> tuple[dict[str, int], int]:
    """The row of every input hinge's equation, and the first row of the links' balances
    (System.residual's order: hinges, inputs, link balances)."""
    row = sum(3 if h.plate else 2 for h in system.hinges)
    inputs = {}
    for h in system.hinges:
        if h.theta is not None:
            inputs[h.name] = row
            row += 1
    # a stroke actuator's row follows the inputs' (symkin.physics.equilibrium.System.residual)
    row += sum(1 for a in getattr(system, "actuators", ()) if a.stroke)
    return inputs, row


def inputs(system: System, u: np.ndarray, jac: np.ndarray, scale: float) -> dict[str, InputLoad]:
    """Angle, actuator moment (N·m; `scale` metres per file unit) and dM/dθ of every input."""
    rows, _ = _rows(system)
    unit = float(system.F) * float(system.L) * scale  # the moment unknown's unit, in N·m
    out = {}
    for h in system.hinges:
        if h.theta is None:
            continue
        k = system.index["tau:" + h.name]
        e = np.zeros(system.size)
        e[rows[h.name]] = 1.0  # −∂R/∂θ: the row is φ_M − φ_P − θ
        du = np.linalg.solve(jac, e)
        out[h.name] = InputLoad(float(h.theta), float(u[k]) * unit, float(du[k]) * unit)
    return out


def actuators(system: System, u: np.ndarray, jac: np.ndarray) -> dict[str, ActuatorLoad]:
    """Stroke, force (N) and dF/ds (N per file unit) of every actuator: the derivative of the
    solution by the actuator's value, du/dv = −J⁻¹ ∂R/∂v (∂R/∂v by the complex step on v, the
    other inputs held), gives the force unknown's rate (a stroke) or the stroke's (a force)."""
    out = {}
    step = 1e-30
    for a in getattr(system, "actuators", ()):
        value = a.value
        try:
            a.value = float(value) + 1j * step
            dr = system.residual(u.astype(complex)[:, None], np.ones(1), 1e-18)[:, 0]
        finally:
            a.value = value
        du = np.linalg.solve(jac, -dr.imag / step)
        stroke = float(np.real(system.stroke(u[:, None], a)[0]))
        moved = u.astype(complex) + 1j * step * du
        rate = float(np.imag(system.stroke(moved[:, None], a)[0])) / step
        if a.stroke:
            force = float(u[system.index["act:" + a.name]]) * float(system.F)
            out[a.name] = ActuatorLoad(
                stroke,
                force,
                float(du[system.index["act:" + a.name]]) * float(system.F),
                None if a.spring is None else float(value),
            )
        else:
            out[a.name] = ActuatorLoad(stroke, float(value), 1.0 / rate if rate else float("inf"))
    return out


def stiffness_and_compliance(
    compliance: np.ndarray, length: float, force: float, singular: float = SINGULAR
) -> tuple[list | None, list | None]:
    """(K, C) of a point from its compliance C (3×3 in the file's unit; rows ΔX, ΔY, Δφ, columns
    Fx, Fy, M), K = C⁻¹, either None where it does not exist (docs/physics.md, "What
    equilibrium reports"). C is judged in the plates' scales, S = C scaled by `length` L and
    `force` F to be dimensionless (a plate's bending compliance is of order 1 there): with
    ‖·‖ the 1-norm, S is singular where ‖S‖ ‖S⁻¹‖ exceeds `singular` (or S⁻¹ does not
    exist). Then the outlier decides which one does not exist: ‖S‖ ≤ ‖S⁻¹‖, a direction far
    stiffer than the plates (a point of the frame, of a link the held inputs, pins or a stroke
    hold rigidly in some direction, e.g. a fixed–guided plate's end whose rotation its input
    holds): K is None, and C's entries within ‖S‖/`singular` of zero (rounding) are exactly 0;
    else a direction far softer (the held mechanism free in it, at a buckling point): C is
    None. A C not finite gives (None, None). The rule is symkin.physics.stiffness_rule's, which
    the generated numpy modules hold too; templates/c/reduced_report.c's is its C twin."""
    c = np.asarray(compliance, dtype=float)
    rows = np.array([force / length, force / length, force])
    cols = np.array([1.0, 1.0, 1.0 / length])
    stiff, comp = _stiffness_compliance(c[None], (rows, cols), singular)
    k = None if np.isnan(stiff[0]).all() else stiff[0].tolist()
    return k, None if np.isnan(comp[0]).all() else comp[0].tolist()


def point_stiffness(
    system: System, u: np.ndarray, jac: np.ndarray
) -> tuple[dict[str, list | None], dict[str, list | None]]:
    """The 3×3 tangent stiffness and compliance of every point (file unit: K in N/unit, N,
    N·unit, C in unit/N, 1/N, 1/(N·unit); rows and columns x, y, rotation), each None where
    it does not exist (:func:`stiffness_and_compliance`); a point of the frame has C = 0."""
    _, balance = _rows(system)
    L, F = float(system.L), float(system.F)
    stiffness: dict[str, list | None] = {}
    compliances: dict[str, list | None] = {}
    for name, (link, at) in system.points.items():
        if link < 0:
            stiffness[name], compliances[name] = None, np.zeros((3, 3)).tolist()
            continue
        x, y = (float(v) for v in system.place(u, link, at))
        ox, oy = float(u[3 * link]) * L, float(u[3 * link + 1]) * L  # the link's origin now
        # ∂R/∂(Fx, Fy, M) of a load at (x, y): the link's rows Σfx/F, Σfy/F, Σm/(F L)
        load = np.zeros((system.size, 3))
        r = balance + 3 * link
        load[r, 0] = load[r + 1, 1] = 1 / F
        load[r + 2] = (-y / (F * L), x / (F * L), 1 / (F * L))
        du = -np.linalg.solve(jac, load)
        dphi = du[3 * link + 2]
        compliance = np.array(
            [
                L * du[3 * link] - (y - oy) * dphi,
                L * du[3 * link + 1] + (x - ox) * dphi,
                dphi,
            ]
        )
        stiffness[name], compliances[name] = stiffness_and_compliance(compliance, L, F)
    return stiffness, compliances


def plates(
    system: System,
    u: np.ndarray,
    moduli: Mapping[str, float],
    allowable: Mapping[str, float | None],
    sections: int = SECTIONS,
) -> dict[str, PlateStress]:
    """Largest normal stress (Pa), its strain and the safety factor of every plate; `moduli`:
    E' of each plate (Pa), `allowable`: its allowable stress (Pa) or None."""
    out = {}
    for h in system.hinges:
        if not h.plate:
            continue
        k = system.index[h.name]
        k0, lx, ly = (float(u[k + j]) for j in range(3))
        if h.grid is not None:
            out[h.name] = notch_stress((k0, lx, ly), h, moduli[h.name], allowable.get(h.name))
            continue
        out[h.name] = plate_stress(
            (k0, lx, ly),
            h.stretch,
            h.shear,
            float(h.slender),
            moduli[h.name],
            allowable.get(h.name),
            sections,
        )
    return out


def notch_stress(
    loads: tuple[float, float, float], hinge, modulus: float, limit: float | None
) -> PlateStress:
    """A notch's largest normal stress (Pa): E' times its largest strain along the hinge,
    |ψ'| T/(2l) + |N|/EA at the nodes of its shot (physics.section_beams), times its
    stress-concentration factor K_t (model.notches.Notch.stress_factor, docs/physics.md)."""
    return section_stress(loads, hinge.grid, hinge.kt, modulus, limit)


def section_stress(
    loads: tuple[float, float, float],
    grid: section_beams.SectionGrid,
    kt: float,
    modulus: float,
    limit: float | None,
) -> PlateStress:
    """:func:`notch_stress` of a section's `grid` (physics.section_beams) and K_t: the loads
    (k0, λx, λy) = (m_P l/EI₀, n l²/EI₀ in P's plate frame), EI₀ the grid's."""
    k0, lx, ly = loads
    end = section_beams.shoot_profile(
        np.array([k0]), np.array([lx]), np.array([ly]), grid, strain=True
    )
    stress = modulus * end.bend * kt
    safety = None if limit is None else (limit / stress if stress > 0 else float("inf"))
    return PlateStress(stress, end.bend * kt, safety, end.where)


def plate_stress(
    loads: tuple[float, float, float],
    stretch: float | None,
    shear: float | None,
    slender: float,
    modulus: float,
    limit: float | None,
    sections: int = SECTIONS,
) -> PlateStress:
    """One plate's largest normal stress (Pa) from `loads` (k0, λx, λy) = (m_P l/EI, n l²/EI in
    P's plate frame), its compliances (None: an elastica), t/l and E' (Pa), shot to `sections`
    sections; `limit` its allowable stress (Pa) or None."""
    k0, lx, ly = loads
    frac = np.arange(1, sections + 1) / sections
    stretch_s = None if stretch is None else float(stretch) / frac**2
    shear_s = None if shear is None else float(shear) / frac**2
    end = beams.shoot(k0 * frac, lx * frac**2, ly * frac**2, 1e-18, False, stretch_s, shear_s)
    psi = np.concatenate([[0.0], end.psi])
    curvature = np.concatenate([[k0], end.omega / frac])  # ψ'(s) in units of 1/l
    normal = lx * np.cos(psi) + ly * np.sin(psi)  # f_N = N l²/EI
    strain = np.abs(curvature) * slender / 2 + np.abs(normal) * slender**2 / 12
    j = int(np.argmax(strain))
    value, where = float(strain[j]), j / sections
    if 0 < j < sections:
        # the parabola's vertex through the three samples around an interior maximum
        a, b, c = strain[j - 1], strain[j], strain[j + 1]
        bend = a - 2 * b + c
        if bend < 0:
            shift = (a - c) / (2 * bend)
            value = float(b - (a - c) * shift / 4)
            where = float((j + shift) / sections)
    stress = modulus * value
    safety = None if limit is None else (limit / stress if stress > 0 else float("inf"))
    return PlateStress(stress, value, safety, where)
