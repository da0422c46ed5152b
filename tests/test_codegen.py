"""Generated numpy and C evaluators against the sympy backend and the independent solver.

Relative error of the deviation <= 1e-9 in float64 at ordinary and extreme inputs: tiny plates
(l/L = 1e-9), tiny angles (1e-8) and near a toggle position.
"""

from __future__ import annotations

import ast
import os
import subprocess
import sys

import mechanisms as M
import numpy as np
import pytest
from conftest import EXAMPLES, ROOT
from evaluators import GENERATED, INPUTS, SOURCES, generated, rel_err, require_compiler
from reference_solver import Reference

import symkin
from symkin.codegen import pipeline


@pytest.mark.parametrize("key", sorted(SOURCES))
@pytest.mark.parametrize("backend", GENERATED)
def test_exact_level_against_independent_solver(key, backend):
    g = generated(key)
    ref = Reference(g.mech).deviation(INPUTS[key])
    got = g.run(backend, INPUTS[key], "exact")
    for name, dev in got.items():
        assert rel_err(dev, ref["points"][name]["deviation"]) <= 1e-9, name


@pytest.mark.parametrize("key", ["four_bar", "six_bar", "nine_bar", "five_bar", "triad"])
@pytest.mark.parametrize("backend", GENERATED)
@pytest.mark.parametrize("level", ["paper", "first_order", "exact"])
def test_every_level_matches_the_sympy_backend(key, backend, level):
    g = generated(key)
    want = symkin.evaluate(g.analysis, INPUTS[key], level)
    got = g.run(backend, INPUTS[key], level)
    for name, dev in got.items():
        assert rel_err(dev, want.points[name].deviation) <= 1e-12, name


@pytest.mark.parametrize("key", ["four_bar", "six_bar", "five_bar", "triad"])
@pytest.mark.parametrize("backend", GENERATED)
def test_tiny_plates(key, backend):
    g = generated(key)
    overrides = {"l": "5e-11"}  # l/L about 1e-9
    ref = Reference(g.mech, overrides).deviation(INPUTS[key])
    got = g.run(backend, INPUTS[key], "exact", overrides)
    for name, dev in got.items():
        assert rel_err(dev, ref["points"][name]["deviation"]) <= 1e-9


@pytest.mark.parametrize(
    "key, inputs",
    [
        ("four_bar", {"A0": "1e-8"}),
        ("six_bar", {"O_A": "-1e-8"}),
        ("five_bar", {"O1": "1e-8", "O2": "2e-8"}),
        ("serial_arm", {"S": "1e-8", "E": "-1e-8"}),
    ],
)
@pytest.mark.parametrize("backend", GENERATED)
def test_tiny_angles(key, inputs, backend):
    g = generated(key)
    ref = Reference(g.mech).deviation(inputs)
    got = g.run(backend, inputs, "exact")
    for name, dev in got.items():
        assert rel_err(dev, ref["points"][name]["deviation"]) <= 1e-9


def toggle_input(g) -> float:
    """The non-Grashof four-bar's rigid assembly limit for A0 > 0, by bisection on the dyad."""
    lo, hi = 0.3, 3.0
    for _ in range(60):
        mid = (lo + hi) / 2
        try:
            symkin.evaluate(g.analysis, {"A0": repr(mid)}, "paper", dps=20)
            lo = mid
        except symkin.AssemblyError:
            hi = mid
    return lo


@pytest.mark.parametrize("margin", ["1e-2", "1e-3"])
@pytest.mark.parametrize("backend", GENERATED)
def test_near_a_toggle_position(margin, backend):
    g = generated("non_grashof")
    limit = toggle_input(g)
    inputs = {"A0": repr(limit - float(margin))}
    ref = Reference(g.mech).deviation(inputs)
    got = g.run(backend, inputs, "exact")
    assert rel_err(got["C"], ref["points"]["C"]["deviation"]) <= 1e-9


def test_numpy_broadcasts_and_masks_what_cannot_assemble():
    g = generated("five_bar")
    o1 = np.array([[0.1], [0.2], [float("nan")]])
    o2 = np.array([[-0.1, 0.0, 0.05, 3.0]])
    res = g.numpy.evaluate({"O1": o1, "O2": o2}, "exact")
    assert res["ok"].shape == (3, 4)
    assert res["points"]["P_tip"]["deviation"].shape == (2, 3, 4)
    assert not res["ok"][2].any()  # NaN input
    for i in range(2):
        for j in range(3):
            assert res["ok"][i, j]
            want = (
                symkin.evaluate(
                    g.analysis, {"O1": repr(float(o1[i, 0])), "O2": repr(float(o2[0, j]))}, "exact"
                )
                .points["P_tip"]
                .deviation
            )
            assert rel_err(res["points"]["P_tip"]["deviation"][:, i, j], want) <= 1e-12
    bad = ~res["ok"]
    assert np.isnan(res["points"]["P_tip"]["deviation"][:, bad]).all()


def test_out_of_range_is_nan_in_numpy_and_status_1_in_c():
    g = generated("non_grashof")
    res = g.numpy.evaluate({"A0": np.array([0.3, 2.5])}, "exact")
    assert res["ok"].tolist() == [True, False]
    assert np.isnan(res["points"]["C"]["compliant"][:, 1]).all()
    status, _, _ = g.lib.evaluate([2.5], None, 2)
    assert status == 1


def test_c_rejects_bad_arguments():
    g = generated("four_bar")
    assert g.lib.evaluate([float("nan")], None, 2)[0] == 3
    unknown = max(lv.code for lv in symkin.core.levels.LEVELS) + 1  # no level has this code
    assert g.lib.evaluate([0.1], None, unknown)[0] == 3
    assert g.lib.evaluate([0.1], [float("inf")], 2)[0] == 3


def test_numpy_module_imports_only_numpy_and_the_standard_library():
    g = generated("four_bar")
    tree = ast.parse(pipeline.emit(g.plan, "numpy", g.mech.path)[0])
    modules = {
        alias.name.split(".")[0]
        for node in ast.walk(tree)
        if isinstance(node, ast.Import)
        for alias in node.names
    }
    modules |= {
        node.module.split(".")[0] for node in ast.walk(tree) if isinstance(node, ast.ImportFrom)
    }
    assert modules <= {"numpy", "math"} | set(sys.stdlib_module_names)


HARNESS = r"""
#include <math.h>
#include <stdio.h>
#include "NAME.h"
int main(void)
{
    double out[6 * NAME_UPPER_N_POINTS + 6], angles[2 * NAME_UPPER_N_HINGES];
    double in[NAME_UPPER_N_INPUTS];
    static const int codes[] = {NAME_LEVELS};
    int i, k, level, status, bad = 0;
    for (k = 0; k < (int)(sizeof codes / sizeof codes[0]); ++k) {
        level = codes[k];
        for (i = 0; i < NAME_UPPER_N_INPUTS; ++i) in[i] = 0.05 * (i + 1);
        status = NAME_evaluate(in, NULL, level, out);
        if (status != 0 || !isfinite(out[4])) bad = 1;
        status = NAME_evaluate_angles(in, NAME_default_params, level, out, angles);
        if (status != 0) bad = 1;
    }
    in[0] = NAN;
    if (NAME_evaluate(in, NULL, 2, out) != 3) bad = 1;
    if (NAME_evaluate(NULL, NULL, 2, out) != 3) bad = 1;
    printf("%s\n", bad ? "FAIL" : "OK");
    return bad;
}
"""


@pytest.mark.parametrize("key", ["four_bar", "triad"])
def test_c_harness_under_address_and_undefined_sanitizers(tmp_path, key):
    require_compiler()
    g = generated(key)
    name = g.mech.name
    header, code = pipeline.emit(g.plan, "c", g.mech.path)
    (tmp_path / f"{name}.h").write_text(header)
    (tmp_path / f"{name}.c").write_text(code)
    (tmp_path / "main.c").write_text(
        HARNESS.replace("NAME_UPPER", name.upper())
        .replace("NAME_LEVELS", ", ".join(str(lv.code) for lv in g.plan.levels))
        .replace("NAME", name)
    )
    cc = os.environ.get("CC", "cc")
    flags = [
        "-std=c99",
        "-pedantic",
        "-Wall",
        "-Wextra",
        "-Werror",
        "-O1",
        "-g",
        "-fsanitize=address,undefined",
        "-fno-sanitize-recover=all",
    ]
    subprocess.run(
        [cc, *flags, "main.c", f"{name}.c", "-o", "harness", "-lm"], cwd=tmp_path, check=True
    )
    proc = subprocess.run(
        ["./harness"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        env={**os.environ, "ASAN_OPTIONS": "detect_leaks=1"},
    )
    assert proc.returncode == 0 and proc.stdout.strip() == "OK", proc.stdout + proc.stderr
    assert "runtime error" not in proc.stderr


def test_derive_is_deterministic_across_hash_seeds(tmp_path):
    """Two processes under two hash seeds each derive the four-bar (every level, loaded and
    the sensitivities: the most set- and dict-heavy derivation) with no kept plan to read."""
    outputs = []
    for seed in ("1", "12345"):
        out = tmp_path / f"out{seed}"
        env = {**os.environ, "PYTHONHASHSEED": seed, "SYMKIN_PLAN_CACHE": "off"}
        subprocess.run(
            [
                sys.executable,
                "-m",
                "symkin",
                "derive",
                "--quiet",
                "--emit",
                "c,numpy",
                str(EXAMPLES / "four_bar.toml"),
                "-o",
                str(out),
            ],
            env=env,
            check=True,
            cwd=ROOT,
        )
        outputs.append({p.name: p.read_bytes() for p in sorted(out.iterdir())})
    assert outputs[0] == outputs[1]


HOSTILE = M.text(
    "hostile",
    M.links("int", "a-b", r"\input{/etc/passwd}", '"; system("true")')
    + M.hinge("int", "int", "a-b", 0.0, 0.0, "pi/2", input=True)
    + M.hinge("*/ x; /*", "a-b", r"\input{/etc/passwd}", 0.015, 0.026)
    + M.hinge(
        '""" + __import__("os").system("touch PWNED") + """',
        "int",
        '"; system("true")',
        0.1,
        0.0,
        "pi/2",
    )
    + M.hinge("\\\\\n#include <x>", r"\input{/etc/passwd}", '"; system("true")', 0.085, 0.068)
    + M.point("'; exit(1); '", r"\input{/etc/passwd}", 0.06, 0.09),
)


def test_hostile_names_give_safe_compiling_code(tmp_path):
    require_compiler()
    mech = symkin.loads(HOSTILE)
    an = symkin.analyze(mech)
    p, module = pipeline.build(an, "numpy", 'x"""y.toml')
    assert module.INPUTS == ("int",)
    assert module.POINTS == ("'; exit(1); '",)
    res = module.evaluate({"int": 0.2}, "exact")
    want = symkin.evaluate(an, {"int": "0.2"}, "exact").points["'; exit(1); '"].deviation
    assert rel_err(res["points"]["'; exit(1); '"]["deviation"], want) <= 1e-12
    assert not (ROOT / "PWNED").exists() and not (tmp_path / "PWNED").exists()
    lib = pipeline.evaluator(p, "c", "x*/y.toml", links=False)
    status, out, _ = lib.evaluate([0.2], None, 2)
    assert status == 0 and rel_err(out[4:6], want) <= 1e-12


@pytest.mark.parametrize("key", ["four_bar", "nine_bar", "triad"])
def test_rigid_res_carries_the_jacobian_of_its_residual(key):
    """rigid_res is the rigid Newton's whole system: its residual, then A, which must be the
    residual's own derivative by the unknown angles (differentiated here, not taken from the
    plan's `linear`), at a pose away from the as-fabricated one."""
    import sympy as sp

    g = generated(key)
    p = g.plan
    r = p.routines["rigid_res"]
    theta = r.arguments[0].symbols
    assert [b.name for b in r.blocks] == ["residual", "A"]
    outputs = list(r.outputs)
    for symbol, expr in reversed(r.assignments):  # the CSE undone: each in terms of theta
        outputs = [o.xreplace({symbol: expr}) for o in outputs]
    k = len(p.unknown_index)
    residual = sp.Matrix(outputs[:k])
    want = residual.jacobian([theta[i] for i in p.unknown_index])
    rng = np.random.default_rng(3)
    values = {s: float(v) for s, v in zip(theta, rng.uniform(-0.4, 0.4, len(theta)))}
    values |= {q.symbol: q.value for q in p.parameters}
    got = np.array([float(e.subs(values)) for e in outputs[k:]])
    ref = np.array([float(e.subs(values)) for e in want])
    assert np.abs(got - ref).max() <= 1e-12 * max(1.0, np.abs(ref).max())
