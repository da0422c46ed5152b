"""What the `loaded` level (the reduced equilibrium, docs/physics.md, "`loaded`: Newton on the
reduced equilibrium") costs in the generated C against `exact`, and the `equilibrium` level (mpmath,
geometrically exact beams) beside them, in one run: per configuration, on the four-bar and
mechanisms unlike the examples. The target (issue 23): `loaded` at most five times `exact` in C.

The C figures are timed inside C (benchmarks/symkin_c.py's harness calls `<name>_evaluate` per
configuration), best of several repeats, the levels interleaved; `equilibrium` is timed on a few
of the same configurations through symkin.evaluate. Run ``python benchmarks/loaded.py
[--points 400] [--repeats 5] [--equilibrium 2]``; it prints a table and writes
benchmarks/results-loaded.json with the load average (wall times on a shared machine move).
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

import numpy as np
from common import ROOT, log, save
from symkin_c import CBench, compile_c

import symkin
from symkin.codegen import pipeline
from symkin.core.levels import get as level_of

#: file -> input ranges
MECHANISMS = {
    "examples/four_bar.toml": {"A0": (-0.3, 0.3)},
    "tests/mechanisms/parallelogram.toml": {"F1": (-0.05, 0.05)},
    "tests/mechanisms/three_leg_stage.toml": {"F1": (-0.05, 0.05)},
}


def measure(points: int, repeats: int, n_equilibrium: int) -> list[dict]:
    rows = []
    rng = np.random.default_rng(1)
    for path, ranges in MECHANISMS.items():
        log(f"loaded: {path}")
        mech = symkin.load(ROOT / path)
        an = symkin.analyze(mech)
        p = pipeline.plan_for(an, sensitivity=False)
        x = np.column_stack([rng.uniform(lo, hi, points) for lo, hi in ranges.values()])
        row: dict = {"mechanism": path, "points": points}
        with tempfile.TemporaryDirectory() as work:
            header, code = pipeline.emit(p, "c", Path(path).name)
            cb = CBench(
                compile_c(Path(work), mech.name, header, code),
                mech.name,
                len(ranges),
                len(p.points),
            )
            best = {}
            for level in ("exact", "loaded"):
                _, _, failed = cb.run(x, level_of(level).code)  # warm
                row[f"{level}_failed"] = failed
                best[level] = float("inf")
            for _ in range(repeats):
                for level in ("exact", "loaded"):
                    secs = cb.per_point(x, level_of(level).code, min_time=0.2, repeat=1)
                    best[level] = min(best[level], secs)
        row.update({f"{level}_us": best[level] * 1e6 for level in best})
        row["loaded_over_exact"] = best["loaded"] / best["exact"]
        t0 = time.perf_counter()
        for k in range(n_equilibrium):
            inputs = {n: float(x[k, j]) for j, n in enumerate(ranges)}
            symkin.evaluate(an, inputs, level="equilibrium")
        row["equilibrium_us"] = (time.perf_counter() - t0) / max(n_equilibrium, 1) * 1e6
        rows.append(row)
    return rows


def render(rows: list[dict]) -> list[str]:
    out = [
        "| mechanism | exact (C, µs) | loaded (C, µs) | loaded / exact | equilibrium (mpmath, µs) "
        "| failed (exact, loaded) |",
        "| --- | --- | --- | --- | --- | --- |",
    ]
    for r in rows:
        out.append(
            f"| {Path(r['mechanism']).stem} | {r['exact_us']:.2f} | {r['loaded_us']:.2f} | "
            f"{r['loaded_over_exact']:.1f} | {r['equilibrium_us']:.3g} | "
            f"{r['exact_failed']}, {r['loaded_failed']} |"
        )
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--points", type=int, default=400)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--equilibrium", type=int, default=2, help="configurations at equilibrium")
    args = ap.parse_args()
    load = os.getloadavg()
    rows = measure(args.points, args.repeats, args.equilibrium)
    save("loaded", rows, render(rows), load)


if __name__ == "__main__":
    main()
