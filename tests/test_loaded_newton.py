"""The reduced equilibrium (symkin.physics.reduced: Newton on the compliant angles and the chord
plates' loads with the closed-form plate relation), the level that is to become `loaded`:

- one plate's relation against the independent shooting solution of tests/reference_beams.py
  (elastica and Reissner), at the accuracy its fourth-order truncation allows;
- mechanisms against symkin's `equilibrium` (itself checked against the independent solvers of
  tests/reference_physics.py and tests/reference_beams.py to 1e-10): within 0.1 % (the target is
  1 % with loads up to 80 % of the first buckling factor, 0.1 % for short unloaded plates) on the
  examples and the zoo, a redundant stage included (Reissner plates make it regular), in float64
  (numpy kernels) and mpmath;
- a load past the mechanism's buckling is refused;
- the plate relation's C routine (the per-plate kernel of the generated level to come) against
  mpmath.
"""

from __future__ import annotations

import math
import shutil
import subprocess
from pathlib import Path

import mpmath as mp
import pytest
import sympy as sp
from reference_beams import cantilever

import symkin
from symkin.codegen.backends.c.backend import standalone
from symkin.codegen.plate import SYMBOLS, plate_routine
from symkin.model import special
from symkin.physics import equilibrium as equilibrium_physics
from symkin.physics.plate_relation import relation
from symkin.studies.evaluation import reduced_equilibrium

ROOT = Path(__file__).resolve().parent.parent
ZOO = ROOT / "tests" / "mechanisms"

# -- one plate ----------------------------------------------------------------------------------

#: (f_x, f_y, m1) at M's end in P's plate frame (scaled by l²/EI, l/EI), eps = EI/(EA l²),
#: gam = EI/(κGA l²), and the bounds on the relative error of the end displacement beyond the
#: circular arc and of the end moment (order 4 in θ and f: the error is about the square of
#: the beam-column's, docs/physics.md)
PLATES = [
    ((0.0, 0.01, 0.025), 0, 0, 1e-8, 1e-9),
    ((0.0, 1.0, 0.5), 0, 0, 3e-3, 1e-3),
    ((-5.0, 0.5, 0.3), 0, 0, 3e-3, 3e-3),
    ((-8.0, 0.2, 0.05), 0, 0, 1e-5, 1e-5),
    ((3.0, 1.0, 1.0), 0, 0, 1e-3, 1e-4),
    ((-5.0, 0.5, 0.3), 8.3e-4, 2.6e-3, 3e-4, 1e-3),
    ((0.0, 0.01, 0.025), 8.3e-4, 2.6e-3, 1e-5, 1e-7),
]


def test_plate_relation_against_shooting():
    th, p, f, ea, es = sp.symbols("th p f ea es")
    rel = relation(th, p, f, ea, es)
    fns = [
        sp.lambdify((th, p, f, ea, es), e, modules=[special.mpmath_namespace(), "mpmath"])
        for e in (rel.along, rel.across, rel.omega)
    ]
    for (fx, fy, m1), eps, gam, bound_d, bound_m in PLATES:
        with mp.workdps(30):
            ref = cantilever(fx, fy, m1, eps=eps, gam=gam, dps=30)
            theta = ref["psi"]
            w = theta / 2
            # the force in the mid-frame (P's frame turned by θ/2)
            pv = mp.cos(w) * fx + mp.sin(w) * fy
            fv = -mp.sin(w) * fx + mp.cos(w) * fy
            along, across, omega = (fn(theta, pv, fv, mp.mpf(eps), mp.mpf(gam)) for fn in fns)
            chord = mp.sin(w) / w
            got = (mp.cos(w) * along - mp.sin(w) * across, mp.sin(w) * along + mp.cos(w) * across)
            want = (ref["x"] - mp.cos(w) * chord, ref["y"] - mp.sin(w) * chord)
            err_d = mp.hypot(got[0] - want[0], got[1] - want[1]) / mp.hypot(*want)
            err_m = abs(omega - m1) / abs(m1)
        assert err_d < bound_d, (fx, fy, m1, eps, float(err_d))
        assert err_m < bound_m, (fx, fy, m1, eps, float(err_m))


def test_pure_moment_is_the_arc():
    """Without force the plate is the circular arc at any θ: no correction, ω = θ."""
    th = sp.Symbol("th")
    rel = relation(th, sp.S.Zero, sp.S.Zero, sp.Rational(1, 1000), sp.Rational(3, 1000))
    for value in (sp.Rational(1, 50), sp.Rational(3, 2)):
        assert abs(rel.along.subs(th, value).evalf(30)) < 1e-28
        assert abs(rel.across.subs(th, value).evalf(30)) < 1e-28
        assert abs(rel.omega.subs(th, value).evalf(30) - value) < 1e-28


# -- mechanisms against the equilibrium level ---------------------------------------------------


def _loaded_parallelogram(tmp: Path, fraction: float) -> Path:
    """The parallelogram with a dead load pressing the stage down, `fraction` times the force
    that puts each plate at its Euler load π²EI/l² (E' = E/(1 - ν²): a wide plate)."""
    ei = 210e9 / (1 - 0.3**2) * 10e-3 * (0.15e-3) ** 3 / 12
    force = 2 * fraction * math.pi**2 * ei / 5e-3**2
    text = (ZOO / "parallelogram.toml").read_text()
    text += f'\n[[load]]\nlink = "stage"\nat = ["w/2", "L"]\nforce = [0.0, {-force!r}]\n'
    path = tmp / f"parallelogram_load_{fraction}.toml"
    path.write_text(text)
    return path


#: (file, inputs): the examples and the zoo at their own loads and parameters.
CASES = [
    ("examples/four_bar.toml", {"A0": 0.1}),
    ("tests/mechanisms/parallelogram.toml", {"F1": 0.05}),
    ("tests/mechanisms/double_parallelogram.toml", {"F1": 0.05, "I1": -0.05}),
    ("tests/mechanisms/scott_russell.toml", {"RA0": 0.01}),
    ("tests/mechanisms/lever_amplifier.toml", {"P0": 0.0}),
    ("tests/mechanisms/roberts.toml", {"O1": 0.1}),
    ("tests/mechanisms/toggle_four_bar.toml", {"O1": 0.3}),
    ("tests/mechanisms/three_leg_stage.toml", {"F1": 0.05}),
]


def _worst(answer, reference) -> float:
    return max(
        math.dist(answer.deviations[n], p.deviation) / math.hypot(*p.deviation)
        for n, p in reference.points.items()
    )


@pytest.mark.parametrize(("path", "inputs"), CASES, ids=[Path(c[0]).stem for c in CASES])
def test_against_equilibrium(path, inputs):
    an = symkin.analyze(symkin.load(ROOT / path))
    answer = reduced_equilibrium(an, inputs)
    assert not answer.refused, answer.refused
    reference = symkin.evaluate(an, inputs, level="equilibrium")
    assert _worst(answer, reference) < 1e-3


def test_sympy_backend_agrees():
    """mpmath and float64 kernels give the same solution; both within 0.1 % of equilibrium."""
    an = symkin.analyze(symkin.load(ROOT / "examples/four_bar.toml"))
    inputs = {"A0": 0.3}
    a64 = reduced_equilibrium(an, inputs, backend="numpy")
    amp = reduced_equilibrium(an, inputs, backend="sympy")
    for name, d in a64.deviations.items():
        assert math.dist(d, amp.deviations[name]) < 1e-9 * math.hypot(*d)
    assert _worst(amp, symkin.evaluate(an, inputs, level="equilibrium")) < 1e-3


def test_compressed_plates(tmp_path, monkeypatch):
    """Plates pressed to half their Euler load (about 60 % of the mechanism's first buckling
    factor): within 0.1 % of equilibrium; at 93 % (beyond the mechanism's buckling) refused."""
    # only equilibrium's deviations are compared: its buckling-factor search, which it runs
    # after solving (and which can stop short this close to the plates' Euler load), is left out
    monkeypatch.setattr(equilibrium_physics, "buckling_factor", lambda *args, **kwargs: None)
    an = symkin.analyze(symkin.load(_loaded_parallelogram(tmp_path, 0.5)))
    answer = reduced_equilibrium(an, {"F1": 0.05})
    assert not answer.refused and 0.4 < answer.p_over_pcr < 0.6
    assert _worst(answer, symkin.evaluate(an, {"F1": 0.05}, level="equilibrium")) < 1e-3
    beyond = symkin.analyze(symkin.load(_loaded_parallelogram(tmp_path, 0.93)))
    assert reduced_equilibrium(beyond, {"F1": 0.05}).refused


# -- the plate relation in generated C ----------------------------------------------------------

#: (θ, p, f, ε_a, ε_s): both sides of the kernels' series threshold |p| = 2, tension and
#: compression, tiny and large rotations
PLATE_POINTS = [
    (0.02, 0.0, 0.01, 0.0, 0.0),
    (0.3, -5.0, 0.5, 0.0, 0.0),
    (1.0, -8.0, 0.2, 8.3e-4, 2.6e-3),
    (0.5, 7.0, 1.0, 0.0, 0.0),
    (-0.1, 1.0, -0.3, 1e-4, 3e-4),
    (1e-9, 1e-8, 1e-9, 0.0, 0.0),
    (0.05, 30.0, 2.0, 0.0, 0.0),
]


def _run_plate_routine(tmp_path: Path, points: list[tuple]) -> list[float]:
    """The C routine's 12 outputs at each point, compiled as strictly as the runtime's code."""
    cc = shutil.which("cc") or shutil.which("gcc")
    assert cc, "no C compiler"
    rows = ",".join("{" + ", ".join(repr(v) for v in pt) + "}" for pt in points)
    src = tmp_path / "plate.c"
    src.write_text(
        "#include <math.h>\n#include <stdio.h>\n"
        + standalone(plate_routine(4))
        + "int main(void)\n{\n    static const double pts[][5] = {"
        + rows
        + "};\n    double out[12];\n    int i, k;\n"
        + f"    for (i = 0; i < {len(points)}; ++i) {{\n"
        + "        sk_plate_relation4(pts[i], out);\n"
        + '        for (k = 0; k < 12; ++k) printf("%.17g\\n", out[k]);\n    }\n'
        + "    return 0;\n}\n"
    )
    exe = tmp_path / "plate"
    flags = ["-std=c99", "-pedantic", "-Wall", "-Wextra", "-Werror", "-O2"]
    subprocess.run([cc, *flags, str(src), "-o", str(exe), "-lm"], check=True)
    run = subprocess.run([str(exe)], check=True, capture_output=True, text=True)
    return [float(v) for v in run.stdout.split()]


#: A dense grid of (θ, p, f) and both plate theories: p at and around 0, on both sides of the
#: kernels' switches to the closed form (p = -4, 16, and the old |p| = 2), up to 0.1 % short of
#: the buckling load -π² and far in tension
DENSE_THETA = [1e-6, 0.05, 0.4, -1.2]
DENSE_P = [0.0, 1e-9, -1e-9, 1e-4, -1e-4, 0.3, -1.0, 1.99, 2.01, -1.99, -2.01, -3.99, -4.0]
DENSE_P += [-4.01, 15.99, 16.0, 16.01, -7.0, -9.0, -9.8, -9.86, 30.0, 60.0, 200.0]
DENSE_F = [0.01, -0.7, 2.0]
DENSE_EPS = [(0.0, 0.0), (8.3e-4, 2.6e-3)]


def test_plate_routine_in_c_dense(tmp_path):
    """The C routine on the dense grid against its 12 expressions evaluated by mpmath at 30
    digits (the kernels' mpmath implementation): each output within 1e-14 of itself plus 1 % of
    the point's largest output (the outputs are sums whose terms cancel), times pi^2/(p + pi^2)
    near the buckling load, where T(p) = tan(v)/v is that ill-conditioned in p. (The Taylor
    series the kernels had on |p| < 2 missed this by 4x at p = 2.01.)"""
    rel = relation(*SYMBOLS)
    values = [rel.along, rel.across, rel.omega]
    exprs = values + [sp.diff(v, w) for v in values for w in SYMBOLS[:3]]
    fn = sp.lambdify(SYMBOLS, exprs, modules=[special.mpmath_namespace(), "mpmath"], cse=True)
    points = [
        (th, p, f, ea, es)
        for th in DENSE_THETA
        for p in DENSE_P
        for f in DENSE_F
        for ea, es in DENSE_EPS
        if (1 + (ea - es) * p) * p > -9.865  # the plate's own index p̃ inside the domain
    ]
    out = iter(_run_plate_routine(tmp_path, points))
    worst = 0.0
    for pt in points:
        with mp.workdps(30):
            want = fn(*[mp.mpf(v) for v in pt])
        pt_tilde = (1 + (pt[3] - pt[4]) * pt[1]) * pt[1]
        condition = max(1.0, math.pi**2 / (pt_tilde + math.pi**2))
        largest = max(abs(w) for w in want)
        for k, w in enumerate(want):
            got = next(out)
            err = float(abs(got - w) / ((abs(w) + 1e-2 * largest) * condition))
            worst = max(worst, err)
            assert err <= 1e-14, (pt, k, got, float(w))
    assert worst > 0  # the comparison is not vacuous


def test_plate_routine_identities():
    """The kernels the plate routine writes through others (symkin.codegen.plate._identities), in
    mpmath at 30 digits: exact, and the sums' terms add to at most 12 (E3' = e3c - 1/1920 over
    p in [-9.5, 60]) and 1.8 (the sinr/cosr recurrences over x = theta/2 in (0, 5]) times the
    result."""
    sinr, cosr = special.sinr, special.cosr
    sinr(5), cosr(5)  # created on demand: registered before the namespace is taken
    ns = special.mpmath_namespace()
    with mp.workdps(30):
        for p in [mp.mpf(k) / 8 for k in range(-76, 481)]:
            w = ns["bcol_w"](p)
            assert abs(ns["bcol_s_d1"](p) + 2 * w) <= 1e-27 * abs(w)
            a = p * w * ns["bcol_invt"](p) ** 2 / 3
            assert abs(ns["bcol_a"](p) - a) <= 1e-27 * abs(a)
            e3c, e3d1 = ns["bcol_e3c"](p), ns["bcol_e3_d1"](p)
            assert abs(e3d1 - (e3c - mp.mpf(1) / 1920)) <= 1e-27 * abs(e3d1)
            assert abs(e3c) + mp.mpf(1) / 1920 <= 12 * abs(e3d1)
        c9, c7, c8 = (mp.mpf(1) / math.factorial(n) for n in (9, 7, 8))
        for x in [mp.mpf(k) / 64 for k in range(1, 321)]:
            x2 = x * x
            for head, constant, tail in (
                (sinr(4), c9, sinr(5)),
                (sinr(3), -c7, sinr(4)),
                (cosr(4), c8, cosr(5)),
            ):
                want, rest = ns[head.__name__](x), x2 * ns[tail.__name__](x)
                assert abs(want - (constant + rest)) <= 1e-27 * abs(want)
                assert abs(constant) + abs(rest) <= 1.8 * abs(want)


def test_plate_routine_in_c(tmp_path):
    """The C routine of the plate relation (CSE'd, the kernels' float source) against the
    relation in mpmath at 30 digits, its partials by mpmath.diff: within 1e-12 of the largest
    output."""
    rel = relation(*SYMBOLS)
    fns = [
        sp.lambdify(SYMBOLS, e, modules=[special.mpmath_namespace(), "mpmath"])
        for e in (rel.along, rel.across, rel.omega)
    ]
    out = iter(_run_plate_routine(tmp_path, PLATE_POINTS))
    for pt in PLATE_POINTS:
        with mp.workdps(30):
            x = [mp.mpf(v) for v in pt]
            want = [fn(*x) for fn in fns]
            for fn in fns:
                for k in range(3):
                    want.append(mp.diff(lambda v, fn=fn, k=k: fn(*x[:k], v, *x[k + 1 :]), x[k]))
        scale = max(abs(w) for w in want)
        for k, w in enumerate(want):
            got = next(out)
            assert abs(got - w) <= 1e-12 * scale, (pt, k, got, float(w))
