"""Notch mechanisms against a plane-strain CalculiX continuum, under both of its finite-strain
laws (docs/physics.md, "Notch mechanisms against a continuum"; docs/fea.md, "Material law").

    python benchmarks/notch_mechanisms.py [--meshes 20,2 40,4 ...] [--study 80,8]
                                          [--out benchmarks/results-notch_mechanisms.json]
                                          [--keep-levels]

Three mechanisms with right-circular notches R = 1 mm, t = 0.1 mm (t/R = 0.1), b = 10 mm, steel
(tests/mechanisms/notch_four_bar.toml, notch_parallelogram.toml, notch_lever.toml), each at
inputs 0.02 and 0.05 rad, without and with a dead load on its point; every case meshed by
`symkin fea` (the notch's element columns following its thickness) at each of `--meshes` under
St. Venant–Kirchhoff (`--law svk`, ccx's *ELASTIC under NLGEOM) and neo-Hookean (`--law
neo-hookean`), and evaluated at `equilibrium` (the notch beam with its continuum correction),
with its model_error, and at the kinematic `exact` level for contrast. `--study` runs a finer
mesh on the four-bar's cases as well (the convergence stated in docs/physics.md).

ccx runs are cached in the JSON by case, law and mesh: a second call runs only what is missing
(the levels are evaluated again: they are cheap beside ccx). One ccx at a time, one thread.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from symkin import analyze, evaluate  # noqa: E402
from symkin.fea import ccx, deviations, parse_mesh, prepare, write_deck  # noqa: E402

OUT = ROOT / "benchmarks" / "results-notch_mechanisms.json"
MECHANISMS = ROOT / "tests" / "mechanisms"
#: name -> (file, input hinge, point read, dead load P in N: the file's parameter P, downwards)
CASES = {
    "four-bar": ("notch_four_bar.toml", "A0", "C", 1.0),
    "parallelogram": ("notch_parallelogram.toml", "F1", "P", 5.0),
    "lever": ("notch_lever.toml", "O", "out", 5.0),
}
INPUTS = (0.02, 0.05)
LAWS = ("svk", "neo-hookean")
MESHES = ("20,2", "40,4")


def key(case: str, angle: float, load: float, law: str, mesh: str) -> str:
    return f"{case}|{angle:g}|{load:g}|{law}|{mesh}"


def norm(v) -> float:
    return math.hypot(v[0], v[1])


def rel(a, b) -> float:
    """|a - b| / |b| of two 2-vectors."""
    return math.hypot(a[0] - b[0], a[1] - b[1]) / norm(b)


def fe_run(case: str, angle: float, load: float, law: str, mesh: str) -> dict:
    file, hinge, point, _ = CASES[case]
    setup = prepare(MECHANISMS / file, {hinge: angle}, {"P": load})
    deck = write_deck(setup, parse_mesh(mesh), law=law)
    run = ccx.run(deck, setup.mechanism.name, threads=1)
    fe = deviations(deck, run)[point]
    return {
        "deviation": list(fe),
        "elements": deck.elements,
        "nodes": deck.nodes,
        "ccx_seconds": run.seconds,
        "ccx_cpu_seconds": run.cpu_seconds,
    }


def levels(case: str, angle: float, load: float) -> dict:
    file, hinge, point, _ = CASES[case]
    out = {}
    analysis = analyze(MECHANISMS / file)
    for level in ("equilibrium", "exact"):
        start = time.perf_counter()
        ev = evaluate(analysis, {hinge: angle}, level=level, params={"P": load})
        entry = {
            "deviation": [float(c) for c in ev.points[point].deviation],
            "seconds": time.perf_counter() - start,
        }
        if level == "equilibrium":
            entry["model_error"] = float(ev.model_error[point])
            parts = getattr(ev, "model_error_parts", {}) or {}
            if point in parts:
                entry["model_error_parts"] = {k: float(v) for k, v in parts[point].items()}
        out[level] = entry
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--meshes", nargs="+", default=list(MESHES))
    ap.add_argument("--study", nargs="*", default=[], help="finer meshes on the four-bar only")
    ap.add_argument("--out", type=Path, default=OUT)
    ap.add_argument(
        "--keep-levels",
        action="store_true",
        help="reuse the levels cached in the JSON (default: evaluate them again)",
    )
    args = ap.parse_args()
    cache = json.loads(args.out.read_text()) if args.out.exists() else {}
    fe_rows = cache.get("fe", {})
    level_rows = cache.get("levels", {}) if args.keep_levels else {}
    load_before = os.getloadavg()
    for case, (_, _, _, dead) in CASES.items():
        meshes = list(args.meshes) + (list(args.study) if case == "four-bar" else [])
        for angle in INPUTS:
            for load in (0.0, dead):
                lk = key(case, angle, load, "-", "-")
                if lk not in level_rows:
                    level_rows[lk] = levels(case, angle, load)
                for mesh in meshes:
                    for law in LAWS:
                        k = key(case, angle, load, law, mesh)
                        if k in fe_rows:
                            continue
                        start = time.perf_counter()
                        fe_rows[k] = fe_run(case, angle, load, law, mesh)
                        print(
                            f"[{time.strftime('%H:%M:%S')}] {k}: "
                            f"{norm(fe_rows[k]['deviation']):.6e} "
                            f"({time.perf_counter() - start:.1f} s)",
                            file=sys.stderr,
                            flush=True,
                        )
                        partial = {**cache, "fe": fe_rows, "levels": level_rows}
                        args.out.write_text(json.dumps(partial, indent=1) + "\n")
    table = [
        "ΔR in mm at the finest mesh run (elements per notch, columns following the thickness); "
        "diff. = |ΔR_eq − ΔR_FE| / |ΔR_FE|; spread = |ΔR_NH − ΔR_SVK| / |ΔR_SVK|; mesh change: "
        "|ΔR_FE| from the next coarser mesh, SVK / NH",
        "| mechanism | input (rad) | load (N) | mesh | FE SVK ‖ΔR‖ | FE neo-Hookean ‖ΔR‖ | "
        "equilibrium ‖ΔR‖ | diff. SVK | diff. NH | spread | model_error | exact ‖ΔR‖ | "
        "mesh change |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    summary = []
    for case, (_, _, _, dead) in CASES.items():
        meshes = list(args.meshes) + (list(args.study) if case == "four-bar" else [])
        for angle in INPUTS:
            for load in (0.0, dead):
                lv = level_rows[key(case, angle, load, "-", "-")]
                eq = lv["equilibrium"]["deviation"]
                ran = [m for m in meshes if key(case, angle, load, "svk", m) in fe_rows]
                fine = ran[-1]
                svk = fe_rows[key(case, angle, load, "svk", fine)]["deviation"]
                nh = fe_rows[key(case, angle, load, "neo-hookean", fine)]["deviation"]
                change = []
                for law in LAWS:
                    finest = fe_rows[key(case, angle, load, law, fine)]["deviation"]
                    if len(ran) > 1:
                        prev = fe_rows[key(case, angle, load, law, ran[-2])]["deviation"]
                        change.append(f"{100 * rel(prev, finest):.2f} %")
                row = {
                    "mechanism": case,
                    "input": angle,
                    "load": load,
                    "fe_svk": svk,
                    "fe_neo_hookean": nh,
                    "equilibrium": eq,
                    "exact": lv["exact"]["deviation"],
                    "difference_svk": rel(eq, svk),
                    "difference_neo_hookean": rel(eq, nh),
                    "spread": rel(nh, svk),
                    "model_error": lv["equilibrium"]["model_error"],
                    "model_error_parts": lv["equilibrium"].get("model_error_parts"),
                    "mesh": fine,
                }
                summary.append(row)
                table.append(
                    f"| {case} | {angle:g} | {load:g} | {fine} | {norm(svk):.4e} | "
                    f"{norm(nh):.4e} | {norm(eq):.4e} | {100 * row['difference_svk']:.2f} % | "
                    f"{100 * row['difference_neo_hookean']:.2f} % | "
                    f"{100 * row['spread']:.2f} % | {100 * row['model_error']:.2f} % | "
                    f"{norm(lv['exact']['deviation']):.4e} | {' / '.join(change)} |"
                )
    print("\n".join(table))
    results = {
        "command": "python " + " ".join(sys.argv),
        "date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
        "machine": {
            "system": f"{platform.system()} {platform.release()} {platform.machine()}",
            "cores": os.cpu_count(),
            "python": platform.python_version(),
            "ccx": "CalculiX 2.20 (single-threaded)",
        },
        "load_average_before": load_before,
        "load_average_after": os.getloadavg(),
        "summary": summary,
        "levels": level_rows,
        "fe": fe_rows,
    }
    args.out.write_text(json.dumps(results, indent=1) + "\n")


if __name__ == "__main__":
    main()
