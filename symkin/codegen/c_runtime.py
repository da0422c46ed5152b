"""Compile generated C with the system compiler (cached by content hash) and call it via ctypes."""

from __future__ import annotations

import ctypes
import hashlib
import os
import shutil
import subprocess
import tempfile
from pathlib import Path

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
    base = os.environ.get("SYMKIN_CACHE") or os.path.join(
        os.environ.get("XDG_CACHE_HOME") or os.path.expanduser("~/.cache"), "symkin")
    return Path(base)


def build(name: str, header: str, source: str, flags: tuple[str, ...] = CFLAGS) -> Path:
    """Shared library of the generated pair; rebuilt only when the text or flags change."""
    cc = compiler()
    digest = hashlib.sha256("\0".join((cc, *flags, header, source)).encode()).hexdigest()[:20]
    target = cache_dir() / f"{name}-{digest}.so"
    if target.exists():
        return target
    target.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        (Path(tmp) / f"{name}.h").write_text(header)
        (Path(tmp) / f"{name}.c").write_text(source)
        built = Path(tmp) / "lib.so"
        proc = subprocess.run([cc, *flags, f"{name}.c", "-o", str(built), "-lm"], cwd=tmp,
                              capture_output=True, text=True)
        if proc.returncode != 0:
            raise RuntimeError(f"the generated C did not compile:\n{proc.stderr}")
        os.replace(built, target)          # atomic: a concurrent build never sees half a file
    return target


class Library:
    """A loaded generated evaluator: `evaluate(inputs, params, level) -> (status, out)`."""

    def __init__(self, path: Path, name: str, n_inputs: int, n_params: int, n_points: int,
                 n_hinges: int):
        self.lib = ctypes.CDLL(str(path))
        self.fn = getattr(self.lib, f"{name}_evaluate_angles")
        self.fn.restype = ctypes.c_int
        dptr = ctypes.POINTER(ctypes.c_double)
        self.fn.argtypes = [dptr, dptr, ctypes.c_int, dptr, dptr]
        self.n_inputs, self.n_params = n_inputs, n_params
        self.n_points, self.n_hinges = n_points, n_hinges

    def evaluate(self, inputs, params=None, level: int = 2
                 ) -> tuple[int, list[float], list[float]]:
        """(status, out: 6 doubles per point, angles: rigid then compliant per hinge)."""
        x = (ctypes.c_double * max(1, self.n_inputs))(*inputs)
        p = None if params is None else (ctypes.c_double * max(1, self.n_params))(*params)
        out = (ctypes.c_double * max(1, 6 * self.n_points))()
        angles = (ctypes.c_double * (2 * self.n_hinges))()
        status = self.fn(x, p, level, out, angles)
        return status, list(out)[: 6 * self.n_points], list(angles)
