"""Sensitivities of the two stroke-driven examples (examples/notch_lever.toml: a lever on notch
hinges behind a spring; examples/piezo_amplifier.toml: circular-arc plates) by a parameter that
moves the point of action and by the stroke, at `exact` and at `loaded`, every backend that
evaluates the configuration, against central differences of the `sympy` backend's 40-digit
evaluation (which solves the strokes by Newton's method and knows nothing of the
implicit-function theorem the sensitivities use), within 1e-7 relative.

The reference: the evaluation's values are float64 numbers (a deviation is a difference of
positions some 50 mm from the origin, so they carry ~1e-14 mm of rounding), which a step of
1e-5 of the parameter turns into ~1e-5 of the derivative. So the steps are large (4 % of the
value, then 2 % and 1 %) and their truncation is removed by Richardson's extrapolation twice
(error O(h⁶)): rounding and truncation each stay under ~3e-8 relative here.
"""

from __future__ import annotations

from functools import cache

import numpy as np
import pytest
from conftest import EXAMPLES
from evaluators import BACKENDS, require

import symkin
from symkin.cli.commands import main
from symkin.codegen.loaded import notched
from symkin.core import backends
from symkin.core.levels import NOTCH_BACKENDS

FILES = {"notch_lever": "notch_lever.toml", "piezo_amplifier": "piezo_amplifier.toml"}
STROKE = 0.02  # mm: the lever turns by s/a = 4 mrad, the amplifier's output by ~0.1 mm


@cache
def analysis(example: str):
    return symkin.analyze(EXAMPLES / FILES[example])


@cache
def reference(example: str, level: str, name: str) -> np.ndarray:
    """d(deviation)/d(name) of every shown point (sorted), (points, 2): central differences of
    the sympy backend at 40 digits at h, h/2, h/4 (h = 4 % of the value), Richardson twice."""
    an = analysis(example)
    values = {p.name: float(p.value) for p in an.mechanism.parameters}

    def at(shift: float) -> np.ndarray:
        params = {k: repr(v + shift * (k == name)) for k, v in values.items()}
        stroke = STROKE + shift * (name == "piezo")
        ev = symkin.evaluate(an, {"piezo": repr(stroke)}, level, params, dps=40)
        return np.array([p.deviation for _, p in sorted(ev.points.items())])

    h = 0.04 * values.get(name, STROKE)
    d = [(at(x) - at(-x)) / (2 * x) for x in (h, h / 2, h / 4)]
    once = [(4 * d[1] - d[0]) / 3, (4 * d[2] - d[1]) / 3]
    return (16 * once[1] - once[0]) / 15


CASES = [
    (example, level, name, backend)
    for example in FILES
    for level in ("exact", "loaded")
    for name in ("a", "piezo")
    for backend in BACKENDS
    # the generated loaded level takes notches in NOTCH_BACKENDS alone (it refuses the others)
    if not (
        level == "loaded"
        and backends.get(backend).generated
        and backend not in NOTCH_BACKENDS
        and example == "notch_lever"
    )
]


def test_the_cases_cover_every_backend():
    """Every backend is checked on both examples at both levels but the refused one."""
    assert {c[3] for c in CASES} == set(BACKENDS)
    assert len(CASES) == 8 * len(BACKENDS) - 2 * (len(BACKENDS) - 1 - len(NOTCH_BACKENDS))
    assert notched(analysis("notch_lever").mechanism)


@pytest.mark.parametrize("example, level, name, backend", CASES)
def test_against_40_digit_central_differences(example, level, name, backend):
    require(backend)
    an = analysis(example)
    ev = symkin.evaluate(
        an, {"piezo": repr(STROKE)}, level, backend=backend, sensitivity=True
    ).sensitivity
    table = ev.deviation_inputs if name == "piezo" else ev.deviation
    found = np.array([row[name] for _, row in sorted(table.items())])
    expected = reference(example, level, name)
    scale = float(np.max(np.abs(expected)))
    assert scale > 0
    assert float(np.max(np.abs(found - expected))) <= 1e-7 * scale, (found, expected)


def test_loaded_refuses_a_notch_read_from_parameters(capsys):
    """At `loaded` a notch's section is numbers: derivatives by its keys would be zero, so the
    sympy backend refuses them (exit 2, naming the hinge and the parameter), as the generated
    ones do."""
    lever = EXAMPLES.parent / "tests" / "mechanisms" / "notch_lever_params.toml"
    args = ["eval", str(lever), "--input", "piezo=0.02", "--level", "loaded", "--sensitivity"]
    for backend in BACKENDS:
        assert main([*args, "--backend", backend]) == 2
        err = capsys.readouterr().err
        assert "[[hinge]] 'O'" in err, (backend, err)
        # (a generated backend outside NOTCH_BACKENDS refuses the notch itself first)
        if not backends.get(backend).generated or backend in NOTCH_BACKENDS:
            assert "parameter(s) R" in err, (backend, err)
