"""Dependency pruning (docs/pruning.md): `derive --points` keeps only the loops that move them.

Two independent checks. What is kept is checked against the full mechanism's own 40-digit
evaluation: lengthening the plate of a dropped hinge leaves a kept point's deviation unchanged,
lengthening a kept one changes it (nothing dropped that matters, nothing kept that does not).
And the pruned evaluators (numpy, C) agree with the full ones on every point they keep, at every
generated level, on loops that are independent (a fan of four-bars), chained (a ladder, a Watt
II) and shared (the nine-bar platform, whose physical levels couple every loop).
"""

from __future__ import annotations

import dataclasses
import sys

import mechanisms as M
import numpy as np
import pytest
import sympy as sp
from conftest import EXAMPLES, ROOT
from evaluators import require_compiler

import symkin
from symkin.codegen import pipeline
from symkin.core import levels as level_table
from symkin.graph.pruning import prune
from symkin.studies.derive import generate
from symkin.studies.evaluation import evaluate

sys.path.insert(0, str(ROOT / "benchmarks"))
import families

STIFF = 'E = 210e9\nthickness = "l/10"\nwidth = 5e-3\n'


def _stiff(text: str) -> str:
    return text.replace('length = "l"\n', 'length = "l"\n' + STIFF, 1)


def _ladder(k: int) -> str:
    """A ladder with a point on its first two rungs as well as the top one."""
    return (
        families.ladder(k)
        + families._point("P1", "r1", 0.02, 0.06)
        + families._point("P2", "r2", 0.03, 0.11)
    )


WATT = M.WATT_II + M.point("P", "coupler", 0.06, 0.07)
# The Watt II with its hinges in another order: the file's skeleton tree reaches the rocker
# through the second loop (O5, D, C), so the paper level of a point on the rocker sums those
# plates (4.8) and pruning must keep them (it once rebuilt the tree and dropped them).
WATT_ORDER = M.text(
    "watt_order",
    M.links("ground", "crank", "coupler", "output", "coupler2", "rocker")
    + M.hinge("C", "rocker", "coupler2", 0.13, 0.05)
    + M.hinge("O1", "ground", "crank", 0.0, 0.0, "pi/2", input=True)
    + M.hinge("A", "crank", "coupler", 0.015, 0.025)
    + M.hinge("O5", "ground", "output", 0.2, 0.0, "pi/2")
    + M.hinge("D", "coupler2", "output", 0.19, 0.07, "pi/2")
    + M.hinge("O3", "ground", "rocker", 0.1, 0.0, "pi/2")
    + M.hinge("B", "coupler", "rocker", 0.09, 0.065, "pi/3")
    + M.point("P", "coupler", 0.06, 0.07)
    + M.point("R", "rocker", 0.11, 0.03),
)
# The file's chords O3 and B: dropping the second loop leaves the rocker without its tree edge C
WATT_CHORDS = WATT.replace('name = "watt_ii"\n', 'name = "watt_ii"\nchords = ["O3", "B"]\n')

CASES = {
    # text, points, inputs (full mechanism), loops kept
    "fan_C2": (families.fan(4), ["C2"], {f"A0_{j}": 0.1 * j - 0.15 for j in range(1, 5)}, 1),
    "fan_C1_C4": (
        families.fan(4),
        ["C1", "C4"],
        {f"A0_{j}": 0.2 - 0.1 * j for j in range(1, 5)},
        2,
    ),
    "ladder_P1": (_ladder(4), ["P1"], {"g0": 0.2}, 1),
    "ladder_P2": (_ladder(4), ["P2"], {"g0": -0.15}, 2),
    "ladder_top": (_ladder(3), ["top"], {"g0": 0.1}, 3),
    "watt_P": (WATT, ["P"], {"O1": 0.25}, 1),
    "watt_order_R": (WATT_ORDER, ["R"], {"O1": 0.2}, 2),
    "watt_order_P": (WATT_ORDER, ["P"], {"O1": -0.2}, 1),
    "watt_chords_P": (WATT_CHORDS, ["P"], {"O1": 0.2}, 1),
    "serial_upper": (
        M.SERIAL_ARM + M.point("U", "upper", 0.01, 0.05),
        ["U"],
        {"S": 0.3, "E": -0.2},
        0,
    ),
}


def _mech(text: str) -> symkin.Mechanism:
    return symkin.loads(text, "pruning.toml")


def _lengthened(mech, hinge: str):
    """The mechanism with one plate 1 % longer."""
    return dataclasses.replace(
        mech,
        hinges=tuple(
            dataclasses.replace(h, length=h.length * sp.Rational(101, 100))
            if h.name == hinge
            else h
            for h in mech.hinges
        ),
    )


@pytest.mark.parametrize("case", sorted(CASES))
def test_kept_hinges_are_exactly_those_that_move_the_points(case):
    text, points, inputs, loops = CASES[case]
    mech = _mech(text)
    sub, pruning = prune(mech, points)
    assert pruning.kept_loops == loops
    kept = {h.name for h in sub.hinges}
    an = symkin.analyze(mech)
    base = {lv: evaluate(an, inputs, lv, dps=30) for lv in ("paper", "exact")}
    for h in mech.hinges:
        longer = symkin.analyze(_lengthened(mech, h.name))
        change = {}
        for level in ("paper", "exact"):
            moved = evaluate(longer, inputs, level, dps=30)
            change[level] = max(
                np.abs(
                    np.subtract(moved.points[p].deviation, base[level].points[p].deviation)
                ).max()
                / np.abs(base[level].points[p].deviation).max()
                for p in points
            )
        if h.name in kept:  # moves some point at some level (paper: over the direct path)
            assert max(change.values()) > 1e-6, (h.name, change)
        else:  # moves none at any level
            assert max(change.values()) < 1e-14, (h.name, change)


def _modules(text: str, points, levels=None, c: bool = True):
    mech = _mech(text)
    emit = ["numpy", "c"] if c else ["numpy"]
    # the evaluators are compared, not their sensitivities (test_sensitivity's): left out
    full = generate(mech, emit, levels=levels, sensitivity=False)
    pruned = generate(mech, emit, points=points, levels=levels, sensitivity=False)
    out = []
    for files in (full, pruned):

        def texts(backend: str, files=files) -> tuple[str, ...]:
            names = pipeline.backend(backend).file_names(mech.name)
            return tuple(files[name].decode() for name in names)

        mod = pipeline.load("numpy", mech.name, texts("numpy"))
        lib = None
        if c:
            require_compiler()
            shape = pipeline.Shape(mod.INPUTS, tuple(mod.PARAMETERS), mod.POINTS, mod.HINGES)
            lib = pipeline.load("c", mech.name, texts("c"), shape)
        out.append((mod, lib, files))
    return mech, out


def _agree(mech, modules, points, inputs, levels):
    (full, full_lib, _), (pruned, pruned_lib, _) = modules
    assert tuple(p.name for p in mech.points if p.name in points) == pruned.POINTS
    assert tuple(n for n in full.INPUTS if n in pruned.INPUTS) == pruned.INPUTS
    sub_inputs = {k: inputs[k] for k in pruned.INPUTS}
    for level in levels:
        want = full.evaluate(inputs, level)["points"]
        got = pruned.evaluate(sub_inputs, level)["points"]
        for p in points:
            for key in ("rigid", "deviation"):
                w, g = np.asarray(want[p][key]), np.asarray(got[p][key])
                assert np.abs(g - w).max() <= 1e-14 * np.abs(w).max(), (level, p, key)
        if full_lib is None:
            continue
        code = level_table.get(level).code
        s1, o1, _ = full_lib.evaluate([inputs[k] for k in full.INPUTS], None, code)
        s2, o2, _ = pruned_lib.evaluate([sub_inputs[k] for k in pruned.INPUTS], None, code)
        assert s1 == s2 == 0
        for i, p in enumerate(pruned.POINTS):
            j = full.POINTS.index(p)
            w, g = np.array(o1[6 * j : 6 * j + 6]), np.array(o2[6 * i : 6 * i + 6])
            assert np.abs(g[4:] - w[4:]).max() <= 1e-14 * np.abs(w[4:]).max(), (level, p)
            assert np.abs(g[:2] - w[:2]).max() <= 1e-14 * np.abs(w[:2]).max(), (level, p)


def test_the_dropped_inputs_are_accepted_and_ignored():
    """Code written for the whole file keeps working: numpy `evaluate` and `symkin.compile`
    take the file's every input and ignore those that move none of the points."""
    text, points, inputs, _ = CASES["fan_C2"]
    mech, ((full, _, _), (pruned, _, _)) = _modules(text, points, c=False)
    assert pruned.PRUNED_INPUTS == ("A0_1", "A0_3", "A0_4") and full.PRUNED_INPUTS == ()
    want = full.evaluate(inputs)["points"]["C2"]["deviation"]
    tol = 1e-14 * np.abs(want).max()
    assert np.abs(pruned.evaluate(inputs)["points"]["C2"]["deviation"] - want).max() <= tol
    ev = symkin.compile(mech, backend="numpy", points=points)
    assert ev.inputs == ("A0_2",)
    assert np.abs(ev.evaluate(inputs)["points"]["C2"]["deviation"] - want).max() <= tol
    with pytest.raises(ValueError, match="inputs must be exactly"):
        pruned.evaluate({"A0_1": 0.1})


@pytest.mark.parametrize(
    "case", ["fan_C2", "ladder_P2", "watt_P", "watt_order_R", "watt_chords_P", "serial_upper"]
)
def test_pruned_evaluators_agree_with_the_full_ones(case):
    text, points, inputs, _ = CASES[case]
    mech, modules = _modules(text, points)
    _agree(mech, modules, points, inputs, modules[0][0].LEVELS)
    header = modules[1][2][f"{mech.name}.h"].decode()
    if prune(mech, points)[1].pruned:
        assert "Pruned for the points" in header


def test_a_fan_with_stiffness_prunes_at_the_physical_levels_too():
    """The four-bars of a fan meet only at the frame: no force passes from one to another, so
    even the statics of `loaded` keep one loop; the pruned evaluator matches the full one."""
    text = _stiff(families.fan(3))
    inputs = {"A0_1": 0.1, "A0_2": 0.2, "A0_3": -0.1}
    mech = _mech(text)
    assert prune(mech, ["C2"], physical=True)[1].kept_loops == 1
    mech, modules = _modules(text, ["C2"], levels=["exact", "loaded"])
    _agree(mech, modules, ["C2"], inputs, ["exact", "loaded"])


def test_physical_levels_keep_the_loops_that_carry_force():
    """A point on the ladder's first rung needs one loop kinematically, but the cells above press
    on that rung through their plates: at the physical levels every loop is kept. The nine-bar's
    F needs no loop at all kinematically, and all of them physically."""
    ladder = _mech(_stiff(_ladder(3)))
    assert prune(ladder, ["P1"])[1].kept_loops == 1
    assert prune(ladder, ["P1"], physical=True)[1].kept_loops == 3
    nine = symkin.load(EXAMPLES / "nine_bar_platform.toml")
    kinematic = prune(nine, ["F"])[1]
    assert kinematic.kept_loops == 0 and set(kinematic.dropped_inputs) == {"B", "K"}
    assert not prune(nine, ["F"], physical=True)[1].pruned


def test_physical_pruning_is_checked_against_the_full_statics():
    """Stiffening a dropped plate (E twice) leaves a kept point's `loaded` deviation unchanged in
    the full mechanism's own evaluation; stiffening a kept one changes it."""
    mech = _mech(_stiff(families.fan(2)))
    sub, _ = prune(mech, ["C1"], physical=True)
    kept = {h.name for h in sub.hinges}
    inputs = {"A0_1": 0.2, "A0_2": -0.1}
    base = evaluate(symkin.analyze(mech), inputs, "loaded", dps=30).points["C1"].deviation
    for h in mech.hinges:
        stiffer = dataclasses.replace(
            mech,
            hinges=tuple(
                dataclasses.replace(x, E=x.E * 2) if x.name == h.name else x for x in mech.hinges
            ),
        )
        dev = evaluate(symkin.analyze(stiffer), inputs, "loaded", dps=30).points["C1"].deviation
        change = np.abs(np.subtract(dev, base)).max() / np.abs(base).max()
        assert (change > 1e-9) if h.name in kept else (change < 1e-14), (h.name, change)


def test_nine_bar_point_on_input_links_solves_no_loop():
    """F rides on links the inputs alone place: the pruned evaluator holds no loop solve."""
    mech, modules = _modules(
        (EXAMPLES / "nine_bar_platform.toml").read_text(),
        ["F"],
        levels=["paper", "first_order", "exact"],
    )
    (_full, _, _), (pruned, _, files) = modules
    assert pruned.INPUTS == ("O", "A")
    source = files[f"{mech.name}.c"].decode()
    assert "newton" not in source and "_linear(" not in source
    _agree(
        mech,
        modules,
        ["F"],
        {"O": 0.1, "A": -0.05, "B": 0.02, "K": 0.03},
        ["paper", "first_order", "exact"],
    )


def test_the_report_says_what_was_kept_and_why(tmp_path):
    mech = _mech(families.fan(2))
    files = generate(mech, ["latex"], points=["C2"], appendix=True)
    body = files[f"{mech.name}.tex"].decode()
    assert "Pruned for the points C2" in body and "do not move the points" in body


def test_unknown_point_is_refused():
    with pytest.raises(symkin.InputError, match="unknown point"):
        prune(_mech(families.fan(2)), ["C9"])


def test_a_range_over_an_input_pruning_drops_is_refused():
    """The report of C1 cannot plot it over the crank of the second four-bar."""
    mech = _mech(families.fan(2))
    with pytest.raises(symkin.InputError, match="A0_2 moves none of the points") as err:
        generate(mech, ["latex"], points=["C1"], spans={"A0_2": (-0.1, 0.1)})
    assert err.value.entry == "--range"


def test_without_paper_the_direct_paths_need_not_be_kept():
    """The rocker's path in the reordered Watt II runs through the second loop; only `paper`
    sums plates over it, so without that level the second loop is dropped."""
    mech = _mech(WATT_ORDER)
    assert prune(mech, ["R"])[1].kept_loops == 2
    assert prune(mech, ["R"], paths=False)[1].kept_loops == 1
