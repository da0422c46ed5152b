"""The finite-element study of docs/fea.md: the mesh convergence of the FE deviation and the
comparison of CalculiX with symkin's `equilibrium` and `loaded` levels.

    python benchmarks/fea.py [--only mesh|compare|bounds|model-error] [--out ...]

Writes the JSON (every number of docs/fea.md's tables) and prints the tables as Markdown; the
comparison's "bound" is the tests' continuum_bound (tests/test_fea.py). Needs
ccx (Debian package calculix-ccx). Runs one ccx at a time, single-threaded; ccx's processor time
is recorded beside the wall-clock time, which depends on the machine's load. About 30 minutes
of processor time in all. `--only model-error` sets the stored FE deviations beside
`equilibrium` with both beam theories, `loaded` and their `model_error` (no ccx run: the FE
model does not depend on the beam theory), a minute or two.
"""

from __future__ import annotations

import argparse
import json
import math
import platform
import re
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests"))

from test_fea import continuum_bound  # noqa: E402  the tests' bound of continuum - elastica

import symkin  # noqa: E402
from symkin import fea  # noqa: E402
from symkin.fea import ccx  # noqa: E402

EXAMPLES = ROOT / "examples"
OWN = ROOT / "tests" / "fea"

#: Mesh study: (label, file, inputs, params, released inputs).
STUDY = [
    ("single plate, t = l/10, theta = 0.2", OWN / "single_plate.toml", {"H": 0.2}, {}, ()),
    ("cantilever, t = l/100, alpha = 1", OWN / "cantilever.toml", {"H": 0}, {}, ("H",)),
    ("four-bar example, A0 = 0.2", EXAMPLES / "four_bar.toml", {"A0": 0.2}, {}, ()),
    (
        "parallel stage, t = l/20, F1 = 0.05, payload 2 N",
        OWN / "parallel_stage.toml",
        {"F1": 0.05},
        {},
        (),
    ),
]
MESHES = [fea.Mesh(n, k, g) for g in (0.0, 0.8) for n, k in ((10, 1), (20, 2), (40, 4), (80, 8))]

#: Comparison: (label, file, list of inputs, params).
NINE = [{"O": 0.02, "A": -0.02, "B": 0.01, "K": 0.02}, {"O": 0.1, "A": -0.1, "B": 0.05, "K": 0.1}]
COMPARE = [
    ("four_bar (example)", EXAMPLES / "four_bar.toml", [{"A0": a} for a in (0.02, 0.1, 0.3)], {}),
    (
        "stephenson_six_bar (example)",
        EXAMPLES / "stephenson_six_bar.toml",
        [{"O_A": a} for a in (0.02, 0.1, 0.3)],
        {},
    ),
    ("nine_bar_platform (example)", EXAMPLES / "nine_bar_platform.toml", NINE, {}),
    (
        "parallel_stage, payload 2 N",
        OWN / "parallel_stage.toml",
        [{"F1": a} for a in (0.02, 0.05, 0.1)],
        {},
    ),
    ("parallel_stage, no payload", OWN / "parallel_stage.toml", [{"F1": 0.05}], {"F": "0"}),
    (
        "four_bar_pins (pins at A, B)",
        OWN / "four_bar_pins.toml",
        [{"A0": a} for a in (0.02, 0.1, 0.3)],
        {},
    ),
    ("single_plate, t = l/10", OWN / "single_plate.toml", [{"H": 0.2}], {}),
    ("serial_pair, t = l/20", OWN / "serial_pair.toml", [{"S": 0.2, "E": -0.3}], {}),
]


def counts(log: str) -> tuple[int, int]:
    """Newton iterations and increments (attempts included) of a ccx run."""
    return (
        len(re.findall(r"^ iteration", log, re.M)),
        len(re.findall(r"increment \d+ attempt", log)),
    )


def mesh_study() -> list[dict]:
    out = []
    for label, path, inputs, params, released in STUDY:
        setup = fea.prepare(path, inputs, params)
        rows = []
        for mesh in MESHES:
            deck = fea.write_deck(setup, mesh, released)
            run = ccx.run(deck, setup.mechanism.name)
            dev = fea.deviations(deck, run)
            point = next(iter(dev))
            iterations, increments = counts(run.log)
            rows.append(
                {
                    "mesh": [mesh.along, mesh.across],
                    "grading": mesh.grading,
                    "point": point,
                    "deviation": list(dev[point]),
                    "nodes": deck.nodes,
                    "elements": deck.elements,
                    "ccx_seconds": run.seconds,
                    "ccx_cpu_seconds": run.cpu_seconds,
                    "iterations": iterations,
                    "increments": increments,
                }
            )
            print(f"  {label}: {mesh}: {dev[point]} ({run.cpu_seconds:.1f} s)", flush=True)
        graded = [r for r in rows if r["grading"] == 0.8]
        norms = [math.hypot(*r["deviation"]) for r in graded[-3:]]
        ratio = (norms[1] - norms[0]) / (norms[2] - norms[1])
        limit = norms[2] + (norms[2] - norms[1]) / (ratio - 1)  # Richardson, observed order
        for r in rows:
            r["error"] = abs(math.hypot(*r["deviation"]) - limit) / limit
        out.append({"case": label, "limit": limit, "ratio": ratio, "rows": rows})
    return out


def comparison() -> list[dict]:
    out = []
    for label, path, configurations, params in COMPARE:
        for inputs in configurations:
            setup = fea.prepare(path, inputs, params)
            deck = fea.write_deck(setup)
            t0 = time.perf_counter()
            result = fea.compare(setup, deck)
            data = result.as_json()
            for name, bound in continuum_bound(setup, inputs).items():
                data["points"][name]["bound"] = bound
            out.append(
                {
                    "case": label,
                    "file": str(path.relative_to(ROOT)),
                    "inputs": inputs,
                    "params": params,
                    **data,
                    "plates": len(setup.conf.plates),
                    "total_seconds": time.perf_counter() - t0,
                }
            )
            worst = max(p["difference"]["equilibrium"] for p in data["points"].values())
            print(
                f"  {label} {inputs}: fea vs equilibrium {100 * worst:.2f} % "
                f"({data['ccx_cpu_seconds']:.1f} s)",
                flush=True,
            )
    return out


def bounds(results: dict) -> None:
    """Add the tests' continuum_bound to every comparison that lacks it (no ccx run)."""
    for c in results.get("compare", []):
        setup = fea.prepare(ROOT / c["file"], c["inputs"], c["params"])
        for name, bound in continuum_bound(setup, c["inputs"]).items():
            c["points"][name]["bound"] = bound


def with_beam(path: Path, beam: str) -> symkin.Mechanism:
    """The mechanism of `path` with every plate's beam theory `beam` (in [defaults])."""
    text = path.read_text().replace("[defaults]\n", f'[defaults]\nbeam = "{beam}"\n', 1)
    return symkin.loads(text, str(path), path.parent)


def model_errors(results: dict) -> list[dict]:
    """Per stored comparison and point: the FE deviation, `equilibrium` (Reissner, elastica) and
    `loaded`, their relative differences from the FE and each level's model_error and parts."""
    out = []
    for c in results.get("compare", []):
        path = ROOT / c["file"]
        row = {"case": c["case"], "inputs": c["inputs"], "params": c["params"], "points": {}}
        levels = {}
        for key, beam, level in (
            ("reissner", "reissner", "equilibrium"),
            ("elastica", "elastica", "equilibrium"),
            ("loaded", "reissner", "loaded"),
        ):
            an = symkin.analyze(with_beam(path, beam))
            t0 = time.perf_counter()
            levels[key] = symkin.evaluate(an, c["inputs"], level=level, params=c["params"] or None)
            row[f"{key}_seconds"] = time.perf_counter() - t0
        for name, p in c["points"].items():
            fe = p["fea"]
            norm = math.hypot(*fe)
            entry = {"fea": fe}
            for key, r in levels.items():
                dev = r.points[name].deviation
                entry[key] = {
                    "deviation": list(dev),
                    "difference": math.hypot(dev[0] - fe[0], dev[1] - fe[1]) / norm,
                    "model_error": r.model_error[name],
                    "parts": r.model_error_parts[name],
                }
            row["points"][name] = entry
        row["mesh"], row["ccx_seconds"] = c["mesh"], c["ccx_seconds"]
        row["ccx_cpu_seconds"] = c["ccx_cpu_seconds"]
        out.append(row)
        print(f"  {c['case']} {c['inputs']}", flush=True)
    return out


def markdown(results: dict) -> str:
    lines = []
    for case in results.get("mesh", []):
        lines += [
            f"\n{case['case']} (point {case['rows'][0]['point']}; converged ‖ΔR‖ "
            f"{case['limit']:.7e}, observed ratio {case['ratio']:.2f})\n",
            "| mesh | grading | ‖ΔR‖ | error | nodes | ccx time (processor) | iterations |",
            "| --- | --- | --- | --- | --- | --- | --- |",
        ]
        for r in case["rows"]:
            lines.append(
                f"| {r['mesh'][0]} x {r['mesh'][1]} | {r['grading']:g} | "
                f"{math.hypot(*r['deviation']):.7e} | {100 * r['error']:.3f} % | "
                f"{r['nodes']} | {r['ccx_seconds']:.1f} s ({r['ccx_cpu_seconds']:.1f} s)"
                f" | {r['iterations']} |"
            )
    if results.get("compare"):
        lines += [
            "",
            "| mechanism | inputs (rad) | point | FE ‖ΔR‖ | equilibrium | loaded | "
            "bound | ccx time (processor) |",
            "| --- | --- | --- | --- | --- | --- | --- | --- |",
        ]
        for c in results["compare"]:
            inputs = ", ".join(f"{k} = {v}" for k, v in c["inputs"].items())
            for name, p in c["points"].items():
                d = p["difference"]
                loaded = "-" if d["loaded"] is None else f"{100 * d['loaded']:.2f} %"
                norm = math.hypot(*p["fea"])
                bound = f"{100 * p['bound'] / norm:.2f} %" if "bound" in p else "-"
                lines.append(
                    f"| {c['case']} | {inputs} | {name} | {norm:.4e} | "
                    f"{100 * d['equilibrium']:.2f} % | {loaded} | {bound} | "
                    f"{c['ccx_seconds']:.0f} s ({c['ccx_cpu_seconds']:.0f} s) |"
                )
    if results.get("model_error"):
        lines += [
            "",
            "| mechanism | inputs (rad) | point | FE ‖ΔR‖ | Reissner: diff. / model_error | "
            "elastica: diff. / model_error | loaded: diff. / model_error | FE mesh, "
            "ccx time (processor) |",
            "| --- | --- | --- | --- | --- | --- | --- | --- |",
        ]
        for c in results["model_error"]:
            inputs = ", ".join(f"{k} = {v}" for k, v in c["inputs"].items())
            for name, p in c["points"].items():
                cells = " | ".join(
                    f"{100 * p[k]['difference']:.2f} % / {100 * p[k]['model_error']:.2f} %"
                    for k in ("reissner", "elastica", "loaded")
                )
                lines.append(
                    f"| {c['case']} | {inputs} | {name} | {math.hypot(*p['fea']):.4e} | {cells} | "
                    f"{c['mesh'][0]} x {c['mesh'][1]}, {c['ccx_seconds']:.0f} s "
                    f"({c['ccx_cpu_seconds']:.0f} s) |"
                )
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--only",
        choices=("mesh", "compare", "bounds", "model-error"),
        help="one part; bounds: add the tests' bound to stored comparisons",
    )
    parser.add_argument("--out", default=str(ROOT / "benchmarks" / "results-fea.json"))
    args = parser.parse_args()
    out = Path(args.out)
    results = json.loads(out.read_text()) if out.exists() else {}
    results["machine"] = {
        "python": platform.python_version(),
        "machine": platform.machine(),
        "ccx": "2.20",
        "threads": 1,
        "default_mesh": str(fea.DEFAULT_MESH),
    }
    if args.only in (None, "mesh"):
        print("mesh study", flush=True)
        results["mesh"] = mesh_study()
        out.write_text(json.dumps(results, indent=1) + "\n")
    if args.only in (None, "compare"):
        print("comparison", flush=True)
        results["compare"] = comparison()
        out.write_text(json.dumps(results, indent=1) + "\n")
    if args.only in (None, "model-error"):
        print("model error", flush=True)
        results["model_error"] = model_errors(results)
        out.write_text(json.dumps(results, indent=1) + "\n")
    if args.only == "bounds":
        bounds(results)
        out.write_text(json.dumps(results, indent=1) + "\n")
    print(markdown(results))


if __name__ == "__main__":
    main()
