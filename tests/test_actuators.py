"""Stroke actuators at the kinematic levels (docs/levels.md, "Actuators"; docs/file-format.md,
"[[actuator]]"), against references written here:

- the parallelogram of tests/mechanisms/parallelogram.toml pushed along x on its stage: the
  rigid stage translates by (-L sin q, -L (1 - cos q)), and with circular-arc plates the compliant
  stage translates too, by the file's closed-form arc deviation at its own leg angle q_c, which
  the stroke fixes: -L sin q_c + dx(q_c) = s (solved here with mpmath);
- the four-bar of examples/four_bar.toml pushed on its rocker, against the independent kinematic
  oracle tests/reference_solver.py driven by its hinge A0 (the crank angle at which the rocker's
  point has moved by the stroke found here by the secant method), rigid and compliant;
- a stroke-driven and a hinge-driven parallelogram reach the same pose where the geometry makes
  them equivalent.
"""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import mechanisms as M
import mpmath
import numpy as np
import pytest
from cli_runs import symkin_cli
from evaluators import BACKENDS, GENERATED, KINEMATIC

import symkin
from symkin.core import backends
from symkin.core.errors import InputError
from symkin.kinematics.variants import Variant
from symkin.studies import tradeoff
from tests.reference_solver import Reference

ROOT = Path(__file__).resolve().parent.parent
PARALLELOGRAM = (ROOT / "tests" / "mechanisms" / "parallelogram.toml").read_text()
FOUR_BAR = (ROOT / "examples" / "four_bar.toml").read_text()

PIEZO = M.PIEZO.format(drive="stroke")

PUSHER = """
[[actuator]]
name = "pusher"
link = "rocker"
at = [0.1, 0.05]
direction = [0.6, 0.8]
"""


def stroke_driven(text: str, hinge: str, actuator: str) -> str:
    """`text` with the input hinge `hinge` made passive and `actuator` appended."""
    return M.made_passive(text, hinge) + actuator


@pytest.fixture(scope="module")
def parallelogram():
    mech = symkin.loads(stroke_driven(PARALLELOGRAM, "F1", PIEZO), "parallelogram_stroke.toml")
    return mech, symkin.analyze(mech)


@pytest.fixture(scope="module")
def four_bar():
    mech = symkin.loads(stroke_driven(FOUR_BAR, "A0", PUSHER), "four_bar_stroke.toml")
    return mech, symkin.analyze(mech)


def test_reader_chooses_a_surrogate_and_lists_the_actuator(parallelogram, four_bar):
    mech, _ = parallelogram
    assert mech.drives == ("piezo",)
    a = mech.actuator("piezo")
    assert a.drive == "stroke" and a.link == "stage" and a.direction == (1, 0)
    assert a.surrogate in ("S1", "S2") and mech.inputs == (a.surrogate,)
    mech4, _ = four_bar
    # normalised by the reader: (0.6, 0.8) is a unit vector already, (3, 4) would be too
    assert [float(c) for c in mech4.actuator("pusher").direction] == [0.6, 0.8]


def parallelogram_reference(s: float, level: str) -> dict:
    """Rigid and compliant stage point P of the stroke-driven parallelogram, in mpmath: the
    stage translates, so the stroke at the stage's point is the stage's x displacement."""
    with mpmath.workdps(40):
        L, l, s = mpmath.mpf("0.040"), mpmath.mpf("5e-3"), mpmath.mpf(s)
        p0 = (mpmath.mpf("0.015"), mpmath.mpf("0.050"))

        def dx(q):
            return l * mpmath.sin(q) - 2 * l * (1 - mpmath.cos(q)) / q

        def dy(q):
            return l * (2 * mpmath.sin(q) / q - 1 - mpmath.cos(q))

        q_r = mpmath.asin(-s / L)
        q_c = mpmath.findroot(lambda q: -L * mpmath.sin(q) + dx(q) - s, q_r)
        rigid = (p0[0] - L * mpmath.sin(q_r), p0[1] - L * (1 - mpmath.cos(q_r)))
        compliant = (
            p0[0] - L * mpmath.sin(q_c) + dx(q_c),
            p0[1] - L * (1 - mpmath.cos(q_c)) + dy(q_c),
        )
        return {"rigid": rigid, "compliant": compliant, "q_r": q_r, "q_c": q_c}


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("level", KINEMATIC)
@pytest.mark.parametrize("s", [2e-3, -1e-4, 2e-5])
def test_parallelogram_stroke_against_closed_form(parallelogram, level, s, backend):
    _, an = parallelogram
    ev = symkin.evaluate(an, {"piezo": s}, level, backend=backend)
    ref = parallelogram_reference(s, level)
    p = ev.points["P"]
    assert set(ev.points) == {"P"}  # the actuator's point stays hidden
    assert ev.inputs == {"piezo": s}
    size = float(mpmath.norm(ref["compliant"][1] - ref["rigid"][1]))
    for i in range(2):
        assert p.rigid[i] == pytest.approx(float(ref["rigid"][i]), abs=1e-15)
        assert p.compliant[i] == pytest.approx(float(ref["compliant"][i]), abs=1e-15)
        dev = float(ref["compliant"][i] - ref["rigid"][i])
        assert abs(p.deviation[i] - dev) <= 1e-9 * size + 1e-17
    # the compliant stage moved by the stroke too: no deviation along the line of action
    assert abs(p.deviation[0]) <= 1e-16
    assert ev.angles_rigid["F1"] == pytest.approx(float(ref["q_r"]), rel=1e-12)
    assert ev.angles_compliant["F1"] == pytest.approx(float(ref["q_c"]), rel=1e-12)


@pytest.mark.parametrize("level", KINEMATIC)
def test_stroke_and_hinge_driven_parallelogram_reach_the_same_pose(parallelogram, level):
    """The hinge-driven parallelogram at the leg angle the stroke gave its rigid linkage has
    the same rigid pose, and at the compliant angle the same compliant pose."""
    _, an = parallelogram
    hinge = symkin.analyze(symkin.loads(PARALLELOGRAM, "parallelogram.toml"))
    s = 1.5e-3
    ev = symkin.evaluate(an, {"piezo": s}, level)
    ref = parallelogram_reference(s, level)
    at_r = symkin.evaluate(hinge, {"F1": float(ref["q_r"])}, level)
    at_c = symkin.evaluate(hinge, {"F1": float(ref["q_c"])}, level)
    for i in range(2):
        assert ev.points["P"].rigid[i] == pytest.approx(at_r.points["P"].rigid[i], abs=1e-16)
        assert ev.points["P"].compliant[i] == pytest.approx(
            at_c.points["P"].compliant[i], abs=1e-16
        )
    # the stroke along x is the leg angle times the leg length to first order
    assert float(ref["q_r"]) == pytest.approx(-s / 0.040, rel=(s / 0.040) ** 2)


def rocker_point(solution: dict, at: tuple, link: str = "rocker") -> tuple:
    x, y, phi = solution["poses"][link]
    c, s = mpmath.cos(phi), mpmath.sin(phi)
    return (x + c * at[0] - s * at[1], y + s * at[0] + c * at[1])


def four_bar_reference(s: float, model: str | None) -> dict:
    """The oracle's four-bar (hinge A0 driven) at the crank angle where the rocker's point
    (0.1, 0.05) has moved by `s` along (0.6, 0.8): rigid pins (model 'rigid') or the file's
    plates (model None); the crank angle by the secant method."""
    ref = Reference(symkin.loads(FOUR_BAR, "four_bar.toml"))
    at = (mpmath.mpf("0.1"), mpmath.mpf("0.05"))
    d = (mpmath.mpf("0.6"), mpmath.mpf("0.8"))
    with mpmath.workdps(40):

        def stroke(q):
            sol = ref.solve({"A0": q}, model_override=model, dps=40)
            p = rocker_point(sol, at)
            return d[0] * (p[0] - at[0]) + d[1] * (p[1] - at[1]) - mpmath.mpf(s), sol

        q0, q1 = mpmath.mpf(0), mpmath.mpf("0.01")
        f0, f1 = stroke(q0)[0], stroke(q1)[0]
        for _ in range(40):
            q0, q1 = q1, q1 - f1 * (q1 - q0) / (f1 - f0)
            f0, (f1, sol) = f1, stroke(q1)
            if abs(f1) < mpmath.mpf(10) ** -30:
                return sol
    raise AssertionError("the reference did not reach the stroke")


@pytest.mark.parametrize("s", [1e-3, -2e-3])
def test_four_bar_stroke_against_reference_solver(four_bar, s):
    _, an = four_bar
    rigid = four_bar_reference(s, "rigid")
    compliant = four_bar_reference(s, None)
    for backend in BACKENDS:
        check_four_bar(
            symkin.evaluate(an, {"pusher": s}, "exact", backend=backend), rigid, compliant
        )
    # the first-order level agrees with the exact one to its own order, (l/L)^2 of ΔR
    first = symkin.evaluate(an, {"pusher": s}, "first_order").points["C"]
    dev = [compliant["points"]["C"][i] - rigid["points"]["C"][i] for i in range(2)]
    size = float(mpmath.norm(mpmath.matrix(dev)))
    assert max(abs(first.deviation[i] - float(dev[i])) for i in range(2)) <= 0.05 * size


def check_four_bar(ev, rigid: dict, compliant: dict) -> None:
    """`ev` against the oracle's rigid and compliant four-bar at the stroke."""
    c = ev.points["C"]
    dev = [compliant["points"]["C"][i] - rigid["points"]["C"][i] for i in range(2)]
    size = float(mpmath.norm(mpmath.matrix(dev)))
    assert size > 1e-6
    for i in range(2):
        assert c.rigid[i] == pytest.approx(float(rigid["points"]["C"][i]), abs=1e-15)
        assert abs(c.deviation[i] - float(dev[i])) <= 1e-9 * size
    assert ev.angles_rigid["A0"] == pytest.approx(float(rigid["angles"]["A0"]), rel=1e-12)
    assert ev.angles_compliant["A0"] == pytest.approx(float(compliant["angles"]["A0"]), rel=1e-12)


def test_what_does_not_take_actuators_yet_is_refused(parallelogram, tmp_path):
    _, an = parallelogram
    force = symkin.loads(
        stroke_driven(PARALLELOGRAM, "F1", PIEZO.replace('"stroke"', '"force"')), "force.toml"
    )
    # the generated evaluators take a force at loaded alone (tests/test_loaded_actuators_codegen.py)
    for backend in [b for b in GENERATED if "equilibrium" not in backends.get(b).forces]:
        title = backends.get(backend).title
        with pytest.raises(InputError, match=rf"generated {title}.*force.*piezo"):
            symkin.evaluate(symkin.analyze(force), {"piezo": 1.0}, "equilibrium", backend=backend)
        with pytest.raises(InputError, match="no generated evaluator"):
            symkin.evaluate(an, {"piezo": 1e-3}, "equilibrium", backend=backend)
    with pytest.raises(InputError, match="not an input"):
        symkin.evaluate(an, {"F1": 1e-3}, "exact")
    with pytest.raises(InputError, match=r"force.*physical level"):
        symkin.evaluate(symkin.analyze(force), {"piezo": 1.0}, "exact")
    with pytest.raises(InputError, match=r"piezo.*force.*kinematic variants"):
        tradeoff.run(force, {"piezo": (0.0, 1.0)}, n=3, with_c=False)


def test_tradeoff_takes_the_strokes(four_bar):
    """tradeoff over a stroke range: each variant's worst relative error is the one found here
    from the sympy backend's deviations of that level against the reference level's (the
    four-bar's plates have their stiffness: `equilibrium`, at the same strokes)."""
    mech, an = four_bar
    spans = tradeoff.parse_ranges(None, mech.drives, mech.path, strokes=mech.stroke_spans())
    assert spans == {"pusher": (-mech.stroke_spans()["pusher"], mech.stroke_spans()["pusher"])}
    table = tradeoff.run(mech, spans, n=3, variants=[Variant("paper")], with_c=False)
    (row,) = table.rows
    assert table.reference == "equilibrium"
    pairs = []
    for s in tradeoff.sample(spans, 3):
        given = {"pusher": repr(s["pusher"])}
        ref = symkin.evaluate(an, given, table.reference, dps=30).points["C"].deviation
        got = symkin.evaluate(an, given, "paper", dps=30).points["C"].deviation
        pairs.append((ref, got))
    scale = max(math.hypot(*ref) for ref, _ in pairs)
    # where the reference vanishes (the as-fabricated pose, s = 0) the error is over the scale
    worst = max(
        math.dist(got, ref) / (math.hypot(*ref) if math.hypot(*ref) > 1e-12 * scale else scale)
        for ref, got in pairs
    )
    assert row.errors["C"] == pytest.approx(worst, rel=1e-6)


def test_cli_check_and_eval(tmp_path):
    path = tmp_path / "stage.toml"
    path.write_text(stroke_driven(PARALLELOGRAM, "F1", PIEZO))
    check = symkin_cli("check", str(path))
    assert check.returncode == 0, check.stderr
    assert "inputs: piezo" in check.stdout and "actuator piezo: stroke" in check.stdout
    out = symkin_cli("eval", str(path), "--input", "piezo=2e-3", "--json", "--level", "exact")
    assert out.returncode == 0, out.stderr
    doc = json.loads(out.stdout)
    ref = parallelogram_reference(2e-3, "exact")
    assert doc["inputs"] == {"piezo": 2e-3}
    assert doc["points"]["P"]["deviation"][1] == pytest.approx(
        float(ref["compliant"][1] - ref["rigid"][1]), rel=1e-9
    )
    # loaded takes it too (tests/test_loaded_actuators.py), the generated numpy and C too
    # (tests/test_loaded_actuators_codegen.py)
    loaded = symkin_cli("eval", str(path), "--input", "piezo=2e-3", "--level", "loaded")
    assert loaded.returncode == 0, loaded.stderr
    assert "actuators: what each actuator delivers" in loaded.stdout
    generated = symkin_cli(
        "eval", str(path), "--input", "piezo=2e-3", "--level", "loaded", "--backend", "c"
    )
    assert generated.returncode == 0, generated.stderr


def test_generated_numpy_module_takes_the_strokes(tmp_path):
    """derive --emit numpy,c: the numpy module's INPUTS are the actuators, its POINTS the
    file's; on an array of strokes it gives what the sympy backend gives one stroke at a time
    (the C: test_parallelogram_stroke_against_closed_form); --fix is refused, naming the
    actuator."""
    import importlib.util

    import numpy as np

    path = tmp_path / "stage.toml"
    path.write_text(stroke_driven(PARALLELOGRAM, "F1", PIEZO))
    run = ["derive", str(path), "-o", str(tmp_path / "out")]
    out = symkin_cli(*run, "--emit", "numpy,c")
    assert out.returncode == 0, out.stderr
    header = (tmp_path / "out" / "parallelogram.h").read_text()
    assert "#define PARALLELOGRAM_N_INPUTS 1" in header and "_N_POINTS 1" in header
    # the sensitivities take the strokes too (tests/test_actuator_sensitivity.py)
    assert "int parallelogram_sensitivity_full(" in header
    fixed = symkin_cli(*run, "--fix", "piezo=0.01")
    assert fixed.returncode == 2 and "piezo" in fixed.stderr and "--fix" in fixed.stderr
    spec = importlib.util.spec_from_file_location("stage", tmp_path / "out" / "parallelogram.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    assert module.INPUTS == ("piezo",) and module.POINTS == ("P",)
    strokes = np.array([-2e-3, 5e-4, 1.5e-3])
    res = module.evaluate({"piezo": strokes}, "exact")
    assert res["ok"].all() and res["points"]["P"]["deviation"].shape == (2, 3)
    for k, s in enumerate(strokes):
        ref = parallelogram_reference(float(s), "exact")
        dev = [float(ref["compliant"][i] - ref["rigid"][i]) for i in range(2)]
        got = res["points"]["P"]["deviation"][:, k]
        # the strokes are met to 64 ulp of the positions (templates/numpy/actuators.py)
        assert abs(got[1] - dev[1]) <= 1e-9 * abs(dev[1]) and abs(got[0]) <= 1e-15
        assert res["angles"]["rigid"]["F1"][k] == pytest.approx(float(ref["q_r"]), rel=1e-12)
    with pytest.raises(ValueError, match="inputs must be exactly"):
        module.evaluate({"S1": 0.1}, "exact")


# -- the equilibrium level -------------------------------------------------------------------


@pytest.fixture(scope="module")
def parallelogram_force():
    text = stroke_driven(PARALLELOGRAM, "F1", PIEZO.replace('"stroke"', '"force"'))
    mech = symkin.loads(text, "parallelogram_force.toml")
    return mech, symkin.analyze(mech)


def test_equilibrium_force_at_the_reported_force_reaches_the_same_stroke(
    parallelogram, parallelogram_force
):
    """The force a stroke-driven parallelogram reports, applied by a force actuator, reaches the
    same stroke and the same deviation (the rigid reference at the stroke it produced)."""
    _, an = parallelogram
    _, anf = parallelogram_force
    s = 1.5e-3
    ev = symkin.evaluate(an, {"piezo": s}, "equilibrium")
    a = ev.actuators["piezo"]
    assert a.stroke == pytest.approx(s, rel=1e-12)
    evf = symkin.evaluate(anf, {"piezo": a.force}, "equilibrium")
    b = evf.actuators["piezo"]
    assert b.force == a.force and b.stroke == pytest.approx(s, rel=1e-9)
    assert b.stiffness == pytest.approx(a.stiffness, rel=1e-7)
    p, q = ev.points["P"], evf.points["P"]
    size = p.norm
    for i in range(2):
        assert abs(p.deviation[i] - q.deviation[i]) <= 1e-8 * size
        assert p.rigid[i] == pytest.approx(q.rigid[i], abs=1e-15)
    assert evf.buckling is None or evf.buckling > 1  # a force actuator counts as a load
    assert set(ev.points) == {"P"} and set(ev.stiffness) <= {"P"}


def test_equilibrium_actuator_stiffness_against_central_differences(parallelogram):
    """dF/ds against central differences of the force the equilibrium reports, and the
    lumped-plate estimate 4 EI/(l L^2) of a parallelogram with four plates (EI with E' =
    E/(1 - nu^2), plates wider than 5 thicknesses), to 1 % at a small stroke."""
    _, an = parallelogram
    s, h = 1e-3, 1e-6
    mid = symkin.evaluate(an, {"piezo": s}, "equilibrium").actuators["piezo"]
    plus = symkin.evaluate(an, {"piezo": s + h}, "equilibrium").actuators["piezo"]
    minus = symkin.evaluate(an, {"piezo": s - h}, "equilibrium").actuators["piezo"]
    assert mid.stiffness == pytest.approx((plus.force - minus.force) / (2 * h), rel=1e-6)
    E, nu, b, t, l, L = 210e9, 0.3, 10e-3, 0.15e-3, 5e-3, 0.040
    ei = E / (1 - nu**2) * b * t**3 / 12
    assert mid.stiffness == pytest.approx(4 * ei / (l * L**2), rel=0.01)
    # work: the force is the stroke's derivative of the elastic energy (no loads)
    e_plus = symkin.evaluate(an, {"piezo": s + h}, "equilibrium").energy
    e_minus = symkin.evaluate(an, {"piezo": s - h}, "equilibrium").energy
    assert mid.force == pytest.approx((e_plus - e_minus) / (2 * h), rel=1e-6)


def test_equilibrium_stroke_rigid_reference_is_the_kinematic_one(parallelogram):
    """At equilibrium the rigid reference is the rigid linkage at the stroke: the same rigid
    pose as the kinematic levels give, and the compliant point meets the stroke."""
    _, an = parallelogram
    s = 2e-3
    ev = symkin.evaluate(an, {"piezo": s}, "equilibrium")
    ref = parallelogram_reference(s, "exact")
    for i in range(2):
        assert ev.points["P"].rigid[i] == pytest.approx(float(ref["rigid"][i]), abs=1e-15)
    assert ev.angles_rigid["F1"] == pytest.approx(float(ref["q_r"]), rel=1e-12)
    # the stage's point of action is at the stroke in the compliant mechanism too: the
    # deviation along x of P is the stage's rotation times P's height above that point
    phi = ev.links["stage"].compliant
    assert ev.points["P"].deviation[0] == pytest.approx(-0.010 * math.sin(phi), rel=1e-6)


def test_piezo_amplifier_example_against_reference_solver():
    """examples/piezo_amplifier.toml (a Scott-Russell amplifier pushed by a piezo on its
    slider) at the rigid level against the oracle driven by the slider's hinge RA0 at the angle
    where the piezo's point (39.392, -40) mm has moved by the stroke along -x (secant method);
    the output B rises by about 27 times the stroke."""
    mech = symkin.load(ROOT / "examples" / "piezo_amplifier.toml")
    text = (ROOT / "examples" / "piezo_amplifier.toml").read_text()
    hinged = symkin.loads(
        text.rsplit("[[actuator]]", 1)[0].replace(
            'plate_angle = "pi/2"\n', 'plate_angle = "pi/2"\ninput = true\n', 1
        ),
        "hinged.toml",
    )
    assert hinged.inputs == ("RA0",)
    ref = Reference(hinged)
    s = mpmath.mpf("0.02")
    with mpmath.workdps(40):
        at = (40 * mpmath.cos(mpmath.pi / 18), mpmath.mpf(-40))

        def stroke(q):
            sol = ref.solve({"RA0": q}, model_override="rigid", dps=40)
            return -(rocker_point(sol, at, "slider")[0] - at[0]) - s, sol

        q0, q1 = mpmath.mpf(0), mpmath.mpf("0.001")
        f0, f1 = stroke(q0)[0], stroke(q1)[0]
        while abs(f1) > mpmath.mpf(10) ** -30:
            q0, q1 = q1, q1 - f1 * (q1 - q0) / (f1 - f0)
            f0, (f1, sol) = f1, stroke(q1)
    an = symkin.analyze(mech)
    b0 = 2 * 20 * math.sin(math.radians(10))
    for backend in BACKENDS:
        ev = symkin.evaluate(an, {"piezo": 0.02}, "exact", backend=backend)
        for i in range(2):
            assert ev.points["B"].rigid[i] == pytest.approx(float(sol["points"]["B"][i]), abs=1e-12)
        assert ev.angles_rigid["RA0"] == pytest.approx(float(q1), rel=1e-12)
    assert 25 < (ev.points["B"].rigid[1] - b0) / 0.02 < 29


def test_report_sweeps_the_stroke(tmp_path):
    """The report's deviation plot sweeps the actuator's stroke (derive --range sets it), in
    the file's unit, and states which hinge's angle the stroke fixes."""
    out = subprocess.run(
        [
            sys.executable,
            "-m",
            "symkin",
            "derive",
            str(ROOT / "examples" / "piezo_amplifier.toml"),
            "--emit",
            "latex",
            "--range",
            "piezo=0:0.05",
            "-o",
            str(tmp_path),
        ],
        capture_output=True,
        text=True,
    )
    assert out.returncode == 0, out.stderr
    tex = (tmp_path / "piezo_amplifier.tex").read_text()
    assert r"stroke of piezo from $0$ to $0.05$~$\mathrm{mm}$" in tex
    assert "the actuator piezo pushes its link" in tex and "(RA0)" in tex
    assert "@piezo" not in tex


def test_direction_over_the_parameters_is_normalised_and_checked(tmp_path):
    """A direction written over a parameter, ["-1/z", 0]: sympy normalises it to -x/|x| (an
    Abs, which the file's numbers are evaluated through) and the pose is the example's with its
    literal [-1, 0]; z = 0 makes it infinite: exit 2 naming the actuator, not an internal
    error."""
    text = (ROOT / "examples" / "piezo_amplifier.toml").read_text()
    text = text.replace("\nh = 10 ", "\nz = 1\nh = 10 ", 1).replace(
        "direction = [-1.0, 0.0]", 'direction = ["-1/z", 0]', 1
    )
    path = tmp_path / "piezo_z.toml"
    path.write_text(text)
    base = symkin.evaluate(
        symkin.analyze(symkin.load(ROOT / "examples" / "piezo_amplifier.toml")),
        {"piezo": 0.01},
        "exact",
        backend="sympy",
    )
    ev = symkin.evaluate(
        symkin.analyze(symkin.load(path)), {"piezo": 0.01}, "exact", {"z": 2.0}, backend="sympy"
    )
    for i in range(2):
        assert ev.points["B"].deviation[i] == pytest.approx(
            base.points["B"].deviation[i], rel=1e-12
        )
    run = symkin_cli("eval", str(path), "--input", "piezo=0.01", "--param", "z=0")
    assert run.returncode == 2, run.stderr
    assert "[[actuator]] 'piezo'" in run.stderr and "not a finite number" in run.stderr


def test_a_chosen_variant_takes_the_strokes(four_bar, tmp_path):
    """What derive --tolerance writes once the trade chose a variant (here paper/taylor2, its
    plates' deviation truncated): its numpy module takes the strokes and gives the sympy
    backend's deviation of the same variant's analysis."""
    import importlib.util

    from symkin.kinematics.variants import analysis_for
    from symkin.studies.derive import generate

    mech, _ = four_bar
    variant = Variant("paper", "taylor2")
    files = generate(mech, ("numpy",), variant=variant)
    (name,) = [n for n in files if n.endswith(".py")]
    (tmp_path / name).write_bytes(files[name])
    spec = importlib.util.spec_from_file_location("variant", tmp_path / name)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    assert module.INPUTS == ("pusher",)
    res = module.evaluate({"pusher": 1e-4}, "paper")
    ref = symkin.evaluate(analysis_for(mech, variant), {"pusher": "1e-4"}, "paper").points["C"]
    assert list(res["points"]["C"]["deviation"]) == pytest.approx(ref.deviation, rel=1e-10)


def test_a_stroke_past_the_toggle_names_the_stroke():
    """tests/mechanisms/toggle_four_bar.toml pushed along -x at its crank's tip A = (0, r): the
    rigid tip moves by r sin q, and the coupler-rocker dyad is straight at q* = 0.35 rad, so
    the rigid linkage reaches strokes up to r sin q* = 68.587 um (hand computation). Just below,
    the surrogate O1 sits at asin(s/r); just past, no pose reaches the stroke (exit 3 naming it,
    not the surrogate's trial angle past the toggle that Newton's differences stepped to)."""
    text = (ROOT / "tests" / "mechanisms" / "toggle_four_bar.toml").read_text()
    push = '\n[[actuator]]\nname = "push"\nlink = "crank"\nat = [0, "r"]\ndirection = [-1, 0]\n'
    an = symkin.analyze(symkin.loads(stroke_driven(text, "O1", push), "toggle_stroke.toml"))
    r, reach = 200.0, 200.0 * math.sin(0.35)
    below = symkin.evaluate(an, {"push": repr(reach - 0.05)}, "exact")
    assert below.angles_rigid["O1"] == pytest.approx(math.asin((reach - 0.05) / r), rel=1e-12)
    with pytest.raises(symkin.SymkinError) as err:
        symkin.evaluate(an, {"push": repr(reach + 0.05)}, "exact")
    assert err.value.exit_code == 3
    assert "push=68.6" in str(err.value) and "no pose of the rigid linkage" in str(err.value)


def test_check_prints_a_cad_direction_as_its_value():
    """A direction exported with CAD noise normalises to a long exact form (600000000001 *
    sqrt(...)/...): `symkin check` prints its value to 12 digits; short forms stay exact."""
    from symkin.cli.output import check_text

    noisy = stroke_driven(PARALLELOGRAM, "F1", PIEZO).replace(
        "direction = [1.0, 0.0]", "direction = [0.600000000001, 0.79999999999]"
    )
    text = check_text(symkin.analyze(symkin.loads(noisy, "noisy.toml")).structure)
    norm = math.hypot(0.600000000001, 0.79999999999)
    want = f"along ({0.600000000001 / norm:.12g}, {0.79999999999 / norm:.12g})"
    assert want in text and "sqrt" not in text, (want, text)
    plain = stroke_driven(PARALLELOGRAM, "F1", PIEZO)
    assert "at (w/2, L) along (1, 0)" in check_text(symkin.analyze(symkin.loads(plain)).structure)


@pytest.mark.parametrize("backend", ["c", "numpy"])
def test_stroke_solves_meet_the_40_digit_path_alone_or_in_a_batch(backend):
    """The generated evaluators' stroke solves (forward differences once, then secant steps,
    the compliant solve from the rigid one's Jacobian, one more step once met; templates/c/
    actuators.c, and symkin/studies/stroke_solver.py in numpy) give the piezo amplifier's rigid
    and compliant B and its deviation within 3e-13 mm of the 40-digit path (B's coordinates are
    7-8 mm) from 1e-4 to 0.05 mm of stroke, and each row the same bits alone as in a batch: no
    warm start from a neighbour."""
    an = symkin.analyze(symkin.load(ROOT / "examples" / "piezo_amplifier.toml"))
    c = symkin.compile(an, backend, levels=["exact"], sensitivity=False)
    strokes = [1e-4, 0.001, 0.013, 0.03, 0.05]
    batch = c.evaluate({"piezo": np.array(strokes)}, "exact")
    for k, s in enumerate(strokes):
        ref = symkin.evaluate(an, {"piezo": repr(s)}, "exact", backend="sympy").points["B"]
        alone = c.evaluate({"piezo": np.array([s])}, "exact")
        for key in ("rigid", "compliant", "deviation"):
            got = np.asarray(batch["points"]["B"][key])[:, k]
            assert max(abs(got - np.array(getattr(ref, key)))) <= 3e-13, (s, key)
            assert np.array_equal(np.asarray(alone["points"]["B"][key])[:, 0], got), (s, key)
