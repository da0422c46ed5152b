"""Running generated code: C compiled with the system compiler and called via ctypes, numpy
modules imported from their text; both cached by content hash under :func:`cache_dir`."""

from __future__ import annotations

import ctypes
import hashlib
import importlib.util
import os
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path
from types import ModuleType

from ..errors import InputError

CFLAGS = ("-std=c99", "-pedantic", "-Wall", "-Wextra", "-Werror", "-O2", "-fPIC", "-shared")


def compiler() -> str:
    """The C compiler: $CC, else cc; a clear error when there is none."""
    cc = os.environ.get("CC", "cc")
    if shutil.which(cc) is None:
        raise InputError(f"no C compiler found ('{cc}')", entry="--backend c",
                         hint="install gcc (apt-get install gcc) or set CC")
    return cc


def cache_dir() -> Path:
    """$SYMKIN_CACHE, else $XDG_CACHE_HOME/symkin, else ~/.cache/symkin."""
    base = os.environ.get("SYMKIN_CACHE") or os.path.join(
        os.environ.get("XDG_CACHE_HOME") or os.path.expanduser("~/.cache"), "symkin")
    return Path(base)


def build(name: str, header: str, source: str, flags: tuple[str, ...] = CFLAGS,
          extra: str = "") -> Path:
    """Shared library of the generated pair (and an `extra` C file, e.g. a timer); rebuilt
    only when the texts or flags change."""
    cc = compiler()
    digest = hashlib.sha256("\0".join((cc, *flags, header, source, extra)).encode()
                            ).hexdigest()[:20]
    target = cache_dir() / f"{name}-{digest}.so"
    if target.exists():
        return target
    target.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        (Path(tmp) / f"{name}.h").write_text(header)
        (Path(tmp) / f"{name}.c").write_text(source)
        files = [f"{name}.c"]
        if extra:
            (Path(tmp) / "extra.c").write_text(extra)
            files.append("extra.c")
        built = Path(tmp) / "lib.so"
        proc = subprocess.run([cc, *flags, *files, "-o", str(built), "-lm"], cwd=tmp,
                              capture_output=True, text=True)
        if proc.returncode != 0:
            raise RuntimeError(f"the generated C did not compile:\n{proc.stderr}")
        os.replace(built, target)          # atomic: a concurrent build never sees half a file
    return target


class Library:
    """A loaded generated evaluator: `evaluate(inputs, params, level) -> (status, out, angles)`,
    `pose(...)` with the links' rotations too."""

    def __init__(self, path: Path, name: str, n_inputs: int, n_params: int, n_points: int,
                 n_hinges: int, n_links: int = 0):
        self.lib = ctypes.CDLL(str(path))
        self.fn = getattr(self.lib, f"{name}_evaluate_pose")
        self.fn.restype = ctypes.c_int
        dptr = ctypes.POINTER(ctypes.c_double)
        self.fn.argtypes = [dptr, dptr, ctypes.c_int, dptr, dptr, dptr]
        self.n_inputs, self.n_params = n_inputs, n_params
        self.n_points, self.n_hinges, self.n_links = n_points, n_hinges, n_links

    def pose(self, inputs, params=None, level: int = 2
             ) -> tuple[int, list[float], list[float], list[float]]:
        """(status, out: 6 doubles per point, angles: rigid then compliant per hinge, links:
        rigid, compliant, deviation per link)."""
        x = (ctypes.c_double * max(1, self.n_inputs))(*inputs)
        p = None if params is None else (ctypes.c_double * max(1, self.n_params))(*params)
        out = (ctypes.c_double * max(1, 6 * self.n_points))()
        angles = (ctypes.c_double * (2 * self.n_hinges))()
        links = (ctypes.c_double * max(1, 3 * self.n_links))()
        status = self.fn(x, p, level, out, angles, links if self.n_links else None)
        return (status, list(out)[: 6 * self.n_points], list(angles),
                list(links)[: 3 * self.n_links])

    def evaluate(self, inputs, params=None, level: int = 2
                 ) -> tuple[int, list[float], list[float]]:
        """(status, out: 6 doubles per point, angles: rigid then compliant per hinge)."""
        return self.pose(inputs, params, level)[:3]


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


def time_per_evaluation(name: str, header: str, source: str, inputs: list[float], n: int,
                        level: int, budget: float = 0.2) -> float:
    """Seconds per call of the generated evaluator over `n` input rows, timed inside C."""
    mech_name = _evaluate_prefix(header)
    extra = TIMER.replace("UPPER", mech_name.upper()).replace("NAME", mech_name)
    lib = ctypes.CDLL(str(build(mech_name, header, source, CFLAGS, extra)))
    fn = lib.symkin_time
    fn.restype = ctypes.c_double
    fn.argtypes = [ctypes.POINTER(ctypes.c_double), ctypes.c_int, ctypes.c_int, ctypes.c_int,
                   ctypes.POINTER(ctypes.c_double)]
    data = (ctypes.c_double * max(1, len(inputs)))(*inputs)
    sink = ctypes.c_double()
    repeats = 1
    while True:
        elapsed = fn(data, n, repeats, level, ctypes.byref(sink))
        if elapsed >= budget or repeats >= 1 << 20:
            return elapsed / (n * repeats)
        repeats *= 2 if elapsed <= 0 else max(2, int(budget / elapsed) + 1)


def _evaluate_prefix(header: str) -> str:
    """The mechanism name a generated header declares (<name>_evaluate)."""
    return re.search(r"int (\w+)_evaluate\(", header).group(1)


def import_numpy_module(source: str, name: str) -> ModuleType:
    """Import a generated numpy module from its text (our own generated code, names escaped)."""
    digest = hashlib.sha256(source.encode()).hexdigest()[:20]
    folder = cache_dir() / "numpy"
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"{name}_{digest}.py"
    if not path.exists():
        tmp = path.with_suffix(f".{os.getpid()}.tmp")
        tmp.write_text(source)
        os.replace(tmp, path)
    module_name = f"symkin_generated_{name}_{digest}"
    if module_name in sys.modules:
        return sys.modules[module_name]
    spec = importlib.util.spec_from_file_location(module_name, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    sys.modules[module_name] = module
    return module
