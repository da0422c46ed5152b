"""What each deviation level costs in the generated C, against the `exact` level, on the examples
(docs/levels.md, docs/physics.md): `loaded` runs Newton on the reduced equilibrium, the plate
relation called per plate and iteration (`loaded_refined`, code 5, is retired and not timed).

Every level runs through `symkin.compile`'s `evaluate_rows` (one C call evaluates the whole
batch into preallocated arrays, so the figure is the evaluator's own time per configuration) over
the same
uniformly sampled inputs (benchmarks/common.py's ranges), best of several repeats, the levels
interleaved so that a change of the machine's load hits them alike.

Each level is also timed inside C (``*_c`` columns): the same generated source, compiled with a
harness of benchmarks/symkin_c.py that calls `<name>_evaluate` (one configuration) over the rows
and reads the clock in C, so the difference from the first figure is what ctypes, numpy and the
batch call add.

Run ``python benchmarks/levels.py [--points 4000] [--repeats 7] [--span 0.3]``; it prints a table
and writes benchmarks/results-levels.json with the load average (wall times on a shared machine
move). With ``--span s`` every input is drawn from (-s, s) instead of the examples' ranges (the
figure of issue 21: the four-bar's `exact` over (-0.3, 0.3), best of 9).
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

import numpy as np
from common import EXAMPLES, ROOT, log, save
from symkin_c import CBench, compile_c

import symkin
from symkin.codegen import pipeline
from symkin.core.levels import get as level_of

LEVELS = ("paper", "first_order", "exact", "loaded")


def inputs_for(example: str, n: int, span: float | None = None) -> np.ndarray:
    """(n, n_inputs) rows, uniform over the example's ranges (or (-span, span))."""
    rng = np.random.default_rng(1)
    ranges = [(-span, span) if span else r for r in EXAMPLES[example].values()]
    return np.column_stack([rng.uniform(lo, hi, n) for lo, hi in ranges])


def in_c(example: str, work: Path) -> CBench:
    """The example's generated C (as symkin.compile builds it: no sensitivities) with the C
    timing harness."""
    mech = symkin.load(ROOT / "examples" / f"{example}.toml")
    p = pipeline.plan_for(symkin.analyze(mech), sensitivity=False)
    header, code = pipeline.emit(p, "c", f"{example}.toml")
    lib = compile_c(work, mech.name, header, code)
    return CBench(lib, mech.name, len(mech.inputs), len(p.points))


def measure(points: int, repeats: int, span: float | None = None) -> list[dict]:
    rows = []
    for example in EXAMPLES:
        log(f"levels: {example}")
        ev = symkin.compile(ROOT / "examples" / f"{example}.toml", backend="c", sensitivity=False)
        assert list(ev.inputs) == list(EXAMPLES[example])
        x = inputs_for(example, points, span)
        row = {"example": example, "points": points, "span": span}
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
        with tempfile.TemporaryDirectory() as work:
            cb = in_c(example, Path(work))
            for level in LEVELS:
                code = level_of(level).code
                _, _, failed = cb.run(x, code)  # warm
                assert failed == row[f"{level}_failed"], f"{example} {level}: C harness differs"
                row[f"{level}_c"] = min(cb.run(x, code)[0] for _ in range(repeats)) / points * 1e9
        row["loaded_over_exact"] = row["loaded"] / row["exact"]
        rows.append(row)
    return rows


def render(rows: list[dict]) -> list[str]:
    out = [
        "| example | " + " | ".join(f"{lv} (ns)" for lv in LEVELS) + " | loaded / exact |",
        "| --- |" + " ---: |" * (len(LEVELS) + 1),
    ]
    for r in rows:
        out.append(
            f"| {r['example']} | "
            + " | ".join(f"{r[lv]:.0f}" for lv in LEVELS)
            + f" | {r['loaded_over_exact']:.2f} |"
        )
    out += [
        "",
        "Timed inside C (`<name>_evaluate` per configuration, the clock read in C):",
        "",
        "| example | " + " | ".join(f"{lv} (ns)" for lv in LEVELS) + " |",
        "| --- |" + " ---: |" * len(LEVELS),
    ]
    for r in rows:
        out.append(
            f"| {r['example']} | " + " | ".join(f"{r[lv + '_c']:.0f}" for lv in LEVELS) + " |"
        )
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--points", type=int, default=4000)
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--span", type=float, default=None, help="inputs in (-span, span)")
    args = ap.parse_args()
    load_before = os.getloadavg()
    rows = measure(args.points, args.repeats, args.span)
    save("levels", rows, render(rows), load_before)


if __name__ == "__main__":
    main()
