"""The suite's rule that a test needing a tool fails, not skips, under CI=true
(tests/strict_skips.py), checked on a small test file of its own in a separate pytest run."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

TESTS = Path(__file__).resolve().parent

CASES = """
import pytest

def test_skip_call():
    pytest.skip("no frobnicator")

@pytest.mark.skipif(True, reason="frobnicator missing")
def test_skipif_mark():
    pass

def test_importorskip():
    pytest.importorskip("a_module_that_is_not_there")

@pytest.mark.xfail(reason="known", strict=True)
def test_expected_failure():
    assert False

def test_passes():
    pass
"""


def _run(tmp_path: Path, ci: str | None) -> subprocess.CompletedProcess[str]:
    (tmp_path / "test_cases.py").write_text(CASES)
    env = {k: v for k, v in os.environ.items() if k not in ("CI", "PYTEST_ADDOPTS")}
    env["PYTHONPATH"] = os.pathsep.join([str(TESTS), env.get("PYTHONPATH", "")])
    if ci is not None:
        env["CI"] = ci
    return subprocess.run(
        [sys.executable, "-m", "pytest", "-p", "strict_skips", "-p", "no:cacheprovider",
         "-o", "addopts=", "-q", "-rA", "test_cases.py"],
        cwd=tmp_path, env=env, capture_output=True, text=True, timeout=120,
    )  # fmt: skip


@pytest.mark.parametrize("ci", ["true", None])
def test_skips_fail_under_ci_only(tmp_path, ci):
    run = _run(tmp_path, ci)
    out = run.stdout
    if ci == "true":
        assert run.returncode == 1, out
        # a skip in the test's call fails it; a `skipif` is decided in its setup: an error
        assert "2 failed, 1 passed, 1 xfailed, 1 error" in out, out
        for reason in (
            "no frobnicator",
            "frobnicator missing",
            "could not import 'a_module_that_is_not_there'",
        ):
            assert f"skipped under CI=true (Skipped: {reason}" in out, out
    else:
        assert run.returncode == 0, out
        assert "1 passed, 3 skipped, 1 xfailed" in out, out


def test_the_suite_uses_the_hook():
    """conftest.py takes the hook, so every test of the suite is under the rule."""
    import conftest
    from strict_skips import pytest_runtest_makereport

    assert conftest.pytest_runtest_makereport is pytest_runtest_makereport


def test_a_module_skipped_at_collection_fails_under_ci(tmp_path):
    (tmp_path / "test_module.py").write_text(
        'import pytest\n\npytest.importorskip("a_module_that_is_not_there")\n\n\n'
        "def test_never():\n    pass\n"
    )
    env = {k: v for k, v in os.environ.items() if k not in ("CI", "PYTEST_ADDOPTS")}
    env["PYTHONPATH"] = os.pathsep.join([str(TESTS), env.get("PYTHONPATH", "")])
    argv = [sys.executable, "-m", "pytest", "-p", "strict_skips", "-p", "no:cacheprovider"]
    argv += ["-o", "addopts=", "-q", "test_module.py"]
    # (pytest exits 5 when a run collects no test: the module skipped whole)
    for ci, code, words in ((None, 5, "1 skipped"), ("true", 2, "skipped under CI=true")):
        run = subprocess.run(
            argv, cwd=tmp_path, env=env | ({"CI": ci} if ci else {}), capture_output=True,
            text=True, timeout=120,
        )  # fmt: skip
        assert run.returncode == code and words in run.stdout, run.stdout
