"""The LaTeX report: it compiles with pdflatex (standalone and as an appendix), nothing runs off
the page, the output is byte-deterministic, and hostile names from the mechanism file stay text.

Tests that need pdflatex skip without it, and fail when CI=true (.ci/run installs TeX Live).
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from collections.abc import Mapping
from pathlib import Path

import pytest
from conftest import EXAMPLES, ROOT, once_per_run

import symkin
from symkin.cli.commands import main
from symkin.codegen.backends.latex.text import escape_latex, math_name
from symkin.studies.derive import generate

EXAMPLE_NAMES = sorted(p.stem for p in EXAMPLES.glob("*.toml"))
MAX_OVERFULL_PT = 1.0
OVERFULL = re.compile(r"Overfull \\hbox \((\d+(?:\.\d+)?)pt too wide\)")
HOSTILE_NAMES = ("int", "a-b", r"\input{/etc/passwd}", '"; system("true")', "50% & $x$_#~^{}")
APPENDIX_WRAPPER = r"""\documentclass{article}
\usepackage{amsmath,amssymb,graphicx,booktabs}
\begin{document}
\appendix
\input{%s}
\end{document}
"""


def pdflatex() -> str:
    path = shutil.which("pdflatex")
    if path is None:
        if os.environ.get("CI") == "true":
            pytest.fail("pdflatex is missing (CI=true): .ci/run installs TeX Live from Debian")
        pytest.skip("pdflatex is not installed")
    return path


def compile_tex(folder: Path, main: str) -> str:
    """Run pdflatex twice (references), halting on the first error; returns the log."""
    exe = pdflatex()
    for flags in (["-draftmode"], []):
        run = subprocess.run(
            [exe, "-interaction=nonstopmode", "-halt-on-error", "-no-shell-escape", *flags, main],
            cwd=folder,
            capture_output=True,
            text=True,
            timeout=180,
        )
        log = (folder / (Path(main).stem + ".log")).read_text(encoding="latin-1")
        assert run.returncode == 0, f"pdflatex failed on {main}:\n" + "\n".join(
            log.splitlines()[-40:]
        )
    return log


def overfull(log: str) -> list[float]:
    return [float(x) for x in OVERFULL.findall(log)]


def write(files: dict[str, bytes], folder: Path) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    for name, content in files.items():
        (folder / name).write_bytes(content)
    return folder


class _Reports(Mapping):
    """example -> (standalone files, appendix files), each generated on first use in this run:
    by the first xdist worker that asks (conftest.once_per_run), read back by the others."""

    def __init__(self, factory) -> None:
        self._factory = factory
        self._done: dict[str, tuple[dict[str, bytes], dict[str, bytes]]] = {}

    def __getitem__(self, name: str) -> tuple[dict[str, bytes], dict[str, bytes]]:
        if name not in EXAMPLE_NAMES:
            raise KeyError(name)
        if name not in self._done:

            def build(folder: Path) -> None:
                for part, files in zip(("standalone", "appendix"), _report(name), strict=True):
                    write(files, folder / part)

            folder = once_per_run(self._factory, f"report-{name}", build)
            standalone, appendix = (
                {p.name: p.read_bytes() for p in sorted((folder / part).iterdir())}
                for part in ("standalone", "appendix")
            )
            self._done[name] = (standalone, appendix)
        return self._done[name]

    def __iter__(self):
        return iter(EXAMPLE_NAMES)

    def __len__(self) -> int:
        return len(EXAMPLE_NAMES)


def _report(name: str) -> tuple[dict[str, bytes], dict[str, bytes]]:
    from symkin.codegen import pipeline
    from symkin.codegen.backends.latex import report
    from symkin.graph.structure import build
    from symkin.kinematics.analysis import Analysis
    from symkin.studies.derive import physics_reference

    mech = symkin.load(EXAMPLES / f"{name}.toml")
    an = Analysis(build(mech))
    source = Path(mech.path).name
    p, module = pipeline.build(an, "numpy", source, report=True)
    physics = None
    if p.loaded is not None:
        # the standalone report and the appendix sweep the same inputs: the physical
        # reference (40-digit equilibrium solves) is computed once for both
        reference, solved = physics_reference(an), {}

        def physics(inputs):
            key = tuple(sorted(inputs.items()))
            if key not in solved:
                solved[key] = reference(inputs)
            return solved[key]

    return (
        report.emit(p, source, evaluator=module, physics=physics),
        report.emit(p, source, appendix=True, evaluator=module, physics=physics),
    )


@pytest.fixture(scope="session")
def reports(tmp_path_factory) -> Mapping[str, tuple[dict[str, bytes], dict[str, bytes]]]:
    """example -> (standalone files, appendix files), generated once per run."""
    return _Reports(tmp_path_factory)


# -- structure of the output ---------------------------------------------------------------------


@pytest.mark.parametrize("example", EXAMPLE_NAMES)
def test_files_header_and_figures(example, reports):
    standalone, appendix = reports[example]
    tex = standalone[f"{example}.tex"].decode()
    body = appendix[f"{example}.tex"].decode()
    header = f"% Generated by symkin from {example}.toml - do not edit."
    assert tex.startswith(header) and body.startswith(header)
    assert tex.count(r"\documentclass") == 1 and r"\end{document}" in tex
    assert r"\documentclass" not in body and r"\begin{document}" not in body
    for text, files in ((tex, standalone), (body, appendix)):
        for figure in re.findall(r"\\includegraphics\[[^]]*\]\{\\symkinfigpath (\S+)\}", text):
            assert figure in files and files[figure].startswith(b"%PDF-")
    assert set(standalone) == set(appendix)
    assert {f"{example}-pose.pdf", f"{example}-graph.pdf", f"{example}-deviation.pdf"} <= set(
        standalone
    )
    for needed in (
        r"\underline{I} = \begin{bmatrix}",
        r"\underline{\Phi} = \begin{bmatrix}",
        r"\underline{\Psi} = \begin{bmatrix}",
        r"\underline{\mathbf{J}} = ",
        r"\underline{\mathbf{J}}^{*} = ",
        r"\tag*{(5.1)}",
        r"\tag*{(5.3)}",
        r"\operatorname{atan2}",
        r"^{\mathrm{paper}}",
        r"^{(1)}",
    ):
        assert needed in tex, needed


def test_report_is_generated_by_derive(reports):
    files = generate(symkin.load(EXAMPLES / "four_bar.toml"), emit=["latex"])
    assert files == reports["four_bar"][0]


# -- pdflatex ------------------------------------------------------------------------------------


@pytest.mark.parametrize("example", EXAMPLE_NAMES)
def test_standalone_compiles_without_overfull_boxes(example, reports, tmp_path):
    folder = write(reports[example][0], tmp_path / example)
    log = compile_tex(folder, f"{example}.tex")
    assert (folder / f"{example}.pdf").stat().st_size > 10_000
    worst = max(overfull(log), default=0.0)
    assert worst <= MAX_OVERFULL_PT, f"an overfull \\hbox {worst} pt too wide in {example}.tex"
    assert "Reference" not in log or "undefined" not in log


@pytest.mark.parametrize("example", EXAMPLE_NAMES)
def test_appendix_compiles_in_a_paper(example, reports, tmp_path):
    folder = write(reports[example][1], tmp_path / example)
    (folder / "paper.tex").write_text(APPENDIX_WRAPPER % example)
    log = compile_tex(folder, "paper.tex")
    # the default article's 345 pt text width: narrower than the standalone report's
    worst = max(overfull(log), default=0.0)
    assert worst <= MAX_OVERFULL_PT, f"an overfull \\hbox {worst} pt too wide in the appendix"


TWO_COLUMN_WRAPPER = r"""\documentclass[twocolumn]{article}
\usepackage{amsmath,amssymb,graphicx,booktabs}
\begin{document}
\typeout{COLUMNWIDTH=\the\columnwidth}
\section{Introduction} A conference paper.
\appendix
%s
\end{document}
"""


@pytest.mark.parametrize(
    "key", [*EXAMPLE_NAMES, "SERIAL_ARM", "FIVE_BAR", "WATT_II", "TRIAD_SIX_BAR"]
)
def test_appendix_fits_a_two_column_paper(key, tmp_path):
    """derive --appendix --columnwidth 229.5pt, \\input into a two-column article (whose column
    is 229.5 pt): no overfull box over 1 pt."""
    pdflatex()
    import mechanisms

    if key in EXAMPLE_NAMES:
        mech = symkin.load(EXAMPLES / f"{key}.toml")
    else:
        path = tmp_path / "m.toml"
        path.write_text(getattr(mechanisms, key))
        mech = symkin.load(path)
    folder = write(
        generate(mech, emit=["latex"], appendix=True, column_width=229.5), tmp_path / "out"
    )
    (folder / "paper.tex").write_text(TWO_COLUMN_WRAPPER % f"\\input{{{mech.name}}}")
    log = compile_tex(folder, "paper.tex")
    assert "COLUMNWIDTH=229.5pt" in log
    worst = max(overfull(log), default=0.0)
    assert worst <= 1.0, f"an overfull \\hbox {worst} pt too wide in {key} (two columns)"


def test_two_reports_input_into_one_paper(tmp_path):
    """The report's helper macros are defined once: two appendices in one document compile."""
    pdflatex()
    parts = []
    for name in ("four_bar", "stephenson_six_bar"):
        write(
            generate(
                symkin.load(EXAMPLES / f"{name}.toml"),
                emit=["latex"],
                appendix=True,
                column_width=229.5,
            ),
            tmp_path,
        )
        parts.append(f"\\input{{{name}}}")
    (tmp_path / "paper.tex").write_text(TWO_COLUMN_WRAPPER % "\n".join(parts))
    log = compile_tex(tmp_path, "paper.tex")
    assert max(overfull(log), default=0.0) <= 1.0


@pytest.mark.parametrize(
    "width, ok",
    [
        ("229.5pt", True),
        ("8.1cm", True),
        ("3.2in", True),
        ("81mm", True),
        ("240", False),
        ("12em", False),
        ("20pt", False),
        ("wide", False),
    ],
)
def test_columnwidth_option(tmp_path, capsys, width, ok):
    code = main(
        [
            "derive",
            str(EXAMPLES / "four_bar.toml"),
            "-o",
            str(tmp_path / "o"),
            "--emit",
            "latex",
            "--appendix",
            "--quiet",
            "--columnwidth",
            width,
        ]
    )
    err = capsys.readouterr().err
    assert (code == 0) == ok, err
    if not ok:
        assert code == 2 and "fix:" in err


@pytest.mark.parametrize("key", ["SERIAL_ARM", "FIVE_BAR", "WATT_II", "TRIAD_SIX_BAR"])
def test_other_models_and_topologies_compile(key, tmp_path):
    """An open chain, two inputs, rigid / expr / prbm / small_deflection / elastica hinges and a
    triad (no closed form): every branch of the report compiles and fits the page."""
    pdflatex()
    import mechanisms

    path = tmp_path / "m.toml"
    path.write_text(getattr(mechanisms, key))
    mech = symkin.load(path)
    folder = write(generate(mech, emit=["latex"]), tmp_path / "out")
    log = compile_tex(folder, f"{mech.name}.tex")
    worst = max(overfull(log), default=0.0)
    assert worst <= MAX_OVERFULL_PT, f"an overfull \\hbox {worst} pt too wide in {key}"


# -- determinism ---------------------------------------------------------------------------------


@pytest.mark.parametrize("example", EXAMPLE_NAMES)
def test_byte_identical_across_processes_and_hash_seeds(reports, tmp_path, example):
    # one example per test (one process each): xdist spreads them over its workers
    seed = "271828" if os.environ.get("PYTHONHASHSEED") != "271828" else "314159"
    script = (
        "import sys, pathlib, symkin\n"
        "from symkin.studies.derive import generate\n"
        "out = pathlib.Path(sys.argv[1])\n"
        "for name in sys.argv[2:]:\n"
        f"    files = generate(symkin.load(pathlib.Path({str(EXAMPLES)!r}) / (name + '.toml')),\n"
        "                     emit=['latex'])\n"
        "    for key, content in files.items():\n"
        "        (out / key).write_bytes(content)\n"
    )
    env = dict(os.environ, PYTHONHASHSEED=seed)
    subprocess.run(
        [sys.executable, "-c", script, str(tmp_path), example],
        check=True,
        env=env,
        cwd=ROOT,
        timeout=300,
    )
    for name, content in reports[example][0].items():
        assert (tmp_path / name).read_bytes() == content, f"{name} differs between runs"


# -- names from the mechanism file ---------------------------------------------------------------

HOSTILE = """
format = 1
name = "hostile"
ground = 'int'

[parameters]
l = 1e-3

[defaults]
model = "circular_arc"
length = "l"

[[link]]
name = 'int'
[[link]]
name = 'a-b'
[[link]]
name = '\\input{/etc/passwd}'
[[link]]
name = '"; system("true")'

[[hinge]]
name = '50% & $x$_#~^{}'
links = ['int', 'a-b']
at = [0.0, 0.0]
plate_angle = "pi/2"
input = true

[[hinge]]
name = '\\input{/etc/passwd}'
links = ['a-b', '\\input{/etc/passwd}']
at = [0.015, 0.026]
plate_angle = "60*deg"

[[hinge]]
name = 'int'
links = ['int', '"; system("true")']
at = [0.1, 0.0]
plate_angle = "pi/2"

[[hinge]]
name = '"; system("true")'
links = ['\\input{/etc/passwd}', '"; system("true")']
at = [0.085, 0.068]

[[point]]
name = '50% & $x$_#~^{}'
link = '\\input{/etc/passwd}'
at = [0.06, 0.09]

[[point]]
name = 'a-b'
link = '"; system("true")'
at = [0.09, 0.04]
"""


def test_hostile_names_compile_to_literal_text(tmp_path):
    pdflatex()
    path = tmp_path / "hostile.toml"
    path.write_text(HOSTILE)
    mech = symkin.load(path)
    assert {lk.name for lk in mech.links} | {h.name for h in mech.hinges} >= set(HOSTILE_NAMES)
    folder = write(generate(mech, emit=["latex"]), tmp_path / "out")
    log = compile_tex(folder, "hostile.tex")
    assert "(/etc/passwd" not in log  # never \input
    tex = (folder / "hostile.tex").read_text()
    assert r"\input{/etc/passwd}" not in tex
    if shutil.which("pdftotext"):
        text = subprocess.run(
            ["pdftotext", str(folder / "hostile.pdf"), "-"],
            capture_output=True,
            text=True,
            check=True,
        ).stdout
        assert r"\input{/etc/passwd}" in text and 'system("true")' in text
        passwd = Path("/etc/passwd")
        if passwd.exists():
            for line in passwd.read_text().splitlines()[:5]:
                assert line not in text


def test_escape_latex_of_every_character_compiles(tmp_path):
    pdflatex()
    every = "".join(chr(c) for c in range(32, 127)) + "\t\x07 éÅßΩ→ ﬁ\U0001f600"
    assert escape_latex("plain Name_1") == r"plain Name\_\penalty0{}1"
    for ch in '\\{}$&#^_%~<>|"':
        out = escape_latex(ch)
        assert out != ch and out.startswith(("\\", "{\\ttfamily\\char")), (ch, out)
    doc = (
        "\\documentclass{article}\\usepackage{amsmath}\\begin{document}\n"
        f"{escape_latex(every)}\n\n$x_{{{math_name(every)}}}$\n\\end{{document}}\n"
    )
    (tmp_path / "chars.tex").write_text(doc)
    compile_tex(tmp_path, "chars.tex")
    if shutil.which("pdftotext"):
        text = subprocess.run(
            ["pdftotext", str(tmp_path / "chars.pdf"), "-"],
            capture_output=True,
            text=True,
            check=True,
        ).stdout
        # (OT1 sets ' and ` as typographic quotes and _ as a rule; the rest is literal)
        for fragment in (
            '!"#$%&',
            "()*+,-./0123456789:;<=>?@ABC",
            "[\\]^",
            "{|}~",
            "[U+0007]",
            "[U+2192]",
        ):
            assert fragment in text, fragment


# -- what the report states --------------------------------------------------------------------


def _derive_tex(tmp_path: Path, file: Path, *options: str) -> str:
    out = tmp_path / "out"
    code = main(["derive", str(file), "-o", str(out), "--emit", "latex", "--quiet", *options])
    assert code == 0
    return next(out.glob("*.tex")).read_text()


def _peak_rows(tex: str) -> list[list[str]]:
    table = tex[tex.index(":peaks}") : tex.index(r"\bottomrule", tex.index(":peaks}"))]
    return [
        [c.strip() for c in line.rstrip("\\ ").split("&")]
        for line in table.splitlines()
        if line.count("&") in (4, 5) and "level" not in line
    ]


def _sci(cell: str) -> float:
    m = re.fullmatch(r"\$(-?[\d.]+)(?:\\times 10\^\{(-?\d+)\})?\$", cell)
    return float(m[1]) * 10 ** int(m[2] or 0)


def test_range_without_tolerance_sets_the_plotted_range(tmp_path):
    """derive --range A0=-0.1:0.25 (no --tolerance): the report sweeps that range, and its table's
    largest exact deviation is the 40-digit evaluation's at the stated angle, no smaller than at
    the range's ends."""
    tex = _derive_tex(tmp_path, EXAMPLES / "four_bar.toml", "--range", "A0=-0.1:0.25")
    assert "of the input $\\theta$ of A0 from $-0.1$ to $0.25$~rad" in tex
    from symkin.graph.structure import build
    from symkin.kinematics.analysis import Analysis

    analysis = Analysis(build(symkin.load(EXAMPLES / "four_bar.toml")))
    rows = [r for r in _peak_rows(tex) if r[1] == "exact"]
    assert [r[0] for r in rows] == ["C"]
    peak, at = _sci(rows[0][2]), float(rows[0][3].strip("$"))
    assert -0.1 <= at <= 0.25
    norm = lambda a: symkin.evaluate(analysis, {"A0": a}, "exact").points["C"].norm  # noqa: E731
    assert abs(norm(at) - peak) <= 5e-3 * peak  # the table prints 3 digits
    assert max(norm(-0.1), norm(0.25)) <= norm(at) * (1 + 1e-9)


def test_range_needs_something_to_act_on(tmp_path, capsys):
    code = main(
        [
            "derive",
            str(EXAMPLES / "four_bar.toml"),
            "-o",
            str(tmp_path / "o"),
            "--emit",
            "c",
            "--quiet",
            "--range",
            "A0=-0.1:0.2",
        ]
    )
    assert code == 2 and "fix:" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()


def test_several_inputs_are_swept_one_at_a_time(tmp_path):
    """A two-input five-bar: one figure per input, each input over its own range with the other
    held at the middle of its range, and the table says which input its largest value is at."""
    import mechanisms

    path = tmp_path / "five_bar.toml"
    path.write_text(mechanisms.FIVE_BAR)
    tex = _derive_tex(tmp_path, path, "--range", "O1=-0.1:0.2")
    assert "O1: $-0.1$ to $0.2$~rad, held at $0.05$; O2: $-0.3$ to $0.3$~rad, held at $0$" in tex
    figures = re.findall(r"\\symkinfigpath (five_bar-deviation\S*\.pdf)", tex)
    assert figures == ["five_bar-deviation.pdf", "five_bar-deviation-2.pdf"]
    assert "the input O1 (the other inputs held)" in tex
    assert "the input O2 (the other inputs held)" in tex
    assert "every input angle" not in tex
    for row in _peak_rows(tex):
        assert re.fullmatch(r"O[12] \$[+-]\d\.\d{3}\$", row[3]), row
    log = compile_tex(tmp_path / "out", "five_bar.tex")
    assert max(overfull(log), default=0.0) <= MAX_OVERFULL_PT


def test_each_input_figure_shows_the_points_it_moves(tmp_path):
    """A fan of three four-bars (benchmarks/families.py): crank A0_j drives only coupler j, so
    the figure of input A0_j holds point Cj alone, and the text says points were left out."""
    sys.path.insert(0, str(ROOT / "benchmarks"))
    import families

    path = tmp_path / "fan_3.toml"
    path.write_text(families.fan(3))
    tex = _derive_tex(tmp_path, path)
    captions = re.findall(
        r"\\caption\{Deviation \$\|\\Delta\\mathbf\{R\}\|\$ of (.*?) over "
        r"the range of the input (\S+) \(",
        tex.replace(r"\penalty0{}", "").replace(r"\_", "_"),
    )
    assert captions == [("point C1", "A0_1"), ("point C2", "A0_2"), ("point C3", "A0_3")]
    assert "A figure shows only the points its input moves" in tex
    log = compile_tex(tmp_path / "out", "fan_3.tex")
    assert max(overfull(log), default=0.0) <= MAX_OVERFULL_PT


def test_tolerance_choice_is_in_the_rendered_report(tmp_path):
    tex = _derive_tex(tmp_path, EXAMPLES / "four_bar.toml", "--tolerance", "0.05")
    body = "\n".join(line for line in tex.splitlines() if not line.startswith("%"))
    assert r"\paragraph{What this derivation covers.}" in body
    body = body.replace(r"\penalty0{}", "").replace("{}", "").replace(r"\_", "_")
    m = re.search(r"Tolerance 0.05 over A0 in \[-0.2, 0.2\]: variant (\S+) chosen", body)
    assert m and "worst relative error" in body
    assert f"variant {m[1]} chosen" in tex.split(r"\documentclass")[0]  # and in the header


def test_mechanism_specific_sentences(reports):
    for example, (standalone, _) in reports.items():
        tex = standalone[f"{example}.tex"].decode()
        assert "graph traversal" not in tex
        # the four-bar's sentence for the four-bars: the paper's and the piezo amplifier (a
        # Scott-Russell linkage is a four-bar with its slider a rocker)
        four_bar = example.startswith("four_bar") or example == "piezo_amplifier"
        assert ("for the four-bar's" in tex) == four_bar, example


def test_units_on_the_text_tables_and_axes(tmp_path, reports):
    """The file's `units` names the lengths in the text, the table of largest deviations and the
    figures' axes (default metres)."""
    import mechanisms as M

    tex = reports["four_bar"][0]["four_bar.tex"].decode()
    assert "are in metres" in tex and r"($\mathrm{m}$)" in tex
    text = M.without_stiffness(EXAMPLES / "four_bar.toml").replace(
        'name = "four_bar"', 'name = "four_bar"\nunits = "mm"', 1
    )
    assert 'units = "mm"' in text
    path = tmp_path / "four_bar_mm.toml"
    path.write_text(text)
    files = generate(symkin.load(path), emit=["latex"])
    tex = files["four_bar.tex"].decode()
    assert "are in millimetres" in tex and r"($\mathrm{mm}$)" in tex
    for figure in ("four_bar-pose.pdf", "four_bar-deviation.pdf"):
        assert b"(mm)" in files[figure] or _pdf_text_has(files[figure], "mm"), figure


def _pdf_text_has(pdf: bytes, needle: str) -> bool:
    """Whether pdftotext finds `needle` in the figure (matplotlib embeds text as glyphs)."""
    exe = shutil.which("pdftotext")
    if exe is None:
        if os.environ.get("CI") == "true":
            raise AssertionError("pdftotext (poppler-utils) is needed under CI")
        pytest.skip("pdftotext not installed")
    proc = subprocess.run([exe, "-", "-"], input=pdf, capture_output=True, check=True)
    return needle in proc.stdout.decode("utf-8", "replace")
