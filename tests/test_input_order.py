"""The generated evaluators bind every input value to its own hinge, whatever the order.

The evaluators take their inputs in the hinges' label order (the skeleton tree's, which a
`basic_chain` or `chords` entry can make differ from the file's order); `INPUTS`, the C
`input_names` and the sensitivities' input columns name them in that same order. Until the
fixed-inputs change, the names were the file's order while the routines read the label order, so
a five-bar whose basic chain starts at its second input swapped its two inputs (a 5x error in
the deviation). Checked against the 40-digit mpmath evaluation, which takes inputs by name.
"""

from __future__ import annotations

import mechanisms as M
import numpy as np
import pytest
from evaluators import GENERATED, require

import symkin
from symkin.studies.evaluation import evaluate

# basic_chain from the right: O2 gets label 1, O1 a later one; the file lists O1 first
REORDERED = M.FIVE_BAR.replace(
    'name = "five_bar"\n', 'name = "five_bar"\nbasic_chain = ["right", "right_top"]\n'
)
INPUTS = {"O1": 0.15, "O2": -0.1}


@pytest.mark.parametrize("backend", GENERATED)
def test_inputs_reach_their_own_hinges(backend):
    require(backend)
    mech = symkin.loads(REORDERED, "five_bar.toml")
    an = symkin.analyze(mech)
    assert mech.inputs == ("O1", "O2") and [an.kin.hinges[a].name for a in an.kin.inputs] == [
        "O2",
        "O1",
    ]
    want = evaluate(an, {k: str(v) for k, v in INPUTS.items()}, "exact", sensitivity=True)
    ev = symkin.compile(mech, backend=backend)
    assert ev.inputs == ("O2", "O1")
    got = ev.evaluate(INPUTS, "exact")["points"]["P_tip"]["deviation"]
    w = np.array(want.points["P_tip"].deviation)
    assert np.abs(np.asarray(got, dtype=float) - w).max() <= 1e-13 * np.abs(w).max()
    full = ev.sensitivity_full(INPUTS, "exact")["deviation"]["P_tip"]["inputs"]
    for name in INPUTS:
        ref = np.array(want.sensitivity.deviation_inputs["P_tip"][name], dtype=float)
        assert (
            np.abs(np.asarray(full[name], dtype=float) - ref).max() <= 1e-10 * np.abs(ref).max()
        ), name
    if ev.sources.source:  # a C source names them in the same order
        names = ev.sources.source.split("five_bar_input_names[FIVE_BAR_N_INPUTS] = {")[1]
        assert [n.strip() for n in names.split("}")[0].split(",")] == ['"O2"', '"O1"']
