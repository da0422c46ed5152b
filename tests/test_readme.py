"""README opens with the two commands a newcomer runs; CI runs the second one verbatim."""

from __future__ import annotations

import re

from conftest import ROOT


def readme_commands() -> list[str]:
    text = (ROOT / "README.md").read_text()
    return [block.strip() for block in re.findall(r"```sh\n(.*?)```", text, re.S)][:2]


def test_readme_opens_with_install_and_test_commands():
    run, test = readme_commands()
    assert run.startswith("pip install . ") and "symkin" in run and "examples/" in run
    assert test.startswith("pip install -e '.[test]'") and "pytest" in test


def test_ci_runs_exactly_readmes_test_command():
    _, test = readme_commands()
    ci = (ROOT / ".ci" / "run").read_text().splitlines()
    assert test in ci, "the last step of .ci/run must be README's test command, verbatim"
