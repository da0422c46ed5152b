"""templates/c/runtime.c on its own: compiled with the strict flags of the generated code and a
driver of its own (tests/runtime_driver.c: a toy mechanism's routines and a command loop), every
function checked against independent computations: an elimination written here in Python (the
same operations, so the same bits), numpy, and the toy mechanism's values and derivatives by
mpmath at 30 digits. The driver also runs under AddressSanitizer and UBSan.
"""

from __future__ import annotations

import math
import os
import subprocess

import numpy as np
import pytest
from conftest import ROOT
from evaluators import require_compiler
from runtime_toy import close, eliminate, toy, toy_partials

from symkin.codegen.templating import runtime

RUNTIME = ROOT / "templates" / "c"
DRIVER = ROOT / "tests" / "runtime_driver.c"
STRICT = ["-std=c99", "-pedantic", "-Wall", "-Wextra", "-Werror"]
SANITIZE = ["-O1", "-g", "-fsanitize=address,undefined", "-fno-sanitize-recover=all"]


def build(folder, flags) -> str:
    require_compiler()
    exe = folder / "driver"
    cc = os.environ.get("CC", "cc")
    subprocess.run(
        [cc, *STRICT, *flags, f"-I{RUNTIME}", str(DRIVER), "-o", str(exe), "-lm"], check=True
    )
    return str(exe)


@pytest.fixture(scope="module")
def driver(tmp_path_factory):
    return build(tmp_path_factory.mktemp("runtime_c"), ["-O2"])


def run(exe: str, commands: list[str]) -> list[tuple[str, list[str]]]:
    """The driver's output lines, each as (label, words)."""
    proc = subprocess.run(
        [exe], input="\n".join(commands) + "\n", capture_output=True, text=True, check=True
    )
    return [(line.split()[0], line.split()[1:]) for line in proc.stdout.splitlines()]


def numbers(words: list[str]) -> np.ndarray:
    return np.array([float(w) for w in words])


def words(values) -> str:
    return " ".join(repr(float(v)) for v in values)


# ---- dense linear algebra ----


def test_solve_is_the_elimination_bit_for_bit_and_agrees_with_numpy(driver):
    rng = np.random.default_rng(3)
    cases = []
    for n in range(1, 7):
        for m in (1, 2, 3):
            a = rng.normal(size=(n, n))
            a[rng.integers(n), :] *= 1e3  # pivoting matters
            cases.append((a, rng.normal(size=(n, m))))
    out = run(
        driver,
        [f"solve {len(b)} {b.shape[1]} {words(a.ravel())} {words(b.ravel())}" for a, b in cases],
    )
    for k, (a, b) in enumerate(cases):
        (_, status), (_, x) = out[2 * k], out[2 * k + 1]
        assert status == ["0"]
        x = numbers(x).reshape(b.shape)
        want = eliminate(a.tolist(), b.tolist())
        assert x.tolist() == want  # the same operations in the same order: the same bits
        np.testing.assert_allclose(x, np.linalg.solve(a, b), rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize(
    "a",
    [
        [[0.0, 0.0], [0.0, 0.0]],
        [[1.0, 2.0], [2.0, 4.0]],  # the second pivot is exactly zero
        [[1.0, float("nan")], [0.0, 1.0]],
        [[float("inf"), 0.0], [0.0, 1.0]],
    ],
)
def test_solve_and_lu_refuse_singular_and_non_finite_matrices(driver, a):
    a = np.array(a)
    out = run(driver, [f"solve 2 1 {words(a.ravel())} 1 1", f"lu 2 {words(a.ravel())} 1 1 1 1"])
    assert out[0] == ("status", ["1"]) and out[2] == ("status", ["1"])


def test_lu_solves_each_right_hand_side_as_solve_does(driver):
    rng = np.random.default_rng(5)
    for n in (1, 3, 5, 8):
        a = rng.normal(size=(n, n))
        b = rng.normal(size=(2, n))
        out = run(
            driver,
            [
                f"lu {n} {words(a.ravel())} {words(b.ravel())}",
                f"solve {n} 1 {words(a.ravel())} {words(b[0])}",
                f"solve {n} 1 {words(a.ravel())} {words(b[1])}",
            ],
        )
        assert out[0] == ("status", ["0"])
        x = numbers(out[1][1]).reshape(2, n)
        assert x[0].tolist() == numbers(out[3][1]).tolist()
        assert x[1].tolist() == numbers(out[5][1]).tolist()
        np.testing.assert_allclose(x, np.linalg.solve(a, b.T).T, rtol=1e-9, atol=1e-12)


def test_wrap_is_remainder_by_two_pi(driver):
    two_pi = 2.0 * math.pi
    xs = [
        0.0,
        -0.0,
        1.0,
        math.pi,
        -math.pi,
        math.nextafter(math.pi, 4.0),
        3.5,
        -3.5,
        7.0,
        -20.0,
        1e9,
        1e-300,
    ]
    out = run(driver, [f"wrap {x!r}" for x in xs] + ["wrap nan"])
    for x, (_, got) in zip(xs, out):
        assert float(got[0]) == math.remainder(x, two_pi) and math.copysign(
            1.0, float(got[0])
        ) == math.copysign(1.0, math.remainder(x, two_pi)), x
    assert math.isnan(float(out[-1][1][0]))


# ---- Newton and continuation ----

RULE = "40 0 1e-8 1e-12 0.5"  # the exact level's: iterations, tolerance, converged, stalled, ratio
STALL = "40 0 1e-20 1e-12 0.5"  # a relative test below the stall test's (as at 30 digits)


@pytest.mark.parametrize(
    "rule, change, size, previous, stop",
    [
        ("30 1e-10 0 0 0", 1e-10, 1.0, "inf", 1),  # at most the tolerance
        ("30 1e-10 0 0 0", 2e-10, 0.0, "inf", 0),  # no relative test without `converged`
        ("30 1e-10 0 0 0", 2e-10, 1.0, 1e-10, 0),  # nor a stall test
        (RULE, 1e-9, 0.2, "inf", 1),  # relative: 1e-9 <= 1e-8 * 0.2
        (RULE, 1e-8, 0.2, "inf", 0),
        (RULE, 0.5, 0.0, "inf", 0),  # a step onto all-zero unknowns: on (a tiny input's polish)
        (RULE, 0.0, 0.0, "inf", 1),  # a zero step at zero: converged
        (STALL, 1e-13, 1.0, 1e-13, 1),  # stalled at rounding: no smaller than half the last
        (STALL, 1e-13, 1.0, 1e-12, 0),  # still shrinking
        (STALL, 1e-11, 1.0, 1e-11, 0),  # stalled, but not at rounding
        (RULE, "nan", 1.0, "inf", 0),
    ],
)
def test_newton_stop(driver, rule, change, size, previous, stop):
    out = run(driver, [f"stop {rule} {change} {size} {previous}"])
    assert out == [("stop", [str(stop)])]


def test_newton_converges_from_any_layout(driver):
    root = math.sqrt(2.0)
    out = run(
        driver,
        [
            f"newton {RULE} 1 0 0 1 1.5",
            f"newton {RULE} 1 1 0 1 1.5",  # the system at x given: the same steps
            f"newton {RULE} 1 0 1 1 1.5",  # the unknowns at x[3], x[1] of a longer array
        ],
    )
    assert out[0][1] == ["0"] and out[2][1] == ["0"] and out[4][1] == ["0"]
    x = numbers(out[1][1])
    assert abs(x[0] - root) <= 2e-16 * root and abs(x[1] - root) <= 2e-16 * root
    assert out[3][1] == out[1][1]
    mapped = numbers(out[5][1])
    assert mapped.tolist() == [100.0, x[1], 102.0, x[0], 104.0]


def test_newton_stops_at_a_residual_at_rounding(driver):
    """A root at zero whose residual stays at rounding noise (+-1e-17, terms of size 1): without
    the residual rule Newton chases the noise to its step limit; with it (symkin.core.settings,
    3b), it stops after the first evaluation, where |f| = 1e-17 <= 2e-13 (1 + |J x|)."""
    out = run(driver, [f"quiet {RULE} 0", f"quiet {RULE} 2e-13"])
    assert out[0][1] == ["2", "evaluations", "40"]
    assert out[1][1] == ["0", "evaluations", "1"]


def test_newton_reports_singular_and_unfinished(driver):
    out = run(
        driver,
        [
            f"newton {RULE} 1 0 0 0 0",  # J = [0 0; 1 -1] at the origin
            "newton 1 0 1e-8 1e-12 0.5 1 0 0 30 -7",  # one step from far away
            "newton 0 0 1e-8 1e-12 0.5 1 0 0 30 -7",  # no step at all
        ],
    )
    assert out[0][1] == ["1"]
    assert out[2][1] == ["2"] and out[4][1] == ["2"]
    assert numbers(out[5][1]).tolist() == [30.0, -7.0]


@pytest.mark.parametrize("top, step, steps", [(1.0, 0.05, 20), (0.0, 0.05, 1), (0.12, 0.05, 3)])
def test_continuation_stages(driver, top, step, steps):
    out = run(driver, [f"continuation 30 1e-10 0 0 0 {top} {step}"])
    status, x = out[0][1], numbers(out[1][1])
    assert status[:3] == ["0", "steps", str(steps)] and status[3:] == [
        "stages",
        str(steps),
        "t",
        "1",
    ]
    # x0^2 + x1^2 = 4 and x0 = x1 at t = 1, followed from (2, 0) at t = 0
    assert abs(x[0] - math.sqrt(2.0)) < 1e-15 and abs(x[1] - math.sqrt(2.0)) < 1e-15


# ---- one mechanism's evaluator: the toy of tests/runtime_driver.c ----


@pytest.mark.parametrize("closed", [1, 0])
@pytest.mark.parametrize("level", [0, 1, 2, 3])
def test_pose_at_every_level(driver, closed, level):
    for theta0, p0, p1 in ((0.3, 0.5, 1.0), (-0.8, 1.7, -0.2), (0.05, -0.4, 0.0)):
        out = dict(run(driver, [f"pose {closed} {level} {theta0} {p0} {p1}"]))
        want = toy(theta0, p0, p1, level)
        assert out["status"] == ["0"]
        o, ang, lnk = numbers(out["out"]), numbers(out["angles"]), numbers(out["links"])
        r, d = want["rigid"], want["dev"]
        assert close(o, [r[0], r[1], r[0] + d[0], r[1] + d[1], d[0], d[1]])
        t, u = want["theta"], want["delta"]
        assert close(ang, [*t, t[0], t[1] + u[0], t[2] + u[1]])
        assert close(lnk, [want["link"], want["link"] + u[0] + u[1], u[0] + u[1]])


@pytest.mark.parametrize(
    "command, status",
    [
        ("pose 1 4 0.3 0.5 1.0", 3),  # a level the mechanism does not have
        ("pose 1 2 3.2 0.5 1.0", 3),  # an input beyond a half turn
        ("pose 0 2 nan 0.5 1.0", 3),
        ("pose 1 2 0.3 nan 1.0", 3),  # a parameter that is not finite
        ("pose 1 2 1.2 0.5 1.0", 1),  # closed form: the dyad's reach 1 - theta_0^2 < 0
        ("pose 1 2 0.3 8.0 1.0", 1),  # hinge 1 beyond its limit 2: theta_1 = 2.4
        ("pose 0 2 0.3 8.0 1.0", 1),
        ("pose 1 2 0.3 6.6 1.0", 1),  # theta_1 = 1.98, but theta_1 + delta_0 > 2
        ("pose 1 3 0.3 0.5 6.0", 1),  # the loaded level's driver refuses
        ("pose 1 5 0.3 0.5 1.0", 3),  # loaded_refined (code 5) is not generated any more
    ],
)
def test_pose_failures_give_nan(driver, command, status):
    out = dict(run(driver, [command]))
    assert out["status"] == [str(status)]
    for key in ("out", "angles", "links"):
        assert np.isnan(numbers(out[key])).all()


def test_rows_and_grid_are_the_poses_of_every_row_and_set(driver):
    inputs = [0.3, -0.7, 1.5, 0.0]
    out = dict(run(driver, [f"rows 1 2 {len(inputs)} {words(inputs)}"]))
    poses = [
        dict(run(driver, [f"pose 1 2 {x} {p0} {p1}"]))
        for p0, p1 in ((0.5, 1.0), (0.4, 1.5))
        for x in inputs
    ]
    assert out["failed"] == ["1"] and out["status"] == ["0", "0", "1", "0"]
    rows = numbers(out["out"]).reshape(len(inputs), 6)
    angles = numbers(out["angles"]).reshape(len(inputs), 6)
    for i in range(len(inputs)):
        assert rows[i].tolist() == numbers(poses[i]["out"]).tolist() or i == 2
        assert angles[i].tolist() == numbers(poses[i]["angles"]).tolist() or i == 2
    assert np.isnan(rows[2]).all()
    assert out["grid"] == ["2"] and out["gstatus"] == ["0", "0", "1", "0"] * 2
    grid = numbers(out["gout"]).reshape(2 * len(inputs), 6)
    for k, pose in enumerate(poses):
        assert np.array_equal(grid[k], numbers(pose["out"]), equal_nan=True)


@pytest.mark.parametrize("closed", [1, 0])
@pytest.mark.parametrize("level", [0, 2])
def test_sensitivities_are_the_derivatives_of_the_deviation(driver, closed, level):
    theta0, p0, p1 = 0.3, 0.5, 1.0
    out = run(driver, [f"deriv {closed} {level} {theta0} {p0} {p1}"])
    got = dict(out[:4])
    assert got["status"] == ["0"]
    dev = numbers(got["dev"]).reshape(3, 2)  # per variable (p0, p1, theta_0): d(dx), d(dy)
    rig = numbers(got["rig"]).reshape(3, 2)
    for table, key in ((dev, "dev"), (rig, "rigid")):
        want = toy_partials(theta0, p0, p1, level, key)
        assert close(table.ravel(), [w for row in want for w in row], 1e-12)
    # the parameters' columns alone, and the same in a batch of one row
    assert numbers(out[5][1]).tolist() == dev[:2].ravel().tolist()
    assert out[6] == ("failed", ["0"]) and out[7][1] == got["dev"]


def test_sensitivities_refused_where_a_level_has_none(driver):
    out = run(driver, ["deriv 1 1 0.3 0.5 1.0", "deriv 1 3 0.3 0.5 1.0"])
    for k in (0, 8):
        assert out[k] == ("status", ["3"])
        for label, values in out[k + 1 : k + 4] + out[k + 5 : k + 6]:
            assert np.isnan(numbers(values)).all(), label


def test_driver_under_address_and_undefined_sanitizers(tmp_path):
    exe = build(tmp_path, SANITIZE)
    commands = [
        "solve 3 2 2 1 0 1 3 1 0 1 4 1 2 3 4 5 6",
        "lu 3 2 1 0 1 3 1 0 1 4 1 2 3 4 5 6",
        f"newton {RULE} 1 1 1 1 1.5",
        "continuation 30 1e-10 0 0 0 1 0.05",
        "rows 1 2 4 0.3 -0.7 1.5 0.0",
        "rows 0 3 2 0.3 -0.7",
        "deriv 0 2 0.3 0.5 1.0",
        "deriv 1 1 0.3 0.5 1.0",
    ] + [f"pose {c} {lv} 0.3 0.5 1.0" for c in (0, 1) for lv in (0, 1, 2, 3, 4, 5)]
    proc = subprocess.run(
        [exe],
        input="\n".join(commands) + "\n",
        capture_output=True,
        text=True,
        env={**os.environ, "ASAN_OPTIONS": "detect_leaks=1"},
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert "runtime error" not in proc.stderr


def test_generated_c_holds_the_runtime_sections_it_runs():
    from evaluators import generated

    from symkin.codegen.backends.c import backend as c_backend

    for key, wanted in (
        (
            "four_bar",
            {
                "SK_LOOPS",
                "SK_CLOSED_FORM",
                "SK_LOADED",
                "SK_LOADED_IFT",
                "SK_LINKS",
                "SK_SENSITIVITY",
            },
        ),
        ("triad", {"SK_LOOPS", "SK_CONTINUATION", "SK_LINKS", "SK_SENSITIVITY"}),
        ("serial_arm", {"SK_LINKS", "SK_SENSITIVITY"}),
    ):
        plan = generated(key).plan
        assert set(c_backend.features(plan)) == wanted, key
        _, code = c_backend.emit(plan, "test")
        text = runtime("c/runtime.c", wanted)
        assert text in code and "#if" not in text and "#endif" not in text
    # the sections are the file's: every line of the resolved text is one of the file's, in order
    whole = (RUNTIME / "runtime.c").read_text()
    assert runtime("c/runtime.c", None) in whole
    lines = iter(whole.splitlines())
    assert all(line in lines for line in runtime("c/runtime.c", wanted).splitlines())
    assert "#include" not in runtime("c/runtime.c", None)  # the generated file's own serve it


def test_runtime_sections_resolve_as_the_preprocessor_would(tmp_path):
    """Each set of features gives the text the C preprocessor keeps with those macros
    defined (comments aside): compared after `cc -E -P` of both."""
    require_compiler()
    cc = os.environ.get("CC", "cc")
    names = ["SK_LOOPS", "SK_CLOSED_FORM", "SK_CONTINUATION", "SK_LOADED", "SK_LINKS"]
    names.append("SK_SENSITIVITY")

    def preprocessed(text: str, defines: list[str]) -> str:
        src = tmp_path / "x.c"
        src.write_text(text)
        flags = [f"-D{d}" for d in defines]
        out = subprocess.run(
            [cc, "-E", "-P", *flags, str(src)], capture_output=True, text=True, check=True
        ).stdout
        return "\n".join(line for line in out.splitlines() if line.strip())

    full = runtime("c/runtime.c", None)
    for k in range(1 << len(names)):
        chosen = [n for i, n in enumerate(names) if k >> i & 1]
        if k % 7 and k != (1 << len(names)) - 1:
            continue  # a spread of the 64 combinations
        assert preprocessed(runtime("c/runtime.c", chosen), []) == preprocessed(full, chosen)
