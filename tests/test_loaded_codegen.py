"""The `loaded` level in the generated numpy and C evaluators: the reduced equilibrium
(docs/physics.md, "`loaded`: Newton on the reduced equilibrium";
templates/numpy/reduced.py, templates/c/reduced.c)
against the Python solver symkin.physics.reduced (reduced_equilibrium, float64 kernels) to 1e-9
and against the `equilibrium` level (mpmath, the geometrically exact beams) within the Python
solver's own bound, 1e-3 (tests/test_loaded_newton.py).

Cases: the four-bar and mechanisms unlike the examples (tests/mechanisms/): a parallelogram, a
Scott-Russell with its preload, a double parallelogram with a payload, the redundant three-leg
stage (refused at `loaded` before), the toggle four-bar; the parallelogram pressed to 80 % of its
first buckling factor (two half plates per plate needed) and past its buckling (refused alike in
numpy and C); parameter overrides; a batch; a file with actuators (no `loaded`).
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest
from conftest import EXAMPLES
from evaluators import backends_with, require

import symkin
from symkin.codegen import pipeline
from symkin.codegen.plan import plan
from symkin.physics import equilibrium as equilibrium_physics
from symkin.physics import reduced
from symkin.studies.physical import reduced_equilibrium

ZOO = Path(__file__).resolve().parent / "mechanisms"

#: (file, inputs): the four-bar and the zoo at their own loads and parameters
CASES = {
    "four_bar": (EXAMPLES / "four_bar.toml", {"A0": 0.3}),
    "parallelogram": (ZOO / "parallelogram.toml", {"F1": 0.05}),
    "scott_russell": (ZOO / "scott_russell.toml", {"RA0": 0.01}),
    "double_parallelogram": (ZOO / "double_parallelogram.toml", {"F1": 0.05, "I1": -0.05}),
    "three_leg_stage": (ZOO / "three_leg_stage.toml", {"F1": 0.05}),
    "toggle_four_bar": (ZOO / "toggle_four_bar.toml", {"O1": 0.3}),
}

_BUILT: dict = {}
#: The generated backends that hold the `loaded` level (the backend table).
LOADED = backends_with(generated=True, levels="loaded")


def _built(path: Path, backend: str):
    """(analysis, plan, evaluator) of `path` for `backend`, built once."""
    key = (str(path), backend)
    if key not in _BUILT:
        an = _BUILT.get(str(path)) or symkin.analyze(symkin.load(path))
        _BUILT[str(path)] = an
        require(backend)
        p, ev = pipeline.build(an, backend, path.name, sensitivity=False)
        _BUILT[key] = (an, p, ev)
    return _BUILT[key]


def _pose(path: Path, backend: str, inputs: dict, params: dict | None = None):
    """(status, {point: deviation}, plan) of the generated evaluator at `loaded`."""
    _, p, ev = _built(path, backend)
    row, shape = pipeline.backend(backend), pipeline.Shape.of(p)
    values = None if params is None else [params.get(n, None) for n in shape.params]
    if values is not None:
        defaults = {q.name: q.value for q in p.parameters}
        values = [defaults[n] if v is None else v for n, v in zip(shape.params, values)]
    status, out, _, _ = row.pose(ev, shape, [inputs[n] for n in shape.inputs], values, "loaded")
    return status, {n: tuple(out[6 * i + 4 : 6 * i + 6]) for i, n in enumerate(shape.points)}


def _rel(got, want) -> float:
    return math.dist(got, want) / math.hypot(*want)


def _loaded_parallelogram(tmp: Path, fraction: float) -> Path:
    """The parallelogram with a dead load pressing the stage down, `fraction` times the force
    that puts each plate at its Euler load π²EI/l² (E' = E/(1 - ν²): a wide plate)."""
    ei = 210e9 / (1 - 0.3**2) * 10e-3 * (0.15e-3) ** 3 / 12
    force = 2 * fraction * math.pi**2 * ei / 5e-3**2
    text = (ZOO / "parallelogram.toml").read_text()
    text += f'\n[[load]]\nlink = "stage"\nat = ["w/2", "L"]\nforce = [0.0, {-force!r}]\n'
    path = tmp / f"parallelogram_load_{fraction}.toml"
    path.write_text(text)
    return path


@pytest.mark.parametrize("backend", LOADED)
@pytest.mark.parametrize("key", sorted(CASES))
def test_loaded_is_the_reduced_equilibrium(key, backend):
    """Every point's deviation within 1e-9 of the Python solver's (the same float64 arithmetic
    in another order)."""
    path, inputs = CASES[key]
    an = _built(path, backend)[0]
    want = reduced_equilibrium(an, inputs, backend="numpy")
    assert not want.refused, want.refused
    (
        status,
        got,
    ) = _pose(path, backend, inputs)[:2]
    assert status == 0
    assert got.keys() == want.deviations.keys()
    for name, dev in got.items():
        assert _rel(dev, want.deviations[name]) <= 1e-9, name


@pytest.mark.parametrize("key", ["four_bar", "three_leg_stage", "scott_russell"])
def test_loaded_against_equilibrium(key):
    """C's `loaded` within the Python solver's bound (1e-3) of the `equilibrium` level, and not
    the old linearised statics' answer: two mechanisms unlike the examples, one redundant."""
    path, inputs = CASES[key]
    an = _built(path, "c")[0]
    reference = symkin.evaluate(an, inputs, level="equilibrium")
    status, got = _pose(path, "c", inputs)
    assert status == 0
    for name, point in reference.points.items():
        assert _rel(got[name], point.deviation) < 1e-3, name


def test_the_redundant_stage_holds_loaded():
    """The three-leg stage (redundant loops) was refused at `loaded`: its plan holds it now."""
    an = _built(CASES["three_leg_stage"][0], "numpy")[0]
    assert an.redundant
    assert "loaded" in [lv.name for lv in plan(an, sensitivity=False).levels]


def test_actuators_get_loaded():
    """A file with stroke actuators gets the generated `loaded` level, numpy and C
    (tests/test_loaded_actuators_codegen.py); with a force actuator its C keeps the kinematic
    levels (none here: a force needs a physical level)."""
    an = symkin.analyze(symkin.load(EXAMPLES / "piezo_amplifier.toml"))
    p = plan(an, sensitivity=False)
    assert "loaded" in [lv.name for lv in p.levels]
    assert p.loaded is not None and p.loaded.surrogate_index == (0,)  # RA0, the piezo's
    header, source = pipeline.emit(p, "c", "piezo_amplifier.toml")
    assert "levels: paper, first_order, exact, loaded.\n" in header
    assert "sk_loaded_unknown_index" in source


@pytest.mark.parametrize("backend", LOADED)
def test_parameter_overrides(backend):
    """The parameters are read at run time: a thinner plate gives the Python solver's answer
    there (the scales of Newton stay the defaults'), not the defaults'."""
    path, inputs = CASES["four_bar"]
    an = _built(path, backend)[0]
    names = [q.name for q in an.mechanism.parameters]
    assert "l" in names
    want = reduced_equilibrium(an, inputs, params={"l": "4e-3"})
    base = reduced_equilibrium(an, inputs)
    status, got = _pose(path, backend, inputs, {"l": 4e-3})
    assert status == 0
    for name, dev in got.items():
        assert _rel(dev, want.deviations[name]) <= 1e-9, name
        assert _rel(dev, base.deviations[name]) > 1e-3, name


def test_numpy_batch_is_elementwise():
    """A batch (with a configuration beyond pi that is not ok) gives each element's answer."""
    path, _ = CASES["four_bar"]
    an, _, module = _built(path, "numpy")
    values = np.array([0.05, 0.3, -0.2, 4.0])
    res = module.evaluate({"A0": values}, "loaded")
    assert res["ok"].tolist() == [True, True, True, False]
    for k, a in enumerate(values[:3]):
        want = reduced_equilibrium(an, {"A0": float(a)}).deviations["C"]
        assert _rel(res["points"]["C"]["deviation"][:, k], want) <= 1e-9
        # solved with the batch, bit for bit as alone
        alone = module.evaluate({"A0": values[k : k + 1]}, "loaded")["points"]["C"]["deviation"]
        assert np.array_equal(alone[:, 0], res["points"]["C"]["deviation"][:, k])


def test_links_and_angles_agree_between_numpy_and_c():
    """The links' rotations (the `links` routine reads δ of the non-input hinges) and the
    compliant angles: numpy and C alike, and the compliant angles move."""
    path, inputs = CASES["four_bar"]
    _, p, _ = _built(path, LOADED[0])
    shape = pipeline.Shape.of(p)
    got = {}
    for backend in LOADED:
        ev = _built(path, backend)[2]
        row = pipeline.backend(backend)
        got[backend] = row.pose(ev, shape, [inputs[n] for n in shape.inputs], None, "loaded")
    s1, _, a1, l1 = got[LOADED[0]]
    assert s1 == 0
    for backend in LOADED[1:]:
        s2, _, a2, l2 = got[backend]
        assert s2 == 0, backend
        assert np.allclose(a1, a2, rtol=1e-9, atol=1e-15), backend
        assert np.allclose(l1, l2, rtol=1e-9, atol=1e-15), backend
    m = len(shape.hinges)
    assert max(abs(c - r) for r, c in zip(a1[:m], a1[m:])) > 1e-6


@pytest.fixture
def no_buckling_search(monkeypatch):
    # only equilibrium's deviations are compared: its buckling-factor search, which it runs
    # after solving (and which can stop short this close to the plates' Euler load), is left out
    monkeypatch.setattr(equilibrium_physics, "buckling_factor", lambda *args, **kwargs: None)


@pytest.mark.usefixtures("no_buckling_search")
def test_two_half_plates_near_buckling(tmp_path):
    """Plates pressed to 80 % of the first buckling factor: one plate relation is refused by its
    truncation estimate; numpy and C chain two half plates, as the Python solver does."""
    path = _loaded_parallelogram(tmp_path, 0.654)
    inputs = {"F1": 0.05}
    an = _built(path, "numpy")[0]
    assert reduced_equilibrium(an, inputs, segments=1).refused.startswith("truncation")
    want = reduced_equilibrium(an, inputs)
    assert want.segments == 2 and not want.refused
    reference = symkin.evaluate(an, inputs, level="equilibrium")
    for backend in LOADED:
        status, got = _pose(path, backend, inputs)
        assert status == 0, backend
        for name, dev in got.items():
            assert _rel(dev, want.deviations[name]) <= 1e-9, (backend, name)
            assert _rel(dev, reference.points[name].deviation) < 1e-3, (backend, name)


def test_past_buckling_is_refused_alike(tmp_path):
    """A load past the mechanism's buckling: refused by the Python solver, and the generated
    evaluators give the same status (1, NaN out), which symkin eval turns into exit 3."""
    path = _loaded_parallelogram(tmp_path, 0.93)
    inputs = {"F1": 0.05}
    an = _built(path, "numpy")[0]
    assert reduced_equilibrium(an, inputs).refused
    statuses = []
    for backend in LOADED:
        status, got = _pose(path, backend, inputs)
        statuses.append(status)
        assert all(math.isnan(v) for dev in got.values() for v in dev)
    assert statuses == [1] * len(LOADED)


def test_continuation_alike(monkeypatch):
    """Newton's turn limit lowered (3e-4 rad) so that the parallelogram needs continuation: numpy
    and C follow the Python solver's path to its answer (the last Newton step's J at s = 1 is the
    configuration's own)."""
    rules = dataclasses.replace(reduced.RULES, max_turn=3e-4)
    monkeypatch.setattr(reduced, "RULES", rules)
    path, inputs = CASES["parallelogram"]
    an = _built(path, "numpy")[0]
    want = reduced_equilibrium(an, inputs)
    assert want.steps > 1 and not want.refused
    p = pipeline.plan_for(an, sensitivity=False)
    assert p.loaded is not None
    p = dataclasses.replace(p, solver=dataclasses.replace(p.solver, loaded=rules))
    shape = pipeline.Shape.of(p)
    for backend in LOADED:
        require(backend)
        ev = pipeline.evaluator(p, backend, path.name, "float64", True, False)
        row = pipeline.backend(backend)
        status, out, _, _ = row.pose(ev, shape, [inputs[n] for n in shape.inputs], None, "loaded")
        assert status == 0, backend
        for i, name in enumerate(shape.points):
            assert _rel(out[6 * i + 4 : 6 * i + 6], want.deviations[name]) <= 1e-9, backend


def test_rest_relation_is_the_relation_without_force():
    """plate_rest4 (the drivers' relation where a plate carries no force) gives plate_relation4's
    values and partials at p = f = 0, to rounding, over the angles the level meets."""
    module = _built(CASES["four_bar"][0], "numpy")[2]
    for theta in np.linspace(-2.0, 2.0, 41):
        for e_a, e_s in ((0.0, 0.0), (3e-5, 1e-4), (1e-3, 4e-3)):
            plate = [theta, 0.0, 0.0, e_a, e_s]
            rest = [float(v) for v in module._plate_rest4(plate)]
            full = [float(v) for v in module._plate_relation4(plate)]
            assert np.allclose(rest, full, rtol=1e-13, atol=0.0), theta
