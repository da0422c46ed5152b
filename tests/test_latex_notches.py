"""Notch hinges in the LaTeX report: the hinge table (profile, keys, thinnest section, span, K_t)
and the notch drawn as cut in the pose figure; a report of uniform plates stays as it was.

References: the notch's numbers from the TOML file itself (tomllib), K_t from Lobontiu's formula
written out here, the flanks from the circle (ellipse) each profile names (docs/file-format.md,
"Notch hinges").
"""

from __future__ import annotations

import math
import os
import re
import shutil
import subprocess
import tomllib
from pathlib import Path

import matplotlib.patches
import pytest
import sympy
from conftest import EXAMPLES, ROOT
from test_latex import compile_tex, write

import symkin
from symkin.report import document, figures
from symkin.report.profiles import notch_polygon, notch_scale
from symkin.report.text import plain_name
from symkin.studies.derive import generate

LEVER = EXAMPLES / "notch_lever.toml"
CELL = r" & \$(.*?)\$"
ROW = re.compile(r"^(\d+) & (\S+) & ([a-z ]+)" + 4 * CELL + r" \\\\$")


def _rows(tex: str) -> dict[str, tuple[str, ...]]:
    """The hinge table's rows by hinge name: (profile, keys, t, span, K_t)."""
    table = tex[tex.index("Hinge profiles:") :]
    table = table[: table.index(r"\end{tabular}")]
    return {m[2]: m.groups()[2:] for line in table.splitlines() if (m := ROW.match(line))}


def _layout_text(pdf: Path) -> str:
    """pdftotext -layout of the compiled report (its tables' rows on one line each)."""
    exe = shutil.which("pdftotext")
    if exe is None:
        if os.environ.get("CI") == "true":
            raise AssertionError("pdftotext (poppler-utils) is needed under CI")
        pytest.skip("pdftotext not installed")
    run = subprocess.run([exe, "-layout", str(pdf), "-"], capture_output=True, check=True)
    return run.stdout.decode("utf-8", "replace")


def _kt(t: float, rho: float) -> float:
    """Lobontiu's notch factor K_t = (1 + t/(2ρ))^(9/20)."""
    return (1 + t / (2 * rho)) ** 0.45


def _number(cell: str) -> float:
    """A table cell's value: the number after the last '=' (gnum's 10^{k} forms too)."""
    text = cell.split("=")[-1].strip()
    m = re.fullmatch(r"(?:([-\d.]+)\\times )?10\^\{(-?\d+)\}", text)
    if m:
        return float(m[1] or 1) * 10.0 ** int(m[2])
    return float(text)


@pytest.fixture(scope="module")
def lever(monkeypatch_module):
    """The notch lever's report, and the pose data its figure was drawn from."""
    drawn = []
    original = document.pose_figure

    def recording(pose, *args, **kwargs):
        drawn.append(pose)
        return original(pose, *args, **kwargs)

    monkeypatch_module.setattr(document, "pose_figure", recording)
    files = generate(symkin.load(LEVER), emit=["latex"])
    return files, drawn[0]


@pytest.fixture(scope="module")
def monkeypatch_module():
    with pytest.MonkeyPatch.context() as mp:
        yield mp


def test_hinge_table_of_the_notch_lever(lever):
    files, _ = lever
    tex = files["notch_lever.tex"].decode()
    data = tomllib.loads(LEVER.read_text())
    radius, thick = data["defaults"]["radius"], data["defaults"]["thickness"]
    rows = _rows(tex)
    assert sorted(rows) == sorted(h["name"] for h in data["hinge"])
    for _name, (profile, keys, t, span, factor) in rows.items():
        assert profile == data["defaults"]["profile"]
        assert keys.startswith("R = ") and _number(keys) == pytest.approx(radius, rel=1e-12)
        assert _number(t) == pytest.approx(thick, rel=1e-12)
        assert _number(span) == pytest.approx(2 * radius, rel=1e-12)
        assert float(factor) == pytest.approx(_kt(thick, radius), abs=6e-5)


def test_hinge_table_reads_back_from_the_pdf(lever, tmp_path):
    files, _ = lever
    folder = write(files, tmp_path / "lever")
    log = compile_tex(folder, "notch_lever.tex")
    assert "Overfull" not in log
    text = _layout_text(folder / "notch_lever.pdf")
    data = tomllib.loads(LEVER.read_text())
    radius, thick = data["defaults"]["radius"], data["defaults"]["thickness"]
    found = 0
    for line in text.splitlines():
        words = line.split()
        if len(words) == 7 and words[2] == "circular":  # a, hinge, profile, R=.., t, l, K_t
            assert words[3].replace(" ", "") == f"R={radius:g}", line
            assert float(words[4]) == thick and float(words[5]) == 2 * radius, line
            assert float(words[6]) == pytest.approx(_kt(thick, radius), abs=6e-5)
            found += 1
    assert found == len(data["hinge"])
    assert "Hinge profiles" in text


def test_pose_figure_draws_the_notch_as_cut(lever, monkeypatch):
    files, pose = lever
    data = tomllib.loads(LEVER.read_text())
    radius, thick = data["defaults"]["radius"], data["defaults"]["thickness"]
    assert len(pose.notches) == len(data["hinge"])
    along, across = notch_scale(pose)
    # the neck stays visible: at least half a percent of the drawing's extent (about 1 pt)
    every = [p for _, _, att in pose.links for p in att] + [p for _, _, p in pose.points]
    size = max(
        max(p[0] for p in every) - min(p[0] for p in every),
        max(p[1] for p in every) - min(p[1] for p in every),
    )
    assert thick * across >= 0.005 * size
    assert 2 * radius * along <= 0.16 * size  # and the notch is not a monster
    tex = files["notch_lever.tex"].decode()
    words = (
        f"magnified {along:g} times"
        if along == across
        else f"magnified {along:g} times along their axis and {across:g} times across it"
    )
    assert f"the notch hinges as cut (their flanks $\\pm T(x)/2$, {words}" in tex
    # the polygons pose_figure draws (matplotlib's Polygon, recorded)
    patches: list = []

    class Recorded(matplotlib.patches.Polygon):
        def __init__(self, xy, *args, **kwargs):
            super().__init__(xy, *args, **kwargs)
            patches.append([tuple(map(float, p)) for p in xy])

    monkeypatch.setattr(matplotlib.patches, "Polygon", Recorded)
    figures.pose_figure.__wrapped__(pose, plain_name, "mm")
    hinges = {h["name"]: h for h in data["hinge"]}
    values = data["parameters"]
    for a, name, p, m, _ in pose.plates:
        centre = ((p[0] + m[0]) / 2, (p[1] + m[1]) / 2)
        # the hinge's axis from the file: plate_angle pi/2, 0 or pi
        angle = {"pi/2": math.pi / 2, "0": 0.0, "pi": math.pi}[str(hinges[name]["plate_angle"])]
        ux, uy = math.cos(angle), math.sin(angle)
        at = [float(sympy.sympify(v).subs(values)) for v in hinges[name]["at"]]
        assert centre == pytest.approx(at, abs=1e-12)
        outline = notch_polygon(centre, (ux, uy), dict(pose.notches)[a], along, across)
        assert any(
            len(drawn) == len(outline)
            and all(math.dist(q, r) < 1e-9 * size for q, r in zip(drawn, outline, strict=True))
            for drawn in patches
        ), name
        # in the hinge's frame: x along the axis, y across it, unscaled
        local = [
            (
                ((x - centre[0]) * ux + (y - centre[1]) * uy) / along,
                (-(x - centre[0]) * uy + (y - centre[1]) * ux) / across,
            )
            for x, y in outline
        ]
        half = len(local) // 2
        lower, upper = local[:half], local[half:][::-1]
        mid = min(range(half), key=lambda k: abs(lower[k][0]))
        assert lower[mid][0] == pytest.approx(0, abs=1e-12)
        assert upper[mid][1] - lower[mid][1] == pytest.approx(thick, rel=1e-9)  # t at the neck
        assert upper[0][1] - lower[0][1] == pytest.approx(thick + 2 * radius, rel=1e-9)
        assert lower[0][0] == pytest.approx(-radius, rel=1e-12)
        assert lower[-1][0] == pytest.approx(radius, rel=1e-12)
        for x, y in lower + upper:  # each flank on its circle, radius R about (0, ±(R + t/2))
            assert math.hypot(x, abs(y) - (radius + thick / 2)) == pytest.approx(radius, rel=1e-9)


MIXED = """
[[hinge]]
name = "B"
links = ["coupler", "rocker"]
at = [0.085, 0.068]
plate_angle = "0"
profile = "elliptical"
semi_axis = 2e-3
depth = 1e-3
thickness = 1e-4
"""


def test_plates_and_a_notch_in_one_table(tmp_path):
    """A four-bar whose hinge B is an elliptical notch: the plates keep their length and
    thickness in the same table, the notch has a, c, t, its span 2a and K_t with ρ = a²/c; the
    pose caption names both drawings."""
    text = (EXAMPLES / "four_bar.toml").read_text()
    start = text.index('name = "B"\n')
    start = text.rindex("[[hinge]]", 0, start)
    end = text.index("[[", start + 2)
    path = tmp_path / "four_bar_notch.toml"
    path.write_text(text[:start] + MIXED.strip() + "\n\n" + text[end:])
    files = generate(symkin.load(path), emit=["latex"])
    tex = files["four_bar.tex"].decode()
    rows = _rows(tex)
    data = tomllib.loads(path.read_text())
    length = data["parameters"]["l"]
    for name in ("A0", "A", "B0"):
        profile, keys, t, span, factor = rows[name]
        assert profile == "uniform" and keys == r"\text{--}" and factor == r"\text{--}"
        assert _number(t) == pytest.approx(length / 10, rel=1e-12)
        assert _number(span) == pytest.approx(length, rel=1e-12)
    profile, keys, t, span, factor = rows["B"]
    a, c = 2e-3, 1e-3
    assert profile == "elliptical"
    got = dict(part.split(" = ") for part in keys.split(", "))
    assert _number(got["a"]) == pytest.approx(a) and _number(got["c"]) == pytest.approx(c)
    assert _number(t) == pytest.approx(1e-4) and _number(span) == pytest.approx(2 * a)
    assert float(factor) == pytest.approx(_kt(1e-4, a * a / c), abs=6e-5)
    assert "the flexure plates as thick black segments" in tex
    assert "the notch hinges as cut" in tex
    folder = write(files, tmp_path / "mixed")
    assert "Overfull" not in compile_tex(folder, "four_bar.tex")


def test_a_uniform_plate_report_is_unchanged(monkeypatch):
    """No notch, no hinge table and no word on notches: the four-bar's report is the committed
    one (generated/, derived before notches reached the report), and its pose figure draws its
    plates as segments (figure bytes depend on the installed matplotlib: tests/test_generated)."""
    drawn = []
    original = document.pose_figure

    def recording(pose, *args, **kwargs):
        drawn.append(pose)
        return original(pose, *args, **kwargs)

    monkeypatch.setattr(document, "pose_figure", recording)
    files = generate(symkin.load(EXAMPLES / "four_bar.toml"), emit=["latex"])
    tex = files["four_bar.tex"].decode()
    assert "Hinge profiles" not in tex and "notch" not in tex
    assert tex == (ROOT / "generated" / "four_bar" / "four_bar.tex").read_text()
    assert drawn and all(pose.notches == () for pose in drawn)
