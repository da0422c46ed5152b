"""Actuators at the `loaded` level (docs/physics.md, "Actuators at loaded"): the reduced
equilibrium with a stroke actuator (its force one more unknown, its point's deviation along the
line of action one more row) or a force actuator (a dead load t·F·d), the surrogate hinge not
held. References, none of them the code under test:

- the `equilibrium` level (geometrically exact beams, another solver) on a stroke-driven
  parallelogram, the piezo amplifier example and a force-driven parallelogram carrying a payload:
  deviations, the actuator's stroke, force and dF/ds, plate stresses, point stiffness, buckling;
- the force a stroke-driven parallelogram reports, applied by a force actuator, reaches the same
  stroke and deviation;
- dF/ds against central differences of the force in the stroke, the force against the stroke
  derivative of the elastic energy (no loads), and the lumped-plate estimate 4 EI/(l L²);
- the stage's point stiffness against central differences of a small load added at the point,
  the mechanism solved again with the stroke held.
"""

from __future__ import annotations

import json
import math

import mechanisms as M
import numpy as np
import pytest
from conftest import EXAMPLES
from evaluators import GENERATED, backends_with

import symkin
from symkin.cli.commands import main
from symkin.core import backends
from symkin.core.errors import InputError
from symkin.physics import reduced_reported
from symkin.studies.physical import reduced_equilibrium

PAYLOAD = '\n[[load]]\npoint = "P"\nforce = [0.0, -5.0]\n'
E_PRIME, WIDTH, THICK, PLATE, LEG = 210e9 / (1 - 0.3**2), 10e-3, 0.15e-3, 5e-3, 0.040


driven = M.parallelogram_driven


def five_bar(drive: str) -> str:
    """The five-bar of tests/mechanisms/five_bar.toml (a load at T) with its input hinge O1
    kept and O2 passive, an actuator pushing its crank c2 along x: inputs of both kinds."""
    text = M.made_passive((M.ZOO / "five_bar.toml").read_text(), "O2")
    actuator = M.PIEZO.replace('"stage"', '"c2"').replace('["w/2", "L"]', "[0.040, 0.012]")
    return text + actuator.format(drive=drive)


CASES = {
    "parallelogram_stroke": (lambda: driven(), {"piezo": 1.5e-3}),
    "piezo_amplifier": (lambda: (EXAMPLES / "piezo_amplifier.toml").read_text(), {"piezo": 0.02}),
    "parallelogram_force_payload": (lambda: driven("force", PAYLOAD), {"piezo": 0.5}),
    "five_bar_hinge_and_force": (lambda: five_bar("force"), {"O1": 0.03, "piezo": 0.5}),
}
#: loaded against equilibrium (relative; deviation: of |dR|; K: of each row's largest entry):
#: the plate relation's quartic truncation. Measured, largest of deviation, stroke, force,
#: dF/ds, stress, K: 2.5e-8 (parallelogram), 2.1e-6 (piezo amplifier), 4.1e-7 (payload),
#: 3.7e-6 (five-bar, its K; the deviations 6.1e-7).
AGREEMENT = {
    "parallelogram_stroke": 1e-7,
    "piezo_amplifier": 1e-5,
    "parallelogram_force_payload": 2e-6,
    "five_bar_hinge_and_force": 1e-5,
}


@pytest.fixture(scope="module")
def evaluated():
    """Both levels' evaluations, by case (computed on first use)."""
    cache: dict = {}

    def get(name: str):
        if name not in cache:
            text, inputs = CASES[name]
            an = symkin.analyze(symkin.loads(text(), f"{name}.toml"))
            cache[name] = tuple(
                symkin.evaluate(an, inputs, level) for level in ("loaded", "equilibrium")
            )
        return cache[name]

    return get


def relative(a: float, b: float) -> float:
    return abs(a - b) / abs(b)


@pytest.mark.parametrize("name", list(CASES))
def test_loaded_with_actuators_against_equilibrium(evaluated, name):
    ours, exact = evaluated(name)
    tol = AGREEMENT[name]
    assert ours.level == "loaded" and set(ours.points) == set(exact.points)
    assert ours.inputs == exact.inputs
    for p, q in exact.points.items():
        got = ours.points[p]
        # a force actuator's rigid reference is at the stroke it produced, which the levels
        # find to their own accuracy
        close = 1e-15 * max(map(abs, q.rigid)) + tol * abs(exact.actuators["piezo"].stroke)
        assert got.rigid == pytest.approx(q.rigid, abs=close)
        assert math.dist(got.deviation, q.deviation) <= tol * q.norm, p
    for link, q in exact.links.items():
        # the links' rotations agree a little less (the parallelogram's legs: 2.5e-7)
        assert abs(ours.links[link].deviation - q.deviation) <= 10 * tol * max(
            abs(v.deviation) for v in exact.links.values()
        ), link
    assert set(ours.actuation) == set(exact.actuation)
    for h, q in exact.actuation.items():  # the input hinges held beside the actuator
        assert ours.actuation[h].angle == q.angle
        assert relative(ours.actuation[h].moment, q.moment) <= tol, h
        assert relative(ours.actuation[h].stiffness, q.stiffness) <= tol, h
    assert set(ours.actuators) == set(exact.actuators) == {"piezo"}
    a, b = ours.actuators["piezo"], exact.actuators["piezo"]
    assert relative(a.stroke, b.stroke) <= tol
    assert relative(a.force, b.force) <= tol
    assert relative(a.stiffness, b.stiffness) <= tol
    for h, plate in exact.plates.items():
        assert relative(ours.plates[h].stress, plate.stress) <= tol, h
    assert set(ours.stiffness) == set(exact.stiffness)
    for p, k in exact.stiffness.items():
        if k is None:
            assert ours.stiffness[p] is None
            continue
        want, got = np.array(k), np.array(ours.stiffness[p])
        scale = np.abs(want).max(axis=1, keepdims=True)
        assert np.all(np.abs(got - want) <= tol * scale), (got, want)
    assert set(ours.compliance) == set(exact.compliance) == set(exact.stiffness)
    for p, c in exact.compliance.items():  # a point a stroke holds along its line: C, no K
        want, got = np.array(c), np.array(ours.compliance[p])
        scale = np.abs(want).max(axis=1, keepdims=True)
        assert np.all(np.abs(got - want) <= tol * scale), (p, got, want)
    if exact.buckling is None or math.isinf(exact.buckling):
        assert ours.buckling == exact.buckling
    else:
        assert relative(ours.buckling, exact.buckling) <= 1e-3  # measured 2.9e-4


def test_the_payload_sways_the_force_driven_stage_near_the_lumped_estimate():
    """Nothing holds the force-driven stage sideways but its plates: at zero force the payload
    W sways it where its geometric softening reaches the plates' lateral stiffness. Lumped: the
    legs turn by q about the plate midpoints against 4 EI/l, the stage moves by x = L q and
    drops by (L - l/3) q²/2 (the rigid legs' L - l and two circular arcs shortening by l q²/6
    each), so dF/dx = 4 EI/(l L²) - W (L - l/3)/L² and W_cr = 4 EI/(l (L - l/3)); the plates'
    own compression softens them a little more (measured 0.55 % and 0.16 %)."""
    an = symkin.analyze(symkin.loads(driven("force", PAYLOAD), "sway.toml"))
    ours = symkin.evaluate(an, {"piezo": 0.0}, "loaded")
    a = ours.actuators["piezo"]
    assert abs(a.stroke) < 1e-15 * LEG
    ei, drop = E_PRIME * WIDTH * THICK**3 / 12, LEG - PLATE / 3
    assert a.stiffness == pytest.approx(4 * ei / (PLATE * LEG**2) - 5.0 * drop / LEG**2, rel=0.01)
    assert ours.buckling * 5.0 == pytest.approx(4 * ei / (PLATE * drop), rel=0.01)


def test_legs_held_by_a_stroke_buckle_together_at_eulers_load():
    """The stroke-driven stage at zero stroke under a payload W: the actuator holds the stage
    sideways, so each leg buckles by translating sideways between its two plates, both bent as
    clamped-guided columns: W_cr = 2 pi^2 E'I/l^2 (Euler, the leg's load W/2 per plate).
    `loaded` finds it (a plate at its sway load; measured 0.18 % below Euler: the legs' turn
    couples in). The two identical legs buckle at one load, two eigenvalues of the tangent
    stiffness crossing zero together, which leaves det J's sign: `equilibrium` finds it by the
    eigenvalues of J⁻¹J_new between its steps (docs/physics.md, "The buckling factor"); with one
    leg's plates 0.2 % thicker the two loads part, each leg at its own (measured: equilibrium
    and loaded within 1e-7 of each other on both)."""
    w = 300.0
    euler = 2 * math.pi**2 * E_PRIME * WIDTH * THICK**3 / 12 / PLATE**2
    text = driven("stroke", PAYLOAD.replace("-5.0", f"-{w}"))
    thicker = text.replace('"right"]\n', '"right"]\nthickness = 0.1503e-3\n')
    thicker = thicker.replace('["right", "stage"]\n', '["right", "stage"]\nthickness = 0.1503e-3\n')
    assert thicker.count("0.1503e-3") == 2
    for what in (text, thicker):
        an = symkin.analyze(symkin.loads(what, "w.toml"))
        factor = symkin.evaluate(an, {"piezo": 0.0}, "loaded").buckling
        assert factor * w == pytest.approx(euler, rel=5e-3)
        exact = symkin.evaluate(an, {"piezo": 0.0}, "equilibrium").buckling
        assert exact == pytest.approx(factor, rel=1e-6)


def test_the_force_a_stroke_needs_reaches_that_stroke(evaluated):
    """A force actuator at the force a stroke-driven parallelogram reports reaches the same
    stroke and deviation at `loaded` (the rigid reference at the stroke the force produced)."""
    ev, _ = evaluated("parallelogram_stroke")
    a = ev.actuators["piezo"]
    assert a.stroke == 1.5e-3
    force = symkin.analyze(symkin.loads(driven("force"), "force.toml"))
    evf = symkin.evaluate(force, {"piezo": a.force}, "loaded")
    b = evf.actuators["piezo"]
    assert b.force == a.force and b.stroke == pytest.approx(a.stroke, rel=1e-9)
    assert b.stiffness == pytest.approx(a.stiffness, rel=1e-7)
    p, q = ev.points["P"], evf.points["P"]
    assert math.dist(p.deviation, q.deviation) <= 1e-8 * p.norm
    assert p.rigid == pytest.approx(q.rigid, abs=1e-15)
    assert ev.buckling is None and evf.buckling is not None and evf.buckling > 1


def solve(an, inputs, params=None):
    answer = reduced_equilibrium(an, inputs, params, backend="numpy")
    assert not answer.refused, answer.refused
    return answer


def test_actuator_stiffness_against_central_differences():
    """dF/ds against central differences of the force, the force against the stroke derivative
    of the elastic energy, and the lumped-plate estimate 4 EI/(l L²) (1 %)."""
    an = symkin.analyze(symkin.loads(driven(), "stroke.toml"))
    s, h = 1e-3, 1e-6

    def at(stroke: float):
        answer = solve(an, {"piezo": stroke})
        return answer, reduced_reported.report(answer, 1.0, buckling=False).actuators["piezo"]

    (_, a), (plus, ap), (minus, am) = at(s), at(s + h), at(s - h)
    assert a.stroke == s and a.force > 0
    assert a.stiffness == pytest.approx((ap.force - am.force) / (2 * h), rel=1e-7)
    assert a.force == pytest.approx((plus.energy - minus.energy) / (2 * h), rel=1e-7)
    ei = E_PRIME * WIDTH * THICK**3 / 12
    assert a.stiffness == pytest.approx(4 * ei / (PLATE * LEG**2), rel=0.01)


def test_stage_stiffness_under_a_force_actuator_by_central_differences():
    """The stage point's K, the actuator's force held, against central differences of the
    solver under a small load added at P. (A held stroke makes it infinitely stiff along the
    line of action: K null, as at equilibrium.)"""
    text = driven("force").replace("[parameters]\n", "[parameters]\nvx = 0\nvy = 0\nvm = 0\n")
    text += '\n[[load]]\npoint = "P"\nforce = ["vx", "vy"]\nmoment = "vm"\n'
    an = symkin.analyze(symkin.loads(text, "stage.toml"))
    inputs = {"piezo": 0.5}
    answer = solve(an, inputs)
    want = np.array(reduced_reported.report(answer, 1.0, buckling=False).stiffness["P"])
    red = answer.solver
    names = {a: h.name for a, h in red.hinges.items()}
    link = red.points["P"][0]

    def state(answer) -> np.ndarray:
        # P's compliant displacement: each solve's rigid reference is at the stroke it
        # produced, where the rigid stage has translated by (s, -L (1 - cos q)), sin q = -s/L
        s = answer.strokes["piezo"]
        rigid = (s, -LEG * (1 - math.cos(math.asin(-s / LEG))))
        turn = math.fsum(
            red.hinges[b].sign * answer.angle_deviations[names[b]] for b in red.paths[link]
        )
        dx, dy = answer.deviations["P"]
        return np.array([rigid[0] + dx, rigid[1] + dy, turn])

    def column(key: str, h: float) -> np.ndarray:
        pair = [state(solve(an, inputs, {key: repr(float(s * h))})) for s in (1, -1)]
        return (pair[0] - pair[1]) / (2 * h)

    # Richardson's extrapolation of two central differences, steps large enough that the
    # solutions' rounding (the stage's sway is 1e6 times softer than its plates' stretch) stays
    # far below the differences (1e-4 F: 7e-7 off)
    steps = [1e-2 * red.F, 1e-2 * red.F, 1e-2 * red.F * red.L]
    columns = [
        (4 * column(key, h / 2) - column(key, h)) / 3
        for key, h in zip(("vx", "vy", "vm"), steps, strict=True)
    ]
    got = np.linalg.inv(np.array(columns).T)
    scale = np.abs(want).max(axis=1, keepdims=True)
    assert np.all(np.abs(got - want) <= 5e-8 * scale), (got, want)  # measured 7.5e-9


@pytest.mark.parametrize("drive, value", [("stroke", 1.5e-3), ("force", 0.5)])
def test_sensitivities_by_the_drive_and_the_parameters_against_central_differences(drive, value):
    """eval --sensitivity at `loaded` with an actuator: the surrogate's rigid angle moves with
    the parameters and the drive (a stroke: the rigid stroke equation; a force: the reference
    at the stroke it produced), the reduced equilibrium with it; against central differences of
    the solver's deviations (the parameters changed in the file, the drive given; steps of 1e-4
    of the value, the force's reference being met to 1e-14 of the size). The piezo sits at
    (w/2, L): w and L move its point too."""
    an = symkin.analyze(symkin.loads(driven(drive), f"{drive}.toml"))
    ev = symkin.evaluate(an, {"piezo": value}, "loaded", sensitivity=True)
    sens = ev.sensitivity
    assert set(sens.deviation) == {"P"} and set(sens.deviation_inputs["P"]) == {"piezo"}

    def deviation(given: float, params=None) -> np.ndarray:
        found = reduced_equilibrium(an, {"piezo": given}, params, backend="sympy")
        return np.array(found.deviations["P"])

    wanted = {"piezo": sens.deviation_inputs["P"]["piezo"]} | sens.deviation["P"]
    defaults = {"piezo": value, "L": 0.040, "w": 0.030, "l": 5e-3}
    for name, rate in wanted.items():
        h = 1e-4 * defaults[name]
        if name == "piezo":
            pair = [deviation(value + k * h) for k in (1, -1)]
        else:
            pair = [deviation(value, {name: repr(defaults[name] + k * h)}) for k in (1, -1)]
        got = (pair[0] - pair[1]) / (2 * h)
        # measured: up to 1.6e-7 of the rate's size (w of the force-driven stage)
        assert np.linalg.norm(got - np.array(rate)) <= 1e-6 * np.linalg.norm(got), name


@pytest.mark.parametrize("drive, value", [("stroke", 2e-4), ("force", 0.5)])
def test_sensitivities_by_an_input_hinge_beside_an_actuator(drive, value):
    """The five-bar (a load at T) with O1 held and an actuator on its other crank: the
    deviations' rates by O1 and by the stroke or force against central differences (measured
    1.7e-11 and 4.8e-12 with the stroke; 1.1e-9 with the force, steps 1e-4 of the value)."""
    an = symkin.analyze(symkin.loads(five_bar(drive), f"five_bar_{drive}.toml"))
    inputs = {"O1": 0.03, "piezo": value}
    sens = symkin.evaluate(an, inputs, "loaded", sensitivity=True).sensitivity
    assert set(sens.deviation_inputs["T"]) == {"O1", "piezo"}
    # a force's reference is met to 1e-14 of the size: larger steps there
    steps = {"O1": 1e-6, "piezo": 1e-8} if drive == "stroke" else {"O1": 3e-6, "piezo": 5e-5}
    for name, h in steps.items():
        pair = [
            reduced_equilibrium(an, inputs | {name: inputs[name] + k * h}, backend="sympy")
            for k in (1, -1)
        ]
        for p in ("T", "Q"):
            got = (np.array(pair[0].deviations[p]) - np.array(pair[1].deviations[p])) / (2 * h)
            rate = np.array(sens.deviation_inputs[p][name])
            assert np.linalg.norm(got - rate) <= 1e-8 * np.linalg.norm(got), (p, name)


def test_the_solvers_agree_across_backends():
    """The reduced equilibrium with the piezo in mpmath and in float64 kernels."""
    an = symkin.analyze(symkin.load(EXAMPLES / "piezo_amplifier.toml"))
    a = solve(an, {"piezo": 0.02})
    b = reduced_equilibrium(an, {"piezo": 0.02}, backend="sympy")
    for name, d in a.deviations.items():
        assert math.dist(d, b.deviations[name]) <= 1e-12 * math.hypot(*d), name
    assert a.strokes == b.strokes == {"piezo": 0.02}


def test_cli(tmp_path, capsys):
    """eval --json reports the actuator (and the sensitivities by it); what loaded with
    actuators does not do yet (the C's sensitivities with a force) is bad input (exit 2) naming
    the actuator."""
    path = EXAMPLES / "piezo_amplifier.toml"
    assert main(["eval", str(path), "--input", "piezo=0.02", "--level", "loaded", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["level"] == "loaded" and set(out["actuators"]) == {"piezo"}
    assert out["actuators"]["piezo"]["stroke"] == 0.02 and out["actuators"]["piezo"]["force"] > 0
    assert "@piezo" not in out["points"] and "@piezo" not in out["stiffness"]
    # the generated numpy and C take the stroke (tests/test_loaded_actuators_codegen.py)
    args = ["eval", str(path), "--input", "piezo=0.02", "--level", "loaded", "--json"]
    loaded = backends_with(generated=True, levels="loaded", actuators="loaded")
    assert loaded == GENERATED
    for backend in loaded:
        assert main([*args, "--backend", backend]) == 0
        got = json.loads(capsys.readouterr().out)["points"]["B"]["deviation"]
        assert math.dist(got, out["points"]["B"]["deviation"]) <= 1e-9 * math.hypot(*got)
    # the C's loaded sensitivities with a stroke are the numpy module's
    # (test_loaded_actuators_sens_codegen); with a force it has none (below)
    rates = {}
    for backend in loaded:
        assert main([*args, "--backend", backend, "--sensitivity"]) == 0
        rates[backend] = json.loads(capsys.readouterr().out)["sensitivity"]["B"]
    first = rates[loaded[0]]
    for backend in loaded[1:]:
        for q, v in first.items():
            assert math.dist(rates[backend][q], v) <= 1e-9 * max(
                math.hypot(*w) for w in first.values()
            ), backend
    # sensitivities by the drive (tests above), in the JSON too
    force = tmp_path / "force.toml"
    force.write_text(driven("force"))
    argv = ["eval", str(force), "--input", "piezo=0.5", "--level", "loaded", "--sensitivity"]
    assert main([*argv, "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert set(out["sensitivity_inputs"]["P"]) == {"piezo"} and "@piezo" not in out["sensitivity"]
    an = symkin.analyze(symkin.load(force))
    for backend in GENERATED:
        with pytest.raises(InputError, match="piezo"):  # a force needs a physical level
            symkin.evaluate(an, {"piezo": 0.5}, "exact", backend=backend)
    # the commands that evaluate through generated code (an internal error before): tolerance
    # needs the sensitivities, which the C lacks with a force; sweep runs the C, which takes a
    # force at loaded
    vary = ["--level", "loaded", "--vary", "l=±1e-5"]
    lacking = [b for b in GENERATED if "loaded" not in backends.get(b).force_sensitivities]
    assert lacking  # the C (the table, tests/test_backends.py)
    for backend in lacking:
        tolerance = ["tolerance", str(force), "--input", "piezo=0.5", *vary]
        assert main([*tolerance, "--backend", backend]) == 2
        assert "actuator 'piezo'" in capsys.readouterr().err
    sweep = ["sweep", str(force), "--input", "piezo=0:0.5:3", "--samples", "2", *vary, "--json"]
    assert main(sweep) == 0
    assert json.loads(capsys.readouterr().out)
