"""Per point on the designs a flexure designer builds (issue 48): a hinge-driven four-bar,
examples/piezo_amplifier.toml (a piezo's stroke), tests/mechanisms/bridge_amplifier.toml (a
stroke, 10 plates, 3 loops) and both driven by a force instead; each actuated file also with the
actuator replaced by the input hinge it turns (its link's frame hinge), to compare what the
drive costs. In one run, every figure beside the others:

- C: the generated `<name>_evaluate` at every generated level and `<name>_loaded_report`, timed
  inside C (a loop in its own translation unit, benchmarks/symkin_c.py's flags) over the same
  points, best of several repeats, the variants interleaved;
- numpy: the generated module's `evaluate` on a batch at every level, at `loaded` with and
  without its report (`report=False`), best of several repeats;
- with `--compare REV`, the same files emitted by symkin at git revision REV (exported with
  `git archive`, emitted in a subprocess) timed interleaved with the working tree's: the ratios
  after / before come from one run;
- the cold start of the bridge: `symkin eval --level loaded --backend c` and `symkin derive`
  in a fresh process on an empty cache (SYMKIN_CACHE, SYMKIN_PLAN_CACHE; docs/cli.md).

Each figure carries the load average read when it was measured (the machine is shared: ratios
within one run move less than times). Run ``python benchmarks/designs.py [--points 2000]
[--batch 4000] [--repeats 5] [--compare REV] [--no-cold]``; it prints the tables and writes
benchmarks/results-designs.json.
"""

from __future__ import annotations

import argparse
import ctypes
import datetime
import importlib.util
import json
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from common import BENCH, C_FLAGS, ROOT, first_line, log, machine

#: label -> (file, input ranges, transform): "hinge" drives the file's actuated link by its frame
#: hinge instead, "force" makes its stroke actuator a force actuator
DESIGNS = {
    "four_bar (hinge)": ("examples/four_bar.toml", {"A0": (-0.3, 0.3)}, None),
    "piezo_amplifier (stroke)": ("examples/piezo_amplifier.toml", {"piezo": (0.0, 0.05)}, None),
    "piezo_amplifier (hinge RA0)": ("examples/piezo_amplifier.toml", {"RA0": (-5e-3, 0)}, "hinge"),
    "piezo_amplifier (force)": ("examples/piezo_amplifier.toml", {"piezo": (0.0, 2.0)}, "force"),
    "bridge_amplifier (stroke)": (
        "tests/mechanisms/bridge_amplifier.toml",
        {"piezo": (0.0, 0.01)},
        None,
    ),
    "bridge_amplifier (hinge SL0)": (
        "tests/mechanisms/bridge_amplifier.toml",
        {"SL0": (-1e-3, 0)},
        "hinge",
    ),
    "bridge_amplifier (force)": (
        "tests/mechanisms/bridge_amplifier.toml",
        {"piezo": (0.0, 2.0)},
        "force",
    ),
}
LEVEL_CODES = {"paper": 0, "first_order": 1, "exact": 2, "loaded": 3}

HARNESS = r"""
#define _POSIX_C_SOURCE 199309L
#include <stddef.h>
#include <time.h>
#include "{name}.h"
static double sk_now(void)
{{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}}
/* level >= 0: <name>_evaluate at it; -1: <name>_loaded_report. Seconds; failures counted. */
double bench(const double *x, int n, int level, int reps, double *out, int *failures)
{{
    int r, i, fails = 0;
    const double t0 = sk_now();
    for (r = 0; r < reps; ++r) {{
        for (i = 0; i < n; ++i) {{
            const double *in = x + (size_t)i * {NAME}_N_INPUTS;
            fails += ({report}) != 0;
        }}
    }}
    *failures = fails;
    return sk_now() - t0;
}}
"""


def variant_text(path: Path, transform: str | None) -> str:
    """The file's text, its actuator turned into a force or replaced by the input hinge it
    turns (the frame hinge of the actuated link)."""
    text = path.read_text()
    if transform is None:
        return text
    if transform == "force":
        return text.replace('drive = "stroke"', 'drive = "force"')
    link = re.search(r'\[\[actuator\]\][^\[]*?link = "([^"]+)"', text, re.S).group(1)
    text = re.sub(r"\n\[\[actuator\]\].*?(?=\n\[\[|\Z)", "\n", text, flags=re.S)
    frame = re.search(r'ground = "([^"]+)"', text).group(1)
    pattern = rf'(links = \["{frame}", "{link}"\]\n(?:.*\n)*?plate_angle = [^\n]*)'
    return re.sub(pattern, r"\1\ninput = true", text, count=1)


EMIT = r"""
import json, sys
from pathlib import Path
import symkin
from symkin.codegen import pipeline
out = Path(sys.argv[1])
for spec in json.loads(sys.argv[2]):
    an = symkin.analyze(symkin.load(spec["file"]))
    p = pipeline.plan_for(an, sensitivity=False)
    h, c = pipeline.emit(p, "c", Path(spec["file"]).name)
    (py,) = pipeline.emit(p, "numpy", Path(spec["file"]).name)
    d = out / spec["key"]
    d.mkdir(parents=True, exist_ok=True)
    (d / "name").write_text(an.mechanism.name)
    (d / "levels").write_text(" ".join(lv.name for lv in p.levels))
    for suffix, text in ((".h", h), (".c", c), (".py", py)):
        (d / (an.mechanism.name + suffix)).write_text(text)
"""


def emit_all(specs: list[dict], out: Path, tree: Path | None) -> None:
    """Emit every spec's C and numpy with the working tree's symkin, or `tree`'s."""
    env = dict(os.environ, SYMKIN_PLAN_CACHE="off")
    if tree is not None:
        env["PYTHONPATH"] = str(tree)
    subprocess.run(
        [sys.executable, "-c", EMIT, str(out), json.dumps(specs)], env=env, check=True, cwd=out
    )


def export(rev: str, into: Path) -> Path:
    """The tree of git revision `rev`, importable as symkin (its templates where it reads them)."""
    into.mkdir(parents=True)
    archive = subprocess.run(["git", "-C", str(ROOT), "archive", rev], capture_output=True)
    subprocess.run(["tar", "-x", "-C", str(into)], input=archive.stdout, check=True)
    link = into / "symkin" / "templates"
    if not link.exists():
        link.symlink_to(into / "templates")
    return into


class Built:
    """One emitted design: its C library with the harness, its numpy module."""

    def __init__(self, folder: Path, tag: str):
        self.name = (folder / "name").read_text()
        self.levels = (folder / "levels").read_text().split()
        name, big = self.name, self.name.upper()
        (folder / "harness.c").write_text(
            HARNESS.format(
                name=name,
                NAME=big,
                report=f"level < 0 ? {name}_loaded_report(in, NULL, out) : "
                f"{name}_evaluate(in, NULL, level, out)"
                if "loaded" in self.levels
                else f"{name}_evaluate(in, NULL, level, out)",
            )
        )
        cc = os.environ.get("CC", "cc")
        lib = folder / f"lib{tag}.so"
        subprocess.run(
            [cc, *C_FLAGS, "-shared", "-o", str(lib), f"{name}.c", "harness.c", "-lm"],
            cwd=folder,
            check=True,
            capture_output=True,
        )
        self.lib = ctypes.CDLL(str(lib))
        d = ctypes.POINTER(ctypes.c_double)
        self.lib.bench.restype = ctypes.c_double
        self.lib.bench.argtypes = [d, ctypes.c_int, ctypes.c_int, ctypes.c_int, d, ctypes.c_void_p]
        spec = importlib.util.spec_from_file_location(f"{name}_{tag}", folder / f"{name}.py")
        self.module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(self.module)
        self.out = np.zeros(4096)

    def c_run(self, x: np.ndarray, level: int, reps: int = 1) -> tuple[float, int]:
        fails = ctypes.c_int(0)
        d = ctypes.POINTER(ctypes.c_double)
        secs = self.lib.bench(
            x.ctypes.data_as(d),
            len(x),
            level,
            reps,
            self.out.ctypes.data_as(d),
            ctypes.byref(fails),
        )
        return secs, fails.value


def timings(builds: dict[str, Built], ranges: dict, points: int, batch: int, repeats: int):
    """Per point, best of `repeats`, every build interleaved: C per level and its report, numpy
    per level and at loaded without its report. Seconds, and the failures."""
    rng = np.random.default_rng(1)
    names = list(ranges)
    x = np.ascontiguousarray(
        np.column_stack([rng.uniform(*ranges[k], points) for k in names]), dtype=float
    )
    xb = {k: rng.uniform(*ranges[k], batch) for k in names}
    some = next(iter(builds.values()))
    cases = [("c", lv) for lv in some.levels] + [("numpy", lv) for lv in some.levels]
    if "loaded" in some.levels:
        cases += [("c", "report"), ("numpy", "loaded without report")]
    best = {(tag, case): float("inf") for tag in builds for case in cases}
    fails: dict = {}
    reps = {}
    for tag, b in builds.items():  # warm, and how many repeats fill 0.1 s in C
        for kind, lv in cases:
            if kind == "c":
                code = -1 if lv == "report" else LEVEL_CODES[lv]
                secs, f = b.c_run(x, code)
                fails[f"{tag} c {lv}"] = f
                reps[kind, lv] = max(1, int(0.1 / max(secs, 1e-9)))
    for _ in range(repeats):
        for kind, lv in cases:
            for tag, b in builds.items():
                if kind == "c":
                    code = -1 if lv == "report" else LEVEL_CODES[lv]
                    secs, _ = b.c_run(x, code, reps[kind, lv])
                    per = secs / (reps[kind, lv] * points)
                else:
                    level = lv.split()[0]
                    kw = {"report": False} if lv.endswith("report") else {}
                    t0 = time.perf_counter()
                    r = b.module.evaluate(xb, level, **kw)
                    per = (time.perf_counter() - t0) / batch
                    fails[f"{tag} numpy {lv}"] = int(np.size(r["ok"]) - np.sum(r["ok"]))
                best[tag, (kind, lv)] = min(best[tag, (kind, lv)], per)
    return {f"{tag} {k} {lv}": v for (tag, (k, lv)), v in best.items()}, fails


def cold(path: Path) -> dict:
    """The bridge's first `eval --level loaded --backend c` and its `derive`, each in a fresh
    process on an empty cache, with `python -X importtime`'s total import time of symkin."""
    res = {}
    with tempfile.TemporaryDirectory() as tmp:
        env = dict(os.environ, SYMKIN_CACHE=str(Path(tmp) / "cache"))
        env.pop("SYMKIN_PLAN_CACHE", None)
        commands = {
            "eval_loaded_c": [
                "eval",
                str(path),
                "--input",
                "piezo=0.005",
                "--level",
                "loaded",
                "--backend",
                "c",
            ],
            "derive": ["derive", str(path), "-o", str(Path(tmp) / "out")],
        }
        for key, args in commands.items():
            load = os.getloadavg()[0]
            t0 = time.perf_counter()
            run = subprocess.run(
                [sys.executable, "-m", "symkin", *args], env=env, capture_output=True, text=True
            )
            res[key] = {
                "s": time.perf_counter() - t0,
                "exit": run.returncode,
                "load": load,
                "command": "symkin "
                + " ".join(args).replace(tmp, "$TMP").replace(str(ROOT) + "/", ""),
            }
    return res


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--points", type=int, default=2000)
    ap.add_argument("--batch", type=int, default=4000)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--compare", metavar="REV", help="also time symkin at this git revision")
    ap.add_argument("--no-cold", action="store_true")
    ap.add_argument("--only", help="designs whose label contains this")
    args = ap.parse_args()
    results: dict = {
        "date": datetime.datetime.now(datetime.UTC).isoformat(timespec="minutes"),
        "machine": machine(),
        "symkin_commit": first_line(["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"]),
        "compare": args.compare,
        "command": "python benchmarks/designs.py " + " ".join(sys.argv[1:]),
        "designs": {},
    }
    with tempfile.TemporaryDirectory(prefix="symkin-designs-") as tmp:
        work = Path(tmp)
        specs = []
        for i, (label, (file, ranges, transform)) in enumerate(DESIGNS.items()):
            if args.only and args.only not in label:
                continue
            f = work / "files" / f"{i}" / Path(file).name
            f.parent.mkdir(parents=True)
            f.write_text(variant_text(ROOT / file, transform))
            specs.append({"key": str(i), "file": str(f), "label": label, "ranges": ranges})
        trees = {"after": None}
        if args.compare:
            trees = {"before": export(args.compare, work / "before-tree"), "after": None}
        for tag, tree in trees.items():
            log(f"emitting with {'the working tree' if tree is None else args.compare}")
            (work / tag).mkdir()
            emit_all(specs, work / tag, tree)
        for s in specs:
            log(f"timing {s['label']}")
            builds = {tag: Built(work / tag / s["key"], tag) for tag in trees}
            load = os.getloadavg()
            t, fails = timings(builds, s["ranges"], args.points, args.batch, args.repeats)
            results["designs"][s["label"]] = {
                "file": next(v[0] for k, v in DESIGNS.items() if k == s["label"]),
                "levels": builds["after"].levels,
                "per_point_s": t,
                "failures": fails,
                "load_average": [load, os.getloadavg()],
            }
    if not args.no_cold:
        log("cold start of the bridge")
        results["cold"] = cold(ROOT / "tests/mechanisms/bridge_amplifier.toml")
    name = "results-designs.json" if not args.only else "results-designs-partial.json"
    (BENCH / name).write_text(json.dumps(results, indent=1) + "\n")
    print("\n".join(render(results)))


def render(results: dict) -> list[str]:
    """The issue's table per tree: µs per point, and the ratios that the targets read."""
    out = []
    trees = ["before", "after"] if results["compare"] else ["after"]
    for tag in trees:
        out += [
            f"{tag}:",
            "| design | C exact | C loaded | C report | numpy exact | numpy loaded (report / "
            "without) | load |",
            "| --- | ---: | ---: | ---: | ---: | ---: | --- |",
        ]
        for label, d in results["designs"].items():
            t = d["per_point_s"]

            def us(key: str, t=t, tag=tag) -> str:
                v = t.get(f"{tag} {key}")
                return "—" if v is None else f"{v * 1e6:.3g}"

            la = d["load_average"]
            out.append(
                f"| {label} | {us('c exact')} | {us('c loaded')} | {us('c report')} | "
                f"{us('numpy exact')} | {us('numpy loaded')} / {us('numpy loaded without report')}"
                f" | {la[0][0]:.1f}–{la[1][0]:.1f} |"
            )
    if results["compare"]:
        out += ["", "after / before (per point, same run):", ""]
        for label, d in results["designs"].items():
            t = d["per_point_s"]
            keys = sorted({k.split(" ", 1)[1] for k in t})
            out.append(
                f"- {label}: "
                + ", ".join(f"{k} {t['after ' + k] / t['before ' + k]:.2f}" for k in keys)
            )
    if "cold" in results:
        out += [""] + [
            f"- cold {k}: {v['s']:.1f} s (exit {v['exit']}, load {v['load']:.1f}): `{v['command']}`"
            for k, v in results["cold"].items()
        ]
    return out


if __name__ == "__main__":
    main()
