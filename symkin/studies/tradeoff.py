"""`symkin tradeoff` (docs/cli.md): every variant's worst error over an input range and its time
per evaluation.

Errors are measured against the most faithful level the file's data allows
(`levels.reference()`): `equilibrium`, the plates' equilibrium, when every plate has its
stiffness (docs/physics.md), else the kinematic `exact` level of the file's own hinge models, in
mpmath at 30 digits. Times are measured in one run: the numpy evaluator vectorized over 10^4
points, the C evaluator in a loop timed inside C.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from ..core import levels
from ..core.errors import AssemblyError, InputError
from ..kinematics.analysis import Analysis
from ..kinematics.variants import Variant, analysis_for, default_variants
from ..model.mechanism import Mechanism
from .configuration import exact_value
from .evaluation import evaluate

DEFAULT_RANGE = (-0.2, 0.2)
TIMING_POINTS = 10_000
#: What every variant of a file without stiffness data is measured against.
REFERENCE = levels.reference()


def reference_level(mech: Mechanism) -> levels.Level:
    """What the variants of `mech` are measured against: `equilibrium` when every plate has its
    stiffness, else the kinematic `exact` level."""
    return levels.reference(mech.has_stiffness)


@dataclass(frozen=True)
class Row:
    """One variant's measurements."""

    variant: Variant
    errors: dict[str, float]  # point -> worst relative error of the deviation
    time_numpy: float  # seconds per point, vectorized
    time_c: float | None  # seconds per point, in a C loop (float64 variants)
    ops: int  # operations of the generated routines (after CSE)
    pareto_c: bool = False  # on the front of the variants timed in C
    pareto_numpy: bool = False  # on the front of the variants timed in numpy

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
    skipped: int  # samples the mechanism cannot assemble
    zero: int = 0  # samples where some point's reference deviation vanishes (worst_errors)
    rows: tuple[Row, ...] = field(default=())
    inputs: tuple[dict, ...] = field(default=())  # the samples measured (assembled ones)
    name: str = ""  # the mechanism's name
    reference: str = REFERENCE.name  # the level the errors are measured against

    @property
    def reference_text(self) -> str:
        if self.reference == "equilibrium":
            return (
                "equilibrium level: the plates' equilibrium as geometrically exact beams (the "
                "file's beam theory: Reissner, or the elastica) under the file's loads"
            )
        return f"mpmath, 30 digits, {self.reference} level, the file's hinge models"

    @property
    def reference_short(self) -> str:
        """The reference in a few words (titles, notes)."""
        if self.reference == "equilibrium":
            return "the equilibrium level (the plates as exact beams)"
        return f"the {self.reference} level in mpmath (30 digits)"

    def as_json(self) -> dict:
        return {
            "reference": self.reference_text,
            "reference_level": self.reference,
            "ranges": {k: list(v) for k, v in self.ranges.items()},
            "samples": self.samples,
            "skipped": self.skipped,
            "relative_error": NORMALISATION,
            "zero_deviation": self.zero,
            "inputs": list(self.inputs),
            "variants": [
                {
                    "name": r.variant.name,
                    "level": r.variant.level,
                    "model": r.variant.model,
                    "precision": r.variant.precision,
                    "worst_error": r.worst,
                    "errors": r.errors,
                    "time_numpy": r.time_numpy,
                    "time_c": r.time_c,
                    "ops": r.ops,
                    "pareto_c": r.pareto_c,
                    "pareto_numpy": r.pareto_numpy,
                }
                for r in self.rows
            ],
        }


def parse_ranges(
    items: Sequence[str] | None,
    inputs: Sequence[str],
    file: str,
    default: tuple[float, float] | None = DEFAULT_RANGE,
    strokes: Mapping[str, float] | None = None,
) -> dict[str, tuple[float, float]]:
    """H=LO:HI options (expressions allowed), every other input at `default` (left out when
    `default` is None), an actuator in `strokes` at ± its entry (Mechanism.stroke_spans)."""
    half = dict(strokes or {})
    ranges = {
        n: (-half[n], half[n]) if n in half and default is not None else default for n in inputs
    }
    for item in items or ():
        name, sep, span = item.partition("=")
        lo, colon, hi = span.partition(":")
        if not sep or not colon or name.strip() not in ranges:
            raise InputError(
                f"'{item}' is not INPUT=LO:HI for an input hinge or actuator",
                file=file,
                entry="--range",
                hint="inputs: " + ", ".join(inputs),
            )
        a, b = (float(exact_value(v.strip(), "--range", file)) for v in (lo, hi))
        if not a < b:
            raise InputError(
                f"empty range {a}:{b}", file=file, entry="--range", hint="give LO < HI"
            )
        ranges[name.strip()] = (a, b)
    return {name: span for name, span in ranges.items() if span is not None}


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


#: Below this fraction of the largest reference |ΔR| over the range, the reference deviation
#: vanishes (to the reference's accuracy: the unloaded as-fabricated pose, 1e-20 of it or less).
VANISHING = 1e-12
#: How every relative error of the table is normalised (the JSON's `relative_error`).
NORMALISATION = (
    "|dR - dR_ref| / |dR_ref| at each sample, dR_ref the reference's deviation there; where "
    f"|dR_ref| is below {VANISHING:g} of its largest over the range (it vanishes: the unloaded "
    "as-fabricated pose), / that largest"
)


def vanishes(want: tuple[float, float], scale: float) -> bool:
    """The reference deviation `want` is zero to its accuracy, against `scale`, the largest
    over the range."""
    return math.hypot(*want) < VANISHING * scale


def reference(analysis: Analysis, samples: list[dict[str, float]], level: str = REFERENCE.name):
    """(kept samples, deviations) of the most faithful derivation at 30 digits (`level`)."""
    kept, devs = [], []
    for s in samples:
        try:
            ev = evaluate(analysis, {k: repr(v) for k, v in s.items()}, level, dps=30)
        except AssemblyError:
            continue
        kept.append(s)
        hidden = {a.point for a in analysis.mechanism.actuators}  # the points of action
        devs.append({n: p.deviation for n, p in ev.points.items() if n not in hidden})
    return kept, devs


def worst_errors(got, want: Sequence[tuple[float, float]]) -> tuple[float, float]:
    """(absolute, relative) worst error of the deviations `got` (2, n) against the reference's
    `want` at the same samples, each sample against the reference as it is there (a preload
    deviates the as-fabricated pose too): |got - want| and that over |want| (see
    :data:`NORMALISATION`; where the reference deviation vanishes, over the largest over the
    range, so no sample goes unchecked). A non-finite result is an infinite error."""
    got = np.asarray(got, dtype=float)
    scale = max(math.hypot(*w) for w in want)
    absolute = relative = 0.0
    for j, w in enumerate(want):
        err = math.hypot(got[0, j] - w[0], got[1, j] - w[1])
        err = err if math.isfinite(err) else math.inf
        absolute = max(absolute, err)
        size = scale if vanishes(w, scale) else math.hypot(*w)
        if size > 0.0:
            relative = max(relative, err / size)
    return absolute, relative


def measure(
    mech: Mechanism,
    variant: Variant,
    samples: list[dict[str, float]],
    ref: list[dict],
    with_c: bool = True,
) -> Row:
    """Derive, emit and run one variant; its errors against `ref` and its times."""
    from ..codegen import pipeline, toolchain

    analysis = analysis_for(mech, variant)
    p, module = pipeline.build(
        analysis,
        "numpy",
        "tradeoff",
        variant.precision,
        levels=[variant.level],
        sensitivity=False,
        reported=False,  # the trade times the deviations alone
    )
    tag = f"{mech.name}_{variant.name.replace('/', '_')}"
    names = list(module.INPUTS)
    arrays = {n: np.array([s[n] for s in samples]) for n in names}
    res = module.evaluate(arrays, variant.level)
    errors = {
        point: worst_errors(res["points"][point]["deviation"], [r[point] for r in ref])[1]
        for point in p.shown_points
    }
    reps = max(1, TIMING_POINTS // max(1, len(samples)))
    big = {n: np.tile(arrays[n], reps) for n in names}
    module.evaluate(big, variant.level)  # warm up
    start = time.perf_counter()
    module.evaluate(big, variant.level)
    time_numpy = (time.perf_counter() - start) / len(next(iter(big.values())))
    time_c = None
    if with_c and variant.precision == "float64":
        header, code = pipeline.emit(p, "c", "tradeoff")
        flat = [s[n] for s in samples for n in names]
        time_c = toolchain.time_per_evaluation(
            tag, header, code, flat, len(samples), levels.get(variant.level).code
        )
    ops = sum(r.ops for r in p.routines.values())
    return Row(variant, errors, time_numpy, time_c, ops)


def front(points: Sequence[tuple[float, float]]) -> list[bool]:
    """For (time, error) points: True where no other point is both faster and at least as
    accurate (the Pareto front)."""
    return [
        not any(
            j != i and t2 <= t1 and e2 <= e1 and (t2 < t1 or e2 < e1)
            for j, (t2, e2) in enumerate(points)
        )
        for i, (t1, e1) in enumerate(points)
    ]


def pareto(rows: list[Row]) -> list[Row]:
    """Rows marked with the Pareto front of each backend they were timed with: C (float64
    variants) and numpy (every variant, float32 ones too)."""
    timed_c = [r for r in rows if r.time_c is not None]
    on_c = dict(zip(map(id, timed_c), front([(r.time_c, r.worst) for r in timed_c])))
    on_numpy = front([(r.time_numpy, r.worst) for r in rows])
    return [
        dataclasses.replace(r, pareto_c=on_c.get(id(r), False), pareto_numpy=flag)
        for r, flag in zip(rows, on_numpy)
    ]


def run(
    mech: Mechanism,
    ranges: Mapping[str, tuple[float, float]],
    n: int = 25,
    variants: Sequence[Variant] | None = None,
    with_c: bool = True,
    progress=None,
) -> Tradeoff:
    """The full table for `mech` over `ranges`."""
    from ..graph.structure import build

    mech.refuse_structure(what="tradeoff (its variants are generated evaluators)")
    forces = [a for a in mech.actuators if a.drive == "force"]
    if forces:
        raise InputError(
            f"the actuator '{forces[0].name}' drives by force: the kinematic variants cannot "
            "take it",
            file=mech.path,
            entry=f"[[actuator]] '{forces[0].name}'",
            hint='make it drive = "stroke" for the trade, or evaluate the force at --level '
            "equilibrium",
        )
    say = progress or (lambda message: None)
    faithful = Analysis(build(mech))
    samples = sample(ranges, n)
    level = reference_level(mech)
    say(f"reference: {len(samples)} samples at level {level.name}")
    kept, ref = reference(faithful, samples, level.name)
    if not kept:
        # the first sample's own refusal says why (a level that cannot take the mechanism, say)
        try:
            evaluate(faithful, {k: repr(v) for k, v in samples[0].items()}, level.name, dps=30)
            why = ""
        except AssemblyError as exc:
            why = (
                f" at level {level.name}; the first one: {str(exc).removeprefix(f'{mech.path}: ')}"
            )
        raise InputError(
            f"no sample of the range can be assembled{why}",
            file=mech.path,
            entry="--range",
            hint="choose a range inside the assembly range",
        )
    rows = []
    chosen = variants or default_variants(stiffness=level.needs_stiffness)
    if mech.actuators:
        # the generated evaluators hold the kinematic levels only with actuators
        # (symkin.codegen.plan: the same rule)
        chosen = [v for v in chosen if not levels.get(v.level).needs_stiffness]
    for v in chosen:
        say(f"variant {v.name}")
        rows.append(measure(mech, v, kept, ref, with_c))
    rows = pareto(rows)
    rows.sort(key=lambda r: (r.time, r.worst, r.variant))
    scales = {point: max(math.hypot(*d[point]) for d in ref) for point in ref[0]}
    zero = sum(any(vanishes(d[point], scales[point]) for point in d) for d in ref)
    return Tradeoff(
        dict(ranges),
        len(samples),
        len(samples) - len(kept),
        zero,
        tuple(rows),
        tuple(kept),
        mech.name,
        level.name,
    )


def choose(table: Tradeoff, tolerance: float, points: Sequence[str] | None = None) -> Row:
    """The cheapest float64 variant whose worst error meets `tolerance` for the points."""
    good = [
        r
        for r in table.rows
        if r.variant.precision == "float64"
        and all(e <= tolerance for p, e in r.errors.items() if points is None or p in points)
    ]
    if not good:
        best = min(table.rows, key=lambda r: r.worst)
        raise InputError(
            f"no variant meets the tolerance {tolerance:g} over the range (the "
            f"most accurate, {best.variant.name}, reaches {best.worst:.3g})",
            entry="--tolerance",
            hint="loosen the tolerance or narrow the range",
        )
    return min(good, key=lambda r: (r.time, r.worst))


def text(table: Tradeoff) -> str:
    """The human table, fastest first, Pareto front marked with '*'."""
    from ..codegen.templating import render

    return render("text/tradeoff.txt.j2", t=table)


def figure(table: Tradeoff):
    """The tradeoff figure: error against time per evaluation, log-log, one marker per variant and
    backend, each backend's Pareto front joined, every variant numbered and listed beside it."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D

    floor = 1e-17  # an error of exactly 0 is drawn at the floor
    fig = plt.figure(figsize=(11, 6))
    ax = fig.add_axes((0.07, 0.1, 0.5, 0.76))
    styles = {"C": ("o", "C0"), "numpy": ("s", "C1")}
    markers: list[tuple[float, float, int]] = []  # (time ns, error, variant number)
    for number, r in enumerate(table.rows, start=1):
        for backend, seconds, on_front in (
            ("C", r.time_c, r.pareto_c),
            ("numpy", r.time_numpy, r.pareto_numpy),
        ):
            if seconds is None:
                continue
            marker, color = styles[backend]
            x, y = seconds * 1e9, max(r.worst, floor)
            ax.loglog(
                x,
                y,
                marker,
                color=color,
                ms=6 if on_front else 4,
                alpha=1.0 if on_front else 0.35,
                markeredgewidth=0,
            )
            markers.append((x, y, number))
    for backend, attr, seconds, line in (
        ("C", "pareto_c", "time_c", "-"),
        ("numpy", "pareto_numpy", "time_numpy", "--"),
    ):
        rows = sorted(
            (r for r in table.rows if getattr(r, attr)), key=lambda r: getattr(r, seconds)
        )
        ax.loglog(
            [getattr(r, seconds) * 1e9 for r in rows],
            [max(r.worst, floor) for r in rows],
            line,
            color=styles[backend][1],
            lw=1,
        )
    ax.set_xlabel("time per evaluation (ns)")
    ax.set_ylabel("worst relative error of the deviation")
    ax.grid(True, which="both", lw=0.3)
    fig.legend(
        handles=[
            Line2D([], [], marker="o", color="C0", ls="", label="C (float64)"),
            Line2D([], [], marker="s", color="C1", ls="", label="numpy (float64, float32)"),
            Line2D([], [], color="C0", ls="-", label="Pareto front in C"),
            Line2D([], [], color="C1", ls="--", label="Pareto front in numpy"),
        ],
        fontsize=7,
        loc="lower left",
        bbox_to_anchor=(0.6, 0.1),
        frameon=False,
    )
    _number_markers(fig, ax, markers)
    span = ", ".join(f"{k} in [{a:g}, {b:g}]" for k, (a, b) in table.ranges.items())
    fig.suptitle(
        f"{table.name}: speed and accuracy of every variant\n{span} rad, "
        f"{table.samples} samples; error against {table.reference_short}, relative to its "
        "deviation at each sample",
        fontsize=10,
    )
    width = max([len(r.variant.name) for r in table.rows] + [7])
    lines = [f"  #  {'variant':<{width}}    error     C ns  numpy ns"]
    for number, r in enumerate(table.rows, start=1):
        c = f"{r.time_c * 1e9:8.0f}" if r.time_c is not None else "       -"
        mark = ("c" if r.pareto_c else " ") + ("n" if r.pareto_numpy else " ")
        lines.append(
            f"{number:3d}  {r.variant.name:<{width}} {r.worst:8.1e} {c} "
            f"{r.time_numpy * 1e9:8.0f} {mark}"
        )
    lines.append("c, n: on the Pareto front in C, in numpy")
    fig.text(0.6, 0.86, "\n".join(lines), family="monospace", fontsize=6.5, va="top")
    return fig


def _number_markers(fig, ax, markers: list[tuple[float, float, int]]) -> None:
    """Write each marker's variant number beside it where it overlaps no other number or marker
    (greedy over eight positions); a crowded marker stays unlabelled, its variant listed."""
    from matplotlib.transforms import Bbox

    fig.canvas.draw()  # final axis limits: display positions are now known
    renderer = fig.canvas.get_renderer()
    taken = [Bbox.from_bounds(*(ax.transData.transform((x, y)) - 3), 6, 6) for x, y, _ in markers]
    offsets = [(5, 3), (5, -9), (-11, 3), (-11, -9), (-3, 6), (-3, -13), (9, -3), (-15, -3)]
    for x, y, number in sorted(markers, key=lambda m: (m[1], m[0])):
        for dx, dy in offsets:
            label = ax.annotate(
                str(number), (x, y), xytext=(dx, dy), textcoords="offset points", fontsize=6
            )
            box = label.get_window_extent(renderer)
            if not any(box.overlaps(other) for other in taken):
                taken.append(box)
                break
            label.remove()


def plot(table: Tradeoff, path: str) -> None:
    """Save the tradeoff figure (the format follows the file's suffix)."""
    save_figure(figure(table), path)


def save_figure(fig, path: str) -> None:
    """Save and close a matplotlib figure without dates or versions (format from the suffix)."""
    import matplotlib.pyplot as plt

    fig.savefig(path, dpi=120, metadata=_PLOT_METADATA.get(path.rsplit(".", 1)[-1].lower()))
    plt.close(fig)


#: No dates or versions in saved figures, so the same table gives the same file.
_PLOT_METADATA = {
    "png": {"Software": None},
    "pdf": {"CreationDate": None, "Producer": None},
    "svg": {"Date": None},
}
