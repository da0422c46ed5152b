"""The report's figures, drawn with matplotlib (Agg canvas, PDF output, byte-deterministic).

- :func:`pose_figure`: the mechanism as fabricated: links between their hinge clamps (a link with
  three or more attachments as a filled polygon), plates as short thick segments along the plate
  (magnified by :func:`plate_scale` when they would be invisible), notch hinges as cut (their
  flanks, magnified by :func:`~symkin.report.profiles.notch_scale`), the ground as hatched anchors,
  the characteristic points, every name labelled; labels are placed greedily where they overlap
  no other label, marker or line (:func:`_place_labels`).
- :func:`graph_figure`: the oriented graph, vertices s_i, arcs u_a from i+(a) to i-(a).
- :func:`deviation_figure`: |ΔR| of each point over an input range at every level, and the
  difference of the approximate levels from the exact one.
- :func:`stress_figure`: each plate's largest stress over an input range at the level
  `equilibrium`, with the allowable stresses as lines.

Names from the mechanism file are drawn with math parsing off (no ``$...$`` interpretation).
Determinism: fixed rcParams (``svg.hashsalt``, ``pdf.compression``, fonts), no timestamps or
producer in the PDF metadata, no dependence on dict/set order.
"""

from __future__ import annotations

import functools
import hashlib
import io
import itertools
import math
import pickle
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from ..core.levels import Level
from ..core.recent import Recent
from .profiles import notch_polygon, notch_scale

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

FIG_WIDTH = 4.8  # inches: one-column text width (345 pt), scaled to \linewidth

LINK_COLOURS = (
    "#1f5fa8",
    "#b5651d",
    "#2e7d32",
    "#8e24aa",
    "#c62828",
    "#00838f",
    "#6d4c41",
    "#ad1457",
    "#455a64",
    "#9e9d24",
)


def sub(k: int) -> str:
    """Unicode subscript digits: s₀, u₁₂ (no math text, so names stay literal)."""
    return str(k).translate(_SUB)


#: The figures drawn last, by their function and a digest of their inputs: a report's figures
#: are drawn again for its appendix and at other column widths, and the same file is reported
#: again in a session (a test run drew 186 figures of 54 kinds, 32 s of its 48 s again).
_DRAWN: Recent[str, bytes] = Recent(64)


def _kept(draw: Callable[..., bytes]) -> Callable[..., bytes]:
    """`draw` (inputs -> PDF bytes, a pure function) drawn once per inputs: equal pickles are
    equal inputs; inputs pickle cannot take are drawn every time."""

    @functools.wraps(draw)
    def kept(*args, **kwargs) -> bytes:
        try:
            data = pickle.dumps((args, sorted(kwargs.items())), protocol=pickle.HIGHEST_PROTOCOL)
        except Exception:  # e.g. a local function among the inputs
            return draw(*args, **kwargs)
        key = f"{draw.__name__}:{hashlib.sha256(data).hexdigest()}"
        return _DRAWN.get_or_make(key, lambda: draw(*args, **kwargs))

    return kept


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

    links: tuple[tuple[int, str, tuple[tuple[float, float], ...]], ...]  # label, name, attachments
    ground: int
    plates: tuple[tuple[int, str, tuple[float, float], tuple[float, float], bool], ...]
    points: tuple[tuple[str, int, tuple[float, float]], ...]  # name, link, position
    #: the notch hinges' profiles: (a, ((x, T(x)), ...)), x along the axis from the hinge
    #: centre (symkin.report.profiles.notch_outlines); drawn as cut, not as plates
    notches: tuple[tuple[int, tuple[tuple[float, float], ...]], ...] = ()


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


def plate_scale(data: PoseData) -> float:
    """Magnification that draws the longest plate at about 4 % of the drawing (1, 2, 5 x 10^k;
    never below 1): flexure plates are tiny next to the links."""
    every = [p for _, _, att in data.links for p in att] + [p for _, _, p in data.points]
    xs = [p[0] for p in every] or [0.0]
    ys = [p[1] for p in every] or [0.0]
    span = max(max(xs) - min(xs), max(ys) - min(ys), 1e-12)
    cut = {a for a, _ in data.notches}
    longest = max(
        [math.hypot(m[0] - p[0], m[1] - p[1]) for a, _, p, m, _ in data.plates if a not in cut]
        + [0]
    )
    if longest <= 0:
        return 1.0
    want = 0.04 * span / longest
    if want <= 1.5:
        return 1.0
    k = 10 ** math.floor(math.log10(want))
    for step in (1, 2, 5, 10):
        if step * k >= want / 1.6:
            return float(step * k)
    return float(10 * k)


def pose_size(data: PoseData) -> tuple[float, float]:
    """Figure (width, height) in inches: equal axes, at most 3.3 in high."""
    every = [p for _, _, att in data.links for p in att] + [p for _, _, p in data.points]
    xs = [p[0] for p in every] or [0.0]
    ys = [p[1] for p in every] or [0.0]
    span = max(max(xs) - min(xs), max(ys) - min(ys), 1e-12)
    w = max(xs) - min(xs) + 0.5 * span
    h = max(ys) - min(ys) + 0.36 * span
    axes_w = FIG_WIDTH - 0.75
    height = axes_w * h / w + 0.55
    if height <= 3.3:
        return FIG_WIDTH, max(height, 1.8)
    height = 3.3
    return min(FIG_WIDTH, (height - 0.55) * w / h + 0.75), height


@dataclass
class _Label:
    """A label to place: anchor points (data), text, style, preferred direction (dx, dy)."""

    anchors: list[tuple[float, float]]
    text: str
    style: dict
    prefer: tuple[float, float]
    distance: float = 7.0
    centred: bool = False  # the anchor itself is a candidate (text over a filled area)


def _segment_hits_box(p, q, box) -> bool:
    """Whether the segment p-q (display coordinates) meets the rectangle `box`."""
    x0, y0, x1, y1 = box.x0, box.y0, box.x1, box.y1
    (px, py), (qx, qy) = p, q
    t0, t1 = 0.0, 1.0
    dx, dy = qx - px, qy - py
    for pk, qk in ((-dx, px - x0), (dx, x1 - px), (-dy, py - y0), (dy, y1 - py)):
        if pk == 0:
            if qk < 0:
                return False
            continue
        r = qk / pk
        if pk < 0:
            t0 = max(t0, r)
        else:
            t1 = min(t1, r)
        if t0 > t1:
            return False
    return True


def _candidates(label: _Label) -> list[tuple[float, float]]:
    """Offsets in points: the preferred direction first, then the others by angle from it."""
    px, py = label.prefer
    base = math.atan2(py, px) if (px or py) else math.pi / 4
    dirs = []
    for k in range(16):
        ang = base + (k + 1) // 2 * (math.pi / 8) * (1 if k % 2 else -1) if k else base
        dirs.append(ang)
    out = [(0.0, 0.0)] if label.centred else []
    for dist in (label.distance, 2.2 * label.distance):
        out += [(dist * math.cos(a), dist * math.sin(a)) for a in dirs]
    return out


def _place_labels(fig, ax, labels: Sequence[_Label], segments, markers) -> None:
    """Greedy placement: for each label the first candidate (anchor x offset) that overlaps no
    placed label or marker, crosses the fewest drawn segments and stays inside the axes."""
    renderer = fig.canvas.get_renderer()
    to_px = ax.transData.transform
    segs = [(tuple(to_px(p)), tuple(to_px(q))) for p, q in segments]
    marks = [tuple(to_px(m)) for m in markers]
    frame = ax.get_window_extent(renderer)
    placed = []
    for label in labels:
        best = None
        for ai, anchor in enumerate(label.anchors):
            own = tuple(to_px(anchor))
            for rank, (dx, dy) in enumerate(_candidates(label)):
                ha = "left" if dx > 0.5 else ("right" if dx < -0.5 else "center")
                va = "bottom" if dy > 0.5 else ("top" if dy < -0.5 else "center")
                text = ax.annotate(
                    label.text,
                    anchor,
                    xytext=(dx, dy),
                    textcoords="offset points",
                    ha=ha,
                    va=va,
                    parse_math=False,
                    **label.style,
                )
                box = text.get_window_extent(renderer).expanded(1.04, 1.12)
                text.remove()
                cost = rank + 0.5 * ai
                cost += 1000 * sum(box.overlaps(b) for b in placed)
                cost += 300 * sum(
                    box.x0 - 3 < mx < box.x1 + 3 and box.y0 - 3 < my < box.y1 + 3
                    for mx, my in marks
                    if (mx, my) != own
                )
                cost += 40 * sum(_segment_hits_box(p, q, box) for p, q in segs)
                if not (
                    frame.x0 <= box.x0
                    and box.x1 <= frame.x1
                    and frame.y0 <= box.y0
                    and box.y1 <= frame.y1
                ):
                    cost += 500
                if best is None or cost < best[0]:
                    best = (cost, anchor, dx, dy, ha, va, box)
        _, anchor, dx, dy, ha, va, box = best
        ax.annotate(
            label.text,
            anchor,
            xytext=(dx, dy),
            textcoords="offset points",
            ha=ha,
            va=va,
            parse_math=False,
            **label.style,
        )
        placed.append(box)


@_kept
def pose_figure(
    data: PoseData,
    plain,
    unit: str = "m",
    mode: Sequence[tuple[tuple[float, float], tuple[float, float]]] = (),
) -> bytes:
    """PDF of the as-fabricated pose, axes in the file's length `unit`; `plain` makes a name safe
    for matplotlib text. `mode`: arrows (from, displacement) drawn on it, a natural mode's
    (symkin.report.modes)."""
    from matplotlib.patches import Polygon

    every = [p for _, _, att in data.links for p in att] + [p for _, _, p in data.points]
    xs = [p[0] for p in every] or [0.0]
    ys = [p[1] for p in every] or [0.0]
    span = max(max(xs) - min(xs), max(ys) - min(ys), 1e-12)
    cx = sum(xs) / len(xs)
    cy = sum(ys) / len(ys)
    width, height = pose_size(data)
    scale = plate_scale(data)
    segments: list = []
    markers: list = []
    labels: list[_Label] = []
    link_labels: list[_Label] = []
    ground_label: list[_Label] = []

    def away(x: float, y: float) -> tuple[float, float]:
        dx, dy = x - cx, y - cy
        norm = math.hypot(dx, dy)
        return (dx / norm, dy / norm) if norm > 1e-12 * span else (1.0, 1.0)

    with rc_context():
        fig = _figure(width, height)
        ax = fig.add_axes((0.6 / width, 0.42 / height, 1 - 0.75 / width, 1 - 0.55 / height))
        ax.grid(True, lw=0.3, color="0.9", zorder=0)
        ax.set_axisbelow(True)
        anchor = 0.03 * span
        for label, name, att in data.links:
            colour = LINK_COLOURS[(label - 1) % len(LINK_COLOURS)] if label else "0.3"
            text = f"{plain(name)} (s{sub(label)})"
            if label == data.ground:
                for x, y in att:
                    ax.add_patch(
                        Polygon(
                            [(x, y), (x - anchor / 2, y - anchor), (x + anchor / 2, y - anchor)],
                            closed=True,
                            facecolor="white",
                            edgecolor="0.25",
                            lw=0.7,
                            zorder=2,
                        )
                    )
                    ax.add_patch(
                        Polygon(
                            [
                                (x - anchor, y - anchor),
                                (x + anchor, y - anchor),
                                (x + anchor, y - 1.5 * anchor),
                                (x - anchor, y - 1.5 * anchor),
                            ],
                            closed=True,
                            facecolor="none",
                            edgecolor="0.35",
                            hatch="//////",
                            lw=0.0,
                            zorder=2,
                        )
                    )
                    ax.plot(
                        [x - anchor, x + anchor],
                        [y - anchor, y - anchor],
                        color="0.25",
                        lw=0.8,
                        zorder=2,
                    )
                    segments.append(((x - anchor, y - 1.5 * anchor), (x + anchor, y - anchor)))
                    segments.append(((x - anchor, y - anchor), (x + anchor, y - 1.5 * anchor)))
                if att:
                    ground_label.append(
                        _Label(
                            [
                                (x, y - 1.5 * anchor)
                                for x, y in sorted(att, key=lambda p: (p[1], p[0]))
                            ],
                            text,
                            {"fontsize": 7, "color": "0.25", "zorder": 6},
                            (0.0, -1.0),
                            distance=3.0,
                        )
                    )
                continue
            pts = list(att) + [p for _, lk, p in data.points if lk == label]
            hull = _hull(pts)
            style = {
                "fontsize": 7,
                "color": colour,
                "zorder": 6,
                "bbox": {"boxstyle": "round,pad=0.12", "fc": "white", "ec": "none", "alpha": 0.8},
            }
            if len(hull) >= 3:
                ax.add_patch(
                    Polygon(
                        hull, closed=True, facecolor=colour, alpha=0.15, edgecolor="none", zorder=2
                    )
                )
                ring = hull + [hull[0]]
                ax.plot(
                    [p[0] for p in ring],
                    [p[1] for p in ring],
                    color=colour,
                    lw=1.4,
                    solid_joinstyle="round",
                    zorder=3,
                )
                segments += list(itertools.pairwise(ring))
                lx = sum(p[0] for p in hull) / len(hull)
                ly = sum(p[1] for p in hull) / len(hull)
                link_labels.append(_Label([(lx, ly)], text, style, away(lx, ly), centred=True))
            elif len(hull) == 2:
                (x0, y0), (x1, y1) = hull
                ax.plot([x0, x1], [y0, y1], color=colour, lw=1.8, solid_capstyle="round", zorder=3)
                segments.append(((x0, y0), (x1, y1)))
                nx, ny = -(y1 - y0), x1 - x0
                norm = math.hypot(nx, ny) or 1.0
                mx, my = (x0 + x1) / 2, (y0 + y1) / 2
                side = 1.0 if (mx - cx) * nx + (my - cy) * ny >= 0 else -1.0
                anchors = [(x0 + f * (x1 - x0), y0 + f * (y1 - y0)) for f in (0.5, 0.35, 0.65)]
                link_labels.append(
                    _Label(anchors, text, style, (side * nx / norm, side * ny / norm))
                )
            elif hull:
                link_labels.append(_Label([hull[0]], text, style, away(*hull[0])))
        notches = dict(data.notches)
        along, across = notch_scale(data)
        for a, name, p, m, is_input in data.plates:
            hx, hy = (p[0] + m[0]) / 2, (p[1] + m[1]) / 2
            ux, uy = (m[0] - p[0]) / 2 * scale, (m[1] - p[1]) / 2 * scale
            if a in notches:  # the notch as cut: its material between the two flanks
                outline = notch_polygon((hx, hy), (ux, uy), notches[a], along, across)
                ax.add_patch(
                    Polygon(
                        outline, closed=True, facecolor="0.35", edgecolor="black", lw=0.5, zorder=5
                    )
                )
                half = len(outline) // 2  # each flank, coarsely, for the labels to avoid
                for flank in (outline[:half], outline[half:]):
                    segments += list(itertools.pairwise([*flank[::16], flank[-1]]))
            else:
                ax.plot(
                    [hx - ux, hx + ux],
                    [hy - uy, hy + uy],
                    color="black",
                    lw=3.0,
                    solid_capstyle="butt",
                    zorder=5,
                )
            markers.append((hx, hy))
            text = f"{plain(name)} (u{sub(a)}" + (", input)" if is_input else ")")
            labels.append(
                _Label([(hx, hy)], text, {"fontsize": 7, "zorder": 6}, away(hx, hy), distance=6.0)
            )
        for name, _link, (x, y) in data.points:
            ax.plot([x], [y], marker="o", ms=4.0, color="#c62828", zorder=7)
            markers.append((x, y))
            labels.append(
                _Label(
                    [(x, y)],
                    plain(name),
                    {"fontsize": 8, "color": "#c62828", "fontweight": "bold", "zorder": 7},
                    away(x, y),
                    distance=4.0,
                )
            )
        for (x, y), (dx, dy) in mode:
            ax.annotate(
                "",
                xy=(x + dx, y + dy),
                xytext=(x, y),
                arrowprops={
                    "arrowstyle": "-|>",
                    "color": "#1565c0",
                    "lw": 1.2,
                    "shrinkA": 0,
                    "shrinkB": 0,
                },
                zorder=8,
            )
            segments.append(((x, y), (x + dx, y + dy)))
        pad = 0.18 * span
        ax.set_xlim(min(xs) - 1.4 * pad, max(xs) + 1.4 * pad)
        ax.set_ylim(min(ys) - pad, max(ys) + pad)
        ax.set_aspect("equal", adjustable="box")
        ax.set_xlabel(f"x ({unit})")
        ax.set_ylabel(f"y ({unit})")
        ax.tick_params(direction="in")
        ax.apply_aspect()
        _place_labels(fig, ax, labels + link_labels + ground_label, segments, markers)
        return _render(fig)


# -- oriented graph ----------------------------------------------------------------------------


def tree_layout(parent: Sequence[int], n: int) -> dict[int, tuple[float, float]]:
    """Layered drawing of the skeleton tree: x = depth from s_0, leaves spread along y
    (children in label order), a parent centred on its children."""
    children: dict[int, list[int]] = {i: [] for i in range(n + 1)}
    for i in range(1, n + 1):
        children[parent[i - 1]].append(i)
    pos: dict[int, tuple[float, float]] = {}
    counter = [0.0]

    def place(i: int, depth: int) -> float:
        if not children[i]:
            y = counter[0]
            counter[0] += 1.0
        else:
            ys = [place(c, depth + 1) for c in sorted(children[i])]
            y = sum(ys) / len(ys)
        pos[i] = (float(depth), -y)
        return y

    place(0, 0)
    return pos


@_kept
def graph_figure(
    positions: dict[int, tuple[float, float]], arcs: Sequence[tuple[int, int, int, bool]]
) -> bytes:
    """PDF of the oriented graph: `arcs` are (a, i+, i-, is_chord)."""
    from matplotlib.patches import Circle, FancyArrowPatch

    labels = sorted(positions)
    xs = [positions[i][0] for i in labels]
    ys = [positions[i][1] for i in labels]
    w = max(xs) - min(xs) + 1.0
    h = max(ys) - min(ys) + 1.0
    unit = min(2.6 / w, 2.2 / h, 0.75)
    radius = 0.2
    with rc_context():
        fig = _figure(unit * w + 0.1, unit * h + 0.1)
        ax = fig.add_axes((0, 0, 1, 1))
        ax.set_axis_off()
        for i in labels:
            x, y = positions[i]
            ax.add_patch(
                Circle((x, y), radius, facecolor="white", edgecolor="black", lw=0.7, zorder=3)
            )
            ax.text(x, y, f"$s_{{{i}}}$", ha="center", va="center", fontsize=8, zorder=4)
        centre = (sum(xs) / len(xs), sum(ys) / len(ys))
        seen: dict[tuple[int, int], int] = {}
        for a, ip, im, chord in arcs:
            key = (min(ip, im), max(ip, im))
            k = seen.get(key, 0)
            seen[key] = k + 1
            p, q = positions[ip], positions[im]
            dx, dy = q[0] - p[0], q[1] - p[1]
            d = math.hypot(dx, dy) or 1.0
            ux, uy = dx / d, dy / d
            rad = 0.0 if (k == 0 and not chord) else 0.3 * (1 if k % 2 == 0 else -1) * (1 + k // 2)
            mid = ((p[0] + q[0]) / 2, (p[1] + q[1]) / 2)
            if rad and uy * (mid[0] - centre[0]) - ux * (mid[1] - centre[1]) < 0:
                rad = -rad  # curve away from the middle of the drawing
            arrow = FancyArrowPatch(
                (p[0] + radius * ux, p[1] + radius * uy),
                (q[0] - radius * ux, q[1] - radius * uy),
                arrowstyle="-|>,head_length=3.5,head_width=1.8",
                connectionstyle=f"arc3,rad={rad}",
                shrinkA=0,
                shrinkB=0,
                lw=0.8,
                linestyle="--" if chord else "-",
                color="black",
                zorder=2,
            )
            ax.add_patch(arrow)
            # label beside the arc's midpoint (arc3 bulges by rad * d / 2 to the right):
            # chords on the inner side of their curve, tree arcs away from the graph's centre
            bulge = rad * d / 2
            mx = (p[0] + q[0]) / 2 + bulge * uy
            my = (p[1] + q[1]) / 2 - bulge * ux
            nx, ny = uy, -ux
            if rad != 0:
                side = -1.0 if rad > 0 else 1.0
            else:
                side = 1.0 if nx * (mx - centre[0]) + ny * (my - centre[1]) >= 0 else -1.0
            off = 0.17 * side
            ax.text(
                mx + off * nx,
                my + off * ny,
                f"$u_{{{a}}}$",
                ha="center",
                va="center",
                fontsize=7,
                zorder=4,
                bbox={"boxstyle": "round,pad=0.05", "fc": "white", "ec": "none"},
            )
        ax.set_xlim(min(xs) - 0.5, max(xs) + 0.5)
        ax.set_ylim(min(ys) - 0.5, max(ys) + 0.5)
        ax.set_aspect("equal", adjustable="box")
        return _render(fig)


# -- deviation over an input range ---------------------------------------------------------


@dataclass(frozen=True)
class Sweep:
    """|ΔR| of the points over t (every input = t), per level; NaN where not assembled."""

    t: np.ndarray
    ok: np.ndarray
    magnitude: dict[str, dict[str, np.ndarray]]  # point -> level -> |ΔR|
    deviation: dict[str, dict[str, np.ndarray]]  # point -> level -> (2, N)
    #: the physical reference at a few samples: (their indices in t, point -> (2, K) deviation),
    #: NaN where it could not be solved; None without stiffness data
    reference: tuple[np.ndarray, dict[str, np.ndarray]] | None = None
    #: the physical reference's whole evaluation at those samples (plate stresses, input
    #: moments, model error; symkin.studies.results.Evaluation), None where not solved
    reported: tuple = ()


#: Colour and dash of each level's curve, by level code (fixed, so figures are deterministic).
LEVEL_STYLES = (
    ("#c62828", "--"),
    ("#1f5fa8", "-."),
    ("black", "-"),
    ("#2e7d32", ":"),
    ("#8e24aa", (0, (5, 1, 1, 1))),
    ("#ef6c00", (0, (3, 1))),
)


#: The physical reference's points: open circles in the colour of the level `equilibrium`.
REFERENCE_MARKER = {
    "marker": "o",
    "markersize": 3.5,
    "markerfacecolor": "none",
    "markeredgecolor": LEVEL_STYLES[4][0],
    "markeredgewidth": 0.8,
}


def _style(level) -> dict:
    color, dash = LEVEL_STYLES[level.code % len(LEVEL_STYLES)]
    return {"color": color, "ls": dash, "label": level.label}


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


def moves(sweep: Sweep, point: str, rel: float = 1e-9) -> bool:
    """Whether the point's deviation changes over the sweep at some level (beyond `rel` of its
    size: a point on a loop the swept input does not drive stays put up to rounding)."""
    for dev in sweep.deviation[point].values():
        dev = np.asarray(dev, dtype=float)
        if not np.isfinite(dev).any():
            continue
        size = np.nanmax(np.abs(dev))
        if np.nanmax(np.nanmax(dev, axis=-1) - np.nanmin(dev, axis=-1)) > rel * size:
            return True
    return False


def differs(sweep: Sweep, points: Sequence[str], levels: Sequence[Level]) -> bool:
    """Whether some level differs from the exact one for some point (then it is plotted)."""
    names = [lv.name for lv in levels]
    return (
        "exact" in names
        and len(names) > 1
        and any(
            np.nanmax(np.abs(sweep.deviation[p][lv] - sweep.deviation[p]["exact"]), initial=0.0) > 0
            for p in points
            for lv in names
        )
    )


@_kept
def deviation_figure(
    sweep: Sweep,
    points: Sequence[str],
    levels: Sequence[Level],
    plain,
    xlim: tuple[float, float],
    xlabel: str,
    length: str = "m",
) -> bytes:
    """PDF with one row per point: |ΔR| at every level, and |ΔR_level - ΔR_exact| when some
    level differs from the exact one; the physical reference's points (`equilibrium`) as
    markers on both, where the sweep has them."""
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    compare = differs(sweep, points, levels)
    rows = len(points)
    ncols = 2 if compare else 1
    # the legend: a row of up to four entries, else two rows
    entries = len(levels) + (sweep.reference is not None) + (not sweep.ok.all())
    legend_cols = entries if entries <= 4 else math.ceil(entries / 2)
    legend = 0.0 if entries <= 4 else 0.16
    height = 0.55 + legend + 1.75 * rows
    t = sweep.t
    step = float(t[1] - t[0]) if len(t) > 1 else 0.0
    with rc_context():
        fig = _figure(FIG_WIDTH, height)
        grid = fig.add_gridspec(
            rows,
            ncols,
            left=0.1,
            right=0.98,
            bottom=(0.5 + legend) / height + 0.06,
            top=1 - 0.28 / height,
            wspace=0.3,
            hspace=0.55,
        )
        handles = []
        for r, name in enumerate(points):
            axes = [fig.add_subplot(grid[r, c]) for c in range(ncols)]
            for ax in axes:
                for i, j in _runs(~sweep.ok):
                    ax.axvspan(
                        t[i] - step / 2,
                        t[j] + step / 2,
                        facecolor="0.85",
                        edgecolor="0.6",
                        hatch="xx",
                        lw=0.0,
                        zorder=0,
                    )
                ax.set_xlim(*xlim)
                ax.grid(True, lw=0.3, color="0.9")
                ax.tick_params(direction="in", which="both")
            peak = max(
                [
                    float(np.nanmax(sweep.magnitude[name][lv.name]))
                    for lv in levels
                    if np.isfinite(sweep.magnitude[name][lv.name]).any()
                ]
                + [0.0]
            )
            power = math.floor(math.log10(peak)) if peak > 0 else 0
            unit = 10.0**power
            for level in levels:
                st = _style(level)
                (line,) = axes[0].plot(
                    t,
                    sweep.magnitude[name][level.name] / unit,
                    color=st["color"],
                    ls=st["ls"],
                    label=st["label"],
                )
                if r == 0:
                    handles.append(line)
            if sweep.reference is not None:
                at, ref = sweep.reference[0], sweep.reference[1][name]
                ref_t = t[at]
                axes[0].plot(ref_t, np.hypot(*ref) / unit, ls="none", **REFERENCE_MARKER)
            axes[0].set_ylabel(
                r"$|\Delta R|$"
                + (f" ({length})" if power == 0 else rf" ($10^{{{power}}}$ {length})")
            )
            axes[0].set_ylim(bottom=0)
            axes[0].set_title(
                plain(name), loc="left", parse_math=False, fontsize=8, fontweight="bold"
            )
            if compare:
                exact = sweep.deviation[name]["exact"]
                for level in levels:
                    if level.name == "exact":
                        continue
                    diff = np.hypot(*(sweep.deviation[name][level.name] - exact))
                    diff = np.where(diff > 0, diff, np.nan)
                    st = _style(level)
                    axes[1].semilogy(t, diff, color=st["color"], ls=st["ls"])
                if sweep.reference is not None:
                    # the physics' own distance from the kinematic exact level, at its points
                    gap = np.hypot(*(ref - exact[:, at]))
                    axes[1].semilogy(
                        ref_t, np.where(gap > 0, gap, np.nan), ls="none", **REFERENCE_MARKER
                    )
                axes[1].set_ylabel(r"$|\Delta R - \Delta R_{\mathrm{exact}}|$" + f" ({length})")
                # nine decades below the largest difference: the dip at t = 0 goes to zero
                finite = [
                    float(np.nanmax(line.get_ydata()))
                    for line in axes[1].get_lines()
                    if np.isfinite(line.get_ydata()).any()
                ]
                if finite and max(finite) > 0:
                    top = 10.0 ** math.ceil(math.log10(max(finite)) + 0.3)
                    axes[1].set_ylim(top * 1e-9, top)
            if r == rows - 1:
                for ax in axes:
                    ax.set_xlabel(xlabel)
        if sweep.reference is not None:
            handles.append(Line2D([], [], ls="none", label="equilibrium", **REFERENCE_MARKER))
        if not sweep.ok.all():
            handles.append(
                Patch(facecolor="0.85", edgecolor="0.6", hatch="xx", label="cannot be assembled")
            )
        fig.legend(
            handles=handles,
            loc="lower center",
            ncol=legend_cols,
            frameon=False,
            bbox_to_anchor=(0.5, 0.0),
        )
        return _render(fig)


# -- stress over an input range ------------------------------------------------------------------

#: Marker of each plate's stress curve, cycled with LINK_COLOURS (a plate is told by both).
PLATE_MARKERS = ("o", "s", "^", "v", "D", "<", ">")


@_kept
def stress_figure(
    t: np.ndarray,
    stress: dict[str, np.ndarray],
    allowable: dict[str, float],
    plain,
    xlim: tuple[float, float],
    xlabel: str,
) -> bytes:
    """PDF of each plate's largest stress (MPa, NaN where not solved) against the input `t`, in
    file order, and every distinct allowable stress (MPa; plate -> value) as a horizontal line."""
    from matplotlib.lines import Line2D

    limits: dict[float, list[str]] = {}
    for name, value in allowable.items():
        limits.setdefault(float(value), []).append(name)
    entries = len(stress) + len(limits)
    legend_cols = min(entries, 6)
    legend_rows = math.ceil(entries / legend_cols) if entries else 0
    legend = 0.16 * legend_rows
    height = 2.1 + legend
    with rc_context():
        fig = _figure(FIG_WIDTH, height)
        ax = fig.add_axes(
            (0.11, (0.42 + legend) / height, 0.87, 1 - (0.42 + legend) / height - 0.12 / height)
        )
        ax.set_xlim(*xlim)
        ax.grid(True, lw=0.3, color="0.9")
        ax.tick_params(direction="in", which="both")
        handles = []
        for k, (name, values) in enumerate(stress.items()):
            (line,) = ax.plot(
                t,
                values,
                color=LINK_COLOURS[k % len(LINK_COLOURS)],
                marker=PLATE_MARKERS[(k // len(LINK_COLOURS)) % len(PLATE_MARKERS)],
                markersize=3.0,
                lw=0.9,
            )
            line.set_label(plain(name))
            handles.append(line)
        for k, (value, names) in enumerate(sorted(limits.items())):
            dash = ("--", "-.", ":")[k % 3]
            ax.axhline(value, color="#c62828", ls=dash, lw=0.9)
            label = (
                "allowable"
                if len(limits) == 1
                else "allowable: " + ", ".join(plain(n) for n in names)
            )
            handles.append(Line2D([], [], color="#c62828", ls=dash, lw=0.9, label=label))
        ax.set_ylim(bottom=0)
        ax.set_ylabel(r"$\sigma_{\max}$ (MPa)")
        ax.set_xlabel(xlabel)
        if handles:
            box = fig.legend(
                handles=handles,
                loc="lower center",
                ncol=legend_cols,
                frameon=False,
                bbox_to_anchor=(0.5, 0.0),
            )
            for text in box.get_texts():  # names from the file, drawn literally
                text.set_parse_math(False)
        return _render(fig)
