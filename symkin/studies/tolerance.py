"""`symkin tolerance` (docs/cli.md): linear worst-case and RSS stack-up of fabrication
tolerances ±a_p on the deviation of every point, over an input range.

At each configuration x of the input grid the sensitivities (docs/sensitivity.md) give, per
varied parameter p, the rate g_p = d|ΔR|/dp of the deviation's length (and d(dx)/dp, d(dy)/dp
of its components). A parameter error e_p with |e_p| <= a_p changes |ΔR| to first order by
Σ g_p e_p, so

    worst case  w(x) = Σ a_p |g_p(x)|           (every error at its limit, signs aligned)
    RSS         r(x) = sqrt(Σ (a_p g_p(x))²)     (independent errors, each a_p at the same
                                                  number of standard deviations)

and the command reports, per point, the largest w and r over the range (the bound on
|ΔR| − |ΔR₀| over the range), the configuration where each occurs, every parameter's share of
the worst case there (a_p |g_p| / w), the same for each component, and the stack-up of the
largest |ΔR| over the range (at the configuration where |ΔR₀| is largest: the quantity that
`symkin sweep` samples). Where ΔR₀ = 0 (the as-fabricated pose) g_p is |dΔR/dp|, the rate at
which |ΔR| grows from zero.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from ..core import levels
from ..core.errors import AssemblyError, InputError
from .compiled import Compiled
from .variation import Grid, Spread


@dataclass(frozen=True)
class Stack:
    """A linear stack-up at one configuration."""

    at: dict[str, float]  # the inputs
    nominal: float  # the quantity at nominal parameters
    worst_case: float
    rss: float
    contributions: dict[str, float]  # p -> a_p |g_p| / worst case, largest first
    rates: dict[str, float]  # p -> g_p

    def as_json(self) -> dict:
        return {
            "at": dict(self.at),
            "nominal": self.nominal,
            "worst_case": self.worst_case,
            "rss": self.rss,
            "contributions": dict(self.contributions),
            "rates": dict(self.rates),
        }


@dataclass(frozen=True)
class PointTolerance:
    """One point: the stack-up of |ΔR| (largest worst case and RSS over the range), of each
    component, and of the largest |ΔR| over the range."""

    worst: Stack  # at the configuration with the largest worst case
    rss: Stack  # at the configuration with the largest RSS
    components: dict[str, Stack]  # "dx", "dy": largest worst case of each component
    peak: Stack  # at the configuration with the largest |ΔR₀|

    def as_json(self) -> dict:
        return {
            "worst_case": self.worst.worst_case,
            "rss": self.rss.rss,
            "contributions": dict(self.worst.contributions),
            "at": dict(self.worst.at),
            "nominal": self.worst.nominal,
            "rss_at": dict(self.rss.at),
            "components": {k: s.as_json() for k, s in self.components.items()},
            "peak": self.peak.as_json(),
        }


@dataclass(frozen=True)
class Tolerance:
    """The result of `symkin tolerance`."""

    name: str
    level: str
    backend: str
    grid: Grid
    vary: dict[str, float]  # p -> a_p
    configurations: int
    failed: int  # configurations that could not be evaluated
    points: dict[str, PointTolerance]
    # configurations beyond the rigid reach of a force actuator's stroke (docs/physics.md):
    # solved, with no deviation to stack up; counted apart from the failures
    beyond_reach: int = 0

    def as_json(self) -> dict:
        return {
            "level": self.level,
            "backend": self.backend,
            "inputs": self.grid.as_json(),
            "vary": dict(self.vary),
            "configurations": self.configurations,
            "failed": self.failed,
            "beyond_reach": self.beyond_reach,
            "points": {p: t.as_json() for p, t in self.points.items()},
        }


def check_level(level: str) -> None:
    """A stack-up needs the level's sensitivities: a level without them is bad input (exit 2),
    naming the levels that have them."""
    if not levels.get(level).sensitivity:
        having = [lv.name for lv in levels.LEVELS if lv.generated and lv.sensitivity]
        raise InputError(
            f"the {level} level has no sensitivities, so no tolerance stack-up",
            entry="--level",
            hint="choose a level with sensitivities: " + ", ".join(having) + " "
            "(docs/sensitivity.md)",
        )


def run(
    evaluator: Compiled, vary: Mapping[str, Spread], grid: Grid, level: str | None = None
) -> Tolerance:
    """The stack-up of the ±a spreads `vary` over the configurations of `grid`, at `level`
    (None: the evaluator's default, Compiled.code)."""
    level = evaluator.code(level, sensitivity=True)
    check_level(level)
    x = grid.rows
    status, values, dev, _ = evaluator.sensitivity_rows(x, level)
    ok = status == 0
    beyond = int((status == 4).sum())  # beyond the rigid reach: solved, no deviation
    if not ok.any():
        raise AssemblyError(
            f"{evaluator.name}: the mechanism cannot be evaluated anywhere in "
            f"the input range {grid.as_json()}"
            + (
                f" ({beyond} configurations beyond the rigid linkage's reach: no deviation)"
                if beyond
                else ""
            )
        )
    names = list(evaluator.sources.params)
    index = [names.index(p) for p in vary]
    a = np.array([s.half_width for s in vary.values()])
    inputs = list(evaluator.inputs)
    points = {}
    for i, point in enumerate(evaluator.points):
        d0 = values[:, 6 * i + 4 : 6 * i + 6]  # (n, 2)
        rates = dev[:, i, index, :]  # (n, n_vary, 2)
        norm = np.hypot(d0[:, 0], d0[:, 1])
        with np.errstate(invalid="ignore", divide="ignore"):
            g = np.where(
                norm[:, None] > 0,
                (d0[:, None, 0] * rates[..., 0] + d0[:, None, 1] * rates[..., 1]) / norm[:, None],
                np.hypot(rates[..., 0], rates[..., 1]),
            )
        quantities = {
            "norm": (norm, g),
            "dx": (d0[:, 0], rates[..., 0]),
            "dy": (d0[:, 1], rates[..., 1]),
        }
        stacks = {}
        for key, (nominal, rate) in quantities.items():
            worst = np.where(ok, (a * np.abs(rate)).sum(axis=1), -np.inf)
            rss = np.where(ok, np.sqrt(((a * rate) ** 2).sum(axis=1)), -np.inf)
            stacks[key] = (nominal, rate, worst, rss)
        nominal, rate, worst, rss = stacks["norm"]
        peak = int(np.argmax(np.where(ok, norm, -np.inf)))

        def stack(k: int, key: str = "norm") -> Stack:
            nom, r, w, s = stacks[key]
            share = {
                p: float(a[j] * abs(r[k, j]) / w[k]) if w[k] > 0 else 0.0
                for j, p in enumerate(vary)
            }
            share = dict(sorted(share.items(), key=lambda item: -item[1]))
            return Stack(
                {h: float(x[k, j]) for j, h in enumerate(inputs)},
                float(nom[k]),
                float(w[k]),
                float(s[k]),
                share,
                {p: float(r[k, j]) for j, p in enumerate(vary)},
            )

        points[point] = PointTolerance(
            worst=stack(int(np.argmax(worst))),
            rss=stack(int(np.argmax(rss))),
            components={key: stack(int(np.argmax(stacks[key][2])), key) for key in ("dx", "dy")},
            peak=stack(peak),
        )
    return Tolerance(
        evaluator.name,
        level,
        evaluator.backend,
        grid,
        {p: s.half_width for p, s in vary.items()},
        len(x),
        int((~ok).sum()) - beyond,
        points,
        beyond,
    )


def text(result: Tolerance) -> str:
    """The ranked tables of `symkin tolerance`."""
    grid = result.grid.as_json()
    over = (
        f"over {result.configurations} configurations of "
        + ", ".join(f"{k} in [{v[0]:g}, {v[1]:g}]" for k, v in grid.items())
        if grid
        else "at its one configuration (a structure: no inputs)"
    )
    lines = [
        f"{result.name}: linear stack-up of the tolerances at level {result.level} "
        f"({result.backend}), {over}"
        + (f"; {result.failed} could not be evaluated" if result.failed else "")
        + (
            f"; {result.beyond_reach} beyond the rigid linkage's reach (no deviation)"
            if result.beyond_reach
            else ""
        )
    ]

    def where(at: Mapping[str, float]) -> str:
        return ", ".join(f"{k}={v:.4g}" for k, v in at.items()) or "the structure's pose"

    for point, t in result.points.items():
        w = t.worst
        at = where(w.at)
        lines += [
            "",
            f"point {point}: |dR| changes by at most {w.worst_case:.4g} (worst case) "
            f"or {t.rss.rss:.4g} (RSS) over the range",
            f"  worst case at {at}, where |dR| = {w.nominal:.4g}:",
            f"    {'parameter':<14} {'tolerance':>11} {'d|dR|/dp':>12} "
            f"{'contribution':>13} {'share':>7}",
        ]
        for p, share in w.contributions.items():
            lines.append(
                f"    {p:<14} {f'±{result.vary[p]:.4g}':>11} {w.rates[p]:>12.4e} "
                f"{result.vary[p] * abs(w.rates[p]):>13.4e} {100 * share:>6.1f}%"
            )
        pk = t.peak
        pat = where(pk.at)
        lines.append(
            f"  largest |dR| over the range: {pk.nominal:.4g} at {pat}, "
            f"± {pk.worst_case:.4g} (worst case), ± {pk.rss:.4g} (RSS)"
        )
        for key, s in t.components.items():
            lines.append(
                f"  {key}: changes by at most {s.worst_case:.4g} (worst case; RSS "
                f"{s.rss:.4g}) at " + where(s.at)
            )
    return "\n".join(lines) + "\n"


def linear_estimate(tol_rates: Mapping[str, float], errors: Mapping[str, float]) -> float:
    """Σ g_p e_p: the first-order change of a quantity for parameter errors e_p."""
    return math.fsum(tol_rates[p] * errors.get(p, 0.0) for p in tol_rates)
