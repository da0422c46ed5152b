"""Shared fixtures: paths of the project and its examples, and work done once per run."""

from __future__ import annotations

import fcntl
import gc
import os
import shutil
import tempfile
from collections.abc import Callable
from pathlib import Path

import pytest
from strict_skips import (  # noqa: F401  (hooks: CI=true fails skips)
    pytest_make_collect_report,
    pytest_runtest_makereport,
)

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = ROOT / "examples"


def once_per_run(tmp_path_factory, name: str, build: Callable[[Path], None]) -> Path:
    """A folder that build(folder) filled once in this test run: under xdist the first worker to
    ask builds it (the others wait on a lock, then read it), so a module fixture whose tests land
    on several workers is computed once, not once per worker."""
    root = tmp_path_factory.getbasetemp()
    if os.environ.get("PYTEST_XDIST_WORKER"):
        root = root.parent  # the run's folder, shared by its workers
    folder = root / f"once-{name}"
    with open(root / f"once-{name}.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)  # released when the file closes
        if not (folder / ".done").exists():
            folder.mkdir(exist_ok=True)
            build(folder)
            (folder / ".done").touch()
    return folder


def pytest_configure(config):
    """One compiled-code and plan cache for the run (docs/cli.md), empty at its start and removed
    at its end: shared by the xdist workers and the CLI subprocesses (they inherit it), never the
    user's own, so a run measures a fresh machine's cost. The generated C is compiled with -O0
    (SYMKIN_CFLAGS, docs/cli.md): 3-7 times faster to build, the same IEEE arithmetic;
    tests/test_compile_flags.py builds every example with the users' -O2 too and compares.
    sympy's cache keeps 100000 results per function instead of 1000 (SYMPY_CACHE_SIZE, read when
    sympy is imported: the workers and subprocesses inherit it): the run's derivations revisit
    the same expressions (9-25 % off the loaded-level and codegen test files measured)."""
    if os.environ.get("PYTEST_XDIST_WORKER"):
        return
    if "SYMPY_CACHE_SIZE" not in os.environ:
        os.environ["SYMPY_CACHE_SIZE"] = "100000"
        config._symkin_sympy_cache = True
    if "SYMKIN_CFLAGS" not in os.environ:
        os.environ["SYMKIN_CFLAGS"] = "-O0"
        config._symkin_cflags = True
    if os.environ.get("SYMKIN_CACHE"):
        return
    folder = tempfile.mkdtemp(prefix="symkin-test-cache-")
    os.environ["SYMKIN_CACHE"] = folder
    config._symkin_cache = folder


def pytest_unconfigure(config):
    if getattr(config, "_symkin_cflags", False):
        os.environ.pop("SYMKIN_CFLAGS", None)
    if getattr(config, "_symkin_sympy_cache", False):
        os.environ.pop("SYMPY_CACHE_SIZE", None)
    folder = getattr(config, "_symkin_cache", None)
    if folder:
        shutil.rmtree(folder, ignore_errors=True)
        os.environ.pop("SYMKIN_CACHE", None)


@pytest.hookimpl(trylast=True)
def pytest_runtest_teardown(item, nextitem):
    """After the test's fixtures are torn down (trylast), what survived it joins the collector's
    permanent generation (gc.freeze): the workers' heaps grow to millions of objects (sympy's
    caches, the kept plans and solvers), and each full collection traversed them all again
    (9-10 % of the loaded-level and report test files' time measured, 0.5 s a collection).
    Young objects are still collected; cyclic garbage a test left to the full collections
    stays (+12 % peak memory measured)."""
    gc.freeze()


def pytest_addoption(parser):
    parser.addoption(
        "--update",
        action="store_true",
        default=False,
        help="rewrite generated/ from examples/ instead of comparing",
    )


#: The slowest tests (node id prefixes, slowest first; measured with --durations). Under xdist
#: (`-n auto` in pyproject's addopts) they are handed out first, so the run does not end with one
#: worker busy on a long test while the others idle. test_scene's derived scene and
#: test_tradeoff's table are built once per run (once_per_run), whichever worker asks first.
SLOW_FIRST = (
    "tests/test_scale.py",
    "tests/test_structure_properties.py::test_structure_identities",
    "tests/test_namespaces.py::test_parameters_named_like_internal_symbols",
    "tests/test_scene.py",
    "tests/test_packaging.py::test_readme_first_command_in_a_fresh_venv",
    "tests/test_pruning.py::test_kept_hinges_are_exactly_those_that_move_the_points",
    "tests/test_latex.py::test_appendix_fits_a_two_column_paper[nine_bar_platform]",
    "tests/test_latex.py::test_files_header_and_figures[nine_bar_platform]",
    "tests/test_latex.py::test_byte_identical_across_processes_and_hash_seeds",
    "tests/test_tradeoff.py",
    "tests/test_notch_beams.py::test_notch_four_bar_at_equilibrium_and_its_stress",
    "tests/test_notch_beams.py::test_notch_parallelogram_at_equilibrium_translates",
    "tests/test_notch_mechanisms_fea.py::test_equilibrium_within_3_percent_of_calculix",
    "tests/test_notch_loaded.py::test_loaded_within_one_percent_of_equilibrium",
    "tests/test_generated.py::test_generated_matches_derive[nine_bar_platform]",
    "tests/test_fuzz.py::test_fuzzed_mechanisms_never_crash",
    "tests/test_angle_tracking.py::test_every_backend_follows_the_oracle_over_the_input_range",
    "tests/test_imports.py::test_every_module_has_a_floor",
    "tests/test_latex.py::test_two_reports_input_into_one_paper",
    "tests/test_files_and_cache.py::test_a_planted_or_corrupt_library_is_rebuilt_not_loaded",
    "tests/test_sensitivity.py::test_every_backend_against_central_differences",
    "tests/test_latex.py::test_files_header_and_figures",
    "tests/test_latex.py::test_tolerance_choice_is_in_the_rendered_report",
    "tests/test_files_and_cache.py::test_killed_derive_leaves_old_or_new_files",
    "tests/test_hinge_models.py::test_elastica_carlson_equals_legendre_rewrite",
    "tests/test_codegen.py::test_derive_is_deterministic_across_hash_seeds",
)


def pytest_collection_modifyitems(config, items):
    """Run the slowest tests first (stable: the rest keep their order)."""

    def rank(item) -> int:
        for i, prefix in enumerate(SLOW_FIRST):
            if item.nodeid.startswith(prefix):
                return i
        return len(SLOW_FIRST)

    items.sort(key=rank)
