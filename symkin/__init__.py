"""symkin: how far a flexure-hinge mechanism strays from its ideal rigid linkage, in closed form.

    mech = symkin.load("examples/four_bar.toml")     # validated Mechanism (names, exact numbers)
    s = symkin.structure(mech)                        # labeling and I, I+, Φ, Ψ = [T; 0]
    an = symkin.analyze(mech)                         # symbolic deviation at every level
    an.evaluate({"A0": 0.2}, level="exact")           # one configuration, mpmath at 40 digits
    an.evaluate({"A0": 0.2}, level="equilibrium")     # the plates as elastica (CONTRACT §7)
    an.evaluate({"A0": 0.2}, level="loaded")          # closed form with the plates' loads

The physical levels need E, thickness and width of the plates (docs/physics.md); their
derivation is symkin.physics.statics.LoadedDerivation, their solvers are in symkin.physics.
"""

from __future__ import annotations

from pathlib import Path

from .errors import AssemblyError, InputError, SymkinError
from .mechanism import Mechanism, load, loads
from .structure import Structure, build as structure

__version__ = "0.1.0"


def analyze(mechanism: Mechanism | str | Path, points: list[str] | None = None):
    """The :class:`symkin.analysis.Analysis` of a mechanism (or of the file at that path)."""
    from .analysis import Analysis

    mech = mechanism if isinstance(mechanism, Mechanism) else load(mechanism)
    return Analysis(structure(mech), points)


__all__ = ["AssemblyError", "InputError", "Mechanism", "Structure", "SymkinError", "analyze",
           "load", "loads", "structure", "__version__"]
