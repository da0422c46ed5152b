"""The report's section on what `equilibrium` reports (docs/physics.md, "In the report"): its
tables carry symkin.evaluate(..., level="equilibrium") at the same inputs faithfully and in the
report's units (MPa, N·m, the file's length unit), and its stress figure is drawn.

The evaluation itself is checked against independent references in
tests/test_equilibrium_reported.py and tests/test_model_error.py; here the reference values are
symkin.evaluate's, and the units are checked against the same stage written in metres.
"""

from __future__ import annotations

import math
import re

import pytest
from conftest import ROOT
from test_latex import _pdf_text_has, compile_tex, write

import symkin
from symkin.studies.derive import generate

ZOO = ROOT / "tests" / "mechanisms"
#: Between the plates' stresses at F1 = -0.1 (about 380 and 426 MPa): some past it, some not.
ALLOWABLE = 400e6
LOAD = '\n[[load]]\npoint = "P"\nforce = [1.5, -4.0]\n'
#: An asymmetric range, so the middle configuration is not the unloaded as-fabricated pose.
SPAN = (-0.1, 0.08)


def _stage(name: str) -> str:
    """The parallelogram stage (mm or m) with a load at P and an allowable stress."""
    text = (ZOO / f"{name}.toml").read_text() + LOAD
    return text.replace("[defaults]\n", f"[defaults]\nallowable_stress = {ALLOWABLE!r}\n", 1)


@pytest.fixture(scope="module")
def stage():
    """The stage in millimetres, its report (LaTeX only) and its analysis."""
    mech = symkin.loads(_stage("parallelogram_mm"), "parallelogram_mm.toml")
    files = generate(mech, emit=("latex",), spans={"F1": SPAN})
    return mech, files, symkin.analyze(mech)


def _number(cell: str) -> float:
    """A table cell `$-1.234\\times 10^{-5}$` (or with a trailing flag) as a float."""
    m = re.match(r"\$(-?[\d.]+)(?:\\times 10\^\{(-?\d+)\})?\$", cell.strip())
    assert m, cell
    return float(m[1]) * 10 ** int(m[2] or 0)


def _tables(tex: str) -> list[tuple[str, dict[str, list[list[str]]]]]:
    """Each equilibrium table: its caption and its rows by block (plate, input, point)."""
    out = []
    for m in re.finditer(r"\\begin\{table\}.*?\\end\{table\}", tex, re.S):
        body = m[0]
        if ":equilibrium-" not in body:
            continue
        caption = re.search(r"\\caption\{(.*?)\}\n\\label", body, re.S)[1]
        blocks: dict[str, list[list[str]]] = {}
        current = None
        for line in body.splitlines():
            if "&" not in line:
                continue
            cells = [c.strip() for c in line.rstrip().removesuffix(r"\\").split("&")]
            if cells[0] in ("plate", "input", "point"):
                current = blocks.setdefault(cells[0], [])
            else:
                current.append(cells)
        out.append((caption, blocks))
    return out


def _inputs(caption: str) -> dict[str, float]:
    return {n: float(v) for n, v in re.findall(r"(\w+)~\$= (-?[\d.e+-]+)\$", caption)}


def _close(got: float, want: float, digits: int, scale: float | None = None) -> bool:
    """`got`, printed to `digits` significant digits, is `want` (within half a unit of the last
    digit, measured on `scale` when the value is a component of a larger vector)."""
    size = abs(want) if scale is None else scale
    return abs(got - want) <= 0.51 * 10 ** (math.floor(math.log10(size)) - digits + 1)


def test_tables_carry_the_evaluation(stage):
    """Every configuration's table: plate stress (MPa), strain, where, safety and the flag,
    the input's moment and stiffness (N·m, N·m/rad), the buckling factor, and each point's
    deviation (mm) beside its model error, equal to symkin.evaluate at the same inputs."""
    _, files, an = stage
    tex = files["parallelogram_mm.tex"].decode()
    tables = _tables(tex)
    assert [next(iter(_inputs(c).values())) for c, _ in tables] == [SPAN[0], -0.01, SPAN[1]]
    flagged_somewhere = False
    for caption, blocks in tables:
        inputs = _inputs(caption)
        ev = symkin.evaluate(an, {k: repr(v) for k, v in inputs.items()}, "equilibrium")
        assert [row[0] for row in blocks["plate"]] == list(ev.plates)
        for name, stress, strain, where, safety in blocks["plate"]:
            plate = ev.plates[name]
            assert _close(_number(stress) * 1e6, plate.stress, 4), (name, stress)
            assert _close(_number(strain), plate.strain, 3)
            assert where == f"${plate.section:.2f}$"
            assert _close(_number(safety), ALLOWABLE / plate.stress, 3)
            past = plate.stress > ALLOWABLE
            assert ("past allowable" in safety) == past, (name, safety)
            flagged_somewhere |= past
        [(name, angle, moment, stiffness)] = blocks["input"]
        load = ev.actuation["F1"]
        assert name == "F1" and _number(angle) == pytest.approx(inputs["F1"], abs=1e-12)
        assert _close(_number(moment), load.moment, 4)
        assert _close(_number(stiffness), load.stiffness, 4)
        [(name, dx, dy, norm, error, spread)] = blocks["point"]
        point = ev.points["P"]
        assert _close(_number(dx), point.deviation[0], 4, point.norm)
        assert _close(_number(dy), point.deviation[1], 4, point.norm)
        assert _close(_number(norm), point.norm, 4)
        assert _close(_number(error), 100 * ev.model_error["P"], 2)
        assert _close(_number(spread), ev.model_error["P"] * point.norm, 2)
        if math.isfinite(ev.buckling):
            factor = re.search(r"\\lambda = (.*?)\$", caption)[1]
            assert _close(_number(f"${factor}$"), ev.buckling, 4)
        else:
            assert "above $10$" in caption
    assert flagged_somewhere
    assert r"safety" in tex and r"($\mathrm{mm}$)" in tex and "(MPa)" in tex


def test_units_against_the_stage_in_metres(stage):
    """The mm report's stresses (MPa), moments (N·m) and deviations (mm) are those of the same
    stage written in metres, evaluated there: the units are converted once, correctly."""
    _, files, _ = stage
    metres = symkin.analyze(symkin.loads(_stage("parallelogram"), "parallelogram.toml"))
    for caption, blocks in _tables(files["parallelogram_mm.tex"].decode())[::2]:
        inputs = _inputs(caption)
        ev = symkin.evaluate(metres, {k: repr(v) for k, v in inputs.items()}, "equilibrium")
        for name, stress, *_ in blocks["plate"]:
            assert _close(_number(stress), ev.plates[name].stress / 1e6, 4)
        assert _close(_number(blocks["input"][0][2]), ev.actuation["F1"].moment, 4)
        assert _close(_number(blocks["point"][0][3]), 1e3 * ev.points["P"].norm, 4)


def test_stress_figure_and_compiles(stage, tmp_path):
    """The stress figure is in the files and the .tex, pdftotext finds its axis labels, every
    plate and the allowable line; the report compiles with the section."""
    _, files, _ = stage
    tex = files["parallelogram_mm.tex"].decode()
    assert r"\includegraphics[width=\linewidth]{\symkinfigpath parallelogram_mm-stress.pdf}" in tex
    pdf = files["parallelogram_mm-stress.pdf"]
    for needle in ("(MPa)", "input θ of F1 (rad)", "F1", "S1", "F2", "S2", "allowable"):
        assert _pdf_text_has(pdf, needle), needle
    compile_tex(write(files, tmp_path), "parallelogram_mm.tex")
