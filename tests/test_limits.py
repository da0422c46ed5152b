"""Work refused before it starts (docs/cli.md, "A ceiling on the work"): a grid or a sweep past
`--max-evaluations` exits 2 naming the option, within a few seconds and a small memory, checked
in a separate process under an address-space limit."""

from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path

import pytest
from cli_runs import symkin_cli
from conftest import EXAMPLES, ROOT

import symkin
from symkin.core.errors import InputError
from symkin.studies import variation

FOUR_BAR = str(EXAMPLES / "four_bar.toml")
VARY = ["--vary", "l=±0.0001"]


@pytest.mark.parametrize(
    "argv, words",
    [
        (
            ["tolerance", FOUR_BAR, *VARY, "--input", "A0=-0.2:0.2:1000000000"],
            ["--input", "1e+09 evaluations", "limit of 1e+08", "--max-evaluations"],
        ),
        (
            ["sweep", FOUR_BAR, *VARY, "--input", "A0=-0.2:0.2:1000000", "--samples", "1000"],
            ["--input, --samples", "1000 samples", "1e+09 evaluations", "--max-evaluations"],
        ),
        (
            [
                "tolerance",
                FOUR_BAR,
                *VARY,
                "--input",
                "A0=-0.2:0.2:1001",
                "--max-evaluations",
                "1000",
            ],
            ["1001 (A0) = 1e+03 evaluations", "limit of 1e+03"],
        ),
        (
            ["tolerance", FOUR_BAR, *VARY, "--max-evaluations", "0"],
            ["--max-evaluations must be positive"],
        ),
    ],
)
def test_too_many_evaluations_exit_2_naming_the_option(argv, words):
    run = symkin_cli(*argv)
    assert run.returncode == 2, run.stderr
    assert "four_bar.toml" in run.stderr or "--max-evaluations" in run.stderr
    for w in words:
        assert w in run.stderr, run.stderr


def test_the_limit_counts_every_combination_and_the_memory():
    """Two inputs of 2e4 values each are 4e8 configurations: over the default, though neither
    alone is; the memory named is 8 bytes x (4 inputs + 2 x points) per evaluation."""
    mech = symkin.load(EXAMPLES / "nine_bar_platform.toml")
    counts = dict.fromkeys(mech.drives, 1)
    variation.check_evaluations(mech, {**counts, "O": 10**4}, limit=10**4)  # at the limit
    with pytest.raises(InputError) as err:
        variation.check_evaluations(mech, {**counts, "O": 2 * 10**4, "A": 2 * 10**4})
    text = str(err.value)
    assert "20000 (O) x 20000 (A) = 4e+08 evaluations" in text, text
    width = len(mech.drives) + 2 * len(mech.points)
    assert f"{4e8 * 8 * width / 1e9:.3g} GB" in text, text
    given = ["O=-0.1:0.1:3", "A=0:0.1:5", "B=0.01", "K=0.02"]
    grid = variation.parse_grid(given, mech, limit=15)
    assert len(grid.rows) == 15
    with pytest.raises(InputError):
        variation.parse_grid(given, mech, limit=14)


#: A refused command under 1.5 GB of address space (far below the 24 GB the refused grid would
#: take), started by a small Python process that reports the command's own peak memory (KB) on
#: stdout: a process started straight from a pytest worker counts the worker's pages in its
#: peak (the kernel keeps the largest memory a process held, its parent's image before exec too).
LIMITED = (
    "import os, resource, subprocess, sys\n"
    "resource.setrlimit(resource.RLIMIT_AS, (1536 * 2**20, 1536 * 2**20))\n"
    "proc = subprocess.Popen([sys.executable, '-m', 'symkin', *sys.argv[1:]])\n"
    "_, status, usage = os.wait4(proc.pid, 0)\n"
    "print(usage.ru_maxrss)\n"
    "sys.exit(os.waitstatus_to_exitcode(status))\n"
)


def test_a_refusal_is_quick_and_small_in_its_own_process(tmp_path):
    """The refusal's own process: under 5 s (on an idle machine) and 300 MB."""
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1")
    start = time.monotonic()
    run = subprocess.run(
        [sys.executable, "-c", LIMITED, "tolerance", FOUR_BAR, *VARY, "--input",
         "A0=-0.2:0.2:1000000000"],
        capture_output=True, text=True, cwd=ROOT, env=env, timeout=120,
    )  # fmt: skip
    took = time.monotonic() - start
    assert run.returncode == 2, run.stderr
    assert "more than the limit" in run.stderr
    assert took < 5 * 4, took  # 5 s on an idle machine; the suite's workers share the cores
    peak = int(run.stdout.split()[-1])
    assert 10 * 1024 < peak < 300 * 1024, peak  # KB: a Python process, under 300 MB


def test_read_input_takes_only_small_regular_files(tmp_path):
    """core.files.read_input: a FIFO, /dev/zero, a link to it, a folder and a file over the limit
    are refused before a byte is read (a FIFO would block forever); a file at the limit is read."""
    from symkin.core.files import Unreadable, read_input

    fifo = tmp_path / "pipe.toml"
    os.mkfifo(fifo)
    link = tmp_path / "zero.toml"
    link.symlink_to("/dev/zero")
    big = tmp_path / "big.toml"
    big.write_bytes(b"#" * 1025)
    ok = tmp_path / "ok.toml"
    ok.write_bytes(b"#" * 1024)
    for path, reason in [
        (fifo, "not a regular file (a device, FIFO or socket)"),
        (Path("/dev/zero"), "not a regular file (a device, FIFO or socket)"),
        (link, "not a regular file (a device, FIFO or socket)"),
        (tmp_path, "not a regular file (a folder)"),
        (big, "larger than 1024 bytes"),
        (tmp_path / "missing.toml", "cannot read the file (No such file or directory)"),
    ]:
        with pytest.raises(Unreadable) as err:
            read_input(path, 1024)
        assert err.value.reason == reason, path
    assert read_input(ok, 1024) == b"#" * 1024


def test_warnings_reach_the_user_as_one_line_without_library_paths(monkeypatch):
    """A warning raised inside the package (numpy's RuntimeWarning, say) prints as
    'symkin: warning: ...' with no path into the installed package; --debug keeps Python's."""
    import warnings

    from symkin.cli import commands

    def warn(args):
        warnings.warn("overflow encountered in multiply", RuntimeWarning, stacklevel=1)
        return "done\n"

    monkeypatch.setattr(commands, "_check", warn)
    run = symkin_cli("check", FOUR_BAR)
    assert run.returncode == 0 and run.stdout == "done\n"
    assert run.stderr == "symkin: warning: overflow encountered in multiply (RuntimeWarning)\n"
    debug = symkin_cli("--debug", "check", FOUR_BAR)
    assert "test_limits.py" in debug.stderr and "RuntimeWarning" in debug.stderr


@pytest.mark.parametrize(
    "make, words",
    [
        (lambda p: os.mkfifo(p), "not a regular file (a device, FIFO or socket)"),
        (lambda p: p.symlink_to("/dev/zero"), "not a regular file (a device, FIFO or socket)"),
        (lambda p: p.mkdir(), "not a regular file (a folder)"),
        (lambda p: p.write_bytes(b"# padding\n" * 110000), "larger than 1048576 bytes"),
    ],
    ids=["fifo", "link-to-dev-zero", "folder", "over-1-MiB"],
)
def test_the_mechanism_file_must_be_a_small_regular_file(tmp_path, make, words):
    """`check` on a FIFO returns at once (it blocked forever), on /dev/zero or a link to it
    without reading (4.4 GB in 10 s before), exit 2 naming the file."""
    path = tmp_path / "m.toml"
    make(path)
    start = time.monotonic()
    run = symkin_cli("check", str(path), timeout=30)
    assert time.monotonic() - start < 20
    assert run.returncode == 2, run.stderr
    assert str(path) in run.stderr and words in run.stderr, run.stderr


def test_dev_zero_itself_is_refused_unread():
    run = symkin_cli("check", "/dev/zero", timeout=30)
    assert run.returncode == 2 and "/dev/zero: not a regular file" in run.stderr, run.stderr


@pytest.mark.parametrize(
    "example, old, new, words",
    [
        ("four_bar.toml", 'name = "A0"', 'name = "A0=1"', "holds '=' or ','"),
        ("four_bar.toml", 'name = "A0"', 'name = "-A0"', "begins with '-'"),
        ("four_bar.toml", 'name = "B0"', 'name = "B0 "', "begins or ends with a blank"),
        ("four_bar.toml", 'name = "C"', 'name = "C,D"', "--points cannot name it"),
        ("piezo_amplifier.toml", 'name = "piezo"', 'name = "pie=zo"', "--input cannot name it"),
    ],
)
def test_names_the_command_line_cannot_express_exit_2_at_read_time(example, old, new, words):
    """An input named 'A0=1' could never be given as --input A0=1=0.1 (the error's own fix
    could not be followed): the reader refuses it, naming the entry and the fix."""
    text = (EXAMPLES / example).read_text()
    assert text.count(old) == 1
    with pytest.raises(InputError) as err:
        symkin.loads(text.replace(old, new), example)
    message = str(err.value)
    assert words in message and new.split('"')[1] in message and "fix:" in message, message


ARC_AS_EXPR = 'model = "expr"\nf = "l*sin(theta)/theta"\ng = "l*(1 - cos(theta))/theta"'


def _four_bar_with(model: str) -> str:
    text = (EXAMPLES / "four_bar.toml").read_text()
    assert text.count('model = "circular_arc"') == 1
    return text.replace('model = "circular_arc"', model)


@pytest.mark.parametrize("angle", ["0", "0.1", "-0.25"])
def test_an_expr_model_with_a_removable_singularity_is_evaluated_by_its_limit(angle):
    """docs' own circular arc written as an `expr` (sin θ/θ: 0/0 at θ = 0) crashed with
    ZeroDivisionError (exit 1) in every backend at the as-fabricated pose, where every hinge is
    at 0. Now each backend evaluates it there by its Taylor polynomial: 0 at A0 = 0, and the
    built-in circular_arc's deviation (its cancellation-free kernels: an independent
    evaluation of the same functions) to 1e-9 elsewhere."""
    from evaluators import rel_err, require_compiler

    expr = symkin.analyze(symkin.loads(_four_bar_with(ARC_AS_EXPR), "arc_expr.toml"))
    arc = symkin.analyze(symkin.load(FOUR_BAR))
    want = symkin.evaluate(arc, {"A0": angle}, "exact").points["C"].deviation
    require_compiler()
    for backend in ("sympy", "numpy", "c"):
        got = symkin.evaluate(expr, {"A0": angle}, "exact", backend=backend).points["C"]
        if angle == "0":
            assert got.deviation == (0.0, 0.0), backend
        else:
            assert rel_err(got.deviation, want) <= 1e-9, (backend, angle)


@pytest.mark.parametrize(
    "g, words",
    [
        ("l/theta", "'g': it has a pole at theta = 0"),
        ("l*theta**2/(theta - 2)", "'g' has a pole at theta = 2"),
        ("l*tan(theta)/2", "'g' has a pole at theta = -1.5708"),
        ("l*sqrt(theta)", "'g' is not a finite real number at theta = -3.14159"),
        ("l*theta**theta - l", "'g' is not a finite real number at theta = -3.14159"),
    ],
)
def test_an_expr_model_that_cannot_be_evaluated_on_a_half_turn_exits_2(g, words):
    """A pole at 0, a pole elsewhere on |θ| ≤ π, a complex value: refused when the file is read
    (θ**θ gave a TypeError, exit 1, at the first evaluation), naming the hinge and the key."""
    text = _four_bar_with(f'model = "expr"\nf = "l*sin(theta)/theta"\ng = "{g}"')
    with pytest.raises(InputError) as err:
        symkin.loads(text, "m.toml")
    message = str(err.value)
    assert words in message and "[[hinge]] #1 'A0'" in message and "fix:" in message, message


@pytest.mark.parametrize(
    "old, new, words",
    [
        ("at = [0.06, 0.09]", "at = [1e308, 1e308]", "[[point]] 'C': 'at' = 1.0e+308"),
        ("at = [0.06, 0.09]", "at = [1e151, 0.09]", "[[point]] 'C': 'at' = 1.0e+151"),
        ("E = 210e9", "E = 1e-300", "'E' = 1.0e-300"),
        ("E = 210e9", "E = 1e200", "'E' = 1.0e+200"),
        ('thickness = "l/10"', "thickness = 1e-160", "'thickness' = 1.0e-160"),
    ],
)
def test_magnitudes_whose_squares_leave_float64_exit_2_at_read_time(old, new, words):
    """A point at [1e308, 1e308] or E = 1e-300: the sympy backend answered while numpy and C
    refused with a message naming neither file nor entry; now every backend refuses alike, at
    read time, naming the entry (symkin.model.mechanism.MAGNITUDE)."""
    text = (EXAMPLES / "four_bar.toml").read_text()
    assert text.count(old) == 1
    with pytest.raises(InputError) as err:
        symkin.loads(text.replace(old, new), "m.toml")
    assert words in str(err.value) and "fix:" in str(err.value), str(err.value)


def test_a_parameter_given_later_is_checked_the_same_way():
    run = symkin_cli("eval", FOUR_BAR, "--input", "A0=0.1", "--param", "l=1e-200")
    assert run.returncode == 2
    assert "--param" in run.stderr and "'length' = 1.0e-200" in run.stderr, run.stderr


def test_a_table_row_far_beyond_a_plate_length_exits_2(tmp_path):
    """A row of 1e308 gave a NaN fit that `check` accepted and `eval` blamed on a toggle
    position: refused when the table is read, naming the file's row."""
    rows = "".join(f"{t / 10},{1 - (t / 10) ** 2 / 6},{t / 20}\n" for t in range(-5, 6))
    (tmp_path / "rows.csv").write_text("theta,f,g\n" + rows + "0.55,1e308,0.1\n")
    text = (
        (EXAMPLES / "four_bar.toml")
        .read_text()
        .replace(
            'plate_angle = "60*deg"',
            'plate_angle = "60*deg"\nmodel = "table"\nfile = "rows.csv"',
            1,
        )
    )
    (tmp_path / "m.toml").write_text(text)
    run = symkin_cli("check", str(tmp_path / "m.toml"))
    assert run.returncode == 2, run.stderr
    assert "rows.csv:13: a value beyond 1000 in magnitude" in run.stderr, run.stderr


def test_the_help_states_the_default_ceiling():
    """The parser does not import the studies (every command builds it): its help states the
    default in words, which must be the studies' own."""
    from symkin.cli.commands import parser

    text = parser().format_help() + "".join(
        action.format_help()
        for action in parser()._subparsers._group_actions[0].choices.values()
        if hasattr(action, "format_help")
    )
    assert "(default 1e8)" in text and variation.MAX_EVALUATIONS == 10**8
