"""Large mechanisms end to end, as a user runs them (the CLI in a subprocess, a cold cache):

- `symkin derive` (every emitter: numpy, C99, the LaTeX report and its figures) of a ladder of
  k loops and a fan of k four-bars (benchmarks/families.py), k = 5, 10, 20;
- `symkin eval` of the same files in each backend (sympy = the 40-digit mpmath evaluation,
  numpy, c), each from a cold cache, so the time includes the derivation and the build.

Run ``python benchmarks/scale.py [--sizes 5,10,20]``; it prints a table and writes
benchmarks/results-scale.json with the machine's load average (the figures are wall times).
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import families
from common import log, save

SYMKIN = [sys.executable, "-m", "symkin"]


def _inputs(kind: str, k: int) -> list[str]:
    if kind == "ladder":
        return ["--input", "g0=0.05"]
    return [a for j in range(1, k + 1) for a in ("--input", f"A0_{j}={0.05 + 0.01 * j:.2f}")]


def _timed(cmd: list[str], env: dict) -> float:
    t0 = time.perf_counter()
    done = subprocess.run(cmd, env=env, capture_output=True, text=True)
    if done.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} exited {done.returncode}: {done.stderr[-400:]}")
    return time.perf_counter() - t0


def measure(sizes: tuple[int, ...]) -> list[dict]:
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        for kind in ("ladder", "fan"):
            for k in sizes:
                path = work / f"{kind}_{k}.toml"
                path.write_text(families.family(kind, k))
                row = {"family": kind, "k": k}
                for backend in ("derive", "sympy", "numpy", "c"):
                    env = {**os.environ, "SYMKIN_CACHE": str(work / f"cache-{kind}{k}{backend}")}
                    cmd = (
                        SYMKIN + ["derive", str(path), "-o", str(work / f"out-{kind}{k}")]
                        if backend == "derive"
                        else SYMKIN + ["eval", str(path), *_inputs(kind, k), "--backend", backend]
                    )
                    log(f"scale: {kind} {k} {backend}")
                    row[backend] = _timed(cmd, env)
                rows.append(row)
    return rows


def render(rows: list[dict]) -> list[str]:
    out = [
        "| mechanism | loops | derive, all emitters (s) | eval sympy (s) | eval numpy (s) | "
        "eval c (s) |",
        "| --- | ---: | ---: | ---: | ---: | ---: |",
    ]
    for r in rows:
        out.append(
            f"| {r['family']} of {r['k']} | {r['k']} | {r['derive']:.1f} | "
            f"{r['sympy']:.1f} | {r['numpy']:.1f} | {r['c']:.1f} |"
        )
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="5,10,20", help="comma-separated k (default 5,10,20)")
    args = ap.parse_args()
    sizes = tuple(int(k) for k in args.sizes.split(","))
    load_before = os.getloadavg()
    rows = measure(sizes)
    save("scale", rows, render(rows), load_before)


if __name__ == "__main__":
    main()
