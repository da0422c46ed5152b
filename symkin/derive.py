"""`symkin derive` (docs/cli.md, docs/generated-code.md): all artifacts of a mechanism, generated
in memory, then written atomically.

Generation is deterministic: the same file gives byte-identical output (names sorted or in file
order, no timestamps, headers name the source file by its base name only).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path

from .analysis import Analysis
from .errors import InputError
from .mechanism import Mechanism, load
from .paths import write_atomically
from .structure import build

EMITTERS = ("latex", "c", "numpy")


def parse_list(text: str | None, allowed: Sequence[str] | None, option: str) -> list[str] | None:
    """A comma-separated option value; None when not given."""
    if text is None:
        return None
    items = [t.strip() for t in text.split(",") if t.strip()]
    if not items:
        raise InputError("empty list", entry=option, hint=f"e.g. {option} " + ",".join(
            allowed or ["A"]))
    for item in items:
        if allowed is not None and item not in allowed:
            raise InputError(f"unknown value '{item}'", entry=option,
                             hint="choose from " + ", ".join(allowed))
    return items


def generate(mech: Mechanism, emit: Sequence[str] = EMITTERS, points: Sequence[str] | None = None,
             levels: Sequence[str] | None = None, appendix: bool = False,
             progress: Callable[[str], None] | None = None, variant=None,
             notes: Sequence[str] = ()) -> dict[str, bytes]:
    """File name -> content of every requested artifact (nothing is written). A `variant`
    (symkin.variants.Variant) derives that cheaper variant instead of the file's models."""
    from .codegen import runtime
    from .codegen.backends.c import backend as c_backend
    from .codegen.backends.numpy import backend as numpy_backend
    from .codegen.plan import plan, with_derivation
    from .evaluation import check_fabricated_pose

    say = progress or (lambda message: None)
    source = Path(mech.path).name
    say(f"deriving {mech.name}: structure and kinematics")
    if variant is not None:
        from .variants import analysis_for

        analysis = analysis_for(mech, variant, points)
        levels = [variant.level]
    else:
        analysis = Analysis(build(mech), points)
    check_fabricated_pose(analysis)
    say("deriving the routines (CSE)")
    p = plan(analysis, points, levels, notes=notes)
    files: dict[str, bytes] = {}
    numpy_text = None
    if "numpy" in emit:
        say("emitting numpy")
        numpy_text = numpy_backend.emit(p, source)
        files[f"{mech.name}.py"] = numpy_text.encode()
    if "c" in emit:
        say("emitting C99")
        header, code = c_backend.emit(p, source)
        files[f"{mech.name}.h"] = header.encode()
        files[f"{mech.name}.c"] = code.encode()
    if "latex" in emit:
        say("emitting the LaTeX report")
        from .codegen.backends.latex import report

        # the report's deviation plot runs the generated numpy module
        evaluator = None
        if p.points:
            numpy_text = numpy_text or numpy_backend.emit(p, source)
            evaluator = runtime.import_numpy_module(numpy_text, mech.name)
        files.update(report.emit(with_derivation(p, analysis), source, appendix, evaluator))
    return files


def derive(path: str | Path, out_dir: str | Path = ".", emit: Sequence[str] = EMITTERS,
           points: Sequence[str] | None = None, levels: Sequence[str] | None = None,
           appendix: bool = False, progress: Callable[[str], None] | None = None,
           tolerance: float | None = None, ranges: Sequence[str] | None = None) -> list[Path]:
    """Load, generate and write; returns the written paths. With a `tolerance`, the cheapest
    variant whose measured worst error over `ranges` meets it is derived instead."""
    mech = load(path)
    variant, notes = None, []
    if tolerance is not None:
        from . import tradeoff

        say = progress or (lambda message: None)
        spans = tradeoff.parse_ranges(ranges, mech.inputs, mech.path)
        say(f"measuring the variants for tolerance {tolerance:g}")
        table = tradeoff.run(mech, spans, with_c="c" in emit, progress=say)
        row = tradeoff.choose(table, tolerance, points)
        variant = row.variant
        span = ", ".join(f"{k} in [{a:g}, {b:g}]" for k, (a, b) in spans.items())
        notes = [f"Tolerance {tolerance:g} over {span}: variant {variant.name} chosen, the "
                 "cheapest whose measured worst relative error meets it;"]
        notes += [f"  point {p}: worst relative error {e:.3g} (against mpmath, 30 digits)"
                  for p, e in row.errors.items() if points is None or p in points]
        say(notes[0])
    elif ranges:
        raise InputError("--range needs --tolerance", entry="--range",
                         hint="add --tolerance, e.g. --tolerance 1e-6")
    files = generate(mech, emit, points, levels, appendix, progress, variant, notes)
    try:
        return write_atomically(files, Path(out_dir))
    except OSError as exc:
        raise InputError(f"cannot write into '{out_dir}' ({exc.strerror or exc})", entry="-o",
                         hint="choose a folder you can write to") from None

