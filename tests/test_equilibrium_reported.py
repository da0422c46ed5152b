"""What `eval --level equilibrium` reports for the designer (docs/physics.md, "What equilibrium
reports"): input moments and stiffness, point stiffness, plate stress, buckling factor.

References written here, apart from symkin: closed forms for a lone plate under a pure moment
(M = E'I θ/l, dM/dθ = E'I/l, σ = E' t θ/(2l)) and for a clamped–guided column (Euler's
π²EI/l², tests/mechanisms.py); the independent beam solver tests/reference_beams.py for a loaded
parallelogram stage: σ = |N|/A + |M| t/(2I) from its plate end loads and poses, the point's
stiffness and the input's stiffness by central differences of its solves (a small added load at
the point, a changed input angle).
"""

from __future__ import annotations

import json
import math

import mechanisms as M
import mpmath
import numpy as np
import pytest
from conftest import ROOT
from reference_beams import BeamEquilibrium
from reference_physics import Load

import symkin
from symkin.cli.commands import main

ZOO = ROOT / "tests" / "mechanisms"
LOAD = '\n[[load]]\npoint = "P"\nforce = [1.5, -4.0]\nmoment = 0.02\n'
# the parallelogram stage's plates (tests/mechanisms/parallelogram.toml): SI units
E_PRIME, WIDTH, THICK, LENGTH = 210e9 / (1 - 0.3**2), 10e-3, 0.15e-3, 5e-3


def run(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


@pytest.mark.parametrize("theta", [0.02, 0.3])
def test_lone_plate_under_a_pure_moment_is_a_circular_arc(theta):
    """No load: the actuator bends the plate by a pure moment into a circular arc."""
    mech = symkin.loads(M.lone_plate(), "lone_plate.toml")
    res = symkin.evaluate(symkin.analyze(mech), {"A": theta}, "equilibrium")
    ei = M.bending_stiffness(5, 0.3, 1e-3)  # N m²
    modulus, t, length = 200e9 / (1 - 0.3**2), 0.2e-3, 10e-3
    a = res.actuation["A"]
    assert a.angle == theta
    assert a.moment == pytest.approx(ei * theta / length, rel=1e-10)
    assert a.stiffness == pytest.approx(ei / length, rel=1e-8)
    plate = res.plates["A"]
    assert plate.stress == pytest.approx(modulus * t * theta / (2 * length), rel=1e-10)
    assert plate.strain == pytest.approx(t * theta / (2 * length), rel=1e-10)
    assert plate.safety is None
    # T is on the arm, whose rotation the input holds: infinitely stiff there, not reported
    assert res.stiffness == {"T": None}
    assert res.buckling is None  # no loads, no buckling search


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


@pytest.fixture(scope="module")
def stage():
    """The parallelogram stage with a load at P, its symkin evaluation and the reference."""
    text = (ZOO / "parallelogram.toml").read_text() + LOAD
    mech = symkin.loads(text, "parallelogram.toml")
    ours = symkin.evaluate(symkin.analyze(mech), {"F1": 0.05}, "equilibrium")
    return mech, ours


def _solve(mech, angle: str = "0.05", extra=()) -> dict:
    """The reference's solve of the stage with its file's load and `extra` loads."""
    loads = [Load(ld.link, tuple(ld.at), tuple(ld.force), ld.moment) for ld in mech.loads]
    with mpmath.workdps(40):
        return BeamEquilibrium(mech, loads=[*loads, *extra]).solve({"F1": angle}, min_digits=12)


@pytest.fixture(scope="module")
def solved(stage):
    return _solve(stage[0])


def test_plate_stress_from_the_reference_end_loads(stage, solved):
    """σ = |N|/A + |M| t/(2I) at both ends from the reference's end loads: the plates of the
    stage are bent most at an end (their moment is linear along them, almost straight)."""
    mech, ours = stage
    area, inertia = WIDTH * THICK, WIDTH * THICK**3 / 12
    for name, plate in ours.plates.items():
        force = np.array([float(v) for v in solved["hinges"][name]["force"]])
        m_end = float(solved["hinges"][name]["moment"])
        (rp, psi_p), (rm, psi_m) = _clamp(solved, mech, name, 0), _clamp(solved, mech, name, 1)
        d = rm - rp
        m_start = m_end + d[0] * force[1] - d[1] * force[0]  # the plate's moment balance
        stresses = [
            abs(force @ (math.cos(psi), math.sin(psi))) / area + abs(m) * THICK / (2 * inertia)
            for psi, m in ((psi_p, m_start), (psi_m, m_end))
        ]
        assert plate.section in (0.0, 1.0)
        assert plate.stress == pytest.approx(max(stresses), rel=1e-9)
        assert plate.strain == pytest.approx(max(stresses) / E_PRIME, rel=1e-9)


def test_input_stiffness_by_central_differences_of_the_reference(stage, solved):
    mech, ours = stage
    step = 1e-6
    up, down = (_solve(mech, f"{0.05 + s:.7f}") for s in (step, -step))
    rate = float((up["actuators"]["F1"] - down["actuators"]["F1"]) / (2 * step))
    a = ours.actuation["F1"]
    assert a.moment == pytest.approx(float(solved["actuators"]["F1"]), rel=1e-10)
    assert a.stiffness == pytest.approx(rate, rel=1e-9)  # measured 5e-14


def test_point_stiffness_by_central_differences_of_the_reference(stage):
    """C = d(x, y, φ_stage)/d(Fx, Fy, M) of a small load added at P, K = C⁻¹ (file unit m)."""
    mech, ours = stage
    at = tuple(mech.point("P").at)
    steps = (1e-5, 1e-5, 1e-7)
    columns = []
    for j, h in enumerate(steps):
        pair = []
        for sign in (1, -1):
            f = [0, 0, 0]
            f[j] = sign * h
            res = _solve(mech, extra=[Load("stage", at, (f[0], f[1]), f[2])])
            # kept in mpf: the displacements are 1e-12 of the positions
            pair.append([*res["points"]["P"]["compliant"], res["poses"]["stage"][2]])
        with mpmath.workdps(40):
            columns.append([float((a - b) / (2 * h)) for a, b in zip(*pair)])
    want = np.linalg.inv(np.array(columns).T)
    got = np.array(ours.stiffness["P"])
    scale = np.abs(want).max(axis=1, keepdims=True)  # each row against its largest entry
    assert np.all(np.abs(got - want) <= 1e-9 * scale), (got, want)  # measured 3e-12
    assert np.allclose(got, got.T, rtol=1e-6, atol=1e-6 * scale.max())  # a potential's Hessian


@pytest.mark.parametrize("beam", ["elastica", "reissner"])
def test_buckling_factor_of_the_clamped_guided_column(beam):
    """The lone plate held by its input at 0 (clamped–guided) under an axial load at half its
    critical load buckles at twice the load: Euler's π²EI/l² (Reissner: with its stretch and
    shear, tests/mechanisms.py)."""
    critical = M.column_buckling_load(beam)
    load = '[[load]]\npoint = "T"\nforce = [0, "-F"]\n'
    mech = symkin.loads(M.lone_plate(load=load, beam=beam), "column.toml")
    an = symkin.analyze(mech)
    res = symkin.evaluate(an, {"A": 0.0}, "equilibrium", params={"F": critical / 2})
    assert res.buckling == pytest.approx(2.0, rel=1e-5) and res.buckling_hinge == "A"
    assert res.plates["A"].stress == pytest.approx(critical / 2 / (5e-3 * 0.2e-3), rel=1e-10)
    far = symkin.evaluate(an, {"A": 0.0}, "equilibrium", params={"F": critical / 20})
    assert far.buckling == math.inf and far.as_json()["buckling"] is None


def test_units_leave_the_reported_quantities_consistent(capsys):
    """The stage in metres and in millimetres: moments in N m, stress in Pa alike; the stiffness
    in N/unit, N, N·unit, the compliance in its inverse units."""
    out = {}
    for name in ("parallelogram", "parallelogram_mm"):
        path = str(ZOO / f"{name}.toml")
        code, text, err = run(
            capsys, "eval", path, "--input", "F1=0.05", "--level", "equilibrium", "--json"
        )
        assert code == 0, err
        out[name] = json.loads(text)
    m, mm = out["parallelogram"], out["parallelogram_mm"]
    assert mm["inputs"]["F1"]["moment"] == pytest.approx(m["inputs"]["F1"]["moment"], rel=1e-9)
    assert mm["inputs"]["F1"]["stiffness"] == pytest.approx(
        m["inputs"]["F1"]["stiffness"], rel=1e-8
    )
    for h, plate in m["plates"].items():
        assert mm["plates"][h]["stress"] == pytest.approx(plate["stress"], rel=1e-9)
    unit = np.array([[1e-3, 1e-3, 1], [1e-3, 1e-3, 1], [1, 1, 1e3]])
    assert np.allclose(mm["stiffness"]["P"], np.array(m["stiffness"]["P"]) * unit, rtol=1e-7)
    assert np.allclose(mm["compliance"]["P"], np.array(m["compliance"]["P"]) / unit, rtol=1e-7)


@pytest.mark.parametrize(
    "name, inputs",
    [
        ("parallelogram", ["F1=0.08"]),
        ("scott_russell", ["RA0=0.02"]),
        ("double_parallelogram", ["F1=0.01", "I1=-0.01"]),
    ],
)
def test_realistic_mechanisms_report_finite_values_and_flag_overstress(
    capsys, tmp_path, name, inputs
):
    """Each zoo mechanism with an allowable stress between its plates' smallest and largest
    stress: finite values, the safety factors allowable/σ, the overstressed plates flagged in
    the text, exit code 0."""
    text = (ZOO / f"{name}.toml").read_text()
    args = [a for i in inputs for a in ("--input", i)]
    path = tmp_path / f"{name}.toml"
    path.write_text(text)
    code, out, err = run(capsys, "eval", str(path), *args, "--level", "equilibrium", "--json")
    assert code == 0, err
    data = json.loads(out)
    stresses = {h: p["stress"] for h, p in data["plates"].items()}
    allowable = (min(stresses.values()) + max(stresses.values())) / 2
    path.write_text(text.replace("[defaults]\n", f"[defaults]\nallowable_stress = {allowable!r}\n"))
    code, out, err = run(capsys, "eval", str(path), *args, "--level", "equilibrium", "--json")
    assert code == 0, err
    data = json.loads(out)
    assert set(data["inputs"]) == {i.split("=")[0] for i in inputs}
    for a in data["inputs"].values():
        assert all(math.isfinite(a[k]) for k in ("angle", "moment", "stiffness"))
    for k in data["stiffness"].values():
        assert np.all(np.isfinite(k)) and np.all(np.linalg.eigvalsh(np.array(k)) > 0)
    for p, c in data["compliance"].items():
        assert np.allclose(np.array(c) @ np.array(data["stiffness"][p]), np.eye(3), atol=1e-9)
    for h, p in data["plates"].items():
        assert p["stress"] == pytest.approx(stresses[h], rel=1e-12)
        assert p["safety"] == pytest.approx(allowable / p["stress"], rel=1e-12)
    if data.get("buckling") is not None:
        assert data["buckling"] > 1
    code, out, err = run(capsys, "eval", str(path), *args, "--level", "equilibrium")
    assert code == 0, err
    flagged = {line.split()[0] for line in out.splitlines() if "PAST ITS ALLOWABLE" in line}
    assert flagged == {h for h, s in stresses.items() if s > allowable} != set()
