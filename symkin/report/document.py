"""The LaTeX report: a report `<name>.tex` (standalone or appendix body) and its figure PDFs.

The report restates the paper's derivation for one mechanism: the labeled graph (i± table, arcs),
I, Φ, Ψ, the plate data c_ia, α±, l_a, J and J*, the link positions (4.7), the hinge models with
their cancellation-free Δf, Δg, the loop equations (5.1)/(5.3) with their scalar, squared and
solved forms, the closed-form rigid solution (dyads, branch signs), the deviation of every point
at the levels paper and first_order (and the exact closure it approximates) and a plot of |ΔR|
over an input range evaluated with the generated numpy module. It reads the plan only: every
expression comes from the plan's :class:`~symkin.codegen.derivation.Derivation`.

Every expression is printed by sympy's LatexPrinter (:class:`.text.Tex`) and long ones are
broken over lines; every name from the mechanism file passes :func:`escape_latex`. Output is
deterministic: sorted or file-ordered data only, no timestamps, figures with fixed metadata.
Packages used: amsmath, amssymb, graphicx, booktabs (and geometry in the standalone document),
all in TeX Live's latex-recommended set.

:func:`emit` lays the report out: :mod:`.sections` restates the derivation, :mod:`.sweeps`
evaluates the figures' and the sensitivity table's numbers, :mod:`.equilibrium` tabulates what
the `equilibrium` level reports, :mod:`.figures` draws; the templates are templates/latex/.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from functools import cache
from types import ModuleType

import jinja2

from ..codegen import templating
from ..codegen.plan import Plan
from .equilibrium import equilibrium_section
from .figures import (
    FIG_WIDTH,
    deviation_figure,
    differs,
    graph_figure,
    moves,
    plate_scale,
    pose_figure,
    pose_size,
    tree_layout,
)
from .modes import first_mode_arrows, frequency_table
from .profiles import caption as notch_caption
from .profiles import notch_scale, profile_rows
from .sections import COLUMN_WIDTH, PLAIN_UNITS, Report, chunks, input_axis
from .sweeps import Physics, pose_data, sensitivity_table, sweep, sweep_spans
from .text import LINE_WIDTH_EM, escape_latex, math_name, plain_name

__all__ = ["COLUMN_WIDTH", "emit", "environment"]


# -- Jinja environment with LaTeX-friendly delimiters (SymForce style) ----------------------------


@cache
def environment() -> jinja2.Environment:
    r"""The shared strict environment with the ``\VAR{...}``/``\BLOCK{...}`` delimiters, plus
    the LaTeX escaping filters."""
    env = templating.environment(latex=True).overlay()
    env.filters["tex"] = escape_latex
    env.filters["mathname"] = math_name
    return env


def emit(
    plan: Plan,
    source: str,
    appendix: bool = False,
    evaluator: ModuleType | None = None,
    column_width: float = COLUMN_WIDTH,
    spans: Mapping[str, tuple[float, float]] | None = None,
    physics: Physics | None = None,
) -> dict[str, bytes]:
    """`<name>.tex` (standalone, or the body alone with `appendix`) and its figure PDFs, laid out
    for a column of `column_width` points; the deviation plots are evaluated with `evaluator`,
    the plan's generated numpy module (needed when the plan has points), over `spans` (input ->
    (lo, hi) in rad; ±SWEEP_RANGE for inputs not given), with the physical reference's points
    from `physics` (the `equilibrium` level, when the file has stiffness data)."""
    if plan.actuators:
        # the report states and plots the file's points, not the actuators' points of action
        shown = set(plan.shown_points)
        derivation = plan.derivation
        if derivation is not None:
            derivation = dataclasses.replace(
                derivation, points=tuple(q for q in derivation.points if q.name in shown)
            )
        plan = dataclasses.replace(plan, points=plan.shown_points, derivation=derivation)
    report = Report(plan, source, column_width)
    name = report.mech.name
    ctx = report.context(appendix)
    files: dict[str, bytes] = {}
    pose = pose_data(report)
    unit = PLAIN_UNITS[report.mech.units]
    files[f"{name}-pose.pdf"] = pose_figure(pose, plain_name, unit)
    scale = plate_scale(pose)
    ctx["pose_width"] = f"{min(1.0, pose_size(pose)[0] / FIG_WIDTH):.2f}"
    plates = "the flexure plates as thick black segments" + (
        " to scale" if scale == 1 else f", drawn {scale:g} times their length"
    )
    if pose.notches:  # a notch is drawn as cut, not as a plate
        cut = notch_caption(*notch_scale(pose))
        whole = len(pose.notches) == len(pose.plates)
        plates = cut if whole else f"{plates}, {cut}"
    ctx["pose_caption"] = (
        plates + ", the fixed link $s_0$ as ground anchors; characteristic points in red."
    )
    arcs = [
        (a, report.s.i_plus[a - 1], report.s.i_minus[a - 1], a > report.s.n)
        for a in range(1, report.s.m + 1)
    ]
    layout = tree_layout(report.s.parent, report.s.n)
    files[f"{name}-graph.pdf"] = graph_figure(layout, arcs)
    depth = max(x for x, _ in layout.values())
    # a shallow tree beside the hinge table, a deep one (a long chain) above it
    ctx["graph_beside"] = depth <= 3 and report.width >= LINE_WIDTH_EM
    ctx["graph_width"] = (
        f"{0.16 + 0.1 * depth:.2f}" if depth <= 3 else f"{min(0.9, 0.13 * (depth + 1)):.2f}"
    )
    ctx["table_width"] = f"{min(0.58, 0.96 - float(ctx['graph_width'])):.2f}"
    ctx["profiles"] = profile_rows(report)
    ctx["deviation_figures"] = []
    ctx["sweep"] = None
    ctx["sensitivity"] = None
    ctx["equilibrium"] = None
    ctx["frequencies"] = None
    drives = plan.drives or plan.inputs
    if plan.points and drives:
        if evaluator is None:
            raise ValueError("the deviation plot needs the plan's generated numpy module")
        strokes = report.mech.stroke_spans()
        runs, summary = sweep(report, evaluator, sweep_spans(drives, spans, strokes), physics)
        single = len(runs) == 1
        points = list(plan.points)
        pruned = False
        for h, data, xlim in runs:
            xlabel = input_axis(report.mech, h, plain_name(h))
            shown = points
            if not single:  # (the caption says that the other inputs are held)
                # only the points this input moves (a fan of four-bars: one point per input)
                shown = [p for p in points if moves(data, p)] or points
                pruned = pruned or len(shown) < len(points)
            for chunk in chunks(shown, 3):
                k = len(ctx["deviation_figures"])
                fname = f"{name}-deviation.pdf" if k == 0 else f"{name}-deviation-{k + 1}.pdf"
                files[fname] = deviation_figure(
                    data, chunk, plan.levels, plain_name, xlim, xlabel, unit
                )
                ctx["deviation_figures"].append(
                    {
                        "file": fname,
                        "points": [escape_latex(p) for p in chunk],
                        "input": None if single else escape_latex(h),
                        "compare": differs(data, chunk, plan.levels),
                    }
                )
        summary["single_input"] = single
        summary["pruned"] = pruned
        ctx["sweep"] = summary
        ctx["equilibrium"] = equilibrium_section(report, runs, files) if physics else None
        ctx["sensitivity"] = sensitivity_table(report, evaluator, runs)
        ctx["frequencies"] = frequency_table(report, evaluator, runs)
        drawn = first_mode_arrows(report, evaluator, runs, pose)
        if drawn is not None:  # the first mode on the pose (links with mass)
            files[f"{name}-pose.pdf"] = pose_figure(pose, plain_name, unit, drawn[0])
            ctx["pose_caption"] += (
                f" Blue arrows: the first natural mode, $f_1 = {drawn[1]['frequency']}$~Hz at "
                f"{drawn[1]['inputs']} (level \\emph{{loaded}}, the inputs held), scaled."
            )
    body = environment().get_template("latex/body.tex.j2").render(**ctx)
    if appendix:
        text = body
    else:
        text = environment().get_template("latex/report.tex.j2").render(body=body, **ctx)
    files[f"{name}.tex"] = text.encode()
    return dict(sorted(files.items()))
