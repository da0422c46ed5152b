"""What each deviation level costs in the generated C, against the `exact` level, on the examples
(docs/levels.md, docs/physics.md): `loaded` is meant to cost at most twice `exact`;
`loaded_refined` solves the statics, the compliance and the closure a second time.

Every level runs through `symkin.compile`'s `evaluate_rows` (one C call evaluates the whole
batch into preallocated arrays, so the figure is the evaluator's own time per configuration) over
the same
uniformly sampled inputs (benchmarks/common.py's ranges), best of several repeats, the levels
interleaved so that a change of the machine's load hits them alike.

Run ``python benchmarks/levels.py [--points 4000] [--repeats 7]``; it prints a table and writes
benchmarks/results-levels.json with the load average (wall times on a shared machine move).
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np
from common import EXAMPLES, ROOT, log, save

import symkin

LEVELS = ("paper", "first_order", "exact", "loaded", "loaded_refined")


def inputs_for(example: str, n: int) -> np.ndarray:
    """(n, n_inputs) rows, uniform over the example's ranges."""
    rng = np.random.default_rng(1)
    return np.column_stack([rng.uniform(lo, hi, n) for lo, hi in EXAMPLES[example].values()])


def measure(points: int, repeats: int) -> list[dict]:
    rows = []
    for example in EXAMPLES:
        log(f"levels: {example}")
        ev = symkin.compile(ROOT / "examples" / f"{example}.toml", backend="c", sensitivity=False)
        assert list(ev.inputs) == list(EXAMPLES[example])
        x = inputs_for(example, points)
        row = {"example": example, "points": points}
        best = {level: float("inf") for level in LEVELS}
        for level in LEVELS:  # warm: the library is built and loaded
            status, _ = ev.evaluate_rows(x, level)
            row[f"{level}_failed"] = int((status != 0).sum())
        for _ in range(repeats):
            for level in LEVELS:
                t0 = time.perf_counter()
                ev.evaluate_rows(x, level)
                best[level] = min(best[level], time.perf_counter() - t0)
        row.update({level: best[level] / points * 1e9 for level in LEVELS})
        row["loaded_over_exact"] = row["loaded"] / row["exact"]
        row["refined_over_exact"] = row["loaded_refined"] / row["exact"]
        rows.append(row)
    return rows


def render(rows: list[dict]) -> list[str]:
    out = [
        "| example | "
        + " | ".join(f"{lv} (ns)" for lv in LEVELS)
        + " | loaded / exact | loaded_refined / exact |",
        "| --- |" + " ---: |" * (len(LEVELS) + 2),
    ]
    for r in rows:
        out.append(
            f"| {r['example']} | "
            + " | ".join(f"{r[lv]:.0f}" for lv in LEVELS)
            + f" | {r['loaded_over_exact']:.2f} | {r['refined_over_exact']:.2f} |"
        )
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--points", type=int, default=4000)
    ap.add_argument("--repeats", type=int, default=7)
    args = ap.parse_args()
    load_before = os.getloadavg()
    rows = measure(args.points, args.repeats)
    save("levels", rows, render(rows), load_before)


if __name__ == "__main__":
    main()
