"""The structure matrices of the paper's three examples (Hasan & Lilov 2008, §2 and §5), entry by
entry, typed in from the paper; the examples/ files list links and hinges in the paper's numbering.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from cli_runs import symkin_cli

import symkin

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"


def paths_from_incidence(incidence: list[list[int]], n: int, m: int) -> list[list[int]]:
    """Ψ = [T; 0] with T = S̆⁻¹, S̆ = I[1:, :n], inverted independently of symkin."""
    s_breve = np.array(incidence, dtype=float)[1:, :n]
    t = np.rint(np.linalg.inv(s_breve)).astype(int)
    return t.tolist() + [[0] * n for _ in range(m - n)]


def incidence_from(i_plus: list[int], i_minus: list[int]) -> list[list[int]]:
    n, m = max(i_minus), len(i_plus)
    rows = [[0] * m for _ in range(n + 1)]
    for a in range(m):
        rows[i_plus[a]][a] = 1
        rows[i_minus[a]][a] = -1
    return rows


# Four-bar (Fig. 2, Fig. 3 and the matrices after them).
FOUR_BAR = {
    "file": "four_bar.toml",
    "links": ["frame", "crank", "coupler", "rocker"],
    "hinges": ["A0", "A", "B0", "B"],
    "i_plus": [0, 1, 0, 2],
    "i_minus": [1, 2, 3, 3],
    "incidence": [[1, 0, 1, 0], [-1, 1, 0, 0], [0, -1, 0, 1], [0, 0, -1, -1]],
    "loops": [[1, 1, -1, 1]],
    "paths": [[-1, -1, 0], [0, -1, 0], [0, 0, -1], [0, 0, 0]],
}

# Six-bar Stephenson-I (Fig. 4, Fig. 5, the table of i+/i- and the printed I and Φ).
SIX_BAR_INCIDENCE = [
    [1, 0, 1, 0, 0, 0, 0],
    [-1, 1, 0, 0, 0, 1, 0],
    [0, -1, 0, 0, 0, 0, 1],
    [0, 0, -1, 1, 1, 0, 0],
    [0, 0, 0, -1, 0, 0, -1],
    [0, 0, 0, 0, -1, -1, 0],
]
SIX_BAR = {
    "file": "stephenson_six_bar.toml",
    "links": ["frame", "input", "coupler", "rocker", "link_ED", "link_AB"],
    "hinges": ["O_A", "C", "O_B", "E", "B", "A", "D"],
    "i_plus": [0, 1, 0, 3, 3, 1, 2],
    "i_minus": [1, 2, 3, 4, 5, 5, 4],
    "incidence": SIX_BAR_INCIDENCE,
    "loops": [[1, 0, -1, 0, -1, 1, 0], [1, 1, -1, -1, 0, 0, 1]],
    "paths": paths_from_incidence(SIX_BAR_INCIDENCE, 5, 7),
}

# Nine-bar platform (Fig. 6, Fig. 7, the table of i+/i-; Φ from the two relations (5.3)).
NINE_BAR_I_PLUS = [0, 1, 2, 3, 4, 5, 3, 7, 0, 0]
NINE_BAR_I_MINUS = [1, 2, 3, 4, 5, 6, 7, 8, 6, 8]
NINE_BAR_INCIDENCE = incidence_from(NINE_BAR_I_PLUS, NINE_BAR_I_MINUS)
NINE_BAR = {
    "file": "nine_bar_platform.toml",
    "links": ["frame", "b1", "b2", "b3", "b4", "b5", "b6", "b7", "b8"],
    "hinges": ["O", "A", "B", "K", "G", "H", "C", "D", "I", "E"],
    "i_plus": NINE_BAR_I_PLUS,
    "i_minus": NINE_BAR_I_MINUS,
    "incidence": NINE_BAR_INCIDENCE,
    "loops": [[-1, -1, -1, -1, -1, -1, 0, 0, 1, 0], [-1, -1, -1, 0, 0, 0, -1, -1, 0, 1]],
    "paths": paths_from_incidence(NINE_BAR_INCIDENCE, 8, 10),
}

PAPER = {"four_bar": FOUR_BAR, "six_bar": SIX_BAR, "nine_bar": NINE_BAR}


def test_independent_inverse_matches_the_printed_four_bar():
    # The helper reproduces the one Ψ the paper prints, so it can stand in for the other two.
    assert paths_from_incidence(FOUR_BAR["incidence"], 3, 4) == FOUR_BAR["paths"]


def test_typed_six_bar_incidence_matches_its_table():
    assert incidence_from(SIX_BAR["i_plus"], SIX_BAR["i_minus"]) == SIX_BAR_INCIDENCE


@pytest.mark.parametrize("key", PAPER)
def test_paper_matrices(key: str):
    expected = PAPER[key]
    s = symkin.structure(symkin.load(EXAMPLES / expected["file"]))
    assert list(s.links) == expected["links"]
    assert list(s.hinges) == expected["hinges"]
    assert not s.relabeled
    assert list(s.i_plus) == expected["i_plus"]
    assert list(s.i_minus) == expected["i_minus"]
    for name in ("incidence", "loops", "paths"):
        got = getattr(s, name)
        want = np.array(expected[name])
        assert got.shape == want.shape, name
        for index in np.ndindex(*want.shape):
            assert got[index] == want[index], f"{name}{list(index)}"
    assert s.T.tolist() == expected["paths"][: s.n]


@pytest.mark.parametrize("key", PAPER)
def test_matrices_json_prints_the_paper(key: str):
    expected = PAPER[key]
    result = symkin_cli("matrices", "--json", str(EXAMPLES / expected["file"]), timeout=60)
    assert result.returncode == 0, result.stderr
    data = json.loads(result.stdout)
    assert data == {k: v for k, v in expected.items() if k != "file"}
