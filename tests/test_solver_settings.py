"""One table of solver rules (symkin.core.settings, docs/numerics.md "The solver table"): the
generated C and numpy evaluators carry exactly its numbers, the float64 ones are the numbers the
runtimes held as literals before the table (pinned here), the 40-digit path scales them by its
own epsilon, and no runtime file keeps a solver literal of its own."""

from __future__ import annotations

import ast
import collections
import dataclasses
import io
import math
import re
import tokenize

import mpmath
import numpy as np
import pytest
from conftest import EXAMPLES, ROOT

import symkin
from symkin.codegen import pipeline, templating
from symkin.core import settings
from symkin.core.settings import SOLVER
from symkin.physics import reduced, reduced_reported
from symkin.studies import actuators, configuration, mpmath_evaluator, stroke_solver

#: The numbers the runtimes held as literals before the table (templates/c/reduced.c,
#: templates/numpy/reduced.py, symkin/physics/reduced.py, ...): the table must give them back
#: bit for bit in float64, so that the generated evaluators' answers do not change.
BEFORE_LOADED = {
    "tol": 1e-12,
    "max_iter": 12,
    "max_turn": 0.2,
    "stall_after": 3,
    "stall_ratio": 0.5,
    "stalled": 1e-9,
    "chord": 1e-3,
    "chord_shrink": 0.1,
    "chord_error": 1e-15,
    "first_step": 0.25,
    "step_growth": 1.5,
    "largest_step": 0.5,
    "step_cut": 0.5,  # ds /= 2
    "smallest_step": 1e-3,
    "p_limit": 0.9,
    "est_factor": 3.0,
    "est_limit": 0.01,
    # new with the table's floor under a point's deviation (not literals before it)
    "est_share": 0.1,
    "est_size": 1e-13,
    "sections": 64,
    "singular": 1e12,
    "buckling_limit": 10.0,
    "buckling_step": 0.5,
    "buckling_growth": 2.0,
    "buckling_largest": 3.0,
    "buckling_cut": 0.5,
    "buckling_locate": 1e-10,
}
BEFORE_STROKES = {
    "iterations": 40,
    "halvings": 40,
    "cut": 0.5,
    "tolerance": 64.0 * 2.220446049250313e-16,
    "floor": 1e-300,
    "step": 1.4901161193847656e-08,  # sqrt(eps)
    "polish": 2.220446049250313e-16,  # added with the C solves' secant steps (one more step)
    "secant": 0.5,  # added with them: a secant step kept where it halves the residual
}
BEFORE_EQUILIBRIUM = {  # symkin/physics/equilibrium.py's constants and literals
    "tiny_input": 1e-4,  # added with the tiny-input digits (docs/numerics.md, "Tiny angles")
    "tiny_guard": 8,
    "min_step": 1e-7,
    "max_turn": 0.05,
    "first_step": 0.25,
    "step_growth": 1.5,
    "step_cut": 0.5,  # dt /= 2
    "approach": 0.5,
    "singular_ratio": 1e-8,
    "max_steps": 1000,
    "time_budget": 20.0,
    "buckling_budget": 2.0,
    "rate_growth": 4.0,
    "rate_margin": 20.0,
    "jump": 1e-9,
    "newton_iterations": 12,
    "newton_tol": 1e-14,
    "stall_ratio": 0.5,  # previous / 2
    "stalled": 1e-9,
    "diverged": 1e3,
    "series_tol": 1e-18,
    "base_digits": 24,
    "max_digits": 400,
    "polish_iterations": 8,
    "polish_digits": 6,
    "polish_guard": 3,
    "rounding_digits": 8,
    "tangent_step": 1e-4,
    "real_eigenvalue": 1e-6,
    "buckling_limit": 10.0,
    "strain_limit": 0.1,
    "probe_steps": 30,
    "gross_overload": 10.0,
}
BEFORE_LOOPS = {  # rigid, converged, stalled, polish, residual, consistent
    # the polish: at most 8 steps of the relative rule (it was 1 step: tiny inputs lost their
    # relative accuracy, docs/numerics.md "Tiny angles")
    "float64": (1e-10, 1e-8, 1e-12, 8, 2e-13, 1e-8),
    "float32": (1e-4, 3e-4, 1e-5, 8, 1e-4, 1e-3),
}


def same(a, b) -> bool:
    """Equal numbers of the same kind (an iteration cap stays an integer)."""
    return type(a) is type(b) and a == b


def test_the_float64_numbers_are_those_the_runtimes_held():
    assert np.finfo(np.float64).eps == settings.EPS64
    assert np.finfo(np.float32).eps == settings.EPS32
    assert SOLVER.loaded.rules().keys() == BEFORE_LOADED.keys()
    for key, value in SOLVER.loaded.rules().items():
        assert same(value, BEFORE_LOADED[key]), key
    for key, value in SOLVER.strokes.rules().items():
        assert same(value, BEFORE_STROKES[key]), key
    for precision, numbers in BEFORE_LOOPS.items():
        tol = SOLVER.tolerances(precision)
        got = (tol.rigid, tol.converged, tol.stalled, tol.polish, tol.residual, tol.consistent)
        assert got == numbers, precision
    eq = SOLVER.equilibrium
    named = {f.name.removesuffix("_eps") for f in dataclasses.fields(eq)}
    assert named == BEFORE_EQUILIBRIUM.keys()
    for key, value in BEFORE_EQUILIBRIUM.items():
        assert same(getattr(eq, key), value), key
    # the Python solvers' own copies (the loaded level's shared solver takes float64's rules)
    assert reduced.RULES is SOLVER.loaded and reduced_reported.RULES is SOLVER.loaded
    assert SOLVER.strokes.reference == 1e-14


def test_the_python_loaded_solver_takes_the_table_at_float64():
    """symkin.physics.reduced's system hands the shared solver the table at float64's ε."""
    an = symkin.analyze(symkin.load(EXAMPLES / "four_bar.toml"))
    values = {p.symbol: p.value for p in an.mechanism.parameters}
    rules = reduced.Reduced(an.kin, values).system.t
    for key, value in SOLVER.loaded.rules(settings.EPS64).items():
        assert getattr(rules, key) == value, key
    assert rules.tol == 1e-12 and rules.stalled == 1e-9 and rules.max_iter == 12


@pytest.mark.parametrize("dps", [15, 40, 60])
def test_the_mpmath_path_stops_in_units_of_its_own_epsilon(dps):
    with mpmath.workdps(dps):
        eps = float(mpmath.mp.eps)  # mpmath's own, not the table's formula
    assert settings.mpmath_eps(dps) == eps
    tol = SOLVER.mpmath(dps)
    for name in ("rigid", "converged", "stalled", "residual"):
        k = getattr(SOLVER.ulps, name)
        assert getattr(tol, name) == k * eps, name
        # the same multiple of epsilon as float64's
        assert math.isclose(getattr(tol, name) / eps, getattr(SOLVER.float64, name) / 2.0**-52)
    assert tol.polish == SOLVER.polish_mpmath and tol.consistent == SOLVER.float64.consistent
    if dps == 40:
        # the stall and step tests sit some 4500 and 450000 units of rounding above 40 digits'
        assert 1e-38 < tol.stalled < 1e-36 and 1e-36 < tol.rigid < 1e-34


def test_the_40_digit_evaluation_reads_the_scaled_rules(monkeypatch):
    """symkin.evaluate (the sympy backend, mpmath) asks the table at its working precision."""
    asked = []

    class Recorded(type(SOLVER)):
        def mpmath(self, dps: int):
            asked.append((dps, super().mpmath(dps)))
            return asked[-1][1]

    monkeypatch.setattr(mpmath_evaluator, "SOLVER", Recorded())
    an = symkin.analyze(symkin.load(EXAMPLES / "four_bar.toml"))
    symkin.evaluate(an, {"A0": "0.1"}, "exact")
    assert asked
    for dps, tol in asked:
        assert dps >= 40
        with mpmath.workdps(dps):
            eps = float(mpmath.mp.eps)
        assert tol.stalled == SOLVER.ulps.stalled * eps and tol.rigid == SOLVER.ulps.rigid * eps


# -- the emitted texts ---------------------------------------------------------------------------


@pytest.fixture(scope="module")
def emitted():
    """The piezo amplifier's C and numpy texts: the loaded level with its report, a stroke
    actuator (every table of the runtimes)."""
    an = symkin.analyze(symkin.load(EXAMPLES / "piezo_amplifier.toml"))
    plan = pipeline.plan_for(an)
    assert plan.loaded is not None and plan.loaded.report is not None and plan.actuators
    c = pipeline.emit(plan, "c", "piezo_amplifier")[1]
    py = pipeline.emit(plan, "numpy", "piezo_amplifier")[0]
    return c, py


def c_number(text: str) -> int | float:
    return int(text) if re.fullmatch(r"-?\d+", text) else float(text)


def test_the_c_evaluator_defines_the_tables_numbers(emitted):
    c, _ = emitted
    for prefix, rules in (
        ("SK_LOADED_", SOLVER.loaded.rules()),
        ("SK_STROKE_", SOLVER.strokes.rules()),
    ):
        defined = {
            m.group(1).lower(): c_number(m.group(2))
            for m in re.finditer(rf"^#define {prefix}(\w+) (\S+)$", c, re.M)
        }
        assert defined.keys() == rules.keys(), prefix
        for key, value in rules.items():
            assert same(defined[key], value), (prefix, key)
    # the loops' rules in the mechanism's table
    tol = SOLVER.float64
    rule = re.search(r"\.rigid_rule = \{(\d+), (\S+), 0\.0, 0\.0, 0\.0\}", c)
    assert rule and (int(rule[1]), float(rule[2])) == (SOLVER.rigid_iterations, tol.rigid)
    rule = re.search(r"\.polish_rule = \{(\d+), 0\.0, (\S+), (\S+), (\S+)\}", c)
    assert rule and (int(rule[1]), *map(float, rule.groups()[1:])) == (
        tol.polish,
        tol.converged,
        tol.stalled,
        SOLVER.stall_ratio,
    )
    rule = re.search(r"\.exact_rule = \{(\d+), 0\.0, (\S+), (\S+), (\S+), (\S+)\}", c)
    assert rule and (int(rule[1]), *map(float, rule.groups()[1:])) == (
        SOLVER.exact_iterations,
        tol.converged,
        tol.stalled,
        SOLVER.stall_ratio,
        tol.residual,
    )
    step = re.search(r"\.continuation_step = (\S+), \.winding = (\S+),", c)
    assert step and (float(step[1]), float(step[2])) == (SOLVER.continuation_step, SOLVER.winding)
    assert re.search(r"\.consistent = (\S+),", c)[1] == repr(tol.consistent)


def keywords(call: ast.Call) -> dict[str, ast.expr]:
    return {k.arg: k.value for k in call.keywords if k.arg}


def test_the_numpy_module_holds_the_tables_numbers(emitted):
    _, py = emitted
    tree = ast.parse(py)
    (mechanism,) = [
        n.value
        for n in tree.body
        if isinstance(n, ast.Assign) and getattr(n.targets[0], "id", "") == "_MECHANISM"
    ]
    fields = keywords(mechanism)
    loaded = keywords(fields["loaded"])
    rules = SOLVER.loaded.rules()
    for key, value in rules.items():
        assert same(ast.literal_eval(loaded[key]), value), key
    strokes = ast.literal_eval(fields["stroke_rules"])
    assert strokes.keys() == SOLVER.strokes.rules().keys()
    for key, value in SOLVER.strokes.rules().items():
        assert same(strokes[key], value), key
    tol = SOLVER.float64
    rigid = [ast.literal_eval(a) for a in fields["rigid_rule"].args]
    assert rigid == [SOLVER.rigid_iterations, tol.rigid]
    polish = [ast.literal_eval(a) for a in fields["polish_rule"].args]
    assert polish == [tol.polish, 0.0, tol.converged, tol.stalled, SOLVER.stall_ratio]
    exact = [ast.literal_eval(a) for a in fields["exact_rule"].args]
    assert exact == [
        SOLVER.exact_iterations,
        0.0,
        tol.converged,
        tol.stalled,
        SOLVER.stall_ratio,
        tol.residual,
    ]
    assert ast.literal_eval(fields["continuation_step"]) == SOLVER.continuation_step
    assert ast.literal_eval(fields["winding"]) == SOLVER.winding
    assert ast.literal_eval(fields["consistent"]) == tol.consistent


def test_the_numpy_module_holds_the_python_solver_verbatim(emitted):
    """The loaded level's solver is written once for Python: the module holds its text."""
    _, py = emitted
    text = templating.shared("symkin.physics.reduced_solver")
    assert "def _red_newton(" in text and "import" not in text.split("\n", 1)[0]
    assert text in py
    assert py.count("def _red_newton(") == 1
    # and the kinematic levels' Newton, the 40-digit evaluation's too
    text = templating.shared("symkin.kinematics.loop_newton")
    assert "def _newton_solve(" in text and text in py
    assert py.count("def _newton_solve(") == 1 and py.count("class _Rule:") == 1


def test_the_numpy_rules_are_the_tables_loop_rules(emitted):
    """The module's three _Rule calls are SOLVER.loop_rules at float64, the arguments the
    40-digit path hands the same Newton at its own ε."""
    _, py = emitted
    rules = SOLVER.loop_rules(SOLVER.float64)
    for name in ("rigid", "polish", "exact"):
        call = re.search(rf"^    {name}_rule=_Rule(\(.*?\)),", py, re.M)
        assert call and ast.literal_eval(call[1]) == rules[name], name


@pytest.mark.parametrize("dps", [40, 60])
def test_the_40_digit_newton_runs_the_rules_at_its_epsilon(monkeypatch, dps):
    """symkin.studies.mpmath_evaluator hands the shared Newton (symkin.kinematics.loop_newton)
    the rules in units of its own ε: the exact level's and the polish's at `dps` digits."""
    seen = []
    solve = mpmath_evaluator._newton_solve

    def recorded(ar, system, x, index, ok, rule, *args, **kwargs):
        seen.append(rule)
        return solve(ar, system, x, index, ok, rule, *args, **kwargs)

    monkeypatch.setattr(mpmath_evaluator, "_newton_solve", recorded)
    an = symkin.analyze(symkin.load(EXAMPLES / "four_bar.toml"))
    with mpmath.workdps(dps):
        eps = float(mpmath.mp.eps)
    config = configuration.configure(an, {"A0": "0.1"}, "exact")
    mpmath_evaluator.evaluator_of(an).values(config, dps)
    polish, exact = seen  # the closed-form start polished, then the exact level's Newton
    assert (polish.iterations, polish.converged, polish.stalled) == (
        SOLVER.polish_mpmath,
        SOLVER.ulps.converged * eps,
        SOLVER.ulps.stalled * eps,
    )
    assert exact.iterations == SOLVER.exact_iterations
    assert (exact.converged, exact.stalled, exact.residual) == (
        SOLVER.ulps.converged * eps,
        SOLVER.ulps.stalled * eps,
        SOLVER.ulps.residual * eps,
    )
    assert exact.stall_ratio == polish.stall_ratio == SOLVER.stall_ratio


def test_the_numpy_module_holds_the_stroke_solve_verbatim(emitted):
    """The stroke actuators' solve is written once for Python: the module holds its text, and
    the sympy backend's solve (symkin.studies.actuators) calls the same function."""
    _, py = emitted
    text = templating.shared("symkin.studies.stroke_solver")
    assert "def _stroke_solve(" in text and text in py
    assert py.count("def _stroke_solve(") == 1
    assert actuators._stroke_solve is stroke_solver._stroke_solve


def test_the_numpy_module_holds_the_python_rates_verbatim(emitted):
    """The loaded level's implicit-function theorem (its reported rates and sensitivities) is
    written once for Python too: the module holds its text, and no other copy of it."""
    _, py = emitted
    text = templating.shared("symkin.physics.reduced_rates")
    assert "def _red_implicit(" in text and "def _red_sensitivity(" in text
    assert text in py
    assert py.count("def _red_implicit(") == 1
    solve = "-numpy.linalg.solve(jac"  # dx = -J^-1 ...: the theorem's solves, the shared ones only
    assert py.count(solve) == text.count(solve) > 0


# -- no solver literal left in a runtime file ------------------------------------------------------

#: Numbers every runtime file may hold: index and layout arithmetic (3 rows per point, 5 inputs
#: and 12 outputs per half plate, 6 values per point, 9 per stiffness, 8 per plate's stress row,
#: 15 partials per half plate, status codes 0-4) and the arithmetic's own 0, 1, 2 (halves in
#: central differences and averages, not step cuts: those are the table's).
COMMON = {"0", "1", "2", "3", "4", "5", "6", "8", "9", "12", "15", "0.0", "1.0", "2.0"}
PI = "3.141592653589793"
#: cos d and sin d of an RK4 stage's small turn by their Taylor series (the stress integration
#: of templates/*/reduced_report.*): the factorials, and the range where the terms left out are
#: below 2e-18 of them (the series' own, libm beyond it), no solver rule.
TURN_SERIES = {
    "0.03": "the turn series' range (|d| <= 0.03: the terms left out below 2e-18)",
    "24": "4!",
    "120": "5!",
    "720": "6!",
    "5040": "7!",
    "40320": "8!",
}
#: What else a file may hold, and why (none of it a solver rule).
ALLOWED = {
    "templates/c/runtime.c": {
        "6.283185307179586476925286766559006": "2 pi (SK_TWO_PI, the angles' wrap)",
        "0.5": "pi = 0.5 SK_TWO_PI in sk_wrap",
        PI: "the inputs' bound |x| <= pi (docs/levels.md)",
    },
    "templates/c/actuators.c": {PI: "the drives' bound |x| <= pi"},
    "templates/c/reduced.c": {PI: "a compliant angle within (-pi, pi); the Euler load's pi^2"},
    "templates/c/reduced_report.c": {
        "7": "the stress row's allowable",
        "12.0": "t^2 / 12",
        **TURN_SERIES,
    },
    "templates/numpy/reduced_report.py": TURN_SERIES,
    "templates/numpy/reduced_notch_report.py": {"7": "the stress row's allowable"},
    "templates/c/modes.c": {"0.5": "the Jacobi rotation's t = 1/(2 theta) for a huge theta"},
    "templates/numpy/runtime.py": {
        "8192": "_CHUNK: elements per block (memory, not arithmetic)",
    },
    "symkin/physics/reduced.py": {
        "1e-300": "the mechanism's size L at least this (an empty file)",
        "30": "digits of a sympy evaluation of the parameters",
        "17": "digits of a float's exact sympy Float",
    },
    "symkin/physics/reduced_reported.py": {"20": "digits of a sympy evaluation"},
    "symkin/physics/equilibrium.py": {
        "1j": "the complex step's imaginary unit (its size: arith.COMPLEX_STEP)",
        "17": "digits of a float's exact sympy Float",
        "20": "digits of a sympy evaluation",
        "10": "mpmath.mpf(10) ** digits: a rule stated in decimal digits",
        "10.0": "10.0 ** digits: a rule stated in decimal digits",
    },
}
ALLOWED["symkin/studies/mpmath_evaluator.py"] = {
    "30": "digits of the parameters' and limits' evaluation",
    "35": "digits of sympy's evaluation of the parameters and inputs",
}
ALLOWED["symkin/studies/actuators.py"] = {
    "30": "digits of the direction's central differences",
    "10": "guard digits above the working precision, and mpmath.mpf(10) ** digits",
}
#: The runtime files and their Python twins: the loaded level's, the sympy backend's loop
#: solvers (symkin.studies.mpmath_evaluator) and its stroke solve (symkin.studies.actuators).
RUNTIMES = [
    "templates/c/runtime.c",
    "templates/c/reduced.c",
    "templates/c/reduced_sens.c",
    "templates/c/reduced_report.c",
    "templates/c/modes.c",
    "templates/c/actuators.c",
    "templates/numpy/runtime.py",
    "templates/numpy/actuators.py",
    "templates/numpy/reduced.py",
    "templates/numpy/reduced_sens.py",
    "templates/numpy/reduced_report.py",
    "templates/numpy/reduced_actuators.py",
    "templates/numpy/reduced_actuators_sens.py",
    "templates/numpy/reduced_notch.py",
    "templates/numpy/reduced_notch_report.py",
    "templates/numpy/modes.py",
    "symkin/physics/reduced.py",
    "symkin/physics/reduced_solver.py",  # the loaded level's solver: Python's and numpy's
    "symkin/kinematics/loop_newton.py",  # the kinematic levels' Newton: mpmath's and numpy's
    "symkin/physics/reduced_rates.py",  # the loaded level's rates: Python's and numpy's
    "symkin/physics/stiffness_rule.py",  # the report's stiffness rule: Python's and numpy's
    "symkin/physics/reduced_reported.py",
    "symkin/physics/equilibrium.py",  # no generated twin, its rules in the table too
    "symkin/studies/mpmath_evaluator.py",
    "symkin/studies/actuators.py",
    "symkin/studies/stroke_solver.py",  # the stroke solve: Python's and numpy's
]
#: An iteration counter compared with a number: a cap or a stall test's start (the table's).
#: (0 and 1 tell the first step from the others.)
COUNTER = re.compile(r"\b(it|iter|iteration|half|halvings|steps)\s*(<=|>=|<|>|==)\s*([2-9]|\d\d)")
NUMBER = re.compile(r"(?<![\w.])(\d+\.\d*|\.\d+|\d+)([eE][-+]?\d+)?(?![\w.])")


def code_of(path: str) -> tuple[str, list[str]]:
    """The file's code without comments and strings, and its numeric literals."""
    text = (ROOT / path).read_text()
    if path.endswith(".c"):
        text = re.sub(r"/\*.*?\*/", " ", text, flags=re.S)
        text = re.sub(r"//[^\n]*", " ", text)
        text = re.sub(r'"[^"\n]*"', '""', text)
        return text, [m.group(0) for m in NUMBER.finditer(text)]
    kept, numbers = [], []
    for tok in tokenize.generate_tokens(io.StringIO(text).readline):
        if tok.type == tokenize.NUMBER:
            numbers.append(tok.string)
        if tok.type not in (tokenize.COMMENT, tokenize.STRING):
            kept.append(tok.string)
    return " ".join(kept), numbers


@pytest.mark.parametrize("path", RUNTIMES)
def test_no_solver_literal_in_a_runtime_file(path):
    code, numbers = code_of(path)
    allowed = COMMON | set(ALLOWED.get(path, {}))
    stray = collections.Counter(n for n in numbers if n not in allowed)
    assert not stray, f"{path}: numbers outside the solver table: {dict(stray)}"
    assert not COUNTER.findall(code), f"{path}: an iteration cap or stall start as a literal"
    # every allowance is still needed (a stale one would hide a new literal of that value)
    assert set(ALLOWED.get(path, {})) <= set(numbers), path


def test_the_scan_finds_what_the_table_replaced():
    """The scan above, on the loaded level's Newton as it read before the table: it fails."""
    before = "if (!chord && it > 3 && size > 0.5 * prev && size < 1e-9 * top) {"
    assert COUNTER.findall(before)
    assert {m.group(0) for m in NUMBER.finditer(before)} - COMMON == {"0.5", "1e-9"}
