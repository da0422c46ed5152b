"""Hinge models (CONTRACT §2): the names the file may use and the parameters each one takes.

A model gives (f(θ), g(θ)), the position of M's clamp in the plate frame fixed in P. This module
holds what the reader needs to validate a file; the formulas themselves are attached per model.
"""

from __future__ import annotations

from dataclasses import dataclass

#: PRBM presets (Howell): characteristic radius factor γ and stiffness/angle factor c_θ.
PRBM_PRESETS: dict[str, dict[str, str]] = {
    "force": {"gamma": "0.8517", "c_theta": "1.2385"},
    "moment": {"gamma": "0.7346", "c_theta": "1.5164"},
}


@dataclass(frozen=True)
class ModelParameter:
    """One model parameter: its kind decides how the reader checks and stores it."""

    name: str
    kind: str            # "number" (expression > 0), "fraction" (0 < x <= 1), "choice", "text", "int", "expr"
    required: bool = False
    choices: tuple[str, ...] = ()
    default: object = None


@dataclass(frozen=True)
class ModelSpec:
    """A hinge model's name, its parameters and a one-line description for reports."""

    name: str
    parameters: tuple[ModelParameter, ...]
    description: str

    def parameter(self, key: str) -> ModelParameter | None:
        return next((p for p in self.parameters if p.name == key), None)


MODELS: dict[str, ModelSpec] = {spec.name: spec for spec in (
    ModelSpec("rigid", (), "ideal revolute joint at the plate's midpoint (eq. 3.1)"),
    ModelSpec("circular_arc", (), "plate bent into a circular arc by a pure end moment"),
    ModelSpec("prbm", (
        ModelParameter("gamma", "fraction", default=PRBM_PRESETS["force"]["gamma"]),
        ModelParameter("c_theta", "number", default=PRBM_PRESETS["force"]["c_theta"]),
        ModelParameter("preset", "choice", choices=tuple(sorted(PRBM_PRESETS))),
    ), "pseudo-rigid-body model: a pin at distance (1 - gamma) l from P's clamp"),
    ModelSpec("small_deflection", (), "linear beam theory: f = l, g = l theta / 2"),
    ModelSpec("elastica_force", (),
              "cantilever elastica under a transverse end force (Bisshopp-Drucker)"),
    ModelSpec("table", (
        ModelParameter("file", "text", required=True),
        ModelParameter("degree", "int", default=3),
    ), "polynomial fit of measured (theta, f/l, g/l) rows"),
    ModelSpec("expr", (
        ModelParameter("f", "expr", required=True),
        ModelParameter("g", "expr", required=True),
    ), "user expressions in theta, l and the parameters"),
)}

#: Hinge keys that are not model parameters.
HINGE_KEYS = ("name", "links", "at", "plate_angle", "length", "model", "input")
#: Every key a model may take, over all models (allowed in [defaults]).
MODEL_KEYS = tuple(sorted({p.name for spec in MODELS.values() for p in spec.parameters}))
