"""`symkin tradeoff`: every variant's worst error over an input range and its time per evaluation.

Errors are measured against an mpmath evaluation (30 digits) of the most faithful derivation:
the file's own hinge models at the `exact` level. Times are measured in one run: the numpy
evaluator vectorized over 10^4 points, the C evaluator in a loop timed inside C.
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from .analysis import Analysis
from .errors import AssemblyError, InputError
from .mechanism import Mechanism
from .variants import Variant, analysis_for, default_variants

DEFAULT_RANGE = (-0.2, 0.2)
TIMING_POINTS = 10_000


@dataclass(frozen=True)
class Row:
    """One variant's measurements."""

    variant: Variant
    errors: dict[str, float]            # point -> worst relative error of the deviation
    time_numpy: float                   # seconds per point, vectorized
    time_c: float | None                # seconds per point, in a C loop (float64 variants)
    ops: int                            # operations of the generated routines (after CSE)
    pareto: bool = False

    @property
    def worst(self) -> float:
        return max(self.errors.values()) if self.errors else 0.0

    @property
    def time(self) -> float:
        """The time that ranks variants: C where there is one, else numpy."""
        return self.time_c if self.time_c is not None else self.time_numpy


@dataclass(frozen=True)
class Tradeoff:
    ranges: dict[str, tuple[float, float]]
    samples: int
    skipped: int                          # samples the mechanism cannot assemble
    zero: int = 0                         # samples in the as-fabricated pose (see measure)
    rows: tuple[Row, ...] = field(default=())
    inputs: tuple[dict, ...] = field(default=())   # the samples measured (assembled ones)

    def as_json(self) -> dict:
        return {
            "reference": "mpmath, 30 digits, exact level, the file's hinge models",
            "ranges": {k: list(v) for k, v in self.ranges.items()},
            "samples": self.samples, "skipped": self.skipped, "zero_deviation": self.zero,
            "inputs": list(self.inputs),
            "variants": [{"name": r.variant.name, "level": r.variant.level,
                          "model": r.variant.model, "precision": r.variant.precision,
                          "worst_error": r.worst, "errors": r.errors,
                          "time_numpy": r.time_numpy, "time_c": r.time_c, "ops": r.ops,
                          "pareto": r.pareto} for r in self.rows],
        }


def parse_ranges(items: Sequence[str] | None, inputs: Sequence[str],
                 file: str) -> dict[str, tuple[float, float]]:
    """H=LO:HI options (expressions allowed), every input defaulting to DEFAULT_RANGE."""
    from .analysis import _exact

    ranges = {name: DEFAULT_RANGE for name in inputs}
    for item in items or ():
        name, sep, span = item.partition("=")
        lo, colon, hi = span.partition(":")
        if not sep or not colon or name.strip() not in ranges:
            raise InputError(f"'{item}' is not INPUT=LO:HI for an input hinge", file=file,
                             entry="--range", hint="inputs: " + ", ".join(inputs))
        a, b = (float(_exact(v.strip(), "--range", file)) for v in (lo, hi))
        if not a < b:
            raise InputError(f"empty range {a}:{b}", file=file, entry="--range",
                             hint="give LO < HI")
        ranges[name.strip()] = (a, b)
    return ranges


def sample(ranges: Mapping[str, tuple[float, float]], n: int) -> list[dict[str, float]]:
    """n deterministic points in the box: a grid for one input, a Halton sequence for more."""
    names = list(ranges)
    out = []
    if len(names) == 1:
        lo, hi = ranges[names[0]]
        return [{names[0]: (lo * (n - 1 - k) + hi * k) / (n - 1)} for k in range(n)]
    primes = [2, 3, 5, 7, 11, 13, 17, 19, 23, 29, 31, 37]
    for k in range(1, n + 1):
        point = {}
        for d, name in enumerate(names):
            f, x, i = 1.0, 0.0, k
            while i:
                f /= primes[d % len(primes)]
                x += f * (i % primes[d % len(primes)])
                i //= primes[d % len(primes)]
            lo, hi = ranges[name]
            point[name] = lo + (hi - lo) * x
        out.append(point)
    return out


def at_rest(sample: Mapping[str, float]) -> bool:
    """Every input zero: the as-fabricated pose, where every deviation vanishes exactly."""
    return all(v == 0 for v in sample.values())


def reference(analysis: Analysis, samples: list[dict[str, float]]):
    """(kept samples, deviations) of the most faithful derivation at 30 digits."""
    kept, devs = [], []
    for s in samples:
        try:
            ev = analysis.evaluate({k: repr(v) for k, v in s.items()}, "exact", dps=30)
        except AssemblyError:
            continue
        kept.append(s)
        devs.append({n: p.deviation for n, p in ev.points.items()})
    return kept, devs


def measure(mech: Mechanism, variant: Variant, samples: list[dict[str, float]],
            ref: list[dict], with_c: bool = True) -> Row:
    """Derive, emit and run one variant; its errors against `ref` and its times."""
    from .codegen import c_backend, c_runtime, numpy_backend
    from .codegen.build import plan
    from .derive import import_numpy_module

    analysis = analysis_for(mech, variant)
    p = plan(analysis, levels=[variant.level])
    tag = f"{mech.name}_{variant.name.replace('/', '_')}"
    module = import_numpy_module(numpy_backend.emit(p, "tradeoff", variant.precision), tag)
    names = list(module.INPUTS)
    arrays = {n: np.array([s[n] for s in samples]) for n in names}
    res = module.evaluate(arrays, variant.level)
    errors = {}
    for point in p.points:
        worst = 0.0
        got = res["points"][point]["deviation"].astype(float)
        # In the as-fabricated pose the deviation is exactly zero: there the error is measured
        # against the largest deviation over the range, so no sample goes unchecked.
        scale = max(math.hypot(*r[point]) for r in ref)
        for j, r in enumerate(ref):
            want = (0.0, 0.0) if at_rest(samples[j]) else r[point]
            size = scale if at_rest(samples[j]) else math.hypot(*want)
            if size == 0.0:
                continue
            err = math.hypot(got[0, j] - want[0], got[1, j] - want[1]) / size
            worst = max(worst, err if math.isfinite(err) else math.inf)
        errors[point] = worst
    reps = max(1, TIMING_POINTS // max(1, len(samples)))
    big = {n: np.tile(arrays[n], reps) for n in names}
    module.evaluate(big, variant.level)                     # warm up
    start = time.perf_counter()
    module.evaluate(big, variant.level)
    time_numpy = (time.perf_counter() - start) / len(next(iter(big.values())))
    time_c = None
    if with_c and variant.precision == "float64":
        header, code = c_backend.emit(p, "tradeoff")
        flat = [s[n] for s in samples for n in names]
        time_c = c_runtime.time_per_evaluation(tag, header, code, flat, len(samples),
                                               {"paper": 0, "first_order": 1,
                                                "exact": 2}[variant.level])
    ops = sum(r.ops for r in p.routines.values())
    return Row(variant, errors, time_numpy, time_c, ops)


def pareto(rows: list[Row]) -> list[Row]:
    """Rows marked when no other row is both faster and at least as accurate."""
    out = []
    for r in rows:
        dominated = any(o is not r and o.time <= r.time and o.worst <= r.worst
                        and (o.time < r.time or o.worst < r.worst) for o in rows)
        out.append(Row(r.variant, r.errors, r.time_numpy, r.time_c, r.ops, not dominated))
    return out


def run(mech: Mechanism, ranges: Mapping[str, tuple[float, float]], n: int = 25,
        variants: Sequence[Variant] | None = None, with_c: bool = True,
        progress=None) -> Tradeoff:
    """The full table for `mech` over `ranges`."""
    from .structure import build

    say = progress or (lambda message: None)
    faithful = Analysis(build(mech))
    samples = sample(ranges, n)
    say(f"reference: {len(samples)} samples at 30 digits")
    kept, ref = reference(faithful, samples)
    if not kept:
        raise InputError("no sample of the range can be assembled", file=mech.path,
                         entry="--range", hint="choose a range inside the assembly range")
    rows = []
    for v in variants or default_variants():
        say(f"variant {v.name}")
        rows.append(measure(mech, v, kept, ref, with_c))
    rows = pareto(rows)
    rows.sort(key=lambda r: (r.time, r.worst, r.variant))
    zero = sum(at_rest(s) for s in kept)
    return Tradeoff(dict(ranges), len(samples), len(samples) - len(kept), zero, tuple(rows),
                    tuple(kept))


def choose(table: Tradeoff, tolerance: float, points: Sequence[str] | None = None) -> Row:
    """The cheapest float64 variant whose worst error meets `tolerance` for the points."""
    good = [r for r in table.rows if r.variant.precision == "float64" and all(
        e <= tolerance for p, e in r.errors.items() if points is None or p in points)]
    if not good:
        best = min(table.rows, key=lambda r: r.worst)
        raise InputError(f"no variant meets the tolerance {tolerance:g} over the range (the "
                         f"most accurate, {best.variant.name}, reaches {best.worst:.3g})",
                         entry="--tolerance", hint="loosen the tolerance or narrow the range")
    return min(good, key=lambda r: (r.time, r.worst))


def text(table: Tradeoff) -> str:
    """The human table, fastest first, Pareto front marked with '*'."""
    from .templating import render

    return render("text/tradeoff.txt.j2", t=table)


def plot(table: Tradeoff, path: str) -> None:
    """Error against time, log-log, the Pareto front joined."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4.5))
    for r in table.rows:
        for t, marker, label in ((r.time_c, "o", "C"), (r.time_numpy, "s", "numpy")):
            if t is None:
                continue
            ax.loglog(t * 1e9, max(r.worst, 1e-17), marker, color="C0" if label == "C" else "C1",
                      alpha=0.9 if r.pareto else 0.35)
    front = sorted((r for r in table.rows if r.pareto), key=lambda r: r.time)
    ax.loglog([r.time * 1e9 for r in front], [max(r.worst, 1e-17) for r in front], "k--", lw=1)
    for r in front:
        ax.annotate(r.variant.name, (r.time * 1e9, max(r.worst, 1e-17)), fontsize=7,
                    xytext=(4, 3), textcoords="offset points")
    ax.set_xlabel("time per evaluation (ns): C (circles), numpy (squares)")
    ax.set_ylabel("worst relative error of the deviation")
    ax.grid(True, which="both", lw=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
