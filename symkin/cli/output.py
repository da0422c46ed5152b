"""Plain-text and JSON reports (docs/cli.md): a mechanism's structure (`symkin check`,
`symkin matrices`, the paper's I, Φ, Ψ of section 2) and one evaluation (`symkin eval`)."""

from __future__ import annotations

import json
import math
from collections.abc import Sequence

import numpy as np
import sympy as sp

from ..codegen.templating import render
from ..graph.structure import Structure
from ..model.expressions import substitute
from ..model.mechanism import closure_rank, crossing_plates
from ..physics.equilibrium import BUCKLING_LIMIT


def grid(row_labels: Sequence[str], col_labels: Sequence[str], matrix: np.ndarray) -> list[str]:
    """Right-aligned text table with row and column labels."""
    cells = [[str(int(v)) for v in row] for row in matrix]
    width = max([len(c) for c in col_labels] + [len(c) for row in cells for c in row] + [1])
    lead = max([len(r) for r in row_labels] + [0])
    head = " " * lead + "".join(f" {c:>{width}}" for c in col_labels)
    body = [
        f"{r:<{lead}}" + "".join(f" {c:>{width}}" for c in row) for r, row in zip(row_labels, cells)
    ]
    return [head.rstrip()] + body


def check_text(s: Structure, dropped: Sequence[int] = ()) -> str:
    """Human summary printed by `symkin check`; `dropped`: the closure rows (3 per loop:
    angular, x, y) the solvers leave out as redundant and check at the solution."""
    mech = s.mechanism
    models = [mech.hinge(name).model for name in s.hinges]
    profiles = [
        f"profile {h.profile}, span {_short(h.length)}"
        for h in (mech.hinge(name) for name in s.hinges)
    ]
    loops = {c: s.loop_text(c) for c in range(s.n + 1, s.m + 1)}
    redundant = [
        f"the {('angular', 'x', 'y')[r % 3]} closure of the loop of u{s.n + 1 + r // 3} "
        "is redundant: checked at every solution, not solved"
        for r in dropped
    ]
    return render(
        "text/check.txt.j2",
        mech=mech,
        s=s,
        models=models,
        profiles=profiles,
        loop_text=loops,
        rank=closure_rank(mech),
        redundant=redundant,
        crossing=crossing_plates(mech),
        short=_short,
        value=lambda e: _value(e, mech.defaults),
    )


def _value(expr: object, values: dict) -> str:
    """An expression at the file's parameter values, to 6 digits (a link's mass, say)."""
    return f"{float(sp.N(substitute(sp.sympify(expr), values), 20)):.6g}"


def _short(expr: object) -> str:
    """An exact value as the file gives it, unless its exact form is long (a CAD export's
    digits normalised: 6000...1*sqrt(...)/...): then its value to 12 digits."""
    text = str(expr)
    if len(text) <= 24 or not getattr(expr, "is_number", False):
        return text
    return f"{float(expr):.12g}"  # type: ignore[arg-type]


def matrices_text(s: Structure) -> str:
    """Pretty-printed I, I+, Φ, Ψ and T with link and hinge names (`symkin matrices`)."""
    links = [f"s{i} {name}" for i, name in enumerate(s.links)]
    hinge_cols = [f"u{a + 1}" for a in range(s.m)]
    hinge_rows = [f"u{a + 1} {name}" for a, name in enumerate(s.hinges)]
    chord_rows = [f"u{c + 1} {s.hinges[c]}" for c in range(s.n, s.m)]
    link_cols = [f"s{i}" for i in range(1, s.n + 1)]
    labeling = [
        f"u{a + 1} {name}: i+ = s{s.i_plus[a]} {s.links[s.i_plus[a]]}, "
        f"i- = s{s.i_minus[a]} {s.links[s.i_minus[a]]}" + ("  (chord)" if a >= s.n else "")
        for a, name in enumerate(s.hinges)
    ]
    tables = [
        ("incidence I (rows: links, columns: hinges)", grid(links, hinge_cols, s.incidence)),
        ("I+ (reference links)", grid(links, hinge_cols, s.incidence_plus)),
        (
            "cyclomatic Phi (rows: chords' loops, columns: hinges)",
            grid(chord_rows, hinge_cols, s.loops) if s.m > s.n else ["(no loops: an open chain)"],
        ),
        (
            "direct paths Psi = [T; 0] (rows: hinges, columns: links)",
            grid(hinge_rows, link_cols, s.paths),
        ),
    ]
    return render("text/matrices.txt.j2", mech=s.mechanism, s=s, labeling=labeling, tables=tables)


def matrices_json(s: Structure) -> str:
    """The JSON of `symkin matrices --json` (docs/cli.md)."""
    data = {
        "links": list(s.links),
        "hinges": list(s.hinges),
        "i_plus": list(s.i_plus),
        "i_minus": list(s.i_minus),
        "incidence": s.incidence.tolist(),
        "loops": s.loops.tolist(),
        "paths": s.paths.tolist(),
    }
    return json.dumps(data, ensure_ascii=False) + "\n"


def evaluation_json(result) -> str:
    """The JSON of `symkin eval --json` (docs/cli.md)."""
    return json.dumps(result.as_json(), indent=2) + "\n"


def evaluation_text(result) -> str:
    """Human summary of `symkin eval`: angles, points, deviations and dyad toggle margins, and
    with --sensitivity each point's derivatives, ranked."""
    tables = sensitivity_tables(result) if result.sensitivity is not None else {}
    return render(
        "text/eval.txt.j2",
        r=result,
        sensitivity=tables,
        inf=math.inf,
        buckling_limit=BUCKLING_LIMIT,
    )


def norm_rate(deviation: Sequence[float], rate: Sequence[float]) -> float:
    """d|ΔR|/dv from ΔR and dΔR/dv; at ΔR = 0 (the as-fabricated pose) |dΔR/dv|, the rate at
    which |ΔR| grows from zero."""
    norm = math.hypot(*deviation)
    if norm == 0:
        return math.hypot(*rate)
    return (deviation[0] * rate[0] + deviation[1] * rate[1]) / norm


def sensitivity_tables(result) -> dict[str, list[dict]]:
    """Per point, one row per parameter and input: value, d(dx, dy)/dv, d|ΔR|/dv, the rigid
    position's d(x, y)/dv and the relative sensitivity (v/|ΔR|) d|ΔR|/dv; ranked by the size
    of the relative sensitivity (parameters of value 0 last)."""
    sens = result.sensitivity
    out = {}
    for name, point in result.points.items():
        rows = []
        for kind, table, rigid, values in (
            ("param", sens.deviation, sens.rigid, result.params),
            ("input", sens.deviation_inputs, sens.rigid_inputs, result.inputs),
        ):
            for var, rate in table[name].items():
                d_norm = norm_rate(point.deviation, rate)
                value = values[var]
                relative = value * d_norm / point.norm if point.norm else None
                rows.append(
                    {
                        "name": var,
                        "kind": kind,
                        "value": value,
                        "rate": rate,
                        "norm": d_norm,
                        "rigid": rigid[name][var],
                        "relative": relative,
                    }
                )
        rows.sort(
            key=lambda r: (
                r["relative"] is None or r["value"] == 0,
                -abs(r["relative"] or 0.0),
                -abs(r["norm"]),
            )
        )
        out[name] = rows
    return out
