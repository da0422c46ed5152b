"""Derivations kept by content (docs/cli.md, "Derivations are kept too"): a derivation is the
slow step of every command, and the same file is derived again and again (each `symkin eval
--backend c`, each test); so are the LaTeX report's reference solves (40-digit `equilibrium`).
A plan (or a reference solve) is found again by a digest of what it is derived from: the
analysis (the file's mechanism, its points, the hinge models), the options, the versions of
symkin's own source, sympy, numpy and Python. In memory for the process; on disk under the
compiled-code cache (toolchain.safe_cache_dir), written atomically and read back only when
verified as the compiled libraries are (a private regular file whose sha256 its record names).

Anything the digest cannot describe exactly (an object that is neither a dataclass, a sympy
expression, a number, a string nor a container of those) is derived, never looked up.
SYMKIN_PLAN_CACHE=memory keeps them in memory only, =off not at all (benchmarks of the
derivation use it).
"""

from __future__ import annotations

import dataclasses
import hashlib
import importlib.metadata
import os
import pickle
import sys
import weakref
from collections.abc import Callable, Iterator, Mapping, Sequence
from contextlib import contextmanager
from contextvars import ContextVar
from pathlib import Path
from typing import Any, TypeVar

import mpmath
import numpy as np
import sympy as sp

from ..core.errors import InputError
from ..core.recent import Recent
from ..kinematics.analysis import Analysis
from . import toolchain
from .plan import Plan


class _Opaque(Exception):
    """An object the digest cannot describe exactly: its plan is derived, not looked up."""


def _describe(obj: Any, out: list[str]) -> None:
    """Append an exact, deterministic description of `obj` (no ids, no hash-seed order)."""
    if obj is None or isinstance(obj, bool | int | str):
        out.append(repr(obj))
    elif isinstance(obj, float):
        out.append(obj.hex())
    elif isinstance(obj, sp.Basic | sp.MatrixBase):
        # srepr names every class and exact value; a parameter symbol and a plain symbol differ
        out.append(f"{type(obj).__name__}:{sp.srepr(obj)}")
    elif isinstance(obj, np.ndarray) and obj.dtype != object:
        out.append(f"ndarray:{obj.dtype.str}:{obj.shape}:{obj.tobytes().hex()}")
    elif dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        out.append(f"{type(obj).__module__}.{type(obj).__qualname__}(")
        for f in dataclasses.fields(obj):
            out.append(f.name + "=")
            _describe(getattr(obj, f.name), out)
        out.append(")")
    elif isinstance(obj, tuple | list):
        out.append(f"{type(obj).__name__}[")
        for item in obj:
            _describe(item, out)
        out.append("]")
    elif isinstance(obj, Mapping):
        items = []
        for k, v in obj.items():
            key: list[str] = []
            _describe(k, key)
            items.append(("".join(key), v))
        out.append("{")
        for k, v in sorted(items, key=lambda kv: kv[0]):
            out.append(k + ":")
            _describe(v, out)
        out.append("}")
    else:
        raise _Opaque(type(obj).__qualname__)


def _source_digest() -> str:
    """The digest of symkin's own Python source (as on disk now), its version and the libraries
    a plan is made of."""
    h = hashlib.sha256()
    root = Path(__file__).resolve().parent.parent
    for path in sorted(root.rglob("*.py")):
        h.update(str(path.relative_to(root)).encode() + b"\0" + path.read_bytes() + b"\0")
    try:
        version = importlib.metadata.version("symkin")
    except importlib.metadata.PackageNotFoundError:
        version = "?"
    h.update(
        f"{version} {sp.__version__} {np.__version__} {mpmath.__version__} {sys.version}".encode()
    )
    return h.hexdigest()


#: taken when symkin is imported: the code this process runs (a file edited later is not)
_CODE = _source_digest()


def _code_digest() -> str:
    return _CODE


def digest(analysis: Analysis, options: Mapping[str, Any]) -> str | None:
    """The content digest of the plan of `analysis` with `options`; None when some part of them
    cannot be described exactly."""
    out: list[str] = [_code_digest()]
    kin = analysis.kin
    try:
        _describe(analysis.mechanism, out)
        _describe(tuple(p.name for p in analysis.points), out)
        # the hinge models as the analysis has them (a variant overrides them)
        _describe([(a, kin.hinges[a]) for a in sorted(kin.hinges)], out)
        _describe(dict(options), out)
    except _Opaque:
        return None
    return hashlib.sha256("\x1f".join(out).encode()).hexdigest()


_T = TypeVar("_T")
#: the last MEMORY derivations, most recent last (a long run does not keep every plan alive)
MEMORY = 64
_MEMORY: Recent[str, Any] = Recent(MEMORY)
_NO_DISK: ContextVar[bool] = ContextVar("symkin_plan_cache_no_disk", default=False)


@contextmanager
def memory_only() -> Iterator[None]:
    """Within it plans are neither read from nor written to disk (symkin.compile leaves no
    file anywhere)."""
    token = _NO_DISK.set(True)
    try:
        yield
    finally:
        _NO_DISK.reset(token)


def _mode() -> str:
    mode = os.environ.get("SYMKIN_PLAN_CACHE", "disk")
    mode = mode if mode in ("disk", "memory", "off") else "disk"
    return "memory" if mode == "disk" and _NO_DISK.get() else mode


def _folder() -> Path | None:
    """The plans' folder in the private cache, or None where the cache is unusable (a plan is
    then derived: only compiling needs the cache)."""
    try:
        folder = toolchain.safe_cache_dir() / "plans"
        os.makedirs(folder, mode=0o700, exist_ok=True)
    except (InputError, OSError):
        return None
    return folder if toolchain.private_folder(folder) else None


def cached(analysis: Analysis, options: Mapping[str, Any], derive: Callable[[], Plan]) -> Plan:
    """The plan of `analysis` with `options`: found by content in memory or on disk, else
    `derive()`d and kept."""
    return kept(analysis, options, derive, Plan)


#: each plan kept or found in this process -> its content key (what is derived from the plan,
#: its emitted texts, is kept on disk by it: derived_from)
_KEYS: weakref.WeakKeyDictionary[Plan, str] = weakref.WeakKeyDictionary()


def _remember(key: str, value: _T) -> _T:
    """`value` kept in memory under `key` (the one already there wins), most recent last."""
    value = _MEMORY.keep(key, value)
    if isinstance(value, Plan):
        _KEYS[value] = key
    return value


def derived_from(p: Plan, parts: Sequence[str], make: Callable[[], _T], kind: type[_T]) -> _T:
    """What `make()` derives from plan `p` and `parts` (a backend's emitted texts: its name, the
    file, the templates' digest), an instance of `kind`, kept on disk beside the plan: found
    there when `p` was kept by content (so it is known by its key) and the same parts were
    derived from it before, by any process; else made and written. Nothing is kept in memory
    here (the caller keeps it with the plan)."""
    base = _KEYS.get(p)
    folder = _folder() if base is not None and _mode() == "disk" else None
    if base is None or folder is None:
        return make()
    key = hashlib.sha256("\x1f".join((base, kind.__qualname__, *parts)).encode()).hexdigest()
    found = _read(folder, key, kind)
    return found if found is not None else _on_disk(folder, key, make, kind)


def _on_disk(folder: Path, key: str, derive: Callable[[], _T], kind: type[_T]) -> _T:
    """What is kept in `folder` under `key`, else `derive()`d and written: one process derives,
    another that needs it meanwhile waits on the lock and reads it."""
    with toolchain.exclusive(f"plan-{key}"):
        value = _read(folder, key, kind)
        if value is None:
            value = derive()
            _write(folder, key, value)
    return value


def _lookup(key: str, kind: type[_T], folder: Path | None) -> _T | None:
    """What is kept under `key` in memory, else in `folder` (then remembered), else None."""
    found = _MEMORY.get(key)
    if isinstance(found, kind):
        return found
    value = _read(folder, key, kind) if folder is not None else None
    return None if value is None else _remember(key, value)


def _key_of(analysis: Analysis, options: Mapping[str, Any], kind: type) -> str | None:
    if _mode() == "off":
        return None
    return digest(analysis, {"kind": kind.__qualname__, **options})


def find(analysis: Analysis, options: Mapping[str, Any], kind: type[_T]) -> _T | None:
    """What :func:`kept` holds for `analysis` and `options` in memory or on disk, derived
    before; None where nothing is (nothing is derived)."""
    key = _key_of(analysis, options, kind)
    if key is None:
        return None
    return _lookup(key, kind, _folder() if _mode() == "disk" else None)


def kept(
    analysis: Analysis, options: Mapping[str, Any], derive: Callable[[], _T], kind: type[_T]
) -> _T:
    """What `derive()` gives for `analysis` and `options` (a plan; the report's reference
    solves), an instance of `kind`: found by content in memory or on disk, else derived and
    kept. `options` name what is derived besides the analysis."""
    key = _key_of(analysis, options, kind)
    if key is None:
        return derive()
    folder = _folder() if _mode() == "disk" else None
    value = _lookup(key, kind, folder)
    if value is None and folder is None:
        value = derive()
    elif value is None:
        value = _on_disk(folder, key, derive, kind)
    return _remember(key, value)


def in_memory(
    analysis: Analysis, options: Mapping[str, Any], make: Callable[[], _T], kind: type[_T]
) -> _T:
    """What `make()` gives for `analysis` and `options`, kept by content in this process's
    memory only: for what cannot be pickled (the Python `loaded` level's lambdified solvers),
    so the same file analysed again (each test, each command of a session) finds it."""
    key = _key_of(analysis, options, kind)
    if key is None:
        return make()
    found = _MEMORY.get(key)
    return found if isinstance(found, kind) else _remember(key, make())


def _read(folder: Path, key: str, kind: type[_T]) -> _T | None:
    target, record = folder / f"{key}.pickle", folder / f"{key}.sha256"
    try:
        if not toolchain.verified(target, record, key):
            return None
        found = pickle.loads(target.read_bytes())
    except Exception:  # a corrupt or stale file: derive again (and overwrite it)
        return None
    return found if isinstance(found, kind) else None


def _write(folder: Path, key: str, found: object) -> None:
    if _source_digest() != _CODE:  # symkin's source changed under this process: not ours to keep
        return
    try:
        data = pickle.dumps(found, protocol=pickle.HIGHEST_PROTOCOL)
    except Exception:  # something in it does not pickle: kept in memory only
        return
    target, record = folder / f"{key}.pickle", folder / f"{key}.sha256"
    try:
        toolchain.replace_atomically(folder, target, data=data)
        digest_ = hashlib.sha256(data).hexdigest()
        toolchain.replace_atomically(folder, record, data=f"{key}\n{digest_}\n".encode())
    except OSError:  # a full disk, a read-only cache: kept in memory only
        return
