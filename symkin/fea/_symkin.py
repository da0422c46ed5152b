"""Everything symkin.fea takes from the rest of symkin, in one place.

The finite-element check is a client of the mechanism reader, the error types, the plates'
sections (their outline) and the public evaluation API only; when those modules move, this file
is the one line that changes.
"""

from __future__ import annotations

from .. import analyze, evaluate
from ..core.errors import AssemblyError, InputError
from ..model.mechanism import Mechanism, Point, load
from ..model.profiles import section_of

__all__ = [
    "AssemblyError",
    "InputError",
    "Mechanism",
    "Point",
    "analyze",
    "evaluate",
    "load",
    "section_of",
]
