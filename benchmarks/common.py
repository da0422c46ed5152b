"""What every part of the benchmarks shares: paths, the examples and their input ranges, the
compile flags, the sizes of a full, --quick or --smoke run, timing helpers, the machine, and the
iteration policy of symkin's generated evaluators (read from symkin.core.settings)."""

from __future__ import annotations

import json
import math
import os
import platform
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

# derivation times are measured: every plan is derived, none found in the cache (docs/cli.md)
os.environ.setdefault("SYMKIN_PLAN_CACHE", "off")

import families
import numpy as np

from symkin.core.levels import get as level
from symkin.core.settings import SOLVER

ROOT = Path(__file__).resolve().parent.parent
BENCH = ROOT / "benchmarks"
EXACT = level("exact").code

EXAMPLES = {
    # example -> input ranges (radians) sampled uniformly; all inside the assembly range
    "four_bar": {"A0": (-1.0, 1.0)},
    "stephenson_six_bar": {"O_A": (-0.5, 0.5)},
    "nine_bar_platform": {"O": (-0.1, 0.1), "A": (-0.1, 0.1), "B": (-0.1, 0.1), "K": (-0.1, 0.1)},
}
#: Compile flags for every timed C / C++ build: the same optimisation level symkin's runtime uses.
C_FLAGS = ["-std=c99", "-pedantic", "-Wall", "-Wextra", "-O2", "-fPIC"]
CXX_FLAGS = ["-std=c++14", "-O2", "-DNDEBUG", "-fPIC", "-w"]
EIGEN = "/usr/include/eigen3"
#: Relative tolerance of each alternative's deviation against symkin's C on the check points.
TOL = {
    "numpy": 1e-12,
    "lambdify": 1e-9,
    "lambdify_cse": 1e-9,
    "lambdify_cse_no_polish": 1e-9,
    "symforce": 1e-9,
    "scipy": 1e-5,
}
#: The generated evaluators' iteration policy, which the lambdify and SymForce drivers follow step
#: for step: symkin's solver settings in float64.
POLICY = {
    "polish": SOLVER.float64.polish,
    "stop": SOLVER.float64.converged,
    "stall": SOLVER.float64.stalled,
    "stall_ratio": SOLVER.stall_ratio,
    "iterations": SOLVER.exact_iterations,
}


@dataclass(frozen=True)
class Sizes:
    """How much a run measures."""

    name: str
    examples: tuple[str, ...]
    points: int  # per-point timings run over this many sampled inputs
    c_time: float  # seconds per timing batch of a C / C++ evaluator
    lambdify_time: float
    scipy_time: float
    throughput: int  # points of the numpy-vs-C throughput comparison
    serial: tuple[int, ...]  # derivation: members of the families
    ladder: tuple[int, ...]
    install_symforce: bool  # try `pip install symforce` once when it is missing


FULL = Sizes(
    "full",
    tuple(EXAMPLES),
    10**4,
    0.3,
    0.5,
    1.0,
    10**6,
    families.SERIAL_SIZES,
    families.LADDER_SIZES,
    True,
)
QUICK = Sizes("quick", tuple(EXAMPLES), 10**4, 0.1, 0.2, 0.3, 10**5, (2, 4, 8, 16), (1, 2, 4), True)
#: Every part once, at the smallest sizes: checks that the benchmarks run, measures nothing.
SMOKE = Sizes("smoke", tuple(EXAMPLES), 200, 0.005, 0.005, 0.005, 10**3, (2,), (1,), False)


def log(message: str) -> None:
    """A timestamped progress line on stderr."""
    print(f"[{time.strftime('%H:%M:%S')}] {message}", file=sys.stderr, flush=True)


def best_time(fn, repeat: int = 3, min_time: float = 0.2) -> tuple[float, int]:
    """Best-of-`repeat` time of one call of fn, with calls batched to last at least min_time."""
    t0 = time.perf_counter()
    fn()
    once = time.perf_counter() - t0
    calls = max(1, int(min_time / max(once, 1e-9)))
    best = math.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        for _ in range(calls):
            fn()
        best = min(best, (time.perf_counter() - t0) / calls)
    return best, calls


def relerr(a, b) -> float:
    """|a - b| / |b| of two vectors."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    return float(np.linalg.norm(a - b) / max(np.linalg.norm(b), 1e-300))


def first_line(cmd: list[str]) -> str:
    """The first line a command prints, or 'unavailable'."""
    try:
        return subprocess.run(cmd, capture_output=True, text=True).stdout.splitlines()[0]
    except (OSError, IndexError):
        return "unavailable"


def machine() -> dict:
    """What the numbers were measured on."""
    cpu = "unknown"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    import scipy
    import sympy

    info = {
        "cpu": cpu,
        "cores": os.cpu_count(),
        "system": f"{platform.system()} {platform.release()} {platform.machine()}",
        "python": platform.python_version(),
        "numpy": np.__version__,
        "sympy": sympy.__version__,
        "scipy": scipy.__version__,
        "cc": first_line([os.environ.get("CC", "cc"), "--version"]),
        "cxx": first_line(["c++", "--version"]),
        "c_flags": " ".join(C_FLAGS),
        "mem_total_gb": None,
    }
    try:
        kb = int(
            next(
                l
                for l in Path("/proc/meminfo").read_text().splitlines()
                if l.startswith("MemTotal")
            ).split()[1]
        )
        info["mem_total_gb"] = round(kb / 2**20, 1)
    except (OSError, StopIteration, ValueError):
        pass
    return info


def save(name: str, rows: list[dict], table: list[str], load_before: tuple) -> None:
    """Print `table` and the load average, and write benchmarks/results-<name>.json with the
    machine and the load before and after (wall times on a shared machine move)."""
    after = os.getloadavg()
    print("\n".join(table))
    print(f"load average before {load_before[0]:.1f}, after {after[0]:.1f}")
    results = {
        "machine": machine(),
        "load_average_before": load_before,
        "load_average_after": after,
        "rows": rows,
    }
    (BENCH / f"results-{name}.json").write_text(json.dumps(results, indent=1) + "\n")
