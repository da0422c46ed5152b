"""The generated numpy module's modes() (docs/generated-code.md, "Natural frequencies in
generated code") against `symkin modes --level loaded` (symkin.studies.modes: the 40-digit
derivation's compliance, an independent implementation) and the formulas of tests/test_modes.py:
a leaf-spring stage pushed by a force actuator held at its force, two stacked stages (the two-mass
chain), a stage preloaded toward buckling, and the lumped parallelogram held at its input hinge
(no actuator: the module's own blocks)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from cli_runs import symkin_cli
from test_modes import EI, PARALLELOGRAM, leaf_stiffness, stacked, stage, sway

import symkin
from symkin.studies.modes import modes

AGREE = 1e-9  # the numpy module against the sympy path, relative


def compiled(text: str, name: str, tmp_path_factory):
    path = tmp_path_factory.mktemp("modes") / f"{name}.toml"
    path.write_text(text)
    return symkin.load(path), symkin.compile(path, backend="numpy").module


@pytest.fixture(scope="module")
def free(tmp_path_factory):
    return compiled(stage(inertia=2e-5, load=True), "stage", tmp_path_factory)


def agree(module, mech, inputs, params, count):
    """modes() of one configuration against the sympy path's: every frequency and every
    shape entry (shapes are normalised to 1: an absolute bound)."""
    found = module.modes(inputs, params=params, count=count)
    reference = modes(mech, inputs, "loaded", params, count)
    assert found["ok"].all()
    for k, f in enumerate(reference.frequencies):
        assert float(found["frequencies"][k]) == pytest.approx(f, rel=AGREE)
        for name, v in reference.links[k].items():
            assert np.asarray(found["links"][name][k]) == pytest.approx(v, abs=AGREE)
        for name, v in reference.points[k].items():
            assert np.asarray(found["points"][name][k]) == pytest.approx(v, abs=AGREE)
    return found, reference


def test_a_free_stage_agrees_with_the_sympy_path_and_the_formula(free):
    mech, module = free
    found, _ = agree(module, mech, {"push": 0.0}, {"P": 0.0}, 3)
    f1 = float(found["frequencies"][0])
    assert f1 == pytest.approx(sway(0.1), rel=1e-3)  # (1/2π)√(24EI/(L³m))
    assert f1 == pytest.approx(math.sqrt(2 * leaf_stiffness() / 0.1) / (2 * math.pi), rel=1e-6)
    # a pushed stage and a preload: still the same as the sympy path
    agree(module, mech, {"push": 0.3}, {"P": 3.0}, 3)
    # the rotation (inertia 2e-5) is a pure rotation, normalised to +1 rad
    assert float(found["links"]["stage"][2][2]) == 1.0


def test_a_batch_over_inputs_and_masses_answers_each_configuration_alone(free):
    _, module = free
    masses = np.array([0.05, 0.1, 0.2, 0.4])
    pushes = np.array([0.0, 0.2, -0.1, 0.0])
    batch = module.modes({"push": pushes}, params={"m": masses, "P": 0.0}, count=2)
    assert batch["frequencies"].shape == (2, 4) and batch["links"]["stage"].shape == (2, 3, 4)
    assert batch["points"]["top"].shape == (2, 2, 4) and batch["ok"].all()
    for j, (m, push) in enumerate(zip(masses, pushes)):
        alone = module.modes({"push": push}, params={"m": m, "P": 0.0}, count=2)
        assert batch["frequencies"][:, j] == pytest.approx(alone["frequencies"], rel=1e-14)
        assert batch["links"]["stage"][..., j] == pytest.approx(alone["links"]["stage"], abs=1e-12)
    # at zero push the sway is the formula's at every mass: f ∝ 1/√m
    for j in (0, 3):
        expected = math.sqrt(2 * leaf_stiffness() / masses[j]) / (2 * math.pi)
        assert batch["frequencies"][0, j] == pytest.approx(expected, rel=1e-6)


def test_more_modes_than_masses_are_infinite(free):
    _, module = free
    found = module.modes({"push": 0.0}, params={"P": 0.0}, count=5)
    assert np.isfinite(found["frequencies"][:3]).all()
    assert np.isinf(found["frequencies"][3:]).all()
    assert np.isnan(found["links"]["stage"][3:]).all()


def test_a_preload_softens_the_stage_and_beyond_buckling_is_not_ok(free):
    mech, module = free
    critical = 2 * math.pi**2 * EI / (40e-3) ** 2  # the two legs' Euler load (N)
    shares = np.array([0.0, 0.3, 0.6, 0.9, 1.2])
    found = module.modes({"push": 0.0}, params={"P": shares * critical}, count=1)
    f = found["frequencies"][0]
    assert list(found["ok"]) == [True, True, True, True, False]
    assert np.isnan(f[4])
    assert np.all(np.diff(f[:4]) < 0)
    for share, value in zip(shares[:4], f[:4]):
        load = float(share * critical)
        expected = math.sqrt(2 * leaf_stiffness(load / 2) / 0.1) / (2 * math.pi)
        assert value == pytest.approx(expected, rel=2e-3)
        reference = modes(mech, {"push": 0.0}, "loaded", {"P": load}, 1).frequencies[0]
        assert value == pytest.approx(reference, rel=AGREE)


def test_two_stacked_stages(tmp_path_factory):
    mech, module = compiled(stacked(), "stacked", tmp_path_factory)
    found, _ = agree(module, mech, {"p1": 0.0, "p2": 0.2}, None, 4)
    # the two-mass chain's characteristic polynomial (tests/test_modes.py)
    m1, m2, k = 0.3, 0.1, 2 * leaf_stiffness()
    a, b, c = m1 * m2, -(2 * k * m2 + k * m1), k * k
    found = module.modes({"p1": 0.0, "p2": 0.0}, count=2)
    for s, f in zip((-1, 1), found["frequencies"]):
        w2 = (-b + s * math.sqrt(b * b - 4 * a * c)) / (2 * a)
        assert float(f) == pytest.approx(math.sqrt(w2) / (2 * math.pi), rel=1e-4)


def test_an_input_hinge_held_without_actuators(tmp_path_factory):
    text = PARALLELOGRAM.replace(
        '[[link]]\nname = "stage"\n', '[[link]]\nname = "stage"\nmass = 0.1\ncentre = [15, 40]\n'
    )
    mech, module = compiled(text, "held", tmp_path_factory)
    agree(module, mech, {"F1": 0.0}, None, 2)
    agree(module, mech, {"F1": 0.05}, None, 2)
    batch = module.modes({"F1": np.linspace(-0.05, 0.05, 3)}, count=1)
    assert batch["ok"].all() and batch["frequencies"].shape == (1, 3)
    # the C evaluator of the same file builds with them (its <name>_modes: tests/test_modes_c.py)
    assert symkin.compile(mech, backend="c").evaluate({"F1": 0.01}, "loaded")["ok"]


def test_the_command_with_backend_numpy(tmp_path):
    path = tmp_path / "stage.toml"
    path.write_text(stage(inertia=2e-5, load=True))
    args = ["modes", str(path), "--input", "push=0.3", "--param", "P=3", "--json"]
    numpy_run = symkin_cli(*args, "--backend", "numpy")
    sympy_run = symkin_cli(*args)
    assert numpy_run.returncode == 0 and sympy_run.returncode == 0, numpy_run.stderr
    got, want = json.loads(numpy_run.stdout), json.loads(sympy_run.stdout)
    assert got["level"] == want["level"] == "loaded"
    assert got["frequencies"] == pytest.approx(want["frequencies"], rel=AGREE)
    for mode, reference in zip(got["modes"], want["modes"]):
        for kind in ("links", "points"):
            for name, v in reference[kind].items():
                assert mode[kind][name] == pytest.approx(v, abs=AGREE)
    run = symkin_cli(
        "modes", str(path), "--input", "push=0", "--backend", "numpy", "--level", "equilibrium"
    )
    assert run.returncode == 2 and "--level loaded" in run.stderr
    # beyond the legs' Euler load: no frequencies (exit 3), as the sympy path
    beyond = f"P={1.2 * 2 * math.pi**2 * EI / 40e-3**2}"
    run = symkin_cli(
        "modes", str(path), "--input", "push=0", "--param", beyond, "--backend", "numpy"
    )
    assert run.returncode == 3, run.stderr
