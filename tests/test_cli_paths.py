"""Every user-supplied path: a mistake is bad input (exit 2, a fix line), found before any work,
with nothing half-written; `--debug` anywhere; Ctrl-C is one line and exit 130."""

from __future__ import annotations

import pytest
from conftest import EXAMPLES

import symkin.cli.commands as cli
from symkin.cli.commands import main

FOUR_BAR = str(EXAMPLES / "four_bar.toml")


def run(args, capsys):
    code = main(args)
    out, err = capsys.readouterr()
    return code, out, err


def test_derive_into_an_existing_file(tmp_path, capsys):
    target = tmp_path / "taken"
    target.write_text("keep me")
    code, _out, err = run(["derive", FOUR_BAR, "-o", str(target), "--emit", "numpy"], capsys)
    assert code == 2 and "is a file, not a folder" in err and "fix:" in err
    assert "deriving" not in err  # refused before any work
    assert target.read_text() == "keep me"


def test_derive_under_a_regular_file(tmp_path, capsys):
    blocker = tmp_path / "file"
    blocker.write_text("")
    code, _, err = run(["derive", FOUR_BAR, "-o", str(blocker / "sub" / "out"), "--quiet"], capsys)
    assert code == 2 and "fix:" in err and "is a file" in err


def test_derive_where_writing_fails(capsys):
    # /proc refuses new entries even to root, whom permission checks would let through.
    code, _, err = run(
        ["derive", FOUR_BAR, "-o", "/proc/symkin-out", "--emit", "numpy", "--quiet"], capsys
    )
    assert code == 2 and "fix:" in err and "Traceback" not in err


def test_derive_creates_missing_folders(tmp_path, capsys):
    code, _, _ = run(
        ["derive", FOUR_BAR, "-o", str(tmp_path / "a" / "b"), "--emit", "numpy", "--quiet"], capsys
    )
    assert code == 0 and (tmp_path / "a" / "b" / "four_bar.py").is_file()


@pytest.mark.parametrize(
    "plot, message",
    [
        ("/missing_dir/x.png", "does not exist"),
        ("{tmp}/plot.txt", "does not end in"),
        ("{tmp}", "is a folder"),
    ],
)
def test_tradeoff_plot_path_checked_before_work(tmp_path, capsys, plot, message):
    code, out, err = run(["tradeoff", FOUR_BAR, "--plot", plot.format(tmp=tmp_path)], capsys)
    assert code == 2 and message in err and "fix:" in err
    assert "reference:" not in err and "variant" not in err  # no work was done
    assert out == ""


def test_missing_mechanism_file(capsys):
    code, _, err = run(["eval", "/no/such/file.toml", "--input", "A0=0.1"], capsys)
    assert code == 2 and "fix:" in err


@pytest.mark.parametrize("where", ["before", "after"])
def test_debug_before_or_after_the_command(tmp_path, capsys, where):
    bad = tmp_path / "bad.toml"
    bad.write_text("format = 2\n")
    args = ["check", str(bad)]
    args = ["--debug", *args] if where == "before" else [*args, "--debug"]
    code, _, err = run(args, capsys)
    assert code == 2 and "Traceback" in err


def test_no_traceback_without_debug(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text("format = 2\n")
    code, _, err = run(["check", str(bad)], capsys)
    assert code == 2 and "Traceback" not in err


def test_ctrl_c_is_one_line_and_exit_130(monkeypatch, capsys):
    def interrupted(args):
        raise KeyboardInterrupt

    monkeypatch.setattr(cli, "_check", interrupted)
    code, out, err = run(["check", FOUR_BAR], capsys)
    assert code == 130 and err.strip() == "symkin: interrupted" and out == ""
