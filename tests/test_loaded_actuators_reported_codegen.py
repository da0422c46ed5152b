"""What the generated numpy module's `evaluate()` reports at `loaded` beyond the deviations for
files with actuators (docs/physics.md, "What loaded reports", "Actuators at loaded";
templates/numpy/reduced_actuators.py's _actuated_report over reduced_report.py): every
actuator's stroke, force and dF/ds with the other inputs held, the input hinges' moments and
dM/dθ, every shown point's 3×3 stiffness with the inputs and actuators held (a stroke that holds
the point along its line: NaN), every plate's largest stress.

Reference, not the code under test: symkin's Python `loaded` report
(symkin.physics.reduced_reported over symkin.studies.evaluation's reduced equilibrium, lambdified
in mpmath; a force actuator's reference solved again at the stroke it produced, its plate stress
by the Taylor-series beam integrator, not RK4), itself tested against `equilibrium`
(tests/test_loaded_actuators.py). Mechanisms: the piezo amplifier example (a stroke), the
parallelogram stage pushed by a stroke (its stage held along the stroke's line: no stiffness), the
stage driven by a force under a payload, the five-bar with an input hinge beside a force actuator
(tests/test_loaded_actuators.py's files). The C evaluator reports none of this with actuators yet:
its files keep no report routines (tests/test_generated.py: the example's C files unchanged).
"""

from __future__ import annotations

import math
import types

import numpy as np
import pytest
from test_loaded_actuators import CASES as ACTUATED
from test_loaded_reported_codegen import relative, rows_close

import symkin
from symkin.codegen import pipeline
from symkin.physics import reduced_reported
from symkin.studies import sweep
from symkin.studies.evaluation import reduced_equilibrium

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
#: 8.2e-13.
VALUES, STIFFNESS, STRESS = 1e-10, 1e-9, 1e-10


@pytest.fixture(scope="module")
def runs():
    """By case: the numpy module, its evaluate() at both configurations at once, and per
    configuration the Python level's report (derived and computed on first use)."""
    cache: dict = {}

    def get(name: str):
        if name not in cache:
            text, batch = CASES[name]
            an = symkin.analyze(symkin.loads(text(), f"{name}.toml"))
            # as tests/test_loaded_actuators_codegen.py's: one plan (the run's plan cache)
            _, module = pipeline.build(an, "numpy", "test", sensitivity=False)
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
            cache[name] = module, got, want
        return cache[name]

    return get


def worst(pairs) -> float:
    """The largest relative difference of (got, want) pairs."""
    return max((relative(g, w) for g, w in pairs), default=0.0)


@pytest.mark.parametrize("name", list(CASES))
def test_generated_numpy_reports_what_the_python_level_reports(runs, name):
    _, got, want = runs(name)
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
        assert set(got["plates"]) == set(rep.plates) != set()
        for h, w in rep.plates.items():
            g = got["plates"][h]
            assert worst([(g["stress"][c], w.stress), (g["strain"][c], w.strain)]) <= STRESS, h
            assert g["section"][c] == pytest.approx(w.section, abs=1e-6)
            assert w.safety is None and math.isnan(g["safety"][c])


def test_report_false_leaves_the_report_out(runs):
    """evaluate(..., report=False) at loaded: the deviations alone, the same numbers."""
    module, got, _ = runs("piezo_amplifier")
    bare = module.evaluate(
        {"piezo": np.array(CASES["piezo_amplifier"][1]["piezo"])}, "loaded", report=False
    )
    assert not {"actuators", "inputs", "stiffness", "plates"} & set(bare)
    assert np.array_equal(bare["points"]["B"]["deviation"], got["points"]["B"]["deviation"])


def test_sweep_reads_the_plates_stress_with_an_actuator(runs):
    """`symkin sweep --level loaded` keeps every plate's largest stress over the grid per
    sample from the module's report (sweep.largest_stress, as for a file without actuators):
    over the piezo amplifier's two strokes, the Python level's largest."""
    module, _, want = runs("piezo_amplifier")
    strokes = np.array(CASES["piezo_amplifier"][1]["piezo"])[:, None]
    evaluator = types.SimpleNamespace(module=module, inputs=module.INPUTS)
    plates = tuple(want[0].plates)
    got = sweep.largest_stress(evaluator, strokes, None, plates)
    for h, value in zip(plates, got):
        assert relative(value, max(rep.plates[h].stress for rep in want)) <= STRESS, h
