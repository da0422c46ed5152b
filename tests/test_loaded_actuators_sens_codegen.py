"""The generated numpy module's `loaded` sensitivities with actuators (docs/sensitivity.md,
"Actuators"; templates/numpy/reduced_actuators_sens.py): the reduced equilibrium's rates carried
to the drives through each surrogate's reference angle, from the rigid stroke equation (a
stroke) or from the point's deviation along its line being zero (a force).

Reference, not the code under test: the Python level's sensitivities (symkin.evaluate with
sensitivity=True, the reduced equilibrium lambdified in mpmath and its stroke columns built
symbolically), themselves checked against central differences of the solver in
tests/test_loaded_actuators.py. Cases: the piezo amplifier example (a stroke), the parallelogram
stage pushed by a force under a payload and by a stroke, the five-bar with an input hinge held
beside a force and beside a stroke (a load at T). The C's, with strokes, against the numpy
module's so checked.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from cli_runs import symkin_cli
from conftest import EXAMPLES
from evaluators import require_compiler
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
    "stage_stroke": (lambda: driven(), {"piezo": [1.5e-3, -0.7e-3]}),
    "five_bar_force": (lambda: five_bar("force"), {"O1": [0.03, -0.01], "piezo": [0.5, 0.3]}),
    # an input hinge beside a stroke, a load at T: the drives' mapping to the kinematic inputs
    "five_bar_stroke": (lambda: five_bar("stroke"), {"O1": [0.03, -0.01], "piezo": [4e-4, -2e-4]}),
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


@pytest.mark.parametrize("name", ["piezo_amplifier", "stage_stroke", "five_bar_stroke"])
def test_c_takes_the_strokes_sensitivities_at_loaded(name):
    """The C's `loaded` sensitivities with stroke actuators (templates/c/actuators.c's
    sk_actuated_loaded_rates) against the numpy module's (checked against the Python level
    above), row by row over configurations: the values, every parameter's and drive's column of
    the deviation and the rigid position (measured: 2e-14 of the largest rate)."""
    text, inputs = CASES[name]
    an = symkin.analyze(symkin.loads(text(), f"{name}.toml"))
    require_compiler()
    ev = symkin.compile(an, levels=("loaded",))
    x = np.array([inputs[h] for h in ev.inputs], dtype=float).T
    status, values, dev, rig = ev.sensitivity_rows(x, "loaded")
    assert (status == 0).all()
    p, module = pipeline.build(an, "numpy", "test", sensitivity=True, levels=("loaded",))
    shape = pipeline.Shape.of(p, True)
    n_status, n_values, n_dev, n_rig = pipeline._numpy_sensitivity_rows(
        module, shape, x, None, "loaded"
    )
    assert (n_status == 0).all()
    np.testing.assert_allclose(values, n_values, rtol=1e-12, atol=1e-15)
    for got, want in ((dev, n_dev), (rig, n_rig)):
        scale = np.max(np.abs(want), axis=(2, 3), keepdims=True)
        assert np.all(np.abs(got - want) <= 1e-10 * scale)


def test_tolerance_at_loaded_takes_actuators_through_both_backends(tmp_path):
    """`symkin tolerance --level loaded` on the piezo amplifier: its worst-case stack-up the sum
    of |d|dR|/dp| tolerance at the worst configuration (checked against the Python level's rates
    there), the C's (the default) and the numpy module's alike; a force actuator's file, whose
    C has no `loaded` sensitivities, asked for them in C exits 2 naming numpy."""
    path = EXAMPLES / "piezo_amplifier.toml"
    args = ["tolerance", str(path), "--level", "loaded", "--input", "piezo=0:0.02:3"]
    args += ["--vary", "a=±0.01", "--vary", "l=±1%", "--json"]
    run = symkin_cli(*args)
    assert run.returncode == 0, run.stderr
    by_numpy = symkin_cli(*args, "--backend", "numpy")
    assert by_numpy.returncode == 0, by_numpy.stderr
    result, other = json.loads(run.stdout), json.loads(by_numpy.stdout)
    assert result["backend"] == "c" and other["backend"] == "numpy"
    assert result["points"]["B"]["worst_case"] == pytest.approx(
        other["points"]["B"]["worst_case"], rel=1e-10
    )
    forced = tmp_path / "force.toml"
    forced.write_text(driven("force", PAYLOAD))
    args = ["tolerance", str(forced), "--level", "loaded", "--input", "piezo=0:0.5:2"]
    args += ["--vary", "l=±1%", "--backend", "c"]
    refused = symkin_cli(*args)
    assert refused.returncode == 2 and "--backend numpy" in refused.stderr
    assert "force actuators" in refused.stderr
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
