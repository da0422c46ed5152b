"""A stroke actuator with a series spring (docs/file-format.md, `[[actuator]]`; docs/physics.md,
"Actuators at loaded"): the input is the free stroke s commanded, the actual stroke s − F/k, the
rigid reference at s. The mechanism is the parallelogram stage pushed along x on its stage
(tests/test_loaded_actuators.py's), in metres. References, none of them the spring's code path:

- the lumped stage stiffness K_m = 4 E'I/(l L²) (two legs, each turning about its two plates):
  a series spring k then gives the actual stroke s k/(k + K_m) and the force K_m times it;
- the force-driven stage (a force actuator, another code path) at the force the spring reports:
  the same actual stroke and compliant pose;
- the ideal stroke actuator (no spring) at the command: a very stiff spring reproduces it;
- `equilibrium` (geometrically exact beams, another solver) against `loaded`, and the generated
  numpy and C against the Python level;
- central differences of the deviation in the spring's parameter.
"""

from __future__ import annotations

import ctypes
import json
import math

import mechanisms as M
import numpy as np
import pytest
from evaluators import require_compiler
from test_loaded_reported_codegen import c_report

import symkin
from symkin.cli.commands import main
from symkin.codegen import pipeline

E_PRIME, WIDTH, THICK, PLATE, LEG = 210e9 / (1 - 0.3**2), 10e-3, 0.15e-3, 5e-3, 0.040
#: the lumped stage stiffness along x (N/m): 4 E'I/(l L²)
K_STAGE = 4 * E_PRIME * WIDTH * THICK**3 / 12 / (PLATE * LEG**2)


def sprung(spring: str | float, drive: str = "stroke") -> str:
    """The stroke-driven parallelogram with `spring = <spring>` on its actuator, and a
    parameter kp (300 N/m) the spring may read."""
    text = M.parallelogram_driven(drive)
    text = text.replace("[parameters]\n", "[parameters]\nkp = 300.0\n", 1)
    value = json.dumps(spring) if isinstance(spring, str) else repr(spring)
    return text.replace(f'drive = "{drive}"\n', f'drive = "{drive}"\nspring = {value}\n')


@pytest.fixture(scope="module")
def stage():
    return symkin.analyze(symkin.loads(sprung("kp"), "sprung.toml"))


def test_series_spring_against_the_lumped_stage():
    """A small command (linear): the actual stroke s k/(k + K_m), the force K_m × stroke and the
    stroke lost F/k, K_m the lumped estimate (1 %, as the ideal stage's dF/ds against it); the
    deviation shows the lost motion. Measured against the lumped figures: stroke 0.27 %, force
    0.52 %, dF/ds 0.25 %; P's deviation along x against the stroke lost 3.9e-6."""
    s, k = 1e-4, 300.0
    an = symkin.analyze(symkin.loads(sprung(k), "k.toml"))
    ev = symkin.evaluate(an, {"piezo": s}, "loaded")
    a = ev.actuators["piezo"]
    assert a.command == s
    assert a.stroke == pytest.approx(s * k / (k + K_STAGE), rel=0.01)
    assert a.force == pytest.approx(K_STAGE * a.stroke, rel=0.01)
    assert s - a.stroke == pytest.approx(a.force / k, rel=1e-12)
    # dF/ds by the command: the two springs in series
    assert a.stiffness == pytest.approx(k * K_STAGE / (k + K_STAGE), rel=0.01)
    # the stage translates: P lags the rigid stage at the command by the stroke lost
    assert ev.points["P"].deviation[0] == pytest.approx(a.stroke - s, rel=1e-3)


def test_the_force_that_compresses_the_spring_drives_the_stage_as_far(stage):
    """The force-driven stage at the force the spring reports reaches the actual stroke, and
    its compliant pose is the spring's (the references differ: the command, the stroke)."""
    s = 1.5e-3
    ev = symkin.evaluate(stage, {"piezo": s}, "loaded")
    a = ev.actuators["piezo"]
    force = symkin.analyze(symkin.loads(M.parallelogram_driven("force"), "force.toml"))
    b = symkin.evaluate(force, {"piezo": a.force}, "loaded")
    assert b.actuators["piezo"].stroke == pytest.approx(a.stroke, rel=1e-9)
    p, q = ev.points["P"], b.points["P"]
    assert math.dist(p.compliant, q.compliant) <= 1e-9 * p.norm
    # the rigid reference at the command: the ideal stroke actuator's
    ideal = symkin.analyze(symkin.loads(M.parallelogram_driven(), "ideal.toml"))
    assert p.rigid == pytest.approx(symkin.evaluate(ideal, {"piezo": s}, "exact").points["P"].rigid)


def test_a_very_stiff_spring_is_the_ideal_actuator():
    s = 1.5e-3
    ideal = symkin.analyze(symkin.loads(M.parallelogram_driven(), "ideal.toml"))
    stiff = symkin.analyze(symkin.loads(sprung(1e12), "stiff.toml"))
    for level in ("loaded", "equilibrium"):
        a = symkin.evaluate(ideal, {"piezo": s}, level)
        b = symkin.evaluate(stiff, {"piezo": s}, level)
        # the stroke lost, F/k = 1e-13 m, against |ΔR| 1.5e-3 m
        assert math.dist(a.points["P"].deviation, b.points["P"].deviation) <= 1e-9 * s
        assert b.actuators["piezo"].force == pytest.approx(a.actuators["piezo"].force, rel=1e-8)
        assert b.actuators["piezo"].stroke == pytest.approx(s, rel=1e-9)
        assert a.actuators["piezo"].command is None
    # the kinematic levels take the command as the stroke: the spring plays no part
    for level in ("exact", "first_order"):
        a = symkin.evaluate(ideal, {"piezo": s}, level).points["P"].deviation
        assert symkin.evaluate(stiff, {"piezo": s}, level).points["P"].deviation == a


def test_equilibrium_agrees_with_loaded(stage):
    """Measured (k = 300 N/m, 1.5 mm): 3.2e-10 (stroke), 2.9e-10 (force), 8.8e-10 (dF/ds),
    2.9e-10 of |ΔR| (deviation), the plate relation's truncation at loaded."""
    s = 1.5e-3
    lo = symkin.evaluate(stage, {"piezo": s}, "loaded")
    eq = symkin.evaluate(stage, {"piezo": s}, "equilibrium")
    a, b = lo.actuators["piezo"], eq.actuators["piezo"]
    assert b.command == a.command == s
    for key in ("stroke", "force", "stiffness"):
        assert getattr(a, key) == pytest.approx(getattr(b, key), rel=1e-8), key
    p, q = lo.points["P"], eq.points["P"]
    assert math.dist(p.deviation, q.deviation) <= 1e-8 * p.norm


def test_every_backend_agrees_at_loaded(stage):
    """The Python level (mpmath) against the generated numpy module's evaluate() and the C's
    <name>_loaded_report (their actual stroke from the point of action's deviation), 1e-9."""
    batch = [1.5e-3, -0.5e-3]
    want = [symkin.evaluate(stage, {"piezo": v}, "loaded") for v in batch]
    plan, module = pipeline.build(stage, "numpy", "test", sensitivity=False)
    got = module.evaluate({"piezo": np.array(batch)}, "loaded")
    require_compiler()
    lib = pipeline.evaluator(plan, "c", "test", links=False).lib
    from_c = c_report(plan, {"piezo": batch}, lib)
    for c, ref in enumerate(want):
        a = ref.actuators["piezo"]
        assert a.stroke != pytest.approx(a.command, rel=0.1)  # the spring gives most of it
        for found in (got["actuators"]["piezo"], from_c["actuators"]["piezo"]):
            assert found["stroke"][c] == pytest.approx(a.stroke, rel=1e-9)
            assert found["force"][c] == pytest.approx(a.force, rel=1e-9)
            assert found["stiffness"][c] == pytest.approx(a.stiffness, rel=1e-9)
        assert got["actuators"]["piezo"]["command"][c] == a.command
        dev = got["points"]["P"]["deviation"][:, c]
        assert math.dist(dev, ref.points["P"].deviation) <= 1e-9 * ref.points["P"].norm
    # the C evaluator's deviations too
    fn = getattr(lib, f"{plan.name}_evaluate")
    out = (ctypes.c_double * (6 * len(plan.shown_points)))()
    level = list(module.LEVELS).index("loaded")
    assert fn((ctypes.c_double * 1)(batch[0]), None, level, out) == 0
    i = plan.shown_points.index("P")
    assert math.dist(out[6 * i + 4 : 6 * i + 6], want[0].points["P"].deviation) <= 1e-9 * 1.5e-3


@pytest.mark.parametrize("backend", ["sympy", "numpy", "c"])
def test_the_spring_is_a_parameter_expression(stage, backend):
    """--param changes it; the loaded sensitivities by it and by the command are the central
    differences (every backend), and the one by k near the lumped d(−F/k)/dk = s K_m/(k + K_m)²
    (the stage translates with the actuator's point)."""
    if backend == "c":
        require_compiler()
    s, k, h, hs = 1.5e-3, 300.0, 1e-3, 1e-7
    base = symkin.evaluate(stage, {"piezo": s}, "loaded", sensitivity=True, backend=backend)
    softer = symkin.evaluate(stage, {"piezo": s}, "loaded", params={"kp": 150.0})
    assert softer.actuators["piezo"].stroke < base.actuators["piezo"].stroke

    def dev(stroke: float, spring: float) -> np.ndarray:
        ev = symkin.evaluate(stage, {"piezo": stroke}, "loaded", params={"kp": spring})
        return np.array(ev.points["P"].deviation)

    fd = (dev(s, k + h) - dev(s, k - h)) / (2 * h)
    rate = np.array(base.sensitivity.deviation["P"]["kp"])
    assert np.linalg.norm(rate - fd) <= 1e-6 * np.linalg.norm(fd)
    # measured 1.2e-5 (k near K_m: the lumped K_m's error nearly cancels)
    assert rate[0] == pytest.approx(s * K_STAGE / (k + K_STAGE) ** 2, rel=1e-3)
    fd = (dev(s + hs, k) - dev(s - hs, k)) / (2 * hs)
    rate = np.array(base.sensitivity.deviation_inputs["P"]["piezo"])
    assert np.linalg.norm(rate - fd) <= 1e-6 * np.linalg.norm(fd)


def test_cli_json_and_text(tmp_path, capsys):
    path = tmp_path / "sprung.toml"
    path.write_text(sprung(300.0))
    args = ["eval", str(path), "--input", "piezo=1.5e-3", "--level", "loaded"]
    assert main([*args, "--json"]) == 0
    got = json.loads(capsys.readouterr().out)["actuators"]["piezo"]
    assert list(got) == ["command", "stroke", "force", "stiffness"]
    assert got["command"] == 1.5e-3 and got["stroke"] == pytest.approx(
        1.5e-3 - got["force"] / 300.0, rel=1e-12
    )
    assert main(args) == 0
    assert "spring: commanded 1.500000000e-03 m" in capsys.readouterr().out
    # a plain stroke actuator has no "command" (its stroke is its input)
    plain = tmp_path / "plain.toml"
    plain.write_text(M.parallelogram_driven())
    assert main(["eval", str(plain), "--input", "piezo=1.5e-3", "--level", "loaded", "--json"]) == 0
    assert list(json.loads(capsys.readouterr().out)["actuators"]["piezo"]) == [
        "stroke",
        "force",
        "stiffness",
    ]


@pytest.mark.parametrize(
    ("text", "words"),
    [
        (sprung(300.0, "force"), ["'spring'", "force actuator", 'drive = "stroke"']),
        (sprung(-1.0), ["'spring' must be positive", "spring = -1"]),
        (sprung("1/(kp - 300)"), ["'spring'"]),
        (
            sprung(300.0).replace("spring = 300.0\n", "spring = 300.0\nstiffness = 300.0\n"),
            ["'spring' and 'stiffness'", "keep one"],
        ),
        (sprung(-2.0).replace("spring = ", "stiffness = "), ["'stiffness' must be positive"]),
    ],
)
def test_bad_springs_exit_2(tmp_path, capsys, text, words):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    assert main(["check", str(path)]) == 2
    err = capsys.readouterr().err
    assert str(path) in err and "[[actuator]] #1 'piezo'" in err and "fix:" in err
    for w in words:
        assert w in err, (w, err)


def test_fea_refuses_a_spring(tmp_path, capsys):
    path = tmp_path / "sprung.toml"
    path.write_text(sprung(300.0))
    assert main(["fea", str(path), "--input", "piezo=1e-3"]) == 2
    err = capsys.readouterr().err
    assert "series spring" in err and "'piezo'" in err and str(path) in err


def test_stiffness_is_the_spring_under_another_name():
    """`stiffness = k` (the name natural frequencies use) gives what `spring = k` gives."""
    named = {
        key: symkin.evaluate(
            symkin.analyze(symkin.loads(sprung(300.0).replace("spring = ", key), "k.toml")),
            {"piezo": 1e-4},
            "loaded",
        ).actuators["piezo"]
        for key in ("spring = ", "stiffness = ")
    }
    assert named["spring = "].stroke == named["stiffness = "].stroke
    assert named["spring = "].force == named["stiffness = "].force
