"""What `eval --level loaded` reports beyond the deviations (docs/physics.md, "What loaded
reports"): input moments and stiffness, point stiffness, plate stress, buckling factor, from the
reduced equilibrium.

References, none of them the code under test: the `equilibrium` level (geometrically exact
beams, another solver) on the four-bar example and four zoo mechanisms unlike it; central
differences of the reduced solver's own solutions (a changed input angle, a small load added at
the point and the mechanism solved again); closed forms for a lone plate under a pure moment
(M = E'I θ/l, dM/dθ = E'I/l, σ = E' t θ/(2l)) and for the clamped–guided column (Euler's
π²EI/l², Haringx's for Reissner's plate, tests/mechanisms.py); σ = |N|/A + |M| t/(2I) from the
independent beam solver's end loads (tests/reference_beams.py); the load at which the
`equilibrium` level's stage stiffness vanishes.
"""

from __future__ import annotations

import json
import math

import mechanisms as M
import mpmath
import numpy as np
import pytest
from conftest import EXAMPLES, ROOT
from evaluators import backends_with, require
from reference_beams import BeamEquilibrium
from reference_physics import Load

import symkin
from symkin.cli.commands import main
from symkin.physics import reduced_reported
from symkin.studies.physical import reduced_equilibrium

ZOO = ROOT / "tests" / "mechanisms"
LOAD = '\n[[load]]\npoint = "P"\nforce = [1.5, -4.0]\nmoment = 0.02\n'
E_PRIME, WIDTH, THICK = 210e9 / (1 - 0.3**2), 10e-3, 0.15e-3  # the parallelogram's plates

CASES = {
    "four_bar": (EXAMPLES / "four_bar.toml", "", {"A0": 0.3}),
    "parallelogram": (ZOO / "parallelogram.toml", LOAD, {"F1": 0.05}),
    "scott_russell": (ZOO / "scott_russell.toml", "", {"RA0": 0.02}),
    "double_parallelogram": (ZOO / "double_parallelogram.toml", "", {"F1": 0.01, "I1": -0.01}),
    "lever_amplifier": (ZOO / "lever_amplifier.toml", "", {"P0": 0.01}),
    # an input chord: its actuator's moment is the plate's less the chord's μ
    "five_bar_coupler_input": (ZOO / "five_bar_coupler_input.toml", "", {"O1": 0.02, "P": 0.02}),
}
# Measured agreement with `equilibrium` (the relation's quartic truncation against the exact
# beam; largest over the quantities' entries): input moment and stiffness, plate stress, point
# stiffness (each row against its largest entry).
AGREEMENT = {
    "four_bar": (3e-8, 1e-7, 1e-7, 5e-4),  # measured 9.4e-9, 2.7e-8, 2.8e-8, 2.2e-4
    "parallelogram": (5e-8, 3e-7, 2e-7, 1e-6),  # measured 1.3e-8, 7.3e-8, 3.9e-8, 1.7e-7
    "scott_russell": (1e-5, 3e-5, 3e-5, 1e-4),  # measured 2.4e-6, 8.8e-6, 8.3e-6, 2.9e-5
    "double_parallelogram": (2e-9, 5e-9, 3e-9, 2e-6),  # measured 4.2e-10, 1.3e-9, 6.2e-10, 5.6e-7
    "lever_amplifier": (2e-7, 1e-6, 3e-6, 3e-6),  # measured 3.8e-8, 2.3e-7, 7.5e-7, 6e-7
    "five_bar_coupler_input": (5e-9, 2e-8, 3e-8, 1e-6),  # measured 1.2e-9, 4.5e-9, 8.5e-9, 3.2e-7
}
# The point compliance alike (each row against its largest entry; C = K⁻¹ carries K's
# differences times its conditioning): measured 1.6e-4, 8.8e-7, 9.6e-5, 5.3e-7, 3.2e-5, 3.2e-6.
COMPLIANCE = {
    "four_bar": 5e-4,
    "parallelogram": 3e-6,
    "scott_russell": 3e-4,
    "double_parallelogram": 2e-6,
    "lever_amplifier": 1e-4,
    "five_bar_coupler_input": 1e-5,
}


def mechanism(name: str):
    path, extra, inputs = CASES[name]
    mech = symkin.loads(path.read_text() + extra, str(path))
    return symkin.analyze(mech), inputs


@pytest.fixture(scope="module")
def evaluated():
    """Both levels' evaluations, by mechanism (computed on first use)."""
    cache: dict = {}

    def get(name: str):
        if name not in cache:
            an, inputs = mechanism(name)
            cache[name] = (
                symkin.evaluate(an, inputs, "loaded"),
                symkin.evaluate(an, inputs, "equilibrium"),
            )
        return cache[name]

    return get


def relative(a: float, b: float) -> float:
    return abs(a - b) / abs(b)


@pytest.mark.parametrize("name", list(CASES))
def test_loaded_reports_what_equilibrium_reports(evaluated, name):
    """Each quantity against the geometrically exact beams of `equilibrium`."""
    ours, exact = evaluated(name)
    moment, rate, stress, stiffness = AGREEMENT[name]
    assert set(ours.actuation) == set(exact.actuation) != set()
    for h, a in ours.actuation.items():
        assert a.angle == exact.actuation[h].angle
        assert relative(a.moment, exact.actuation[h].moment) <= moment, h
        assert relative(a.stiffness, exact.actuation[h].stiffness) <= rate, h
    assert set(ours.plates) == set(exact.plates) != set()
    for h, p in ours.plates.items():
        assert relative(p.stress, exact.plates[h].stress) <= stress, h
        assert relative(p.strain, exact.plates[h].strain) <= stress, h
        assert p.safety is None and exact.plates[h].safety is None
    assert set(ours.stiffness) == set(exact.stiffness) != set()
    for point, k in ours.stiffness.items():
        got, want = np.array(k), np.array(exact.stiffness[point])
        scale = np.abs(want).max(axis=1, keepdims=True)
        assert np.all(np.abs(got - want) <= stiffness * scale), (point, got, want)
    assert set(ours.compliance) == set(exact.compliance) == set(ours.stiffness)
    for point, c in ours.compliance.items():
        got, want = np.array(c), np.array(exact.compliance[point])
        scale = np.abs(want).max(axis=1, keepdims=True)
        assert np.all(np.abs(got - want) <= COMPLIANCE[name] * scale), (point, got, want)
    if exact.buckling is None:
        assert ours.buckling is None
    elif math.isinf(exact.buckling):
        assert math.isinf(ours.buckling)


def test_the_reported_quantities_in_json_and_text_every_backend(capsys):
    """`eval --level loaded` prints them in text and JSON, the same whichever the backend: eval
    takes them from the derivation (symkin.studies.generated), so this checks the printing and
    the dispatch, not the generated code's own report (tests/test_loaded_reported_codegen.py
    checks that against the Python level)."""
    path = str(EXAMPLES / "four_bar.toml")
    data = {}
    for backend in backends_with(levels="loaded"):
        require(backend)
        args = ["eval", path, "--input", "A0=0.3", "--level", "loaded", "--json"]
        code = main([*args, "--backend", backend])
        out, err = capsys.readouterr()
        assert code == 0, err
        data[backend] = json.loads(out)
    assert len(data) > 1
    for backend in data:
        for key in ("inputs", "stiffness", "compliance", "plates"):
            assert data[backend][key] == data["sympy"][key] != {}, (backend, key)
    assert "buckling" not in data["sympy"]  # the file has no loads
    code = main(["eval", path, "--input", "A0=0.3", "--level", "loaded"])
    out, err = capsys.readouterr()
    assert code == 0, err
    for heading in (
        "inputs: what each input",
        "plate stress:",
        "point stiffness with",
        "point stiffness along each direction, the other two free",
    ):
        assert heading in out


# -- against the reduced solver's own central differences -------------------------------------


def solve(an, inputs, params=None):
    answer = reduced_equilibrium(an, inputs, params, backend="sympy")
    assert not answer.refused
    return answer


@pytest.mark.parametrize("name", ["four_bar", "scott_russell", "double_parallelogram"])
def test_input_stiffness_by_central_differences_of_the_solver(name):
    an, inputs = mechanism(name)
    scale = float(an.mechanism.unit_scale)
    report = reduced_equilibrium_report(an, inputs, scale)
    step = 1e-5
    for h in inputs:

        def difference(d: float) -> float:
            m = [
                reduced_equilibrium_report(an, dict(inputs) | {h: inputs[h] + s * d}, scale)
                .inputs[h]
                .moment
                for s in (1, -1)
            ]
            return (m[0] - m[1]) / (2 * d)

        # Richardson's extrapolation of two central differences (the Scott–Russell moment's
        # third derivative alone is 5e-8 of the rate at this step)
        rate = (4 * difference(step / 2) - difference(step)) / 3
        # measured: four-bar 4e-12, Scott-Russell 8e-12, double parallelogram 8e-12
        assert relative(report.inputs[h].stiffness, rate) <= 1e-10, h


def reduced_equilibrium_report(an, inputs, scale):
    return reduced_reported.report(solve(an, inputs), scale, buckling=False)


def central_stiffness(name: str, point: str, inputs: dict[str, float]) -> np.ndarray:
    """K = C⁻¹, C = d(x, y, φ)/d(Fx, Fy, M) by central differences of the Python solver under a
    small load added at the point (file units), the mechanism solved again (the inputs held)."""
    path, extra, _ = CASES[name]
    text = path.read_text().replace("[parameters]\n", "[parameters]\nvx = 0\nvy = 0\nvm = 0\n")
    text += extra + f'\n[[load]]\npoint = "{point}"\nforce = ["vx", "vy"]\nmoment = "vm"\n'
    an = symkin.analyze(symkin.loads(text, str(path)))
    red = solve(an, inputs).solver
    link = red.points[point][0]
    names = {a: h.name for a, h in red.hinges.items()}

    def state(answer) -> np.ndarray:
        # the point's deviation and its link's rotation beyond the rigid (the inputs held)
        turn = math.fsum(
            red.hinges[b].sign * answer.angle_deviations[names[b]] for b in red.paths[link]
        )
        return np.array([*answer.deviations[point], turn])

    # small against the plates' load scale F = EI/(l L): the load stiffens them
    steps = [1e-4 * red.F, 1e-4 * red.F, 1e-4 * red.F * red.L]
    columns = []
    for key, h in zip(("vx", "vy", "vm"), steps, strict=True):
        pair = [state(solve(an, inputs, params={key: repr(float(s * h))})) for s in (1, -1)]
        columns.append((pair[0] - pair[1]) / (2 * h))
    return np.linalg.inv(np.array(columns).T)


@pytest.mark.parametrize("name, point", [("four_bar", "C"), ("parallelogram", "P")])
def test_point_stiffness_by_central_differences_of_the_solver(name, point):
    """The reported K against central differences of the solver under a load at the point."""
    an, inputs = mechanism(name)
    want = np.array(
        reduced_reported.report(solve(an, inputs), 1.0, buckling=False).stiffness[point]
    )
    got = central_stiffness(name, point, inputs)
    scale = np.abs(want).max(axis=1, keepdims=True)
    # measured: four-bar 1e-10, parallelogram 7e-10 (of each row's largest entry)
    assert np.all(np.abs(got - want) <= 1e-8 * scale), (got, want)


# -- closed forms -------------------------------------------------------------------------------


@pytest.mark.parametrize("theta", [0.02, 0.3])
def test_lone_plate_under_a_pure_moment_is_a_circular_arc(theta):
    mech = symkin.loads(M.lone_plate(), "lone_plate.toml")
    res = symkin.evaluate(symkin.analyze(mech), {"A": theta}, "loaded")
    ei = M.bending_stiffness(5, 0.3, 1e-3)  # N m²
    modulus, t, length = 200e9 / (1 - 0.3**2), 0.2e-3, 10e-3
    a = res.actuation["A"]
    assert a.moment == pytest.approx(ei * theta / length, rel=1e-12)
    assert a.stiffness == pytest.approx(ei / length, rel=1e-12)
    plate = res.plates["A"]
    assert plate.stress == pytest.approx(modulus * t * theta / (2 * length), rel=1e-12)
    assert res.stiffness == {"T": None}  # the input holds the arm
    assert res.buckling is None


def _clamp(ref, mech, hinge, end):
    """Position and section angle of a plate's clamp from the reference's poses."""
    h = mech.hinge(hinge)
    ang = float(h.plate_angle)
    length = float(h.length.subs(mech.defaults))
    sign = -1 if end == 0 else 1
    p0 = [
        float(h.at[k].subs(mech.defaults)) + sign * length / 2 * v
        for k, v in enumerate((math.cos(ang), math.sin(ang)))
    ]
    x, y, phi = (float(v) for v in ref["poses"][h.links[end]])
    c, s = math.cos(phi), math.sin(phi)
    return np.array([x + c * p0[0] - s * p0[1], y + s * p0[0] + c * p0[1]]), phi + ang


def test_plate_stress_from_the_reference_end_loads():
    """σ = |N|/A + |M| t/(2I) at both ends of the loaded stage's plates, from the independent
    beam solver's end loads and clamp poses (its plates are bent most at an end)."""
    an, inputs = mechanism("parallelogram")
    mech = an.mechanism
    ours = symkin.evaluate(an, inputs, "loaded")
    loads = [Load(ld.link, tuple(ld.at), tuple(ld.force), ld.moment) for ld in mech.loads]
    with mpmath.workdps(40):
        ref = BeamEquilibrium(mech, loads=loads).solve({"F1": "0.05"}, min_digits=12)
    area, inertia = WIDTH * THICK, WIDTH * THICK**3 / 12
    for name, plate in ours.plates.items():
        force = np.array([float(v) for v in ref["hinges"][name]["force"]])
        m_end = float(ref["hinges"][name]["moment"])
        (rp, psi_p), (rm, psi_m) = _clamp(ref, mech, name, 0), _clamp(ref, mech, name, 1)
        d = rm - rp
        m_start = m_end + d[0] * force[1] - d[1] * force[0]
        stresses = [
            abs(force @ (math.cos(psi), math.sin(psi))) / area + abs(m) * THICK / (2 * inertia)
            for psi, m in ((psi_p, m_start), (psi_m, m_end))
        ]
        assert plate.section in (0.0, 1.0)
        # measured 3.9e-8: the relation's quartic truncation against the exact beam
        assert plate.stress == pytest.approx(max(stresses), rel=1e-7)
        assert plate.strain == pytest.approx(max(stresses) / E_PRIME, rel=1e-7)


# -- buckling -----------------------------------------------------------------------------------


@pytest.mark.parametrize("beam", ["elastica", "reissner"])
def test_buckling_of_the_clamped_guided_column(beam):
    """The lone plate held by its input at 0 under a quarter of its critical load: the factor 4
    (Euler's π²EI/l²; Haringx's with Reissner's stretch and shear)."""
    critical = M.column_buckling_load(beam)
    load = '[[load]]\npoint = "T"\nforce = [0, "-F"]\n'
    mech = symkin.loads(M.lone_plate(load=load, beam=beam), "column.toml")
    res = symkin.evaluate(symkin.analyze(mech), {"A": 0.0}, "loaded", {"F": critical / 4})
    assert res.buckling == pytest.approx(4.0, rel=1e-9)  # measured 3e-11


def test_buckling_of_the_parallelogram_stage_where_its_stiffness_vanishes():
    """The stage pushed down along its legs, the input held: it sways sideways when the plates'
    compression (each leg's plates clamped–guided columns, the other leg's tilt beside them)
    makes its lateral stiffness vanish. The reference: the load at which the `equilibrium`
    level's K_xx of the stage reaches zero (a parabola through three loads just below)."""
    base = (ZOO / "parallelogram.toml").read_text()
    text = base.replace("[parameters]\n", "[parameters]\nW = 200\n")
    text += '\n[[load]]\npoint = "P"\nforce = [0.0, "-W"]\n'
    an = symkin.analyze(symkin.loads(text, "parallelogram.toml"))
    ours = symkin.evaluate(an, {"F1": 0.0}, "loaded")
    loads = [405.0, 412.0, 416.0]
    kxx = [
        symkin.evaluate(an, {"F1": 0.0}, "equilibrium", {"W": w}).stiffness["P"][0][0]
        for w in loads
    ]
    roots = np.roots(np.polyfit(loads, kxx, 2))
    critical = float(min(r.real for r in roots if r.real > loads[-1] and abs(r.imag) < 1e-9))
    assert ours.buckling * 200 == pytest.approx(critical, rel=1e-4)  # measured 1.1e-5
    # equilibrium's own search finds the same sway (it once stepped over it to a buckled branch)
    exact = symkin.evaluate(an, {"F1": 0.0}, "equilibrium")
    assert exact.buckling * 200 == pytest.approx(critical, rel=1e-4)  # measured 1.0e-5
    # Euler's clamped–guided load of one plate, π²EI/l² per leg, bounds it from above
    ei = E_PRIME * WIDTH * THICK**3 / 12
    assert ours.buckling * 200 < 2 * math.pi**2 * ei / 5e-3**2


def test_buckling_of_the_scott_russell_amplifier_is_equilibriums():
    an, _ = mechanism("scott_russell")
    ours = symkin.evaluate(an, {"RA0": 0.0}, "loaded")
    exact = symkin.evaluate(an, {"RA0": 0.0}, "equilibrium")
    assert ours.buckling == pytest.approx(exact.buckling, rel=1e-3)  # measured 2.8e-4
