"""docs/ is enough to write a mechanism file from scratch (issue: the newcomer's first hour):
the file-format page's complete example loads and evaluates, every key and model the reader
accepts is documented, every relative link resolves, and nothing points outside the repository."""

from __future__ import annotations

import re

import mpmath
import pytest
from conftest import ROOT
from reference_solver import Reference

import symkin
from symkin.model.hinges import HINGE_KEYS, MODELS
from symkin.model.reader import LINK_KEYS, POINT_KEYS, TOP_KEYS

DOCS = sorted((ROOT / "docs").glob("*.md"))
FILE_FORMAT = (ROOT / "docs" / "file-format.md").read_text()


def toml_blocks(text: str) -> list[str]:
    return re.findall(r"```toml\n(.*?)```", text, flags=re.S)


def test_the_pages_exist():
    names = {p.name for p in DOCS}
    assert {"file-format.md", "levels.md", "cli.md", "generated-code.md", "numerics.md"} <= names


def test_the_complete_example_loads_and_matches_the_independent_solver():
    """The page's first block is a whole file: it loads, and its deviation at A0 = 0.2 agrees
    with the independent 40-digit solver (tests/reference_solver.py)."""
    text = toml_blocks(FILE_FORMAT)[0]
    mech = symkin.loads(text, "from_the_docs.toml")
    assert list(mech.inputs) == ["A0"]
    got = symkin.evaluate(symkin.analyze(mech), {"A0": 0.2}, "exact").points["C"].deviation
    ref = [
        float(x)
        for x in Reference(mech).deviation({"A0": mpmath.mpf("0.2")})["points"]["C"]["deviation"]
    ]
    assert max(abs(g - r) for g, r in zip(got, ref)) <= 1e-9 * max(map(abs, ref))


@pytest.mark.parametrize(
    "key", sorted(set(TOP_KEYS) | set(HINGE_KEYS) | set(LINK_KEYS) | set(POINT_KEYS))
)
def test_every_key_is_documented(key):
    assert any(f"`{form}`" in FILE_FORMAT for form in (key, f"[{key}]", f"[[{key}]]")), key


@pytest.mark.parametrize("model", sorted(MODELS))
def test_every_model_and_its_parameters_are_documented(model):
    row = next(
        (line for line in FILE_FORMAT.splitlines() if line.startswith(f"| `{model}` |")), None
    )
    assert row, f"no row for model {model}"
    for parameter in MODELS[model].parameters:
        assert f"`{parameter.name}`" in row, (model, parameter.name)


@pytest.mark.parametrize("page", [*DOCS, ROOT / "README.md"], ids=lambda p: p.name)
def test_links_resolve_inside_the_repository(page):
    text = page.read_text()
    assert "CONTRACT" not in text and "../shared" not in text and "DESIGN.md" not in text
    for target in re.findall(r"\]\(([^)#\s]+)(?:#[^)]*)?\)", text):
        if re.match(r"[a-z]+://", target):
            continue
        path = (page.parent / target).resolve()
        assert path.is_relative_to(ROOT) and path.exists(), f"{page.name}: {target}"
