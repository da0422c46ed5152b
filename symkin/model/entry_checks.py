"""What the mechanism file reader checks an entry with: where an entry or a key is in the TOML
text (tomllib keeps no positions), its keys, text, names, expressions, finite numbers and
vectors, each problem raised as an :class:`~symkin.core.errors.InputError` naming the file, the
line, the entry and the fix. :mod:`.hinge_entries` and :mod:`.reader` build on
:class:`EntryChecks`.
"""

from __future__ import annotations

import keyword
import re
import sys
from collections.abc import Mapping, Sequence
from pathlib import Path

import mpmath
import sympy as sp

from ..core.errors import InputError, suggest
from . import expressions

MAX_NAME = 64


C_KEYWORDS = frozenset(
    [
        "auto",
        "break",
        "case",
        "char",
        "const",
        "continue",
        "default",
        "do",
        "double",
        "else",
        "enum",
        "extern",
        "float",
        "for",
        "goto",
        "if",
        "inline",
        "int",
        "long",
        "register",
        "restrict",
        "return",
        "short",
        "signed",
        "sizeof",
        "static",
        "struct",
        "switch",
        "typedef",
        "union",
        "unsigned",
        "void",
        "volatile",
        "while",
    ]
)
#: modules whose names a mechanism may not take: the generated module imports them, and a file
#: <name>.py beside a script would shadow them
SHADOWED = frozenset(sys.stdlib_module_names) | {"numpy", "symkin", "mpmath", "sympy"}


def name_problem(name: str, longest: int = MAX_NAME) -> tuple[str, str] | None:
    """(what is wrong, how to fix it) when `name` cannot name generated files and C functions,
    else None."""
    if len(name) > longest:
        return (
            f"name is {len(name)} characters long, more than {longest}",
            f"use at most {longest} characters: it names the generated files and the C functions",
        )
    if not expressions.IDENTIFIER.match(name) or name.startswith("_"):
        return (
            f"name '{name}' is not identifier-safe",
            "use letters, digits and '_' only, starting with a letter",
        )
    if keyword.iskeyword(name) or name in C_KEYWORDS or name in SHADOWED:
        return (
            f"name '{name}' is a Python or C keyword or the name of a module the generated "
            f"code imports",
            f'rename it, e.g. name = "{name}_mechanism"',
        )
    return None


def entry_name(kind: str, i: int, table: Mapping[str, object]) -> str:
    """How an error names the i-th [[kind]] entry: by number, and by name once it has one."""
    name = table.get("name")
    return f"[[{kind}]] #{i + 1}" + (f" '{name}'" if isinstance(name, str) and name else "")


class _Locator:
    """Finds the line of an entry in the TOML text (tomllib keeps no positions)."""

    def __init__(self, text: str) -> None:
        self.lines = text.splitlines()

    def header(self, array: str, index: int) -> int | None:
        pattern = re.compile(r"\s*\[\[\s*" + re.escape(array) + r"\s*\]\]")
        hits = [i + 1 for i, line in enumerate(self.lines) if pattern.match(line)]
        return hits[index] if index < len(hits) else None

    def key(self, key: str, table: str | None = None, after: int | None = None) -> int | None:
        start = after or 0
        if table is not None:
            pattern = re.compile(r"\s*\[\s*" + re.escape(table) + r"\s*\]")
            start = next((i + 1 for i, line in enumerate(self.lines) if pattern.match(line)), 0)
        keypat = re.compile(r"\s*[\"']?" + re.escape(key) + r"[\"']?\s*=")
        for i in range(start, len(self.lines)):
            if i > start and table is not None and self.lines[i].lstrip().startswith("["):
                break
            if keypat.match(self.lines[i]):
                return i + 1
        return None


class EntryChecks:
    """The reader's state (the file, its folder, the parameters read so far) and its checks."""

    def __init__(self, text: str, file: str, base_dir: Path) -> None:
        self.file = file
        self.base_dir = base_dir
        self.where = _Locator(text)
        self.names: dict[str, sp.Expr] = {}
        self.defaults: dict[sp.Symbol, sp.Expr] = {}

    # -- helpers -------------------------------------------------------------------------------
    def error(
        self,
        message: str,
        entry: str | None = None,
        line: int | None = None,
        hint: str | None = None,
    ) -> InputError:
        return InputError(message, file=self.file, line=line, entry=entry, hint=hint)

    def check_keys(
        self, table: Mapping[str, object], allowed: Sequence[str], entry: str, line: int | None
    ) -> None:
        for key in table:
            if key not in allowed:
                near = suggest(key, allowed)
                raise self.error(
                    f"unknown key '{key}'",
                    entry,
                    line if line is not None else self.where.key(key),
                    near or "allowed keys: " + ", ".join(allowed),
                )

    def expr(
        self,
        value: object,
        entry: str,
        key: str,
        line: int | None,
        names: Mapping[str, sp.Expr] | None = None,
    ) -> sp.Expr:
        """A number or an expression string, as an exact sympy expression."""
        try:
            if isinstance(value, str):
                return expressions.parse(
                    value, self.names if names is None else names, self.defaults
                )
            return expressions.number(value)  # type: ignore[arg-type]
        except expressions.ExpressionError as exc:
            raise self.error(
                f"'{key}': {exc}", entry, line, "use a number or an expression over the parameters"
            ) from None

    def finite(self, expr: sp.Expr, entry: str, key: str, line: int | None) -> sp.Expr:
        """Check that `expr` evaluates to a finite real number with the default parameters."""
        try:
            value = expressions.numeric(expr, self.defaults)
        except expressions.NotReal as exc:
            raise self.error(
                f"'{key}' does not evaluate to a finite real number ({exc})",
                entry,
                line,
                "change the expression or the parameters it uses",
            ) from None
        if abs(value) > expressions.FLOAT64_MAX:
            raise self.error(
                f"'{key}' evaluates to {mpmath.nstr(value, 6)}, beyond a float64 "
                "(|value| < 1.8e308), the generated code's number format",
                entry,
                line,
                "change the expression or the parameters it uses",
            )
        return sp.Float(value, expressions.NUMERIC_DPS)

    def text(self, table: Mapping[str, object], key: str, entry: str, line: int | None) -> str:
        """The non-empty string at `key`; missing or anything else is bad input."""
        if key not in table:
            raise self.error(f"missing required key '{key}'", entry, line, f'add {key} = "..."')
        value = table[key]
        if not isinstance(value, str) or not value.strip():
            raise self.error(
                f"'{key}' must be a non-empty string, got {value!r}",
                entry,
                line,
                f'write {key} = "..." (quoted text, not empty)',
            )
        return value

    def option_name(
        self, table: Mapping[str, object], entry: str, line: int | None, options: str
    ) -> str:
        """The `name` of an entry the command line names in `options` (--input H=V, --fix,
        --points A,B, ...): refused at read time when no option could express it (an '=' or
        ',' inside, a leading '-', blanks at either end), with the fix."""
        name = self.text(table, "name", entry, line)
        problem = None
        if name != name.strip():
            problem = "begins or ends with a blank"
        elif name.startswith("-"):
            problem = "begins with '-' (the command line reads it as an option)"
        elif "=" in name or "," in name:
            problem = "holds '=' or ',' (the command line's NAME=VALUE and A,B separators)"
        if problem is not None:
            raise self.error(
                f"name '{name}' {problem}: {options} cannot name it",
                entry,
                line,
                "use letters, digits and '_' (e.g. A0, piezo_1)",
            )
        return name

    def array_of_tables(self, data: Mapping[str, object], key: str) -> list[Mapping[str, object]]:
        value = data.get(key, [])
        if not isinstance(value, list) or not all(isinstance(t, dict) for t in value):
            raise self.error(
                f"'{key}' must be an array of tables written as [[{key}]]",
                f"[[{key}]]",
                self.where.key(key),
                f"write each entry as a [[{key}]] table (docs/file-format.md)",
            )
        return value

    def unique(self, kind: str, names: list[str], lines: list[int | None]) -> None:
        seen: dict[str, int] = {}
        for i, name in enumerate(names):
            if name in seen:
                raise self.error(
                    f"duplicate {kind} name '{name}' (also {kind} #{seen[name] + 1})",
                    f"[[{kind}]] #{i + 1} '{name}'",
                    lines[i],
                    f"give every {kind} its own name",
                )
            seen[name] = i

    def vector(
        self, value: object, entry: str, key: str, line: int | None
    ) -> tuple[sp.Expr, sp.Expr]:
        if not isinstance(value, list) or len(value) != 2:
            raise self.error(
                f"'{key}' must be a list of two coordinates [x, y], got {value!r}",
                entry,
                line,
                f"write {key} = [x, y] with two numbers or expressions",
            )
        vec = (self.expr(value[0], entry, key, line), self.expr(value[1], entry, key, line))
        for v in vec:
            self.finite(v, entry, key, line)
        return vec
