"""symkin's command line run in the test's own process, returning what `python -m symkin` would
(exit code, stdout, stderr) without a second interpreter's start (~1 s each, sympy's import) and
with this worker's derivations at hand. Tests of what only a separate process shows (the entry
point, hash seeds, two processes at once, a killed run, the disk caches) keep subprocess."""

from __future__ import annotations

import contextlib
import io
import os
import signal
import subprocess
import threading
import traceback
import warnings
from collections.abc import Iterator, Mapping
from pathlib import Path

from symkin.cli import main

#: warnings a fresh interpreter's default filters do not print (outside __main__)
_SILENT = (DeprecationWarning, PendingDeprecationWarning, ImportWarning, ResourceWarning)


class _Timeout(BaseException):
    """Raised by the alarm; a BaseException, so the CLI's `except Exception` lets it through."""


@contextlib.contextmanager
def _alarm(seconds: float | None) -> Iterator[None]:
    """subprocess.run's timeout, in this process: SIGALRM (the main thread only)."""
    if seconds is None or threading.current_thread() is not threading.main_thread():
        yield
        return

    def ring(signum, frame):
        raise _Timeout

    old = signal.signal(signal.SIGALRM, ring)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)


@contextlib.contextmanager
def _environment(cwd: str | Path | None, env: Mapping[str, str] | None) -> Iterator[None]:
    """The working directory and environment variables for one run, restored after it."""
    here = os.getcwd()
    saved = dict(os.environ)
    try:
        if env is not None:
            os.environ.update(env)
        if cwd is not None:
            os.chdir(cwd)
        yield
    finally:
        os.chdir(here)
        os.environ.clear()
        os.environ.update(saved)


def symkin_cli(
    *args: str,
    cwd: str | Path | None = None,
    env: Mapping[str, str] | None = None,
    timeout: float | None = None,
) -> subprocess.CompletedProcess:
    """`symkin *args` as subprocess.run(capture_output=True, text=True) returns it: `env` adds
    to the environment; warnings go to stderr as an interpreter's default filters print them;
    an exception escaping the CLI is a traceback on stderr and exit 1; past `timeout`
    subprocess.TimeoutExpired."""
    argv = [str(a) for a in args]
    out, err = io.StringIO(), io.StringIO()
    with (
        _environment(cwd, env),
        contextlib.redirect_stdout(out),
        contextlib.redirect_stderr(err),
        warnings.catch_warnings(record=True) as caught,
    ):
        warnings.simplefilter("always")
        try:
            with _alarm(timeout):
                code = main(argv)
        except _Timeout:
            raise subprocess.TimeoutExpired(["symkin", *argv], timeout or 0.0) from None
        except SystemExit as stop:  # argparse: usage errors, --help
            code = stop.code if isinstance(stop.code, int) else (0 if stop.code is None else 1)
            if isinstance(stop.code, str):
                err.write(stop.code + "\n")
        except Exception:
            traceback.print_exc(file=err)
            code = 1
    shown = "".join(
        warnings.formatwarning(w.message, w.category, w.filename, w.lineno, w.line)
        for w in caught
        if not issubclass(w.category, _SILENT)
    )
    return subprocess.CompletedProcess(
        ["symkin", *argv], code, out.getvalue(), err.getvalue() + shown
    )
