"""The Jinja2 environment every emitter and report shares (templates ship in the wheel)."""

from __future__ import annotations

from functools import cache
from importlib import resources

import jinja2

#: Jinja delimiters for LaTeX templates (SymForce style), so TeX's braces never clash with Jinja's.
LATEX_DELIMITERS = {
    "block_start_string": r"\BLOCK{",
    "block_end_string": "}",
    "variable_start_string": r"\VAR{",
    "variable_end_string": "}",
    "comment_start_string": r"\#{",
    "comment_end_string": "}",
}


@cache
def environment(latex: bool = False) -> jinja2.Environment:
    """Strict environment over the packaged templates: a missing variable is an error, not ''.
    `latex=True` uses the \\VAR{...} / \\BLOCK{...} delimiters of the LaTeX templates."""
    root = resources.files("symkin.templates")
    env = jinja2.Environment(
        loader=jinja2.FileSystemLoader(str(root)),
        undefined=jinja2.StrictUndefined,
        trim_blocks=True,
        lstrip_blocks=True,
        keep_trailing_newline=True,
        autoescape=False,
        **(LATEX_DELIMITERS if latex else {}),
    )
    # Names from a mechanism file reach generated code only through these escaping filters.
    env.filters["pyrepr"] = repr
    env.filters["cstring"] = c_string
    return env


def c_string(text: str) -> str:
    """A C string literal for any text: printable ASCII kept, everything else escaped."""
    out = []
    for byte in text.encode("utf-8"):
        ch = chr(byte)
        if ch in '"\\?':
            out.append("\\" + ch)
        elif 32 <= byte < 127:
            out.append(ch)
        else:
            out.append(f"\\{byte:03o}")
    return '"' + "".join(out) + '"'


def render(template: str, **context: object) -> str:
    """Render `template` (a path under templates/) with `context`."""
    return environment().get_template(template).render(**context)
