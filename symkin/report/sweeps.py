"""The numbers of the report's figures and tables that the generated numpy module evaluates: the
pose as fabricated, |ΔR| of every point at every level over each input's range (with the
physical reference, the `equilibrium` level, at a few inputs) and the parameters ranked by their
effect on each point's deviation (docs/sensitivity.md).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np

from ..codegen import pipeline
from ..core.errors import SymkinError
from .figures import PoseData, Sweep
from .profiles import notch_outlines
from .sections import Report, float_at, input_unit
from .text import escape_latex, gnum, sci

#: Default input range of the deviation plot: every input equal to t, |t| <= SWEEP_RANGE (rad).
SWEEP_RANGE = 0.3
SWEEP_SAMPLES = 241
#: Inputs of each swept range at which the physical reference (`equilibrium`) is solved.
REFERENCE_SAMPLES = 9
#: The physical reference of a report: input name -> value  to  the `equilibrium` level's
#: evaluation there (symkin.studies.results.Evaluation: `points` with their `deviation` and
#: `model_error`, `plates`, `actuation`, `buckling`, `buckling_hinge`).
Physics = Callable[[Mapping[str, float]], Any]


def pose_data(report: Report) -> PoseData:
    d, s, defaults = report.d, report.s, report.defaults
    num = lambda v: (float_at(v[0], defaults), float_at(v[1], defaults))  # noqa: E731
    attachments: dict[int, list[tuple[float, float]]] = {i: [] for i in range(s.n + 1)}
    plates = []
    for a in range(1, s.m + 1):
        h = d.hinges[a]
        p, m = num(h.clamp(h.P)), num(h.clamp(h.M))
        attachments[h.P].append(p)
        attachments[h.M].append(m)
        plates.append((a, s.hinges[a - 1], p, m, h.is_input))
    links = tuple((i, s.links[i], tuple(attachments[i])) for i in range(s.n + 1))
    points = tuple((pt.name, pt.link, num(pt.at)) for pt in d.points)
    return PoseData(links, 0, tuple(plates), points, notch_outlines(report))


def sweep_spans(
    inputs: Sequence[str],
    given: Mapping[str, tuple[float, float]] | None = None,
    strokes: Mapping[str, float] | None = None,
) -> dict[str, tuple[float, float]]:
    """Each input's plotted range: the `given` ones (derive --range), else ±SWEEP_RANGE, or for
    an actuator ±its `strokes` entry (file unit)."""
    spans = {
        h: (-(strokes or {})[h], (strokes or {})[h])
        if h in (strokes or {})
        else (-SWEEP_RANGE, SWEEP_RANGE)
        for h in inputs
    }
    spans.update({h: (float(lo), float(hi)) for h, (lo, hi) in (given or {}).items()})
    return spans


def reference_points(
    report: Report,
    t: np.ndarray,
    ok: np.ndarray,
    inputs: Mapping[str, np.ndarray],
    physics: Physics,
) -> tuple[np.ndarray, dict[str, np.ndarray], tuple]:
    """The physical reference (`physics`: inputs -> its evaluation, the `equilibrium` level) at
    REFERENCE_SAMPLES evenly spaced samples of a sweep: their indices, the point deviations (NaN
    where it cannot be solved) and the evaluations themselves (None there)."""
    at = np.unique(np.round(np.linspace(0, len(t) - 1, REFERENCE_SAMPLES)).astype(int))
    out = {p: np.full((2, len(at)), np.nan) for p in report.plan.points}
    evaluations: list = [None] * len(at)
    for k, i in enumerate(at):
        if not ok[i]:
            continue
        try:
            evaluations[k] = physics({n: float(v[i]) for n, v in inputs.items()})
        except SymkinError:  # beyond the assembly range, a plate buckling
            continue
        for p in report.plan.points:
            out[p][:, k] = evaluations[k].points[p].deviation
    return at, out, tuple(evaluations)


def sweep(
    report: Report,
    numpy_module,
    spans: Mapping[str, tuple[float, float]],
    physics: Physics | None = None,
) -> tuple[list[tuple[str, Sweep, tuple[float, float]]], dict]:
    """|ΔR| of the points at every level with each input in turn over its span (the others held
    at the middle of theirs), evaluated with the generated numpy module, and with `physics` the
    physical reference at a few of the inputs.

    Returns per input its sweep and the plot's clipped x range, and the report's summary (the
    largest deviation per point and level over all sweeps, where it occurs, the largest
    distance of each level from the exact one relative to the largest exact deviation and, with
    `physics`, from the reference relative to the reference's largest deviation)."""
    names = [lv.name for lv in report.plan.levels]
    held = {h: 0.5 * (lo + hi) for h, (lo, hi) in spans.items()}
    single = len(spans) == 1
    runs: list[tuple[str, Sweep, tuple[float, float]]] = []
    summary: dict = {"samples": 0, "failed": 0, "spans": [], "rows": []}
    for h, (lo, hi) in spans.items():
        t = np.linspace(lo, hi, SWEEP_SAMPLES)
        inputs = {n: (t if n == h else np.full_like(t, held[n])) for n in numpy_module.INPUTS}
        magnitude: dict[str, dict[str, np.ndarray]] = {p: {} for p in report.plan.points}
        deviation: dict[str, dict[str, np.ndarray]] = {p: {} for p in report.plan.points}
        ok = np.ones(t.shape, dtype=bool)
        for lv in names:
            # the deviations alone (the loaded level's report and buckling search are not read)
            result = numpy_module.evaluate(
                inputs, level=lv, **pipeline.evaluate_options(numpy_module, report=False)
            )
            ok &= np.asarray(result["ok"], dtype=bool)
            for p in report.plan.points:
                deviation[p][lv] = np.asarray(result["points"][p]["deviation"], dtype=float)
        for p in report.plan.points:
            for lv in names:
                deviation[p][lv] = np.where(ok, deviation[p][lv], np.nan)
                magnitude[p][lv] = np.hypot(*deviation[p][lv])
        # clipped to the assembling samples, with a margin (10 % of the span) showing where
        # assembly stops
        margin = 0.1 * (hi - lo)
        a, b = lo, hi
        if ok.any():
            idx = np.flatnonzero(ok)
            a = lo if idx[0] == 0 else max(lo, t[idx[0]] - margin)
            b = hi if idx[-1] == len(t) - 1 else min(hi, t[idx[-1]] + margin)
        reference, reported = None, ()
        if physics is not None:
            at_ref, ref, reported = reference_points(report, t, ok, inputs, physics)
            reference = (at_ref, ref)
        runs.append((h, Sweep(t, ok, magnitude, deviation, reference, reported), (a, b)))
        summary["samples"] += len(t)
        summary["failed"] += int((~ok).sum())
        act = next((a for a in report.mech.actuators if a.name == h), None)
        summary["spans"].append(
            {
                "input": escape_latex(h),
                # what is swept: a hinge's angle (rad), an actuator's stroke (file unit) or
                # force (N)
                "what": r"input $\theta$" if act is None else act.drive,
                "unit": input_unit(report.mech, h, tex=True),
                "lo": f"{lo:g}",
                "hi": f"{hi:g}",
                "held": f"{held[h]:g}",
                "clip": f"[{a:.3f}, {b:.3f}]",
                "clipped": bool(a > lo or b < hi),
            }
        )
    for p in report.plan.points:
        for level in report.plan.levels:
            lv = level.name
            peak, at, diff, ref = float("nan"), "", float("nan"), float("nan")
            for h, data, _ in runs:
                mag = data.magnitude[p][lv]
                if np.isfinite(mag).any() and not np.nanmax(mag) <= peak:
                    k = int(np.nanargmax(mag))
                    peak = float(mag[k])
                    at = (
                        f"${data.t[k]:+.3f}$" if single else f"{escape_latex(h)} ${data.t[k]:+.3f}$"
                    )
                exact = data.deviation[p].get("exact")
                if exact is not None and lv != "exact" and np.isfinite(exact).any():
                    d = np.hypot(*(data.deviation[p][lv] - exact))
                    diff = np.nanmax([diff, np.nanmax(d)])
                    ref = np.nanmax([ref, np.nanmax(np.hypot(*exact))])
            rel = float(diff / ref) if np.isfinite(diff) and ref > 0 else None
            row = {
                "point": escape_latex(p),
                "level": level.title,
                "peak": sci(peak),
                "at": at or r"\text{--}",
                "rel": sci(rel, 2) if rel is not None else r"\text{--}",
            }
            if physics is not None:
                row["physics"] = _physics_distance(runs, p, lv)
            summary["rows"].append(row)
    summary["physics"] = physics is not None
    if physics is not None:  # the configurations where the reference was solved
        first = report.plan.points[0]
        summary["reference_samples"] = sum(
            int(np.isfinite(data.reference[1][first][0]).sum()) for _, data, _ in runs
        )
    return runs, summary


def _physics_distance(
    runs: Sequence[tuple[str, Sweep, tuple[float, float]]], point: str, level: str
) -> str:
    """max |ΔR_level − ΔR_equilibrium| over the reference's samples of every sweep, relative to
    the largest |ΔR_equilibrium|, as LaTeX math text."""
    gap, size = [], []
    for _, data, _ in runs:
        at, ref = data.reference[0], data.reference[1][point]
        gap.append(np.hypot(*(data.deviation[point][level][:, at] - ref)))
        size.append(np.hypot(*ref))
    gap_all, size_all = np.concatenate(gap), np.concatenate(size)
    if not np.isfinite(gap_all).any() or not np.nanmax(size_all) > 0:
        return r"\text{--}"
    return sci(float(np.nanmax(gap_all) / np.nanmax(size_all)), 2)


def sensitivity_table(
    report: Report, numpy_module, runs: Sequence[tuple[str, Sweep, tuple[float, float]]]
) -> dict | None:
    """The parameters ranked by their effect on each point's deviation (docs/sensitivity.md),
    at the evaluators' default level (else the most faithful with sensitivities), at the swept
    input where the point's |ΔR| at that level is largest; None without parameters or
    sensitivities."""
    plan = report.plan
    names = list(getattr(numpy_module, "PARAMETERS", {}))
    # with actuators `loaded` has no sensitivities yet (docs/physics.md, "Actuators at loaded")
    with_rates = [
        lv for lv in plan.levels if lv.sensitivity and not (plan.actuators and lv.needs_stiffness)
    ]
    if not names or not with_rates or not hasattr(numpy_module, "sensitivity_full"):
        return None
    # the evaluators' default level (docs/levels.md, "The default level") where it has them
    chosen = next((lv for lv in with_rates if lv.name == plan.default_level), with_rates[-1])
    level = chosen.name
    single = len(runs) == 1
    held = {h: 0.5 * (data.t[0] + data.t[-1]) for h, data, _ in runs}
    rows = []
    for point in plan.points:
        best = None  # (|ΔR|, swept input, its value)
        for h, data, _ in runs:
            mag = data.magnitude[point][level]
            if (
                np.isfinite(mag).any()
                and np.nanmax(mag) > 0
                and (best is None or np.nanmax(mag) > best[0])
            ):
                best = (float(np.nanmax(mag)), h, float(data.t[int(np.nanargmax(mag))]))
        if best is None:
            continue
        _, swept, t = best
        inputs = {n: (t if n == swept else float(held[n])) for n in numpy_module.INPUTS}
        at = f"${t:+.3f}$" if single else f"{escape_latex(swept)} ${t:+.3f}$"
        res = numpy_module.sensitivity_full(inputs, level)
        d = np.asarray(res["points"][point]["deviation"], dtype=float)
        norm = float(np.hypot(d[0], d[1]))
        entries = []
        for name in names:
            rate = np.asarray(res["deviation"][point]["params"][name], dtype=float)
            d_norm = float((d[0] * rate[0] + d[1] * rate[1]) / norm)
            value = float(numpy_module.PARAMETERS[name])
            relative = value * d_norm / norm
            entries.append(
                (
                    abs(relative),
                    {
                        "point": escape_latex(point),
                        "name": escape_latex(name),
                        "value": gnum(value),
                        "dx": sci(float(rate[0])),
                        "dy": sci(float(rate[1])),
                        "norm": sci(d_norm),
                        "relative": f"{relative:+.3f}" if value else r"\text{--}",
                        "at": at,
                    },
                )
            )
        entries.sort(key=lambda e: -e[0])
        rows += [e[1] for e in entries]
    if not rows:
        return None
    return {
        "level": chosen.title,
        "rows": rows,
        "single_input": single,
        "inputs": [escape_latex(n) for n in numpy_module.INPUTS],
        # the actuators' names: their strokes are held, the surrogate angles follow
        "strokes": [escape_latex(a.name) for a in report.mech.actuators],
    }
