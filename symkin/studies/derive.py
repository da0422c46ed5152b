"""`symkin derive` (docs/cli.md, docs/generated-code.md): all artifacts of a mechanism, generated
in memory, then written atomically.

Generation is deterministic: the same file gives byte-identical output (names sorted or in file
order, no timestamps, headers name the source file by its base name only).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import sympy as sp

from ..codegen import pipeline, plan_cache
from ..core.errors import InputError
from ..core.files import write_atomically
from ..graph.pruning import for_levels
from ..graph.structure import build
from ..kinematics.analysis import Analysis
from ..model.mechanism import Mechanism
from ..model.reader import load

if TYPE_CHECKING:
    from .results import Evaluation

#: What `derive --emit` writes: the LaTeX report and every generated-code backend's files.
EMITTERS = ("latex", *pipeline.BACKENDS)


def parse_list(text: str | None, allowed: Sequence[str] | None, option: str) -> list[str] | None:
    """A comma-separated option value; None when not given."""
    if text is None:
        return None
    items = [t.strip() for t in text.split(",") if t.strip()]
    if not items:
        raise InputError(
            "empty list", entry=option, hint=f"e.g. {option} " + ",".join(allowed or ["A"])
        )
    for item in items:
        if allowed is not None and item not in allowed:
            raise InputError(
                f"unknown value '{item}'", entry=option, hint="choose from " + ", ".join(allowed)
            )
    return items


#: TeX's length units in points (pt), for --columnwidth.
TEX_UNITS = {"pt": 1.0, "bp": 72.27 / 72, "in": 72.27, "cm": 72.27 / 2.54, "mm": 72.27 / 25.4}


def parse_length(text: str, option: str = "--columnwidth") -> float:
    """A TeX length such as '240pt', '8.4cm' or '3.3in', in points; bad input exits 2."""
    value, unit = text.strip()[:-2], text.strip()[-2:]
    try:
        points = float(value) * TEX_UNITS[unit]
    except (KeyError, ValueError):
        raise InputError(
            f"'{text}' is not a length",
            entry=option,
            hint="give a number with a unit pt, bp, mm, cm or in, e.g. 240pt "
            "(your document's \\the\\columnwidth)",
        ) from None
    if not 100 <= points <= 1000:
        raise InputError(
            f"{text} is not a plausible column width",
            entry=option,
            hint="give the column width of your document, between 100pt and "
            "1000pt (e.g. 229.9pt for a two-column article)",
        )
    return points


def generate(
    mech: Mechanism,
    emit: Sequence[str] = EMITTERS,
    points: Sequence[str] | None = None,
    levels: Sequence[str] | None = None,
    appendix: bool = False,
    progress: Callable[[str], None] | None = None,
    variant=None,
    notes: Sequence[str] = (),
    column_width: float | None = None,
    spans: Mapping[str, tuple[float, float]] | None = None,
    fixed: Mapping[str, object] | None = None,
    *,
    sensitivity: bool = True,
) -> dict[str, bytes]:
    """File name -> content of every requested artifact (nothing is written). A `variant`
    (symkin.kinematics.variants.Variant) derives that cheaper variant instead of the file's models
    (a float32 one: its numpy module in float32, no C); `column_width` (points) lays the LaTeX
    report out for that column and `spans` (input -> (lo, hi) rad) sets its deviation plots' ranges;
    `fixed` (input -> angle, numbers or expressions) holds inputs constant, folded into the
    evaluators; `sensitivity` False leaves the evaluators' sensitivity functions out
    (docs/sensitivity.md: most of a stiff file's derivation)."""
    return generate_plan(
        mech,
        emit,
        points,
        levels,
        appendix,
        progress,
        variant,
        notes,
        column_width,
        spans,
        fixed,
        sensitivity=sensitivity,
    )[0]


def generate_plan(
    mech: Mechanism,
    emit: Sequence[str] = EMITTERS,
    points: Sequence[str] | None = None,
    levels: Sequence[str] | None = None,
    appendix: bool = False,
    progress: Callable[[str], None] | None = None,
    variant=None,
    notes: Sequence[str] = (),
    column_width: float | None = None,
    spans: Mapping[str, tuple[float, float]] | None = None,
    fixed: Mapping[str, object] | None = None,
    *,
    sensitivity: bool = True,
) -> tuple[dict[str, bytes], object]:
    """:func:`generate`, and the Plan the evaluators were emitted from."""
    from ..codegen.plan import with_derivation
    from .configuration import check_fabricated_pose, fixed_angles

    say = progress or (lambda message: None)
    source = Path(mech.path).name
    precision = variant.precision if variant is not None else "float64"
    held = fixed_angles(mech, fixed)
    pruning = None
    if points is not None:
        mech, pruning = for_levels(mech, points, [variant.level] if variant is not None else levels)
        notes = [*notes, *pruning.notes()]
        held = {k: v for k, v in held.items() if k in mech.inputs}  # a pruned one moves nothing
    if spans:
        # the report sweeps the evaluator's own inputs; a --range over another cannot be
        # plotted (with --tolerance, the ranges were the measurement's and are dropped)
        swept = [k for k in mech.drives if k not in held]
        other = [k for k in spans if k not in swept]
        if other and variant is None:
            k = other[0]
            if k in held:
                raise InputError(
                    f"the input {k} is fixed (--fix) and cannot be swept",
                    file=mech.path,
                    entry="--range",
                    hint=f"drop --range {k}=... or --fix {k}=...",
                )
            asked = ", ".join(pruning.points) if pruning is not None else "asked for"
            raise InputError(
                f"the input {k} moves none of the points {asked}",
                file=mech.path,
                entry="--range",
                hint=f"drop --range {k}=..., or ask for a point it moves (docs/pruning.md)",
            )
        spans = {k: v for k, v in spans.items() if k in swept}
    say(f"deriving {mech.name}: structure and kinematics")
    if variant is not None:
        from ..kinematics.variants import analysis_for

        analysis = analysis_for(mech, variant, points)
        levels = [variant.level]
    else:
        analysis = Analysis(build(mech), points)
    check_fabricated_pose(analysis)
    say("deriving the routines (CSE)")
    p = pipeline.plan_for(
        analysis,
        points=points,
        levels=levels,
        notes=notes,
        fixed=held,
        pruned_inputs=pruning.dropped_inputs if pruning is not None else (),
        sensitivity=sensitivity,
    )
    files: dict[str, bytes] = {}
    for name, row in pipeline.REGISTRY.items():
        if name not in emit:
            continue
        if precision not in row.precisions:
            raise InputError(
                f"the variant {variant.name} runs in {precision}; {row.language} evaluates in "
                + " and ".join(row.precisions),
                file=mech.path,
                entry="--emit",
                hint=f"leave {name} out of --emit",
            )
        say(f"emitting {row.language}")
        for file, text in pipeline.files(p, name, source, precision).items():
            files[file] = text.encode()
    if "latex" in emit:
        say("emitting the LaTeX report")
        from ..report import document as report

        # the report's deviation plot runs the generated numpy module
        evaluator = pipeline.evaluator(p, "numpy", source, precision) if p.points else None
        files.update(
            report.emit(
                with_derivation(p, analysis),
                source,
                appendix,
                evaluator,
                column_width or report.COLUMN_WIDTH,
                spans,
                physics_reference(analysis, held) if p.loaded is not None else None,
            )
        )
    return files, p


def physics_reference(
    analysis: Analysis, fixed: Mapping[str, object] | None = None
) -> Callable[[Mapping[str, float]], Evaluation]:
    """The report's physical reference: the `equilibrium` level's evaluation (deviations, plate
    stresses, input moments, model error) at given inputs and the `fixed` ones (the file's own
    plates and loads, whatever variant the report derives)."""
    from .configuration import configure
    from .physical import equilibrium
    from .results import Evaluation

    hidden = {a.point for a in analysis.mechanism.actuators}  # tracked by the levels themselves
    reference = Analysis(
        analysis.structure, [p.name for p in analysis.points if p.name not in hidden]
    )

    def evaluated(inputs: Mapping[str, float]) -> Evaluation:
        given = {k: repr(v) for k, v in inputs.items()}
        given.update({k: sp.sstr(v) for k, v in (fixed or {}).items()})
        # a report of the same file derives the same solves: kept by content (docs/cli.md)
        return plan_cache.kept(
            reference,
            {"level": "equilibrium", "inputs": given},
            lambda: equilibrium(reference, configure(reference, given, "equilibrium")),
            Evaluation,
        )

    return evaluated


def derive(
    path: str | Path,
    out_dir: str | Path = ".",
    emit: Sequence[str] = EMITTERS,
    points: Sequence[str] | None = None,
    levels: Sequence[str] | None = None,
    appendix: bool = False,
    progress: Callable[[str], None] | None = None,
    tolerance: float | None = None,
    ranges: Sequence[str] | None = None,
    column_width: float | None = None,
    fixed: Mapping[str, object] | None = None,
) -> list[Path]:
    """Load, generate and write; returns the written paths. With a `tolerance`, the cheapest
    variant whose measured worst error over `ranges` meets it is derived instead; `fixed`
    inputs are held at their angles (a scene file: symkin.studies.scene.derive)."""
    mech = load(path)
    if fixed and tolerance is not None:
        raise InputError(
            "--fix and --tolerance together are not supported yet",
            entry="--fix",
            hint="derive with --tolerance alone, or --fix alone",
        )
    variant, notes, spans = None, [], None
    if tolerance is not None:
        from . import tradeoff

        say = progress or (lambda message: None)
        spans = tradeoff.parse_ranges(ranges, mech.drives, mech.path, strokes=mech.stroke_spans())
        say(f"measuring the variants for tolerance {tolerance:g}")
        table = tradeoff.run(mech, spans, with_c="c" in emit, progress=say)
        row = tradeoff.choose(table, tolerance, points)
        variant = row.variant
        span = ", ".join(f"{k} in [{a:g}, {b:g}]" for k, (a, b) in spans.items())
        notes = [
            f"Tolerance {tolerance:g} over {span}: variant {variant.name} chosen, the "
            "cheapest whose measured worst relative error meets it;"
        ]
        notes += [
            f"  point {p}: worst relative error {e:.3g} (against {table.reference_short})"
            for p, e in row.errors.items()
            if points is None or p in points
        ]
        say(notes[0])
    elif ranges:
        from . import tradeoff

        if "latex" not in emit:
            raise InputError(
                "--range sets the ranges of --tolerance and of the report's "
                "deviation plots; neither is asked for",
                entry="--range",
                hint="add --tolerance TOL or --emit latex, or drop --range",
            )
        spans = tradeoff.parse_ranges(ranges, mech.drives, mech.path, default=None)
    files = generate(
        mech, emit, points, levels, appendix, progress, variant, notes, column_width, spans, fixed
    )
    return write_files(files, out_dir)


def write_files(files: dict[str, bytes], out_dir: str | Path) -> list[Path]:
    """Write every file at once (none when one cannot be written); the paths written."""
    try:
        return write_atomically(files, Path(out_dir))
    except OSError as exc:
        raise InputError(
            f"cannot write into '{out_dir}' ({exc.strerror or exc})",
            entry="-o",
            hint="choose a folder you can write to",
        ) from None
