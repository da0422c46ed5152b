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


def natural_modes(mechanism: Mechanism, inputs, level, params, count):
    """`symkin modes` (symkin.studies.modes.modes), imported when first asked for: the
    command line builds every parser, `fea`'s included, at each start."""
    from ..studies.modes import modes

    return modes(mechanism, inputs, level, params, count)


__all__ = [
    "AssemblyError",
    "InputError",
    "Mechanism",
    "Point",
    "analyze",
    "evaluate",
    "load",
    "natural_modes",
    "section_of",
]
