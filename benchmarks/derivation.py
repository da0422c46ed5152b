"""Derivation time and memory (`symkin.studies.derive.generate`, every emitter, all levels), each
case in
a fresh process, on the examples and on the families of benchmarks/families.py, with growth
exponents fitted on log-log.

    python benchmarks/derivation.py KIND ARG     (the child: one case, one JSON line)
"""

from __future__ import annotations

import importlib
import json
import math
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import families
import numpy as np
from common import ROOT, log


def emitters() -> list[str]:
    """Every emitter symkin has: the derivation is timed with all of them."""
    from symkin.studies.derive import EMITTERS

    return list(EMITTERS)


def peak_rss_mb() -> float:
    """Peak resident set of this process (VmHWM; ru_maxrss would carry the parent's peak over
    fork + exec on Linux)."""
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("VmHWM:"):
                return int(line.split()[1]) / 1024
    except (OSError, ValueError, IndexError):
        pass
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def derive_child(kind: str, arg: str) -> None:
    """Runs in a fresh process: prints one JSON line with the derivation's time and memory."""
    t_start = time.perf_counter()
    import symkin.codegen.plan  # noqa: F401 - the emitters' imports are start-up, not derivation
    from symkin.studies.derive import generate

    for module in ("numpy.backend", "c.backend", "latex.report"):
        importlib.import_module(f"symkin.codegen.backends.{module}")
    rss0 = peak_rss_mb()
    t_import = time.perf_counter() - t_start
    mech = mechanism(kind, arg)
    stats = sizes_of(mech)
    emit = emitters()
    marks = []
    t0 = time.perf_counter()
    files = generate(
        mech, emit=emit, progress=lambda msg: marks.append((time.perf_counter() - t0, msg))
    )
    total = time.perf_counter() - t0
    rss1 = peak_rss_mb()
    phases, prev = {}, (0.0, "start")
    for t, msg in marks + [(total, "end")]:
        if prev[1] != "start":
            phases[prev[1]] = t - prev[0]
        prev = (t, msg)
    print(
        json.dumps(
            {
                **stats,
                "emit": emit,
                "derive_s": total,
                "import_s": t_import,
                "phases_s": phases,
                "without_latex_s": total - sum(v for k, v in phases.items() if "LaTeX" in k),
                "maxrss_mb": rss1,
                "baseline_rss_mb": rss0,
                "output_kb": sum(len(v) for v in files.values()) / 1024,
            }
        )
    )


def mechanism(kind: str, arg):
    """The mechanism of one case: an example by name, or a family member by size."""
    import symkin

    if kind == "example":
        return symkin.load(ROOT / "examples" / f"{arg}.toml")
    return symkin.loads(families.family(kind, int(arg)), f"{kind}_{arg}.toml")


def structure_stats(kind: str, arg) -> dict:
    """Links, hinges, loops and path sizes of one case (for the cases not run)."""
    return sizes_of(mechanism(kind, arg))


def sizes_of(mech) -> dict:
    """Links, hinges, loops, inputs and path sizes of a mechanism."""
    import symkin

    s = symkin.structure(mech)
    paths = [len(s.tree_path(i)) for i in range(1, s.n + 1)]
    return {
        "links": s.n + 1,
        "hinges": s.m,
        "loops": s.m - s.n,
        "inputs": len(mech.inputs),
        "mean_path": sum(paths) / len(paths),
        "size": s.m * sum(paths) / len(paths),
    }


def derive_case(kind: str, arg, budget: float) -> dict:
    """One case in a fresh process (this file as the child), within `budget` seconds."""
    cmd = [sys.executable, str(Path(__file__).resolve()), kind, str(arg)]
    t0 = time.perf_counter()
    try:
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=budget, cwd=ROOT)
    except subprocess.TimeoutExpired:
        log(f"derive {kind} {arg}: over budget ({budget:.0f} s)")
        return {
            "kind": kind,
            "case": str(arg),
            "over_budget": True,
            "budget_s": budget,
            **structure_stats(kind, arg),
        }
    wall = time.perf_counter() - t0
    if proc.returncode != 0:
        return {"kind": kind, "case": str(arg), "error": proc.stderr.strip()[-500:]}
    out = json.loads(proc.stdout.strip().splitlines()[-1])
    out.update(kind=kind, case=str(arg), process_wall_s=wall, over_budget=False)
    log(f"derive {kind} {arg}: {out['derive_s']:.2f} s, peak RSS {out['maxrss_mb']:.0f} MB")
    return out


def cli_derive(example: str) -> dict:
    """Wall time of the whole `symkin derive` command (start-up and writing included)."""
    with tempfile.TemporaryDirectory() as tmp:
        cmd = [
            sys.executable,
            "-m",
            "symkin",
            "derive",
            str(ROOT / "examples" / f"{example}.toml"),
            "-o",
            tmp,
            "--quiet",
            "--emit",
            ",".join(emitters()),
        ]
        t0 = time.perf_counter()
        proc = subprocess.run(cmd, capture_output=True, text=True, cwd=ROOT)
        return {
            "wall_s": time.perf_counter() - t0,
            "exit": proc.returncode,
            "stderr": proc.stderr.strip()[-300:],
        }


def fit(xs, ys) -> float | None:
    """Least-squares slope of log y against log x; None with fewer than two points."""
    pts = [(math.log(x), math.log(y)) for x, y in zip(xs, ys) if x > 0 and y > 0]
    if len(pts) < 2:
        return None
    a = np.array(pts)
    return float(np.polyfit(a[:, 0], a[:, 1], 1)[0])


def exponents(cases: list[dict]) -> dict:
    """Growth exponents of a family's time and memory against its size and its hinges."""
    ok = [c for c in cases if not c.get("over_budget") and "derive_s" in c]
    out = {}
    for label, key in (("size", "size"), ("hinges", "hinges")):
        xs = [c[key] for c in ok]
        ys = [c["derive_s"] for c in ok]
        core = [c["without_latex_s"] for c in ok]
        out[f"time_vs_{label}_last_step"] = fit(xs[-2:], ys[-2:]) if len(ok) >= 2 else None
        out[f"core_vs_{label}_largest3"] = fit(xs[-3:], core[-3:]) if len(ok) >= 3 else None
        out[f"time_vs_{label}"] = fit(xs, ys)
        out[f"time_vs_{label}_largest3"] = fit(xs[-3:], ys[-3:]) if len(ok) >= 3 else None
        mem = [max(c["maxrss_mb"] - c["baseline_rss_mb"], 1e-3) for c in ok]
        out[f"memory_vs_{label}_largest3"] = fit(xs[-3:], mem[-3:]) if len(ok) >= 3 else None
    return out


def measure(examples, serial, ladder, budget: float) -> dict:
    """Every derivation case: the examples (with the whole command's wall time) and the families
    up to their first member over `budget` seconds (the larger ones are reported as skipped)."""
    dv: dict = {"budget_s": budget, "emitters": emitters(), "examples": []}
    for e in examples:
        case = derive_case("example", e, budget)
        case["cli"] = cli_derive(e)
        dv["examples"].append(case)
    for kind, sizes in (("serial", serial), ("ladder", ladder)):
        dv[kind] = []
        over = False
        for n in sizes:
            if over:  # a larger member of a family already over budget: skip, say so
                dv[kind].append(
                    {
                        "kind": kind,
                        "case": str(n),
                        "over_budget": True,
                        "budget_s": budget,
                        "skipped": True,
                        **structure_stats(kind, n),
                    }
                )
                continue
            case = derive_case(kind, n, budget)
            over = bool(case.get("over_budget"))
            dv[kind].append(case)
    dv["exponents"] = {k: exponents(dv[k]) for k in ("serial", "ladder")}
    return dv


if __name__ == "__main__":
    derive_child(*sys.argv[1:])
