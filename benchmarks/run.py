"""symkin benchmarks: one command, every number in one run.

    python benchmarks/run.py [--quick | --smoke] [--no-page] [--budget SECONDS]

Measures, on this machine:

1. Per point, exact level, for each example (evaluators.py): symkin's generated C (timed inside
   C, symkin_c.py), symkin's numpy module (vectorized over 10^4 points), `sympy.lambdify` of the
   same closed form with the same Newton loop in Python (lambdify_alt.py),
   `scipy.optimize.root` on the compliant loop equations (scipy_alt.py), and SymForce-generated
   C++ for the same routines driven by the same algorithm (symforce_alt.py with
   symforce_driver.cc, where SymForce installs). Every alternative is first checked to give the
   same deviation as the C evaluator; the drivers follow symkin.core.settings's settings.
2. Throughput: the numpy module on 10^6 points against the C evaluator called 10^6 times in a
   C loop.
3. Derivation (derivation.py: `symkin.studies.derive.generate`, every emitter, all levels) time and
peak
   memory on the examples and on generated families (families.py), each in a fresh process,
   with growth exponents fitted by least squares on log-log.
4. Sweeps and sensitivities (sweeps.py): batch calls against one ctypes call per point, a
   sensitivity evaluation against a deviation evaluation in C, `symkin sweep` throughput on
   this machine's cores against the single-core C rate, Dask's overhead per chunk. Its own
   block of docs/benchmarks.md (`<!-- sweeps:start -->`); `--only sweeps` measures and rewrites
   only that.

Writes benchmarks/results.json (raw numbers) and rewrites only the docs/benchmarks.md block between
`<!-- benchmarks:start -->` and `<!-- benchmarks:end -->` (report.py; read-modify-write at the
very end). `--quick` measures less and writes results-quick.json; `--smoke` runs every part once
at the smallest sizes to check that it works, prints the block and writes nothing.
"""

from __future__ import annotations

import argparse
import datetime
import json
import subprocess
import tempfile
import time
from pathlib import Path

import sweeps
from common import BENCH, FULL, POLICY, QUICK, ROOT, SMOKE, first_line, log, machine
from derivation import measure
from evaluators import bench_example
from report import render, targets, write_page
from symforce_alt import symforce_status


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    size = ap.add_mutually_exclusive_group()
    size.add_argument("--quick", action="store_true", help="smaller sizes, shorter timings")
    size.add_argument(
        "--smoke",
        action="store_true",
        help="every part once at the smallest sizes; prints, writes nothing",
    )
    ap.add_argument("--no-page", action="store_true", help="do not rewrite docs/benchmarks.md")
    ap.add_argument(
        "--budget",
        type=float,
        default=120.0,
        help="seconds allowed per derivation case (default 120)",
    )
    ap.add_argument(
        "--only",
        choices=("sweeps",),
        help="measure only this part; rewrites only its block of docs/benchmarks.md",
    )
    args = ap.parse_args()
    sizes = SMOKE if args.smoke else QUICK if args.quick else FULL
    if args.only == "sweeps":
        run_sweeps(
            sizes, args.no_page, {"date": datetime.date.today().isoformat(), "machine": machine()}
        )
        return
    t_start = time.perf_counter()
    results: dict = {
        "quick": sizes is not FULL,
        "sizes": sizes.name,
        "date": datetime.date.today().isoformat(),
        "machine": machine(),
        "solver": POLICY,
        "symkin_commit": first_line(["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"]),
        "symkin_dirty": bool(
            subprocess.run(
                ["git", "-C", str(ROOT), "status", "--porcelain", "symkin", "templates"],
                capture_output=True,
                text=True,
            ).stdout.strip()
        ),
    }
    log("machine: " + json.dumps(results["machine"]))
    results["symforce"] = symforce_status(install=sizes.install_symforce)
    log(f"SymForce: {results['symforce']}")

    with tempfile.TemporaryDirectory(prefix="symkin-bench-") as tmp:
        results["evaluators"] = {
            e: bench_example(e, sizes, results["symforce"], Path(tmp)) for e in sizes.examples
        }
    examples = sizes.examples if sizes is not SMOKE else sizes.examples[:1]
    results["derivation"] = measure(examples, sizes.serial, sizes.ladder, args.budget)
    results["total_s"] = time.perf_counter() - t_start
    results["targets"] = targets(results)
    block = render(results)
    print(block)
    if sizes is SMOKE:
        log(f"smoke run done in {results['total_s'] / 60:.1f} min; nothing written")
        run_sweeps(sizes, True, {"date": results["date"], "machine": results["machine"]})
        return
    out = BENCH / ("results-quick.json" if sizes is QUICK else "results.json")
    out.write_text(json.dumps(results, indent=1, default=str) + "\n")
    if not args.no_page:
        write_page(block)  # read-modify-write of the marked block only, at the end
    log(f"done in {results['total_s'] / 60:.1f} min; raw numbers in {out.relative_to(ROOT)}")
    run_sweeps(sizes, args.no_page, {"date": results["date"], "machine": results["machine"]})


def run_sweeps(sizes, no_page: bool, header: dict) -> None:
    """Part 4 (sweeps.py): measured, printed, written to results-sweeps.json and its block of
    docs/benchmarks.md (not for --smoke)."""
    t0 = time.perf_counter()
    results = {
        **header,
        "sizes": sizes.name,
        "sweeps": sweeps.measure(sizes),
        "symkin_commit": first_line(["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"]),
    }
    results["total_s"] = time.perf_counter() - t0
    results["targets"] = sweeps.targets(results)
    m = results["machine"]
    block = "\n".join(
        [
            f"Measured {results['date']} by `python benchmarks/run.py --only sweeps` in "
            f"{results['total_s'] / 60:.1f} min (symkin at commit {results['symkin_commit']}) on "
            f"{m['cpu']}, {m['cores']} cores; raw numbers: `benchmarks/results-sweeps.json`.",
            "",
        ]
        + sweeps.render(results)
        + ["", "Targets:", ""]
        + [
            f"- {'met' if t['met'] else 'MISSED'}: {t['text']} — measured {t['measured']}"
            for t in results["targets"]
        ]
    )
    print(block)
    if sizes is SMOKE:
        return
    (BENCH / ("results-sweeps-quick.json" if sizes is QUICK else "results-sweeps.json")).write_text(
        json.dumps(results, indent=1, default=str) + "\n"
    )
    if not no_page:
        write_page(block, "<!-- sweeps:start -->", "<!-- sweeps:end -->")


if __name__ == "__main__":
    main()
