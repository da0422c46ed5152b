"""The backend table (symkin.core.backends) pinned, and what it promises checked in the code: the
generated backends are the pipeline's registry, `symkin.compile(..., backend="c")` loads no
numpy module, and a C evaluator's parameters are the numpy module's.

The table is written out here on purpose: a capability dropped from (or added to) a backend
fails this test, instead of making the tests that draw their backends from the table skip it
quietly."""

from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
import pytest
from conftest import EXAMPLES, ROOT
from evaluators import require_compiler

import symkin
from symkin.codegen import pipeline, toolchain
from symkin.core import backends, levels

#: The whole table, written out, as the code supports it today (docs/generated-code.md,
#: "Backends"): name -> title, generated, levels, sensitivities, precisions, actuators (stroke),
#: forces, force_sensitivities, reports, compiler, batched, scenes.
K = {"paper", "first_order", "exact"}  # the kinematic levels
EXPECTED = {
    "sympy": {
        "title": "sympy",
        "generated": False,
        "levels": K | {"loaded", "equilibrium"},
        "sensitivities": K | {"loaded"},
        "precisions": ("mpmath",),
        "actuators": K | {"loaded", "equilibrium"},
        "forces": {"loaded", "equilibrium"},
        "force_sensitivities": {"loaded"},
        "reports": {"inputs", "stiffness", "compliance", "plates", "actuators", "buckling"},
        "compiler": False,
        "batched": False,
        "scenes": False,
    },
    "numpy": {
        "title": "numpy",
        "generated": True,
        "levels": K | {"loaded"},
        "sensitivities": K | {"loaded"},
        "precisions": ("float64", "float32"),
        "actuators": K | {"loaded"},
        "forces": {"loaded"},
        "force_sensitivities": {"loaded"},
        "reports": {"inputs", "stiffness", "compliance", "plates", "actuators", "buckling"},
        "compiler": False,
        "batched": True,
        "scenes": True,
    },
    "c": {
        "title": "C",
        "generated": True,
        "levels": K | {"loaded"},
        "sensitivities": K | {"loaded"},
        "precisions": ("float64",),
        "actuators": K | {"loaded"},
        "forces": {"loaded"},
        "force_sensitivities": set(),
        "reports": {"inputs", "stiffness", "compliance", "plates", "actuators"},
        "compiler": True,
        "batched": True,
        "scenes": True,
    },
}


def test_the_capability_table_is_pinned():
    assert backends.NAMES == ("sympy", "numpy", "c")
    for b in backends.BACKENDS:
        got = {k: getattr(b, k) for k in EXPECTED[b.name]}
        assert set(got) | {"name"} == set(b.__dataclass_fields__), b.name  # every field pinned
        assert got == EXPECTED[b.name], b.name


def test_the_table_names_levels_and_reports_that_exist():
    for b in backends.BACKENDS:
        named = b.levels | b.sensitivities | b.actuators | b.forces | b.force_sensitivities
        assert named <= set(levels.NAMES), b.name
        assert b.sensitivities <= b.levels and b.forces <= b.actuators <= b.levels, b.name
        assert b.force_sensitivities <= b.forces & b.sensitivities, b.name
        assert b.reports <= set(backends.REPORTS), b.name


def test_the_generated_backends_are_the_registry():
    assert pipeline.BACKENDS == backends.GENERATED == ("numpy", "c")
    for name, row in pipeline.REGISTRY.items():
        assert row.capabilities is backends.get(name)
        assert row.precisions == backends.get(name).precisions


def test_having_selects_by_capability():
    assert backends.having(generated=True) == ("numpy", "c")
    assert backends.having(force_sensitivities="loaded") == ("sympy", "numpy")
    assert backends.having(precisions="float32") == ("numpy",)
    assert backends.having(levels="equilibrium") == ("sympy",)
    assert backends.having(compiler=True) == ("c",)
    with pytest.raises(TypeError, match="no capability"):
        backends.having(speed=True)


def test_an_unknown_backend_is_bad_input():
    with pytest.raises(symkin.InputError, match="unknown backend 'fortran'") as caught:
        backends.get("fortran")
    assert "sympy, numpy, c" in str(caught.value.hint)


def test_compiling_for_c_loads_no_numpy_module(monkeypatch):
    """The C evaluator answers evaluate, sensitivity, parameters and defaults without the numpy
    module; asking for the module (a loaded sweep's report reads it) loads it then."""
    require_compiler()
    loaded = []
    for name in ("numpy_module_in_memory", "import_numpy_module"):
        real = getattr(toolchain, name)

        def spy(text, module_name, real=real):
            loaded.append(module_name)
            return real(text, module_name)

        monkeypatch.setattr(toolchain, name, spy)
    ev = symkin.compile(EXAMPLES / "four_bar.toml", levels=["exact"])
    x = np.linspace(-0.2, 0.2, 5)
    res = ev.evaluate({"A0": x})
    ev.sensitivity({"A0": 0.1})
    shifted = ev.parameter_values(None, {"l": np.array([0.0, 1e-4])})
    assert ev.parameters({"l": 0.002}) == [0.002] and ev.defaults == {"l": 0.001}
    assert loaded == []
    module = ev.module  # on demand
    assert loaded == ["four_bar"]
    want = module.evaluate({"A0": x}, "exact")
    np.testing.assert_allclose(
        res["points"]["C"]["deviation"], want["points"]["C"]["deviation"], rtol=1e-12, atol=1e-18
    )
    np.testing.assert_array_equal(shifted[0], module.parameters(None, {"l": [0.0, 1e-4]})[0])


def test_a_fresh_process_compiling_for_c_imports_no_generated_module():
    """The same in a process of its own: after compiling and evaluating for C, no module that
    the numpy backend generated is among the loaded modules (sys.modules) and no in-memory one
    was made."""
    require_compiler()
    code = f"""
import sys
import symkin
from symkin.codegen import toolchain
made = []
real = toolchain.numpy_module_in_memory
toolchain.numpy_module_in_memory = lambda *a: made.append(a[1]) or real(*a)
ev = symkin.compile({str(EXAMPLES / "four_bar.toml")!r}, backend="c", levels=["exact"])
ev.evaluate({{"A0": 0.1}})
ev.sensitivity({{"A0": 0.1}})
generated = [m for m in sys.modules if m.startswith("four_bar")]
print(made, generated)
"""
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    run = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, env=env, cwd=ROOT
    )
    assert run.returncode == 0, run.stderr
    assert run.stdout.strip() == "[] []"


@pytest.mark.parametrize(
    "given,shifts", [(None, None), ({"ax": 0.016}, {"l": 1e-4}), (None, {"l": -2e-4})]
)
def test_a_c_evaluators_parameters_are_the_modules(given, shifts):
    """Parameters whose defaults read others: the parameter section (templates/numpy/
    parameters.py.j2) gives the module's values, which the C takes."""
    require_compiler()
    path = EXAMPLES / "four_bar_dimensions.toml"
    c = symkin.compile(path, levels=["exact"], sensitivity=False)
    numpy = symkin.compile(path, backend="numpy", levels=["exact"], sensitivity=False)
    assert c.defaults == numpy.defaults
    got = dict(zip(c.defaults, c.parameters(given, shifts)))
    assert list(got.values()) == numpy.parameters(given, shifts)
    # the file's l_A0 = "l": re-evaluated from l once l is given or shifted
    assert got["l_A0"] == got["l"] == 1e-3 + (shifts or {}).get("l", 0.0)
    assert got["ax"] == (given or {}).get("ax", 0.015)
    x = np.array([[0.1], [-0.1]])
    params = np.array([c.parameters(given, shifts)] * 2)
    got, want = c.evaluate_grid(params, x), numpy.evaluate_grid(params, x)
    np.testing.assert_array_equal(got[0], want[0])
    np.testing.assert_allclose(got[1], want[1], rtol=1e-11, atol=1e-18)


@pytest.mark.parametrize("backend", backends.NAMES)
def test_the_table_is_what_evaluate_does(backend):
    """Its levels and sensitivities are what symkin.evaluate answers through the backend, and
    what it refuses (exit 2) the table leaves out: the four-bar example (steel plates) at
    every level."""
    b = backends.get(backend)
    if b.compiler:
        require_compiler()
    an = symkin.analyze(symkin.load(EXAMPLES / "four_bar.toml"))
    for level in levels.NAMES:
        for sensitivity in (False, True):
            can = level in (b.sensitivities if sensitivity else b.levels)
            try:
                ev = symkin.evaluate(
                    an, {"A0": "0.1"}, level, backend=backend, sensitivity=sensitivity
                )
            except symkin.InputError:
                assert not can, (level, sensitivity)
            else:
                assert can and ev.backend == backend, (level, sensitivity)
                assert (ev.sensitivity is not None) == sensitivity, level


@pytest.mark.parametrize("backend", backends.GENERATED)
def test_the_precisions_are_what_the_pipeline_emits(backend):
    p = pipeline.plan_for(symkin.analyze(symkin.load(EXAMPLES / "four_bar.toml")), levels=["exact"])
    for precision in ("float64", "float32"):
        if precision in backends.get(backend).precisions:
            assert pipeline.emit(p, backend, "x.toml", precision)
        else:
            with pytest.raises(symkin.InputError, match=f"not {precision}"):
                pipeline.emit(p, backend, "x.toml", precision)
