"""Error types that map onto the command line's exit codes (docs/cli.md).

Every error a user can cause carries the file, the entry and what to change, so the CLI can print
one or a few plain lines instead of a traceback.
"""

from __future__ import annotations

import difflib
from collections.abc import Iterable


class SymkinError(Exception):
    """Base class; exit code 1 means an internal error (a bug in symkin)."""

    exit_code = 1


class InputError(SymkinError):
    """Bad input: a mechanism file, an expression or a command-line option (exit code 2)."""

    exit_code = 2

    def __init__(
        self,
        message: str,
        *,
        file: str | None = None,
        line: int | None = None,
        entry: str | None = None,
        hint: str | None = None,
    ) -> None:
        self.message = message
        self.file = file
        self.line = line
        self.entry = entry
        self.hint = hint
        super().__init__(self.render())

    def render(self) -> str:
        where = ""
        if self.file:
            where = self.file + (f":{self.line}" if self.line else "") + ": "
        what = f"{self.entry}: " if self.entry else ""
        text = f"{where}{what}{self.message}"
        if self.hint:
            text += f"\n  fix: {self.hint}"
        return text


class PlausibilityWarning(UserWarning):
    """A result that stands but suggests a mistake in the file (its units, a degree meant as a
    radian): the command line prints it as one line (docs/cli.md)."""


class AssemblyError(SymkinError):
    """The mechanism cannot reach the requested input: out of range or no convergence (exit 3)."""

    exit_code = 3


def suggest(name: str, choices: Iterable[str]) -> str | None:
    """Return a 'did you mean' fragment for the closest of `choices`, or None."""
    close = difflib.get_close_matches(name, sorted(choices), n=1, cutoff=0.6)
    return f"did you mean '{close[0]}'?" if close else None
