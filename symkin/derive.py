"""`symkin derive`: all artifacts of a mechanism, generated in memory, then written atomically.

Generation is deterministic: the same file gives byte-identical output (names sorted or in file
order, no timestamps, headers name the source file by its base name only).
"""

from __future__ import annotations

import importlib.util
import os
import shutil
import sys
import tempfile
from collections.abc import Callable, Sequence
from pathlib import Path

from .analysis import LEVELS, Analysis
from .errors import InputError
from .mechanism import Mechanism, load
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
    from .codegen import c_backend, numpy_backend
    from .codegen.build import plan

    say = progress or (lambda message: None)
    source = Path(mech.path).name
    say(f"deriving {mech.name}: structure and kinematics")
    if variant is not None:
        from .variants import analysis_for

        analysis = analysis_for(mech, variant, points)
        levels = [variant.level]
    else:
        analysis = Analysis(build(mech), points)
    analysis.check_fabricated_pose()
    say("deriving the routines (CSE)")
    p = plan(analysis, points, levels or LEVELS, notes=notes)
    files: dict[str, bytes] = {}
    if "numpy" in emit:
        say("emitting numpy")
        files[f"{mech.name}.py"] = numpy_backend.emit(p, source).encode()
    if "c" in emit:
        say("emitting C99")
        header, code = c_backend.emit(p, source)
        files[f"{mech.name}.h"] = header.encode()
        files[f"{mech.name}.c"] = code.encode()
    if "latex" in emit:
        say("emitting the LaTeX report")
        from .codegen import latex_backend

        files.update(latex_backend.emit(p, source, appendix=appendix))
    return files


def write_atomically(files: dict[str, bytes], out_dir: Path) -> list[Path]:
    """Write all files or none: into a temporary folder beside `out_dir`, then moved into place.

    A new `out_dir` is the temporary folder renamed; into an existing one each file is moved with
    an atomic rename, after every file has been written in full.
    """
    out_dir = Path(out_dir)
    parent = out_dir.resolve().parent
    parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{out_dir.name}.symkin-", dir=parent))
    umask = os.umask(0)
    os.umask(umask)
    os.chmod(tmp, 0o777 & ~umask)          # mkdtemp's 0700 would stick to a renamed folder
    try:
        for name, content in sorted(files.items()):
            (tmp / name).write_bytes(content)
        if not out_dir.exists():
            os.replace(tmp, out_dir)
        else:
            for name in sorted(files):
                os.replace(tmp / name, out_dir / name)
    finally:
        if tmp.exists():
            shutil.rmtree(tmp, ignore_errors=True)
    return [out_dir / name for name in sorted(files)]


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


def import_numpy_module(source: str, name: str):
    """Import a generated numpy module from its text (our own generated code, names escaped)."""
    from .codegen.c_runtime import cache_dir
    import hashlib

    digest = hashlib.sha256(source.encode()).hexdigest()[:20]
    folder = cache_dir() / "numpy"
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"{name}_{digest}.py"
    if not path.exists():
        tmp = path.with_suffix(f".{os.getpid()}.tmp")
        tmp.write_text(source)
        os.replace(tmp, path)
    module_name = f"symkin_generated_{name}_{digest}"
    if module_name in sys.modules:
        return sys.modules[module_name]
    spec = importlib.util.spec_from_file_location(module_name, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    sys.modules[module_name] = module
    return module
