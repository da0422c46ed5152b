"""`symkin fea FILE --input H=V ... [--param K=V ...] [-o DIR] [--mesh NL,NT] [--run] [--json]`
(docs/fea.md, docs/cli.md): write the CalculiX deck; with --run, run it and compare."""

from __future__ import annotations

import argparse
import json
import math
import sys
from collections.abc import Callable, Sequence

from . import Comparison, compare, prepare, save, write_deck
from ._symkin import InputError
from .ccx import executable
from .deck import DEFAULT_MESH, Mesh, parse_mesh
from .material import DEFAULT_LAW, NAMES, parse_law


def register(command: Callable[[str, str], argparse.ArgumentParser]) -> None:
    """Add the `fea` subcommand through the CLI's subcommand factory."""
    fe = command(
        "fea",
        "write a CalculiX model of the mechanism in one configuration; "
        "with --run, solve it and compare with equilibrium and loaded",
    )
    fe.add_argument("file", metavar="FILE")
    fe.add_argument(
        "--input",
        action="append",
        metavar="H=V",
        help="input hinge angle in radians (an expression such as 10*deg is fine)",
    )
    fe.add_argument("--param", action="append", metavar="K=V", help="override a parameter")
    fe.add_argument(
        "-o", "--output", default=".", metavar="DIR", help="folder of the deck DIR/<name>.inp (.)"
    )
    fe.add_argument(
        "--mesh",
        metavar="NL,NT[,G]",
        help=f"elements per plate along it and through its thickness, and their "
        f"grading towards the clamps and faces, 0 to 1 (default {DEFAULT_MESH}"
        f": the deviation converged to about 0.03 %%)",
    )
    fe.add_argument(
        "--law",
        metavar="LAW",
        help="the plates' finite-strain law: svk (St. Venant-Kirchhoff, *ELASTIC; the default) "
        "or neo-hookean (*HYPERELASTIC, NEO HOOKE with the same E and nu at small strain)",
    )
    fe.add_argument(
        "--run",
        action="store_true",
        dest="solve",
        help="run ccx (Debian package calculix-ccx) and compare the deviations",
    )
    fe.add_argument(
        "--modes",
        type=int,
        metavar="N",
        help="add a frequency step after the static one, the links' masses on their rigid "
        "bodies; with --run, the N lowest frequencies beside symkin modes'",
    )
    fe.add_argument(
        "--plate-density",
        type=float,
        default=0.0,
        metavar="RHO",
        help="with --modes: the plates' density in kg/m^3 (default 0: massless, as symkin's "
        "model; 7850 for steel shows what their own mass changes)",
    )
    fe.add_argument("--json", action="store_true", help="machine-readable output")
    fe.add_argument("--quiet", action="store_true", help="no progress messages")
    fe.set_defaults(run=main)


def pairs(items: Sequence[str] | None, option: str, file: str | None = None) -> dict[str, str]:
    """NAME=VALUE options as a dict; a malformed one or a name given twice is bad input (exit
    2, naming `file`, the mechanism they are for)."""
    out: dict[str, str] = {}
    for item in items or ():
        name, sep, value = item.partition("=")
        if not sep or not name.strip() or not value.strip():
            raise InputError(
                f"'{item}' is not NAME=VALUE",
                file=file,
                entry=option,
                hint=f"write e.g. {option} A0=0.2",
            )
        if name.strip() in out:
            raise InputError(
                f"'{name.strip()}' given twice ({option} {name.strip()}={out[name.strip()]} "
                f"and {item.strip()})",
                file=file,
                entry=option,
                hint=f"give each {option} once",
            )
        out[name.strip()] = value.strip()
    return out


#: The most elements (plates x NL x NT) one `--run` solves: ccx's time grows a little faster than
#: the element count (docs/fea.md, "Limits": the nine-bar platform's 10 plates took 114 s at the
#: default 40,4 and 781 s at 80,8 on two cores, partly beside the test suite), so a larger mesh
#: is refused before the run rather than left running for hours.
MAX_RUN_ELEMENTS = 6_400


def check_run_size(file: str, mesh: Mesh) -> None:
    """Refuse (exit 2, naming --mesh) a run whose mesh exceeds MAX_RUN_ELEMENTS in all, before
    any derivation: the file is read only to count its plates."""
    from ._symkin import load

    mech = load(file)
    plates = sum(1 for h in mech.hinges if h.is_plate)
    elements = plates * mesh.along * mesh.across
    if elements > MAX_RUN_ELEMENTS:
        raise InputError(
            f"{plates} plates x {mesh.along} x {mesh.across} = {elements} elements is more than "
            f"one ccx run solves in about 10 minutes ({MAX_RUN_ELEMENTS})",
            file=mech.path,
            entry="--mesh",
            hint=f"use fewer elements per plate (the default {DEFAULT_MESH} converges to about "
            "0.03 %), or write the deck without --run and run ccx yourself",
        )


def main(args: argparse.Namespace) -> str:
    """Run the subcommand; returns what goes to stdout."""
    mesh = parse_mesh(args.mesh) if args.mesh else DEFAULT_MESH
    law = parse_law(args.law, file=args.file) if args.law is not None else DEFAULT_LAW
    if law != DEFAULT_LAW and args.modes is not None:
        raise InputError(
            f"--law {law} with --modes: the frequency step is written for the default law only",
            file=args.file,
            entry="--law",
            hint="leave --law out with --modes (the frequencies are small-strain: the law does "
            "not change them to first order)",
        )
    if args.solve:
        executable()  # before any work: exit 2 naming the package
        check_run_size(args.file, mesh)
    setup = prepare(
        args.file, pairs(args.input, "--input", args.file), pairs(args.param, "--param", args.file)
    )
    if not setup.conf.plates:
        raise InputError(
            "the mechanism has no compliant plate (every hinge is rigid)",
            file=setup.mechanism.path,
            entry="[[hinge]]",
            hint="symkin fea models plates: give a hinge a plate model",
        )
    modal = None
    if args.modes is not None:
        from . import frequency

        modal = frequency.write(setup, mesh, args.modes, args.plate_density)
        deck = modal.deck
    elif args.plate_density:
        raise InputError(
            "--plate-density is the plates' density in a frequency step",
            file=setup.mechanism.path,
            entry="--plate-density",
            hint="add --modes N, or leave --plate-density out",
        )
    else:
        deck = write_deck(setup, mesh, law=law)
    name = setup.mechanism.name
    path = save(deck.text, args.output, name)
    for stale in (".frd", ".dat", ".log"):  # results of an earlier deck would not match it
        (path.parent / f"{name}{stale}").unlink(missing_ok=True)

    def progress(message: str) -> None:
        if not args.quiet:
            print(f"symkin: {message}", file=sys.stderr, flush=True)

    if not args.solve:
        if args.json:
            return (
                json.dumps(
                    {
                        "deck": str(path),
                        "mesh": [mesh.along, mesh.across],
                        "grading": mesh.grading,
                        "law": law,
                        "nodes": deck.nodes,
                        "elements": deck.elements,
                    },
                    indent=2,
                )
                + "\n"
            )
        return f"{path}\n"
    progress(f"wrote {path} ({deck.nodes} nodes, {deck.elements} elements); running ccx")
    if modal is None:
        result = compare(setup, deck, progress, keep=args.output)
        return json.dumps(result.as_json(), indent=2) + "\n" if args.json else text(result)
    from . import frequency

    result, modes = frequency.compare_modes(setup, modal, progress, keep=args.output)
    if args.json:
        return json.dumps({**result.as_json(), "modes": modes.as_json()}, indent=2) + "\n"
    return text(result) + frequency.text(modes)


def _percent(value: float | None) -> str:
    if value is None:
        return "-"
    return f"{100 * value:.3g} %"


def text(result: Comparison) -> str:
    """The comparison as a table: per point the FE deviation, then each level's and its
    relative difference |dR_level - dR_fea| / |dR_fea|."""
    setup = result.setup
    unit = setup.mechanism.units
    drives = {a.name: a.drive for a in setup.mechanism.actuators}
    what = {"stroke": unit, "force": "N"}
    inputs = ", ".join(
        f"{h} = {v:.6g} {what.get(drives.get(h, ''), 'rad')}" for h, v in setup.inputs.items()
    )
    inputs = inputs or "no input (a structure)"
    lines = [
        f"{setup.mechanism.name}: {inputs}; mesh {result.mesh.along} x "
        f"{result.mesh.across} per plate, grading {result.mesh.grading:g}, "
        f"{NAMES[result.deck.law]} "
        f"({result.deck.elements} elements); ccx {result.ccx_seconds:.1f} s "
        f"({result.ccx_cpu_seconds:.1f} s processor time)",
        f"deviation from the rigid linkage ({unit}); difference = |dR - dR_fea| / |dR_fea|",
        f"{'point':<10} {'source':<12} {'dx':>15} {'dy':>15} {'|dR|':>13} {'difference':>11}",
    ]
    for p, dev in result.fea.items():
        rows = [("fea", dev, None)] + [
            (level, result.levels[level][p], _percent(result.difference(p, level)))
            for level in result.levels
        ]
        for k, (source, d, diff) in enumerate(rows):
            lines.append(
                f"{p if k == 0 else '':<10} {source:<12} {d[0]:>15.7e} {d[1]:>15.7e} "
                f"{math.hypot(*d):>13.6e} {diff or '':>11}"
            )
    for name, s in result.strokes.items():
        at = result.level_strokes.get(name)
        lines.append(
            f"actuator {name}: stroke {s:.9g} {unit} (fea)"
            + (f", {at:.9g} {unit} (equilibrium)" if at is not None else "")
        )
    for level, message in result.failed.items():
        lines.append(f"{level}: not available ({message})")
    lines += [f"note: {n}" for n in result.notes]
    return "\n".join(line.rstrip() for line in lines) + "\n"
