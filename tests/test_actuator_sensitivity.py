"""Sensitivities with stroke actuators (docs/sensitivity.md, "Actuators"): the derivatives of the
deviation and the rigid position by the parameters, the input hinges and the strokes, at fixed
strokes, against central differences (Richardson-extrapolated) of the sympy backend's own
evaluation at 30 digits, which meets each stroke by Newton's method and knows nothing of the
implicit-function theorem the evaluators use; the numpy and C evaluators against the sympy
backend; tolerance and sweep run on an actuated mechanism.

Mechanisms: the piezo amplifier of examples/ (one actuator, a four-bar near its output's
toggle-free range) and the double parallelogram of tests/mechanisms/ with its hinge F1 replaced
by a piezo pushing the intermediate body along x (an actuator beside an input hinge, I1).
"""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import numpy as np
import pytest
from cli_runs import symkin_cli
from evaluators import GENERATED, KINEMATIC

import symkin

ROOT = Path(__file__).resolve().parent.parent
PIEZO_FILE = ROOT / "examples" / "piezo_amplifier.toml"
DOUBLE = (ROOT / "tests" / "mechanisms" / "double_parallelogram.toml").read_text()
PUSH = """
[[actuator]]
name = "piezo"
link = "intermediate"
at = [25, "L"]
direction = [1.0, 0.0]
drive = "stroke"
"""


def stroke_driven(text: str, hinge: str, actuator: str) -> str:
    """`text` with the input hinge `hinge` made passive and `actuator` appended."""
    head, tail = text.split(f'name = "{hinge}"', 1)
    return head + f'name = "{hinge}"' + tail.replace("input = true\n", "", 1) + actuator


@pytest.fixture(scope="module")
def piezo():
    mech = symkin.load(PIEZO_FILE)
    return mech, symkin.analyze(mech), {"piezo": 0.02}


@pytest.fixture(scope="module")
def mixed():
    mech = symkin.loads(stroke_driven(DOUBLE, "F1", PUSH), "double_parallelogram_stroke.toml")
    return mech, symkin.analyze(mech), {"piezo": 1.5, "I1": -0.03}


def reference(an, inputs: dict, level: str, name: str) -> np.ndarray:
    """d(deviation, rigid)/d(name) of every point, a (points, 4) array, by central differences
    of the sympy backend at 30 digits, Richardson-extrapolated (error O(h⁴))."""
    mech = an.mechanism
    values = {p.name: float(p.value) for p in mech.parameters}

    def at(shift: float) -> np.ndarray:
        if name in values:
            params = {k: repr(v + shift * (k == name)) for k, v in values.items()}
            given = {k: repr(v) for k, v in inputs.items()}
        else:
            params = None
            given = {k: repr(v + shift * (k == name)) for k, v in inputs.items()}
        ev = symkin.evaluate(an, given, level, params, dps=30)
        return np.array([[*p.deviation, *p.rigid] for _, p in sorted(ev.points.items())])

    base = values.get(name, inputs.get(name))
    h = 1e-3 * max(1.0, abs(base))

    def central(step: float) -> np.ndarray:
        return (at(step) - at(-step)) / (2 * step)

    return (4 * central(h / 2) - central(h)) / 3


def closed_form(an, inputs: dict, level: str, name: str, backend: str = "sympy") -> np.ndarray:
    ev = symkin.evaluate(an, inputs, level, backend=backend, sensitivity=True)
    s = ev.sensitivity
    table = (
        (s.deviation, s.rigid)
        if name in s.deviation[next(iter(s.deviation))]
        else (
            s.deviation_inputs,
            s.rigid_inputs,
        )
    )
    return np.array([[*table[0][p][name], *table[1][p][name]] for p in sorted(table[0])])


def close(found: np.ndarray, expected: np.ndarray, rtol: float) -> bool:
    scale = max(float(np.max(np.abs(expected))), 1e-300)
    return bool(np.max(np.abs(found - expected)) <= rtol * scale)


@pytest.mark.parametrize(
    "case, level, name",
    [
        ("piezo", "exact", "l"),
        ("piezo", "exact", "piezo"),
        ("piezo", "paper", "phi"),
        ("piezo", "first_order", "a"),
        ("mixed", "exact", "L"),
        ("mixed", "exact", "piezo"),
        ("mixed", "exact", "I1"),
    ],
)
def test_against_central_differences(case, level, name, request):
    _, an, inputs = request.getfixturevalue(case)
    expected = reference(an, inputs, level, name)
    found = closed_form(an, {k: repr(v) for k, v in inputs.items()}, level, name)
    assert close(found, expected, 1e-6), (found, expected)


@pytest.mark.parametrize("case", ["piezo", "mixed"])
def test_generated_evaluators_agree_with_sympy(case, request):
    _, an, inputs = request.getfixturevalue(case)
    given = {k: repr(v) for k, v in inputs.items()}
    for level in KINEMATIC:
        ref = symkin.evaluate(an, given, level, sensitivity=True).sensitivity.as_json()
        for backend in GENERATED:
            got = symkin.evaluate(an, given, level, backend=backend, sensitivity=True)
            found = got.sensitivity.as_json()
            assert found.keys() == ref.keys()
            for key, table in ref.items():
                for point, row in table.items():
                    assert row.keys() == found[key][point].keys()
                    for var, value in row.items():
                        assert close(np.array(found[key][point][var]), np.array(value), 1e-9), (
                            backend,
                            level,
                            key,
                            point,
                            var,
                        )


def test_compiled_rows_take_the_strokes(mixed):
    """symkin.compile: rows and sensitivities over arrays of strokes and hinge angles, per row
    as eval gives them."""
    mech, an, _ = mixed
    for backend in GENERATED:
        c = symkin.compile(mech, backend, levels=["exact"])
        assert c.inputs == ("I1", "piezo")
        strokes = [0.0, 0.8, 1.5]
        full = c.sensitivity_full({"piezo": np.array(strokes), "I1": -0.03}, "exact")
        for k, s in enumerate(strokes):
            ev = symkin.evaluate(an, {"piezo": repr(s), "I1": "-0.03"}, "exact", sensitivity=True)
            for p in ev.points:
                assert close(
                    np.asarray(full["points"][p]["deviation"])[:, k],
                    np.array(ev.points[p].deviation),
                    1e-9,
                )
                for q, v in ev.sensitivity.deviation[p].items():
                    got = np.asarray(full["deviation"][p]["params"][q])[:, k]
                    assert np.allclose(got, v, rtol=1e-8, atol=1e-12 * max(1, abs(max(v)))), q


def run(*args: str) -> subprocess.CompletedProcess:
    return symkin_cli(*args, cwd=ROOT)


def test_tolerance_and_sweep_take_actuators():
    """The CLI's tolerance stack-up over a stroke range: each parameter's d|dR|/dp at the
    worst configuration is the closed form's, checked against central differences of eval."""
    done = run(
        "tolerance", str(PIEZO_FILE), "--vary", "l=±1%", "--vary", "h=±0.05",
        "--input", "piezo=0:0.05:3", "--level", "exact", "--backend", "numpy", "--json",
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    out = json.loads(done.stdout)
    an = symkin.analyze(PIEZO_FILE)
    peak = out["points"]["B"]["peak"]
    at = peak["at"]["piezo"]
    dev = np.array(symkin.evaluate(an, {"piezo": repr(at)}, "exact", dps=30).points["B"].deviation)
    for name, found in peak["rates"].items():
        d = reference(an, {"piezo": at}, "exact", name)[0]
        rate = float(dev @ d[:2] / np.hypot(*dev))  # d|dR|/dp
        assert abs(found - rate) <= 1e-6 * abs(rate), (name, found, rate)
    done = run(
        "sweep", str(PIEZO_FILE), "--vary", "l=±1%", "--samples", "20",
        "--backend", "numpy", "--json",
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    sweep = json.loads(done.stdout)
    assert sweep["failed"] == 0
