"""The generated numpy module's `loaded` sensitivities with actuators (docs/sensitivity.md,
"Actuators"; templates/numpy/reduced_actuators_sens.py): the reduced equilibrium's rates carried
to the drives through each surrogate's reference angle, from the rigid stroke equation (a
stroke) or from the point's deviation along its line being zero (a force).

Reference, not the code under test: the Python level's sensitivities (symkin.evaluate with
sensitivity=True, the reduced equilibrium lambdified in mpmath and its stroke columns built
symbolically), themselves checked against central differences of the solver in
tests/test_loaded_actuators.py. Cases: the piezo amplifier example (a stroke), the parallelogram
stage pushed by a force under a payload, the five-bar with an input hinge held beside a force.
"""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest
from conftest import EXAMPLES
from test_loaded_actuators import PAYLOAD, driven, five_bar

import symkin
from symkin.codegen import pipeline

#: name -> (file text, the inputs of two configurations evaluated in one call)
CASES = {
    "piezo_amplifier": (
        lambda: (EXAMPLES / "piezo_amplifier.toml").read_text(),
        {"piezo": [0.02, 0.004]},
    ),
    "stage_force_payload": (lambda: driven("force", PAYLOAD), {"piezo": [0.5, -0.2]}),
    "five_bar_force": (lambda: five_bar("force"), {"O1": [0.03, -0.01], "piezo": [0.5, 0.3]}),
}
#: relative to the largest rate of the point (measured: 1.4e-13 at most)
AGAINST_PYTHON = 1e-10


@pytest.mark.parametrize("name", list(CASES))
def test_generated_sensitivities_are_the_python_levels(name):
    text, inputs = CASES[name]
    an = symkin.analyze(symkin.loads(text(), f"{name}.toml"))
    _, module = pipeline.build(an, "numpy", "test", sensitivity=True, levels=("loaded",))
    assert "loaded" in module.SENSITIVITY_LEVELS
    got = module.sensitivity_full({k: np.array(v) for k, v in inputs.items()}, "loaded")
    assert got["ok"].all()
    drives = list(module.INPUTS)
    for c in range(2):
        given = {k: repr(v[c]) for k, v in inputs.items()}
        want = symkin.evaluate(an, given, "loaded", sensitivity=True)
        sens = want.sensitivity
        for p in sens.deviation:
            np.testing.assert_allclose(
                got["points"][p]["deviation"][:, c], want.points[p].deviation, rtol=1e-9
            )
            for kind, params, inputs_ in (
                ("deviation", sens.deviation, sens.deviation_inputs),
                ("rigid", sens.rigid, sens.rigid_inputs),
            ):
                assert set(inputs_[p]) == set(drives)
                rows = [(got[kind][p]["params"][q][:, c], v) for q, v in params[p].items()]
                rows += [(got[kind][p]["inputs"][h][:, c], v) for h, v in inputs_[p].items()]
                scale = max(np.linalg.norm(v) for _, v in rows)
                assert scale > 0
                for g, v in rows:
                    assert np.linalg.norm(g - np.array(v)) <= AGAINST_PYTHON * scale, (kind, p)


def test_tolerance_at_loaded_takes_actuators_through_numpy():
    """`symkin tolerance --level loaded` on the piezo amplifier: the numpy module's rates (the
    C has no `loaded` sensitivities with actuators: asked for, it exits 2 naming numpy), its
    worst-case stack-up the sum of |d|dR|/dp| tolerance at the worst configuration (checked
    against the Python level's rates there)."""
    path = EXAMPLES / "piezo_amplifier.toml"
    args = ["tolerance", str(path), "--level", "loaded", "--input", "piezo=0:0.02:3"]
    args += ["--vary", "a=±0.01", "--vary", "l=±1%", "--json"]
    run = subprocess.run([sys.executable, "-m", "symkin", *args], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    refused = subprocess.run(
        [sys.executable, "-m", "symkin", *args, "--backend", "c"], capture_output=True, text=True
    )
    assert refused.returncode == 2 and "--backend numpy" in refused.stderr
    result = json.loads(run.stdout)
    assert result["backend"] == "numpy"
    point = result["points"]["B"]
    an = symkin.analyze(symkin.load(path))
    worst = point["at"]["piezo"]
    ev = symkin.evaluate(an, {"piezo": repr(worst)}, "loaded", sensitivity=True)
    d = np.array(ev.points["B"].deviation)
    size = np.linalg.norm(d)
    assert point["nominal"] == pytest.approx(size, rel=1e-9)
    rates = {q: d @ np.array(ev.sensitivity.deviation["B"][q]) / size for q in ("a", "l")}
    want = abs(rates["a"]) * 0.01 + abs(rates["l"]) * 0.025
    assert point["worst_case"] == pytest.approx(want, rel=1e-8)
