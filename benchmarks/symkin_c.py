"""symkin's generated C, compiled with a timing harness in a separate translation unit (no
inlining) and timed inside C."""

from __future__ import annotations

import ctypes
import os
import subprocess
from pathlib import Path

import numpy as np
from common import C_FLAGS, EXACT

HARNESS_C = r"""
#define _POSIX_C_SOURCE 199309L
#include <stddef.h>
#include <time.h>
#include "{name}.h"

/* Calls {name}_evaluate on n_points input vectors, reps times; returns the elapsed seconds
   (CLOCK_MONOTONIC, measured here in C) and the number of non-zero statuses. */
double bench_loop(const double *inputs, int n_points, const double *params, int level, int reps,
                  double *out, int *failures)
{{
    struct timespec t0, t1;
    int r, i, fails = 0;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    for (r = 0; r < reps; ++r) {{
        for (i = 0; i < n_points; ++i) {{
            if ({name}_evaluate(inputs + (size_t)i * {NAME}_N_INPUTS, params, level,
                                out + (size_t)i * 6 * {NAME}_N_POINTS) != 0) {{
                ++fails;
            }}
        }}
    }}
    clock_gettime(CLOCK_MONOTONIC, &t1);
    *failures = fails;
    return (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec);
}}
"""


def compile_c(workdir: Path, name: str, header: str, code: str) -> Path:
    """The generated pair and the timing harness, compiled into one shared library."""
    cc = os.environ.get("CC", "cc")
    (workdir / f"{name}.h").write_text(header)
    (workdir / f"{name}.c").write_text(code)
    (workdir / "harness.c").write_text(HARNESS_C.format(name=name, NAME=name.upper()))
    for src in (f"{name}.c", "harness.c"):
        subprocess.run(
            [cc, *C_FLAGS, "-c", src, "-o", src + ".o"],
            cwd=workdir,
            check=True,
            capture_output=True,
            text=True,
        )
    lib = workdir / f"lib{name}_bench.so"
    subprocess.run(
        [cc, "-shared", f"{name}.c.o", "harness.c.o", "-o", str(lib), "-lm"],
        cwd=workdir,
        check=True,
        capture_output=True,
        text=True,
    )
    return lib


class CBench:
    """symkin's compiled C with its harness: `run` evaluates points, `per_point` times them."""

    def __init__(self, lib: Path, name: str, n_inputs: int, n_points: int):
        self.lib = ctypes.CDLL(str(lib))
        d = ctypes.POINTER(ctypes.c_double)
        self.loop = self.lib.bench_loop
        self.loop.restype = ctypes.c_double
        self.loop.argtypes = [
            d,
            ctypes.c_int,
            d,
            ctypes.c_int,
            ctypes.c_int,
            d,
            ctypes.POINTER(ctypes.c_int),
        ]
        self.n_inputs, self.n_points = n_inputs, n_points

    def run(
        self, x: np.ndarray, level: int = EXACT, reps: int = 1
    ) -> tuple[float, np.ndarray, int]:
        """(seconds for reps x len(x) calls, measured in C; out (N, n_points, 6); failures)."""
        x = np.ascontiguousarray(x, dtype=float).reshape(-1, self.n_inputs)
        out = np.zeros((len(x), self.n_points, 6))
        fails = ctypes.c_int(0)
        d = ctypes.POINTER(ctypes.c_double)
        secs = self.loop(
            x.ctypes.data_as(d),
            len(x),
            None,
            level,
            reps,
            out.ctypes.data_as(d),
            ctypes.byref(fails),
        )
        return secs, out, fails.value

    def per_point(
        self, x: np.ndarray, level: int = EXACT, min_time: float = 0.3, repeat: int = 3
    ) -> float:
        secs, _, _ = self.run(x, level, 1)
        reps = max(1, int(min_time / max(secs, 1e-9)))
        return min(self.run(x, level, reps)[0] for _ in range(repeat)) / (reps * len(x))
