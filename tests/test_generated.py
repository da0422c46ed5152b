"""generated/ holds `symkin derive` output for every example, byte for byte (SymForce style).

On a difference the test fails with a unified diff; `pytest --update` rewrites generated/.
"""

from __future__ import annotations

import difflib

import pytest
from conftest import EXAMPLES, ROOT

import symkin
from symkin.studies.derive import generate, write_atomically

GENERATED = ROOT / "generated"


@pytest.mark.parametrize("example", sorted(p.stem for p in EXAMPLES.glob("*.toml")))
def test_generated_matches_derive(example, request):
    files = generate(symkin.load(EXAMPLES / f"{example}.toml"))
    folder = GENERATED / example
    if request.config.getoption("--update"):
        write_atomically(files, folder)
        return
    problems = []
    for name, content in sorted(files.items()):
        path = folder / name
        if not path.exists():
            problems.append(f"{path} is missing (run pytest --update)")
            continue
        old = path.read_bytes()
        if name.endswith(".pdf"):
            # Figure bytes depend on the installed matplotlib; their determinism is tested in
            # tests/test_latex.py. Here: a PDF is committed and is one.
            if not old.startswith(b"%PDF"):
                problems.append(f"{path} is not a PDF")
            continue
        if old != content:
            diff = difflib.unified_diff(
                old.decode().splitlines(),
                content.decode().splitlines(),
                f"{path} (committed)",
                f"{name} (derived now)",
                lineterm="",
                n=2,
            )
            problems.append("\n".join(list(diff)[:80]))
    stale = sorted({p.name for p in folder.iterdir()} - set(files)) if folder.exists() else []
    problems += [f"{folder / s} is not produced any more" for s in stale]
    assert not problems, "generated/ is out of date (pytest --update rewrites it):\n" + "\n".join(
        problems
    )
