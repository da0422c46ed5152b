"""Survey of the symkin command line on the zoo (tests/mechanisms/): every file at a few inputs,
every level and backend of `symkin eval --json`, compared with the independent reference
(tests/reference_solver.py) at the kinematic levels and with `equilibrium` at `loaded`.

Run from the repository root with the project's venv active:

    python tests/mechanisms/survey.py [--out results.json] [--only NAME,...]

Each `symkin` run is capped at 120 s (`timeout`) and niced. The raw results go to a JSON file;
SURVEY.md beside this script is written by hand from them.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

import mpmath  # noqa: E402
from reference_solver import Reference, ReferenceAssemblyError, load_unchecked  # noqa: E402

CAP = 120
#: (file, list of input dicts): 0, 1e-6 and typical working inputs
CASES = {
    "parallelogram": [{"F1": "0"}, {"F1": "1e-6"}, {"F1": "0.05"}, {"F1": "0.1"}],
    "parallelogram_mm": [{"F1": "0"}, {"F1": "1e-6"}, {"F1": "0.05"}, {"F1": "0.1"}],
    "three_leg_stage": [{"F1": "0"}, {"F1": "1e-6"}, {"F1": "0.05"}],
    "double_parallelogram": [
        {"F1": "0", "I1": "0"},
        {"F1": "1e-6", "I1": "-1e-6"},
        {"F1": "0.05", "I1": "-0.05"},
        {"F1": "0.03", "I1": "0.02"},
    ],
    "scott_russell": [{"RA0": "0"}, {"RA0": "1e-6"}, {"RA0": "0.01"}, {"RA0": "0.02"}],
    "roberts": [{"O1": "0"}, {"O1": "1e-6"}, {"O1": "0.1"}, {"O1": "-0.2"}],
    "toggle_four_bar": [{"O1": "0"}, {"O1": "1e-6"}, {"O1": "0.2"}, {"O1": "0.34"}],
    "lever_amplifier": [{"P0": "0"}, {"P0": "1e-6"}, {"P0": "0.005"}, {"P0": "0.01"}],
}
RUNS = [
    ("paper", "sympy"),
    ("paper", "numpy"),
    ("paper", "c"),
    ("first_order", "sympy"),
    ("first_order", "numpy"),
    ("first_order", "c"),
    ("exact", "sympy"),
    ("exact", "numpy"),
    ("exact", "c"),
    ("loaded", "sympy"),
    ("equilibrium", "sympy"),
]


def run_symkin(args: list[str]) -> dict:
    """One niced, capped symkin run: exit code, stderr, wall and CPU seconds, parsed JSON."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    proc = subprocess.run(
        ["timeout", str(CAP), "nice", "-n", "10", "symkin", *args], capture_output=True, text=True
    )
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    out = {
        "rc": proc.returncode,
        "wall": round(wall, 2),
        "cpu": round(cpu, 2),
        "stderr": proc.stderr.strip()[-600:],
    }
    if proc.returncode == 0:
        try:
            out["json"] = json.loads(proc.stdout)
        except json.JSONDecodeError:
            out["stdout"] = proc.stdout[-600:]
    return out


def reference(name: str, inputs: dict) -> dict:
    """The reference's rigid and compliant positions and deviation of every point (floats),
    or the reason it has none."""
    mech = load_unchecked(HERE / f"{name}.toml")
    try:
        d = Reference(mech).deviation(inputs)
    except ReferenceAssemblyError as exc:
        return {"error": str(exc)}
    with mpmath.workdps(d["dps"]):
        return {
            "points": {
                p: {k: [float(x) for x in v[k]] for k in ("rigid", "deviation")}
                for p, v in d["points"].items()
            }
        }


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--out", default="survey-results.json")
    parser.add_argument("--only", default="")
    parser.add_argument("--report", metavar="RESULTS", help="print the tables of a results file")
    parser.add_argument(
        "--physics",
        metavar="RESULTS",
        help="compare a results file's physical levels with the elastica oracle",
    )
    args = parser.parse_args()
    if args.report:
        print(report(args.report))
        return
    if args.physics:
        print(physics(args.physics))
        return
    only = [s for s in args.only.split(",") if s]
    results = []
    for name, inputs_list in CASES.items():
        if only and name not in only:
            continue
        path = str(HERE / f"{name}.toml")
        check = run_symkin(["check", path])
        results.append({"file": name, "command": "check", **check})
        print(name, "check", check["rc"], flush=True)
        for inputs in inputs_list:
            ref = reference(name, inputs)
            flags = [a for k, v in inputs.items() for a in ("--input", f"{k}={v}")]
            for level, backend in RUNS:
                r = run_symkin(
                    ["eval", path, *flags, "--level", level, "--backend", backend, "--json"]
                )
                entry = {
                    "file": name,
                    "inputs": inputs,
                    "level": level,
                    "backend": backend,
                    "reference": ref,
                    **r,
                }
                results.append(entry)
                print(name, inputs, level, backend, r["rc"], r["wall"], flush=True)
                Path(args.out).write_text(json.dumps(results, indent=1))
    Path(args.out).write_text(json.dumps(results, indent=1))


# --------------------------------------------------------------------------------------------
# report: markdown tables from the results file
# --------------------------------------------------------------------------------------------
def _norm(v) -> float:
    return (v[0] ** 2 + v[1] ** 2) ** 0.5


def _rel(got, want) -> str:
    diff = _norm([got[0] - want[0], got[1] - want[1]])
    size = _norm(want)
    if size == 0:
        return f"abs {diff:.1e}"
    return f"{diff / size:.1e}"


def _inputs(inputs: dict) -> str:
    return ", ".join(f"{k}={v}" for k, v in inputs.items())


def _message(stderr: str) -> str:
    line = stderr.replace("\n", " ").replace("|", "/")
    for prefix in (str(HERE) + "/",):
        line = line.replace(prefix, "")
    return line[:160]


def report(path: str) -> str:
    results = json.loads(Path(path).read_text())
    out = []
    evals = [r for r in results if r.get("command") != "check"]
    out.append("### Failures (exit code ≠ 0)\n")
    out.append("| file | inputs | level | backend | exit | s | message |")
    out.append("| --- | --- | --- | --- | --- | --- | --- |")
    for r in evals:
        if r["rc"] != 0:
            msg = "timeout (120 s)" if r["rc"] == 124 else _message(r["stderr"])
            out.append(
                f"| {r['file']} | {_inputs(r['inputs'])} | {r['level']} | "
                f"{r['backend']} | {r['rc']} | {r['wall']} | {msg} |"
            )
    out.append(
        "\n### Kinematic levels against the reference (relative error of the deviation, "
        "‖Δ − Δref‖ / ‖Δref‖)\n"
    )
    out.append(
        "| file | inputs | point | ‖Δref‖ | paper (s/n/c) | first_order (s/n/c) | exact (s/n/c) |"
    )
    out.append("| --- | --- | --- | --- | --- | --- | --- |")
    groups: dict = {}
    for r in evals:
        groups.setdefault((r["file"], json.dumps(r["inputs"])), []).append(r)
    for (name, inputs), rs in groups.items():
        ref = rs[0]["reference"]
        if "points" not in ref:
            continue
        for point, rv in ref["points"].items():
            cells = []
            for level in ("paper", "first_order", "exact"):
                parts = []
                for backend in ("sympy", "numpy", "c"):
                    r = next(x for x in rs if x["level"] == level and x["backend"] == backend)
                    if r["rc"] != 0:
                        parts.append(f"rc{r['rc']}")
                    else:
                        parts.append(_rel(r["json"]["points"][point]["deviation"], rv["deviation"]))
                cells.append(" / ".join(parts))
            out.append(
                f"| {name} | {_inputs(json.loads(inputs))} | {point} | "
                f"{_norm(rv['deviation']):.3e} | " + " | ".join(cells) + " |"
            )
    out.append(
        "\n### Physical levels: `loaded` against `equilibrium` (sympy backend)\n\n"
        '"kinematic" is the reference\'s circular-arc deviation.\n'
    )
    out.append("| file | inputs | point | ‖Δeq‖ | loaded vs eq | kinematic vs eq | s loaded / eq |")
    out.append("| --- | --- | --- | --- | --- | --- | --- |")
    for (name, inputs), rs in groups.items():
        eq = next(x for x in rs if x["level"] == "equilibrium")
        ld = next(x for x in rs if x["level"] == "loaded")
        ref = rs[0]["reference"]
        if eq["rc"] != 0:
            continue
        for point, v in eq["json"]["points"].items():
            d_eq = v["deviation"]
            # below 1e-20 (file units) both are rounding noise of a zero deviation
            d_eq = d_eq if _norm(d_eq) > 1e-20 else [0.0, 0.0]
            l_cell = (
                _rel(ld["json"]["points"][point]["deviation"], d_eq)
                if ld["rc"] == 0
                else f"rc{ld['rc']}"
            )
            e_cell = _rel(ref["points"][point]["deviation"], d_eq) if "points" in ref else "—"
            out.append(
                f"| {name} | {_inputs(json.loads(inputs))} | {point} | "
                f"{_norm(d_eq):.3e} | {l_cell} | {e_cell} | {ld['wall']} / "
                f"{eq['wall']} |"
            )
    out.append("\n### Wall time per run (s): median and max over the zoo\n")
    out.append("| level | backend | runs | failed | median | max |")
    out.append("| --- | --- | --- | --- | --- | --- |")
    for level, backend in RUNS:
        rs = [r for r in evals if r["level"] == level and r["backend"] == backend]
        if not rs:
            continue
        walls = sorted(r["wall"] for r in rs)
        fails = sum(r["rc"] != 0 for r in rs)
        out.append(
            f"| {level} | {backend} | {len(rs)} | {fails} | "
            f"{walls[len(walls) // 2]} | {walls[-1]} |"
        )
    cpu = sum(r["cpu"] for r in results)
    out.append(f"\nTotal CPU time of the symkin runs: {cpu:.0f} s.")
    return "\n".join(out)


#: the independent elastica reference (tests/reference_physics.py, shooting) on the zoo: file,
#: inputs, E in N per (file unit)^2, nu, width, thickness, loads (point, force in N)
PHYSICS = [
    ("parallelogram", {"F1": "0.05"}, "210e9", "0.3", "10e-3", "0.15e-3", []),
    ("parallelogram", {"F1": "1e-6"}, "210e9", "0.3", "10e-3", "0.15e-3", []),
    ("roberts", {"O1": "0.1"}, "114e9", "0.34", "6e-3", "0.11e-3", []),
    ("scott_russell", {"RA0": "0"}, "70e3", "0.33", "10", "0.25", [("B", ("0", "-5"))]),
    ("scott_russell", {"RA0": "0.02"}, "70e3", "0.33", "10", "0.25", [("B", ("0", "-5"))]),
    ("lever_amplifier", {"P0": "0.01"}, "200e3", "0.29", "5", "0.02", [("OUT", ("0", "0.01"))]),
    (
        "double_parallelogram",
        {"F1": "0.03", "I1": "0.02"},
        "210e3",
        "0.3",
        "10",
        "0.2",
        [("S", ("0", "-9.81"))],
    ),
    ("toggle_four_bar", {"O1": "0.2"}, "169e-3", "0.22", "25", "2", []),
    ("toggle_four_bar", {"O1": "0.34"}, "169e-3", "0.22", "25", "2", []),
]


def physics(path: str) -> str:
    """symkin's `equilibrium` and `loaded` (from a results file) against the independent
    elastica reference, as a markdown table. Plates at least 5 thicknesses wide: E' = E/(1-nu^2)."""
    from reference_physics import Equilibrium, point_load

    import symkin

    results = json.loads(Path(path).read_text())

    def sym(name, inputs, level):
        return next(
            r
            for r in results
            if r["file"] == name and r.get("inputs") == inputs and r.get("level") == level
        )["json"]["points"]

    out = [
        "| file | inputs | point | ‖Δ‖ elastica reference | symkin equilibrium | symkin loaded |",
        "| --- | --- | --- | --- | --- | --- |",
    ]
    for name, inputs, E, nu, width, thick, loads in PHYSICS:
        mech = symkin.load(HERE / f"{name}.toml")
        with mpmath.workdps(30):
            e_plane = mpmath.mpf(E) / (1 - mpmath.mpf(nu) ** 2)
        eq = Equilibrium(
            mech,
            stiffness=(e_plane, width, thick),
            loads=[point_load(mech, p, f) for p, f in loads],
        )
        res = eq.solve(inputs)
        with mpmath.workdps(res["dps"]):
            for point, v in res["points"].items():
                want = [float(x) for x in v["deviation"]]
                cells = [
                    _rel(sym(name, inputs, level)[point]["deviation"], want)
                    for level in ("equilibrium", "loaded")
                ]
                out.append(
                    f"| {name} | {_inputs(inputs)} | {point} | {_norm(want):.4e} | "
                    + " | ".join(cells)
                    + " |"
                )
    return "\n".join(out)


if __name__ == "__main__":
    os.environ.setdefault("SYMKIN_CACHE", "/tmp/symkin-zoo-survey-cache")
    main()
