"""A notch's keys as parameters (docs/file-format.md, "Notch hinges"; symkin.model.notch_series):
the pure-moment coefficients ĉ_k as expressions of the shape ratios (the fit in log(t/R)) against
a nested mpmath quadrature written here, the fit's range refused (NaN in floats, exit 2 in the
CLI), the deviation of a notch lever with parameters R and t against the same lever with those
numbers, and `tolerance` and `equilibrium` on that file.

The reference: Ψ̃(x) = ∫₀ˣ T⁻³ / (2 ∫₀^{h} T⁻³) over the half span h from the hinge centre, and
ĉ_k = (1/h) ∫₀^h (Ψ̃^{2k} − 4^{−k}) dx by mpmath.quad at DPS digits, the intervals cut at
multiples of the neck's width √(t R); T(x) by the formulas of docs/file-format.md."""

from __future__ import annotations

import itertools
import math
from pathlib import Path

import mpmath
import numpy as np
import pytest
import sympy as sp
from evaluators import require_compiler

import symkin
from symkin.cli.commands import main
from symkin.model import notch_series, notches

DPS = 45
TERMS = notch_series.TERMS
MECHANISMS = Path(__file__).parent / "mechanisms"
PARAMETRIC = MECHANISMS / "notch_lever_params.toml"
t, R, c, a, r, l = sp.symbols("t R c a r l", positive=True)


def reference(depth, half, neck, middle=0):
    """ĉ_1..ĉ_TERMS of a symmetric profile T(x) = depth(x), 0 ≤ x ≤ half, by nested quadrature;
    `neck` the width the cuts scale with, `middle` a break of the profile (a fillet's start)."""
    with mpmath.workdps(DPS + 10):
        half, neck, middle = (mpmath.mpf(v) for v in (half, neck, middle))
        cuts = {mpmath.mpf(0), half, middle}
        for j in range(-3, 40):
            for base in (0, middle):
                p = base + neck * mpmath.mpf(2) ** j
                if p < half:
                    cuts.add(p)
        cuts = sorted(cuts)
        parts = [mpmath.quad(lambda x: depth(x) ** -3, [p, q]) for p, q in itertools.pairwise(cuts)]
        total = 2 * mpmath.fsum(parts)
        sums = [mpmath.mpf(0)] * TERMS
        for i, (p, q) in enumerate(itertools.pairwise(cuts)):
            before = mpmath.fsum(parts[:i])
            psi = {}

            def at(x, p=p, before=before, psi=psi):
                if x not in psi:
                    psi[x] = (before + mpmath.quad(lambda y: depth(y) ** -3, [p, x])) / total
                return psi[x]

            for k in range(1, TERMS + 1):
                sums[k - 1] += mpmath.quad(
                    lambda x, k=k: at(x) ** (2 * k) - mpmath.mpf(4) ** -k, [p, q]
                )
        return [s / half for s in sums]


def found(exprs, values):
    """The expressions at `values` (sympy Floats at DPS digits), as mpmath numbers."""
    sub = {k: sp.Float(v, DPS) for k, v in values.items()}
    with mpmath.workdps(DPS):
        return [mpmath.mpf(sp.N(e.xreplace(sub), DPS)) for e in exprs]


def circular_section(thickness, radius):
    nan = sp.nan
    return notches.CircularNotch("A", 2 * radius, thickness, nan, nan, nan, 1, radius=radius)


def relative(got, ref):
    return [abs(g / e - 1) for g, e in zip(got, ref)]


@pytest.mark.parametrize("tau", ["0.005", "0.0137", "0.1", "0.61", "2"])
def test_circular_coefficients_against_nested_quadrature(tau):
    """ĉ_k of a circular notch with t and R parameters (the fit in log(t/R)) at its range's ends
    and between the fit's points: ĉ_1..ĉ_3 to 2e-15 relative, ĉ_4..ĉ_6 to 1e-11, and every later
    term's error, weighted by θ^{2k}/(2k)! at θ = π, below 1e-16 of the first term."""
    exprs = notch_series.coefficient_expressions(circular_section(t, R), TERMS)
    assert all(e.free_symbols == {t, R} for e in exprs)
    tau_mp = mpmath.mpf(tau)
    ref = reference(lambda x: tau_mp + 2 * (1 - mpmath.sqrt(1 - x * x)), 1, mpmath.sqrt(tau_mp))
    err = relative(found(exprs, {t: tau, R: 1}), ref)
    assert max(err[:3]) < 2e-15 and max(err[3:6]) < 1e-11, err
    # every later term's error in D(θ) at θ = π below 1e-16 of the first term
    first = abs(ref[0]) * mpmath.pi**2 / 2
    for k, (e, c_k) in enumerate(zip(err, ref), start=1):
        assert (
            k < 4 or e * abs(c_k) * mpmath.pi ** (2 * k) / mpmath.factorial(2 * k) < 1e-16 * first
        ), k
    # the ratio only: R = 3, t = 3τ gives the same numbers
    again = found(exprs[:3], {t: str(3 * float(tau)), R: 3})
    assert max(relative(again, ref[:3])) < 2e-15


def test_fit_range_is_refused_outside():
    """Outside the fitted range the expression is NaN in floating point (the generated code):
    the fit never extrapolates; inside it, a number."""
    expr = notch_series.coefficient_expressions(circular_section(t, R), 1)[0]
    f = sp.lambdify((t, R), expr, "numpy")
    with np.errstate(invalid="ignore"):
        assert np.isnan(f(np.float64(0.003), 1.0)) and np.isnan(f(np.float64(2.6), 1.0))
        assert np.isnan(f(np.float64(-0.1), 1.0)) and np.isfinite(f(np.float64(0.1), 1.0))
    assert notch_series.check_ratio(circular_section(t, R), {t: 0.001, R: 1}) is not None
    assert notch_series.check_ratio(circular_section(t, R), {t: 0.1, R: 1}) is None


@pytest.mark.parametrize(
    ("param", "says"),
    [("t=-0.1", "thickness must be positive"), ("t=0.001", "thickness/radius = 0.001"),
     ("t=0.0049", "thickness/radius = 0.0049"), ("R=-1", "must be positive")],
)  # fmt: skip
def test_cli_refuses_invalid_keys(param, says, capsys):
    """A non-positive key or a ratio outside the fit's range: exit 2, naming the hinge and key."""
    code = main(["eval", str(PARAMETRIC), "--input", "piezo=0.02", "--level", "exact",
                 "--param", param])  # fmt: skip
    err = capsys.readouterr().err
    assert code == 2, err
    assert says in err and "[[hinge]] 'O'" in err, err


def test_elliptical_and_corner_filleted_coefficients():
    """The elliptical notch (a ≠ c: its ratio is t/c) and the corner-filleted one (a uniform
    middle between two circular flanks: t/r and r/l) against the same nested quadrature."""
    section = notches.EllipticalNotch(
        "B", 2 * a, t, sp.nan, sp.nan, sp.nan, 1, semi_axis=a, depth_c=c
    )
    exprs = notch_series.coefficient_expressions(section, TERMS)
    T = lambda x: mpmath.mpf("0.05") + 2 * mpmath.mpf("0.7") * (1 - mpmath.sqrt(1 - (x / 2) ** 2))  # noqa: E731
    ref = reference(T, 2, mpmath.mpf(2) * mpmath.sqrt(mpmath.mpf("0.05") / mpmath.mpf("0.7")))
    err = relative(found(exprs, {t: "0.05", c: "0.7", a: 2}), ref)
    assert max(err[:3]) < 2e-15 and max(err[:6]) < 1e-11, err

    section = notches.CornerFilleted("C", l, t, sp.nan, sp.nan, sp.nan, 1, fillet=r)
    exprs = notch_series.coefficient_expressions(section, TERMS)
    mid = mpmath.mpf("1.1")  # l/2 − r with l = 3, r = 0.4

    def T(x):
        u = x - mid
        return mpmath.mpf("0.08") + (
            0 if u <= 0 else 2 * (mpmath.mpf("0.4") - mpmath.sqrt(mpmath.mpf("0.16") - u * u))
        )

    ref = reference(T, mpmath.mpf("1.5"), mpmath.sqrt(mpmath.mpf("0.08") * mpmath.mpf("0.4")), mid)
    err = relative(found(exprs, {t: "0.08", r: "0.4", l: 3}), ref)
    assert max(err[:3]) < 2e-15 and max(err[:6]) < 1e-11, err


def test_numbers_keep_the_numeric_coefficients():
    """Keys that one parameter scales (t = R/10) keep the 45-digit numbers of the graded
    quadrature, equal to those of the file's numbers; independent keys give expressions."""
    scaled = notches.coefficients(circular_section(R / 10, R))
    plain = notches.coefficients(circular_section(sp.Float("0.1", 50), sp.Integer(1)))
    assert all(x.is_Number for x in scaled) and scaled == plain
    assert not any(x.is_Number for x in notches.coefficients(circular_section(t, R)))


@pytest.fixture(scope="module")
def lever():
    """The parametric lever and the same lever with its notches' keys as numbers."""
    return symkin.analyze(PARAMETRIC), PARAMETRIC.read_text()


def numbers_file(text: str, tmp_path: Path, thickness: str, radius: str) -> Path:
    """The lever with `radius = ...`, `thickness = ...` as numbers and R, t removed."""
    out = []
    for line in text.splitlines():
        if line.startswith(("R = ", "t = ")):
            continue
        if line.startswith("radius = "):
            line = f"radius = {radius}"
        if line.startswith("thickness = "):
            line = f"thickness = {thickness}"
        out.append(line)
    path = tmp_path / "numbers.toml"
    path.write_text("\n".join(out) + "\n")
    return path


def deviations(ev):
    return [v for _, p in sorted(ev.points.items()) for v in p.deviation]


@pytest.mark.parametrize("values", [("0.1", "1"), ("0.04", "1.5")])
def test_parametric_lever_equals_the_numbers(lever, values, tmp_path):
    """At `exact`, the lever with t and R at values equals the lever with those numbers to
    1e-12 relative (the expression path against the 45-digit numbers)."""
    an, text = lever
    thickness, radius = values
    ev = symkin.evaluate(an, {"piezo": "0.02"}, "exact", params={"t": thickness, "R": radius})
    ref = symkin.evaluate(
        symkin.analyze(numbers_file(text, tmp_path, thickness, radius)), {"piezo": "0.02"}, "exact"
    )
    got, want = deviations(ev), deviations(ref)
    scale = max(abs(v) for v in want)
    assert scale > 1e-7
    assert max(abs(g - w) for g, w in zip(got, want)) <= 1e-12 * scale, (got, want)


def test_tolerance_varies_t_and_r(capsys):
    """`symkin tolerance` on the parametric lever, varying t and R: exit 0, both contribute."""
    require_compiler()
    code = main(
        [
            "tolerance",
            str(PARAMETRIC),
            "--level",
            "exact",
            "--vary",
            "t=±0.005",
            "--vary",
            "R=±1%",
            "--input",
            "piezo=0:0.02:3",
            "--json",
        ]
    )
    out, err = capsys.readouterr()
    assert code == 0, err
    import json

    point = json.loads(out)["points"]["out"]
    assert set(point["contributions"]) == {"t", "R"}
    assert all(math.isfinite(float(v)) for v in _numbers(point["worst_case"]))


def _numbers(value):
    if isinstance(value, (list, tuple)):
        return [x for v in value for x in _numbers(v)]
    if isinstance(value, dict):
        return [x for v in value.values() for x in _numbers(v)]
    return [value]


def test_equilibrium_runs_at_the_parameters(lever, tmp_path):
    """`equilibrium` on the parametric lever at t = 0.1, R = 1 equals the numbers file's."""
    an, text = lever
    ev = symkin.evaluate(an, {"piezo": "0.02"}, "equilibrium")
    ref = symkin.evaluate(
        symkin.analyze(numbers_file(text, tmp_path, "0.1", "1")), {"piezo": "0.02"}, "equilibrium"
    )
    got, want = deviations(ev), deviations(ref)
    scale = max(abs(v) for v in want)
    assert max(abs(g - w) for g, w in zip(got, want)) <= 1e-9 * scale, (got, want)


@pytest.fixture(scope="module")
def numbers_rates(lever, tmp_path_factory):
    """d(deviation)/dt and d/dR of every point (sorted, x then y) by central differences of the
    40-digit `sympy` backend on files with the keys as numbers (that path does not use the fitted
    series), steps h, h/2, h/4 (h = 4 % of the key), Richardson-extrapolated twice (O(h⁶)). The
    values carry ~1e-14 mm of float64 rounding (a deviation is a difference of positions ~50 mm
    from the origin): a step of 1e-5 of the key turns it into 4e-5 (t) and 1e-4 (R) of the
    derivative, which the large steps avoid."""
    _, text = lever
    tmp_path = tmp_path_factory.mktemp("numbers")
    inputs = {"piezo": "0.02"}
    out = {}
    for name, base in (("t", 0.1), ("R", 1.0)):

        def at(value, name=name):
            keys = {"t": "0.1", "R": "1"} | {name: repr(value)}
            path = numbers_file(text, tmp_path, keys["t"], keys["R"])
            return np.array(deviations(symkin.evaluate(symkin.analyze(path), inputs, "exact")))

        h = 0.04 * base
        d = [(at(base + x) - at(base - x)) / (2 * x) for x in (h, h / 2, h / 4)]
        once = [(4 * d[1] - d[0]) / 3, (4 * d[2] - d[1]) / 3]
        out[name] = (16 * once[1] - once[0]) / 15
    return out


@pytest.mark.parametrize("backend", ["numpy", "c"])
def test_sensitivity_to_t_and_r_against_central_differences(lever, numbers_rates, backend):
    """d(deviation)/dt and d/dR of the generated evaluators (the fitted series in log(t/R))
    against the numbers files' Richardson-extrapolated central differences (numbers_rates):
    within 1e-6 relative (measured 8e-8 for t and 3e-8 for R; 1e-6 leaves the fit its share)."""
    if backend == "c":
        require_compiler()
    an, _ = lever
    ev = symkin.evaluate(an, {"piezo": "0.02"}, "exact", backend=backend, sensitivity=True)
    for name, ref in numbers_rates.items():
        got = np.array(
            [v for _, row in sorted(ev.sensitivity.deviation.items()) for v in row[name]]
        )
        scale = float(np.max(np.abs(ref)))
        assert scale > 0
        assert float(np.max(np.abs(got - ref))) <= 1e-6 * scale, (name, got, ref)
