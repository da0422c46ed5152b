"""What one call of the plate relation's C routine costs (symkin.codegen.plate, the per-plate
kernel of the Newton level, docs/physics.md), before and after the kernels shared one T(p) and
became economised polynomials: the routine as commit 8aa0702 generated it (its symkin, unpacked
by `git archive` into a temporary directory and run there) against the working tree's.

Both are compiled with the benchmarks' flags into one program each, with a harness that reads the
same random inputs (θ, p, f, ε_a, ε_s) and calls `sk_plate_relation4` through a volatile function
pointer (no inlining into the loop), the clock read in C; the programs run interleaved, best of
several repeats. Input sets: `typical` (|θ| < 0.5, |p| < 3: the beam constraint model's range),
`near` (p in (-4, 16): the polynomials), `far` (p in (-9.5, -4) or (16, 60): the closed forms).
The outputs of both routines are compared on every input (largest difference relative to the
point's largest output).

Run ``python benchmarks/plate_routine.py [--points 4000] [--repeats 7]``; it prints a table and
writes benchmarks/results-plate_routine.json with the load average (wall times on a shared
machine move).
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tarfile
import tempfile
from pathlib import Path

import numpy as np
from common import C_FLAGS, ROOT, log, save

from symkin.codegen.backends.c.backend import standalone
from symkin.codegen.plate import plate_routine

BEFORE = "8aa0702"

HARNESS = r"""
#define _POSIX_C_SOURCE 199309L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
{routine}
/* argv: input file (n x 5 doubles), n, calls per repeat over the inputs, repeats, output file.
   Prints the best ns per call; writes the 12 outputs of every input. */
int main(int argc, char **argv)
{{
    void (*volatile call)(const double *, double *) = sk_plate_relation4;
    const int n = atoi(argv[2]), reps = atoi(argv[3]), repeats = atoi(argv[4]);
    double *in = malloc(sizeof(double) * 5 * (size_t)n);
    double *out = malloc(sizeof(double) * 12 * (size_t)n);
    double best = 1e300, sink = 0.0;
    struct timespec t0, t1;
    int r, k, i;
    FILE *f = fopen(argv[1], "rb");
    if (argc != 6 || !f || fread(in, sizeof(double), 5 * (size_t)n, f) != 5 * (size_t)n) return 1;
    fclose(f);
    for (k = 0; k < repeats; ++k) {{
        clock_gettime(CLOCK_MONOTONIC, &t0);
        for (r = 0; r < reps; ++r) {{
            for (i = 0; i < n; ++i) {{
                call(in + 5 * i, out + 12 * i);
            }}
            sink += out[0];
        }}
        clock_gettime(CLOCK_MONOTONIC, &t1);
        {{
            const double s = (double)(t1.tv_sec - t0.tv_sec);
            const double t = (s + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec)) / reps / n * 1e9;
            if (t < best) best = t;
        }}
    }}
    f = fopen(argv[5], "wb");
    if (!f || fwrite(out, sizeof(double), 12 * (size_t)n, f) != 12 * (size_t)n) return 1;
    fclose(f);
    printf("%.3f %g\n", best, sink);
    return 0;
}}
"""

#: input set -> (θ range, p ranges (drawn with equal weight), f range)
SETS = {
    "typical": ((-0.5, 0.5), [(-3.0, 3.0)], (-1.0, 1.0)),
    "near": ((-1.0, 1.0), [(-4.0, 16.0)], (-1.0, 1.0)),
    "far": ((-1.0, 1.0), [(-9.5, -4.0), (16.0, 60.0)], (-1.0, 1.0)),
}


def before_source(work: Path) -> str:
    """The routine's C as commit BEFORE generated it (its own symkin, in a fresh process)."""
    tree = work / f"symkin-{BEFORE}"
    tree.mkdir()
    archive = work / "before.tar"
    with archive.open("wb") as fh:
        subprocess.run(["git", "archive", BEFORE, "symkin"], cwd=ROOT, stdout=fh, check=True)
    with tarfile.open(archive) as tar:
        tar.extractall(tree, filter="data")
    code = (
        "import symkin, sys\n"
        f"assert symkin.__file__.startswith({str(tree)!r}), symkin.__file__\n"
        "from symkin.codegen.backends.c.backend import standalone\n"
        "from symkin.codegen.plate import plate_routine\n"
        "sys.stdout.write(standalone(plate_routine(4)))\n"
    )
    env = dict(os.environ, PYTHONPATH=str(tree))
    run = subprocess.run(
        [sys.executable, "-c", code], cwd=tree, env=env, check=True, capture_output=True, text=True
    )
    return run.stdout


def build(work: Path, name: str, routine: str) -> Path:
    src = work / f"{name}.c"
    src.write_text(HARNESS.format(routine=routine))
    exe = work / name
    cc = os.environ.get("CC", "cc")
    flags = [f for f in C_FLAGS if f != "-fPIC"]
    subprocess.run([cc, *flags, str(src), "-o", str(exe), "-lm"], check=True)
    return exe


def inputs(kind: str, n: int) -> np.ndarray:
    """(n, 5) rows of (θ, p, f, ε_a, ε_s), seeded."""
    rng = np.random.default_rng(7)
    theta, p_ranges, f = SETS[kind]
    which = rng.integers(0, len(p_ranges), n)
    p = np.array([rng.uniform(*p_ranges[w]) for w in which])
    return np.column_stack(
        [
            rng.uniform(*theta, n),
            p,
            rng.uniform(*f, n),
            rng.uniform(0.0, 1e-3, n),
            rng.uniform(0.0, 3e-3, n),
        ]
    )


def measure(points: int, repeats: int) -> list[dict]:
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        log("plate routine: generating both versions")
        exes = {
            "before": build(work, "plate_before", before_source(work)),
            "after": build(work, "plate_after", standalone(plate_routine(4))),
        }
        reps = max(1, 200_000 // points)
        for kind in SETS:
            log(f"plate routine: {kind}")
            x = inputs(kind, points)
            data = work / f"{kind}.bin"
            x.astype(np.float64).tofile(data)
            best = {v: float("inf") for v in exes}
            outputs = {}
            for _ in range(repeats):  # interleaved: a change of the machine's load hits both
                for version, exe in exes.items():
                    out = work / f"{kind}-{version}.out"
                    run = subprocess.run(
                        [str(exe), str(data), str(points), str(reps), "3", str(out)],
                        check=True,
                        capture_output=True,
                        text=True,
                    )
                    best[version] = min(best[version], float(run.stdout.split()[0]))
                    outputs[version] = np.fromfile(out).reshape(points, 12)
            scale = np.max(np.abs(outputs["before"]), axis=1, keepdims=True)
            diff = np.max(np.abs(outputs["after"] - outputs["before"]) / scale)
            rows.append(
                {
                    "inputs": kind,
                    "points": points,
                    "before_ns": best["before"],
                    "after_ns": best["after"],
                    "speedup": best["before"] / best["after"],
                    "max_difference": float(diff),
                }
            )
    return rows


def render(rows: list[dict]) -> list[str]:
    out = [
        f"Plate routine (sk_plate_relation4), ns per call, {BEFORE} against the working tree:",
        "",
        "| inputs | before (ns) | after (ns) | speed-up | max difference / largest output |",
        "| --- | ---: | ---: | ---: | ---: |",
    ]
    for r in rows:
        out.append(
            f"| {r['inputs']} | {r['before_ns']:.0f} | {r['after_ns']:.0f} | "
            f"{r['speedup']:.2f} | {r['max_difference']:.1e} |"
        )
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--points", type=int, default=4000)
    ap.add_argument("--repeats", type=int, default=7)
    args = ap.parse_args()
    load_before = os.getloadavg()
    rows = measure(args.points, args.repeats)
    save("plate_routine", rows, render(rows), load_before)


if __name__ == "__main__":
    main()
