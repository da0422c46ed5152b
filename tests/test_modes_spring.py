"""Natural frequencies with a stroke actuator behind a series `spring` (docs/physics.md,
"Natural frequencies", "A stroke actuator with a spring"): the command s is held, not the actual
stroke, so the actuator is a spring k between the held command and its point of action. The
references, none of them the spring's code path (its row d·ΔX = −f/k in the level's equations):

- the leaf-spring stage of tests/test_modes.py pushed sideways at its centre's height: the legs
  and the spring side by side, the sway (1/2π)√((K_m + k)/m) with the legs' K_m = 2 k_leaf;
  k → ∞ the plain stroke actuator's modes (the sway held), k → 0 the force actuator's at zero
  force (the stage free);
- two stages stacked, the lower one massless and pushed: the spring beside the lower legs, both
  in series with the upper legs, (1/2π)√(K_e/m₂), K_e = k₂ (k₁ + k)/(k₁ + k₂ + k);
- an oblique spring on a pushed, preloaded stage with inertia: the compliance of the same stage
  driven by a force actuator at the force the spring reports (another code path), the spring
  added by Sherman–Morrison, C_k = C_f − C_f w wᵀ C_f / (1/k + wᵀ C_f w), and that 3×3
  eigenproblem solved here (numpy.linalg.eigvals of C_k M);
- the generated numpy module's modes() and `symkin modes --backend numpy` against the sympy path.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from cli_runs import symkin_cli
from test_modes import LEG, SPACING, leaf_stiffness, stacked, stage

import symkin
from symkin.studies.modes import modes

AGREE = 1e-9  # the backends and levels against each other, and the exact references
MASS = 0.1  # kg, the stage's (tests/test_modes.py)


def sprung(text: str, link: str, at: tuple[float, float], direction=(1, 0)) -> str:
    """`text` whose first force actuator becomes a stroke actuator at `at` on `link` along
    `direction` behind the spring ks (N/mm, a parameter)."""
    head, tail = text.split("[[actuator]]\n", 1)
    actuator, rest = tail.split('drive = "force"\n', 1)
    name = actuator.split("\n", 1)[0]
    entry = (
        f'[[actuator]]\n{name}\nlink = "{link}"\nat = [{at[0]}, {at[1]}]\n'
        f'direction = [{direction[0]}, {direction[1]}]\ndrive = "stroke"\nspring = "ks"\n'
    )
    return (head + entry + rest).replace("[parameters]\n", "[parameters]\nks = 300.0\n", 1)


def hz(stiffness: float, mass: float) -> float:
    return math.sqrt(stiffness / mass) / (2 * math.pi)


#: the stage pushed at its centre's height (a sideways force there turns nothing)
SIDEWAYS = sprung(stage(), "stage", (SPACING / 2, LEG / 2))


@pytest.mark.parametrize("level", ["loaded", "equilibrium"])
def test_the_spring_and_the_legs_side_by_side(level):
    """The actuator pushes the stage against the frame: the stage sways on the legs' K_m and
    the spring's k together. k in N/mm (the file unit), K_m in N/m."""
    mech = symkin.loads(SIDEWAYS, "sprung.toml")
    legs = 2 * leaf_stiffness()
    axial = None
    for k in (0.3, 3.0, 300.0):
        found = modes(mech, {"push": 0}, level, {"ks": k}, count=3)
        assert len(found.frequencies) == 2
        assert found.frequencies[0] == pytest.approx(hz(legs + 1e3 * k, MASS), rel=AGREE)
        assert found.links[0]["stage"][0] == 1.0 and abs(found.links[0]["stage"][1]) < AGREE
        axial = found.frequencies[1]  # along the legs: the spring plays no part
        assert found.links[1]["stage"][1] == 1.0
    # k → ∞: the plain stroke actuator, the sway held (its frequency beyond the axial mode)
    plain = SIDEWAYS.replace('spring = "ks"\n', "")
    held = modes(symkin.loads(plain, "plain.toml"), {"push": 0}, level, count=3)
    assert held.frequencies[0] == pytest.approx(axial, rel=AGREE)
    # the held sway: none at loaded; equilibrium's float64 Jacobian leaves a rounding's
    # compliance there (7e8 Hz, 1/ω² 1e-11 of the axial mode's, above SOLVER.modes.rigid)
    assert all(f > 1e5 * axial for f in held.frequencies[1:])
    stiff = modes(mech, {"push": 0}, level, {"ks": 1e9}, count=2)
    assert stiff.frequencies[0] == pytest.approx(axial, rel=AGREE)
    assert stiff.frequencies[1] == pytest.approx(hz(1e12, MASS), rel=1e-6)
    assert stiff.links[1]["stage"][0] == 1.0
    # k → 0: the force actuator at zero force, the stage free on its legs
    free = modes(symkin.loads(stage(), "free.toml"), {"push": 0}, level, count=1)
    loose = modes(mech, {"push": 0}, level, {"ks": 1e-10}, count=1)
    assert loose.frequencies[0] == pytest.approx(free.frequencies[0], rel=AGREE)
    assert free.frequencies[0] == pytest.approx(hz(legs, MASS), rel=AGREE)


def test_a_massless_pushed_stage_puts_the_spring_in_series():
    """Stage one (no mass) pushed along x behind the spring, stage two (m₂ = 0.1 kg) on legs
    standing on it: m₂ sees its own legs k₂ in series with stage one's legs k₁ and the spring
    side by side. The chain model leaves out stage one's rotation on its legs' stretch (as
    tests/test_modes.py's stacked stages, 8e-5 there): measured 2.2e-5 to 4.4e-5."""
    text = stacked().replace('mass = "m1"\n', "", 1)
    text = text.replace(f"centre = [{SPACING / 2}, {LEG / 2}]\n", "", 1)
    mech = symkin.loads(sprung(text, "one", (SPACING / 2, LEG)), "stacked.toml")
    k1 = k2 = 2 * leaf_stiffness()
    for level in ("loaded", "equilibrium"):
        for k in (1e-6, 3.0, 300.0, 1e9):
            spring = 1e3 * k
            found = modes(mech, {"p1": 0, "p2": 0}, level, {"ks": k}, count=1)
            series = k2 * (k1 + spring) / (k1 + k2 + spring)
            assert found.frequencies[0] == pytest.approx(hz(series, 0.1), rel=1e-4), (level, k)


OBLIQUE = (1, 0.5)


def oblique(drive: str) -> str:
    """The stage with inertia under the compressive load P, pushed at its top along OBLIQUE by
    a stroke actuator behind ks, or (drive "force") by a force actuator; a point at the
    centre."""
    text = stage(inertia=2e-5, load=True)
    if drive == "stroke":
        text = sprung(text, "stage", (SPACING / 2, LEG), OBLIQUE)
    else:
        text = text.replace("direction = [1, 0]", f"direction = [{OBLIQUE[0]}, {OBLIQUE[1]}]")
    return text + f'[[point]]\nname = "mid"\nlink = "stage"\nat = [{SPACING / 2}, {LEG / 2}]\n'


@pytest.mark.parametrize("level", ["loaded", "equilibrium"])
def test_the_spring_added_to_the_force_driven_compliance(level):
    """The spring's stiffness k w wᵀ added to the force-driven stage's tangent stiffness (the
    actuator's force the same dead load along d at its point, so the geometric terms agree):
    by Sherman–Morrison on the force-driven compliance C_f at the centre, w = (d_x, d_y,
    (a − c) × d) the actuator's unit force carried to the centre c from its point a (the
    compliant pose). Measured 1.8e-13."""
    command, load = 0.2, 3.0
    mech = symkin.loads(oblique("stroke"), "sprung.toml")
    driven = symkin.analyze(symkin.loads(oblique("force"), "force.toml"))
    for k in (0.5, 300.0):
        ev = symkin.evaluate(symkin.analyze(mech), {"push": command}, level, {"P": load, "ks": k})
        force = ev.actuators["push"].force
        by_force = symkin.evaluate(driven, {"push": force}, level, {"P": load})
        assert by_force.points["top"].compliant == pytest.approx(
            ev.points["top"].compliant, abs=1e-9
        )
        c_f = np.array(by_force.compliance["mid"])  # mm/N, 1/N, 1/(N mm)
        a = np.array(by_force.points["top"].compliant)
        c = np.array(by_force.points["mid"].compliant)
        d = np.array(OBLIQUE) / math.hypot(*OBLIQUE)
        w = np.array([d[0], d[1], (a - c)[0] * d[1] - (a - c)[1] * d[0]])
        c_k = c_f - np.outer(c_f @ w, c_f @ w) / (1 / k + w @ c_f @ w)
        # SI: rows (m, m, rad), columns (N, N, N m)
        c_si = np.diag([1e-3, 1e-3, 1.0]) @ c_k @ np.diag([1.0, 1.0, 1e3])
        inverse_w2 = np.linalg.eigvals(c_si @ np.diag([MASS, MASS, 2e-5])).real
        expected = sorted(1 / np.sqrt(inverse_w2) / (2 * math.pi))
        found = modes(mech, {"push": command}, level, {"P": load, "ks": k}, count=3)
        assert found.frequencies == pytest.approx(expected, rel=AGREE), k


@pytest.fixture(scope="module")
def compiled(tmp_path_factory):
    path = tmp_path_factory.mktemp("spring") / "oblique.toml"
    path.write_text(oblique("stroke"))
    return path, symkin.load(path), symkin.compile(path, backend="numpy").module


def test_the_numpy_module_holds_the_command_too(compiled):
    """modes() over a batch of springs and commands against the sympy path, every frequency
    and shape entry (measured 2.8e-11); the sideways stage's sway on the legs and the
    spring."""
    _, mech, module = compiled
    springs = np.array([0.5, 30.0, 300.0, 3000.0])
    commands = np.array([0.2, -0.1, 0.0, 0.2])
    batch = module.modes({"push": commands}, params={"ks": springs, "P": 3.0}, count=3)
    assert batch["ok"].all()
    for j, (k, s) in enumerate(zip(springs, commands)):
        reference = modes(mech, {"push": float(s)}, "loaded", {"ks": float(k), "P": 3.0}, 3)
        for i, f in enumerate(reference.frequencies):
            assert float(batch["frequencies"][i, j]) == pytest.approx(f, rel=AGREE)
            for name, v in reference.links[i].items():
                assert batch["links"][name][i, :, j] == pytest.approx(v, rel=AGREE, abs=AGREE)
            for name, v in reference.points[i].items():
                # a pure rotation normalised to 1 rad moves the top by ~50 mm: relative too
                assert batch["points"][name][i, :, j] == pytest.approx(v, rel=AGREE, abs=AGREE)
    legs = 2 * leaf_stiffness()
    sideways = symkin.compile(symkin.loads(SIDEWAYS, "sideways.toml"), backend="numpy").module
    found = sideways.modes({"push": 0.0}, params={"ks": np.array([0.3, 300.0])}, count=1)
    expected = [hz(legs + 1e3 * k, MASS) for k in (0.3, 300.0)]
    assert found["frequencies"][0] == pytest.approx(expected, rel=AGREE)


def test_the_command_with_backend_numpy(compiled):
    path, _, _ = compiled
    args = ["modes", str(path), "--input", "push=0.2", "--param", "P=3", "--param", "ks=30"]
    numpy_run = symkin_cli(*args, "--json", "--backend", "numpy")
    sympy_run = symkin_cli(*args, "--json")
    assert numpy_run.returncode == 0 and sympy_run.returncode == 0, numpy_run.stderr
    got, want = json.loads(numpy_run.stdout), json.loads(sympy_run.stdout)
    assert len(got["frequencies"]) == len(want["frequencies"]) == 3
    assert got["frequencies"] == pytest.approx(want["frequencies"], rel=AGREE)
    for mode, reference in zip(got["modes"], want["modes"]):
        for kind in ("links", "points"):
            for name, v in reference[kind].items():
                assert mode[kind][name] == pytest.approx(v, rel=AGREE, abs=AGREE)
