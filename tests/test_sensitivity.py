"""Sensitivities (docs/sensitivity.md) against central differences of the 40-digit mpmath
evaluation: every parameter and input, every point, deviation and rigid position, at every level,
in all three backends (mpmath, the generated numpy module and the generated C).

The references are independent of the sensitivity code: two mpmath evaluations of the
configuration at p ± h (h = 1e-12 relative; the values are passed as exact rationals, so the
difference quotient keeps ~25 digits), nothing differentiated.
"""

from __future__ import annotations

import math
import os
import pickle
import subprocess
import sys

import mechanisms as M
import mpmath
import numpy as np
import pytest
import sympy as sp
from conftest import EXAMPLES, ROOT
from evaluators import BACKENDS, require_compiler

import symkin
from symkin.cli.commands import main
from symkin.studies.configuration import configure
from symkin.studies.evaluation import evaluate
from symkin.studies.mpmath_evaluator import evaluator_of

FOUR_BAR = (EXAMPLES / "four_bar.toml").read_text()
TINY = FOUR_BAR.replace("l = 1e-3 ", "l = 1e-10 ")  # plates 1e-9 of the link lengths

CASES = {
    "four_bar": (FOUR_BAR, {"A0": "0.2"}, ("paper", "first_order", "exact")),
    "param_four_bar": (M.PARAM_FOUR_BAR, {"A0": "-0.25"}, ("paper", "first_order", "exact")),
    "six_bar": ((EXAMPLES / "stephenson_six_bar.toml").read_text(), {"O_A": "0.2"}, ("exact",)),
    "nine_bar": (
        (EXAMPLES / "nine_bar_platform.toml").read_text(),
        {"O": "0.05", "A": "0.03", "B": "-0.02", "K": "0.04"},
        ("exact",),
    ),
    "triad": (M.TRIAD_SIX_BAR, {"O1": "0.1"}, ("exact",)),
    "serial_arm": (M.SERIAL_ARM, {"S": "0.3", "E": "-0.2"}, ("paper",)),
    "tiny_plates": (TINY, {"A0": "1e-3"}, ("first_order", "exact")),
}


def exact(x) -> str:
    """An mpmath number as an expression string the parser reads exactly (integers)."""
    x = mpmath.mpf(x)
    sign = "-" if x < 0 else ""
    man, exp = x.man_exp
    return sign + (f"{man}/{2**-exp}" if exp < 0 else str(man * 2**exp))


_ANALYSES: dict[str, symkin.kinematics.analysis.Analysis] = {}


def analysis(key: str):
    if key not in _ANALYSES:
        _ANALYSES[key] = symkin.analyze(symkin.loads(CASES[key][0], key + ".toml"))
    return _ANALYSES[key]


def central(an, inputs: dict, level: str) -> dict:
    """(variable kind, name) -> {point: (d deviation, d rigid)} as mpmath pairs."""
    ev = evaluator_of(an)
    out = {}
    with mpmath.workdps(40):
        variables = [
            ("params", p.name, mpmath.mpf(sp.N(p.value, 45))) for p in an.mechanism.parameters
        ]
        variables += [("inputs", k, mpmath.mpf(v)) for k, v in inputs.items()]
        for kind, name, v0 in variables:
            h = abs(v0) * mpmath.mpf("1e-12") if v0 else mpmath.mpf("1e-15")
            values = []
            for step in (h, -h):
                if kind == "params":
                    values.append(
                        ev.values(configure(an, inputs, level, {name: exact(v0 + step)}), 40)
                    )
                else:
                    values.append(
                        ev.values(configure(an, {**inputs, name: exact(v0 + step)}, level), 40)
                    )
            plus, minus = values
            out[kind, name] = {
                p: tuple(
                    tuple((plus[p][k][c] - minus[p][k][c]) / (2 * h) for c in range(2))
                    for k in (1, 0)
                )
                for p in plus
            }
    return out


def rel(got, want) -> float:
    """|got - want| / |want| for 2-vectors (absolute when want is 0)."""
    with mpmath.workdps(40):
        diff = mpmath.sqrt(sum((mpmath.mpf(g) - w) ** 2 for g, w in zip(got, want)))
        size = mpmath.sqrt(sum(w**2 for w in want))
        return float(diff / size) if size else float(diff)


_COMPILED: dict[str, symkin.studies.compiled.Compiled] = {}


def compiled(key: str):
    if key not in _COMPILED:
        # the levels this file checks (`loaded`'s sensitivities: test_loaded_sensitivity)
        _COMPILED[key] = symkin.compile(analysis(key), levels=CASES[key][2])
    return _COMPILED[key]


@pytest.mark.parametrize("key,level", [(k, lv) for k, (_, _, lvs) in CASES.items() for lv in lvs])
def test_every_backend_against_central_differences(key, level):
    an = analysis(key)
    inputs = CASES[key][1]
    want = central(an, inputs, level)
    mp = evaluate(an, inputs, level, sensitivity=True).sensitivity
    x = np.array([[float(inputs[h]) for h in an.mechanism.inputs]])
    ev = compiled(key)
    require_compiler()
    c_status, _, c_dev, c_rig = ev.sensitivity_rows(x, level)
    assert c_status[0] == 0
    py = ev.module.sensitivity_full({h: x[0, j] for j, h in enumerate(ev.inputs)}, level)
    names = [p.name for p in an.mechanism.parameters]
    worst = {"mpmath": 0.0, "c": 0.0, "numpy": 0.0}
    for (kind, name), per_point in want.items():
        v = names.index(name) if kind == "params" else len(names) + ev.inputs.index(name)
        for i, point in enumerate(ev.points):
            dev_ref, rig_ref = per_point[point]
            table = mp.deviation if kind == "params" else mp.deviation_inputs
            rtable = mp.rigid if kind == "params" else mp.rigid_inputs
            checks = {
                "mpmath": ((table[point][name], dev_ref), (rtable[point][name], rig_ref)),
                "c": ((c_dev[0, i, v], dev_ref), (c_rig[0, i, v], rig_ref)),
                "numpy": (
                    (py["deviation"][point][kind][name], dev_ref),
                    (py["rigid"][point][kind][name], rig_ref),
                ),
            }
            for backend, pairs in checks.items():
                for got, ref in pairs:
                    worst[backend] = max(worst[backend], rel(got, ref))
    # mpmath: the derivative at 40 digits, rounded; the generated code: float64 throughout
    assert worst["mpmath"] < 1e-12, worst
    assert worst["c"] < 1e-8 and worst["numpy"] < 1e-8, worst


def test_a_parameter_carries_the_defaults_that_read_it():
    """L2 = 2*l: d/dl is the total derivative (L2 follows l), d/dL2 the partial one, and the
    total is the partial by l with L2 held plus 2 d/dL2 (central differences both ways)."""
    an = analysis("param_four_bar")
    inputs = {"A0": "0.2"}
    sens = evaluate(an, inputs, "exact", sensitivity=True).sensitivity.deviation["C"]
    ev = evaluator_of(an)
    with mpmath.workdps(40):
        l0, h = mpmath.mpf("1e-3"), mpmath.mpf("1e-15")
        held = exact(2 * l0)
        plus = ev.values(configure(an, inputs, "exact", {"l": exact(l0 + h), "L2": held}), 40)["C"][
            1
        ]
        minus = ev.values(configure(an, inputs, "exact", {"l": exact(l0 - h), "L2": held}), 40)[
            "C"
        ][1]
        partial = [(plus[c] - minus[c]) / (2 * h) for c in range(2)]
        combined = [partial[c] + 2 * mpmath.mpf(sens["L2"][c]) for c in range(2)]
    assert rel(sens["l"], combined) < 1e-12
    assert rel(sens["l"], partial) > 1e-3  # the dependence matters here


def test_eval_sensitivity_json_is_the_same_in_every_backend(capsys):
    require_compiler()
    docs = {}
    for backend in BACKENDS:
        code = main(
            [
                "eval",
                str(EXAMPLES / "four_bar.toml"),
                "--input",
                "A0=0.2",
                "--sensitivity",
                "--json",
                "--backend",
                backend,
            ]
        )
        out = capsys.readouterr().out
        assert code == 0
        import json

        docs[backend] = json.loads(out)
    keys = ("sensitivity", "sensitivity_inputs", "rigid_sensitivity", "rigid_sensitivity_inputs")
    for backend, doc in docs.items():
        assert set(doc["sensitivity"]["C"]) == {"l"}
        assert set(doc["sensitivity_inputs"]["C"]) == {"A0"}
        for key in keys:
            for point, row in doc[key].items():
                for name, pair in row.items():
                    assert (
                        rel(pair, [mpmath.mpf(v) for v in docs["sympy"][key][point][name]]) < 1e-12
                    ), (backend, key, name)


def test_text_output_ranks_the_parameters(capsys):
    code = main(["eval", str(EXAMPLES / "four_bar.toml"), "--input", "A0=0.2", "--sensitivity"])
    out = capsys.readouterr().out
    assert code == 0
    assert "sensitivity of point C" in out and "d|dR|/dv" in out


def test_c_batch_entry_points():
    """The batch calls give, row by row, exactly what one call per row gives; failing rows are
    NaN with their status; the sensitivity's contract layout is the full one's first columns."""
    require_compiler()
    ev = compiled("param_four_bar")
    lib = ev.library
    x = np.array([[0.2], [-0.1], [4.0], [0.0]])  # 4.0 > pi: status 3
    status, out, angles = lib.evaluate_rows(x, None, 2, angles=True)
    for i, row in enumerate(x):
        s, o, a = lib.evaluate(row, None, 2)
        assert s == status[i]
        assert np.array_equal(np.array(o), out[i], equal_nan=True)
        assert np.array_equal(np.array(a), angles[i], equal_nan=True)
    assert list(status) == [0, 0, 3, 0]
    assert np.isnan(out[2]).all() and np.isfinite(out[[0, 1, 3]]).all()
    failed = lib.batch(
        len(x), x.ctypes.data_as(lib_ptr()), None, 2, out.ctypes.data_as(lib_ptr()), None, None
    )
    assert failed == 1
    long_crank = ev.parameters({"ay": 0.08})  # a crank too long to turn beyond ~0.5
    status_far, out_far, _ = lib.evaluate_rows(np.array([[0.2], [1.5]]), long_crank, 2)
    assert list(status_far) == [0, 1] and np.isnan(out_far[1]).all()
    s_status, values, dev, _ = lib.sensitivity_rows(x, None, 2)
    assert list(s_status) == list(status)
    assert np.array_equal(values, out, equal_nan=True)
    import ctypes

    fn = lib.lib.param_four_bar_sensitivity
    fn.argtypes = [lib_ptr(), lib_ptr(), ctypes.c_int, lib_ptr()]
    n_p = len(ev.sources.params)
    small = np.empty(2 * n_p)
    row = np.ascontiguousarray(x[0])
    assert fn(row.ctypes.data_as(lib_ptr()), None, 2, small.ctypes.data_as(lib_ptr())) == 0
    assert np.array_equal(small, dev[0, 0, :n_p].reshape(-1))
    assert fn(row.ctypes.data_as(lib_ptr()), None, 2, None) == 3


def lib_ptr():
    import ctypes

    return ctypes.POINTER(ctypes.c_double)


def test_compile_leaves_no_files_and_pickles_as_its_texts(tmp_path):
    """symkin.compile writes nothing (not even the compile cache); an unpickled copy in a fresh
    process compiles itself and gives the same bits."""
    require_compiler()
    cache, tmp = tmp_path / "cache", tmp_path / "tmp"
    cache.mkdir()
    tmp.mkdir()
    script = f"""
import pickle, sys, numpy as np, symkin
ev = symkin.compile({str(EXAMPLES / "four_bar.toml")!r})
res = ev.evaluate({{"A0": np.linspace(-0.2, 0.2, 7)}})
sens = ev.sensitivity({{"A0": 0.2}})
sys.stdout.buffer.write(pickle.dumps((ev, res["points"]["C"]["deviation"], sens["C"]["l"])))
"""
    env = {**os.environ, "SYMKIN_CACHE": str(cache), "TMPDIR": str(tmp)}
    proc = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, env=env, cwd=ROOT, check=True
    )
    assert list(cache.iterdir()) == [] and list(tmp.iterdir()) == []
    ev, deviation, dl = pickle.loads(proc.stdout)
    again = ev.evaluate({"A0": np.linspace(-0.2, 0.2, 7)})["points"]["C"]["deviation"]
    assert np.array_equal(again, deviation)
    assert np.array_equal(ev.sensitivity({"A0": 0.2})["C"]["l"], dl)
    assert math.isfinite(float(dl[0]))


def test_report_ranks_the_parameters():
    """The LaTeX report's sensitivity table: every parameter once per point, ranked by the size
    of the relative sensitivity, at the input where |ΔR| is largest."""
    import re

    from symkin.studies.derive import generate

    mech = symkin.loads(M.PARAM_FOUR_BAR, "param_four_bar.toml")
    tex = generate(mech, emit=["latex"])["param_four_bar.tex"].decode()
    table = tex[tex.index(r"\label{symkin:param-four-bar:sensitivity}") :]
    table = table[: table.index(r"\bottomrule")]
    rows = re.findall(
        r"^C & (\S+) & .* & \$([+-]\d\.\d{3})\$ & \$([+-]\d\.\d{3})\$ \\\\$", table, re.MULTILINE
    )
    assert sorted(r[0] for r in rows) == sorted(p.name for p in mech.parameters)
    relative = [abs(float(r[1])) for r in rows]
    assert relative == sorted(relative, reverse=True)
    assert len({r[2] for r in rows}) == 1
