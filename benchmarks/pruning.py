"""What dependency pruning saves (docs/pruning.md): one point of a large mechanism, in the C.

For a fan of k four-bars (point C1 on the first coupler, one loop of k) and a ladder of k loops
(a point P1 on the first rung, one loop of k; benchmarks/families.py), three C evaluators at
level `exact`, built by `symkin.compile`:

- ``full``: the point alone requested but every loop solved (what `--points` did before pruning);
- ``pruned``: `--points` as it is now (only the loops that move the point);
- ``alone``: the one loop by itself (a lone four-bar, a ladder of one).

The figures are the generated code's operation counts (after CSE, from its header) and the C time
per configuration through `evaluate_rows` (one call per batch), best of several repeats, the
three interleaved. The goal: ``pruned`` within 1.5x of ``alone``. A last row takes the
nine-bar platform's point F (examples/), which rides on links the inputs alone place: pruned, it
solves no loop (``alone`` is then the pruned evaluator itself).

Run ``python benchmarks/pruning.py [--sizes 1,2,5,10,20] [--points 2000] [--repeats 5]``; it prints
a table and writes benchmarks/results-pruning.json with the machine's load average.
"""

from __future__ import annotations

import argparse
import os
import re
import time

import families
import numpy as np
from common import ROOT, log, save

import symkin
from symkin.graph.structure import build
from symkin.kinematics.analysis import Analysis

POINT = {"fan": "C1", "ladder": "P1", "nine_bar": "F"}


def _text(kind: str, k: int) -> str:
    if kind == "fan":
        return families.fan(k)
    return families.ladder(k) + families._point("P1", "r1", 0.02, 0.06)


def _ops(header: str) -> dict[str, int]:
    """Routine -> operation count, from the generated header's 'Operation counts' line."""
    line = next(x for x in header.splitlines() if "Operation counts after CSE" in x)
    return {m.group(1): int(m.group(2)) for m in re.finditer(r"(\w+) (\d+)", line.split(":")[1])}


def _evaluators(kind: str, k: int) -> dict[str, symkin.studies.compiled.Compiled]:
    point = POINT[kind]
    opts = {"backend": "c", "levels": ["exact"], "sensitivity": False}
    if kind == "nine_bar":
        mech = symkin.load(ROOT / "examples" / "nine_bar_platform.toml")
        pruned = symkin.compile(mech, points=[point], **opts)
        return {
            "full": symkin.compile(Analysis(build(mech), [point]), points=[point], **opts),
            "pruned": pruned,
            "alone": pruned,
        }
    mech = symkin.loads(_text(kind, k), f"{kind}_{k}.toml")
    alone = symkin.loads(_text(kind, 1), f"{kind}_1.toml")
    return {
        "full": symkin.compile(Analysis(build(mech), [point]), points=[point], **opts),
        "pruned": symkin.compile(mech, points=[point], **opts),
        "alone": symkin.compile(alone, points=[point], **opts),
    }


def _rows(ev, n: int, rng: np.random.Generator) -> np.ndarray:
    return np.column_stack([rng.uniform(-0.1, 0.2, n) for _ in ev.inputs])


def measure(sizes: tuple[int, ...], points: int, repeats: int) -> list[dict]:
    out = []
    for kind, ks in (("fan", sizes), ("ladder", sizes), ("nine_bar", (1,))):
        for k in ks:
            log(f"pruning: {kind} {k}")
            evs = _evaluators(kind, k)
            rng = np.random.default_rng(3)
            # the same input rows for the point's own input(s); the full fan's other cranks
            # take their own values (they move only their own loops)
            x = {tag: _rows(ev, points, rng) for tag, ev in evs.items()}
            # the point's own inputs take the same values in every evaluator; the full
            # mechanism's other inputs (a fan's other cranks) their own
            for tag in ("full", "pruned"):
                for j, name in enumerate(evs["alone"].inputs):
                    x[tag][:, list(evs[tag].inputs).index(name)] = x["alone"][:, j]
            row = {"family": kind, "k": k, "point": POINT[kind]}
            for tag, ev in evs.items():
                status, _res = ev.evaluate_rows(x[tag], "exact")
                row[f"{tag}_failed"] = int((status != 0).sum())
                ops = _ops(ev.sources.header)
                row[f"{tag}_ops"] = ops
                row[f"{tag}_ops_rigid_newton"] = ops.get("rigid", 0) + ops.get("newton", 0)
            want = evs["full"].evaluate_rows(x["full"], "exact")[1]
            got = evs["pruned"].evaluate_rows(x["pruned"], "exact")[1]
            row["pruned_vs_full_max_rel"] = float(
                np.nanmax(np.abs(got - want)) / np.nanmax(np.abs(want))
            )
            best = {tag: float("inf") for tag in evs}
            for _ in range(repeats):
                for tag, ev in evs.items():
                    t0 = time.perf_counter()
                    ev.evaluate_rows(x[tag], "exact")
                    best[tag] = min(best[tag], time.perf_counter() - t0)
            for tag in evs:
                row[f"{tag}_ns"] = best[tag] / points * 1e9
            row["pruned_over_alone"] = row["pruned_ns"] / row["alone_ns"]
            row["full_over_pruned"] = row["full_ns"] / row["pruned_ns"]
            out.append(row)
    return out


def render(rows: list[dict]) -> list[str]:
    out = [
        "| mechanism | point | ops rigid+newton full / pruned / alone | C ns full | C ns pruned "
        "| C ns alone | pruned / alone | full / pruned |",
        "| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: |",
    ]
    for r in rows:
        name = "nine-bar platform" if r["family"] == "nine_bar" else f"{r['family']} of {r['k']}"
        out.append(
            f"| {name} | {r['point']} | "
            f"{r['full_ops_rigid_newton']} / {r['pruned_ops_rigid_newton']} / "
            f"{r['alone_ops_rigid_newton']} | {r['full_ns']:.0f} | {r['pruned_ns']:.0f} | "
            f"{r['alone_ns']:.0f} | {r['pruned_over_alone']:.2f} | "
            f"{r['full_over_pruned']:.2f} |"
        )
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="1,2,5,10,20")
    ap.add_argument("--points", type=int, default=2000)
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args()
    sizes = tuple(int(k) for k in args.sizes.split(","))
    load_before = os.getloadavg()
    rows = measure(sizes, args.points, args.repeats)
    save("pruning", rows, render(rows), load_before)


if __name__ == "__main__":
    main()
