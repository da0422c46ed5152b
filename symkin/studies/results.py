"""What one evaluated configuration reports (`symkin eval`, docs/cli.md): every point's rigid
and compliant position and deviation, every link's rotation, the sensitivities and, at the
physical levels, the plates' loads, stresses and stiffness (docs/physics.md)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field, replace

from ..core import levels
from ..physics.result import ActuatorLoad, HingeLoad, InputLoad, PlateStress


@dataclass(frozen=True)
class PointResult:
    rigid: tuple[float, float]
    compliant: tuple[float, float]
    deviation: tuple[float, float]

    @property
    def norm(self) -> float:
        """|ΔR|, the length of the deviation (NaN where it has none: beyond the rigid reach)."""
        return math.hypot(*self.deviation)


def _finite(value: float) -> float | None:
    """A JSON number, or null for NaN (no deviation beyond the rigid reach)."""
    return None if math.isnan(value) else value


Pair = tuple[float, float]


@dataclass(frozen=True)
class Sensitivity:
    """Total derivatives at one configuration (docs/sensitivity.md): per point, per parameter
    (file order) or input hinge, the derivative of (x, y) of the deviation and of the rigid
    position. A parameter whose default reads others carries them along."""

    deviation: dict[str, dict[str, Pair]]  # P -> parameter -> d(dx, dy)/dp
    deviation_inputs: dict[str, dict[str, Pair]]  # P -> input hinge -> d(dx, dy)/dθ
    rigid: dict[str, dict[str, Pair]]  # P -> parameter -> d(x, y)/dp, rigid
    rigid_inputs: dict[str, dict[str, Pair]]

    def as_json(self) -> dict:
        """The keys `eval --sensitivity --json` adds (docs/cli.md)."""

        def lists(table: dict) -> dict:
            return {p: {k: list(v) for k, v in row.items()} for p, row in table.items()}

        return {
            "sensitivity": lists(self.deviation),
            "sensitivity_inputs": lists(self.deviation_inputs),
            "rigid_sensitivity": lists(self.rigid),
            "rigid_sensitivity_inputs": lists(self.rigid_inputs),
        }

    @classmethod
    def from_columns(
        cls, points: Sequence[str], params: Sequence[str], inputs: Sequence[str], deviation, rigid
    ) -> Sensitivity:
        """From arrays indexed [point][variable][component], variables = params then inputs."""
        n = len(params)

        def table(data, names, offset) -> dict:
            return {
                p: {
                    v: (float(data[i][offset + k][0]), float(data[i][offset + k][1]))
                    for k, v in enumerate(names)
                }
                for i, p in enumerate(points)
            }

        return cls(
            table(deviation, params, 0),
            table(deviation, inputs, n),
            table(rigid, params, 0),
            table(rigid, inputs, n),
        )


@dataclass(frozen=True)
class LinkResult:
    """A link's rotation from the as-fabricated pose (radians): rigid (wrapped to (−π, π]),
    compliant = rigid + deviation, and the deviation itself, computed from δ directly."""

    rigid: float
    compliant: float
    deviation: float


@dataclass(frozen=True)
class Evaluation:
    """One configuration evaluated at one level (the `eval --json` of docs/cli.md via
    :meth:`as_json`)."""

    level: str
    backend: str
    inputs: dict[str, float]
    angles_rigid: dict[str, float]
    angles_compliant: dict[str, float]
    points: dict[str, PointResult]
    dyads: tuple[dict, ...] = field(default=())
    params: dict[str, float] = field(default_factory=dict)  # every parameter's value used
    overrides: tuple[str, ...] = ()  # the ones given with --param
    links: dict[str, LinkResult] = field(default_factory=dict)  # every link's rotation
    sensitivity: Sensitivity | None = None  # with eval --sensitivity
    # The physical levels (docs/physics.md): each plate's end load, the elastic energy (J) and,
    # at `equilibrium`, the solver's estimate of the deviations' largest relative error.
    hinges: dict[str, HingeLoad] = field(default_factory=dict)
    energy: float | None = None
    error_estimate: float | None = None
    # At `equilibrium` (docs/physics.md, "What equilibrium reports"): every input's actuator
    # moment and stiffness, every point's 3×3 tangent stiffness and compliance with the inputs
    # held (None where it does not exist: K of a point held rigidly in some direction, C of one
    # free in some direction), every plate's largest stress, and with loads their first
    # buckling factor (math.inf: none up to physics.equilibrium.BUCKLING_LIMIT) and the hinge
    # that buckles.
    actuation: dict[str, InputLoad] = field(default_factory=dict)
    # every actuator's stroke, force and dF/ds (docs/physics.md)
    actuators: dict[str, ActuatorLoad] = field(default_factory=dict)
    stiffness: dict[str, list | None] = field(default_factory=dict)
    compliance: dict[str, list | None] = field(default_factory=dict)
    plates: dict[str, PlateStress] = field(default_factory=dict)
    buckling: float | None = None
    buckling_hinge: str | None = None
    buckling_note: str | None = None  # why the buckling search could not finish (factor None)
    units: str = "m"  # the file's length unit (the stiffness's unit)
    # The physical levels' model error per point (docs/physics.md, "Model error"): relative to
    # |ΔR|, an estimate of the level's beam theory against a continuum, and its parts.
    model_error: dict[str, float] = field(default_factory=dict)
    model_error_parts: dict[str, dict[str, float]] = field(default_factory=dict)
    # Beyond the rigid reach (docs/physics.md): why the points' rigid positions and deviations
    # (and the rigid angles and links' deviations) are NaN, the compliant ones reported.
    deviation_note: str | None = None

    def beyond_reach(self, note: str) -> Evaluation:
        """This evaluation where no pose of the rigid linkage reaches the stroke a force actuator
        produced (docs/physics.md, "Beyond the rigid reach"): the compliant positions, angles and
        rotations kept, the rigid ones and the deviations NaN (JSON null) with `note`, no model
        error (it is relative to the deviation)."""
        nan = math.nan
        return replace(
            self,
            points={
                n: PointResult((nan, nan), p.compliant, (nan, nan)) for n, p in self.points.items()
            },
            angles_rigid=dict.fromkeys(self.angles_rigid, nan),
            links={n: LinkResult(nan, r.compliant, nan) for n, r in self.links.items()},
            model_error={},
            model_error_parts={},
            deviation_note=note,
        )

    def directional(self, point: str) -> list[float | None] | None:
        """The point's stiffness along x, y and in rotation, each with the other two directions
        free (no force or moment in them; the inputs held): 1/C_ii (N per file unit, N per file
        unit, N·unit/rad), None in a direction held rigidly (C_ii = 0); None without a
        compliance (the held mechanism free in some direction)."""
        c = self.compliance.get(point)
        if c is None:
            return None
        return [None if c[i][i] == 0 else 1.0 / c[i][i] for i in range(3)]

    def as_json(self) -> dict:
        """The `eval --json` document (docs/cli.md; the physical levels' keys: docs/physics.md)."""
        extra = self.sensitivity.as_json() if self.sensitivity is not None else {}
        physical = {}
        if levels.get(self.level).needs_stiffness:
            physical = {
                "hinges": {
                    name: {"moment": h.moment, "force": list(h.force)}
                    for name, h in self.hinges.items()
                },
                "energy": self.energy,
            }
            if self.error_estimate is not None:
                physical["error_estimate"] = self.error_estimate
            if self.actuation:
                physical["inputs"] = {
                    name: {"angle": a.angle, "moment": a.moment, "stiffness": a.stiffness}
                    for name, a in self.actuation.items()
                }
            if self.actuators:
                physical["actuators"] = {
                    name: ({} if a.command is None else {"command": a.command})
                    | {"stroke": a.stroke, "force": a.force, "stiffness": a.stiffness}
                    for name, a in self.actuators.items()
                }
            if self.stiffness:
                physical["stiffness"] = dict(self.stiffness)
            if self.compliance:
                physical["compliance"] = dict(self.compliance)
            if self.plates:
                physical["plates"] = {
                    name: {"stress": p.stress, "strain": p.strain, "safety": p.safety}
                    for name, p in self.plates.items()
                }
            if self.buckling is not None:
                # JSON has no infinity: null is "none up to the factor searched"
                physical["buckling"] = self.buckling if math.isfinite(self.buckling) else None
            elif self.buckling_note is not None:
                physical["buckling"] = None
                physical["buckling_note"] = self.buckling_note
        return {
            "level": self.level,
            "backend": self.backend,
            "inputs": dict(self.inputs),
            "params": dict(self.params),
            "angles": {
                "rigid": {n: _finite(v) for n, v in self.angles_rigid.items()},
                "compliant": dict(self.angles_compliant),
            },
            "points": {name: self._point_json(name, p) for name, p in self.points.items()},
            "links": {
                name: {
                    "rigid": _finite(r.rigid),
                    "compliant": r.compliant,
                    "deviation": _finite(r.deviation),
                }
                for name, r in self.links.items()
            },
            "dyads": [dict(d) for d in self.dyads],
            **extra,
        } | physical

    def _point_json(self, name: str, p: PointResult) -> dict:
        """One point of `eval --json`: beyond the rigid reach its rigid position, deviation and
        norm null and its `deviation_note` (docs/physics.md)."""
        if self.deviation_note is not None:
            return {
                "rigid": None,
                "compliant": list(p.compliant),
                "deviation": None,
                "norm": None,
                "deviation_note": self.deviation_note,
            }
        return {
            "rigid": list(p.rigid),
            "compliant": list(p.compliant),
            "deviation": list(p.deviation),
            "norm": p.norm,
        } | ({"model_error": self.model_error[name]} if name in self.model_error else {})
