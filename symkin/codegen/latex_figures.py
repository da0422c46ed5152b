"""The report's figures, drawn with matplotlib (Agg canvas, PDF output, byte-deterministic).

- :func:`pose_figure`: the mechanism as fabricated: links between their hinge clamps (a link with
  three or more attachments as a filled polygon), plates as short thick segments from clamp to
  clamp, the ground as hatched anchors, the characteristic points, every name labelled.
- :func:`graph_figure`: the oriented graph, vertices s_i, arcs u_a from i+(a) to i-(a).
- :func:`deviation_figure`: |ΔR| of each point over an input range at every level, and the
  difference of the approximate levels from the exact one.

Names from the mechanism file are drawn with math parsing off (no ``$...$`` interpretation).
Determinism: fixed rcParams (``svg.hashsalt``, ``pdf.compression``, fonts), no timestamps or
producer in the PDF metadata, no dependence on dict/set order.
"""

from __future__ import annotations

import io
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

_SUB = str.maketrans("0123456789", "₀₁₂₃₄₅₆₇₈₉")

RC = {
    "svg.hashsalt": "symkin",
    "pdf.compression": 6,
    "pdf.fonttype": 42,
    "font.family": "serif",
    "font.serif": ["DejaVu Serif"],
    "mathtext.fontset": "dejavuserif",
    "font.size": 8.0,
    "axes.titlesize": 8.5,
    "axes.labelsize": 8.0,
    "legend.fontsize": 7.0,
    "xtick.labelsize": 7.0,
    "ytick.labelsize": 7.0,
    "axes.linewidth": 0.6,
    "lines.linewidth": 1.1,
    "xtick.major.width": 0.5,
    "ytick.major.width": 0.5,
    "axes.formatter.use_mathtext": True,
    "path.simplify": False,
    "hatch.linewidth": 0.5,
}

METADATA = {"CreationDate": None, "ModDate": None, "Producer": None, "Creator": None}

FIG_WIDTH = 4.8          # inches: one-column text width (345 pt), scaled to \linewidth

LINK_COLOURS = ("#1f5fa8", "#b5651d", "#2e7d32", "#8e24aa", "#c62828", "#00838f", "#6d4c41",
                "#ad1457", "#455a64", "#9e9d24")


def sub(k: int) -> str:
    """Unicode subscript digits: s₀, u₁₂ (no math text, so names stay literal)."""
    return str(k).translate(_SUB)


def _render(fig) -> bytes:
    buf = io.BytesIO()
    fig.savefig(buf, format="pdf", metadata=METADATA)
    return buf.getvalue()


def _figure(width: float, height: float):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width, height))
    FigureCanvasAgg(fig)
    return fig


def rc_context():
    import matplotlib

    return matplotlib.rc_context(RC)


# -- pose ------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class PoseData:
    """Numbers of the as-fabricated pose (floats, absolute frame)."""

    links: tuple[tuple[int, str, tuple[tuple[float, float], ...]], ...]   # label, name, attachments
    ground: int
    plates: tuple[tuple[int, str, tuple[float, float], tuple[float, float], bool], ...]
    points: tuple[tuple[str, int, tuple[float, float]], ...]                # name, link, position


def _hull(pts: Sequence[tuple[float, float]]) -> list[tuple[float, float]]:
    """Convex hull (monotone chain), counter-clockwise, deterministic."""
    pts = sorted(set(pts))
    if len(pts) <= 2:
        return list(pts)

    def cross(o, a, b):
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])

    lower: list = []
    for p in pts:
        while len(lower) >= 2 and cross(lower[-2], lower[-1], p) <= 0:
            lower.pop()
        lower.append(p)
    upper: list = []
    for p in reversed(pts):
        while len(upper) >= 2 and cross(upper[-2], upper[-1], p) <= 0:
            upper.pop()
        upper.append(p)
    return lower[:-1] + upper[:-1]


def pose_figure(data: PoseData, plain) -> bytes:
    """PDF of the as-fabricated pose; `plain` makes a name safe for matplotlib text."""
    from matplotlib.patches import Polygon

    every = [p for _, _, att in data.links for p in att] + [p for _, _, p in data.points]
    xs = [p[0] for p in every] or [0.0]
    ys = [p[1] for p in every] or [0.0]
    span = max(max(xs) - min(xs), max(ys) - min(ys), 1e-12)
    cx, cy = (max(xs) + min(xs)) / 2, (max(ys) + min(ys)) / 2
    aspect = (max(ys) - min(ys) + 0.3 * span) / (max(xs) - min(xs) + 0.3 * span)
    height = min(max(FIG_WIDTH * aspect, 2.2), 4.6)
    with rc_context():
        fig = _figure(FIG_WIDTH, height)
        ax = fig.add_axes((0.11, 0.1, 0.86, 0.86))
        ax.set_aspect("equal", adjustable="datalim")
        ax.grid(True, lw=0.3, color="0.88", zorder=0)
        ax.set_axisbelow(True)
        anchor = 0.035 * span
        for label, name, att in data.links:
            colour = LINK_COLOURS[(label - 1) % len(LINK_COLOURS)] if label else "0.3"
            if label == data.ground:
                for x, y in att:
                    tri = Polygon([(x, y), (x - anchor / 2, y - anchor), (x + anchor / 2, y - anchor)],
                                  closed=True, facecolor="white", edgecolor="0.25", lw=0.7,
                                  zorder=2)
                    ax.add_patch(tri)
                    ax.add_patch(Polygon([(x - anchor, y - anchor), (x + anchor, y - anchor),
                                          (x + anchor, y - 1.45 * anchor),
                                          (x - anchor, y - 1.45 * anchor)], closed=True,
                                         facecolor="none", edgecolor="0.25", hatch="////",
                                         lw=0.0, zorder=2))
                    ax.plot([x - anchor, x + anchor], [y - anchor, y - anchor], color="0.25",
                            lw=0.8, zorder=2)
                if att:
                    gx, gy = min(att)
                    ax.annotate(f"{plain(name)} (s{sub(label)})", (gx, gy),
                                xytext=(gx, gy - 1.6 * anchor), textcoords="data",
                                ha="center", va="top", fontsize=7, color="0.25",
                                annotation_clip=False, parse_math=False)
                continue
            pts = list(att) + [p for _, lk, p in data.points if lk == label]
            hull = _hull(pts)
            if len(hull) >= 3:
                ax.add_patch(Polygon(hull, closed=True, facecolor=colour, alpha=0.16,
                                     edgecolor="none", zorder=2))
                ring = hull + [hull[0]]
                ax.plot([p[0] for p in ring], [p[1] for p in ring], color=colour, lw=1.4,
                        solid_joinstyle="round", zorder=3)
                lx = sum(p[0] for p in hull) / len(hull)
                ly = sum(p[1] for p in hull) / len(hull)
                offset = (0, 0)
            elif len(hull) == 2:
                (x0, y0), (x1, y1) = hull
                ax.plot([x0, x1], [y0, y1], color=colour, lw=1.8, solid_capstyle="round",
                        zorder=3)
                lx, ly = (x0 + x1) / 2, (y0 + y1) / 2
                nx, ny = -(y1 - y0), x1 - x0
                norm = math.hypot(nx, ny) or 1.0
                # label on the side away from the mechanism's centre
                side = 1.0 if (lx - cx) * nx + (ly - cy) * ny >= 0 else -1.0
                offset = (side * 9 * nx / norm, side * 9 * ny / norm)
            else:
                if not hull:
                    continue
                lx, ly = hull[0]
                offset = (8, 8)
            ax.annotate(f"{plain(name)} (s{sub(label)})", (lx, ly), xytext=offset,
                        textcoords="offset points", ha="center", va="center", fontsize=7,
                        color=colour, parse_math=False, zorder=6,
                        bbox={"boxstyle": "round,pad=0.15", "fc": "white", "ec": "none",
                              "alpha": 0.75})
        for a, name, p, m, is_input in data.plates:
            ax.plot([p[0], m[0]], [p[1], m[1]], color="black", lw=3.2, solid_capstyle="butt",
                    zorder=5)
            hx, hy = (p[0] + m[0]) / 2, (p[1] + m[1]) / 2
            ax.plot([hx], [hy], marker="o", ms=7.5, mfc="none", mec="black", mew=0.6,
                    zorder=5)
            dx, dy = hx - cx, hy - cy
            norm = math.hypot(dx, dy) or 1.0
            text = f"{plain(name)} (u{sub(a)})" + (", input" if is_input else "")
            ax.annotate(text, (hx, hy), xytext=(12 * dx / norm, 12 * dy / norm),
                        textcoords="offset points", ha="left" if dx > 0.2 * norm else (
                            "right" if dx < -0.2 * norm else "center"),
                        va="bottom" if dy > 0 else "top", fontsize=7, parse_math=False,
                        zorder=6)
        for name, link, (x, y) in data.points:
            ax.plot([x], [y], marker="o", ms=4.0, color="#c62828", zorder=7)
            ax.annotate(plain(name), (x, y), xytext=(5, 5), textcoords="offset points",
                        fontsize=8, color="#c62828", fontweight="bold", parse_math=False,
                        zorder=7)
        pad = 0.14 * span
        ax.set_xlim(min(xs) - pad, max(xs) + pad)
        ax.set_ylim(min(ys) - pad - 1.6 * anchor, max(ys) + pad)
        ax.set_xlabel("x")
        ax.set_ylabel("y")
        ax.tick_params(direction="in")
        return _render(fig)


# -- oriented graph ----------------------------------------------------------------------------

def graph_figure(positions: dict[int, tuple[float, float]],
                 arcs: Sequence[tuple[int, int, int, bool]]) -> bytes:
    """PDF of the oriented graph: `arcs` are (a, i+, i-, is_chord)."""
    from matplotlib.patches import Circle, FancyArrowPatch

    labels = sorted(positions)
    xs = [positions[i][0] for i in labels]
    ys = [positions[i][1] for i in labels]
    span = max(max(xs) - min(xs), max(ys) - min(ys), 1e-12)
    aspect = (max(ys) - min(ys) + 0.35 * span) / (max(xs) - min(xs) + 0.35 * span)
    width = 2.6
    height = min(max(width * aspect, 1.5), 3.0)
    radius = 0.055 * span
    with rc_context():
        fig = _figure(width, height)
        ax = fig.add_axes((0.01, 0.01, 0.98, 0.98))
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_axis_off()
        for i in labels:
            x, y = positions[i]
            ax.add_patch(Circle((x, y), radius, facecolor="white", edgecolor="black", lw=0.7,
                                zorder=3))
            ax.text(x, y, f"s{sub(i)}", ha="center", va="center", fontsize=7, zorder=4,
                    parse_math=False)
        seen: dict[tuple[int, int], int] = {}
        for a, ip, im, chord in arcs:
            key = (min(ip, im), max(ip, im))
            k = seen.get(key, 0)
            seen[key] = k + 1
            rad = 0.0 if k == 0 else 0.35 * (1 if k % 2 else -1) * ((k + 1) // 2)
            p, q = positions[ip], positions[im]
            arrow = FancyArrowPatch(p, q, arrowstyle="-|>,head_length=3.5,head_width=1.8",
                                    connectionstyle=f"arc3,rad={rad}", shrinkA=0, shrinkB=0,
                                    patchA=None, patchB=None, lw=0.8,
                                    linestyle="--" if chord else "-", color="black", zorder=2)
            # shrink to the circles' edges in data units
            dx, dy = q[0] - p[0], q[1] - p[1]
            d = math.hypot(dx, dy) or 1.0
            ux, uy = dx / d, dy / d
            arrow.set_positions((p[0] + radius * ux, p[1] + radius * uy),
                                (q[0] - radius * ux, q[1] - radius * uy))
            ax.add_patch(arrow)
            mx, my = (p[0] + q[0]) / 2 - rad * dy / 2, (p[1] + q[1]) / 2 + rad * dx / 2
            ax.text(mx - 0.5 * radius * uy * 1.6, my + 0.5 * radius * ux * 1.6, f"u{sub(a)}",
                    ha="center", va="center", fontsize=6.5, zorder=4, parse_math=False,
                    bbox={"boxstyle": "round,pad=0.08", "fc": "white", "ec": "none"})
        pad = 0.12 * span + radius
        ax.set_xlim(min(xs) - pad, max(xs) + pad)
        ax.set_ylim(min(ys) - pad, max(ys) + pad)
        return _render(fig)


# -- deviation over an input range ---------------------------------------------------------

@dataclass(frozen=True)
class Sweep:
    """|ΔR| of the points over t (every input = t), per level; NaN where not assembled."""

    t: np.ndarray
    ok: np.ndarray
    magnitude: dict[str, dict[str, np.ndarray]]      # point -> level -> |ΔR|
    deviation: dict[str, dict[str, np.ndarray]]      # point -> level -> (2, N)


LEVEL_STYLE = {
    "paper": {"color": "#c62828", "ls": "--", "label": "paper (4.8)"},
    "first_order": {"color": "#1f5fa8", "ls": "-.", "label": "first order"},
    "exact": {"color": "black", "ls": "-", "label": "exact"},
}


def _runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """Index ranges [i, j] of consecutive True entries."""
    out, start = [], None
    for k, v in enumerate(mask):
        if v and start is None:
            start = k
        if not v and start is not None:
            out.append((start, k - 1))
            start = None
    if start is not None:
        out.append((start, len(mask) - 1))
    return out


def deviation_figure(sweep: Sweep, points: Sequence[str], levels: Sequence[str], plain,
                     xlim: tuple[float, float], xlabel: str) -> bytes:
    """PDF with one row per point: |ΔR| at every level, and |ΔR_level - ΔR_exact|."""
    from matplotlib.patches import Patch

    compare = "exact" in levels and len(levels) > 1
    rows = len(points)
    ncols = 2 if compare else 1
    height = 0.55 + 1.75 * rows
    t = sweep.t
    step = float(t[1] - t[0]) if len(t) > 1 else 0.0
    with rc_context():
        fig = _figure(FIG_WIDTH, height)
        grid = fig.add_gridspec(rows, ncols, left=0.1, right=0.98, bottom=0.5 / height + 0.06,
                                top=1 - 0.28 / height, wspace=0.3, hspace=0.55)
        handles = []
        for r, name in enumerate(points):
            axes = [fig.add_subplot(grid[r, c]) for c in range(ncols)]
            for ax in axes:
                for i, j in _runs(~sweep.ok):
                    ax.axvspan(t[i] - step / 2, t[j] + step / 2, facecolor="0.85",
                               edgecolor="0.6", hatch="xx", lw=0.0, zorder=0)
                ax.set_xlim(*xlim)
                ax.grid(True, lw=0.3, color="0.9")
                ax.tick_params(direction="in", which="both")
            for lv in levels:
                st = LEVEL_STYLE[lv]
                line, = axes[0].plot(t, sweep.magnitude[name][lv], color=st["color"],
                                     ls=st["ls"], label=st["label"])
                if r == 0:
                    handles.append(line)
            axes[0].set_ylabel("|ΔR|")
            axes[0].ticklabel_format(axis="y", style="sci", scilimits=(-2, 3), useMathText=True)
            axes[0].set_title(f"point {plain(name)}: deviation", loc="left", parse_math=False)
            if compare:
                exact = sweep.deviation[name]["exact"]
                for lv in levels:
                    if lv == "exact":
                        continue
                    diff = np.hypot(*(sweep.deviation[name][lv] - exact))
                    diff = np.where(diff > 0, diff, np.nan)
                    st = LEVEL_STYLE[lv]
                    axes[1].semilogy(t, diff, color=st["color"], ls=st["ls"])
                axes[1].set_ylabel("|ΔR − ΔR_exact|")
                axes[1].set_title(f"point {plain(name)}: error of the approximations",
                                  loc="left", parse_math=False)
            if r == rows - 1:
                for ax in axes:
                    ax.set_xlabel(xlabel)
        if not sweep.ok.all():
            handles.append(Patch(facecolor="0.85", edgecolor="0.6", hatch="xx",
                                 label="cannot be assembled"))
        fig.legend(handles=handles, loc="lower center", ncol=len(handles), frameon=False,
                   bbox_to_anchor=(0.5, 0.0))
        return _render(fig)
