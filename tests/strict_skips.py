"""Under CI=true a skipped test is a failed test: .ci/run installs every tool the suite needs (a
C compiler, TeX Live, poppler, CalculiX) and every package it imports, so a skip there means a
missing install step, not a check that may be left out. conftest.py takes the hooks from here;
tests/test_strict_skips.py runs them on test files of their own."""

from __future__ import annotations

import os

import pytest


def _fail_a_skip(report, what: str) -> None:
    """Make a skipped report a failed one naming the skip's reason, when CI=true."""
    if os.environ.get("CI") != "true" or not report.skipped or hasattr(report, "wasxfail"):
        return
    longrepr = report.longrepr
    reason = longrepr[2] if isinstance(longrepr, tuple) and len(longrepr) == 3 else str(longrepr)
    report.outcome = "failed"
    report.longrepr = (
        f"skipped under CI=true ({reason}): CI {what}, so .ci/run must install what this one needs"
    )


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item, call):
    """Turn a skip (a `skip` call, `skipif`, `importorskip`) into a failure when CI=true; an
    expected failure (`xfail`) stays what it is."""
    outcome = yield
    _fail_a_skip(outcome.get_result(), "runs every test")


@pytest.hookimpl(hookwrapper=True)
def pytest_make_collect_report(collector):
    """The same at collection: a module-level `importorskip` or `skip(allow_module_level=True)`
    fails its module under CI=true instead of dropping every test in it."""
    outcome = yield
    _fail_a_skip(outcome.get_result(), "collects every test module")
