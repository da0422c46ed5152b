"""README opens with the two commands a newcomer runs; CI runs the second one verbatim; its worked
example and table are what `symkin eval` prints."""

from __future__ import annotations

import json
import re
import shlex

import pytest
from cli_runs import symkin_cli
from conftest import ROOT


def readme_commands() -> list[str]:
    text = (ROOT / "README.md").read_text()
    return [block.strip() for block in re.findall(r"```sh\n(.*?)```", text, re.S)][:2]


def test_readme_opens_with_install_and_test_commands():
    run, test = readme_commands()
    assert run.startswith("pip install . ") and "symkin" in run and "examples/" in run
    assert test.startswith("pip install -e '.[test]'") and "pytest" in test


def worked_example() -> tuple[list[str], str]:
    """README's worked example: the command after `$ ` and the output printed under it."""
    text = (ROOT / "README.md").read_text()
    block = next(b for b in re.findall(r"```text\n(.*?)```", text, re.S) if b.startswith("$ "))
    command, output = block.split("\n", 1)
    return shlex.split(command[2:]), output


def test_the_worked_example_is_what_the_command_prints():
    argv, output = worked_example()
    assert argv[0] == "symkin"
    run = symkin_cli(*argv[1:], cwd=ROOT)
    assert run.returncode == 0, run.stderr
    assert run.stdout == output


def level_rows() -> dict[str, tuple[str, str]]:
    """The worked example's table: level -> (deviation, |dR|) as README prints them."""
    text = (ROOT / "README.md").read_text()
    rows = re.findall(r"^\| `(\w+)` \| (\([^)]*\)) \| ([0-9.e+-]+) \|$", text, re.M)
    return {level: (dev, size) for level, dev, size in rows}


def test_the_worked_example_table_has_every_level():
    from symkin.core.levels import NAMES

    assert tuple(level_rows()) == NAMES


@pytest.mark.parametrize("level", sorted(level_rows()))
def test_the_worked_example_table_is_what_eval_prints(level):
    """Each row is `eval --level L` at the example's input, rounded to four digits."""
    argv, _ = worked_example()
    run = symkin_cli(*argv[1:], "--level", level, "--json", cwd=ROOT)
    assert run.returncode == 0, run.stderr
    deviation = json.loads(run.stdout)["points"]["C"]["deviation"]
    dev, size = level_rows()[level]
    assert dev == "(" + ", ".join(f"{v:.3e}" for v in deviation) + ")"
    assert size == f"{(deviation[0] ** 2 + deviation[1] ** 2) ** 0.5:.3e}"


def test_ci_runs_exactly_readmes_test_command():
    _, test = readme_commands()
    ci = (ROOT / ".ci" / "run").read_text().splitlines()
    assert test in ci, "the last step of .ci/run must be README's test command, verbatim"


def test_ci_stops_at_a_failing_static_check():
    """Each static check is a command of its own: under `set -e` a failure on the left of `&&`
    does not stop the script (ruff's findings once went by so)."""
    lines = [ln.strip() for ln in (ROOT / ".ci" / "run").read_text().splitlines()]
    assert "set -euo pipefail" in lines
    for check in ("ruff check .", "ruff format --check .", "mypy"):
        assert check in lines, check
    checks = [ln for ln in lines if ln.split(" ", 1)[0] in ("ruff", "mypy")]
    assert all("&&" not in ln and "||" not in ln for ln in checks), checks


def test_ci_builds_a_fresh_venv_before_the_test_command():
    lines = (ROOT / ".ci" / "run").read_text().splitlines()
    _, test = readme_commands()
    venv_line = next(i for i, ln in enumerate(lines) if "-m venv" in ln)
    activate = next(i for i, ln in enumerate(lines) if "/bin/activate" in ln)
    assert "--system-site-packages" not in lines[venv_line]
    assert venv_line < activate < lines.index(test)


def test_under_ci_the_tests_run_in_a_venv_without_system_site_packages():
    """What .ci/run promises, checked from inside the test process itself."""
    import os
    import sys
    from pathlib import Path

    if os.environ.get("CI") != "true":
        return
    cfg = Path(sys.prefix) / "pyvenv.cfg"
    assert sys.prefix != sys.base_prefix and cfg.is_file(), "CI must run the tests in a venv"
    settings = {
        key.strip(): value.strip()
        for key, value in (
            line.split("=", 1) for line in cfg.read_text().splitlines() if "=" in line
        )
    }
    assert settings.get("include-system-site-packages") == "false"
