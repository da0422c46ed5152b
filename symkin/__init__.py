"""symkin: how far a flexure-hinge mechanism strays from its ideal rigid linkage, in closed form.

Start with :func:`load` (a validated :class:`Mechanism`), then :func:`structure` for the paper's
labeling and structure matrices I, Φ, Ψ.
"""

from __future__ import annotations

from .errors import AssemblyError, InputError, SymkinError
from .mechanism import Mechanism, load, loads
from .structure import Structure, build as structure

__version__ = "0.1.0"

__all__ = ["AssemblyError", "InputError", "Mechanism", "Structure", "SymkinError", "load", "loads",
           "structure", "__version__"]
