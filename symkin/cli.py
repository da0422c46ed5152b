"""Command line (CONTRACT §4): a thin shell over the Python API.

Exit codes: 0 success, 1 internal error (a bug), 2 bad input, 3 cannot reach the input.
"""

from __future__ import annotations

import argparse
import sys
import traceback
from collections.abc import Sequence

from . import __version__, load
from .errors import SymkinError
from .reports import check_text, matrices_json, matrices_text
from .structure import build


def _check(args: argparse.Namespace) -> str:
    return check_text(build(load(args.file)))


def _matrices(args: argparse.Namespace) -> str:
    structure = build(load(args.file))
    return matrices_json(structure) if args.json else matrices_text(structure)


def parser() -> argparse.ArgumentParser:
    """The argument parser; argparse itself exits with code 2 on a bad option."""
    top = argparse.ArgumentParser(
        prog="symkin",
        description="Closed-form accuracy of planar compliant mechanisms (Hasan & Lilov, 2008).")
    top.add_argument("--version", action="version", version=f"symkin {__version__}")
    top.add_argument("--debug", action="store_true", help="show a traceback on errors")
    sub = top.add_subparsers(dest="command", required=True, metavar="COMMAND")
    check = sub.add_parser("check", help="validate a mechanism file and summarize it")
    check.add_argument("file", metavar="FILE")
    check.set_defaults(run=_check)
    matrices = sub.add_parser("matrices", help="labeling and structure matrices I, Phi, Psi")
    matrices.add_argument("file", metavar="FILE")
    matrices.add_argument("--json", action="store_true", help="machine-readable output")
    matrices.set_defaults(run=_matrices)
    return top


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; returns the exit code."""
    args = parser().parse_args(argv)
    try:
        output = args.run(args)
    except SymkinError as exc:
        if args.debug:
            traceback.print_exc()
        print(f"symkin: {exc}", file=sys.stderr)
        return exc.exit_code
    except Exception as exc:  # noqa: BLE001 - anything else is a bug: say so, exit 1
        if args.debug:
            traceback.print_exc()
        print(f"symkin: internal error ({type(exc).__name__}: {exc}); this is a bug in symkin, "
              "rerun with --debug for a traceback and report it", file=sys.stderr)
        return 1
    sys.stdout.write(output)
    return 0


if __name__ == "__main__":
    sys.exit(main())
