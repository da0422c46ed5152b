"""`symkin modes` (docs/cli.md): the natural frequencies and mode shapes of a mechanism whose
links carry mass, about a physical level's equilibrium (symkin.studies.modes), as text or
JSON."""

from __future__ import annotations

import argparse
import json
from collections.abc import Callable

from .. import load
from ..fea.command import pairs

#: The modes printed unless --count says otherwise.
DEFAULT_COUNT = 3


def register(command: Callable[[str, str], argparse.ArgumentParser]) -> None:
    """Add the `modes` command to the parser (`command(name, help)` makes a subparser)."""
    mo = command("modes", "natural frequencies and mode shapes, the inputs held")
    mo.add_argument("file", metavar="FILE")
    mo.add_argument(
        "--input",
        action="append",
        metavar="H=V",
        help="every input, as eval takes them (held: an angle, a stroke, a force)",
    )
    mo.add_argument("--param", action="append", metavar="K=V", help="override a parameter")
    mo.add_argument(
        "--level",
        choices=("loaded", "equilibrium"),
        default="loaded",
        help="whose equilibrium and tangent stiffness (default: loaded)",
    )
    mo.add_argument(
        "--count",
        type=int,
        default=DEFAULT_COUNT,
        metavar="N",
        help=f"the N lowest modes (default {DEFAULT_COUNT})",
    )
    mo.add_argument(
        "--backend",
        choices=("sympy", "numpy"),
        default="sympy",
        help="sympy: the derivation (default); numpy: the generated module's modes() (loaded)",
    )
    mo.add_argument("--json", action="store_true", help="machine-readable output")
    mo.set_defaults(run=run)


def run(args: argparse.Namespace) -> str:
    from ..studies.modes import modes

    result = modes(
        load(args.file),
        pairs(args.input, "--input", args.file),
        args.level,
        pairs(args.param, "--param", args.file),
        args.count,
        args.backend,
    )
    if args.json:
        return json.dumps(result.as_json(), indent=2) + "\n"
    return text(result)


def text(result) -> str:
    """The modes as `symkin modes` prints them."""
    unit = result.units
    given = ", ".join(f"{n} = {v:.10g}" for n, v in result.inputs.items()) or "none"
    lines = [
        f"level {result.level}; inputs held: {given}",
        "natural frequencies of small oscillations about the equilibrium (massless plates; "
        "each mode's largest centre translation 1 " + unit + ", or its largest rotation 1 rad)",
    ]
    for k, (f, links, points) in enumerate(zip(result.frequencies, result.links, result.points), 1):
        lines.append("")
        lines.append(f"mode {k}: {f:.9g} Hz")
        lines.append(
            f"  {'':14} {'dx (' + unit + ')':>16} {'dy (' + unit + ')':>16} {'dphi (rad)':>16}"
        )
        for name, (dx, dy, dphi) in links.items():
            lines.append(f"  link {name:<9} {dx:16.9e} {dy:16.9e} {dphi:16.9e}")
        for name, (dx, dy) in points.items():
            lines.append(f"  point {name:<8} {dx:16.9e} {dy:16.9e}")
    if not result.frequencies:
        lines.append("")
        lines.append("no finite frequency: the inputs hold every massive link rigidly")
    return "\n".join(lines) + "\n"
