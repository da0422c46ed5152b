"""The generated numpy module's `loaded` level for files with actuators (docs/physics.md,
"Actuators at loaded"; templates/numpy/reduced_actuators.py): the rigid linkage at the strokes,
the reduced equilibrium with the surrogates free, a stroke's force and a force's stroke solved
for, a force actuator's deviations against the rigid linkage at the stroke it produced.

References, none of them the code under test: symkin's Python `loaded` level (the reduced
equilibrium lambdified in mpmath, its rigid references from the mpmath kinematics) and the
`equilibrium` level (geometrically exact beams, another solver), on the piezo amplifier example
(a stroke, two strokes in one call) and the parallelogram stage pushed by a stroke and by a
force under a payload (tests/test_loaded_actuators.py's files). The C evaluator takes stroke
actuators at loaded (templates/c/actuators.c); with a force actuator it keeps the kinematic
levels, its `loaded` refused naming the actuator.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import EXAMPLES
from test_loaded_actuators import AGREEMENT, PAYLOAD, driven
from test_loaded_reported_codegen import compiler_or_fail

import symkin
from symkin.codegen import pipeline
from symkin.core.errors import InputError

#: name -> (file text, the actuator's values one call takes, the equilibrium tolerance's case)
CASES = {
    "piezo_amplifier": (
        lambda: (EXAMPLES / "piezo_amplifier.toml").read_text(),
        [0.02, 0.005],
        "piezo_amplifier",
    ),
    "parallelogram_stroke": (lambda: driven(), [1.5e-3, -0.5e-3], "parallelogram_stroke"),
    "parallelogram_force_payload": (
        lambda: driven("force", PAYLOAD),
        [0.5, 0.2],
        "parallelogram_force_payload",
    ),
}
#: generated numpy against the Python level (relative to |dR|; measured below 1e-10)
AGAINST_PYTHON = 1e-9


@pytest.fixture(scope="module")
def runs():
    """By case: the analysis, the numpy module's evaluate at all the values at once, and per
    value the Python `loaded` and the `equilibrium` evaluations (computed on first use)."""
    cache: dict = {}

    def get(name: str):
        if name not in cache:
            text, values, _ = CASES[name]
            an = symkin.analyze(symkin.loads(text(), f"{name}.toml"))
            plan, module = pipeline.build(an, "numpy", "test", sensitivity=False)
            assert "loaded" in module.LEVELS and module.INPUTS == ("piezo",)
            got = module.evaluate({"piezo": np.array(values)}, "loaded")
            refs = [
                tuple(symkin.evaluate(an, {"piezo": v}, lv) for lv in ("loaded", "equilibrium"))
                for v in values
            ]
            cache[name] = (an, plan, got, refs)
        return cache[name]

    return get


@pytest.mark.parametrize("name", list(CASES))
def test_generated_loaded_against_python_and_equilibrium(runs, name):
    _, plan, got, refs = runs(name)
    # what it reports beyond the deviations: tests/test_loaded_actuators_reported_codegen.py
    assert plan.loaded is not None and plan.loaded.report is not None
    assert got["ok"].all()
    assert set(got["points"]) == ({"B"} if name == "piezo_amplifier" else {"P"})
    tol = AGREEMENT[CASES[name][2]]
    for k, (python, exact) in enumerate(refs):
        for p, q in python.points.items():
            size = math.hypot(*q.deviation)
            assert size > 0
            dev = got["points"][p]["deviation"][:, k]
            rigid = got["points"][p]["rigid"][:, k]
            # against the Python level: the same equations, another arithmetic
            assert math.dist(dev, q.deviation) <= AGAINST_PYTHON * size, (p, k)
            assert np.allclose(rigid, q.rigid, rtol=0, atol=1e-12 * max(map(abs, q.rigid)))
            # against equilibrium: the plate relation's quartic truncation
            e = exact.points[p]
            assert math.dist(dev, e.deviation) <= tol * e.norm, (p, k)
        for h, v in python.angles_compliant.items():
            assert abs(got["angles"]["compliant"][h][k] - v) <= 1e-11, h
            assert abs(got["angles"]["rigid"][h][k] - python.angles_rigid[h]) <= 1e-11, h
        top = max(abs(v.deviation) for v in python.links.values())
        for link, v in python.links.items():
            assert abs(got["links"][link]["deviation"][k] - v.deviation) <= 1e-9 * top, link


@pytest.mark.parametrize("name", ["piezo_amplifier", "parallelogram_stroke"])
def test_generated_c_loaded_with_a_stroke(runs, name):
    """The C evaluator (templates/c/actuators.c, reduced.c) at loaded with a stroke actuator:
    symkin.evaluate --backend c, one configuration per call, against the Python level and
    equilibrium; the surrogates' turn in the compliant angles and the links."""
    if not compiler_or_fail():
        return
    an, _, _, refs = runs(name)
    tol = AGREEMENT[CASES[name][2]]
    for v, (python, exact) in zip(CASES[name][1], refs):
        got = symkin.evaluate(an, {"piezo": v}, "loaded", backend="c")
        assert got.inputs == {"piezo": v}
        for p, q in python.points.items():
            assert math.dist(got.points[p].deviation, q.deviation) <= AGAINST_PYTHON * q.norm
            e = exact.points[p]
            assert math.dist(got.points[p].deviation, e.deviation) <= tol * e.norm, (p, v)
        for h, a in python.angles_compliant.items():
            assert abs(got.angles_compliant[h] - a) <= 1e-11, h
        top = max(abs(x.deviation) for x in python.links.values())
        for link, x in python.links.items():
            assert abs(got.links[link].deviation - x.deviation) <= 1e-9 * top, link


def test_cli_numpy_backend_and_the_c_refusal():
    """eval --level loaded --backend numpy takes the actuator (the Python level's deviation);
    the C evaluator does not take a force actuator at loaded yet: bad input naming it."""
    an = symkin.analyze(symkin.load(EXAMPLES / "piezo_amplifier.toml"))
    want = symkin.evaluate(an, {"piezo": 0.02}, "loaded").points["B"]
    got = symkin.evaluate(an, {"piezo": 0.02}, "loaded", backend="numpy").points["B"]
    assert math.dist(got.deviation, want.deviation) <= AGAINST_PYTHON * want.norm
    force = symkin.analyze(symkin.loads(driven("force"), "force.toml"))
    with pytest.raises(InputError, match=r"generated c.*force.*piezo"):
        symkin.evaluate(force, {"piezo": 0.5}, "loaded", backend="c")
    with pytest.raises(InputError, match=r"C evaluator.*force.*loaded.*piezo"):
        pipeline.emit(pipeline.plan_for(force, sensitivity=False), "c", "force.toml")


def test_a_force_without_the_plates_stiffness_has_no_generated_level():
    """A force actuator drives the generated `loaded` level alone: without the plates' E,
    thickness and width there is none, bad input naming the actuator."""
    import re

    text = "\n".join(
        line
        for line in driven("force").splitlines()
        if not re.match(r"(E|thickness|width)\b", line)
    )
    an = symkin.analyze(symkin.loads(text + "\n", "bare.toml"))
    with pytest.raises(InputError, match=r"actuator 'piezo'.*force.*loaded level alone"):
        pipeline.plan_for(an, sensitivity=False)
