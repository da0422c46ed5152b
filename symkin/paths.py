"""Checks of the paths a user gives (`-o DIR`, `--plot FILE`), made before any long work starts.

A mistake in a path is bad input (exit code 2) with a `fix:` line, never an internal error after
minutes of derivation.
"""

from __future__ import annotations

import os
from pathlib import Path

from .errors import InputError


def _existing_ancestor(path: Path) -> Path:
    """The nearest ancestor of `path` (or `path` itself) that exists."""
    for candidate in (path, *path.parents):
        if candidate.exists():
            return candidate
    return Path(".")


def output_dir(path: str | Path, option: str) -> Path:
    """A folder symkin may create (with its parents) and write into; raise InputError if not."""
    target = Path(path)
    shown = str(path)
    if target.exists() and not target.is_dir():
        raise InputError(f"'{shown}' is a file, not a folder", entry=option,
                         hint="give a folder (it is created if missing), e.g. -o out/")
    base = _existing_ancestor(target.absolute())
    if not base.is_dir():
        raise InputError(f"'{shown}' cannot be created: '{base}' is a file, not a folder",
                         entry=option, hint="choose a folder outside it")
    if not os.access(base, os.W_OK | os.X_OK):
        raise InputError(f"'{shown}' is not writable (no permission to write in '{base}')",
                         entry=option, hint="choose a folder you can write to")
    return target


def output_file(path: str | Path, option: str, suffixes: tuple[str, ...]) -> Path:
    """A file symkin may write: its folder exists and is writable, its suffix is one of
    `suffixes` (lower case, with the dot)."""
    target = Path(path)
    shown = str(path)
    if target.is_dir():
        raise InputError(f"'{shown}' is a folder", entry=option,
                         hint=f"name a file inside it, e.g. {target / ('plot' + suffixes[0])}")
    if target.suffix.lower() not in suffixes:
        raise InputError(f"'{shown}' does not end in {' or '.join(suffixes)}", entry=option,
                         hint=f"name the file e.g. plot{suffixes[0]}")
    folder = target.absolute().parent
    if not folder.is_dir():
        what = "is a file, not a folder" if folder.exists() else "does not exist"
        raise InputError(f"the folder '{folder}' of '{shown}' {what}", entry=option,
                         hint="create the folder first, or write the file elsewhere")
    if not os.access(folder, os.W_OK | os.X_OK) or (target.exists()
                                                     and not os.access(target, os.W_OK)):
        raise InputError(f"'{shown}' is not writable", entry=option,
                         hint="choose a path you can write to")
    return target
