"""Natural frequencies (`symkin modes`, docs/physics.md "Natural frequencies") against
independent references written here: a parallelogram stage of leaf-spring legs (its sway
(1/2π)√(24EI/(L³m)) and its axial mode (1/2π)√(2EA/(Lm))), two such stages stacked (a 2-DOF
chain solved here by its characteristic polynomial), a hand-built compliance and mass matrix,
and a stage preloaded toward its buckling load (the beam-column's sway stiffness)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from cli_runs import symkin_cli
from conftest import ROOT

import symkin
from symkin.core.errors import AssemblyError, InputError
from symkin.physics import modes as physical_modes
from symkin.studies.modes import modes

E, NU, WIDTH, THICK = 210e9, 0.3, 10.0, 0.2  # Pa, -, mm, mm: b = 50 t, a wide plate
LEG, SPACING, GAP = 40.0, 30.0, 1e-3  # mm: the leaf's length, the legs' spacing, a tiny joint
E_WIDE = E / (1 - NU**2)  # plane strain (docs/physics.md)
EI = E_WIDE * (WIDTH * 1e-3) * (THICK * 1e-3) ** 3 / 12  # N m²
EA = E_WIDE * (WIDTH * 1e-3) * (THICK * 1e-3)  # N
KGA = 5 / 6 * E / (2 * (1 + NU)) * (WIDTH * 1e-3) * (THICK * 1e-3)  # N


def legs(bottom: str, top: str, base: float, tag: str) -> str:
    """Two leaf-spring legs from link `bottom` (at height `base`) to link `top`: each leaf two
    plates of (LEG - GAP)/2 joined by a massless link GAP long (the reader wants plates shorter
    than the links between them), vertical, SPACING apart."""
    half = (LEG - GAP) / 2
    out = []
    for side, x in (("l", 0.0), ("r", SPACING)):
        mid = f"{tag}{side}"
        out.append(f'[[link]]\nname = "{mid}"\n')
        for name, pair, y in (
            (f"{mid}0", (bottom, mid), base + half / 2),
            (f"{mid}1", (mid, top), base + LEG - half / 2),
        ):
            out.append(
                f'[[hinge]]\nname = "{name}"\nlinks = ["{pair[0]}", "{pair[1]}"]\n'
                f'at = [{x}, {y}]\nplate_angle = "pi/2"\n'
            )
    return "\n".join(out)


HEAD = f"""format = 1
name = "stage"
units = "mm"
ground = "frame"

[parameters]
m = 0.1
P = 0

[defaults]
model = "circular_arc"
length = {(LEG - GAP) / 2}
E = {E}
nu = {NU}
thickness = {THICK}
width = {WIDTH}

[[link]]
name = "frame"
"""


def stage(inertia: float = 0.0, load: bool = False) -> str:
    """One stage of mass m on two leaf-spring legs, pushed sideways by a force actuator (held
    at its force: the sway is free); its centre at the legs' mid-height (their inflection
    points: a sideways force there turns nothing)."""
    text = (
        HEAD
        + f'[[link]]\nname = "stage"\nmass = "m"\ninertia = {inertia}\n'
        + f"centre = [{SPACING / 2}, {LEG / 2}]\n"
        + legs("frame", "stage", 0.0, "a")
        + f'[[actuator]]\nname = "push"\nlink = "stage"\nat = [{SPACING / 2}, {LEG}]\n'
        + 'direction = [1, 0]\ndrive = "force"\n'
        + f'[[point]]\nname = "top"\nlink = "stage"\nat = [{SPACING / 2}, {LEG}]\n'
    )
    if load:
        text += f'[[load]]\nlink = "stage"\nat = [{SPACING / 2}, {LEG}]\nforce = [0, "-P"]\n'
    return text


def stacked() -> str:
    """Stage 2 (mass m2) on legs standing on stage 1 (mass m1), each pushed by its own force
    actuator; the centres at their legs' mid-heights."""
    return (
        HEAD.replace("m = 0.1", "m1 = 0.3\nm2 = 0.1")
        + f'[[link]]\nname = "one"\nmass = "m1"\ncentre = [{SPACING / 2}, {LEG / 2}]\n'
        + f'[[link]]\nname = "two"\nmass = "m2"\ncentre = [{SPACING / 2}, {1.5 * LEG}]\n'
        + legs("frame", "one", 0.0, "a")
        + legs("one", "two", LEG, "b")
        + f'[[actuator]]\nname = "p1"\nlink = "one"\nat = [{SPACING / 2}, {LEG}]\n'
        + 'direction = [1, 0]\ndrive = "force"\n'
        + f'[[actuator]]\nname = "p2"\nlink = "two"\nat = [{SPACING / 2}, {2 * LEG}]\n'
        + 'direction = [1, 0]\ndrive = "force"\n'
    )


def sway(m: float) -> float:
    """(1/2π)√(24EI/(L³m)): two fixed-guided leaves."""
    return math.sqrt(24 * EI / ((LEG * 1e-3) ** 3 * m)) / (2 * math.pi)


def axial(m: float) -> float:
    """(1/2π)√(2EA/(Lm)): two leaves in tension."""
    return math.sqrt(2 * EA / (LEG * 1e-3 * m)) / (2 * math.pi)


def leaf_stiffness(P: float = 0.0) -> float:
    """A fixed-guided leaf's sideways stiffness (N/m) under a compression P (N), with its
    shear and the rigid joint GAP in the middle: each half a cantilever to the inflection point
    at mid-length; for P > 0 the beam-column's P/(L (tan u/u - 1)), u = (L/2)√(P/EI)."""
    L, a, l = LEG * 1e-3, LEG * 1e-3 / 2, (LEG - GAP) * 1e-3 / 2
    if P == 0:
        bend = 2 * (a**3 - (a - l) ** 3) / (3 * EI)  # both halves, the joint rigid
        return 1 / (bend + 2 * l / KGA)
    u = L / 2 * math.sqrt(P / EI)
    return P / (L * (math.tan(u) / u - 1))


def file(tmp_path, text: str):
    path = tmp_path / "stage.toml"
    path.write_text(text)
    return path


@pytest.mark.parametrize("level", ["loaded", "equilibrium"])
def test_a_free_stage_sways_and_stretches_as_the_formulas_say(level):
    m = 0.1
    mech = symkin.loads(stage(), "stage.toml")
    found = modes(mech, {"push": 0}, level, count=3)
    assert len(found.frequencies) == 2  # the stage's rotation has no inertia: condensed
    f1, f2 = found.frequencies
    assert f1 == pytest.approx(sway(m), rel=1e-3)
    assert f2 == pytest.approx(axial(m), rel=1e-3)
    # closer, with the leaves' shear and the joint: the reference of the same model
    assert f1 == pytest.approx(math.sqrt(2 * leaf_stiffness() / m) / (2 * math.pi), rel=1e-6)
    k_axial = 2 / (2 * (LEG - GAP) / 2 * 1e-3 / EA)
    assert f2 == pytest.approx(math.sqrt(k_axial / m) / (2 * math.pi), rel=1e-6)
    # the shapes: sideways, then along the legs, each normalised to +1 mm
    first, second = found.links
    assert first["stage"][0] == 1 and abs(first["stage"][1]) < 1e-9
    assert second["stage"][1] == 1 and abs(second["stage"][0]) < 1e-6
    assert found.points[0]["top"][0] == pytest.approx(1, abs=1e-9)


def test_inertia_adds_the_rotation_mode():
    """The stage's rotation rides on the legs' axial stiffness: k = 2 (EA/L)(w/2)² about the
    middle of the legs (its centre); with an inertia I the third mode is √(k/I)/2π, a pure
    rotation normalised to 1 rad."""
    inertia = 2e-5
    found = modes(symkin.loads(stage(inertia), "stage.toml"), {"push": 0}, count=3)
    assert len(found.frequencies) == 3
    k_rot = 2 * (EA / (LEG * 1e-3)) * (SPACING * 1e-3 / 2) ** 2
    # the legs' bending adds a little to the rotation's stiffness: a few (t/w)² parts
    assert found.frequencies[2] == pytest.approx(
        math.sqrt(k_rot / inertia) / (2 * math.pi), rel=1e-3
    )
    assert found.links[2]["stage"][2] == 1.0
    assert abs(found.links[2]["stage"][0]) < 1e-6 and abs(found.links[2]["stage"][1]) < 1e-6


def test_two_stacked_stages_are_a_two_mass_chain():
    """k1 = k2 = 2 k_leaf, masses m1, m2: K = [[k1 + k2, -k2], [-k2, k2]], M = diag(m1, m2);
    ω² from det(K - ω² M) = 0 by the quadratic formula, and the shape's ratio x1/x2."""
    m1, m2 = 0.3, 0.1
    k = 2 * leaf_stiffness()
    a, b, c = m1 * m2, -((k + k) * m2 + k * m1), k * k
    roots = sorted((-b + s * math.sqrt(b * b - 4 * a * c)) / (2 * a) for s in (-1, 1))
    found = modes(symkin.loads(stacked(), "stacked.toml"), {"p1": 0, "p2": 0}, count=2)
    for f, w2 in zip(found.frequencies, roots):
        assert f == pytest.approx(math.sqrt(w2) / (2 * math.pi), rel=1e-4)
    for shape, w2 in zip(found.links, roots):
        ratio = k / (2 * k - w2 * m1)  # x1/x2 from the first row
        assert shape["one"][0] / shape["two"][0] == pytest.approx(ratio, rel=1e-3)
        assert max(abs(shape["one"][0]), abs(shape["two"][0])) == 1.0


def test_the_eigen_solve_against_a_hand_built_model():
    """Two point masses on springs, given as a compliance (file unit mm): a hand-built K, its
    inverse, and the frequencies from det(K - ω² M) = 0; a rigid direction (zero compliance)
    is left out, and a negative stiffness is refused."""
    k1, k2, k3 = 3.0e4, 1.0e4, 2.0e4  # N/m: ground-1, 1-2, 2-ground, along x
    m1, m2 = 0.2, 0.05
    K = np.array([[k1 + k2, -k2], [-k2, k2 + k3]])
    a, b, c = m1 * m2, -((k1 + k2) * m2 + (k2 + k3) * m1), np.linalg.det(K)
    expected = sorted(math.sqrt((-b + s * math.sqrt(b * b - 4 * a * c)) / (2 * a)) for s in (-1, 1))
    C = np.zeros((6, 6))  # rows and columns x, y, φ of two centres; y and φ held rigidly
    C[np.ix_([0, 3], [0, 3])] = np.linalg.inv(K) * 1e3  # m/N -> mm/N
    found = physical_modes.solve(C, [(m1, 0.0), (m2, 0.0)], 1e-3, 10.0)
    assert [mode.frequency * 2 * math.pi for mode in found] == pytest.approx(expected, rel=1e-12)
    lowest = found[0].shape
    w2 = expected[0] ** 2
    assert lowest[0] / lowest[3] == pytest.approx(k2 / (k1 + k2 - w2 * m1), rel=1e-9)
    with pytest.raises(AssemblyError, match="unstable"):
        physical_modes.solve(-C, [(m1, 0.0), (m2, 0.0)], 1e-3, 10.0)


def test_a_preload_softens_the_stage_toward_its_buckling_load(tmp_path):
    """A compressive load P on the stage: the sway frequency falls monotonically, as the
    beam-column's sideways stiffness P/(L (tan u/u - 1)) says, toward zero at the buckling
    load symkin reports (eval's buckling factor), 2π²EI/L² for the two legs."""
    m = 0.1
    path = file(tmp_path, stage(load=True))
    run = symkin_cli(
        "eval", str(path), "--input", "push=0", "--level", "loaded", "--param", "P=10", "--json"
    )
    assert run.returncode == 0, run.stderr
    critical = json.loads(run.stdout)["buckling"] * 10  # N
    assert critical == pytest.approx(2 * math.pi**2 * EI / (LEG * 1e-3) ** 2, rel=2e-3)
    mech = symkin.load(path)
    previous = math.inf
    for share in (0.0, 0.3, 0.6, 0.8, 0.9, 0.95):
        load = share * critical
        f = modes(mech, {"push": 0}, params={"P": load}, count=1).frequencies[0]
        expected = math.sqrt(2 * leaf_stiffness(load / 2) / m) / (2 * math.pi)
        assert f == pytest.approx(expected, rel=2e-3), share
        # the shape f0 √(1 - P/P_cr) holds to a few percent: the beam-column's stiffness is
        # nearly linear in P
        assert f / sway(m) == pytest.approx(math.sqrt(1 - share), rel=0.05, abs=0.01), share
        assert f < previous
        previous = f
    assert previous < 0.25 * sway(m)


def test_the_equilibrium_level_agrees_under_a_preload():
    mech = symkin.loads(stage(load=True), "stage.toml")
    load = 0.5 * 2 * math.pi**2 * EI / (LEG * 1e-3) ** 2
    loaded = modes(mech, {"push": 0}, "loaded", {"P": load}, 1).frequencies[0]
    exact = modes(mech, {"push": 0}, "equilibrium", {"P": load}, 1).frequencies[0]
    expected = math.sqrt(2 * leaf_stiffness(load / 2) / 0.1) / (2 * math.pi)
    assert loaded == pytest.approx(expected, rel=2e-3)
    assert exact == pytest.approx(expected, rel=2e-3)


def guided(total: float, plate: float, ei: float, kga: float) -> float:
    """The sideways stiffness (N/m) of a leg clamped to two links that do not turn: `plate`
    of it flexible at either end (m), rigid between, `total` from clamp to clamp (one plate
    alone: plate = total/2): each half a cantilever to the inflection point in the middle,
    bending and shear."""
    a = total / 2
    return 1 / (2 * ((a**3 - (a - plate) ** 3) / (3 * ei) + plate / kga))


PARALLELOGRAM = (ROOT / "tests" / "mechanisms" / "parallelogram_mm.toml").read_text()


def test_holding_a_parallelograms_input_hinge_locks_its_sway():
    """The lumped parallelogram (short plates on rigid legs): its input hinge F1 held, the left
    leg cannot turn and the sway bends F1 and S1 as fixed-guided plates; driven by a force
    actuator held at zero, both legs turn freely. Each against the legs' beam formulas; the
    free stage's first mode is about ten times lower (docs/physics.md)."""
    mass, leg, plate, t = 0.1, 40e-3, 5e-3, 0.15e-3
    ei = E_WIDE * 10e-3 * t**3 / 12
    kga = 5 / 6 * E / (2 * (1 + NU)) * 10e-3 * t
    text = PARALLELOGRAM.replace(
        '[[link]]\nname = "stage"\n', '[[link]]\nname = "stage"\nmass = 0.1\ncentre = [15, 40]\n'
    )
    free_text = text.replace("input = true\n", "") + (
        '[[actuator]]\nname = "push"\nlink = "stage"\nat = [15, 40]\ndirection = [1, 0]\n'
        'drive = "force"\n'
    )
    held = modes(symkin.loads(text, "held.toml"), {"F1": 0}, count=1).frequencies[0]
    free = modes(symkin.loads(free_text, "free.toml"), {"push": 0}, count=1).frequencies[0]
    swinging = guided(leg + plate, plate, ei, kga)  # a leg whose ends' links do not turn
    locked = guided(plate, plate / 2, ei, kga) / 2  # F1 and S1 each fixed-guided, in series
    assert free == pytest.approx(math.sqrt(2 * swinging / mass) / (2 * math.pi), rel=1e-3)
    assert held == pytest.approx(math.sqrt((locked + swinging) / mass) / (2 * math.pi), rel=1e-3)
    assert 8 < held / free < 12


def test_the_command_prints_text_and_the_contract_json(tmp_path):
    path = file(tmp_path, stage())
    run = symkin_cli("modes", str(path), "--input", "push=0", "--json", "--count", "2")
    assert run.returncode == 0, run.stderr
    data = json.loads(run.stdout)
    assert set(data) == {"level", "frequencies", "modes"} and data["level"] == "loaded"
    assert data["frequencies"][0] == pytest.approx(sway(0.1), rel=1e-3)
    assert set(data["modes"][0]) == {"links", "points"}
    assert (
        data["modes"][0]["links"]["stage"][0] == 1.0
        and len(data["modes"][0]["links"]["stage"]) == 3
    )
    assert len(data["modes"][0]["points"]["top"]) == 2
    text = symkin_cli("modes", str(path), "--input", "push=0", "--level", "equilibrium")
    assert text.returncode == 0, text.stderr
    assert "mode 1: 12.08" in text.stdout and "link stage" in text.stdout, text.stdout


def test_bad_requests_exit_2(tmp_path):
    massless = tmp_path / "massless.toml"
    massless.write_text(stage().replace('mass = "m"\ninertia = 0.0\ncentre = [15.0, 20.0]\n', ""))
    run = symkin_cli("modes", str(massless), "--input", "push=0")
    assert run.returncode == 2 and "no link has a mass" in run.stderr and "fix:" in run.stderr
    path = file(tmp_path, stage())
    run = symkin_cli("modes", str(path), "--input", "push=0", "--level", "exact")
    assert run.returncode == 2
    run = symkin_cli("modes", str(path), "--input", "push=0", "--count", "0")
    assert run.returncode == 2 and "--count" in run.stderr
    run = symkin_cli("modes", str(path), "--input", "push=0", "--param", "m=0")
    assert run.returncode == 2 and "mass must be positive" in run.stderr
    with pytest.raises(InputError):
        modes(symkin.load(path), {}, "loaded")
