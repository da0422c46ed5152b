"""Stability audit of the generated evaluators at the extremes (float64 and float32).

Grids over the input angle (1e-12 .. 1 rad), the plate ratio l/L (1e-9 .. 0.1) and the approach
to a toggle position, against the independent solver. float64: <= 1e-9 relative error of the
deviation everywhere. float32: the error is reported and must stay within the bound docs/numerics.md
documents (1e-4 relative, about 1000 float32 epsilons).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from evaluators import generated, rel_err
from reference_solver import Reference

import symkin
from symkin.codegen import pipeline

ANGLES = ["1e-12", "1e-10", "1e-8", "1e-6", "1e-4", "1e-2", "0.1", "0.3", "0.6", "1.0"]
RATIOS = ["1e-9", "1e-7", "1e-5", "1e-3", "1e-2", "0.1"]
FLOAT32_BOUND = 1e-4


@pytest.mark.parametrize("key, hinge", [("four_bar", "A0"), ("six_bar", "O_A")])
def test_angle_grid_float64(key, hinge):
    g = generated(key)
    ref = Reference(g.mech)
    for angle in ANGLES + ["-" + a for a in ANGLES[::3]]:
        want = ref.deviation({hinge: angle})["points"]
        for backend in (g.run_numpy, g.run_c):
            got = backend({hinge: angle}, "exact")
            for name, dev in got.items():
                assert rel_err(dev, want[name]["deviation"]) <= 1e-9, (key, angle, name)


@pytest.mark.parametrize("key", ["four_bar", "five_bar"])
def test_plate_ratio_grid_float64(key):
    g = generated(key)
    inputs = {"four_bar": {"A0": "0.25"}, "five_bar": {"O1": "0.15", "O2": "-0.1"}}[key]
    length_scale = 0.05  # the links are about 5 cm
    for ratio in RATIOS:
        overrides = {"l": f"{float(ratio) * length_scale:.6e}"}
        want = Reference(g.mech, overrides).deviation(inputs)["points"]
        for backend in (g.run_numpy, g.run_c):
            got = backend(inputs, "exact", overrides)
            for name, dev in got.items():
                assert rel_err(dev, want[name]["deviation"]) <= 1e-9, (key, ratio, name)


def test_approaching_a_toggle_position():
    """Error of the exact level as the margin to the toggle (in input angle) shrinks."""
    from test_codegen import toggle_input

    g = generated("non_grashof")
    limit = toggle_input(g)
    report = []
    for margin in (1e-1, 1e-2, 1e-3, 1e-4, 1e-5):
        inputs = {"A0": repr(limit - margin)}
        want = Reference(g.mech).deviation(inputs)["points"]["C"]["deviation"]
        errs = [rel_err(b(inputs, "exact")["C"], want) for b in (g.run_numpy, g.run_c)]
        report.append((margin, max(errs)))
        assert max(errs) <= 1e-9, (margin, errs)
    # The rounding error grows as the loop Jacobian degenerates, but slowly.
    print("toggle margin -> worst relative error:", report)


@pytest.mark.parametrize("key", ["four_bar", "six_bar", "nine_bar"])
def test_float32_error_is_bounded(key):
    g = generated(key)
    module = pipeline.evaluator(g.plan, "numpy", "f32", "float32")
    inputs = {
        "four_bar": {"A0": ["1e-6", "0.05", "0.2", "0.5"]},
        "six_bar": {"O_A": ["1e-6", "0.05", "0.2", "0.5"]},
        "nine_bar": {
            "O": ["0.05", "0.01"],
            "A": ["0.03", "-0.02"],
            "B": ["-0.02", "0.01"],
            "K": ["0.04", "0.02"],
        },
    }[key]
    n = len(next(iter(inputs.values())))
    res = module.evaluate(
        {k: np.array([float(v) for v in vs]) for k, vs in inputs.items()}, "exact"
    )
    assert res["ok"].all()
    ref = Reference(g.mech)
    worst = 0.0
    for j in range(n):
        want = ref.deviation({k: vs[j] for k, vs in inputs.items()})["points"]
        for name in module.POINTS:
            worst = max(
                worst,
                rel_err(
                    res["points"][name]["deviation"][:, j].astype(float), want[name]["deviation"]
                ),
            )
    assert worst <= FLOAT32_BOUND, worst


#: Inputs from a double's tiny angles down to where |ΔR| ≈ 2.3e-4 θ² (the four-bar's C; the
#: six-bar's points alike) is still a normal double (θ ≈ 1e-152): docs/numerics.md, "Tiny angles".
TINY = ["1e-16", "1e-32", "1e-64", "1e-100", "-1e-120", "1e-150"]


def _every_backend(g, inputs: dict, level: str) -> dict[str, dict]:
    """The deviation of every point from the sympy backend (40 digits), numpy and C."""
    ev = symkin.evaluate(g.analysis, inputs, level, backend="sympy")
    sympy_dev = {n: tuple(float(v) for v in p.deviation) for n, p in ev.points.items()}
    return {"sympy": sympy_dev, "numpy": g.run_numpy(inputs, level), "c": g.run_c(inputs, level)}


@pytest.mark.parametrize("key, hinge", [("four_bar", "A0"), ("six_bar", "O_A")])
def test_tiny_angles_keep_their_relative_accuracy_in_every_backend(key, hinge):
    """Issue: at A0 = 1e-32 numpy and C were 37x too large and at 1e-100 every backend was
    wrong: the rigid start (dyads, continuation) leaves each angle an absolute error near the
    arithmetic's ε, and one polishing step left ε². The polish now runs the relative rule
    (symkin.core.settings, 2). exact: against the independent reference solver, at digits
    enough for the positions' cancellation (2 log10(1/θ) + 40); paper and first_order, which
    the reference does not model: numpy and C against the 40-digit sympy backend, and ΔR/θ²
    the same number at every input (Δz ∝ θ² to the last digit at these angles)."""
    g = generated(key)
    ref = Reference(g.mech)
    runs = {}
    for angle in TINY:
        inputs = {hinge: angle}
        digits = 40 + 2 * round(-math.log10(abs(float(angle))))
        want = ref.deviation(inputs, dps=digits)["points"]
        for backend, got in _every_backend(g, inputs, "exact").items():
            for name, dev in got.items():
                err = rel_err(dev, want[name]["deviation"])
                assert err <= 1e-9, (key, angle, backend, name, err)
        for level in ("paper", "first_order"):
            runs[angle, level] = _every_backend(g, inputs, level)
            for backend, got in runs[angle, level].items():
                for name, dev in got.items():
                    err = rel_err(dev, runs[angle, level]["sympy"][name])
                    assert err <= 1e-9, (key, angle, level, backend, name, err)
    # ΔR ∝ θ^k at these angles: k = 2 for a midpoint model, 1 for a pivot elsewhere (prbm,
    # docs/file-format.md "Which pin?"), read off the first two inputs
    a, b = TINY[0], TINY[1]
    for level in ("paper", "first_order"):
        for name, dev in runs[a, level]["sympy"].items():
            ta, tb = abs(float(a)), abs(float(b))
            size_b = math.hypot(*runs[b, level]["sympy"][name])
            k = round(math.log(size_b / math.hypot(*dev)) / math.log(tb / ta))
            assert k in (1, 2), (level, name, k)
            first = (dev[0] / ta**k, dev[1] / ta**k)
            for angle in TINY:
                t = abs(float(angle))
                for backend, got in runs[angle, level].items():
                    ratio = (got[name][0] / t**k, got[name][1] / t**k)
                    if float(angle) < 0 and k == 1:
                        ratio = (-ratio[0], -ratio[1])
                    assert rel_err(ratio, first) <= 1e-9, (key, angle, level, backend, name, k)


def test_tiny_angles_at_the_physical_levels():
    """`equilibrium` chose its digits from the float64 solution's deviation, which at a tiny
    input is rounding noise: at A0 = 1e-32 it answered a 6.5e-27 floor. Now, from 1e-16 down to
    1e-100, its deviation and `loaded`'s scale exactly with the input (the plates carry forces:
    a first-order deviation), the two agree to their 1 %, and `loaded` agrees in every backend."""
    g = generated("four_bar")
    first = {}
    for angle in ("1e-16", "1e-32", "1e-100"):
        theta = float(angle)
        eq = symkin.evaluate(g.analysis, {"A0": angle}, "equilibrium").points["C"].deviation
        runs = _every_backend(g, {"A0": angle}, "loaded")
        for backend, got in runs.items():
            assert rel_err(got["C"], runs["sympy"]["C"]) <= 1e-9, (angle, backend)
        assert rel_err(runs["sympy"]["C"], eq) <= 1e-2, angle
        for level, dev in (("equilibrium", eq), ("loaded", runs["sympy"]["C"])):
            ratio = (dev[0] / theta, dev[1] / theta)
            want = first.setdefault(level, ratio)
            assert rel_err(ratio, want) <= 1e-9, (level, angle)
