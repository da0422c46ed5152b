"""Checks of the paths a user gives (`-o DIR`, `--plot FILE`, the files read), made before any
long work starts, and writing a set of files all or none (`derive`).

A mistake in a path is bad input (exit code 2) with a `fix:` line, never an internal error after
minutes of derivation.
"""

from __future__ import annotations

import contextlib
import fcntl
import os
import shutil
import stat
import tempfile
from pathlib import Path

from .errors import InputError


class Unreadable(Exception):
    """Why an input file cannot be read (`reason`) and what to do (`hint`): the caller names the
    file and the entry in its InputError."""

    def __init__(self, reason: str, hint: str) -> None:
        super().__init__(reason)
        self.reason = reason
        self.hint = hint


def read_input(path: str | Path, limit: int) -> bytes:
    """The bytes of a regular file of at most `limit` bytes. Anything else is refused before a
    byte is read: a FIFO would block the read forever, /dev/zero (or a link to it) never ends,
    a folder or a device is not a file; a file larger than `limit`, or grown past it since its
    size was read, is refused too (raises Unreadable)."""
    try:
        # opened without blocking (a FIFO swapped in after a stat would block the open), then
        # judged by what was opened; links followed: a link to /dev/zero is a device
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK)
    except OSError as exc:
        raise Unreadable(
            f"cannot read the file ({exc.strerror or exc})", "check the path"
        ) from None
    too_large = Unreadable(
        f"larger than {limit} bytes", "a mechanism file or table needs a few kB at most"
    )
    info = os.fstat(fd)
    if not stat.S_ISREG(info.st_mode):
        os.close(fd)
        kind = "a folder" if stat.S_ISDIR(info.st_mode) else "a device, FIFO or socket"
        raise Unreadable(f"not a regular file ({kind})", "give the path of a text file")
    if info.st_size > limit:
        os.close(fd)
        raise too_large
    with os.fdopen(fd, "rb") as f:
        try:
            raw = f.read(limit + 1)
        except OSError as exc:
            raise Unreadable(
                f"cannot read the file ({exc.strerror or exc})", "check the path"
            ) from None
    if len(raw) > limit:
        raise too_large
    return raw


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
        raise InputError(
            f"'{shown}' is a file, not a folder",
            entry=option,
            hint="give a folder (it is created if missing), e.g. -o out/",
        )
    base = _existing_ancestor(target.absolute())
    if not base.is_dir():
        raise InputError(
            f"'{shown}' cannot be created: '{base}' is a file, not a folder",
            entry=option,
            hint="choose a folder outside it",
        )
    if not os.access(base, os.W_OK | os.X_OK):
        raise InputError(
            f"'{shown}' is not writable (no permission to write in '{base}')",
            entry=option,
            hint="choose a folder you can write to",
        )
    return target


def output_file(path: str | Path, option: str, suffixes: tuple[str, ...]) -> Path:
    """A file symkin may write: its folder exists and is writable, its suffix is one of
    `suffixes` (lower case, with the dot)."""
    target = Path(path)
    shown = str(path)
    if target.is_dir():
        raise InputError(
            f"'{shown}' is a folder",
            entry=option,
            hint=f"name a file inside it, e.g. {target / ('plot' + suffixes[0])}",
        )
    if target.suffix.lower() not in suffixes:
        raise InputError(
            f"'{shown}' does not end in {' or '.join(suffixes)}",
            entry=option,
            hint=f"name the file e.g. plot{suffixes[0]}",
        )
    folder = target.absolute().parent
    if not folder.is_dir():
        what = "is a file, not a folder" if folder.exists() else "does not exist"
        raise InputError(
            f"the folder '{folder}' of '{shown}' {what}",
            entry=option,
            hint="create the folder first, or write the file elsewhere",
        )
    if not os.access(folder, os.W_OK | os.X_OK) or (
        target.exists() and not os.access(target, os.W_OK)
    ):
        raise InputError(
            f"'{shown}' is not writable", entry=option, hint="choose a path you can write to"
        )
    return target


# -- writing a set of files all or none (`derive`) ---------------------------------------------

#: Temporary folders a writer stages its files in, inside the output folder (hidden).
TEMP_PREFIX = ".symkin-tmp-"
#: The commit record: present while staged files are being moved into place.
COMMIT = ".symkin-commit"


@contextlib.contextmanager
def _locked(folder: Path):
    """An exclusive lock on `folder` itself (flock on the folder): writers of one folder take
    turns, and a killed writer's lock goes with it. No lock file is left behind."""
    fd = os.open(folder, os.O_RDONLY | os.O_DIRECTORY)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)
        yield
    finally:
        os.close(fd)  # releases the lock


def _roll_forward(folder: Path) -> None:
    """Finish a commit a killed writer left (the lock held): move its staged files into place;
    then remove every stale temporary folder."""
    record = folder / COMMIT
    if record.exists():
        staged, *names = record.read_text().split("\n")
        for name in names:
            if name and (folder / staged / name).exists():
                os.replace(folder / staged / name, folder / name)
        record.unlink()
    for stale in folder.glob(TEMP_PREFIX + "*"):
        # a staging folder, or the commit record's temporary file (killed before its rename)
        if stale.is_dir() and not stale.is_symlink():
            shutil.rmtree(stale, ignore_errors=True)
        else:
            stale.unlink(missing_ok=True)


def complete_interrupted(folder: str | Path) -> None:
    """Leave `folder` as the last writer meant it: a commit interrupted by a kill is completed,
    temporary folders of killed writers are removed. Every write starts with this."""
    folder = Path(folder)
    if folder.is_dir():
        with _locked(folder):
            _roll_forward(folder)


def write_atomically(files: dict[str, bytes], out_dir: str | Path) -> list[Path]:
    """Write all `files` into `out_dir` or none, even when killed or raced by other writers.

    Under a lock on the folder: staged in full in a hidden temporary folder inside it, then a
    commit record names the staged files (one atomic rename makes it appear), the files are
    moved into place with one rename each and the record is removed. A writer killed before the
    record appears leaves the old files (its temporary folder is removed by the next write or
    :func:`complete_interrupted`); one killed after it is completed by them. Concurrent writers
    take turns: the folder holds one writer's complete set.
    """
    out_dir = Path(out_dir)
    os.makedirs(out_dir, exist_ok=True)
    with _locked(out_dir):
        _roll_forward(out_dir)
        staged = Path(tempfile.mkdtemp(prefix=TEMP_PREFIX, dir=out_dir))
        try:
            for name, content in sorted(files.items()):
                with open(staged / name, "wb") as f:
                    f.write(content)
                    f.flush()
                    os.fsync(f.fileno())
            fd, tmp = tempfile.mkstemp(prefix=TEMP_PREFIX, dir=out_dir)
            with os.fdopen(fd, "w") as f:
                f.write("\n".join([staged.name, *sorted(files)]))
                f.flush()
                os.fsync(f.fileno())
            os.replace(tmp, out_dir / COMMIT)  # the commit point
            _roll_forward(out_dir)
        finally:
            if staged.exists():
                shutil.rmtree(staged, ignore_errors=True)
    return [out_dir / name for name in sorted(files)]
