"""The Jinja2 environment every emitter and report shares (templates ship in the wheel)."""

from __future__ import annotations

from functools import cache
from importlib import resources

import jinja2


@cache
def environment() -> jinja2.Environment:
    """Strict environment over the packaged templates: a missing variable is an error, not ''."""
    root = resources.files("symkin.templates")
    return jinja2.Environment(
        loader=jinja2.FileSystemLoader(str(root)),
        undefined=jinja2.StrictUndefined,
        trim_blocks=True,
        lstrip_blocks=True,
        keep_trailing_newline=True,
        autoescape=False,
    )


def render(name: str, **context: object) -> str:
    """Render the template `name` (a path under templates/) with `context`."""
    return environment().get_template(name).render(**context)
