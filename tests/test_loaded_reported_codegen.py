"""What the generated numpy evaluator's result dict and the C evaluator's <name>_loaded_report
hold at the `loaded` level beyond the deviations (docs/physics.md, "What loaded reports"): the
input moments and stiffness, every point's 3×3 stiffness with the inputs held, every plate's
largest stress.

References, none of them the code under test: symkin's Python `loaded` report
(symkin.physics.reduced_reported, lambdified in mpmath; its plate stress by the Taylor-series
beam integrator, not RK4); central differences of the Python solver under a small load added at
the point (the mechanism solved again); the closed forms of a lone plate under a pure moment
(M = E'I θ/l, dM/dθ = E'I/l, σ = E' t θ/(2l)). The numpy module's `evaluate()` and the C
evaluator's `<name>_loaded_report` alike. Mechanisms unlike each other: the four-bar
example, a parallelogram stage with a payload load, a five-bar whose input is a chord, the lone
plate in millimetres with an allowable stress (with actuators:
tests/test_loaded_actuators_reported_codegen.py).
"""

from __future__ import annotations

import ctypes
import math

import mechanisms as M
import numpy as np
import pytest
import sympy as sp
from conftest import EXAMPLES, ROOT
from evaluators import backends_with, require_compiler
from test_loaded_reported import CASES, central_stiffness, solve

import symkin
from symkin.codegen import pipeline
from symkin.core import backends
from symkin.physics import reduced_reported

ZOO = ROOT / "tests" / "mechanisms"
#: the configurations each module evaluates at once (a batch: every one on its own)
BATCH = {
    "four_bar": {"A0": [0.3, -0.15]},
    "parallelogram": {"F1": [0.05, -0.02]},
    "five_bar_coupler_input": {"O1": [0.02, -0.01], "P": [0.02, 0.015]},
}
#: generated against Python: moments and rates, point stiffness (of each row's largest entry),
#: plate stress (RK4 against the Taylor series); measured 1.3e-15, 7.5e-13, 4.9e-12 (the
#: parallelogram's stress under its payload)
MOMENT, STIFFNESS, STRESS = 1e-10, 1e-10, 1e-9


def text(name: str, extra: str = "") -> tuple[str, str]:
    path, load, _ = CASES[name]
    return path.read_text() + load + extra, str(path)


@pytest.fixture(scope="module")
def built():
    """The analysis, plan and numpy module of each case (derived on first use)."""
    cache: dict = {}

    def get(name: str):
        if name not in cache:
            an = symkin.analyze(symkin.loads(*text(name)))
            plan, module = pipeline.build(an, "numpy", "test", sensitivity=False)
            cache[name] = an, plan, module
        return cache[name]

    return get


def c_report(plan, inputs: dict[str, list[float]], lib=None) -> dict:
    """The C evaluator's <name>_loaded_report at every configuration, shaped as the numpy
    module's result entries (the configurations on the last axis); with actuators their block
    after the plates' (stroke, force, dF/ds each) as "actuators"; the points' compliance last.
    `lib`: the plan's compiled library (None: built here)."""
    require_compiler()
    if lib is None:
        lib = pipeline.evaluator(plan, "c", "test", links=False).lib
    rep = plan.loaded.report
    nin, npt, npl, nact = len(rep.inputs), len(rep.points), len(rep.plates), len(rep.actuators)
    fn = getattr(lib, f"{plan.name}_loaded_report")
    count = len(next(iter(inputs.values())))
    args = plan.drives if plan.actuators else plan.inputs
    rows = []
    for c in range(count):
        out = (ctypes.c_double * (2 * nin + 18 * npt + 4 * npl + 3 * nact))()
        x = (ctypes.c_double * len(args))(*(inputs[h][c] for h in args))
        assert fn(x, None, out) == 0
        rows.append(list(out))
    v = np.array(rows).T
    plates = v[2 * nin + 9 * npt : 2 * nin + 9 * npt + 4 * npl]
    acts = v[2 * nin + 9 * npt + 4 * npl : 2 * nin + 9 * npt + 4 * npl + 3 * nact]
    compliance = v[2 * nin + 9 * npt + 4 * npl + 3 * nact :]  # <NAME>_REPORT_COMPLIANCE
    return {
        "ok": np.ones(count, dtype=bool),
        "inputs": {
            # a held input (derive --fix) is not an argument: its angle is the plan's
            h: {
                "angle": np.array(inputs.get(h, [math.nan] * count)),
                "moment": v[2 * k],
                "stiffness": v[2 * k + 1],
            }
            for k, h in enumerate(rep.inputs)
        },
        "stiffness": {
            p: v[2 * nin + 9 * k : 2 * nin + 9 * k + 9].reshape(3, 3, count)
            for k, p in enumerate(rep.points)
        },
        "plates": {
            h: dict(zip(("stress", "strain", "safety", "section"), plates[4 * k : 4 * k + 4]))
            for k, h in enumerate(rep.plates)
        },
        "compliance": {
            p: compliance[9 * k : 9 * k + 9].reshape(3, 3, count) for k, p in enumerate(rep.points)
        },
        **(
            {
                "actuators": {
                    a: dict(zip(("stroke", "force", "stiffness"), acts[3 * k : 3 * k + 3]))
                    for k, a in enumerate(rep.actuators)
                }
            }
            if nact
            else {}
        ),
    }


#: How this file reads each generated backend's `loaded` report: the C's through its
#: <name>_loaded_report entry point (c_report), the numpy module's from its evaluate.
READERS = {
    "numpy": lambda plan, module, inputs: module.evaluate(
        {k: np.array(v) for k, v in inputs.items()}, "loaded"
    ),
    "c": lambda plan, module, inputs: c_report(plan, inputs),
}
#: The generated backends that report the plates at `loaded` (the backend table).
REPORTING = backends_with(generated=True, reports="plates")


def reporting_here() -> list[str]:
    """REPORTING; a compiled one needs the compiler (a skip here, a failure under CI=true)."""
    if any(backends.get(b).compiler for b in REPORTING):
        require_compiler()
    return list(REPORTING)


def reported(backend: str, plan, module, inputs: dict[str, list[float]]) -> dict:
    return READERS[backend](plan, module, inputs)


def test_every_reporting_backend_is_read_here():
    assert set(READERS) == set(REPORTING)


def python_report(an, inputs: dict[str, float]):
    return reduced_reported.report(
        solve(an, inputs), float(an.mechanism.unit_scale), buckling=False
    )


def relative(a: float, b: float) -> float:
    return abs(a - b) / abs(b)


def rows_close(got, want, tol: float) -> bool:
    got, want = np.asarray(got, dtype=float), np.asarray(want, dtype=float)
    scale = np.abs(want).max(axis=1, keepdims=True)
    return bool(np.all(np.abs(got - want) <= tol * scale))


@pytest.fixture(scope="module")
def python_reports():
    """The Python report of each case's configurations (computed on first use)."""
    cache: dict = {}

    def get(name: str, an):
        if name not in cache:
            batch = BATCH[name]
            count = len(next(iter(batch.values())))
            cache[name] = [
                python_report(an, {k: v[c] for k, v in batch.items()}) for c in range(count)
            ]
        return cache[name]

    return get


@pytest.mark.parametrize("backend", REPORTING)
@pytest.mark.parametrize("name", list(BATCH))
def test_generated_code_reports_what_the_python_loaded_level_reports(
    built, python_reports, name, backend
):
    an, plan, module = built(name)
    batch = BATCH[name]
    res = reported(backend, plan, module, batch)
    assert res["ok"].all()
    for c, want in enumerate(python_reports(name, an)):
        assert set(res["inputs"]) == set(want.inputs) != set()
        for h, w in want.inputs.items():
            got = res["inputs"][h]
            assert got["angle"][c] == w.angle
            assert relative(got["moment"][c], w.moment) <= MOMENT, h
            assert relative(got["stiffness"][c], w.stiffness) <= MOMENT, h
        assert set(res["stiffness"]) == set(want.stiffness) != set()
        for p, w in want.stiffness.items():
            got = res["stiffness"][p][..., c]
            if w is None:
                assert np.isnan(got).all(), p
            else:
                assert rows_close(got, w, STIFFNESS), (p, got, w)
        assert set(res["compliance"]) == set(want.compliance) == set(want.stiffness)
        for p, w in want.compliance.items():
            got = res["compliance"][p][..., c]
            assert w is not None and rows_close(got, w, STIFFNESS), (p, got, w)
        assert set(res["plates"]) == set(want.plates) != set()
        for h, w in want.plates.items():
            got = res["plates"][h]
            assert relative(got["stress"][c], w.stress) <= STRESS, h
            assert relative(got["strain"][c], w.strain) <= STRESS, h
            assert got["section"][c] == pytest.approx(w.section, abs=1e-6)
            assert w.safety is None and math.isnan(got["safety"][c])


@pytest.mark.parametrize("name, point", [("four_bar", "C"), ("parallelogram", "P")])
def test_point_stiffness_by_central_differences_of_the_solver(built, name, point):
    """K of the numpy and C evaluators against the inverse of C = d(x, y, φ)/d(Fx, Fy, M) by
    central differences of the Python solver under a small load added at the point."""
    _, plan, module = built(name)
    inputs = {k: v[:1] for k, v in BATCH[name].items()}
    want = central_stiffness(name, point, {k: v[0] for k, v in inputs.items()})
    for backend in reporting_here():
        got = reported(backend, plan, module, inputs)["stiffness"][point][..., 0]
        # measured: four-bar 9.6e-11, parallelogram 7.5e-10 (of each row's largest entry), both
        assert rows_close(got, want, 1e-8), (backend, got, want)


@pytest.fixture(scope="module")
def lone_plate():
    source = M.lone_plate().replace("[defaults]\n", "[defaults]\nallowable_stress = 900e6\n")
    an = symkin.analyze(symkin.loads(source, "lone_plate.toml"))
    # with sensitivities: a loop-free evaluator without them leaves runtime.c's sk_solve unused
    # (its C does not compile under -Werror)
    return pipeline.build(an, "numpy", "test")


@pytest.mark.parametrize("backend", REPORTING)
def test_lone_plate_under_a_pure_moment_is_a_circular_arc(lone_plate, backend):
    """In millimetres (the moments in N m), with an allowable stress (the safety factor)."""
    plan, module = lone_plate
    thetas = [0.02, 0.3]
    res = reported(backend, plan, module, {"A": thetas})
    ei = M.bending_stiffness(5, 0.3, 1e-3)  # N m²
    modulus, t, length = 200e9 / (1 - 0.3**2), 0.2e-3, 10e-3
    for c, theta in enumerate(thetas):
        a = res["inputs"]["A"]
        assert a["moment"][c] == pytest.approx(ei * theta / length, rel=1e-12)
        assert a["stiffness"][c] == pytest.approx(ei / length, rel=1e-12)
        plate = res["plates"]["A"]
        stress = modulus * t * theta / (2 * length)
        assert plate["stress"][c] == pytest.approx(stress, rel=1e-12)
        assert plate["safety"][c] == pytest.approx(900e6 / stress, rel=1e-12)
        assert np.isnan(res["stiffness"]["T"][..., c]).all()  # the input holds the arm


def test_what_the_other_levels_and_modules_hold(built):
    """The report only at `loaded`; the C report refuses what its evaluate refuses (a bad
    input: 3, out NaN); a file with actuators has it in numpy and in C, with the actuators'
    block (tests/test_loaded_actuators_reported_codegen.py)."""
    _, plan, module = built("four_bar")
    assert "inputs" not in module.evaluate({"A0": 0.3}, "exact")
    assert {"loaded_report1", "loaded_report2"} <= set(plan.routines)
    require_compiler()
    lib = pipeline.evaluator(plan, "c", "test", links=False).lib
    out = (ctypes.c_double * (2 + 9 + 16 + 9))()  # the four-bar: 1 input, 1 point, 4 plates
    assert lib.four_bar_loaded_report((ctypes.c_double * 1)(4.0), None, out) == 3
    assert all(math.isnan(v) for v in out)
    piezo = symkin.analyze(symkin.load(EXAMPLES / "piezo_amplifier.toml"))
    plan, module = pipeline.build(piezo, "numpy", "test", sensitivity=False)
    assert "loaded" in module.LEVELS and plan.loaded.report is not None
    assert "actuators" in module.evaluate({"piezo": 0.02}, "loaded")
    header, code = pipeline.emit(plan, "c", "piezo_amplifier.toml")
    assert "PIEZO_AMPLIFIER_N_REPORT_ACTUATORS 1" in header and "sk_actuated_report(" in code


def test_a_held_input_is_reported_too():
    """derive --fix: the held input leaves the arguments, its moment and stiffness stay in the
    report (the Python report at its angle)."""
    an = symkin.analyze(symkin.loads(*text("five_bar_coupler_input")))
    plan, module = pipeline.build(
        an, "numpy", "test", sensitivity=False, fixed={"P": sp.Rational(3, 200)}
    )
    want = python_report(an, {"O1": 0.02, "P": 0.015})
    for backend in reporting_here():
        res = reported(backend, plan, module, {"O1": [0.02]})
        assert set(res["inputs"]) == {"O1", "P"}
        for h, w in want.inputs.items():
            assert relative(res["inputs"][h]["moment"][0], w.moment) <= MOMENT, (backend, h)
            assert relative(res["inputs"][h]["stiffness"][0], w.stiffness) <= MOMENT, (backend, h)
        for p, w in want.stiffness.items():
            assert rows_close(res["stiffness"][p][..., 0], w, STIFFNESS), (backend, p)
    assert float(module.evaluate({"O1": 0.02}, "loaded")["inputs"]["P"]["angle"]) == 0.015


def test_the_report_takes_the_inputs_shape(built):
    """Entries shaped like the broadcast inputs (the stiffness (3, 3, *shape)), the same values
    as a flat batch; `report=False` leaves them out."""
    _, _, module = built("four_bar")
    flat = module.evaluate({"A0": np.array([0.3, -0.15, 0.1, 0.0])}, "loaded")
    grid = module.evaluate({"A0": np.array([[0.3, -0.15], [0.1, 0.0]])}, "loaded")
    assert grid["stiffness"]["C"].shape == (3, 3, 2, 2)
    assert np.array_equal(grid["stiffness"]["C"].reshape(3, 3, 4), flat["stiffness"]["C"])
    for h, plate in flat["plates"].items():
        assert np.array_equal(grid["plates"][h]["stress"].reshape(4), plate["stress"])
    assert grid["inputs"]["A0"]["moment"].shape == (2, 2)
    assert "plates" not in module.evaluate({"A0": 0.3}, "loaded", report=False)
