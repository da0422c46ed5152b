"""The result of a physical level: the kinematic levels' Evaluation plus the plates' end loads, the
elastic energy and the solver's own error estimate (CONTRACT §7 `eval --json`)."""

from __future__ import annotations

from dataclasses import dataclass, field

from ..analysis import Evaluation


@dataclass(frozen=True)
class HingeLoad:
    """What link M exerts on the plate at its M end: force (N, frame axes), moment (N·m, CCW,
    about M's clamp). A pin carries no moment."""

    force: tuple[float, float]
    moment: float


@dataclass(frozen=True)
class PhysicalEvaluation(Evaluation):
    """Evaluation at `equilibrium` or `loaded`: adds `hinges`, `energy` (J) and `error_estimate`
    (`equilibrium`: an estimate of the largest relative numerical error of the points'
    deviations; None for `loaded`, a closed form evaluated at 40 digits)."""

    hinges: dict[str, HingeLoad] = field(default_factory=dict)
    energy: float = 0.0
    error_estimate: float | None = None

    def as_json(self) -> dict:
        data = super().as_json()
        data["hinges"] = {name: {"moment": h.moment, "force": list(h.force)}
                          for name, h in self.hinges.items()}
        data["energy"] = self.energy
        if self.error_estimate is not None:
            data["error_estimate"] = self.error_estimate
        return data

    def text(self) -> str:
        """Plain-text lines that follow the points in `symkin eval` (the plates' loads)."""
        lines = ["", "plate loads (on the plate at its M end, by link M)        moment (N m)"]
        for name, h in self.hinges.items():
            lines.append(f"  {name:<12s} force ({h.force[0]:.6e}, {h.force[1]:.6e}) N   "
                         f"{h.moment:.6e}")
        lines.append(f"elastic energy {self.energy:.6e} J")
        if self.error_estimate is not None:
            lines.append(f"estimated relative error of the deviations {self.error_estimate:.1e}")
        return "\n".join(lines) + "\n"
