"""The report's section on what the `equilibrium` level reports (docs/physics.md): a table per
tabulated configuration (the plates' stresses, strains and safety factors, the inputs' moments
and stiffnesses, the buckling factor, the points' deviations beside their model errors) and a
stress figure per swept input.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import numpy as np

from ..physics import model_error
from ..physics.equilibrium import BUCKLING_LIMIT
from .figures import Sweep, stress_figure
from .sections import Report, float_at, input_axis, input_unit
from .text import escape_latex, plain_name, sci

#: Pa per MPa: the report gives stresses in MPa.
MPA = 1e6


def _input_text(values: Mapping[str, float], mech=None) -> str:
    """Inputs as LaTeX text with their unit, `A0 = 0.3 rad`, rounded to 1e-9 (a swept range's
    middle is its linspace sample, zero up to rounding); input hinges alone: one `rad` at the
    end, actuators beside them: each its own (a stroke in the file's unit, a force in N)."""
    text = [f"{escape_latex(n)}~$= {round(v, 9) + 0.0:g}$" for n, v in values.items()]
    if mech is None or not any(input_unit(mech, n) != "rad" for n in values):
        return ", ".join(text) + "~rad"
    return ", ".join(f"{t}~{input_unit(mech, n, tex=True)}" for t, n in zip(text, values))


def equilibrium_configurations(
    runs: Sequence[tuple[str, Sweep, tuple[float, float]]],
) -> list:
    """The physical reference's evaluations the report tabulates: the ends and the middle of
    every swept range (of those it solved), each configuration once, in sweep order."""
    out, seen = [], set()
    for _, data, _ in runs:
        if not data.reported:
            continue
        last = len(data.reported) - 1
        for k in (0, last // 2, last):
            ev = data.reported[k]
            if ev is None:
                continue
            key = tuple((n, round(v, 9) + 0.0) for n, v in ev.inputs.items())
            if key not in seen:
                seen.add(key)
                out.append(ev)
    return out


#: A reported value at most this fraction of the largest of its kind over the tabulated
#: configurations is zero up to rounding (the as-fabricated pose: stresses of 1e-23 MPa).
ROUNDING = 1e-12


def _scales(configurations: Sequence) -> dict[tuple[str, str], float]:
    """The largest plate stress, input moment and |ΔR| of each plate, input and point over the
    tabulated configurations: what "zero up to rounding" is measured against."""
    scales: dict[tuple[str, str], float] = {}

    def seen(key: tuple[str, str], value: float) -> None:
        scales[key] = max(scales.get(key, 0.0), abs(value))

    for ev in configurations:
        for name, p in ev.plates.items():
            seen(("plate", name), p.stress)
        for name, a in ev.actuation.items():
            seen(("input", name), a.moment)
        for name, pt in ev.points.items():
            seen(("point", name), pt.norm)
    return scales


def equilibrium_table(report: Report, ev, scales: Mapping[tuple[str, str], float]) -> dict:
    """One configuration of the physical reference as the report's table: every plate's largest
    stress (MPa), strain, where along the plate and safety factor, every input hinge's moment
    (N·m) and stiffness (N·m/rad), the buckling factor with loads, and every point's deviation
    (file unit) beside its model error; a value at most ROUNDING of its `scales` entry is 0."""

    def zero(key: tuple[str, str], value: float) -> bool:
        return abs(value) <= ROUNDING * scales.get(key, 0.0)

    dash = r"\text{--}"
    plates = []
    for name, p in ev.plates.items():
        nil = zero(("plate", name), p.stress)
        plates.append(
            {
                "name": escape_latex(name),
                "stress": "0" if nil else sci(p.stress / MPA, 4),
                "strain": "0" if nil else sci(p.strain, 3),
                "where": dash if nil else f"{p.section:.2f}",
                "safety": sci(p.safety, 3) if p.safety is not None and not nil else dash,
                "over": p.overloaded,
            }
        )
    actuation = [
        {
            "name": escape_latex(name),
            "angle": sci(a.angle, 4),
            "moment": "0" if zero(("input", name), a.moment) else sci(a.moment, 4),
            "stiffness": sci(a.stiffness, 4),
        }
        for name, a in ev.actuation.items()
    ]
    points = []
    # a model error is relative to the point's |ΔR| but at least the floor (docs/physics.md,
    # "Model error"): the spread is the error times what it is relative to
    least = model_error.least_deviation(
        {n: p.deviation for n, p in ev.points.items()},
        model_error.size(report.mech, report.defaults),
    )
    for name in report.plan.points:
        pt = ev.points[name]
        error = ev.model_error.get(name)
        if zero(("point", name), pt.norm):
            row = dict.fromkeys(("dx", "dy", "norm"), "0") | {"error": dash, "spread": dash}
        else:
            row = {
                "dx": sci(pt.deviation[0], 4),
                "dy": sci(pt.deviation[1], 4),
                "norm": sci(pt.norm, 4),
                "error": sci(100 * error, 2) if error is not None else dash,
                "spread": sci(error * max(pt.norm, least), 2) if error is not None else dash,
            }
        row["floored"] = (
            error is not None and pt.norm < least and not zero(("point", name), pt.norm)
        )
        points.append({"name": escape_latex(name)} | row)
    buckling = None
    if ev.buckling is not None:
        buckling = {
            "factor": sci(ev.buckling, 4) if math.isfinite(ev.buckling) else None,
            "limit": f"{BUCKLING_LIMIT:g}",
            "hinge": escape_latex(ev.buckling_hinge) if ev.buckling_hinge else None,
        }
    return {
        "inputs": _input_text(ev.inputs, report.mech),
        "plates": plates,
        "safety": any(p.safety is not None for p in ev.plates.values()),
        "over": [row["name"] for row in plates if row["over"]],
        "actuation": actuation,
        "points": points,
        "buckling": buckling,
    }


def allowable_stresses(report: Report) -> dict[str, float]:
    """Every plate's allowable stress (MPa) where its hinge or `[defaults]` gives one."""
    return {
        h.name: float_at(h.allowable_stress, report.defaults) / MPA
        for h in report.mech.hinges
        if h.allowable_stress is not None
    }


def plate_stresses(data: Sweep) -> dict[str, np.ndarray]:
    """Each plate's largest stress (MPa) at the physical reference's samples of a sweep, NaN
    where it was not solved; plates in file order."""
    solved = [ev for ev in data.reported if ev is not None]
    if not solved:
        return {}
    return {
        name: np.array(
            [np.nan if ev is None else ev.plates[name].stress / MPA for ev in data.reported]
        )
        for name in solved[0].plates
    }


def equilibrium_section(
    report: Report, runs: Sequence[tuple[str, Sweep, tuple[float, float]]], files: dict
) -> dict | None:
    """The context of the report's section on what `equilibrium` reports (docs/physics.md): a
    table per configuration of :func:`equilibrium_configurations` and, into `files`, a stress
    figure per swept input; None when the reference was solved nowhere."""
    configurations = equilibrium_configurations(runs)
    if not configurations:
        return None
    name = report.mech.name
    allowable = allowable_stresses(report)
    single = len(runs) == 1
    figures = []
    for h, data, xlim in runs:
        stress = plate_stresses(data)
        if not stress:
            continue
        fname = f"{name}-stress.pdf" if not figures else f"{name}-stress-{len(figures) + 1}.pdf"
        files[fname] = stress_figure(
            data.t[data.reference[0]],
            stress,
            {p: v for p, v in allowable.items() if p in stress},
            plain_name,
            xlim,
            input_axis(report.mech, h, plain_name(h)),
        )
        figures.append({"file": fname, "input": None if single else escape_latex(h)})
    scales = _scales(configurations)
    tables = [equilibrium_table(report, ev, scales) for ev in configurations]
    return {
        "tables": tables,
        "figures": figures,
        "allowable": bool(allowable),
        "loads": any(t["buckling"] is not None for t in tables),
        "over": any(t["over"] for t in tables),
        "actuation": any(t["actuation"] for t in tables),
        "floored": any(row["floored"] for t in tables for row in t["points"]),
    }
