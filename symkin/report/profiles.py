"""Notch hinges in the report (docs/file-format.md, "Notch hinges"): the hinge table's rows (each
hinge's profile, its keys, thinnest section, span and a notch's stress-concentration factor K_t)
and the notch as cut in the pose figure (its two flanks ±T(x)/2 along its axis, magnified so that
the neck stays visible).

A report whose hinges are all uniform plates has neither (the table and the drawing appear with
the first notch), so plate reports are what they were.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import sympy as sp

from ..model.notches import Notch
from ..model.profiles import section_of
from ..model.sections import X
from .sections import Report, float_at
from .text import escape_latex, gnum

#: The pose's numbers (symkin.report.figures.PoseData, which draws with this module: not imported).
PoseData = Any

#: Samples of T(x) per piece of a profile drawn in the pose figure (cosine-spaced: dense at the
#: piece's ends, where a circular flank meets the block at a right angle).
SAMPLES = 96
#: A notch's span is drawn at least this fraction of the pose's extent (as plates are:
#: figures.plate_scale), its neck at least NECK of it (about 1 pt at the figure's width) and its
#: span at most LONGEST of it: beyond, the thickness alone is magnified further.
SPAN = 0.04
NECK = 0.006
LONGEST = 0.15
#: How a profile's own keys are printed (besides the thinnest section t and the span l_a).
KEY_SYMBOLS = {"radius": "R", "semi_axis": "a", "depth": "c", "length": "l", "fillet": "r"}


def _shown(report: Report, expr: Any) -> str:
    """A key as the file gives it: its number, or its expression and value."""
    value = gnum(float_at(expr, report.defaults))
    if sp.sympify(expr).is_number:
        return value
    return f"{report.tex.inline(sp.sympify(expr))} = {value}"


def has_notches(report: Report) -> bool:
    return any(report.d.hinges[a].hinge.profile != "uniform" for a in range(1, report.s.m + 1))


def profile_rows(report: Report) -> list[dict[str, object]] | None:
    """The hinge table (one row per hinge, in label order): the profile, its keys (file unit),
    the thinnest section t_a, the span l_a and a notch's K_t = (1 + t/(2ρ))^(9/20) at the file's
    parameter values (model.notches.Notch.stress_factor). None without a notch hinge."""
    if not has_notches(report):
        return None
    rows = []
    for a in range(1, report.s.m + 1):
        hinge = report.d.hinges[a].hinge
        keys, factor = [], r"\text{--}"
        if hinge.profile != "uniform":
            section = section_of(hinge, report.mech.unit_scale)
            assert isinstance(section, Notch)
            params = dict(hinge.profile_params)
            keys = [f"{KEY_SYMBOLS.get(k, k)} = {_shown(report, params[k])}" for k in section.keys]
            factor = f"{float_at(section.stress_factor(), report.defaults):.4f}"
        thickness = r"\text{--}" if hinge.thickness is None else _shown(report, hinge.thickness)
        rows.append(
            {
                "a": a,
                "name": report.hinge_name(a),
                "profile": escape_latex(hinge.profile.replace("_", " ")),
                "shape": ", ".join(keys) if keys else r"\text{--}",
                "thickness": thickness,
                "span": _shown(report, hinge.length),
                "factor": factor,
            }
        )
    return rows


def notch_outlines(report: Report) -> tuple[tuple[int, tuple[tuple[float, float], ...]], ...]:
    """Each notch hinge's profile for the pose figure: (a, ((x, T(x)), ...)) with x from the
    hinge centre along its axis, −span/2 to span/2, file unit, at the file's parameter values."""
    out = []
    for a in range(1, report.s.m + 1):
        hinge = report.d.hinges[a].hinge
        if hinge.profile == "uniform":
            continue
        section = section_of(hinge, report.mech.unit_scale)
        values = {s: sp.sympify(v) for s, v in report.defaults.items()}
        numbers = section.at(values)
        half = float_at(numbers.length, {}) / 2
        samples: dict[float, float] = {}
        for lo, hi, depth in numbers.pieces():
            thick = sp.lambdify(X, depth, "math")
            start, end = float_at(lo, {}), float_at(hi, {})
            for k in range(SAMPLES + 1):
                x = start + (end - start) * (1 - math.cos(math.pi * k / SAMPLES)) / 2
                samples[x - half] = float(thick(x))
            if start < half < end:
                samples[0.0] = float(thick(half))  # the neck, exactly
        out.append((a, tuple(sorted(samples.items()))))
    return tuple(out)


def _series(want: float) -> float:
    """The smallest of 1, 2, 5 × 10^k that is at least `want` (1 at least)."""
    if want <= 1:
        return 1.0
    k = 10 ** math.floor(math.log10(want))
    return float(next(step * k for step in (1, 2, 5, 10) if step * k >= want * (1 - 1e-12)))


def _largest(limit: float) -> float:
    """The largest of 1, 2, 5 × 10^k that is at most `limit` (1 at least)."""
    if limit <= 1:
        return 1.0
    k = 10 ** math.floor(math.log10(limit))
    return float(next(step * k for step in (5, 2, 1) if step * k <= limit * (1 + 1e-12)))


def extent(data: PoseData) -> float:
    """The pose's extent: the larger side of the box around the clamps and points."""
    every = [p for _, _, att in data.links for p in att] + [p for _, _, p in data.points]
    xs = [p[0] for p in every] or [0.0]
    ys = [p[1] for p in every] or [0.0]
    return float(max(max(xs) - min(xs), max(ys) - min(ys), 1e-12))


def notch_scale(data: PoseData) -> tuple[float, float]:
    """(along, across): the magnification of the notches' span and of their thickness in the
    pose figure. Both the same (the shape kept) where a span of SPAN..LONGEST of the extent
    shows the thinnest neck at NECK of it; else the span at LONGEST and the thickness further."""
    if not data.notches:
        return 1.0, 1.0
    size = extent(data)
    spans = [prof[-1][0] - prof[0][0] for _, prof in data.notches]
    necks = [min(t for _, t in prof) for _, prof in data.notches]
    longest, thinnest = max(spans), min(necks)
    along = _series(max(SPAN * size / longest, NECK * size / thinnest))
    along = min(along, _largest(LONGEST * size / longest))
    across = along * _series(NECK * size / (thinnest * along))
    return along, across


def notch_polygon(
    centre: tuple[float, float],
    axis: tuple[float, float],
    profile: Sequence[tuple[float, float]],
    along: float,
    across: float,
) -> list[tuple[float, float]]:
    """The notch's material between its two flanks as a closed polygon (data coordinates):
    x·along along the unit `axis` from `centre`, ±T(x)/2·across across it; the lower flank
    (to the axis's right) forwards, then the upper one back."""
    ux, uy = axis
    norm = math.hypot(ux, uy)
    ux, uy = ux / norm, uy / norm
    nx, ny = -uy, ux
    cx, cy = centre
    lower = [
        (cx + x * along * ux - t / 2 * across * nx, cy + x * along * uy - t / 2 * across * ny)
        for x, t in profile
    ]
    upper = [
        (cx + x * along * ux + t / 2 * across * nx, cy + x * along * uy + t / 2 * across * ny)
        for x, t in reversed(profile)
    ]
    return lower + upper


def caption(along: float, across: float) -> str:
    """The pose caption's words on the notches."""
    if along == across == 1:
        size = "to scale"
    elif along == across:
        size = f"magnified {along:g} times"
    else:
        size = f"magnified {along:g} times along their axis and {across:g} times across it"
    return f"the notch hinges as cut (their flanks $\\pm T(x)/2$, {size}, the neck at the centre)"
