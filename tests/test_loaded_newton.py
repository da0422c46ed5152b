"""The reduced equilibrium (symkin.physics.reduced: Newton on the compliant angles and the chord
plates' loads with the closed-form plate relation), the `loaded` level's solver:

- one plate's relation and its elastic energy against the independent shooting solution of
  tests/reference_beams.py (elastica and Reissner), at the accuracy its fourth-order truncation
  allows;
- mechanisms against symkin's `equilibrium` (itself checked against the independent solvers of
  tests/reference_physics.py and tests/reference_beams.py to 1e-10): within 0.1 % (the target is
  1 % with loads up to 80 % of the first buckling factor, 0.1 % for short unloaded plates) on the
  examples and the zoo, a redundant stage included (Reissner plates make it regular), in float64
  (numpy kernels) and mpmath;
- a load past the mechanism's buckling is refused;
- the `loaded` level (sympy backend) against `equilibrium`: deviations, angles, links, the
  hinges' end loads and the energy within 1e-4 on the examples with stiffness data and the zoo,
  a redundant stage with plates of unequal length included; refusals exit 3 naming the reason;
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
from mechanisms import with_beam
from reference_beams import cantilever

import symkin
from symkin.cli.commands import main
from symkin.codegen.backends.c.backend import standalone
from symkin.codegen.plate import SYMBOLS, plate_routine
from symkin.model import special
from symkin.physics import equilibrium as equilibrium_physics
from symkin.physics.plate_relation import energy, relation
from symkin.studies.physical import reduced_equilibrium

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


#: the bounds on the energy's relative error, per case of PLATES (measured 1e-11 .. 8.1e-4)
ENERGY_BOUNDS = [1e-10, 3e-4, 3e-3, 1e-5, 1e-5, 3e-4, 1e-7]


def test_plate_energy_against_shooting():
    """The elastic energy U + p X + f Y from the mixed potential against the shooting solution's
    ∫ m²/(2EI) + N²/(2EA) + Q²/(2κGA) ds, at the relation's truncation order."""
    th, p, f, ea, es = sp.symbols("th p f ea es")
    fn = sp.lambdify(
        (th, p, f, ea, es), energy(th, p, f, ea, es), modules=[special.mpmath_namespace(), "mpmath"]
    )
    for ((fx, fy, m1), eps, gam, _, _), bound in zip(PLATES, ENERGY_BOUNDS, strict=True):
        with mp.workdps(30):
            ref = cantilever(fx, fy, m1, eps=eps, gam=gam, dps=30)
            w = ref["psi"] / 2
            pv = mp.cos(w) * fx + mp.sin(w) * fy
            fv = -mp.sin(w) * fx + mp.cos(w) * fy
            got = fn(ref["psi"], pv, fv, mp.mpf(eps), mp.mpf(gam))
            err = abs(got - ref["energy"]) / ref["energy"]
        assert err < bound, (fx, fy, m1, eps, float(err))


def test_pure_moment_is_the_arc():
    """Without force the plate is the circular arc at any θ: no correction, ω = θ."""
    th = sp.Symbol("th")
    rel = relation(th, sp.S.Zero, sp.S.Zero, sp.Rational(1, 1000), sp.Rational(3, 1000))
    for value in (sp.Rational(1, 50), sp.Rational(3, 2)):
        assert abs(rel.along.subs(th, value).evalf(30)) < 1e-28
        assert abs(rel.across.subs(th, value).evalf(30)) < 1e-28
        assert abs(rel.omega.subs(th, value).evalf(30) - value) < 1e-28
        work = energy(th, sp.S.Zero, sp.S.Zero, sp.Rational(1, 1000), sp.Rational(3, 1000))
        assert abs(work.subs(th, value).evalf(30) - value**2 / 2) < 1e-28


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


def _load_errors(hinges, energy, reference) -> tuple[float, float, float]:
    """The largest force and moment errors over the hinges, relative to the largest force and
    moment `reference` reports, and the energy's relative error; `hinges` by name as
    (force, moment)."""
    forces = max(math.hypot(*h.force) for h in reference.hinges.values())
    moments = max(abs(h.moment) for h in reference.hinges.values())
    df = max(math.dist(hinges[n][0], h.force) for n, h in reference.hinges.items())
    dm = max(abs(hinges[n][1] - h.moment) for n, h in reference.hinges.items())
    return df / forces, dm / moments, abs(energy - reference.energy) / reference.energy


@pytest.mark.parametrize(("path", "inputs"), CASES, ids=[Path(c[0]).stem for c in CASES])
def test_against_equilibrium(path, inputs):
    """Deviations within 0.1 %; the hinges' end loads and the plates' energy (float64 kernels)
    within 1e-4 (measured up to 1.2e-5, the lever amplifier's energy)."""
    an = symkin.analyze(symkin.load(ROOT / path))
    answer = reduced_equilibrium(an, inputs)
    assert not answer.refused, answer.refused
    reference = symkin.evaluate(an, inputs, level="equilibrium")
    assert _worst(answer, reference) < 1e-3
    scale = float(an.mechanism.unit_scale)  # moments and energy in N·u -> N·m, J
    hinges = {n: ((fx, fy), m * scale) for n, (fx, fy, m) in answer.hinge_loads.items()}
    assert max(_load_errors(hinges, answer.energy * scale, reference)) < 1e-4


#: (file, inputs): what the file format allows beyond the cases above: rigid pins off the plates'
#: midpoints (pin = "prbm", three pivots on one four-bar), an input hinge that is a loop's chord
#: (at the ground, and between two moving links with prbm pins beside it).
OWN_CASES = [
    ("tests/mechanisms/prbm_four_bar.toml", {"O1": 0.1}),
    ("tests/mechanisms/prbm_four_bar.toml", {"O1": -0.15}),
    ("tests/mechanisms/five_bar.toml", {"O1": 0.05, "O2": -0.08}),
    ("tests/mechanisms/five_bar_coupler_input.toml", {"O1": 0.05, "P": -0.08}),
]


@pytest.mark.parametrize(
    ("path", "inputs"),
    OWN_CASES,
    ids=[f"{Path(c[0]).stem}-{'-'.join(map(str, c[1].values()))}" for c in OWN_CASES],
)
def test_prbm_pins_and_input_chords(path, inputs):
    """Pins at the prbm pivots and input chords: within 0.1 % of equilibrium in float64 and in
    mpmath, the two backends alike."""
    an = symkin.analyze(symkin.load(ROOT / path))
    st = an.kin.structure
    # the file is the case it is meant to be
    assert any(h.midpoint is not None for h in an.kin.hinges.values()) or any(
        an.kin.hinges[c].is_input for c in range(st.n + 1, st.m + 1)
    )
    reference = symkin.evaluate(an, inputs, level="equilibrium")
    answers = {b: reduced_equilibrium(an, inputs, backend=b) for b in ("numpy", "sympy")}
    for answer in answers.values():
        assert not answer.refused, answer.refused
        assert _worst(answer, reference) < 1e-3
    for name, d in answers["numpy"].deviations.items():
        assert math.dist(d, answers["sympy"].deviations[name]) < 1e-9 * math.hypot(*d)


def test_open_chain(tmp_path):
    """Every hinge an input of an open chain (no unknowns: the plates' loads follow from
    statics), a load at the tip: within 0.1 % of equilibrium in float64 and in mpmath."""
    path = tmp_path / "serial_pair_loaded.toml"
    text = (ROOT / "tests/fea/serial_pair.toml").read_text()
    path.write_text(text + '\n[[load]]\npoint = "T"\nforce = [20.0, -40.0]\nmoment = 0.5\n')
    an = symkin.analyze(symkin.load(path))
    inputs = {"S": 0.2, "E": -0.3}
    reference = symkin.evaluate(an, inputs, level="equilibrium")
    for backend in ("numpy", "sympy"):
        answer = reduced_equilibrium(an, inputs, backend=backend)
        assert answer.x.size == 0 and not answer.refused, answer.refused
        assert _worst(answer, reference) < 1e-3


def test_prbm_pins_matter(tmp_path):
    """The prbm four-bar's pins off the midpoints move its deviation by far more than the bound
    above: the same plates against midpoint pins are 10 % or more away from its equilibrium."""
    path = ROOT / "tests/mechanisms/prbm_four_bar.toml"
    moved = tmp_path / "prbm_four_bar_midpoint.toml"
    text = path.read_text()
    assert 'pin = "prbm"' in text
    moved.write_text(text.replace('pin = "prbm"', 'pin = "midpoint"'))
    reference = symkin.evaluate(symkin.analyze(symkin.load(path)), {"O1": 0.1}, level="equilibrium")
    midpoint = reduced_equilibrium(symkin.analyze(symkin.load(moved)), {"O1": 0.1})
    assert not midpoint.refused
    assert _worst(midpoint, reference) > 0.1


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


def test_two_half_plates_near_buckling(tmp_path, monkeypatch):
    """Plates pressed to 0.654 π²EI/l² (80 % of the mechanism's first buckling factor): one
    plate relation is refused by its truncation estimate, two chained half plates per plate are
    within 0.1 % of equilibrium in float64 and in mpmath."""
    monkeypatch.setattr(equilibrium_physics, "buckling_factor", lambda *args, **kwargs: None)
    an = symkin.analyze(symkin.load(_loaded_parallelogram(tmp_path, 0.654)))
    inputs = {"F1": 0.05}
    assert reduced_equilibrium(an, inputs, segments=1).refused.startswith("truncation")
    reference = symkin.evaluate(an, inputs, level="equilibrium")
    answers = {b: reduced_equilibrium(an, inputs, backend=b) for b in ("numpy", "sympy")}
    for answer in answers.values():
        assert answer.segments == 2 and not answer.refused, answer.refused
        assert _worst(answer, reference) < 1e-3
    for name, d in answers["numpy"].deviations.items():
        assert math.dist(d, answers["sympy"].deviations[name]) < 1e-9 * math.hypot(*d)


@pytest.mark.parametrize(
    ("path", "inputs"),
    [CASES[0], OWN_CASES[0], OWN_CASES[3]],
    ids=["four_bar", "prbm_four_bar", "five_bar_coupler_input"],
)
def test_two_half_plates_everywhere(path, inputs):
    """Two half plates per plate where one would do: the chain's geometry and joint balance
    agree with equilibrium (3.8e-7, 2.3e-7, 1.5e-6 measured; one plate: 1.5e-6, 9.2e-7, 5.7e-6),
    pins off the midpoints and an input chord included."""
    an = symkin.analyze(symkin.load(ROOT / path))
    answer = reduced_equilibrium(an, inputs, segments=2)
    assert answer.segments == 2 and not answer.refused, answer.refused
    assert _worst(answer, symkin.evaluate(an, inputs, level="equilibrium")) < 1e-4


# -- the `loaded` level: the reduced equilibrium in mpmath, reported as an Evaluation -----------

#: (file, inputs): every example with stiffness data (the piezo amplifier's actuators:
#: tests/test_loaded_actuators.py) and the zoo, its own loads included (the Scott–Russell's
#: preload, the double parallelogram's payload), the redundant stage, prbm pins and input chords.
LEVEL_CASES = [
    ("examples/four_bar.toml", {"A0": 0.3}),
    ("examples/nine_bar_platform.toml", {"O": 0.02, "A": -0.02, "B": 0.01, "K": 0.02}),
    ("examples/stephenson_six_bar.toml", {"O_A": 0.2}),
    ("tests/mechanisms/parallelogram.toml", {"F1": 0.05}),
    ("tests/mechanisms/parallelogram_mm.toml", {"F1": 0.05}),  # moments and energy from N·mm
    ("tests/mechanisms/double_parallelogram.toml", {"F1": 0.05, "I1": -0.05}),
    ("tests/mechanisms/scott_russell.toml", {"RA0": 0.01}),
    ("tests/mechanisms/lever_amplifier.toml", {"P0": 0.0}),
    ("tests/mechanisms/roberts.toml", {"O1": 0.1}),
    ("tests/mechanisms/toggle_four_bar.toml", {"O1": 0.3}),
    ("tests/mechanisms/three_leg_stage.toml", {"F1": 0.05}),
    ("tests/mechanisms/prbm_four_bar.toml", {"O1": 0.1}),
    ("tests/mechanisms/five_bar.toml", {"O1": 0.05, "O2": -0.08}),
    ("tests/mechanisms/five_bar_coupler_input.toml", {"O1": 0.05, "P": -0.08}),
]


def _level_against_equilibrium(an, inputs, bound: float, params=None) -> None:
    """`loaded` (sympy backend) against `equilibrium`: every point's deviation, every hinge's and
    link's angle deviation (relative to the largest), the hinges' end loads and the energy within
    `bound`; the rigid linkage the same; compliant = rigid + deviation; a model error per point."""
    got = symkin.evaluate(an, inputs, level="loaded", params=params)
    ref = symkin.evaluate(an, inputs, level="equilibrium", params=params)
    assert got.level == "loaded" and got.backend == "sympy" and got.params == ref.params
    size = max(math.hypot(*p.rigid) for p in ref.points.values())
    for name, p in ref.points.items():
        mine = got.points[name]
        assert math.dist(mine.rigid, p.rigid) < 1e-12 * size
        assert math.dist(mine.deviation, p.deviation) < bound * math.hypot(*p.deviation), name
        assert (
            math.dist(
                mine.compliant,
                (mine.rigid[0] + mine.deviation[0], mine.rigid[1] + mine.deviation[1]),
            )
            < 1e-15 * size
        )
    assert set(got.model_error) == set(ref.points)
    turns = {n: ref.angles_compliant[n] - ref.angles_rigid[n] for n in ref.angles_rigid}
    largest = max(abs(v) for v in turns.values())
    for name, turn in turns.items():
        assert got.angles_rigid[name] == pytest.approx(ref.angles_rigid[name], abs=1e-14)
        assert abs(got.angles_compliant[name] - got.angles_rigid[name] - turn) < bound * largest
    largest = max(abs(lk.deviation) for lk in ref.links.values())
    for name, link in ref.links.items():
        assert got.links[name].rigid == pytest.approx(link.rigid, abs=1e-14)
        assert abs(got.links[name].deviation - link.deviation) < bound * largest, name
    hinges = {n: (h.force, h.moment) for n, h in got.hinges.items()}
    assert set(hinges) == set(ref.hinges)
    assert max(_load_errors(hinges, got.energy, ref)) < bound


@pytest.mark.parametrize(
    ("path", "inputs"), LEVEL_CASES, ids=[Path(c[0]).stem for c in LEVEL_CASES]
)
def test_loaded_level_against_equilibrium(path, inputs):
    """Within 1e-4 of equilibrium (the target is 1 %; measured 4.2e-7 .. 2.4e-5 for the
    deviations, 1e-10 .. 1.2e-5 for the loads and energy, docs/physics.md)."""
    _level_against_equilibrium(symkin.analyze(symkin.load(ROOT / path)), inputs, 1e-4)


def test_loaded_level_takes_parameter_overrides():
    """--param reaches the reduced equilibrium: the four-bar with plates twice as long (and
    thick) against equilibrium with the same override."""
    an = symkin.analyze(symkin.load(ROOT / "examples/four_bar.toml"))
    _level_against_equilibrium(an, {"A0": 0.1}, 1e-4, params={"l": "2e-3"})
    default = symkin.evaluate(an, {"A0": 0.1}, level="loaded").points["C"].deviation
    longer = symkin.evaluate(an, {"A0": 0.1}, level="loaded", params={"l": "2e-3"})
    assert longer.params["l"] == 2e-3
    assert math.dist(longer.points["C"].deviation, default) > 0.1 * math.hypot(*default)


def test_loaded_level_takes_an_input_written_as_an_expression():
    """An input such as pi/16 is read once, as every level reads it (it was handed to the
    reduced equilibrium as text, which float() could not read): the same deviation as its
    double written out, in mpmath and in the numpy module."""
    an = symkin.analyze(symkin.load(ROOT / "examples/four_bar.toml"))
    for backend in ("sympy", "numpy"):
        written = symkin.evaluate(an, {"A0": "pi/16"}, level="loaded", backend=backend)
        double = symkin.evaluate(an, {"A0": repr(math.pi / 16)}, level="loaded", backend=backend)
        assert written.inputs["A0"] == math.pi / 16
        deviation = written.points["C"].deviation
        assert math.dist(deviation, double.points["C"].deviation) <= 1e-12 * math.hypot(*deviation)


def test_loaded_level_closes_a_redundant_loop_elastically(tmp_path):
    """The three-leg stage with its third leg's plates 1 % longer: no kinematic level can close
    the redundant loop (tests/test_parallelograms.py), the plates' stretch and bending do; within
    1e-4 of equilibrium."""
    text = (ZOO / "three_leg_stage.toml").read_text()
    for old in ('at = ["w/2", 0.0]\n', 'at = ["w/2", "L"]\n'):
        assert text.count(old) == 1
        text = text.replace(old, old + 'length = "1.01*l"\n')
    path = tmp_path / "three_leg_stage_long.toml"
    path.write_text(text)
    _level_against_equilibrium(symkin.analyze(symkin.load(path)), {"F1": 0.05}, 1e-4)


def test_loaded_level_refuses_an_inextensible_redundant_mechanism(tmp_path, capsys):
    """Elastica plates leave the redundant loop's self-stress undetermined: exit 3 at both
    physical levels, as equilibrium refuses it (docs/levels.md)."""
    text = with_beam((ZOO / "three_leg_stage.toml").read_text(), "elastica")
    path = tmp_path / "three_leg_stage_elastica.toml"
    path.write_text(text)
    for level in ("loaded", "equilibrium"):
        assert main(["eval", str(path), "--input", "F1=0.05", "--level", level]) == 3
        assert "inextensible elastica" in capsys.readouterr().err


def test_loaded_level_refuses_past_buckling(tmp_path, capsys):
    """The parallelogram pressed to 0.93 π²EI/l² per plate (past the mechanism's buckling):
    exit 3 naming the reason; at 0.5 it answers (exit 0)."""
    for fraction, code in ((0.5, 0), (0.93, 3)):
        path = str(_loaded_parallelogram(tmp_path, fraction))
        assert main(["eval", path, "--input", "F1=0.05", "--level", "loaded"]) == code
        err = capsys.readouterr().err
        if code:
            assert "loaded level refuses" in err and "buckling" in err, err


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
