"""Element columns that follow a hinge's local thickness (docs/fea.md, "One notch").

A notch's thickness T(x) varies along its span by a factor of 10–100, so columns of elements
equally spaced along it either waste elements in the thick ends or leave the neck coarse. Here
the corners sit at equal steps of s(x) = ∫ dx/T: every column is as long as a fixed fraction of
its own thickness. Used by the mechanism's deck (fea.deck, a plate whose profile is not uniform)
and by the single-notch model (fea.notch_mesh).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable

#: Fine steps per local thickness of the quadrature of s(x) = ∫ dx/T that places the columns.
STEPS_PER_THICKNESS = 64

Depth = Callable[[float], float]


def _stretch(depth: Depth, span: float) -> tuple[list[float], list[float]]:
    """Samples (x_k, s_k) of s(x) = ∫_0^x dx/T(x) over [0, span] (Simpson's rule on 1/T): steps
    of T(x)/STEPS_PER_THICKNESS, shrinking geometrically towards both ends."""
    xs, ss = [0.0], [0.0]
    x, s = 0.0, 0.0
    tiny = 1e-12 * span
    while x < span:
        # steps shrink geometrically into both ends, where T(x) may have a vertical tangent (a
        # circular notch's ends): Simpson's rule then stays accurate on every step
        rest = span - x
        h = (
            rest
            if rest <= tiny
            else min(depth(x) / STEPS_PER_THICKNESS, 0.2 * max(x, tiny), 0.2 * rest)
        )
        s += _simpson(depth, x, x + h)
        x = span if h == rest else x + h
        xs.append(x)
        ss.append(s)
    return xs, ss


def _simpson(depth: Depth, a: float, b: float) -> float:
    """∫_a^b dx/T by Simpson's rule (b − a at most a fine step)."""
    return (b - a) * (1 / depth(a) + 4 / depth((a + b) / 2) + 1 / depth(b)) / 6


def column_count(depth: Depth, span: float, across: int, aspect: float = 1.0) -> int:
    """Columns of elements over the span so that an element is about `aspect` times as long as
    it is thick (T(x)/across): across/aspect · ∫ dx/T, rounded up."""
    _, ss = _stretch(depth, span)
    return max(1, math.ceil(across / aspect * ss[-1] - 1e-9))


def columns(depth: Depth, span: float, count: int) -> list[float]:
    """The 2 count + 1 node positions along [0, span] of `count` quadratic element columns whose
    widths are proportional to the local thickness: corners at equal steps of s(x) = ∫ dx/T,
    midside nodes halfway between them."""
    xs, ss = _stretch(depth, span)
    total = ss[-1]
    corners = [0.0]
    k = 0
    for n in range(1, count):
        target = total * n / count
        while ss[k + 1] < target:
            k += 1
        f = (target - ss[k]) / (ss[k + 1] - ss[k])
        x = xs[k] + f * (xs[k + 1] - xs[k])
        for _ in range(3):  # Newton on s(x) = target, s'(x) = 1/T(x)
            x += (target - ss[k] - _simpson(depth, xs[k], x)) * depth(x)
        corners.append(x)
    corners.append(span)
    out: list[float] = []
    for a, b in itertools.pairwise(corners):
        out += [a, (a + b) / 2]
    return out + [span]
