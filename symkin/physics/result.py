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
