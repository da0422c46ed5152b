"""The generated numpy module's `loaded` level for files with actuators (docs/physics.md,
"Actuators at loaded"; templates/numpy/reduced_actuators.py): the rigid linkage at the strokes,
the reduced equilibrium with the surrogates free, a stroke's force and a force's stroke solved
for, a force actuator's deviations against the rigid linkage at the stroke it produced.

References, none of them the code under test: symkin's Python `loaded` level (the reduced
equilibrium lambdified in mpmath, its rigid references from the mpmath kinematics) and the
`equilibrium` level (geometrically exact beams, another solver), on the piezo amplifier example
(a stroke, two strokes in one call) and the parallelogram stage pushed by a stroke and by a
force under a payload (tests/test_loaded_actuators.py's files). The C evaluator
(templates/c/actuators.c, reduced.c) takes both at loaded: strokes on the same files, forces on
the force-driven stage under its payload, a five-bar with an input hinge beside a force actuator
and that five-bar pulled near its toggle, where Newton from the as-fabricated pose fails and
continuation takes over (against the Python level in mpmath, which tests/test_loaded_actuators.py
checks against `equilibrium`).
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from conftest import EXAMPLES
from evaluators import backends_with, require_compiler
from test_loaded_actuators import AGREEMENT, PAYLOAD, driven, five_bar

import symkin
from symkin.cli.commands import main
from symkin.codegen import pipeline
from symkin.core import backends
from symkin.core.errors import InputError
from symkin.studies.physical import reduced_equilibrium

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
    require_compiler()
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


#: The C evaluator with a force actuator: name -> (file text, the configurations one call
#: takes). The five-bar's pull of 20 N brings crank c2 near its toggle (the rigid linkage
#: reaches no farther than about 9 mm the other way): Newton from the as-fabricated pose fails,
#: continuation takes 12 steps.
FORCES = {
    "five_bar_hinge_and_force": (
        lambda: five_bar("force"),
        {"O1": [0.03, -0.05, 0.03], "piezo": [0.5, 5.0, -20.0]},
    ),
}


@pytest.fixture(scope="module")
def c_forces():
    """By case: the analysis and the C evaluator's `loaded` (symkin.compile, one call for every
    configuration)."""
    cache: dict = {}

    def get(name: str, text, inputs: dict[str, list[float]]):
        if name not in cache:
            an = symkin.analyze(symkin.loads(text(), f"{name}.toml"))
            ev = symkin.compile(an, "c", levels=["loaded"], sensitivity=False)
            arrays = {k: np.array(v) for k, v in inputs.items()}
            cache[name] = (an, ev.evaluate(arrays, "loaded"))
        return cache[name]

    return get


def test_generated_c_loaded_with_a_force_under_a_payload(runs):
    """The C evaluator at loaded with a force actuator (the stage driven by 0.5 N and 0.2 N
    under a 5 N payload; symkin.evaluate --backend c) against the Python level and
    equilibrium: the deviation, the rigid reference at the stroke the force produced, the
    compliant and rigid angles, the links' rotations and deviations."""
    require_compiler()
    name = "parallelogram_force_payload"
    an, _, _, refs = runs(name)
    for v, (python, exact) in zip(CASES[name][1], refs):
        got = symkin.evaluate(an, {"piezo": v}, "loaded", backend="c")
        q, p = python.points["P"], got.points["P"]
        assert math.dist(p.deviation, q.deviation) <= AGAINST_PYTHON * q.norm  # measured 4.2e-13
        assert math.dist(p.rigid, q.rigid) <= 1e-12 * max(map(abs, q.rigid))
        e = exact.points["P"]
        assert math.dist(p.deviation, e.deviation) <= AGREEMENT[name] * e.norm, v
        for h, a in python.angles_compliant.items():
            assert abs(got.angles_compliant[h] - a) <= 1e-11, h
            assert abs(got.angles_rigid[h] - python.angles_rigid[h]) <= 1e-11, h
        top = max(abs(x.deviation) for x in python.links.values())
        for link, x in python.links.items():
            assert abs(got.links[link].deviation - x.deviation) <= 1e-9 * top, link
            assert abs(got.links[link].rigid - x.rigid) <= 1e-11, link


@pytest.mark.parametrize("k", [0, 1, 2])
def test_generated_c_loaded_five_bar_with_a_hinge_and_a_force(c_forces, k):
    """The five-bar with its input hinge O1 held and a force actuator on its other crank, in C
    against the Python level (reduced_equilibrium in mpmath, its rigid reference re-solved at
    the stroke the force produced): every point's deviation and the hinges' compliant turn. The
    third configuration, pulled near the toggle, goes through continuation in both."""
    require_compiler()
    name = "five_bar_hinge_and_force"
    text, inputs = FORCES[name]
    an, got = c_forces(name, text, inputs)
    given = {n: v[k] for n, v in inputs.items()}
    python = reduced_equilibrium(an, given, backend="sympy")
    assert not python.refused and (python.steps > 1) == (k == 2)
    assert got["ok"][k] and set(got["points"]) == {"Q", "T"}
    for p, d in python.deviations.items():
        # measured 3.2e-12 (k = 0) and below 1e-11 through the continuation
        assert math.dist(got["points"][p]["deviation"][:, k], d) <= AGAINST_PYTHON * math.hypot(*d)
    angles = got["angles"]
    for h, v in python.angle_deviations.items():
        assert abs(angles["compliant"][h][k] - angles["rigid"][h][k] - v) <= 1e-11, h


def test_cli_numpy_and_c_backends_with_actuators(tmp_path, capsys):
    """eval --level loaded --backend numpy takes the stroke (the Python level's deviation);
    --backend c takes a force (exit 0, the Python level's deviation); a force at a kinematic
    level is still bad input naming the actuator (exit 2)."""
    an = symkin.analyze(symkin.load(EXAMPLES / "piezo_amplifier.toml"))
    want = symkin.evaluate(an, {"piezo": 0.02}, "loaded").points["B"]
    got = symkin.evaluate(an, {"piezo": 0.02}, "loaded", backend="numpy").points["B"]
    assert math.dist(got.deviation, want.deviation) <= AGAINST_PYTHON * want.norm
    force = tmp_path / "force.toml"
    force.write_text(driven("force"))
    require_compiler()
    argv = ["eval", str(force), "--input", "piezo=0.5", "--level", "loaded", "--json"]
    out = {}
    for backend in ("sympy", *backends_with(generated=True, forces="loaded")):
        assert main([*argv, "--backend", backend]) == 0, backend
        out[backend] = json.loads(capsys.readouterr().out)["points"]["P"]["deviation"]
    ref = out.pop("sympy")
    for backend, got in out.items():
        assert math.dist(got, ref) <= 1e-10 * math.hypot(*ref), backend
    for backend in backends_with(generated=True):
        assert "exact" not in backends.get(backend).forces
        exact = ["eval", str(force), "--input", "piezo=0.5", "--level", "exact"]
        assert main([*exact, "--backend", backend]) == 2
        assert "actuator 'piezo'" in capsys.readouterr().err


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
