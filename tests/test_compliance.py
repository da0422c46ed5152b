"""The points' compliance beside their stiffness at the physical levels (docs/physics.md, "What
equilibrium reports"): C = d(ΔX, ΔY, Δφ)/d(Fx, Fy, M) with the inputs held, K = C⁻¹, either
null where it does not exist, and the text's stiffness along each direction with the other two
free, 1/C_ii.

References, none of them the code under test: central differences of the `equilibrium` level
under a small [[load]] added at the point in the file (the force or the moment alone, the
mechanism solved again, the point's deviation and its link's rotation measured); the
fixed–guided plate's closed forms (a lone plate whose input holds its end's rotation at 0 rad:
12 E'I/l³ for the elastica, l³/(12 E'I) + l/(κGA) and l/(E'A) with Reissner's stretch and
shear; E', I, κGA, EA written in tests/mechanisms.py from the documented rules); the identity
C K = I; matrices built here whose singular side is known.
"""

from __future__ import annotations

import json
import math

import mechanisms as M
import numpy as np
import pytest
from cli_runs import symkin_cli
from conftest import ROOT
from evaluators import require_compiler
from test_loaded_reported_codegen import c_report

import symkin
from symkin.codegen import pipeline
from symkin.core.settings import SOLVER
from symkin.physics.reported import stiffness_and_compliance

ZOO = ROOT / "tests" / "mechanisms"
#: a load (Fx, Fy, M) at the stage's point P, zero by default
PROBE = '\n[[load]]\npoint = "P"\nforce = ["fx", "fy"]\nmoment = "fm"\n'


def probed(extra: str = ""):
    """The parallelogram stage with the probe load's parameters (and `extra` text)."""
    text = (ZOO / "parallelogram.toml").read_text()
    text = text.replace("[parameters]\n", "[parameters]\nfx = 0\nfy = 0\nfm = 0\n")
    return symkin.analyze(symkin.loads(text + PROBE + extra, "parallelogram.toml"))


def rows_close(got, want, tol: float) -> bool:
    got, want = np.asarray(got, dtype=float), np.asarray(want, dtype=float)
    scale = np.abs(want).max(axis=1, keepdims=True)
    return bool(np.all(np.abs(got - want) <= tol * scale))


@pytest.fixture(scope="module")
def stage():
    """The deflected stage (F1 = 0.05 held) at both physical levels, and its compliance by
    central differences of `equilibrium` under the probe load: column j from ±h in Fx, Fy or M
    (h = 1e-3 of the plates' load scale E'I/(l L), about 3 mN), the rows P's deviation and the
    stage's rotation."""
    an = probed()
    inputs = {"F1": 0.05}
    ei = 210e9 / (1 - 0.3**2) * 10e-3 * 0.15e-3**3 / 12
    force = ei / (5e-3 * 0.040)
    steps = {"fx": 1e-3 * force, "fy": 1e-3 * force, "fm": 1e-3 * force * 0.040}
    columns = []
    for key, h in steps.items():
        pair = []
        for sign in (1, -1):
            res = symkin.evaluate(an, inputs, "equilibrium", {key: sign * h})
            pair.append(np.array([*res.points["P"].deviation, res.links["stage"].deviation]))
        columns.append((pair[0] - pair[1]) / (2 * h))
    return (
        {lv: symkin.evaluate(an, inputs, lv) for lv in ("loaded", "equilibrium")},
        np.array(columns).T,
    )


@pytest.mark.parametrize("level", ["equilibrium", "loaded"])
def test_compliance_and_directional_stiffness_by_differences_of_the_equilibrium(stage, level):
    """C, and 1/C_ii (the stiffness along x, y, rotation with the other two free), against the
    equilibrium's own displacement under a small force or moment at the point."""
    results, want = stage
    res = results[level]
    got = np.array(res.compliance["P"])
    # measured: equilibrium 6.0e-10 (the differences' truncation), loaded 4.6e-7 (the plate
    # relation's truncation against the exact beam), of each row's largest entry
    tol = {"equilibrium": 1e-8, "loaded": 2e-6}[level]
    assert rows_close(got, want, tol), (got, want)
    directional = res.directional("P")
    for i in range(3):
        assert directional[i] == pytest.approx(1 / want[i, i], rel=tol), i
    assert np.allclose(np.array(res.stiffness["P"]) @ got, np.eye(3), rtol=0, atol=1e-9)


def test_a_deflected_stage_is_far_softer_across_with_its_rotation_free(stage):
    """The stage's stiffness across its legs with its rotation free (1/C_xx) against the 3×3
    K_xx, which holds the rotation: at F1 = 0.05 the stage tilts under a sideways force and is
    softer by a factor 3.1 (measured 3.170e4 against 9.970e4 N/m); the reference is the
    difference quotient of the equilibrium's own displacement."""
    results, want = stage
    res = results["equilibrium"]
    kxx = res.stiffness["P"][0][0]
    assert 1 / want[0, 0] < kxx / 2.5
    assert res.directional("P")[0] == pytest.approx(1 / want[0, 0], rel=1e-8)


# -- the fixed–guided plate: a lone plate whose held input holds its end's rotation ------------


def fixed_guided(beam: str) -> tuple[float, float]:
    """The lone plate's compliance across (x) and along (y) its axis at its held end (mm/N):
    Reissner's l³/(12 E'I) + l/(κGA) and l/(E'A), the elastica's l³/(12 E'I) and 0."""
    length = 0.01  # m
    ei = M.bending_stiffness(5, 0.3, 1e-3)
    across = length**3 / (12 * ei)
    if beam == "elastica":
        return across * 1e3, 0.0
    return (
        (across + length / M.shear_stiffness(5, 0.3, 1e-3)) * 1e3,
        length / M.axial_stiffness(5, 0.3, 1e-3) * 1e3,
    )


@pytest.mark.parametrize("beam", ["elastica", "reissner"])
@pytest.mark.parametrize("level", ["loaded", "equilibrium"])
def test_a_plate_held_at_zero_is_a_fixed_guided_beam(beam, level):
    """The input held at 0 rad holds the arm's rotation: K does not exist (null), C does, with
    12 E'I/l³ across for the elastica (Reissner's adds its shear), its rotation row and column
    0. Off zero (0.02 rad) the same: the held input is an input like any other."""
    an = symkin.analyze(symkin.loads(M.lone_plate(beam=beam), "lone_plate.toml"))
    across, along = fixed_guided(beam)
    for theta in (0.0, 0.02):
        res = symkin.evaluate(an, {"A": theta}, level)
        assert res.stiffness == {"T": None}
        c = np.array(res.compliance["T"])
        assert np.all(c[2] == 0) and np.all(c[:, 2] == 0), c
        if theta == 0:
            assert c[0, 0] == pytest.approx(across, rel=1e-9)  # measured 6.7e-16
            assert c[1, 1] == pytest.approx(along, rel=1e-9, abs=1e-18)
            assert c[0, 1] == c[1, 0] == 0
            x, y, rotation = res.directional("T")
            assert x == pytest.approx(1 / across, rel=1e-9) and rotation is None
            assert (y is None) == (beam == "elastica")
        else:  # bent: across and along couple; near the straight plate's across (1.2e-4)
            assert c[0, 0] == pytest.approx(across, rel=1e-3)


def test_the_fixed_guided_plate_in_every_generated_backend():
    """The numpy module's "compliance" and the C's block after the report's: the same closed
    form at 0 rad, K NaN, C's rotation row and column exactly 0."""
    an = symkin.analyze(symkin.loads(M.lone_plate(beam="elastica"), "lone_plate.toml"))
    # with sensitivities: a loop-free evaluator without them leaves runtime.c's sk_solve unused
    plan, module = pipeline.build(an, "numpy", "test")
    across, _ = fixed_guided("elastica")
    got = {"numpy": module.evaluate({"A": np.array([0.0, 0.02])}, "loaded")}
    require_compiler()
    got["c"] = c_report(plan, {"A": [0.0, 0.02]})
    for backend, res in got.items():
        assert np.isnan(res["stiffness"]["T"]).all(), backend
        c = res["compliance"]["T"]
        assert c.shape == (3, 3, 2)
        assert c[0, 0, 0] == pytest.approx(across, rel=1e-9), backend
        assert np.all(c[2] == 0) and np.all(c[:, 2] == 0), backend
        assert c[0, 0, 1] == pytest.approx(across, rel=1e-3), backend
    # to rounding (the same solves in another order), the zeros alike
    assert np.allclose(
        got["numpy"]["compliance"]["T"], got["c"]["compliance"]["T"], rtol=1e-12, atol=0
    )


def test_the_text_and_the_json_of_a_held_plate(tmp_path):
    """`eval` prints the stiffness along each direction with the others free, its units, and
    `held` for the held rotation; the JSON holds C, K null, and never an infinity."""
    path = tmp_path / "lone_plate.toml"
    path.write_text(M.lone_plate(beam="elastica"))
    args = ("eval", str(path), "--input", "A=0", "--level", "loaded")
    text, js = symkin_cli(*args), symkin_cli(*args, "--json")
    assert text.returncode == js.returncode == 0, (text.stderr, js.stderr)
    out, jout = text.stdout, js.stdout
    across, _ = fixed_guided("elastica")
    lines = out.splitlines()
    title = "point stiffness along each direction, the other two free (1/C_ii, the inputs held)"
    at = lines.index(title)
    heading = ["point", "x", "(N/mm)", "y", "(N/mm)", "rotation", "(N", "mm/rad)"]
    assert lines[at + 1].split() == heading
    name, x, y, rotation = lines[at + 2].split()
    assert name == "T" and float(x) == pytest.approx(1 / across, rel=1e-6)
    assert y == rotation == "held"  # the elastica does not stretch

    def refuse(constant: str):
        raise AssertionError(f"{constant} in the JSON")

    data = json.loads(jout, parse_constant=refuse)
    assert data["stiffness"] == {"T": None}
    assert data["compliance"]["T"][0][0] == pytest.approx(across, rel=1e-9)


# -- which one is null --------------------------------------------------------------------------


def test_compliance_times_stiffness_is_the_identity():
    """Every point of mechanisms unlike each other, at `loaded`: where both exist C K = I."""
    cases = {
        "parallelogram": ({"F1": 0.05}, "P"),
        "double_parallelogram": ({"F1": 0.01, "I1": -0.01}, "S"),
        "scott_russell": ({"RA0": 0.02}, "B"),
        "five_bar_coupler_input": ({"O1": 0.02, "P": 0.02}, "T"),
    }
    for name, (inputs, point) in cases.items():
        res = symkin.evaluate(symkin.analyze(symkin.load(ZOO / f"{name}.toml")), inputs, "loaded")
        for p, k in res.stiffness.items():
            if k is None:
                continue
            product = np.array(res.compliance[p]) @ np.array(k)
            assert np.allclose(product, np.eye(3), rtol=0, atol=1e-9), (name, p, product)
        assert res.stiffness[point] is not None, name


SCALES = (2.0, 3.0)  # L (file unit) and F (N) the matrices below are judged in


def scaled_back(s: np.ndarray) -> np.ndarray:
    """The compliance in file units whose scaled form (reported.stiffness_and_compliance's) is
    s: rows times L/F, L/F, 1/F, columns times 1, 1, L."""
    length, force = SCALES
    rows = np.array([length / force, length / force, 1 / force])[:, None]
    return s * rows * np.array([1.0, 1.0, length])


@pytest.fixture(scope="module")
def runtime():
    """The numpy runtime's rule (symkin/physics/stiffness_rule.py, held by the module), from a
    generated module."""
    an = symkin.analyze(symkin.loads(M.lone_plate(), "lone_plate.toml"))
    _, module = pipeline.build(an, "numpy", "test", sensitivity=False)
    length, force = SCALES
    scales = np.array([force / length, force / length, force]), np.array([1, 1, 1 / length])

    def rule(c):
        k, comp = module._stiffness_compliance(np.array([c]), scales, SOLVER.loaded.singular)
        return k[0], comp[0]

    return rule


def test_the_singular_side_decides_which_one_is_null(runtime):
    """Matrices whose singular side is known (in the plates' scale): a held direction (scaled
    compliance 1e-20, or exactly 0) leaves C with that entry 0 and no K; a free one (1e20) K
    with that stiffness ~1e-20 and no C; a regular one both; a C not finite neither. The
    numpy runtime decides the same."""
    rot = np.array([[0.8, -0.6, 0.0], [0.6, 0.8, 0.0], [0.0, 0.0, 1.0]])
    regular = rot @ np.diag([1.0, 1e-3, 0.5]) @ rot.T
    cases = {
        "regular": scaled_back(regular),
        "held": scaled_back(np.diag([1.0, 1e-3, 1e-20])),
        "held exactly": scaled_back(np.diag([1.0, 1e-3, 0.0])),
        "held along a slant": scaled_back(rot @ np.diag([1.0, 0.0, 0.5]) @ rot.T),
        "free": scaled_back(np.diag([1.0, 1e-3, 1e20])),
        "not finite": scaled_back(np.diag([1.0, math.inf, 1.0])),
    }
    for name, c in cases.items():
        k, comp = stiffness_and_compliance(c, *SCALES)
        nk, ncomp = runtime(c)
        assert np.isnan(nk).all() == (k is None) and np.isnan(ncomp).all() == (comp is None)
        if k is not None:
            assert np.allclose(np.array(k) @ c, np.eye(3), atol=1e-9) or name == "free"
            assert np.allclose(nk, k, rtol=1e-12, atol=0), name
        if comp is not None:
            assert np.array_equal(ncomp, comp), name
        assert (k is None, comp is None) == {
            "regular": (False, False),
            "held": (True, False),
            "held exactly": (True, False),
            "held along a slant": (True, False),
            "free": (False, True),
            "not finite": (True, True),
        }[name], name
    # the held direction's rounding is exactly 0, the rest as computed
    _, comp = stiffness_and_compliance(cases["held"], *SCALES)
    assert comp[2][2] == 0.0 and comp[0][0] == cases["held"][0][0]
    # the free direction: the scaled stiffness 1e-20 along it, the others as the inverse's
    k, _ = stiffness_and_compliance(cases["free"], *SCALES)
    assert np.allclose(np.array(k), np.linalg.inv(cases["free"]), rtol=1e-12, atol=0)
