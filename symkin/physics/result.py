"""What the physical levels report per hinge beyond the kinematic ones (docs/physics.md): the end
load of each plate, for `eval`'s JSON `"hinges"` and its text."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class HingeLoad:
    """What link M exerts on the plate at its M end: force (N, frame axes), moment (N·m, CCW,
    about M's clamp). A pin carries no moment."""

    force: tuple[float, float]
    moment: float


@dataclass(frozen=True)
class ActuatorLoad:
    """What an actuator delivers at equilibrium (docs/physics.md): its stroke (file unit), the
    force it exerts on its link along its line (N) and the stiffness dF/ds (N per file unit)
    along the equilibrium path with the other inputs held (a stroke actuator: d(force)/d(stroke);
    a force actuator: the inverse of d(stroke)/d(force)). An actuator with a `spring` also
    has its `command`, the free stroke given (file unit): `stroke` is then the actual one,
    command − force/spring, and dF/ds is by the command."""

    stroke: float
    force: float
    stiffness: float
    command: float | None = None


@dataclass(frozen=True)
class InputLoad:
    """What an input hinge's actuator delivers at equilibrium: its angle (rad), the moment it
    exerts on link M (N·m, counter-clockwise; −moment on P) and the stiffness dM/dθ (N·m/rad)
    along the equilibrium path with the other inputs held."""

    angle: float
    moment: float
    stiffness: float


@dataclass(frozen=True)
class PlateStress:
    """A plate's largest normal stress (Pa; bending plus axial, |N|/A + |M| t/(2I), at its worst
    section and fibre), the strain there (σ/E', E' the plate's modulus) and, when the hinge has
    an allowable stress, the safety factor allowable/σ (None otherwise)."""

    stress: float
    strain: float
    safety: float | None = None
    section: float = 0.0  # where along the plate, 0 at P's clamp to 1 at M's

    @property
    def overloaded(self) -> bool:
        """Past its allowable stress."""
        return self.safety is not None and self.safety < 1
