"""The beam-column kernels of the axial load index (symkin.model.special.axial) against their
defining formulas typed here independently and evaluated by mpmath at 150 digits (derivatives by
mpmath.diff of those formulas): the mpmath implementation to 1e-45, the float64 algorithm (numpy,
scalar Python and C) to 1e-11 over p in [-9.5, 60], both sides of the series threshold."""

from __future__ import annotations

import math
import shutil
import subprocess

import mpmath as mp
import numpy as np
import pytest
import sympy as sp

from symkin.codegen.backends.c import kernels as c_kernels
from symkin.codegen.backends.numpy import kernels as np_kernels
from symkin.model import special
from symkin.model.special import axial

PS = [-9.5, -7.0, -3.0, -2.0000001, -1.9999999, -0.7, -0.01, 1e-5, 0.3, 1.9999999, 2.0000001]
PS += [4.0, 12.0, 30.0, 60.0]


def _t(p):
    if p > 0:
        u = mp.sqrt(p) / 2
        return mp.tanh(u) / u
    v = mp.sqrt(-p) / 2
    return mp.tan(v) / v


def _s(p):
    return (1 - _t(p)) / p


def _w(p):
    return (12 * _s(p) - _t(p) ** 2) / (16 * p)


def _e1(p):
    t = _t(p)
    return (t**4 * p**2 - 4 * t**3 * p + 8 * t**2 * p + 48 * t - 48) / (512 * t**2 * p**2)


def _e2(p):
    t = _t(p)
    return -(t**4 * p**2 - 4 * t**3 * p + 24 * t**2 * p + 240 * t - 240) / (1024 * p**3)


def _e3(p):
    t = _t(p)
    return -(3 * t**4 * p**2 + 20 * t**3 * p - 24 * t**2 * p - 48 * t + 48) / (3072 * t**4 * p)


DEFINITIONS = {
    "invt": lambda p: 1 / _t(p),
    "s": _s,
    "w": _w,
    "a": lambda p: p * _w(p) / (3 * _t(p) ** 2),
    "e1": _e1,
    "e2": _e2,
    "e3": _e3,
    "e3c": lambda p: mp.diff(_e3, p) + mp.mpf(1) / 1920,
}

NAMES = [(b, o) for b in DEFINITIONS for o in range(3)]


def reference(base: str, order: int, p: float):
    """The kernel's value at the double p, from the definition at 150 digits."""
    with mp.workdps(150):
        x = mp.mpf(p)
        f = DEFINITIONS[base]
        return mp.diff(f, x, order) if order else f(x)


@pytest.fixture(scope="module")
def references():
    return {(b, o): [reference(b, o, p) for p in PS] for b, o in NAMES}


def test_series_at_zero_is_the_beam_constraint_model():
    """Values at p = 0 and first coefficients: the clamped-guided plate's compliance 1/12 and
    the series S = 1/12 - p/120 + 17 p^2/20160 (the inverse of 12 + 6p/5 - p^2/700)."""
    s = axial.kernel("s")
    assert [s.coeff(k) for k in range(3)] == [
        sp.Rational(1, 12),
        sp.Rational(-1, 120),
        sp.Rational(17, 20160),
    ]
    inverse = sp.series(1 / (12 + sp.Rational(6, 5) * axial.P - axial.P**2 / 700), axial.P, 0, 3)
    assert sp.expand(inverse.removeO() - sum(s.coeff(k) * axial.P**k for k in range(3))) == 0
    assert axial.kernel("w")(sp.S.Zero) == sp.Rational(1, 240)
    assert axial.kernel("e3")(sp.S.Zero) == 0
    assert axial.kernel("e3", 1)(sp.S.Zero) == sp.Rational(-1, 1920)


def test_derivatives_stay_in_the_family():
    p = sp.Symbol("p")
    for base in DEFINITIONS:
        f = axial.kernel(base)(p)
        assert sp.diff(f, p) == axial.kernel(base, 1)(p)
        assert sp.diff(f, p, 2) == axial.kernel(base, 2)(p)
    assert special.used_names(axial.kernel("e1", 1)(p)) == ["bcol_e1_d1"]


def test_mpmath_implementation_at_50_digits(references):
    ns = special.mpmath_namespace()
    for (base, order), refs in references.items():
        name = axial.kernel(base, order).__name__
        for p, want in zip(PS, refs):
            with mp.workdps(50):
                got = ns[name](mp.mpf(p))
            assert abs(got - want) <= mp.mpf(10) ** -45 * abs(want), (name, p)
    # sympy's evalf goes through the same implementation
    got = axial.kernel("e2", 1)(sp.Float(0.3, 50)).evalf(50)
    assert abs(got - sp.Float(references["e2", 1][PS.index(0.3)], 50)) < 1e-50


def test_float_algorithms(references):
    """numpy (vectorised), scalar Python: within 1e-11 of the 150-digit values; NaN or
    DomainError at and beyond the buckling load p = -pi^2."""
    vec, f64 = np_kernels.numpy_namespace(), np_kernels.float64_namespace()
    worst = 0.0
    for (base, order), refs in references.items():
        name = axial.kernel(base, order).__name__
        values = vec[name](np.array(PS))
        for p, want, v in zip(PS, refs, values):
            for got in (v, f64[name](p)):
                err = float(abs(mp.mpf(float(got)) - want) / abs(want))
                worst = max(worst, err)
                assert err < 1e-11, (name, p, err)
        assert np.isnan(vec[name](np.array([-(math.pi**2), -12.0]))).all()
        with pytest.raises(special.DomainError):
            f64[name](-10.0)
    assert worst > 0  # the comparison is not vacuous


def test_c_source_agrees(tmp_path, references):
    cc = shutil.which("cc") or shutil.which("gcc")
    assert cc, "no C compiler"
    names = [axial.kernel(b, o).__name__ for b, o in NAMES]
    calls = "\n".join(
        f'    for (i = 0; i < n; ++i) printf("%.17g\\n", symkin_{n}(ps[i]));' for n in names
    )
    src = tmp_path / "bcol.c"
    src.write_text(
        "#include <math.h>\n#include <stdio.h>\n"
        + c_kernels.support(names)
        + "\nint main(void)\n{\n    static const double ps[] = {"
        + ", ".join(repr(p) for p in PS + [-10.0])
        + "};\n    const int n = "
        + str(len(PS) + 1)
        + ";\n    int i;\n"
        + calls
        + "\n    return 0;\n}\n"
    )
    exe = tmp_path / "bcol"
    flags = ["-std=c99", "-pedantic", "-Wall", "-Wextra", "-Werror", "-O2"]
    subprocess.run([cc, *flags, str(src), "-o", str(exe), "-lm"], check=True)
    out = iter(
        subprocess.run([str(exe)], check=True, capture_output=True, text=True).stdout.split()
    )
    for b, o in NAMES:
        for want in references[b, o]:
            got = float(next(out))
            assert abs(mp.mpf(got) - want) < 1e-11 * abs(want), (b, o)
        assert math.isnan(float(next(out)))


#: A dense grid over [-9.5, 60] and beyond: around 0, both sides of the float algorithm's switches
#: (p = -4, 16: the economised polynomials against the closed and far forms) to the last double
DENSE = [float(x) for x in np.linspace(-9.5, 60.0, 277)]
DENSE += [0.0, 1e-12, -1e-12, 1e-6, -1e-6, 2.0, -2.0, 100.0, 300.0, 1000.0, 1e4]
for _edge in (axial.NEAR_LOW, axial.NEAR_HIGH):
    DENSE += [_edge, math.nextafter(_edge, -math.inf), math.nextafter(_edge, math.inf)]


def _dense_bound(p: float) -> float:
    """The relative error allowed the float algorithm: 2e-14, times 1/(p + pi^2) near the
    buckling load, where T = tan(v)/v is that ill-conditioned in p."""
    return 2e-14 * max(1.0, 1 / (p + math.pi**2))


def test_float_algorithms_on_a_dense_grid(tmp_path):
    """numpy, scalar Python and C against the mpmath implementation at 30 digits (itself checked
    against the definitions above) on the dense grid, within _dense_bound; a zero (p = 0 of a, e3,
    e3c) exactly. (The closed forms in p and T the kernels had beyond |p| = 2 lost 6e-12 at
    p = 2, and e3c'' 4e-12 at p = 60.)"""
    vec, f64 = np_kernels.numpy_namespace(), np_kernels.float64_namespace()
    mpns = special.mpmath_namespace()
    names = [axial.kernel(b, o).__name__ for b, o in NAMES]
    cc = shutil.which("cc") or shutil.which("gcc")
    assert cc, "no C compiler"
    src = tmp_path / "dense.c"
    src.write_text(
        "#include <math.h>\n#include <stdio.h>\n"
        + c_kernels.support(names)
        + "\nint main(void)\n{\n    static const double ps[] = {"
        + ", ".join(repr(p) for p in DENSE)
        + f"}};\n    int i;\n    for (i = 0; i < {len(DENSE)}; ++i) {{\n"
        + "".join(f'        printf("%.17g\\n", symkin_{n}(ps[i]));\n' for n in names)
        + "    }\n    return 0;\n}\n"
    )
    exe = tmp_path / "dense"
    flags = ["-std=c99", "-pedantic", "-Wall", "-Wextra", "-Werror", "-O2"]
    subprocess.run([cc, *flags, str(src), "-o", str(exe), "-lm"], check=True)
    run = subprocess.run([str(exe)], check=True, capture_output=True, text=True)
    c_out = iter(float(v) for v in run.stdout.split())
    vectors = {n: vec[n](np.array(DENSE)) for n in names}
    worst = 0.0
    for i, p in enumerate(DENSE):
        for n in names:
            with mp.workdps(30):
                want = mpns[n](mp.mpf(p))
            got = [float(vectors[n][i]), f64[n](p), next(c_out)]
            if want == 0:
                assert got == [0.0, 0.0, 0.0], (n, p, got)
                continue
            for g in got:
                err = float(abs(mp.mpf(g) - want) / abs(want))
                worst = max(worst, err)
                assert err <= _dense_bound(p), (n, p, g, err)
    assert worst > 0  # the comparison is not vacuous
