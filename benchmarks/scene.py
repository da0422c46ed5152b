"""What a scene's per-point variants save (docs/scene.md): the nine-bar platform with one tight and
one loose point, the scene evaluator against the cheapest single variant meeting both.

Two points the example does not have are added by the scene: P8 on b8 (in loop 2 only) and P5 on
b5 (loop 1). Two scenes:

- ``kinematic``: reference `exact`; P8 to 1e-12 m absolute, P5 to 5 % relative;
- ``physical``: reference `equilibrium` (the plates' elastica under the file's data); P8 to 1 %
  relative, P5 to 300 % relative (the kinematic levels are 2-3x off at these angles, so a loose
  point may take one).

For each: `symkin derive --scene` (C), and the single variant the same measurement picks for both
points, derived with `--points P8,P5` (pruned alike). Figures: the weighted operation counts the
choice ranks by, and the C time per configuration (scene evaluator vs single evaluator, both timed
inside C over the same input rows, interleaved, best of the repeats).

Run ``python benchmarks/scene.py [--points 2000] [--repeats 5]``; it prints a table and writes
benchmarks/results-scene.json with the machine's load average.
"""

from __future__ import annotations

import argparse
import ctypes
import dataclasses
import os
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np
from common import C_FLAGS, ROOT, log, save

import symkin
from symkin.studies import scene as scenes
from symkin.studies.derive import generate

NINE_BAR = ROOT / "examples" / "nine_bar_platform.toml"
POINTS = """
[[point]]
name = "P8"
link = "b8"
at = [0.1, 0.01]
{p8}

[[point]]
name = "P5"
link = "b5"
at = [0.18, 0.075]
{p5}
"""
SCENES = {
    "kinematic": ('reference = "exact"', "tolerance = 1e-12", "relative_tolerance = 0.05"),
    "physical": (
        'reference = "equilibrium"',
        "relative_tolerance = 0.01",
        "relative_tolerance = 3.0",
    ),
}
RANGE = 0.1
TIMER = r"""
#define _POSIX_C_SOURCE 199309L
#include <stddef.h>
#include <time.h>
#include "NAME.h"

double bench_time(const double *inputs, int n, int repeats, double *sink)
{
    struct timespec t0, t1;
    double out[6 * UPPER_N_POINTS];
    double acc = 0.0;
    int r, i;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    for (r = 0; r < repeats; ++r) {
        for (i = 0; i < n; ++i) {
            if (CALL == 0) {
                acc += out[4];
            }
        }
    }
    clock_gettime(CLOCK_MONOTONIC, &t1);
    *sink = acc;
    return (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec);
}
"""


def _library(files: dict[str, bytes], name: str, call: str, folder: Path) -> ctypes.CDLL:
    """Compile every generated .c with the timer calling `call`; the loaded library."""
    for file, data in files.items():
        (folder / file).write_bytes(data)
    timer = TIMER.replace("UPPER", name.upper()).replace("NAME", name).replace("CALL", call)
    (folder / f"timer_{name}.c").write_text(timer)
    sources = [str(p) for p in sorted(folder.glob("*.c"))]
    lib = folder / f"lib{name}.so"
    subprocess.run(["cc", *C_FLAGS, "-shared", *sources, "-o", str(lib), "-lm"], check=True)
    dll = ctypes.CDLL(str(lib))
    dll.bench_time.restype = ctypes.c_double
    dll.bench_time.argtypes = [
        ctypes.POINTER(ctypes.c_double),
        ctypes.c_int,
        ctypes.c_int,
        ctypes.POINTER(ctypes.c_double),
    ]
    return dll


def _time(lib: ctypes.CDLL, rows: np.ndarray, repeats: int) -> float:
    data = np.ascontiguousarray(rows, dtype=float)
    sink = ctypes.c_double()
    ptr = data.ctypes.data_as(ctypes.POINTER(ctypes.c_double))
    return lib.bench_time(ptr, len(data), repeats, ctypes.byref(sink)) / (len(data) * repeats)


def run(n_points: int, repeats: int) -> list[dict]:
    mech = symkin.load(NINE_BAR)
    rows_out = []
    for key, (reference, p8, p5) in SCENES.items():
        text = (
            f'format = 1\nname = "stage_{key}"\n{reference}\n[ranges]\n'
            + "".join(f"{h} = [{-RANGE}, {RANGE}]\n" for h in mech.inputs)
            + POINTS.format(p8=p8, p5=p5)
        )
        scene = scenes.loads(text, mech, f"{key}.toml")
        start = time.perf_counter()
        files, choice = scenes.generate(scene, ["c"])
        seconds = time.perf_counter() - start
        single = choice.single
        name = scene.name
        single_name = f"{name}_single"
        single_files = generate(
            dataclasses.replace(scene.mechanism, name=single_name),
            ["c"],
            list(scene.point_names),
            variant=single.variant,
        )
        rng = np.random.default_rng(1)
        x = rng.uniform(-RANGE, RANGE, size=(n_points, len(mech.inputs)))
        with tempfile.TemporaryDirectory() as a, tempfile.TemporaryDirectory() as b:
            lib = _library(
                files,
                name,
                f"{name}_evaluate(inputs + (size_t)i * {name.upper()}_N_INPUTS, NULL, out)",
                Path(a),
            )
            code = symkin.core.levels.get(single.variant.level).code
            lib1 = _library(
                single_files,
                single_name,
                f"{single_name}_evaluate(inputs + (size_t)i * "
                f"{single_name.upper()}_N_INPUTS, NULL, {code}, out)",
                Path(b),
            )
            # the scene takes the free inputs in label order, the single evaluator its own
            best, best1 = float("inf"), float("inf")
            for _ in range(repeats):
                best = min(best, _time(lib, x, 1))
                best1 = min(best1, _time(lib1, x, 1))
        row = {
            "scene": key,
            "choice": {p: g.variant.name for g in choice.groups for p in g.points},
            "errors": {p: {"absolute": e[0], "relative": e[1]} for p, e in choice.errors.items()},
            "single": single.variant.name,
            "cost_scene": sum(g.cost for g in choice.groups),
            "cost_single": single.cost,
            "ns_scene": best * 1e9,
            "ns_single": best1 * 1e9,
            "derive_seconds": seconds,
        }
        row["time_ratio"] = row["ns_single"] / row["ns_scene"]
        row["cost_ratio"] = row["cost_single"] / row["cost_scene"]
        rows_out.append(row)
        log(
            f"{key}: scene {row['choice']} cost {row['cost_scene']} ({row['ns_scene']:.0f} ns) "
            f"vs single {single.variant.name} cost {single.cost} ({row['ns_single']:.0f} ns): "
            f"{row['time_ratio']:.2f}x faster, ops {row['cost_ratio']:.2f}x"
        )
    return rows_out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--points", type=int, default=2000)
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    before = os.getloadavg()
    rows = run(args.points, args.repeats)
    table = [
        f"{'scene':<10} {'per point':<40} {'single':<16} {'ops':>11} {'C ns':>13} "
        f"{'ops x':>6} {'time x':>6}"
    ]
    for r in rows:
        choice = ", ".join(f"{p} {v}" for p, v in r["choice"].items())
        table.append(
            f"{r['scene']:<10} {choice:<40} {r['single']:<16} "
            f"{r['cost_scene']:>5}/{r['cost_single']:<5} "
            f"{r['ns_scene']:>6.0f}/{r['ns_single']:<6.0f} {r['cost_ratio']:>6.2f} "
            f"{r['time_ratio']:>6.2f}"
        )
    save("scene", rows, table, before)


if __name__ == "__main__":
    main()
