"""Running generated code: C compiled with the system compiler and called via ctypes, cached by
content hash under :func:`cache_dir` (private, verified before loading: docs/cli.md, SYMKIN_CACHE);
numpy modules executed from their text in memory, never read back from disk."""

from __future__ import annotations

import contextlib
import ctypes
import hashlib
import os
import re
import shlex
import shutil
import stat
import subprocess
import sys
import tempfile
import threading
from collections.abc import Iterable, Iterator
from pathlib import Path
from types import ModuleType
from typing import TypeAlias

import numpy as np
import numpy.typing as npt

from ..core.errors import InputError

# What the generated functions take for an array of doubles or ints: a ctypes array or pointer
# (None where the C accepts NULL).
_Doubles: TypeAlias = "ctypes.Array[ctypes.c_double]"
_DoublePointer: TypeAlias = "ctypes._Pointer[ctypes.c_double]"
_IntPointer: TypeAlias = "ctypes._Pointer[ctypes.c_int]"

CFLAGS = ("-std=c99", "-pedantic", "-Wall", "-Wextra", "-Werror", "-O2", "-fPIC", "-shared")


#: GCC's passes that take a fifth of the build of a large mechanism's C (the bridge amplifier's
#: 0.8 MB: the alias walks of dead-store elimination, the second scheduling pass over its long
#: straight-line routines) and change neither a bit of its results nor its speed measurably
#: (docs/benchmarks.md); added for GCC only (other compilers may not take them).
GCC_CFLAGS = ("-fno-tree-dse", "-fno-schedule-insns2")


def cflags() -> tuple[str, ...]:
    """The flags the generated C is compiled with: :data:`CFLAGS` (with GCC also
    :data:`GCC_CFLAGS`), then $SYMKIN_CFLAGS's (split as a shell would; docs/cli.md): a later -O
    wins, so `-O0` compiles a large mechanism several times faster for a quick check, `-O3
    -march=native` tunes it to this machine."""
    extra = GCC_CFLAGS if _is_gcc(os.environ.get("CC", "cc")) else ()
    return CFLAGS + extra + tuple(shlex.split(os.environ.get("SYMKIN_CFLAGS", "")))


_GCC: dict[str, bool] = {}


def _is_gcc(cc: str) -> bool:
    """Whether the compiler `cc` is GCC (its --version names the FSF, not clang); asked once per
    process and name."""
    if cc not in _GCC:
        try:
            text = subprocess.run(
                [cc, "--version"], capture_output=True, text=True, timeout=30
            ).stdout
        except (OSError, subprocess.SubprocessError):
            text = ""
        _GCC[cc] = "Free Software Foundation" in text and "clang" not in text.lower()
    return _GCC[cc]


def compiler() -> str:
    """The C compiler: $CC, else cc; a clear error when there is none."""
    cc = os.environ.get("CC", "cc")
    if shutil.which(cc) is None:
        raise InputError(
            f"no C compiler found ('{cc}')",
            entry="--backend c",
            hint="install gcc (apt-get install gcc) or set CC",
        )
    return cc


def cache_dir() -> Path:
    """$SYMKIN_CACHE, else $XDG_CACHE_HOME/symkin, else ~/.cache/symkin (docs/cli.md)."""
    base = os.environ.get("SYMKIN_CACHE") or os.path.join(
        os.environ.get("XDG_CACHE_HOME") or os.path.expanduser("~/.cache"), "symkin"
    )
    return Path(base)


def _cache_error(folder: Path, why: str) -> InputError:
    return InputError(
        f"the compiled-code cache '{folder}' {why}",
        entry="SYMKIN_CACHE",
        hint="set SYMKIN_CACHE to a folder of your own that only you can write "
        "(it is created with mode 0700 if missing)",
    )


def _private(stat_result: os.stat_result) -> bool:
    """Owned by this user and writable by no one else."""
    return stat_result.st_uid == os.getuid() and not stat_result.st_mode & (
        stat.S_IWGRP | stat.S_IWOTH
    )


def safe_cache_dir() -> Path:
    """The cache folder, created 0700 if missing; InputError (exit 2) when it cannot be made or
    is not safe to load code from: not a folder, not owned by this user, or writable by others."""
    folder = cache_dir()
    try:
        os.makedirs(folder, mode=0o700, exist_ok=True)
        info = os.stat(folder)
    except OSError as exc:
        raise _cache_error(folder, f"cannot be created ({exc.strerror or exc})") from None
    if not stat.S_ISDIR(info.st_mode):
        raise _cache_error(folder, "is not a folder")
    if not _private(info):
        who = (
            "belongs to another user"
            if info.st_uid != os.getuid()
            else f"is writable by others (mode {stat.S_IMODE(info.st_mode):o})"
        )
        raise _cache_error(folder, f"{who}: code loaded from it could be anyone's")
    if not os.access(folder, os.W_OK | os.X_OK):
        raise _cache_error(folder, "is not writable")
    return folder


def _sha256(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def private_folder(folder: Path) -> bool:
    """A folder (not a link to one) of this user's that no one else can write."""
    try:
        info = os.lstat(folder)
    except OSError:
        return False
    return stat.S_ISDIR(info.st_mode) and _private(info)


@contextlib.contextmanager
def exclusive(name: str) -> Iterator[None]:
    """Held by one process (and thread) at a time per `name`, through a lock file in the
    cache's private `locks` folder: two processes that need the same library or plan build it
    once, the second reading what the first wrote. Without a usable folder (or fcntl), a no-op:
    then both build it, as before."""
    fd: int | None
    try:
        import fcntl

        folder = safe_cache_dir() / "locks"
        os.makedirs(folder, mode=0o700, exist_ok=True)
        if not private_folder(folder):
            raise OSError("not private")
        fd = os.open(folder / f"{name}.lock", os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW, 0o600)
    except (ImportError, InputError, OSError):
        fd = None  # yielded below, outside the handler: the body's errors carry no context
    if fd is None:
        yield
        return
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)  # released when fd closes
        yield
    finally:
        os.close(fd)


def verified(target: Path, record: Path, source_digest: str) -> bool:
    """A cached file (a library, a plan) is ours and intact: both files private regular files,
    the record names the source digest and the file's own sha256 (a planted, truncated or
    corrupt file fails this and is rebuilt, never loaded)."""
    try:
        for p in (target, record):
            info = os.lstat(p)
            if not stat.S_ISREG(info.st_mode) or not _private(info):
                return False
        lines = record.read_text().split()
        return lines == [source_digest, _sha256(target)]
    except (OSError, UnicodeDecodeError):
        return False


def replace_atomically(
    folder: Path, final: Path, data: bytes | None = None, src: Path | None = None
) -> None:
    """Put `data` (or the file `src`) at `final` with a unique temporary name and one rename."""
    fd, tmp = tempfile.mkstemp(dir=folder, prefix=f".{final.name}.", suffix=".tmp")
    try:
        if data is None:
            if src is None:
                raise TypeError("replace_atomically needs data or src")
            payload = src.read_bytes()
        else:
            payload = data
        with os.fdopen(fd, "wb") as f:
            f.write(payload)
        os.chmod(tmp, 0o600 if data is not None else 0o700)
        os.replace(tmp, final)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise


def build(
    name: str, header: str, source: str, flags: tuple[str, ...] | None = None, extra: str = ""
) -> Path:
    """Shared library of the generated pair (and an `extra` C file, e.g. a timer), cached by the
    hash of its texts and flags; a cached library is loaded only when verified (see verified)
    and rebuilt otherwise. `flags` default to :func:`cflags`."""
    cc = compiler()
    flags = cflags() if flags is None else flags
    full = hashlib.sha256("\0".join((cc, *flags, header, source, extra)).encode()).hexdigest()
    folder = safe_cache_dir()
    target = folder / f"{name}-{full[:20]}.so"
    record = folder / f"{name}-{full[:20]}.sha256"
    if verified(target, record, full):
        return target
    with exclusive(target.stem):
        if verified(target, record, full):  # built by another process while we waited
            return target
        with tempfile.TemporaryDirectory() as tmp:
            built = _compile(cc, flags, name, header, source, extra, Path(tmp))
            digest = _sha256(built)
            # atomic, unique temporary names: a concurrent build never sees half a file; the
            # record last, so a reader that sees it finds the library it describes
            replace_atomically(folder, target, src=built)
            replace_atomically(folder, record, data=f"{full}\n{digest}\n".encode())
    return target


def load_transient(
    name: str, header: str, source: str, flags: tuple[str, ...] | None = None
) -> ctypes.CDLL:
    """The generated pair compiled in a temporary folder and loaded; the folder is removed
    before returning (the loaded library stays mapped), so no file is left behind."""
    with tempfile.TemporaryDirectory(prefix="symkin-") as tmp:
        flags = cflags() if flags is None else flags
        return ctypes.CDLL(str(_compile(compiler(), flags, name, header, source, "", Path(tmp))))


def _compile(
    cc: str, flags: tuple[str, ...], name: str, header: str, source: str, extra: str, folder: Path
) -> Path:
    """The shared library of the texts, built in `folder`."""
    (folder / f"{name}.h").write_text(header)
    (folder / f"{name}.c").write_text(source)
    files = [f"{name}.c"]
    if extra:
        (folder / "extra.c").write_text(extra)
        files.append("extra.c")
    built = folder / "lib.so"
    proc = subprocess.run(
        [cc, *flags, *files, "-o", str(built), "-lm"], cwd=folder, capture_output=True, text=True
    )
    if proc.returncode != 0:
        given = os.environ.get("SYMKIN_CFLAGS", "")
        if given.strip() and tuple(flags) == cflags():  # the user's flags are in this line
            raise InputError(
                f"the generated C did not compile with SYMKIN_CFLAGS='{given}':\n"
                + proc.stderr.strip(),
                entry="SYMKIN_CFLAGS",
                hint="unset SYMKIN_CFLAGS or give flags the compiler takes",
            )
        raise RuntimeError(f"the generated C did not compile:\n{proc.stderr}")
    return built


class Library:
    """A loaded generated evaluator, called through its batch entry points (one ctypes call for
    any number of configurations: docs/generated-code.md)."""

    def __init__(
        self,
        path: Path | ctypes.CDLL,
        name: str,
        n_inputs: int,
        n_params: int,
        n_points: int,
        n_hinges: int,
        n_links: int = 0,
    ):
        self.lib = path if isinstance(path, ctypes.CDLL) else ctypes.CDLL(str(path))
        dptr, iptr = ctypes.POINTER(ctypes.c_double), ctypes.POINTER(ctypes.c_int)
        self.fn = getattr(self.lib, f"{name}_evaluate_pose")
        self.fn.restype = ctypes.c_int
        self.fn.argtypes = [dptr, dptr, ctypes.c_int, dptr, dptr, dptr]
        self.batch = getattr(self.lib, f"{name}_evaluate_angles_batch")
        self.batch.restype = ctypes.c_int
        self.batch.argtypes = [ctypes.c_int, dptr, dptr, ctypes.c_int, dptr, dptr, iptr]
        self.grid = getattr(self.lib, f"{name}_evaluate_grid")
        self.grid.restype = ctypes.c_int
        self.grid.argtypes = [ctypes.c_int, dptr, ctypes.c_int, dptr, ctypes.c_int, dptr, iptr]
        self.sensitivity = getattr(self.lib, f"{name}_sensitivity_batch", None)
        if self.sensitivity is not None:
            self.sensitivity.restype = ctypes.c_int
            self.sensitivity.argtypes = [
                ctypes.c_int,
                dptr,
                dptr,
                ctypes.c_int,
                dptr,
                dptr,
                dptr,
                iptr,
            ]
        self.n_inputs, self.n_params = n_inputs, n_params
        self.n_points, self.n_hinges, self.n_links = n_points, n_hinges, n_links
        self.n_variables = n_params + n_inputs

    def pose(
        self, inputs: Iterable[float], params: Iterable[float] | None = None, level: int = 2
    ) -> tuple[int, list[float], list[float], list[float]]:
        """One configuration in one call: (status, out: 6 doubles per point, angles: rigid then
        compliant per hinge, links: rigid, compliant, deviation per link)."""
        x = (ctypes.c_double * max(1, self.n_inputs))(*inputs)
        out = (ctypes.c_double * max(1, 6 * self.n_points))()
        angles = (ctypes.c_double * (2 * self.n_hinges))()
        links = (ctypes.c_double * max(1, 3 * self.n_links))()
        status = self.fn(
            x, self.params(params), level, out, angles, links if self.n_links else None
        )
        return (
            status,
            list(out)[: 6 * self.n_points],
            list(angles),
            list(links)[: 3 * self.n_links],
        )

    def evaluate(
        self, inputs: Iterable[float], params: Iterable[float] | None = None, level: int = 2
    ) -> tuple[int, list[float], list[float]]:
        """One configuration: (status, out: 6 doubles per point, angles: rigid then compliant
        per hinge)."""
        return self.pose(inputs, params, level)[:3]

    def evaluate_rows(
        self,
        inputs: np.ndarray,
        params: Iterable[float] | None = None,
        level: int = 2,
        angles: bool = False,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
        """n configurations in one call: inputs (n, n_inputs); (status (n,), out (n, 6 n_points),
        angles (n, 2 n_hinges) or None)."""
        x = _rows(inputs, self.n_inputs)
        n = x.shape[0]
        out = np.empty((n, 6 * self.n_points))
        ang = np.empty((n, 2 * self.n_hinges)) if angles else None
        status = np.empty(n, dtype=np.intc)
        self.batch(n, _ptr(x), self.params(params), level, _ptr(out), _ptr(ang), _iptr(status))
        return status, out, ang

    def evaluate_grid(
        self, params: np.ndarray, inputs: np.ndarray, level: int = 2, out: np.ndarray | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """Every row of params (n_sets, n_params) at every row of inputs (n, n_inputs), one
        call: (status (n_sets, n), out (n_sets, n, 6 n_points)); `out` may be given, to reuse."""
        p = np.ascontiguousarray(params, dtype=np.float64)
        if p.ndim != 2 or p.shape[1] != self.n_params:
            raise ValueError(f"params must have shape (n_sets, {self.n_params}), got {p.shape}")
        x = _rows(inputs, self.n_inputs)
        shape = (p.shape[0], x.shape[0])
        if out is None or out.shape != shape + (6 * self.n_points,) or not out.flags.c_contiguous:
            out = np.empty(shape + (6 * self.n_points,))
        status = np.empty(shape, dtype=np.intc)
        self.grid(
            shape[0],
            _ptr(p) if self.n_params else None,
            shape[1],
            _ptr(x),
            level,
            _ptr(out),
            _iptr(status),
        )
        return status, out

    def sensitivity_rows(
        self, inputs: np.ndarray, params: Iterable[float] | None = None, level: int = 2
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Sensitivities of n configurations in one call: (status (n,), values (n, 6 n_points),
        deviation and rigid (n, n_points, n_variables, 2))."""
        if self.sensitivity is None:
            raise RuntimeError("this evaluator was generated without sensitivities")
        x = _rows(inputs, self.n_inputs)
        n = x.shape[0]
        values = np.empty((n, 6 * self.n_points))
        dev = np.empty((n, self.n_points, self.n_variables, 2))
        rig = np.empty((n, self.n_points, self.n_variables, 2))
        status = np.empty(n, dtype=np.intc)
        self.sensitivity(
            n,
            _ptr(x),
            self.params(params),
            level,
            _ptr(values),
            _ptr(dev),
            _ptr(rig),
            _iptr(status),
        )
        return status, values, dev, rig

    def params(self, params: Iterable[float] | None) -> _Doubles | None:
        """A parameter array for the C calls (None: the defaults)."""
        if params is None:
            return None
        values = [float(v) for v in params]
        if len(values) != self.n_params:
            raise ValueError(f"expected {self.n_params} parameter values, got {len(values)}")
        return (ctypes.c_double * max(1, self.n_params))(*values)


def _rows(inputs: npt.ArrayLike, width: int) -> np.ndarray:
    x = np.ascontiguousarray(inputs, dtype=np.float64)
    if x.ndim != 2 or x.shape[1] != width:
        raise ValueError(f"inputs must have shape (n, {width}), got {x.shape}")
    return x


def _ptr(array: np.ndarray | None) -> _DoublePointer | None:
    return None if array is None else array.ctypes.data_as(ctypes.POINTER(ctypes.c_double))


def _iptr(array: np.ndarray) -> _IntPointer:
    return array.ctypes.data_as(ctypes.POINTER(ctypes.c_int))


TIMER = r"""
#define _POSIX_C_SOURCE 199309L
#include <stddef.h>
#include <time.h>
#include "NAME.h"

/* Evaluate n configurations `repeats` times; the elapsed seconds, measured inside C. */
double symkin_time(const double *inputs, int n, int repeats, int level, double *sink)
{
    struct timespec t0, t1;
    double out[6 * UPPER_N_POINTS + 6];
    double acc = 0.0;
    int r, i;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    for (r = 0; r < repeats; ++r) {
        for (i = 0; i < n; ++i) {
            if (NAME_evaluate(inputs + (size_t)i * UPPER_N_INPUTS, NULL, level, out) == 0) {
                acc += out[4];
            }
        }
    }
    clock_gettime(CLOCK_MONOTONIC, &t1);
    *sink = acc;
    return (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec);
}
"""


def time_per_evaluation(
    name: str,
    header: str,
    source: str,
    inputs: list[float],
    n: int,
    level: int,
    budget: float = 0.2,
) -> float:
    """Seconds per call of the generated evaluator over `n` input rows, timed inside C."""
    mech_name = _evaluate_prefix(header)
    extra = TIMER.replace("UPPER", mech_name.upper()).replace("NAME", mech_name)
    lib = ctypes.CDLL(str(build(mech_name, header, source, extra=extra)))
    fn = lib.symkin_time
    fn.restype = ctypes.c_double
    fn.argtypes = [
        ctypes.POINTER(ctypes.c_double),
        ctypes.c_int,
        ctypes.c_int,
        ctypes.c_int,
        ctypes.POINTER(ctypes.c_double),
    ]
    data = (ctypes.c_double * max(1, len(inputs)))(*inputs)
    sink = ctypes.c_double()
    repeats = 1
    while True:
        elapsed: float = fn(data, n, repeats, level, ctypes.byref(sink))
        if elapsed >= budget or repeats >= 1 << 20:
            return elapsed / (n * repeats)
        repeats *= 2 if elapsed <= 0 else max(2, int(budget / elapsed) + 1)


def _evaluate_prefix(header: str) -> str:
    """The mechanism name a generated header declares (<name>_evaluate)."""
    match = re.search(r"int (\w+)_evaluate\(", header)
    if match is None:
        raise ValueError("the header declares no <name>_evaluate function")
    return match.group(1)


def numpy_module_in_memory(source: str, name: str) -> ModuleType:
    """A generated numpy module executed from its text, with no file (our own generated code,
    names escaped); it is not entered in sys.modules."""
    module = ModuleType(f"symkin_compiled_{name}")
    exec(compile(source, f"<symkin generated {name}>", "exec"), module.__dict__)
    return module


_MODULES: dict[str, ModuleType] = {}
_MODULES_LOCK = threading.Lock()


def import_numpy_module(source: str, name: str) -> ModuleType:
    """A generated numpy module, executed from its text in memory (our own generated code, names
    escaped): nothing is written to or read back from disk, so no planted or truncated file can
    be executed, and threads importing the same text at once get one module."""
    digest = hashlib.sha256(source.encode()).hexdigest()[:20]
    module_name = f"symkin_generated_{name}_{digest}"
    with _MODULES_LOCK:
        module = _MODULES.get(module_name)
        if module is None:
            module = ModuleType(module_name)
            module.__file__ = f"<symkin generated {name}>"
            sys.modules[module_name] = module  # functions pickle by module name
            try:
                exec(compile(source, module.__file__, "exec"), module.__dict__)
            except BaseException:
                del sys.modules[module_name]
                raise
            _MODULES[module_name] = module
        return module
