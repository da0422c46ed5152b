"""Command line (docs/cli.md): a thin shell over the Python API.

Exit codes: 0 success, 1 internal error (a bug), 2 bad input, 3 cannot reach the input.
"""

from __future__ import annotations

import argparse
import re
import sys
import traceback
import warnings
from collections.abc import Sequence

from .. import __version__, load
from ..core import backends, levels
from ..core.errors import InputError, SymkinError
from ..core.files import output_dir, output_file
from ..fea.command import pairs as _pairs
from ..graph.structure import build
from .output import check_text, matrices_json, matrices_text

#: --level's help of tolerance and sweep (eval's names the levels that are not generated too).
_LEVEL_HELP = "default: loaded where every plate has E, thickness and width, else exact"
#: File types `tradeoff --plot` can write (matplotlib picks the format from the suffix).
PLOT_SUFFIXES = (".png", ".pdf", ".svg")


def _check(args: argparse.Namespace) -> str:
    from ..kinematics.analysis import Analysis
    from ..studies.configuration import check_fabricated_pose

    structure = build(load(args.file))
    # What evaluation would refuse: a dyad at a toggle position as fabricated (raised while
    # decomposing into dyads), inputs that leave the loops singular.
    analysis = Analysis(structure)
    check_fabricated_pose(analysis)
    return check_text(structure, analysis.dropped)


def _matrices(args: argparse.Namespace) -> str:
    structure = build(load(args.file))
    return matrices_json(structure) if args.json else matrices_text(structure)


def _eval(args: argparse.Namespace) -> str:
    from ..kinematics.analysis import Analysis
    from ..studies.evaluation import evaluate
    from .output import evaluation_json, evaluation_text

    analysis = Analysis(build(load(args.file)))
    choice = _level(args, analysis.mechanism, backends.get(args.backend).generated and args.backend)
    result = evaluate(
        analysis,
        _pairs(args.input, "--input", args.file),
        choice.name,
        _pairs(args.param, "--param", args.file),
        args.backend,
        sensitivity=args.sensitivity,
    )
    return evaluation_json(result) if args.json else choice.line + "\n" + evaluation_text(result)


def _level(args: argparse.Namespace, mech, generated: bool | str = False) -> levels.Choice:
    """The level of eval, tolerance and sweep (docs/levels.md, "The default level"): --level,
    or the file's default (for the `generated` evaluators: tolerance, sweep, eval's numpy and
    c backends; a backend's name, or True); args.level is set to it. A kinematic level asked
    for on a file whose plates all have stiffness data is run, with a one-line warning that it
    ignores their forces."""
    choice = levels.choose(mech, args.level, generated)
    args.level = choice.name
    ignored = levels.ignores_forces(mech, choice)
    if ignored:
        warnings.warn(ignored, levels.LevelWarning, stacklevel=2)
    return choice


def _derive(args: argparse.Namespace) -> str:
    from ..core.levels import GENERATED
    from ..studies.derive import EMITTERS, derive, parse_length, parse_list

    emit = parse_list(args.emit, EMITTERS, "--emit") or list(EMITTERS)
    levels = parse_list(args.levels, GENERATED, "--levels")
    points = parse_list(args.points, None, "--points")

    def progress(message: str) -> None:
        if not args.quiet:
            print(f"symkin: {message}", file=sys.stderr, flush=True)

    if args.tolerance is not None and not args.tolerance > 0:
        raise InputError(f"tolerance must be positive, got {args.tolerance}", entry="--tolerance")
    output_dir(args.output, "-o")
    column = parse_length(args.columnwidth) if args.columnwidth else None
    if args.scene is not None:
        from ..studies.scene import derive as derive_scene

        given = [
            option
            for option, value in (
                ("--points", points),
                ("--levels", levels),
                ("--tolerance", args.tolerance),
                ("--range", args.range),
                ("--fix", args.fix),
            )
            if value
        ]
        if given:
            raise InputError(
                f"{given[0]} and --scene together: the scene file states the points, "
                "their tolerances and ranges, and the fixed inputs",
                entry=given[0],
                hint=f"drop {given[0]}, or put it in the scene file (docs/scene.md)",
            )
        written = derive_scene(
            args.file, args.scene, args.output, emit, progress, column, args.appendix
        )
    else:
        written = derive(
            args.file,
            args.output,
            emit,
            points,
            levels,
            args.appendix,
            progress,
            args.tolerance,
            args.range,
            column,
            _pairs(args.fix, "--fix", args.file),
        )
    return "".join(f"{path}\n" for path in written)


def _tradeoff(args: argparse.Namespace) -> str:
    import json

    from ..studies import tradeoff

    mech = load(args.file)
    if args.samples < 3:
        raise InputError(f"--samples must be at least 3, got {args.samples}", entry="--samples")
    if args.plot:
        output_file(args.plot, "--plot", PLOT_SUFFIXES)
    spans = tradeoff.parse_ranges(args.range, mech.drives, mech.path, strokes=mech.stroke_spans())

    def progress(message: str) -> None:
        if not args.quiet:
            print(f"symkin: {message}", file=sys.stderr, flush=True)

    table = tradeoff.run(mech, spans, args.samples, progress=progress)
    if args.plot:
        try:
            tradeoff.plot(table, args.plot)
        except OSError as exc:
            raise InputError(
                f"cannot write '{args.plot}' ({exc.strerror or exc})",
                entry="--plot",
                hint="choose a path you can write to",
            ) from None
    return json.dumps(table.as_json(), indent=2) + "\n" if args.json else tradeoff.text(table)


def _evaluator(args: argparse.Namespace, mech, sensitivity: bool = True):
    """The compiled evaluator of `mech` at args.level (C unless --backend numpy); without its
    sensitivities where they are not read (a sweep)."""
    from ..studies.compiled import compile as build_evaluator

    level = levels.get(args.level)
    if not level.generated:
        raise InputError(
            f"level '{level.name}' has no generated evaluator",
            entry="--level",
            hint="choose one of " + ", ".join(levels.GENERATED),
        )
    if backends.get(args.backend).compiler:  # no compiler: exit 2 before any derivation
        from ..codegen.toolchain import compiler

        compiler()
    return build_evaluator(mech, args.backend, levels=[level.name], sensitivity=sensitivity)


def _tolerance(args: argparse.Namespace) -> str:
    import json

    from ..studies import tolerance, variation
    from ..studies.actuators import check_actuated_level

    mech = load(args.file)
    nominal = {p.name: float(p.value) for p in mech.parameters}
    vary = variation.parse_vary(args.vary, mech, nominal, kinds=("pm",))
    grid = variation.parse_grid(args.input, mech, limit=_max_evaluations(args))
    if (
        args.backend is None
        and args.level in (None, "loaded")
        and levels.first_notch(mech) is not None
    ):
        args.backend = "numpy"  # the generated loaded that takes notches (core.levels)
    choice = _level(args, mech, generated=args.backend or True)
    tolerance.check_level(args.level)  # before compiling anything
    if args.backend is None:
        # the C, unless force actuators drive and it has no sensitivities with them at the level:
        # then the first generated backend that has
        args.backend = "c"
        if any(a.drive == "force" for a in mech.actuators):
            able = backends.having(generated=True, force_sensitivities=args.level)
            if args.level not in backends.get(args.backend).force_sensitivities and able:
                args.backend = able[0]
    if mech.actuators:
        check_actuated_level(mech, args.level, args.backend, sensitivity=True)
    result = tolerance.run(_evaluator(args, mech), vary, grid, args.level)
    if args.json:
        return json.dumps(result.as_json(), indent=2) + "\n"
    return choice.line + "\n" + tolerance.text(result)


def _max_evaluations(args: argparse.Namespace) -> int:
    """--max-evaluations, checked: a positive number of evaluations (the default when none)."""
    from ..studies.variation import MAX_EVALUATIONS

    if args.max_evaluations is None:
        return MAX_EVALUATIONS
    if args.max_evaluations < 1:
        raise InputError(
            f"--max-evaluations must be positive, got {args.max_evaluations}",
            entry="--max-evaluations",
            hint="e.g. --max-evaluations 1000000000",
        )
    return args.max_evaluations


def _sweep(args: argparse.Namespace) -> str:
    import json

    from ..studies import sweep, variation

    mech = load(args.file)
    nominal = {p.name: float(p.value) for p in mech.parameters}
    vary = variation.parse_vary(args.vary, mech, nominal)
    grid = variation.parse_grid(
        args.input,
        mech,
        points=variation.DEFAULT_POINTS,
        limit=_max_evaluations(args),
        samples=max(1, args.samples),
    )
    if args.samples < 2:
        raise InputError(
            f"--samples must be at least 2, got {args.samples}",
            entry="--samples",
            hint="e.g. --samples 10000",
        )
    if args.seed < 0:
        raise InputError(f"--seed must be a non-negative integer, got {args.seed}", entry="--seed")
    if args.chunks is not None and args.chunks < 1:
        raise InputError(f"--chunks must be positive, got {args.chunks}", entry="--chunks")
    if args.plot:
        output_file(args.plot, "--plot", PLOT_SUFFIXES)
    scheduler = sweep.parse_scheduler(args.scheduler)
    choice = _level(args, mech, generated=args.backend)
    client = sweep.connect(scheduler) if scheduler.kind == "distributed" else None
    try:
        evaluator = _evaluator(args, mech, sensitivity=False)
        sweep.check_grid(evaluator, grid, args.level)
    except BaseException:
        if client is not None:
            client.close()
        raise
    progress = sys.stderr.isatty() and not args.json
    result = sweep.run(
        evaluator,
        mech,
        vary,
        grid,
        args.samples,
        args.seed,
        scheduler,
        args.level,
        args.chunks,
        progress,
        client,
    )
    if args.plot:
        try:
            sweep.plot(result, args.plot)
        except OSError as exc:
            raise InputError(
                f"cannot write '{args.plot}' ({exc.strerror or exc})",
                entry="--plot",
                hint="choose a path you can write to",
            ) from None
    if args.json:
        return json.dumps(result.as_json(), indent=2) + "\n"
    return choice.line + "\n" + sweep.text(result)


def _evaluations_option(command: argparse.ArgumentParser) -> None:
    """--max-evaluations: the ceiling on a command's evaluations (None: the studies' default,
    variation.MAX_EVALUATIONS, read when the command runs: the parser is built for every
    command, and importing the studies for it cost every start 16 ms)."""
    command.add_argument(
        "--max-evaluations",
        type=int,
        metavar="N",
        help="refuse more than N evaluations, grid x samples (default 1e8)",
    )


def parser() -> argparse.ArgumentParser:
    """The argument parser; argparse itself exits with code 2 on a bad option."""
    top = argparse.ArgumentParser(
        prog="symkin",
        description="Closed-form accuracy of planar compliant mechanisms (Hasan & Lilov, 2008).",
    )
    top.add_argument("--version", action="version", version=f"symkin {__version__}")
    top.add_argument("--debug", action="store_true", help="show a traceback on errors")
    # --debug after the command too; SUPPRESS keeps a top-level --debug from being reset.
    debug = argparse.ArgumentParser(add_help=False)
    debug.add_argument(
        "--debug", action="store_true", default=argparse.SUPPRESS, help="show a traceback on errors"
    )
    sub = top.add_subparsers(dest="command", required=True, metavar="COMMAND")

    def command(name: str, help: str) -> argparse.ArgumentParser:
        return sub.add_parser(name, help=help, parents=[debug])

    check = command("check", "validate a mechanism file and summarize it")
    check.add_argument("file", metavar="FILE")
    check.set_defaults(run=_check)
    matrices = command("matrices", "labeling and structure matrices I, Phi, Psi")
    matrices.add_argument("file", metavar="FILE")
    matrices.add_argument("--json", action="store_true", help="machine-readable output")
    matrices.set_defaults(run=_matrices)
    ev = command("eval", "deviation of the points in one configuration")
    ev.add_argument("file", metavar="FILE")
    ev.add_argument(
        "--input",
        action="append",
        metavar="H=V",
        help="input hinge angle in radians (an expression such as 10*deg is fine)",
    )
    ev.add_argument("--param", action="append", metavar="K=V", help="override a parameter")
    ev.add_argument(
        "--level",
        choices=levels.NAMES,
        help="deviation level (default: loaded where every plate has E, thickness and width, "
        "else exact: docs/levels.md)",
    )
    ev.add_argument(
        "--backend",
        choices=backends.NAMES,
        default=backends.DEFAULT,
        help="how to evaluate (default: sympy, the derivation in 40-digit mpmath; numpy: "
        "the generated module; c: the generated C, compiled and cached)",
    )
    ev.add_argument(
        "--sensitivity",
        action="store_true",
        help="also the derivatives by every parameter and input",
    )
    ev.add_argument("--json", action="store_true", help="machine-readable output")
    ev.set_defaults(run=_eval)
    de = command("derive", "write the LaTeX report and the C99 and numpy evaluators")
    de.add_argument("file", metavar="FILE")
    de.add_argument("-o", "--output", default=".", metavar="DIR", help="output folder (.)")
    de.add_argument("--emit", metavar="LIST", help="latex,c,numpy (all by default)")
    de.add_argument("--points", metavar="LIST", help="only these points (all by default)")
    de.add_argument("--levels", metavar="LIST", help="paper,first_order,exact (all by default)")
    de.add_argument(
        "--fix",
        action="append",
        metavar="H=V",
        help="hold input H at angle V (rad): not an argument of the evaluators, its "
        "value folded into them",
    )
    de.add_argument(
        "--appendix", action="store_true", help="LaTeX body only, to \\input into a paper"
    )
    de.add_argument(
        "--columnwidth",
        metavar="LENGTH",
        help="lay the report out for this column, e.g. 229.9pt for a two-column "
        "article (default 345pt)",
    )
    de.add_argument("--quiet", action="store_true", help="no progress messages")
    de.add_argument(
        "--tolerance",
        type=float,
        metavar="TOL",
        help="derive the cheapest variant whose worst relative error meets TOL",
    )
    de.add_argument(
        "--range",
        action="append",
        metavar="H=LO:HI",
        help="input range of --tolerance (default -0.2:0.2 rad) and of the report's "
        "deviation plots (default -0.3:0.3 rad)",
    )
    de.add_argument(
        "--scene",
        metavar="SCENE.toml",
        help="derive what a scene file asks for: per point a tolerance, ranges and a "
        "reference, each point by its cheapest variant (docs/scene.md)",
    )
    de.set_defaults(run=_derive)
    tr = command("tradeoff", "speed and accuracy of every variant over a range")
    tr.add_argument("file", metavar="FILE")
    tr.add_argument(
        "--range",
        action="append",
        metavar="H=LO:HI",
        help="input range (default -0.2:0.2 rad for every input)",
    )
    tr.add_argument("--samples", type=int, default=25, metavar="N", help="samples (25)")
    tr.add_argument("--json", action="store_true", help="machine-readable output")
    tr.add_argument(
        "--plot", metavar="FILE.png", help="error against time, log-log (.png, .pdf or .svg)"
    )
    tr.add_argument("--quiet", action="store_true", help="no progress messages")
    tr.set_defaults(run=_tradeoff)
    to = command("tolerance", "worst-case and RSS stack-up of parameter tolerances")
    to.add_argument("file", metavar="FILE")
    to.add_argument(
        "--vary",
        action="append",
        metavar="P=±A",
        help="a parameter's tolerance (±A, or ±A%% of its value)",
    )
    to.add_argument(
        "--input",
        action="append",
        metavar="H=LO:HI[:N]",
        help="input range (default -0.2:0.2, 25 values)",
    )
    to.add_argument("--level", choices=levels.GENERATED, help=_LEVEL_HELP)
    to.add_argument(
        "--backend",
        choices=backends.GENERATED,
        help="c (default), or numpy; at loaded with force actuators: numpy (default)",
    )
    to.add_argument("--json", action="store_true", help="machine-readable output")
    _evaluations_option(to)
    to.set_defaults(run=_tolerance)
    sw = command("sweep", "Monte Carlo over parameter spreads, on Dask")
    sw.add_argument("file", metavar="FILE")
    sw.add_argument(
        "--vary",
        action="append",
        metavar="P=DIST",
        help="normal(MU,SIGMA), uniform(LO,HI) or ±A around the value",
    )
    sw.add_argument(
        "--input", action="append", metavar="H=LO:HI:N", help="input grid (default -0.2:0.2:25)"
    )
    sw.add_argument("--samples", type=int, default=1000, metavar="S", help="samples (1000)")
    _evaluations_option(sw)
    sw.add_argument("--seed", type=int, default=0, metavar="K", help="random seed (0)")
    sw.add_argument("--level", choices=levels.GENERATED, help=_LEVEL_HELP)
    sw.add_argument("--backend", choices=backends.GENERATED, default="c")
    sw.add_argument(
        "--scheduler",
        metavar="SPEC",
        help="threads[:N] (default, this machine's cores), processes[:N], sync, "
        "or tcp://HOST:PORT of a running distributed scheduler",
    )
    sw.add_argument(
        "--chunks", type=int, metavar="K", help="Dask tasks (default about 4 per worker)"
    )
    sw.add_argument("--json", action="store_true", help="machine-readable output")
    sw.add_argument("--plot", metavar="FILE.png", help="histograms (.png, .pdf or .svg)")
    sw.set_defaults(run=_sweep)
    from ..fea.command import register as register_fea
    from .modes import register as register_modes

    register_fea(command)
    register_modes(command)
    return top


#: Characters a terminal could act on (C0 and C1 controls but newline and tab, DEL, the
#: bidirectional overrides and isolates): never printed raw, whatever a file or option names.
CONTROL = re.compile("[\x00-\x08\x0b-\x1f\x7f-\x9f\u202a-\u202e\u2066-\u2069]")


def escape(text: str) -> str:
    """`text` with every control character shown as an escape (\\x1b, \\u202e)."""
    return CONTROL.sub(
        lambda m: (
            f"\\x{ord(m.group()):02x}" if ord(m.group()) < 0x100 else f"\\u{ord(m.group()):04x}"
        ),
        text,
    )


class _Escaping:
    """A text stream that escapes control characters in everything written to it."""

    def __init__(self, stream) -> None:
        self._stream = stream

    def write(self, text: str) -> int:
        return self._stream.write(escape(text))

    def __getattr__(self, name: str):
        return getattr(self._stream, name)


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; returns the exit code. Nothing it prints holds a raw control
    character (names in a file or an option are escaped; JSON escapes them itself)."""
    out, err = sys.stdout, sys.stderr
    sys.stdout, sys.stderr = _Escaping(out), _Escaping(err)
    try:
        return _main(argv)
    finally:
        sys.stdout, sys.stderr = out, err


def _show_warning(message, category, filename, lineno, file=None, line=None) -> None:
    """A warning as one line of symkin's own, without the library path and source line Python
    prints (those name files inside the installed package; --debug shows them)."""
    print(f"symkin: warning: {message} ({category.__name__})", file=sys.stderr)


def _main(argv: Sequence[str] | None = None) -> int:
    args = parser().parse_args(argv)
    with warnings.catch_warnings():
        if not args.debug:
            warnings.showwarning = _show_warning
        return _run(args)


def _run(args: argparse.Namespace) -> int:
    try:
        output = args.run(args)
    except KeyboardInterrupt:
        print("symkin: interrupted", file=sys.stderr)
        return 130
    except SymkinError as exc:
        if args.debug:
            traceback.print_exc()
        print(f"symkin: {exc}", file=sys.stderr)
        return exc.exit_code
    except Exception as exc:
        if args.debug:
            traceback.print_exc()
        print(
            f"symkin: internal error ({type(exc).__name__}: {exc}); this is a bug in symkin, "
            "rerun with --debug for a traceback and report it",
            file=sys.stderr,
        )
        return 1
    sys.stdout.write(output)
    return 0


if __name__ == "__main__":
    sys.exit(main())
