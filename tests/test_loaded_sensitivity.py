"""The `loaded` level's closed-form sensitivities (docs/sensitivity.md) against an independent
numeric reference: central differences of the Python reduced-equilibrium solver itself
(symkin.physics.reduced through physical.reduced_equilibrium) re-solved at p ± h, in the
sympy, numpy and C backends (which agree with each other to rounding); the parameter chain
(four_bar's thickness = "l/10") and `symkin tolerance --level loaded` against the linear
estimate from central differences of |ΔR| over the input grid.

Mechanisms: tests/mechanisms/five_bar_params.toml (two inputs, the input O2 a chord, a load,
thickness, modulus, width, a plate length, a hinge coordinate and the load named as
parameters) and examples/four_bar.toml (no loads; the plates' thickness follows l).
"""

from __future__ import annotations

import ctypes
import json
import math
from pathlib import Path

import pytest
from conftest import EXAMPLES
from evaluators import backends_with, require, require_compiler

import symkin
import symkin.core.levels
from symkin.cli.commands import main
from symkin.codegen import pipeline
from symkin.studies.physical import reduced_equilibrium

HERE = Path(__file__).parent / "mechanisms"
FIVE = HERE / "five_bar_params.toml"
FIVE_AT = {"O1": 0.03, "O2": -0.02}
#: thickness, modulus, a plate's length alone, the length of every plate (and lA with it), a
#: hinge coordinate, the load
FIVE_VARIED = ("t", "E0", "lA", "l", "ay", "Fy")
FOUR = EXAMPLES / "four_bar.toml"
FOUR_AT = {"A0": 0.3}
#: central differences: step relative to the parameter (the solver stops at 1e-12 relative: the
#: rounding in the difference ~1e-12/H, the truncation ~H²)
H = 1e-4
#: closed form against the central differences, relative to the derivative's size
RTOL = 1e-6
#: backends against each other
BTOL = 1e-10


def nominal(an) -> dict[str, float]:
    return {p.name: float(p.value) for p in an.mechanism.parameters}


def deviation(an, inputs, params=None) -> dict[str, tuple[float, float]]:
    """The reference solver's deviations (numpy kernels: the Python solver in float64)."""
    answer = reduced_equilibrium(an, inputs, params, backend="numpy")
    assert not answer.refused, answer.refused
    return {k: (float(v[0]), float(v[1])) for k, v in answer.deviations.items()}


def central(an, inputs, name: str) -> dict[str, tuple[float, float]]:
    """d(dx, dy)/d name by central differences of the re-solved equilibrium (the parameters
    whose defaults read `name` re-evaluated: the total derivative)."""
    value = nominal(an)[name]
    h = H * abs(value)
    plus = deviation(an, inputs, {name: value + h})
    minus = deviation(an, inputs, {name: value - h})
    return {
        p: ((plus[p][0] - minus[p][0]) / (2 * h), (plus[p][1] - minus[p][1]) / (2 * h))
        for p in plus
    }


def close(a, b, tol: float, what: str) -> None:
    scale = max(math.hypot(*b), 1e-300)
    assert math.dist(a, b) <= tol * scale, f"{what}: {a} vs {b}"


@pytest.fixture(scope="module")
def five():
    return symkin.analyze(FIVE)


@pytest.fixture(scope="module")
def five_sympy(five):
    return symkin.evaluate(five, FIVE_AT, level="loaded", sensitivity=True)


@pytest.fixture(scope="module")
def five_by(five):
    """backend -> its `loaded` evaluation with sensitivities, each evaluated once."""
    found = {}

    def get(backend):
        if backend not in found:
            require(backend)
            found[backend] = symkin.evaluate(
                five, FIVE_AT, level="loaded", backend=backend, sensitivity=True
            )
        return found[backend]

    return get


@pytest.fixture(scope="module")
def five_numpy(five_by):
    return five_by("numpy")


@pytest.fixture(scope="module")
def five_c(five_by):
    return five_by("c")


@pytest.mark.parametrize("name", FIVE_VARIED)
def test_closed_form_matches_central_differences(five, five_sympy, name):
    reference = central(five, FIVE_AT, name)
    for point, d in reference.items():
        close(five_sympy.sensitivity.deviation[point][name], d, RTOL, f"{point} d/d{name}")


def test_inputs_match_central_differences(five, five_sympy):
    """By an input (a tree hinge and the chord O2): through the rigid angles only."""
    for name in FIVE_AT:
        h = 1e-5
        plus = deviation(five, {**FIVE_AT, name: FIVE_AT[name] + h})
        minus = deviation(five, {**FIVE_AT, name: FIVE_AT[name] - h})
        for point in plus:
            d = tuple((plus[point][c] - minus[point][c]) / (2 * h) for c in range(2))
            close(five_sympy.sensitivity.deviation_inputs[point][name], d, RTOL, name)


def test_the_deviation_is_the_solvers(five, five_sympy):
    for point, d in deviation(five, FIVE_AT).items():
        close(five_sympy.points[point].deviation, d, 1e-12, point)


@pytest.mark.parametrize("backend", backends_with(generated=True, sensitivities="loaded"))
def test_backends_agree(five_by, five_sympy, backend):
    ev = five_by(backend)
    ref = five_sympy.sensitivity
    for table, other in (
        (ref.deviation, ev.sensitivity.deviation),
        (ref.deviation_inputs, ev.sensitivity.deviation_inputs),
        (ref.rigid, ev.sensitivity.rigid),
        (ref.rigid_inputs, ev.sensitivity.rigid_inputs),
    ):
        for point, row in table.items():
            scale = max(math.hypot(*v) for v in row.values())
            for name, v in row.items():
                assert math.dist(other[point][name], v) <= BTOL * scale, (backend, point, name)


def test_rigid_sensitivities_are_the_kinematic_levels(five, five_numpy):
    """The rigid positions' derivatives do not depend on the level."""
    exact = symkin.evaluate(five, FIVE_AT, level="exact", backend="numpy", sensitivity=True)
    for point, row in exact.sensitivity.rigid.items():
        for name, v in row.items():
            close(five_numpy.sensitivity.rigid[point][name], v, 1e-13, name)


def test_the_generated_sensitivity_functions(five, five_c):
    """`sensitivity(inputs, level, params)` (numpy) and `<name>_sensitivity` (C) at the loaded
    level: per point and parameter (file order) d(dx)/dp, d(dy)/dp."""
    names = [p.name for p in five.mechanism.parameters]
    # the evaluators the fixtures' evaluations built (pipeline.build keeps them)
    _, module = pipeline.build(five, "numpy", five.mechanism.path, sensitivity=True)
    out = module.sensitivity({k: [v] for k, v in FIVE_AT.items()}, "loaded")
    lib = pipeline.build(five, "c", five.mechanism.path, sensitivity=True)[1].lib
    points = list(five_c.sensitivity.deviation)
    flat = (ctypes.c_double * (2 * len(points) * len(names)))()
    x = (ctypes.c_double * 2)(*FIVE_AT.values())
    code = symkin.core.levels.get("loaded").code
    assert lib.five_bar_params_sensitivity(x, None, code, flat) == 0
    for i, point in enumerate(points):
        for j, name in enumerate(names):
            v = five_c.sensitivity.deviation[point][name]
            got = (float(out[point][name][0][0]), float(out[point][name][1][0]))
            close(got, v, BTOL, f"numpy {point} {name}")
            at = 2 * (i * len(names) + j)
            assert (flat[at], flat[at + 1]) == v, (point, name)


def test_the_chain_of_a_parameter_defined_from_another():
    """four_bar's thickness = "l/10": d/dl moves every plate's length and thickness."""
    an = symkin.analyze(FOUR)
    reference = central(an, FOUR_AT, "l")
    ev = symkin.evaluate(an, FOUR_AT, level="loaded", sensitivity=True)
    close(ev.sensitivity.deviation["C"]["l"], reference["C"], RTOL, "l")
    # (the generated code's chain: five_bar_params' lA = "l", test_backends_agree)


def test_tolerance_stack_up_at_loaded(five, capsys):
    """`symkin tolerance --level loaded`: with one varied parameter the worst case and the RSS
    are max over the grid of a |d|ΔR|/dp|, here from central differences of the re-solved
    equilibrium."""
    require_compiler()
    a = 2e-6
    grid = [{"O1": q, "O2": -0.02} for q in (0.0, 0.015, 0.03)]
    code = main(
        [
            "tolerance",
            str(FIVE),
            "--level",
            "loaded",
            "--vary",
            f"t=±{a}",
            "--input",
            "O1=0:0.03:3",
            "--input",
            "O2=-0.02",
            "--json",
        ]
    )
    out, err = capsys.readouterr()
    assert code == 0, err
    doc = json.loads(out)
    assert doc["level"] == "loaded" and doc["failed"] == 0
    value = nominal(five)["t"]
    h = H * value
    for point in ("T", "Q"):
        rates = []
        for at in grid:
            plus = math.hypot(*deviation(five, at, {"t": value + h})[point])
            minus = math.hypot(*deviation(five, at, {"t": value - h})[point])
            rates.append(abs(plus - minus) / (2 * h))
        expected = a * max(rates)
        got = doc["points"][point]
        assert abs(got["worst_case"] - expected) <= 1e-5 * expected, (point, got, expected)
        assert abs(got["rss"] - expected) <= 1e-5 * expected
        assert got["contributions"] == {"t": 1.0}
