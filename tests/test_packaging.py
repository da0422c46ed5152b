"""A fresh venv (no system site packages) runs README's first command literally, from a copy of
the project, and the installed wheel derives and evaluates through every backend.

This is what a newcomer does first; it once failed because pyproject listed packages by hand and
left symkin.codegen out of the wheel.
"""

from __future__ import annotations

import json
import os
import pathlib
import re
import shutil
import subprocess
import venv

from conftest import ROOT
from evaluators import BACKENDS, GENERATED
from test_readme import readme_commands

from symkin.codegen.templating import _sections

IGNORED = shutil.ignore_patterns(
    ".git",
    "build",
    "dist",
    "*.egg-info",
    "__pycache__",
    ".venv*",
    ".hypothesis",
    ".pytest_cache",
    "generated",
)


def test_readme_first_command_in_a_fresh_venv(tmp_path):
    project = tmp_path / "symkin"
    shutil.copytree(ROOT, project, ignore=IGNORED)
    env_dir = tmp_path / "venv"
    venv.EnvBuilder(system_site_packages=False, with_pip=True).create(env_dir)
    bin_dir = env_dir / "bin"
    env = {
        **os.environ,
        "PATH": f"{bin_dir}{os.pathsep}{os.environ['PATH']}",
        "SYMKIN_CACHE": str(tmp_path / "cache"),
        "VIRTUAL_ENV": str(env_dir),
    }
    env.pop("PYTHONPATH", None)
    first, _ = readme_commands()
    run = subprocess.run(
        ["bash", "-c", first], cwd=project, env=env, capture_output=True, text=True
    )
    assert run.returncode == 0, run.stderr[-3000:]
    assert "point C" in run.stdout and "deviation" in run.stdout

    def symkin(*args: str) -> str:
        proc = subprocess.run(
            [str(bin_dir / "symkin"), *args], cwd=tmp_path, env=env, capture_output=True, text=True
        )
        assert proc.returncode == 0, (args, proc.stderr[-3000:])
        return proc.stdout

    # The package came from the built wheel, not from the source tree.
    where = subprocess.run(
        [str(bin_dir / "python"), "-c", "import symkin; print(symkin.__file__)"],
        cwd=tmp_path,
        env=env,
        capture_output=True,
        text=True,
        check=True,
    )
    assert where.stdout.startswith(str(env_dir)), where.stdout
    # Every module and template of the source tree is in the installed package.
    installed = pathlib.Path(where.stdout.strip()).parent
    for pattern, root in (
        ("*.py", ROOT / "symkin"),
        ("*.j2", ROOT / "templates"),
        ("*.c", ROOT / "templates"),  # the runtimes the generated files hold
        ("*.py", ROOT / "templates"),
    ):
        found = [f for f in root.rglob(pattern) if "__pycache__" not in f.parts]
        assert found, (pattern, root)
        for f in found:
            target = (
                installed / ("templates" if root.name == "templates" else "") / f.relative_to(root)
            )
            assert target.is_file(), f"{f.relative_to(ROOT)} is missing from the wheel"
    example = str(project / "examples" / "four_bar.toml")
    written = symkin("derive", example, "-o", str(tmp_path / "out"), "--quiet").split()
    assert {os.path.basename(p) for p in written} >= {
        "four_bar.c",
        "four_bar.h",
        "four_bar.py",
        "four_bar.tex",
    }
    results = {
        b: json.loads(symkin("eval", example, "--input", "A0=0.2", "--backend", b, "--json"))[
            "points"
        ]["C"]["deviation"]
        for b in BACKENDS
    }
    for backend in GENERATED:
        assert all(
            abs(a - b) <= 1e-15 * abs(b) + 1e-22 for a, b in zip(results[backend], results["sympy"])
        ), backend
    # The templates (package data of symkin.templates) ship inside the wheel.
    matrices = symkin("matrices", example)
    assert "incidence I" in matrices
    # The installed package reads its runtimes: the generated files hold them verbatim, the C
    # runtime with its optional sections resolved for the sections the four-bar runs.
    for name, runtime in (("four_bar.c", "c/runtime.c"), ("four_bar.py", "numpy/runtime.py")):
        text = (installed / "templates" / runtime).read_text()
        body = text.split("symkin runtime: every generated", 1)[1].split("\n", 1)[1].lstrip("\n")
        generated = (tmp_path / "out" / name).read_text()
        if name.endswith(".c"):
            macros = sorted(set(re.findall(r"defined\((SK_\w+)\)", body)))
            bodies = [
                _sections(body, frozenset(m for i, m in enumerate(macros) if used >> i & 1))
                for used in range(1 << len(macros))
            ]
            assert any(b in generated for b in bodies), name
        else:
            assert body and body in generated, name
