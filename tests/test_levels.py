"""The level table (symkin/core/levels.py) is the one place levels are defined: every layer reads
names and codes from it (docs/levels.md)."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import EXAMPLES
from evaluators import require_compiler

import symkin
from symkin.cli.commands import parser
from symkin.codegen import pipeline
from symkin.core import levels


def test_the_table():
    codes = [lv.code for lv in levels.LEVELS] + list(levels.RESERVED.values())
    assert sorted(codes) == list(range(len(codes)))  # unique (retired ones too), none skipped
    # the contract's codes never change: new levels take the next free one
    assert [
        levels.get(n).code for n in ("paper", "first_order", "exact", "loaded", "equilibrium")
    ] == [0, 1, 2, 3, 4]
    assert len(set(levels.NAMES)) == len(levels.NAMES)
    assert {levels.PHYSICAL_DEFAULT, levels.KINEMATIC_DEFAULT} <= set(levels.NAMES)
    assert levels.reference().name == "exact"
    assert not levels.get("paper").needs_delta and levels.get("exact").needs_delta
    with pytest.raises(symkin.InputError, match="unknown level 'best'"):
        levels.get("best")
    # a retired level's name is refused, its code reserved (docs/levels.md)
    assert levels.RESERVED == {"loaded_refined": 5}
    with pytest.raises(symkin.InputError, match=r"'loaded_refined' \(retired"):
        levels.get("loaded_refined")


def test_cli_choices_come_from_the_table():
    ev = parser()._subparsers._group_actions[0].choices["eval"]
    level = next(a for a in ev._actions if a.dest == "level")
    # no fixed default: the file's (levels.default_for, test_default_level.py)
    assert tuple(level.choices) == levels.NAMES and level.default is None


@pytest.mark.parametrize("wanted", [["paper"], ["first_order", "exact"], ["loaded"], None])
def test_generated_code_takes_the_plans_levels_and_their_codes(wanted):
    require_compiler()
    an = symkin.analyze(symkin.load(EXAMPLES / "four_bar.toml"))
    p, module = pipeline.build(an, "numpy", "levels", levels=wanted)
    names = tuple(lv.name for lv in p.levels)
    assert names == module.LEVELS
    # the file's default (loaded: its plates have E, thickness and width) when it is generated,
    # else exact when it is generated, else the most faithful level generated
    expected = next((n for n in ("loaded", "exact") if n in names), names[-1])
    assert expected == module.DEFAULT_LEVEL
    default = module.evaluate({"A0": np.array([0.2])})
    given = module.evaluate({"A0": np.array([0.2])}, expected)
    assert np.array_equal(default["points"]["C"]["deviation"], given["points"]["C"]["deviation"])
    lib = pipeline.evaluator(p, "c", "levels", links=False)
    for lv in levels.LEVELS:
        status = lib.evaluate([0.2], None, lv.code)[0]
        assert status == (0 if lv.name in names else 3), lv.name
