"""The report's natural frequencies (docs/physics.md, "Natural frequencies"): the lowest
frequencies at a few values of each swept input (the others held as in the deviation plots) and
the first frequency's range over the whole sweep, from the generated numpy module's modes()
(docs/generated-code.md, "Natural frequencies in generated code"), for files whose links carry
mass."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from ..physics.modes import massive_links
from .figures import Sweep
from .sections import TEX_UNITS, Report, float_at
from .text import escape_latex, sci

#: The frequencies tabulated per configuration, and the configurations per swept input.
COUNT = 3
ROWS = 5
#: The first mode's largest arrow on the pose figure, as a share of the pose's extent.
ARROW = 0.15


def frequency_table(
    report: Report, numpy_module, runs: Sequence[tuple[str, Sweep, tuple[float, float]]]
) -> dict | None:
    """The table's rows (per swept input ROWS values evenly over the part of its range that
    assembles, each with its COUNT lowest frequencies in Hz) and each input's first-frequency
    range over its sweep; None when the module has no modes() (no link has a mass)."""
    if not hasattr(numpy_module, "modes") or not runs:
        return None
    held = {h: 0.5 * (data.t[0] + data.t[-1]) for h, data, _ in runs}
    actuators = {a.name: a for a in report.mech.actuators}
    unit = f"${TEX_UNITS[report.mech.units]}$"
    rows, spans = [], []
    for h, data, (lo, hi) in runs:
        act = actuators.get(h)
        what = "rad" if act is None else ("N" if act.drive == "force" else unit)

        def at(t: np.ndarray, h=h) -> dict:
            inputs = {n: (t if n == h else np.full_like(t, held[n])) for n in numpy_module.INPUTS}
            return numpy_module.modes(inputs, count=COUNT)

        whole = at(np.asarray(data.t, dtype=float))
        first = np.where(whole["ok"], whole["frequencies"][0], np.nan)
        first = first[np.isfinite(first)]
        spans.append(
            {
                "input": escape_latex(h),
                "unit": what,
                "lo": sci(float(first.min()), 4) if first.size else r"\text{--}",
                "hi": sci(float(first.max()), 4) if first.size else r"\text{--}",
            }
        )
        picks = np.linspace(lo, hi, ROWS)
        found = at(picks)
        for k, t in enumerate(picks):
            values = [
                float(found["frequencies"][j][k]) if found["ok"][k] else float("nan")
                for j in range(COUNT)
            ]
            rows.append(
                {
                    "input": escape_latex(h),
                    "unit": what,
                    "value": f"{t:+.3f}",
                    "frequencies": [sci(v, 4) for v in values],
                }
            )
    return {
        "count": COUNT,
        "rows": rows,
        "spans": spans,
        "links": [escape_latex(lk.name) for lk in massive_links(report.mech)],
    }


def first_mode_arrows(
    report: Report, numpy_module, runs: Sequence[tuple[str, Sweep, tuple[float, float]]], pose
) -> tuple[list[tuple[tuple[float, float], tuple[float, float]]], dict] | None:
    """The first mode at the middle of every swept range (the configuration the plots hold the
    other inputs at) as arrows on the as-fabricated pose (`pose`: symkin.report.figures's
    PoseData): from every massive link's centre and every point, its displacement scaled so
    that the largest is ARROW of the pose's extent; and the caption's numbers (the frequency,
    the inputs). None without modes() or where that configuration has no first mode."""
    if not hasattr(numpy_module, "modes") or not runs:
        return None
    held = {h: 0.5 * (data.t[0] + data.t[-1]) for h, data, _ in runs}
    found = numpy_module.modes({n: float(held[n]) for n in numpy_module.INPUTS}, count=1)
    f1 = float(found["frequencies"][0])
    if not (bool(found["ok"]) and math.isfinite(f1)):
        return None
    mech = report.mech
    defaults = report.defaults
    starts, moves = [], []
    for lk in massive_links(mech):
        assert lk.centre is not None
        starts.append(tuple(float_at(v, defaults) for v in lk.centre))
        moves.append(tuple(float(found["links"][lk.name][0][j]) for j in range(2)))
    for name, _, at in pose.points:
        if name in found["points"]:
            starts.append(at)
            moves.append(tuple(float(found["points"][name][0][j]) for j in range(2)))
    every = [p for _, _, att in pose.links for p in att] + [p for _, _, p in pose.points]
    every += starts
    extent = max(
        max(p[0] for p in every) - min(p[0] for p in every),
        max(p[1] for p in every) - min(p[1] for p in every),
        1e-12,
    )
    largest = max(math.hypot(*d) for d in moves)
    if not largest > 0:
        return None
    scale = ARROW * extent / largest
    arrows = [
        ((a[0], a[1]), (d[0] * scale, d[1] * scale))
        for a, d in zip(starts, moves)
        if math.hypot(*d) > 1e-3 * largest
    ]
    inputs = ", ".join(f"{escape_latex(n)} = {held[n]:.3g}" for n in numpy_module.INPUTS)
    return arrows, {"frequency": sci(f1, 4), "inputs": inputs}
