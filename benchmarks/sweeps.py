"""Sweeps, sensitivities and batch calls, measured side by side in one run (issue 12's speed
targets and issue 8's batch entry point):

1. the cost of one ctypes call per point against one batch call and against the C loop timed
   inside C (the four-bar, exact level);
2. a sensitivity evaluation (<name>_sensitivity_full) against one deviation evaluation
   (<name>_evaluate), both timed inside C, on the four-bar (1 parameter) and on the four-bar
   with its dimensions as 12 parameters (examples/four_bar_dimensions.toml);
3. `symkin sweep` throughput on this machine's cores (Dask's threaded scheduler) against twice
   the single-core C rate on the same configurations (measured just before and just after),
   the 10^7-evaluation sweep's wall time, and Dask's overhead per chunk (no-op tasks, local
   threaded scheduler and a distributed LocalCluster with two worker processes).

Every evaluator is first checked against symkin's 40-digit mpmath evaluation.
"""

from __future__ import annotations

import ctypes
import os
import time

import numpy as np
from common import ROOT, log

TIMER_C = r"""
#define _POSIX_C_SOURCE 199309L
#include <stddef.h>
#include <time.h>
#include "NAME.h"

/* Seconds for `repeats` passes over n input rows of NAME_evaluate (what = 0) or
   NAME_sensitivity_full (what = 1), measured inside C. */
double bench_time(const double *inputs, int n, int repeats, int level, int what, double *sink)
{
    struct timespec t0, t1;
    double out[6 * UPPER_N_POINTS + 1];
    double dev[2 * UPPER_N_POINTS * UPPER_N_VARIABLES + 1];
    double acc = 0.0;
    int r, i;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    for (r = 0; r < repeats; ++r) {
        for (i = 0; i < n; ++i) {
            const double *x = inputs + (size_t)i * UPPER_N_INPUTS;
            if (what == 0) {
                if (NAME_evaluate(x, NULL, level, out) == 0) {
                    acc += out[4];
                }
            } else if (NAME_sensitivity_full(x, NULL, level, NULL, dev, NULL) == 0) {
                acc += dev[0];
            }
        }
    }
    clock_gettime(CLOCK_MONOTONIC, &t1);
    *sink = acc;
    return (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec);
}
"""


class Timed:
    """A generated evaluator with the C timer above, timed inside C."""

    def __init__(self, mech, plan_levels=("exact",)):
        import symkin
        from symkin.codegen import pipeline, toolchain

        an = symkin.analyze(mech)
        self.analysis = an
        self.plan = pipeline.plan_for(an, levels=list(plan_levels))
        header, code = pipeline.emit(self.plan, "c", f"{mech.name}.toml")
        name = mech.name
        extra = TIMER_C.replace("UPPER", name.upper()).replace("NAME", name)
        path = toolchain.build(name, header, code, toolchain.CFLAGS, extra)
        self.raw = ctypes.CDLL(str(path))
        self.fn = self.raw.bench_time
        self.fn.restype = ctypes.c_double
        d = ctypes.POINTER(ctypes.c_double)
        self.fn.argtypes = [d, ctypes.c_int, ctypes.c_int, ctypes.c_int, ctypes.c_int, d]
        self.lib = toolchain.Library(
            path,
            name,
            len(self.plan.inputs),
            len(self.plan.parameters),
            len(self.plan.points),
            len(self.plan.hinges),
        )
        self.name = name

    def per_call(self, x: np.ndarray, what: int, budget: float, level: int = 2) -> float:
        """Seconds per call, the best of three passes of about `budget` seconds."""
        x = np.ascontiguousarray(x, dtype=float)
        d = ctypes.POINTER(ctypes.c_double)
        sink = ctypes.c_double()
        reps = 1
        while True:
            t = self.fn(x.ctypes.data_as(d), len(x), reps, level, what, ctypes.byref(sink))
            if t >= budget / 3 or reps > 1 << 20:
                break
            reps *= 2
        best = min(
            self.fn(x.ctypes.data_as(d), len(x), reps, level, what, ctypes.byref(sink))
            for _ in range(3)
        )
        return best / (reps * len(x))


def check(timed: Timed, x: np.ndarray) -> float:
    """Largest relative error of the C deviation and sensitivity against mpmath (40 digits)."""
    import symkin

    an = timed.analysis
    worst = 0.0
    for row in x[:2]:
        inputs = dict(zip(timed.plan.inputs, map(float, row)))
        ref = symkin.evaluate(an, inputs, "exact", sensitivity=True)
        status, values, dev, _ = timed.lib.sensitivity_rows(row[None, :], None, 2)
        assert status[0] == 0
        p = timed.plan.points[0]
        got = values[0, 4:6]
        want = np.array(ref.points[p].deviation)
        worst = max(worst, float(np.abs(got - want).max() / np.abs(want).max()))
        for k, q in enumerate(ref.sensitivity.deviation[p]):
            want = np.array(ref.sensitivity.deviation[p][q])
            if np.abs(want).max():
                worst = max(worst, float(np.abs(dev[0, 0, k] - want).max() / np.abs(want).max()))
    return worst


def batch_calls(timed: Timed, n: int, budget: float) -> dict:
    """One ctypes call per point (raw, and through symkin's Library) against one batch call
    and the C loop timed inside C."""
    rng = np.random.default_rng(3)
    x = rng.uniform(-1.0, 1.0, (n, 1))
    c_loop = timed.per_call(x, 0, budget)
    fn = getattr(timed.raw, f"{timed.name}_evaluate")
    d = ctypes.POINTER(ctypes.c_double)
    fn.argtypes = [d, d, ctypes.c_int, d]
    fn.restype = ctypes.c_int
    rows = [(ctypes.c_double * 1)(float(v)) for v in x[:, 0]]
    out = (ctypes.c_double * (6 * len(timed.plan.points)))()

    def raw():
        for r in rows:
            fn(r, None, 2, out)

    def library():
        for v in x[: n // 10]:
            timed.lib.evaluate(v, None, 2)

    def batch():
        timed.lib.evaluate_rows(x, None, 2)

    t_raw = best(raw) / n
    t_lib = best(library) / (n // 10)
    t_batch = best(batch) / n
    return {
        "points": n,
        "c_loop_s": c_loop,
        "ctypes_per_point_s": t_raw,
        "library_per_point_s": t_lib,
        "batch_s": t_batch,
        "ratio_ctypes_per_point": t_raw / c_loop,
        "ratio_library_per_point": t_lib / c_loop,
        "ratio_batch": t_batch / c_loop,
    }


def best(fn, repeat: int = 3) -> float:
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def sensitivity_cost(timed: Timed, n: int, budget: float) -> dict:
    """A sensitivity evaluation (all parameters and inputs) ÷ one deviation evaluation, in C."""
    x = np.random.default_rng(4).uniform(-1.0, 1.0, (n, 1))
    t_dev = timed.per_call(x, 0, budget)
    t_sens = timed.per_call(x, 1, budget)
    return {
        "variables": len(timed.plan.parameters) + len(timed.plan.inputs),
        "deviation_s": t_dev,
        "sensitivity_s": t_sens,
        "ratio": t_sens / t_dev,
    }


def dask_overhead(tasks: int) -> dict:
    """Seconds per no-op Dask task: the local threaded scheduler (2 workers) and a distributed
    LocalCluster with two worker processes."""
    import dask
    from distributed import Client, LocalCluster

    def noop(i):
        return i

    jobs = [dask.delayed(noop, pure=False)(i) for i in range(tasks)]
    t0 = time.perf_counter()
    dask.compute(*jobs, scheduler="threads", num_workers=2)
    local = (time.perf_counter() - t0) / tasks
    with (
        LocalCluster(
            n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
        ) as cluster,
        Client(cluster) as client,
    ):
        client.gather(client.map(noop, range(10), pure=False))  # warm up
        t0 = time.perf_counter()
        client.gather(client.map(noop, range(tasks), pure=False))
        dist = (time.perf_counter() - t0) / tasks
    return {"tasks": tasks, "threads_s": local, "distributed_s": dist}


def sweep_throughput(samples: int, grid: int) -> dict:
    """`symkin sweep` of the four-bar (l = normal(1e-3, 2e-5)) on this machine's cores against
    twice the single-core C rate on the same configurations, measured before and after."""
    import symkin
    from symkin.studies import sweep, variation

    mech = symkin.load(ROOT / "examples" / "four_bar.toml")
    ev = symkin.compile(mech, levels=["exact"])
    vary = variation.parse_vary(["l=normal(1e-3,2e-5)"], mech, {"l": 1e-3})
    g = variation.parse_grid([f"A0=-1:1:{grid}"], mech)
    task = sweep.Task(
        ev,
        "exact",
        g.rows,
        tuple((p, s, 1e-3) for p, s in vary.items()),
        1,
        sweep.BLOCK,
        sweep.geometry_checks(mech),
        tuple(p.symbol for p in mech.parameters),
    )
    params, _ = sweep.sample_block(task, 0)

    def single_core() -> tuple[float, float]:
        """(points per wall second, points per CPU second) of one C call on one thread."""
        t0, c0 = time.perf_counter(), time.process_time()
        status, _ = ev.library.evaluate_grid(params, g.rows, 2)
        assert (status == 0).all()
        n = params.shape[0] * len(g.rows)
        return n / (time.perf_counter() - t0), n / (time.process_time() - c0)

    single_core()  # warm up
    before = single_core()
    workers = os.cpu_count() or 1
    load = os.getloadavg()[0]
    c0 = time.process_time()
    result = sweep.run(
        ev,
        mech,
        vary,
        g,
        samples,
        seed=1,
        scheduler=sweep.parse_scheduler(f"threads:{workers}"),
        level="exact",
    )
    cpu = time.process_time() - c0
    after = single_core()
    points = samples * len(g.rows)
    rate = points / result.seconds
    one = (before[0] + after[0]) / 2
    one_cpu = (before[1] + after[1]) / 2
    assert result.failed == 0
    return {
        "samples": samples,
        "grid": len(g.rows),
        "points": points,
        "workers": workers,
        "chunks": result.chunks,
        "sweep_s": result.seconds,
        "sweep_cpu_s": cpu,
        "sweep_points_per_s": rate,
        "single_core_points_per_s": one,
        "single_core_points_per_cpu_s": one_cpu,
        "single_core_before": before[0],
        "single_core_after": after[0],
        "load_average_before": load,
        "load_average_after": os.getloadavg()[0],
        "cores_obtained": cpu / result.seconds,
        "cpu_efficiency": (points / cpu) / one_cpu,
        "ratio_to_ideal": rate / (workers * one),
    }


def measure(sizes) -> dict:
    """Every measurement of this part (sizes: common.Sizes, smoke or full)."""
    import symkin

    smoke = sizes.name == "smoke"
    budget = 0.02 if smoke else 0.5
    log("sweeps: batch calls and sensitivity cost")
    four = Timed(symkin.load(ROOT / "examples" / "four_bar.toml"))
    param = Timed(symkin.load(ROOT / "examples" / "four_bar_dimensions.toml"))
    x = np.array([[0.3], [-0.7]])
    out = {"checks": {"four_bar": check(four, x), "four_bar_dimensions": check(param, x)}}
    out["batch"] = batch_calls(four, 200 if smoke else 10**4, budget)
    out["sensitivity"] = {
        "four_bar": sensitivity_cost(four, 100 if smoke else 1000, budget),
        "four_bar_dimensions": sensitivity_cost(param, 100 if smoke else 1000, budget),
    }
    log("sweeps: Dask overhead per chunk")
    out["dask"] = dask_overhead(20 if smoke else 500)
    log("sweeps: throughput on this machine's cores")
    out["sweep"] = sweep_throughput(*((512, 20) if smoke else (10**4, 10**3)))
    return out


def render(results: dict) -> list[str]:
    """The docs/benchmarks.md lines of this part."""
    s = results["sweeps"]
    b, sw, dk = s["batch"], s["sweep"], s["dask"]
    lines = [
        "Sweeps and sensitivities (four-bar, exact level; `benchmarks/sweeps.py`), "
        "measured side by side in this run:",
        "",
        "| measurement | value | target |",
        "| --- | ---: | --- |",
    ]
    lines.append(
        f"| one ctypes call per point ÷ the C loop (timed inside C) | "
        f"{b['ratio_ctypes_per_point']:.1f}× | |"
    )
    lines.append(
        f"| symkin's Library.evaluate per point ÷ the C loop | "
        f"{b['ratio_library_per_point']:.1f}× | |"
    )
    lines.append(
        f"| one batch call (`<name>_evaluate_batch`, 10^4 rows) ÷ the C loop | "
        f"{b['ratio_batch']:.2f}× | |"
    )
    for key, label in (("four_bar", "four_bar"), ("four_bar_dimensions", "four_bar_dimensions")):
        r = s["sensitivity"][key]
        lines.append(
            f"| sensitivity ÷ deviation evaluation in C ({label}, "
            f"{r['variables']} variables) | {r['ratio']:.2f}× | ≤ 3× |"
        )
    lines.append(
        f"| sweep throughput ({sw['workers']} threads, {sw['chunks']} chunks) ÷ "
        f"{sw['workers']} × single-core C | {100 * sw['ratio_to_ideal']:.0f} % | ≥ 70 % |"
    )
    lines.append(
        f"| sweep of {sw['points']:.0e} evaluations ({sw['samples']} samples × "
        f"{sw['grid']} inputs) | {sw['sweep_s']:.1f} s | < 20 s |".replace("1e+07", "10^7")
    )
    lines.append(
        f"| Dask overhead per chunk, local threads / distributed (2 processes) | "
        f"{dk['threads_s'] * 1e3:.2f} ms / {dk['distributed_s'] * 1e3:.2f} ms | |"
    )
    lines.append("")
    lines.append(
        f"Single-core C: {sw['single_core_points_per_s']:.3g} points/s "
        f"({sw['single_core_before']:.3g} before, {sw['single_core_after']:.3g} after "
        f"the sweep); the sweep: {sw['sweep_points_per_s']:.3g} points/s, using "
        f"{sw['cores_obtained']:.2f} cores' worth of CPU time (load average "
        f"{sw['load_average_before']:.1f} before, {sw['load_average_after']:.1f} after: "
        f"other work shares the machine), at {100 * sw['cpu_efficiency']:.0f} % of the "
        f"single-core rate per CPU second. Dask's overhead, {sw['chunks']} chunks × "
        f"{dk['threads_s'] * 1e3:.2f} ms, is "
        f"{100 * sw['chunks'] * dk['threads_s'] / sw['sweep_s']:.2g} % of the sweep."
    )
    return lines


def targets(results: dict) -> list[dict]:
    s = results["sweeps"]
    sw = s["sweep"]
    sens = s["sensitivity"]
    return [
        {
            "text": "a sensitivity evaluation ≤ 3× one deviation evaluation in C",
            "met": all(r["ratio"] <= 3 for r in sens.values()),
            "measured": ", ".join(f"{k} {r['ratio']:.2f}×" for k, r in sens.items()),
        },
        {
            "text": f"sweep throughput ≥ 70 % of {sw['workers']} × single-core C",
            "met": sw["ratio_to_ideal"] >= 0.7,
            "measured": f"{100 * sw['ratio_to_ideal']:.0f} %",
        },
        {
            "text": "10^7 evaluations of the four-bar at exact in a sweep < 20 s",
            "met": sw["points"] >= 10**7 and sw["sweep_s"] < 20,
            "measured": f"{sw['points']:.0e} in {sw['sweep_s']:.1f} s".replace("1e+07", "10^7"),
        },
    ]


if __name__ == "__main__":  # python benchmarks/sweeps.py [--smoke]
    import json
    import sys

    from common import FULL, SMOKE

    res = {"sweeps": measure(SMOKE if "--smoke" in sys.argv else FULL)}
    print("\n".join(render(res)))
    print(json.dumps(res, indent=1))
