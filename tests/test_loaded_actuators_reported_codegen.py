"""What the generated numpy module's `evaluate()` and the C evaluator's `<name>_loaded_report`
report at `loaded` beyond the deviations for files with actuators (docs/physics.md, "What loaded
reports", "Actuators at loaded"; templates/numpy/reduced_actuators.py's _actuated_report over
reduced_report.py, templates/c/actuators.c's sk_actuated_report over reduced_report.c): every
actuator's stroke, force and dF/ds with the other inputs held, the input hinges' moments and
dM/dθ, every shown point's 3×3 stiffness with the inputs and actuators held (a stroke that holds
the point along its line: NaN), every plate's largest stress.

Reference, not the code under test: symkin's Python `loaded` report
(symkin.physics.reduced_reported over symkin.studies.physical's reduced equilibrium, lambdified
in mpmath; a force actuator's reference solved again at the stroke it produced, its plate stress
by the Taylor-series beam integrator, not RK4), itself tested against `equilibrium`
(tests/test_loaded_actuators.py). Mechanisms: the piezo amplifier example (a stroke), the
parallelogram stage pushed by a stroke (its stage held along the stroke's line: no stiffness), the
stage driven by a force under a payload, the five-bar with an input hinge beside a force actuator
(tests/test_loaded_actuators.py's files). The C evaluator is compiled from the numpy module's
plan, once per case.
"""

from __future__ import annotations

import ctypes
import math
import types

import numpy as np
import pytest
from evaluators import require_compiler
from test_loaded_actuators import CASES as ACTUATED
from test_loaded_reported_codegen import (
    REPORTING,
    c_report,
    relative,
    rows_close,
)

import symkin
from symkin.codegen import pipeline
from symkin.core import backends
from symkin.physics import reduced_reported
from symkin.studies import sweep
from symkin.studies.physical import reduced_equilibrium

#: name -> (file text, the inputs one call takes: two configurations each)
CASES = {
    "piezo_amplifier": (ACTUATED["piezo_amplifier"][0], {"piezo": [0.02, 0.005]}),
    "parallelogram_stroke": (ACTUATED["parallelogram_stroke"][0], {"piezo": [1.5e-3, -0.5e-3]}),
    "parallelogram_force_payload": (
        ACTUATED["parallelogram_force_payload"][0],
        {"piezo": [0.5, 0.2]},
    ),
    "five_bar_hinge_and_force": (
        ACTUATED["five_bar_hinge_and_force"][0],
        {"O1": [0.03, -0.01], "piezo": [0.5, 0.3]},
    ),
}
#: generated (float64, RK4) against the Python level (mpmath): relative differences of the
#: moments, dM/dθ, forces, strokes and dF/ds; the point stiffness (of each row's largest entry);
#: the plates' stress and strain. Measured at most 4.7e-13, 2.8e-11 (the payload's stage) and
#: 8.2e-13 (numpy); C the same (its RK4 and solves are numpy's).
VALUES, STIFFNESS, STRESS = 1e-10, 1e-9, 1e-10


@pytest.fixture(scope="module")
def runs():
    """By case: the plan and numpy module, its evaluate() at both configurations at once, and per
    configuration the Python level's report (derived and computed on first use)."""
    cache: dict = {}

    def get(name: str):
        if name not in cache:
            text, batch = CASES[name]
            an = symkin.analyze(symkin.loads(text(), f"{name}.toml"))
            # as tests/test_loaded_actuators_codegen.py's: one plan (the run's plan cache)
            plan, module = pipeline.build(an, "numpy", "test", sensitivity=False)
            got = module.evaluate({k: np.array(v) for k, v in batch.items()}, "loaded")
            scale = float(an.mechanism.unit_scale)
            count = len(next(iter(batch.values())))
            want = []
            for c in range(count):
                answer = reduced_equilibrium(
                    an, {k: v[c] for k, v in batch.items()}, backend="sympy"
                )
                assert not answer.refused, answer.refused
                want.append(reduced_reported.report(answer, scale, buckling=False))
            cache[name] = plan, module, got, want
        return cache[name]

    return get


@pytest.fixture(scope="module")
def c_runs(runs):
    """By case: the C library compiled from the case's plan and its <name>_loaded_report at the
    same configurations, shaped as the numpy module's result (on first use)."""
    cache: dict = {}

    def get(name: str):
        if name not in cache:
            plan = runs(name)[0]
            lib = pipeline.evaluator(plan, "c", "test", links=False).lib
            cache[name] = lib, c_report(plan, CASES[name][1], lib)
        return cache[name]

    return get


def worst(pairs) -> float:
    """The largest relative difference of (got, want) pairs."""
    return max((relative(g, w) for g, w in pairs), default=0.0)


@pytest.mark.parametrize("backend", REPORTING)
@pytest.mark.parametrize("name", list(CASES))
def test_generated_code_reports_what_the_python_level_reports(runs, c_runs, name, backend):
    if backends.get(backend).compiler:
        require_compiler()
    # the numpy module's report (runs) or the C's <name>_loaded_report (c_runs)
    got = {"numpy": lambda: runs(name)[2], "c": lambda: c_runs(name)[1]}[backend]()
    want = runs(name)[3]
    assert got["ok"].all()
    for c, rep in enumerate(want):
        assert set(got["actuators"]) == set(rep.actuators) == {"piezo"}
        for a, w in rep.actuators.items():
            g = got["actuators"][a]
            pairs = [(g[key][c], getattr(w, key)) for key in ("stroke", "force", "stiffness")]
            assert worst(pairs) <= VALUES, (a, c, pairs)
        assert set(got["inputs"]) == set(rep.inputs)
        for h, w in rep.inputs.items():
            g = got["inputs"][h]
            assert g["angle"][c] == pytest.approx(w.angle, rel=0, abs=1e-15)
            assert worst([(g["moment"][c], w.moment), (g["stiffness"][c], w.stiffness)]) <= VALUES
        # every point of the file (not the actuators' points of action)
        assert set(got["stiffness"]) == set(rep.stiffness) != set()
        for p, w in rep.stiffness.items():
            k = got["stiffness"][p][..., c]
            if w is None:
                assert np.isnan(k).all(), p
            else:
                assert rows_close(k, w, STIFFNESS), (p, c, k, w)
        assert set(got["compliance"]) == set(rep.compliance) == set(rep.stiffness)
        for p, w in rep.compliance.items():
            k = got["compliance"][p][..., c]
            assert w is not None and rows_close(k, w, STIFFNESS), (p, c, k, w)
        assert set(got["plates"]) == set(rep.plates) != set()
        for h, w in rep.plates.items():
            g = got["plates"][h]
            assert worst([(g["stress"][c], w.stress), (g["strain"][c], w.strain)]) <= STRESS, h
            assert g["section"][c] == pytest.approx(w.section, abs=1e-6)
            assert w.safety is None and math.isnan(g["safety"][c])


def test_report_false_leaves_the_report_out(runs):
    """evaluate(..., report=False) at loaded: the deviations alone, the same numbers."""
    _, module, got, _ = runs("piezo_amplifier")
    bare = module.evaluate(
        {"piezo": np.array(CASES["piezo_amplifier"][1]["piezo"])}, "loaded", report=False
    )
    assert not {"actuators", "inputs", "stiffness", "plates"} & set(bare)
    assert np.array_equal(bare["points"]["B"]["deviation"], got["points"]["B"]["deviation"])


def test_sweep_reads_the_plates_stress_with_an_actuator(runs):
    """`symkin sweep --level loaded` keeps every plate's largest stress over the grid per
    sample from the module's report (sweep.largest_stress, as for a file without actuators):
    over the piezo amplifier's two strokes, the Python level's largest."""
    _, module, _, want = runs("piezo_amplifier")
    strokes = np.array(CASES["piezo_amplifier"][1]["piezo"])[:, None]
    evaluator = types.SimpleNamespace(module=module, inputs=module.INPUTS)
    plates = tuple(want[0].plates)
    got = sweep.largest_stress(evaluator, strokes, None, plates)
    for h, value in zip(plates, got):
        assert relative(value, max(rep.plates[h].stress for rep in want)) <= STRESS, h


def test_c_report_is_numpy_s(runs, c_runs):
    """The C report against the numpy module's on every case, to rounding (the same solves and
    RK4, in another order); a force actuator's dF/ds is 1/(ds/dF) in both."""
    require_compiler()
    for name in CASES:
        _, _, want, _ = runs(name)
        got = c_runs(name)[1]
        for a, entry in want["actuators"].items():
            for key, w in entry.items():
                assert np.allclose(got["actuators"][a][key], w, rtol=1e-12, atol=0), (name, a)
        for p, w in want["stiffness"].items():
            for c in range(w.shape[-1]):
                if np.isnan(w[..., c]).all():
                    assert np.isnan(got["stiffness"][p][..., c]).all(), (name, p)
                else:
                    assert rows_close(got["stiffness"][p][..., c], w[..., c], STIFFNESS), (name, p)
        for p, w in want["compliance"].items():
            for c in range(w.shape[-1]):
                assert rows_close(got["compliance"][p][..., c], w[..., c], STIFFNESS), (name, p)
        for h, w in want["plates"].items():
            assert np.allclose(got["plates"][h]["stress"], w["stress"], rtol=1e-12), (name, h)


def test_c_report_refuses_what_its_evaluate_refuses(runs, c_runs):
    """A bad argument (a stroke or a force that is not finite, a NULL input) returns 3 and out
    all NaN, the actuators' block too, as <name>_evaluate at loaded; the actuators' names."""
    require_compiler()
    for name in ("piezo_amplifier", "parallelogram_force_payload"):
        plan = runs(name)[0]
        lib = c_runs(name)[0]
        rep = plan.loaded.report
        size = 2 * len(rep.inputs) + 18 * len(rep.points) + 4 * len(rep.plates) + 3
        out = (ctypes.c_double * size)()
        bad = (ctypes.c_double * 1)(math.nan)
        assert getattr(lib, f"{plan.name}_loaded_report")(bad, None, out) == 3, name
        assert all(math.isnan(v) for v in out)
        assert getattr(lib, f"{plan.name}_loaded_report")(None, None, out) == 3
        values = (ctypes.c_double * (6 * len(plan.shown_points)))()
        assert getattr(lib, f"{plan.name}_evaluate")(bad, None, 3, values) == 3, name
        names = ctypes.c_char_p.in_dll(lib, f"{plan.name}_report_actuator_names")
        assert names.value == b"piezo"
