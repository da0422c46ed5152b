"""Stiffness, loads and the physical levels of CONTRACT §7 (docs/physics.md).

`equilibrium`: the mechanism's plates as elastica in equilibrium with the actuators and the loads
(symkin.physics.equilibrium). The kinematic levels are in symkin.analysis.
"""

from __future__ import annotations

from collections.abc import Mapping

#: The physical levels, in the order of the C level codes that follow the kinematic ones.
LEVELS = ("loaded", "equilibrium")


def evaluate(analysis, inputs: Mapping[str, object], level: str,
             params: Mapping[str, object] | None = None):
    """One configuration at a physical level, as a result.PhysicalEvaluation."""
    from . import equilibrium, loaded

    if level == "equilibrium":
        return equilibrium.evaluate(analysis, inputs, params)
    if level == "loaded":
        return loaded.evaluate(analysis, inputs, params)
    raise ValueError(f"not a physical level: {level!r}")
