"""Beyond the rigid reach (docs/physics.md, "Beyond the rigid reach"): a force actuator drives a
cantilever past every pose its rigid linkage (a pin at the plate's midpoint) can reach, a tip
deflection of l/2. The compliant results are reported, the deviation is null with a note, exit
0, in every backend; the numpy module's "reference" is False, the C returns 4; `tolerance` and
`sweep` count such configurations apart from failures.

The reference, not the code under test: Bisshopp and Drucker's large deflection of a cantilever
under a transverse end force that keeps its direction (the actuator's force is a dead load
along its `direction` in the frame, docs/physics.md "Actuators at loaded"), in Legendre's
elliptic integrals, computed here with mpmath. ν = 0, so symkin's E′ = E/(1 − ν²) is E.
"""

from __future__ import annotations

import json
import math

import mpmath
import numpy as np
import pytest
from cli_runs import symkin_cli
from evaluators import require_compiler

import symkin

L, T, B, E = 10.0, 0.1, 10.0, 200e9  # mm, mm, mm, Pa
EI = E * 1e-6 * B * T**3 / 12  # N mm²
ALPHA = 10
FORCE = ALPHA * EI / L**2  # N

CANTILEVER = f"""
format = 1
name = "cantilever_force"
units = "mm"
ground = "frame"

[parameters]
l = {L}
t = {T}
b = {B}

[defaults]
model = "circular_arc"
length = "l"
E = {E}
nu = 0.0
thickness = "t"
width = "b"

[[link]]
name = "frame"
[[link]]
name = "tip"

[[hinge]]
name = "H"
links = ["frame", "tip"]
at = ["l/2", 0.0]
plate_angle = 0

[[point]]
name = "T"
link = "tip"
at = ["l", 0.0]

[[actuator]]
name = "push"
link = "tip"
at = ["l", 0.0]
direction = [0.0, 1.0]
drive = "force"
"""


def bisshopp_drucker(alpha: float) -> tuple[float, float, float]:
    """(tip angle φ0, tip x / l, tip deflection y / l) of a cantilever under an end force of
    constant (transverse) direction, α = F l²/EI: k² = (1 + sin φ0)/2, sin φ1 = 1/(k√2),
    √α = K(k) − F(φ1, k), x/l = √(2 sin φ0/α), y/l = 1 − 2 (E(k) − E(φ1, k))/√α."""
    with mpmath.workdps(30):
        a = mpmath.mpf(alpha)

        def parts(phi0):
            m = (1 + mpmath.sin(phi0)) / 2
            return m, mpmath.asin(1 / mpmath.sqrt(2 * m))

        def residual(phi0):
            m, phi1 = parts(phi0)
            return mpmath.ellipk(m) - mpmath.ellipf(phi1, m) - mpmath.sqrt(a)

        phi0 = mpmath.findroot(residual, 1.0)
        m, phi1 = parts(phi0)
        x = mpmath.sqrt(2 * mpmath.sin(phi0) / a)
        y = 1 - 2 * (mpmath.ellipe(m) - mpmath.ellipe(phi1, m)) / mpmath.sqrt(a)
        return float(phi0), float(x), float(y)


@pytest.fixture(scope="module")
def cantilever(tmp_path_factory):
    path = tmp_path_factory.mktemp("reach") / "cantilever_force.toml"
    path.write_text(CANTILEVER)
    return path


def test_the_reference_is_beyond_the_rigid_reach():
    """Check of the test's own premise and reference: at α = 10 the tip has gone 0.81 l (the pin
    at l/2 reaches l/2); at α = 2 (0.49 l) it is within reach; the elliptic solution against a
    quadrature of the elastica's first integral (ds = dφ / √(2α (sin φ0 − sin φ)))."""
    phi0, x, y = bisshopp_drucker(ALPHA)
    assert y > 0.5 > bisshopp_drucker(2)[2]

    def integral(f):
        return float(
            mpmath.quad(
                lambda p: f(p) / mpmath.sqrt(2 * ALPHA * (mpmath.sin(phi0) - mpmath.sin(p))),
                [0, phi0],
            )
        )

    # φ0 as a double: the singular end's integrand loses about half its digits
    assert integral(lambda p: 1) == pytest.approx(1, rel=1e-8)  # the plate's length
    assert integral(mpmath.cos) == pytest.approx(x, rel=1e-8)
    assert integral(mpmath.sin) == pytest.approx(y, rel=1e-8)


#: Measured against Bisshopp-Drucker (of l): loaded 3.8e-4 (x), 2.2e-4 (y), 7e-5 rad (tip angle);
#: equilibrium (Reissner's beam: its stretch and shear at t/l = 0.01) 1.3e-5, 1.1e-4, 2.4e-5.
AGAINST_BD = {"loaded": 1e-3, "equilibrium": 3e-4}


@pytest.mark.parametrize("level", ["loaded", "equilibrium"])
def test_the_cantilever_beyond_reach_against_bisshopp_drucker(cantilever, level):
    """eval --json and text at α = 10: exit 0, the compliant tip where Bisshopp and Drucker put
    it, the deviation, rigid position and rigid angles null with the note, the force at the
    clamp along the frame's y (a dead load: it keeps its direction as the tip turns)."""
    argv = ["eval", str(cantilever), "--level", level, "--input", f"push={FORCE!r}"]
    run = symkin_cli(*argv, "--json")
    assert run.returncode == 0, run.stderr
    got = json.loads(run.stdout)
    phi0, x, y = bisshopp_drucker(ALPHA)
    tip = got["points"]["T"]
    tol = AGAINST_BD[level]
    assert abs(tip["compliant"][0] - x * L) <= tol * L, tip
    assert abs(tip["compliant"][1] - y * L) <= tol * L, tip
    assert abs(got["angles"]["compliant"]["H"] - phi0) <= tol
    assert abs(got["links"]["tip"]["compliant"] - phi0) <= tol
    assert tip["deviation"] is None and tip["rigid"] is None and tip["norm"] is None
    assert "no pose of the rigid linkage reaches the stroke push=" in tip["deviation_note"]
    assert got["angles"]["rigid"]["H"] is None and got["links"]["tip"]["deviation"] is None
    assert got["hinges"]["H"]["force"] == pytest.approx([0.0, FORCE], abs=1e-9 * FORCE)
    assert got["actuators"]["push"]["stroke"] == pytest.approx(tip["compliant"][1], rel=1e-12)
    text = symkin_cli(*argv)
    assert text.returncode == 0, text.stderr
    assert "deviation    none (no pose of the rigid linkage reaches the stroke" in text.stdout


def test_every_backend_agrees_beyond_reach(cantilever):
    """The numpy and C backends of eval give the sympy backend's bytes but for the backend's
    name (the same compliant pose to its printed digits, the same note); the numpy module's
    "reference" is False there and True within reach, "ok" True both; the C returns 4."""
    require_compiler()
    outputs = {}
    for backend in ("sympy", "numpy", "c"):
        run = symkin_cli(
            "eval", str(cantilever), "--level", "loaded", "--input", f"push={FORCE!r}",
            "--backend", backend,
        )  # fmt: skip
        assert run.returncode == 0, (backend, run.stderr)
        outputs[backend] = run.stdout.replace(f"backend {backend};", "backend -;")
    assert outputs["numpy"] == outputs["sympy"] == outputs["c"]

    within = 2 * EI / L**2  # α = 2: within the rigid reach
    forces = np.array([within, FORCE])
    module = symkin.compile(cantilever, "numpy", levels=["loaded"], sensitivity=False).module
    res = module.evaluate({"push": forces}, "loaded")
    assert res["ok"].tolist() == [True, True]
    assert res["reference"].tolist() == [True, False]
    tip = res["points"]["T"]
    assert np.isfinite(tip["deviation"][:, 0]).all() and np.isnan(tip["deviation"][:, 1]).all()
    assert np.isnan(tip["rigid"][:, 1]).all()
    _, x, y = bisshopp_drucker(ALPHA)
    assert math.dist(tip["compliant"][:, 1], (x * L, y * L)) <= AGAINST_BD["loaded"] * L

    c = symkin.compile(cantilever, "c", levels=["loaded"], sensitivity=False)
    status, out = c.evaluate_rows(forces[:, None], "loaded")
    assert status.tolist() == [0, 4]
    assert np.isnan(out[1, [0, 1, 4, 5]]).all()
    assert out[1, 2:4] == pytest.approx(tip["compliant"][:, 1], rel=1e-12)
    assert out[0, 4:6] == pytest.approx(tip["deviation"][:, 0], rel=1e-10)


def test_tolerance_and_sweep_count_them_apart_from_failures(cantilever):
    """Over push from α = 0.6 to 10 (4 values), 3 configurations are beyond the rigid reach:
    `tolerance` counts them as beyond_reach, not failed; so does `sweep` per sample."""
    grid = f"push={0.6 * EI / L**2!r}:{FORCE!r}:4"
    run = symkin_cli(
        "tolerance", str(cantilever), "--vary", "t=±1%", "--input", grid, "--level", "loaded",
        "--backend", "numpy", "--json",
    )  # fmt: skip
    assert run.returncode == 0, run.stderr
    got = json.loads(run.stdout)
    assert (got["configurations"], got["failed"], got["beyond_reach"]) == (4, 0, 3)
    run = symkin_cli(
        "sweep", str(cantilever), "--vary", "t=±1%", "--input", grid, "--level", "loaded",
        "--backend", "numpy", "--samples", "4", "--scheduler", "sync", "--json",
    )  # fmt: skip
    assert run.returncode == 0, run.stderr
    got = json.loads(run.stdout)
    assert (got["samples"], got["failed"], got["beyond_reach"]) == (4, 0, 4)
    text = symkin_cli(
        "sweep", str(cantilever), "--vary", "t=±1%", "--input", grid, "--level", "loaded",
        "--backend", "numpy", "--samples", "4", "--scheduler", "sync",
    )  # fmt: skip
    assert "failed: 0; beyond the rigid linkage's reach (no deviation): 4" in text.stdout


def test_the_same_command_gives_the_same_bytes(cantilever):
    """Beyond the reach the answer is deterministic (docs/physics.md: side outputs never lose the
    main answer): the same eval twice, at both physical levels, gives the same bytes."""
    for level in ("loaded", "equilibrium"):
        argv = ["eval", str(cantilever), "--level", level, "--input", f"push={FORCE!r}", "--json"]
        first, second = symkin_cli(*argv), symkin_cli(*argv)
        assert first.returncode == second.returncode == 0, first.stderr
        assert first.stdout == second.stdout and first.stderr == second.stderr
