"""The generated numpy module's "buckling" at `loaded` (docs/generated-code.md, "What `loaded`
reports in generated code"; templates/numpy/reduced_report.py's _red_buckling): the smallest
factor on the file's loads and force actuators' forces, the inputs held, at which the tangent
stiffness becomes singular, every configuration of a batch searched at once.

References, not the code under test: the Python `loaded` level's buckling factor
(symkin.physics.reduced_reported.buckling_factor on the float64 Python solver of the same
derivation, each configuration alone) and, for the stroke-held stage whose legs buckle together,
Euler's 2π²E'I/l² (tests/test_loaded_actuators.py). Mechanisms: the parallelogram stage pushed
down along its legs with its input hinge held, the stage driven by a force actuator under a
payload, the stroke-driven stage under 300 N at zero stroke; the stage without loads has no
"buckling".
"""

from __future__ import annotations

import math
import types

import numpy as np
import pytest
from conftest import EXAMPLES
from test_loaded_actuators import E_PRIME, PAYLOAD, PLATE, THICK, WIDTH, driven
from test_loaded_reported import ZOO
from test_loaded_reported_codegen import relative

import symkin
from symkin.codegen import pipeline
from symkin.studies import sweep

#: the stroke-held stage's payload (N)
HELD = 300.0


def stage_payload() -> str:
    """The parallelogram stage under a 200 N payload down along its legs (its input F1)."""
    base = (ZOO / "parallelogram.toml").read_text()
    text = base.replace("[parameters]\n", "[parameters]\nW = 200\n")
    return text + '\n[[load]]\npoint = "P"\nforce = [0.0, "-W"]\n'


#: name -> (file text, the configurations one call takes)
CASES = {
    "stage_payload": (stage_payload, {"F1": [0.0]}),
    "stage_force": (lambda: driven("force", PAYLOAD), {"piezo": [0.5, 0.2]}),
    "stage_stroke_held": (
        lambda: driven("stroke", PAYLOAD.replace("-5.0", f"-{HELD}")),
        {"piezo": [0.0]},
    ),
}
#: generated against the Python level (relative): both bisect to 1e-10 of t, from solutions
#: that differ in their last digits (the Python level's kernels in mpmath).
#: Measured 3.3e-9 (the stage, its input held), 0 (force-driven), 2.1e-9 (stroke-held).
AGREEMENT = 1e-7


@pytest.fixture(scope="module")
def runs():
    """By case: the analysis, numpy module and its evaluate() at every configuration at once
    (derived and computed on first use)."""
    cache: dict = {}

    def get(name: str):
        if name not in cache:
            text, batch = CASES[name]
            an = symkin.analyze(symkin.loads(text(), f"{name}.toml"))
            _, module = pipeline.build(an, "numpy", "test", sensitivity=False)
            got = module.evaluate(
                {k: np.array(v) for k, v in batch.items()}, "loaded", buckling=True
            )
            cache[name] = an, module, got
        return cache[name]

    return get


@pytest.mark.parametrize("name", list(CASES))
def test_generated_buckling_is_the_python_levels(runs, name):
    an, _, got = runs(name)
    batch = CASES[name][1]
    assert got["ok"].all()
    assert got["buckling"].shape == got["ok"].shape
    for c in range(got["ok"].size):
        want = symkin.evaluate(an, {k: v[c] for k, v in batch.items()}, "loaded").buckling
        assert want is not None and 1 < want < 10
        assert relative(got["buckling"][c], want) <= AGREEMENT, (c, got["buckling"][c], want)


def test_legs_held_by_a_stroke_buckle_at_eulers_load(runs):
    """Each leg's two plates clamped-guided columns under half the payload: 2 pi^2 E'I/l^2
    (tests/test_loaded_actuators.py: loaded finds it 0.17 % below, the legs' turn coupling)."""
    *_, got = runs("stage_stroke_held")
    euler = 2 * math.pi**2 * E_PRIME * WIDTH * THICK**3 / 12 / PLATE**2
    assert got["buckling"][0] * HELD == pytest.approx(euler, rel=5e-3)


def test_configurations_at_once_are_each_alone(runs):
    """A batch (here of shape (2, 1), one configuration not solved) gives every configuration
    the factor it gets alone, bit for bit: each has its own steps; NaN where not ok."""
    _, module, got = runs("stage_force")
    forces = CASES["stage_force"][1]["piezo"]
    many = module.evaluate({"piezo": np.array([[forces[1]], [math.nan]])}, "loaded", buckling=True)
    assert many["buckling"].shape == (2, 1)
    assert many["ok"].tolist() == [[True], [False]] and math.isnan(many["buckling"][1, 0])
    assert many["buckling"][0, 0] == got["buckling"][1]
    for c, force in enumerate(forces):
        alone = module.evaluate({"piezo": np.array([force])}, "loaded", buckling=True)
        assert alone["buckling"][0] == got["buckling"][c]


def test_buckling_only_when_asked(runs, monkeypatch):
    """The default call leaves the buckling factor out (docs/generated-code.md: only with
    buckling=True) and runs no search; buckling=False says so too: the rest of the report, the
    same numbers."""
    _, module, got = runs("stage_force")
    forces = {"piezo": np.array(CASES["stage_force"][1]["piezo"])}
    bare = module.evaluate(forces, "loaded", buckling=False)

    def searched(*args):
        raise AssertionError("the buckling search ran")

    monkeypatch.setattr(module, "_red_buckling", searched)
    default = module.evaluate(forces, "loaded")
    for result in (bare, default):
        assert "buckling" not in result and "plates" in result
        for h, plate in got["plates"].items():
            assert np.array_equal(result["plates"][h]["stress"], plate["stress"]), h


def test_sweep_reads_the_stress_without_the_search(runs, monkeypatch):
    """`sweep --level loaded` reads the plates' stress alone (sweep.largest_stress): the same
    stress, the buckling search not run."""
    _, module, got = runs("stage_force")

    def searched(*args):
        raise AssertionError("the buckling search ran")

    monkeypatch.setattr(module, "_red_buckling", searched)
    forces = np.array(CASES["stage_force"][1]["piezo"])[:, None]
    with pytest.raises(AssertionError, match="search ran"):  # the stand-in is the one called
        module.evaluate({"piezo": forces[:, 0]}, "loaded", buckling=True)
    evaluator = types.SimpleNamespace(module=module, inputs=module.INPUTS)
    plates = tuple(got["plates"])
    for h, value in zip(plates, sweep.largest_stress(evaluator, forces, None, plates)):
        assert value == got["plates"][h]["stress"].max(), h


def test_without_loads_there_is_no_buckling():
    an = symkin.analyze(symkin.loads(driven("stroke"), "unloaded.toml"))
    _, module = pipeline.build(an, "numpy", "test", sensitivity=False)
    got = module.evaluate({"piezo": np.array([1.5e-3])}, "loaded", buckling=True)
    assert got["ok"].all() and "plates" in got and "buckling" not in got
    assert symkin.evaluate(an, {"piezo": 1.5e-3}, "loaded").buckling is None


def test_compile_leaves_the_report_or_the_buckling_out_when_told(runs):
    """symkin.compile(...).evaluate takes report=False and buckling=True/False to the numpy
    module; its default leaves the search out, as the module's does."""
    an, _, got = runs("stage_force")
    ev = symkin.compile(an, backend="numpy", sensitivity=False)
    forces = {"piezo": np.array(CASES["stage_force"][1]["piezo"])}
    full = ev.evaluate(forces, "loaded", buckling=True)
    assert np.array_equal(full["buckling"], got["buckling"], equal_nan=True)
    for bare in (ev.evaluate(forces, "loaded", buckling=False), ev.evaluate(forces, "loaded")):
        assert "buckling" not in bare and "plates" in bare
    alone = ev.evaluate(forces, "loaded", report=False)
    assert "plates" not in alone and "buckling" not in alone
    assert np.array_equal(alone["points"]["P"]["deviation"], got["points"]["P"]["deviation"])
    # a module without the loaded level's report takes the flags and has nothing to leave out
    kin = symkin.compile(EXAMPLES / "four_bar.toml", "numpy", levels=["exact"], sensitivity=False)
    a0 = {"A0": np.array([0.1, 0.2])}
    plain, told = kin.evaluate(a0), kin.evaluate(a0, report=False, buckling=True)
    assert set(told) == set(plain)
    assert np.array_equal(told["points"]["C"]["deviation"], plain["points"]["C"]["deviation"])
