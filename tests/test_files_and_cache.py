"""Files symkin writes and code it loads: `derive` writes all or none, even when killed or raced;
the compiled-code cache is verified, not trusted; generated numpy modules are never read back
from disk (docs/cli.md: `derive`, SYMKIN_CACHE)."""

from __future__ import annotations

import hashlib
import json
import os
import random
import shutil
import signal
import stat
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest
from conftest import EXAMPLES
from evaluators import rel_err, require_compiler
from reference_solver import Reference

import symkin
from symkin.codegen import pipeline
from symkin.codegen.toolchain import import_numpy_module
from symkin.core.files import COMMIT, TEMP_PREFIX, complete_interrupted, write_atomically

FOUR_BAR = EXAMPLES / "four_bar.toml"
ROOT = Path(__file__).resolve().parent.parent


def cli(*args: str, cache: Path, timeout: float = 300) -> subprocess.CompletedProcess:
    env = {**os.environ, "SYMKIN_CACHE": str(cache)}
    return subprocess.run(
        [sys.executable, "-m", "symkin", *args],
        capture_output=True,
        text=True,
        env=env,
        timeout=timeout,
        cwd=ROOT,
    )


def deviation(stdout: str) -> list[float]:
    return json.loads(stdout)["points"]["C"]["deviation"]


#: the oracle is the kinematic model's: the file's plates have E, thickness and width, so eval's
#: default level is loaded (docs/levels.md, "The default level")
EXACT = ("--level", "exact")


def oracle() -> list:
    return Reference(symkin.load(FOUR_BAR)).deviation({"A0": "0.2"})["points"]["C"]["deviation"]


# -- the compiled-code cache -------------------------------------------------------------------

PLANTED = r"""
#include <stdio.h>
__attribute__((constructor)) static void planted(void)
{
    FILE *f = fopen("MARKER", "w");
    if (f) { fputs("ran", f); fclose(f); }
}
int four_bar_evaluate_angles(const double *i, const double *p, int l, double *o, double *a)
{
    (void)i; (void)p; (void)l; (void)a; o[4] = 42.0; o[5] = 42.0; return 0;
}
"""


def planted_library(tmp_path: Path, marker: Path) -> bytes:
    source = tmp_path / "planted.c"
    source.write_text(PLANTED.replace("MARKER", str(marker)))
    out = tmp_path / "planted.so"
    subprocess.run(
        [os.environ.get("CC", "cc"), "-shared", "-fPIC", str(source), "-o", str(out)], check=True
    )
    return out.read_bytes()


def test_cache_is_created_private(tmp_path):
    require_compiler()
    cache = tmp_path / "new" / "cache"
    result = cli(
        "eval", str(FOUR_BAR), "--input", "A0=0.2", *EXACT, "--backend", "c", "--json", cache=cache
    )
    assert result.returncode == 0, result.stderr
    assert stat.S_IMODE(cache.stat().st_mode) == 0o700
    assert rel_err(deviation(result.stdout), oracle()) <= 1e-9


def test_a_planted_or_corrupt_library_is_rebuilt_not_loaded(tmp_path):
    require_compiler()
    cache = tmp_path / "cache"
    first = cli(
        "eval", str(FOUR_BAR), "--input", "A0=0.2", *EXACT, "--backend", "c", "--json", cache=cache
    )
    assert first.returncode == 0, first.stderr
    [library] = cache.glob("four_bar-*.so")
    marker = tmp_path / "marker"
    for content in (planted_library(tmp_path, marker), library.read_bytes()[:1000], b""):
        library.write_bytes(content)  # same name, planted or truncated
        again = cli(
            "eval",
            str(FOUR_BAR),
            "--input",
            "A0=0.2",
            *EXACT,
            "--backend",
            "c",
            "--json",
            cache=cache,
        )
        assert again.returncode == 0, again.stderr
        assert not marker.exists(), "the planted library's constructor ran"
        assert rel_err(deviation(again.stdout), oracle()) <= 1e-9


@pytest.mark.parametrize("how", ["others_can_write", "someone_elses"])
def test_an_unsafe_cache_is_refused(tmp_path, how):
    require_compiler()
    cache = tmp_path / "cache"
    cache.mkdir()
    if how == "others_can_write":
        cache.chmod(0o777)
    else:
        if os.getuid() != 0:
            pytest.skip("giving a folder to another user needs root")
        os.chown(cache, 65534, 65534)
    result = cli("eval", str(FOUR_BAR), "--input", "A0=0.2", "--backend", "c", cache=cache)
    assert result.returncode == 2, result.stderr
    assert "SYMKIN_CACHE" in result.stderr and "fix:" in result.stderr
    assert list(cache.iterdir()) == []


def test_an_unusable_cache_is_bad_input(tmp_path):
    require_compiler()
    blocker = tmp_path / "file"
    blocker.write_text("")
    for cache in (Path("/proc/symkin-cache"), blocker / "cache"):
        result = cli("eval", str(FOUR_BAR), "--input", "A0=0.2", "--backend", "c", cache=cache)
        assert result.returncode == 2, result.stderr
        assert "SYMKIN_CACHE" in result.stderr and "fix:" in result.stderr


def test_no_numpy_module_is_read_from_the_cache(tmp_path):
    """Where symkin used to keep generated modules (cache/numpy/<name>_<sha256[:20]>.py), a
    planted or truncated file is never executed."""
    cache = tmp_path / "cache"
    an = symkin.analyze(symkin.load(FOUR_BAR))
    (source,) = pipeline.emit(pipeline.plan_for(an), "numpy", FOUR_BAR.name)
    digest = hashlib.sha256(source.encode()).hexdigest()[:20]
    (cache / "numpy").mkdir(parents=True)
    marker = tmp_path / "marker"
    planted = cache / "numpy" / f"four_bar_{digest}.py"
    planted.write_text(f"open({str(marker)!r}, 'w').write('ran')\n")
    result = cli(
        "eval",
        str(FOUR_BAR),
        "--input",
        "A0=0.2",
        *EXACT,
        "--backend",
        "numpy",
        "--json",
        cache=cache,
    )
    assert result.returncode == 0, result.stderr
    assert not marker.exists()
    assert rel_err(deviation(result.stdout), oracle()) <= 1e-9


def test_threads_import_one_module_at_once():
    source = (
        pipeline.emit(pipeline.plan_for(symkin.analyze(symkin.load(FOUR_BAR))), "numpy", "threads")[
            0
        ]
        + f"\n# {random.random()}\n"
    )  # a text no earlier test imported
    start = threading.Barrier(9)
    modules, errors = [], []

    def worker():
        start.wait()
        try:
            modules.append(import_numpy_module(source, "four_bar_threads"))
        except Exception as exc:
            errors.append(exc)

    threads = [threading.Thread(target=worker) for _ in range(9)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert errors == [] and len(modules) == 9 and len({id(m) for m in modules}) == 1


# -- derive: all or none -----------------------------------------------------------------------


def version(tag: str, size: int) -> dict[str, bytes]:
    """A set of files whose every byte says which write it belongs to."""
    names = ["m.c", "m.h", "m.py", "m.tex", "m-pose.pdf", "m-graph.pdf", "m-deviation.pdf"]
    return {n: (tag.encode() * (size // len(tag) + 1))[:size] for n in names}


def tags(folder: Path) -> set[str]:
    """The writes the visible generated files come from."""
    return {p.read_bytes()[:4].decode() for p in folder.iterdir() if not p.name.startswith(".")}


def test_killed_writes_leave_the_old_set_or_the_new(tmp_path):
    """Writers killed at random points (SIGKILL, seeded): the folder holds one complete set, or
    a commit that the next writer completes; temporary folders never outlive the next write."""
    rng = random.Random(7)
    folder = tmp_path / "out"
    write_atomically(version("old0", 1 << 20), folder)
    kills = {"before": 0, "after": 0, "completed": 0}
    for k in range(20):
        new = f"new{k % 10}"
        pid = os.fork()
        if pid == 0:  # the writer
            try:
                write_atomically(version(new, 4 << 20), folder)
            finally:
                os._exit(0)
        time.sleep(rng.uniform(0.0, 0.08))
        os.kill(pid, signal.SIGKILL)
        os.waitpid(pid, 0)
        visible = tags(folder)
        if (folder / COMMIT).exists():
            kills["after"] += 1
            complete_interrupted(folder)
            assert tags(folder) == {new}
        elif visible == {new}:
            kills["completed"] += 1
        else:
            kills["before"] += 1
            assert len(visible) == 1, visible
        write_atomically(version("old0", 1 << 20), folder)
        assert tags(folder) == {"old0"}
        assert not list(folder.glob(TEMP_PREFIX + "*")) and not (folder / COMMIT).exists()
    assert kills["before"] > 0  # the test did kill writes midway


def test_concurrent_writers_never_mix(tmp_path):
    rounds = 10
    for r in range(rounds):
        folder = tmp_path / f"new{r}"  # a new folder, four writers at once
        start = threading.Barrier(4)
        errors = []

        def writer(tag: str) -> None:
            start.wait()
            try:
                write_atomically(version(tag, 1 << 16), folder)
            except Exception as exc:
                errors.append(exc)

        threads = [threading.Thread(target=writer, args=(f"w{n}{r}",)) for n in range(4)]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        assert errors == []
        assert len(tags(folder)) == 1
        assert [p.name for p in folder.iterdir() if p.name.startswith(".")] == []


def test_killed_derive_leaves_old_or_new_files(tmp_path):
    """The command itself, killed at random points while deriving into a folder that holds an
    earlier derivation (of another plate length)."""
    rng = random.Random(3)
    folder = tmp_path / "out"
    cache = tmp_path / "cache"
    other = tmp_path / "four_bar.toml"
    other.write_text(FOUR_BAR.read_text().replace("l = 1e-3", "l = 2e-3", 1))
    assert (
        cli(
            "derive", str(other), "-o", str(folder), "--emit", "numpy,c", "--quiet", cache=cache
        ).returncode
        == 0
    )
    old = {p.name: p.read_bytes() for p in folder.iterdir()}
    assert (
        cli(
            "derive",
            str(FOUR_BAR),
            "-o",
            str(tmp_path / "ref"),
            "--emit",
            "numpy,c",
            "--quiet",
            cache=cache,
        ).returncode
        == 0
    )
    new = {p.name: p.read_bytes() for p in (tmp_path / "ref").iterdir()}
    assert old.keys() == new.keys() and old != new
    # the killed runs read the kept plan, as this one does: their kills are spread over its
    # duration (a kill after the run is over tests nothing)
    start = time.perf_counter()
    warm = cli(
        "derive", str(FOUR_BAR), "-o", str(tmp_path / "warm"), "--emit", "numpy,c", cache=cache
    )
    assert warm.returncode == 0
    duration = time.perf_counter() - start
    env = {**os.environ, "SYMKIN_CACHE": str(cache)}
    killed = 0
    for _ in range(4):
        # each run starts from the earlier derivation: a torn write shows as neither old nor new
        shutil.rmtree(folder)
        folder.mkdir()
        for name, content in old.items():
            (folder / name).write_bytes(content)
        proc = subprocess.Popen(
            [
                sys.executable,
                "-m",
                "symkin",
                "derive",
                str(FOUR_BAR),
                "-o",
                str(folder),
                "--emit",
                "numpy,c",
                "--quiet",
            ],
            env=env,
            cwd=ROOT,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
        time.sleep(rng.uniform(0.3, 1.1) * duration)
        proc.kill()
        killed += proc.wait() == -signal.SIGKILL
        complete_interrupted(folder)
        now = {p.name: p.read_bytes() for p in folder.iterdir()}
        assert now in (old, new)
    assert killed, "every run had ended before its kill: nothing was interrupted"
