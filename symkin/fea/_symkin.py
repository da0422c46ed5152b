"""Everything symkin.fea takes from the rest of symkin, in one place.

The finite-element check is a client of the mechanism reader, the error types, the plates'
sections (their outline) and the public evaluation API only; when those modules move, this file
is the one line that changes.
"""

from __future__ import annotations

from .. import analyze, evaluate
from ..core.errors import AssemblyError, InputError
from ..model.entries import Point
from ..model.mechanism import Mechanism
from ..model.profiles import section_of
from ..model.reader import load

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
