"""The physical levels (docs/physics.md) against closed forms and published values.

- the plate integrator (symkin.physics.beams): a pure end moment bends a circular arc (both
  beams); the elastica's Bisshopp–Drucker cantilever (load index α = F L²/EI, α = 1, 2, 5) and
  Mattiasson's α = 10; the linear limits, Euler–Bernoulli and Timoshenko (clamped–guided
  V l³/(12 EI) + V l/(κGA), cantilever V l³/(3 EI) + V l/(κGA), stretch N l/EA); Reissner's first
  integral at large loads;
- `equilibrium` and `loaded` on a lone plate held by its actuator: a pure actuator torque (circular
  arc, moment EI θ/l, energy EI θ²/(2l)), a small transverse load (clamped–guided compliance,
  with shear for a Reissner plate), the fixed–guided column below its buckling load (Euler's
  for the elastica, P(1 + P (1/κGA − 1/EA)) = π² EI/l² for Reissner's beam; beyond it:
  test_buckling.py);
- the file's length unit, the wide-plate modulus, the error estimate, the command line.

Comparisons with the independent whole-mechanism reference are in test_physics_reference.py.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import mechanisms as M
import mpmath
import numpy as np
import pytest
from conftest import EXAMPLES
from evaluators import BACKENDS, backends_with
from mechanisms import (
    axial_stiffness,
    bending_stiffness,
    column_buckling_load,
    lone_plate,
    shear_stiffness,
)

import symkin
from symkin.cli.commands import main
from symkin.core import backends
from symkin.physics import arith, beams
from symkin.studies import physical
from symkin.studies.configuration import configure

DPS = 30


def shoot_mp(k0, lx, ly, energy: bool = False, stretch=None, shear=None) -> beams.PlateEnd:
    """One plate at DPS digits: an elastica, or a Reissner beam with the compliances
    stretch = EI/(EA l²) and shear = EI/(κGA l²)."""

    def opt(v):
        return None if v is None else arith.mp_array([v])

    return beams.shoot(
        arith.mp_array([k0]),
        arith.mp_array([lx]),
        arith.mp_array([ly]),
        tol=10.0 ** (-DPS - 3),
        energy=energy,
        stretch=opt(stretch),
        shear=opt(shear),
    )


# -- the elastica -----------------------------------------------------------------------------


@pytest.mark.parametrize("compliance", [(None, None), ("1e-3", "3e-3"), ("0.05", "0.2")])
@pytest.mark.parametrize("theta", ["1e-8", "0.3", "2", "6"])
def test_pure_end_moment_bends_a_circular_arc(theta, compliance):
    # A pure moment neither stretches nor shears a Reissner beam: the arc is exact for both.
    with mpmath.workdps(DPS):
        t = mpmath.mpf(theta)
        end = shoot_mp(t, 0, 0, True, *compliance)
        expected = (mpmath.sin(t) / t, 2 * mpmath.sin(t / 2) ** 2 / t, t, t, t**2)
        got = (end.x[0], end.y[0], end.psi[0], end.omega[0], end.energy[0])
        for g, e in zip(got, expected):
            assert abs(g - e) <= mpmath.mpf(10) ** (3 - DPS) * (1 + abs(e))


def cantilever(alpha) -> beams.PlateEnd:
    """Tip-loaded cantilever (transverse dead force, index α): the M end carries no moment."""
    k0 = mpmath.findroot(lambda k: shoot_mp(k, 0, alpha).omega[0], mpmath.mpf(alpha) * 0.45)
    return shoot_mp(k0, 0, alpha)


# Bisshopp & Drucker (1945): α, tip angle (deg), 1 - x/L, y/L
@pytest.mark.parametrize(
    "alpha, angle, short, rise",
    [
        (1, "26.4335196", "0.0564332363", "0.301720774"),
        (2, "44.790966", "0.160641721", "0.49345748"),
        (5, "69.6354637", "0.387628361", "0.713791524"),
    ],
)
def test_bisshopp_drucker_cantilever(alpha, angle, short, rise):
    with mpmath.workdps(DPS):
        end = cantilever(alpha)
        for got, want in (
            (end.psi[0] * 180 / mpmath.pi, angle),
            (1 - end.x[0], short),
            (end.y[0], rise),
        ):
            digits = len(want.replace(".", "").lstrip("0"))
            assert abs(got - mpmath.mpf(want)) <= 0.6 * 10.0 ** (-digits) * 10 ** math.floor(
                math.log10(float(want)) + 1
            )


def test_mattiasson_cantilever_alpha_10():
    with mpmath.workdps(DPS):
        end = cantilever(10)
        assert abs(end.y[0] - mpmath.mpf("0.81061")) < 6e-6
        assert abs(1 - end.x[0] - mpmath.mpf("0.55500")) < 6e-6
        assert abs(end.psi[0] - mpmath.mpf("1.430286")) < 6e-7


#: Reissner compliances (EI/(EA l²), EI/(κGA l²)) of a steel plate with t = l/10 and of an
#: exaggerated one; (None, None) is the elastica.
COMPLIANCES = [(None, None), ("8.333e-4", "2.96e-3"), ("0.01", "0.03")]


@pytest.mark.parametrize("compliance", COMPLIANCES)
@pytest.mark.parametrize("shear", ["1e-6", "1e-3"])
def test_clamped_guided_linear_limit(shear, compliance):
    # Both ends keep their rotation (ψ(1) = 0): the transverse end displacement is
    # V l³/(12 EI) + V l/(κGA), i.e. λy (1/12 + γ_a) in units of l (Timoshenko), up to O(λ³);
    # the shortening is second order.
    with mpmath.workdps(DPS):
        lam = mpmath.mpf(shear)
        gam = mpmath.mpf(compliance[1] or 0)
        k0 = mpmath.findroot(lambda k: shoot_mp(k, 0, lam, False, *compliance).psi[0], lam / 2)
        end = shoot_mp(k0, 0, lam, False, *compliance)
        assert abs(end.y[0] / (lam * (mpmath.mpf(1) / 12 + gam)) - 1) < 10 * lam**2
        assert abs(end.x[0] - 1) < lam**2


@pytest.mark.parametrize("compliance", COMPLIANCES)
def test_cantilever_linear_limit(compliance):
    # Free end under a small transverse force λ: deflection λ (1/3 + γ_a), rotation λ/2
    # (Timoshenko's cantilever: the shear adds V l/(κGA) and no rotation).
    with mpmath.workdps(DPS):
        lam = mpmath.mpf("1e-7")
        gam = mpmath.mpf(compliance[1] or 0)
        k0 = mpmath.findroot(lambda k: shoot_mp(k, 0, lam, False, *compliance).omega[0], lam)
        end = shoot_mp(k0, 0, lam, False, *compliance)
        assert abs(end.y[0] / (lam * (mpmath.mpf(1) / 3 + gam)) - 1) < 10 * lam
        assert abs(end.psi[0] / (lam / 2) - 1) < 10 * lam
        assert abs(k0 / lam - 1) < 10 * lam  # the root moment V l


@pytest.mark.parametrize("compliance", COMPLIANCES)
@pytest.mark.parametrize("axial", ["-2", "0.5", "30"])
def test_an_axial_force_stretches_a_straight_plate(axial, compliance):
    # Straight under an axial end force: x(1) = 1 + ε_a λ (N l/EA), energy ε_a λ² (N² l/EA).
    with mpmath.workdps(DPS):
        lam = mpmath.mpf(axial)
        eps = mpmath.mpf(compliance[0] or 0)
        end = shoot_mp(0, lam, 0, True, *compliance)
        assert abs(end.x[0] - 1 - eps * lam) < mpmath.mpf(10) ** (4 - DPS)
        assert end.y[0] == 0 and end.psi[0] == 0
        assert abs(end.energy[0] - eps * lam**2) < mpmath.mpf(10) ** (4 - DPS)


@pytest.mark.parametrize("loads", [("0.4", "-3", "2"), ("-6", "4", "-1.5"), ("10", "25", "0")])
def test_reissner_first_integral_holds_at_large_loads(loads):
    # ψ'' = −f_Q (1 + d f_N) = −dV/dψ with V = f_N + d f_N²/2 (d = ε_a − γ_a, df_N/dψ = f_Q):
    # ψ'²/2 + V(ψ) is constant along the plate, a check of the nonlinear terms independent of
    # the recurrences.
    eps, gam = mpmath.mpf("0.01"), mpmath.mpf("0.03")
    with mpmath.workdps(DPS):
        k0, lx, ly = (mpmath.mpf(v) for v in loads)
        end = shoot_mp(k0, lx, ly, False, eps, gam)

        def invariant(psi, omega):
            n = lx * mpmath.cos(psi) + ly * mpmath.sin(psi)
            return omega**2 / 2 + n + (eps - gam) * n**2 / 2

        start, stop = invariant(0, k0), invariant(end.psi[0], end.omega[0])
        assert abs(stop - start) < mpmath.mpf(10) ** (5 - DPS) * (1 + abs(start))


def test_complex_step_derivative_of_a_straight_plate():
    # A straight plate under the axial load λ: ψ(1) = k0 sin(√λ)/√λ exactly to first order in k0.
    lam = 9.8722
    end = beams.shoot(
        np.array([1j * arith.COMPLEX_STEP]), np.array([-lam + 0j]), np.array([0j]), tol=1e-18
    )
    slope = end.psi.imag[0] / arith.COMPLEX_STEP
    assert slope == pytest.approx(math.sin(math.sqrt(lam)) / math.sqrt(lam), rel=1e-12)


def test_complex_step_derivative_of_a_straight_reissner_plate():
    # Linearised about the straight plate under the compression λ (f_N = −λ, f_Q = λ ψ):
    # ψ'' = −λ (1 − d λ) ψ with d = ε_a − γ_a, so ψ(1) = k0 sin ω/ω, ω² = λ (1 − d λ).
    lam, eps, gam = 9.0, 0.01, 0.03
    end = beams.shoot(
        np.array([1j * arith.COMPLEX_STEP]),
        np.array([-lam + 0j]),
        np.array([0j]),
        tol=1e-18,
        stretch=np.array([eps]),
        shear=np.array([gam]),
    )
    omega = math.sqrt(lam * (1 - (eps - gam) * lam))
    slope = end.psi.imag[0] / arith.COMPLEX_STEP
    assert slope == pytest.approx(math.sin(omega) / omega, rel=1e-12)


# -- a lone plate held by its actuator --------------------------------------------------------


@pytest.mark.parametrize("beam", ["reissner", "elastica"])
@pytest.mark.parametrize("level", ["equilibrium", "loaded"])
@pytest.mark.parametrize("theta", [0.05, 0.5, 1.5])
def test_actuator_torque_alone_bends_a_circular_arc(level, theta, beam):
    an = symkin.analyze(symkin.loads(lone_plate(beam=beam), "lone.toml"))
    result = symkin.evaluate(an, {"A": theta}, level)
    with mpmath.workdps(DPS):
        t, l = mpmath.mpf(theta), mpmath.mpf(10)
        # rigid: the arm turns by θ about the pin (0, l/2); compliant: the arc carries M's clamp
        # (0, l) to (-l (1 - cos θ)/θ, l sin θ/θ) and the arm turns by θ about it
        T = (mpmath.mpf(0), 3 * l)
        rigid = (-mpmath.sin(t) * (T[1] - l / 2), l / 2 + mpmath.cos(t) * (T[1] - l / 2))
        clamp = (-2 * l * mpmath.sin(t / 2) ** 2 / t, l * mpmath.sin(t) / t)
        compliant = (clamp[0] - mpmath.sin(t) * (T[1] - l), clamp[1] + mpmath.cos(t) * (T[1] - l))
        dev = result.points["T"].deviation
        want = (compliant[0] - rigid[0], compliant[1] - rigid[1])
        assert math.hypot(dev[0] - want[0], dev[1] - want[1]) < 1e-13 * float(mpmath.hypot(*want))
    ei = bending_stiffness(5, 0.3, 1e-3)
    hinge = result.hinges["A"]
    assert hinge.moment == pytest.approx(ei * theta / 0.01, rel=1e-12)
    assert max(abs(f) for f in hinge.force) < 1e-12 * ei / 0.01**2
    assert result.energy == pytest.approx(ei * theta**2 / (2 * 0.01), rel=1e-12)


@pytest.mark.parametrize("beam", ["reissner", "elastica"])
@pytest.mark.parametrize("level", ["equilibrium", "loaded"])
@pytest.mark.parametrize("width, nu", [("5", "0.3"), ("0.5", "0.3"), ("5", "0")])
def test_small_transverse_load_moves_the_arm_by_the_clamped_guided_compliance(
    level, width, nu, beam
):
    # Input held at 0, a force F across the plate at T: the arm translates by F l³/(12 EI), plus
    # F l/(κGA) where the plate shears (a Reissner plate, at either level: `loaded`'s plate
    # relation takes the stretch and shear, docs/physics.md).
    force = 1e-3
    load = '[[load]]\npoint = "T"\nforce = ["F", 0]\n'
    text = lone_plate(width=width, nu=nu, load=load, beam=beam)
    an = symkin.analyze(symkin.loads(text, "lone.toml"))
    result = symkin.evaluate(an, {"A": 0}, level, params={"F": force})
    ei = bending_stiffness(float(width), float(nu), 1e-3)
    compliance = 0.01**3 / (12 * ei)
    if beam == "reissner":
        compliance += 0.01 / shear_stiffness(float(width), float(nu), 1e-3)
    expected = force * compliance * 1e3  # metres -> the file's mm
    dev = result.points["T"].deviation
    assert dev[0] == pytest.approx(expected, rel=1e-6)
    alpha = force * 0.01**2 / ei
    assert abs(dev[1]) < expected * alpha  # no axial force: second order only


def test_lengths_in_m_mm_um_give_the_same_physics():
    load = '[[load]]\npoint = "T"\nforce = ["F", "-F"]\nmoment = "F/1000"\n'
    results = {}
    for units, scale in (("m", 1e-3), ("mm", 1.0), ("um", 1e3)):
        an = symkin.analyze(symkin.loads(lone_plate(units, scale=scale, load=load), "u.toml"))
        results[units] = (symkin.evaluate(an, {"A": 0.2}, "equilibrium", params={"F": 0.5}), scale)
    base, base_scale = results["m"]
    for r, scale in results.values():
        for k in range(2):
            assert r.points["T"].deviation[k] / scale == pytest.approx(
                base.points["T"].deviation[k] / base_scale, rel=1e-12
            )
        assert r.hinges["A"].moment == pytest.approx(base.hinges["A"].moment, rel=1e-12)
        assert r.energy == pytest.approx(base.energy, rel=1e-12)


@pytest.mark.parametrize("beam", ["reissner", "elastica"])
def test_below_the_buckling_load_the_column_stays_straight(tmp_path, beam):
    # At 0.9 of the critical load the column stays straight; a Reissner plate shortens by P l/EA.
    text = lone_plate(load='[[load]]\npoint = "T"\nforce = [0, "-F"]\n', beam=beam)
    an = symkin.analyze(symkin.loads(text, "column.toml"))
    force = 0.9 * column_buckling_load(beam)
    result = symkin.evaluate(an, {"A": 0}, "equilibrium", params={"F": force})
    dev = result.points["T"].deviation
    assert dev[0] == 0.0
    if beam == "elastica":
        assert dev[1] == 0.0
    else:
        assert dev[1] == pytest.approx(
            -force * 0.01 / axial_stiffness(5, 0.3, 1e-3) * 1e3, rel=1e-12
        )
    assert result.hinges["A"].force[1] == pytest.approx(-force, rel=1e-12)


def test_the_error_estimate_is_honest_and_below_1e_10():
    text = M.without_stiffness(EXAMPLES / "four_bar.toml").replace(
        'length = "l"', 'length = "l"\nE = 210e9\nthickness = "l/10"\nwidth = 5e-3'
    )
    text += '[[load]]\npoint = "C"\nforce = [0.5, -2.0]\nmoment = 0.01\n'
    an = symkin.analyze(symkin.loads(text, "four_bar.toml"))
    for angle in (1e-3, 0.2):
        plain = physical.equilibrium(an, configure(an, {"A0": angle}, "equilibrium"))
        finer = physical.equilibrium(
            an, configure(an, {"A0": angle}, "equilibrium"), extra_digits=25
        )
        d0, d1 = plain.points["C"].deviation, finer.points["C"].deviation
        gap = math.hypot(d0[0] - d1[0], d0[1] - d1[1]) / math.hypot(*d1)
        assert plain.error_estimate < 1e-10
        assert gap <= max(plain.error_estimate, 2.3e-16)  # float64 rounding of the output


# -- the command line -------------------------------------------------------------------------


def steel_four_bar(tmp_path, extra: str = "") -> str:
    text = M.without_stiffness(EXAMPLES / "four_bar.toml").replace(
        'length = "l"', 'length = "l"\nE = 210e9\nthickness = "l/10"\nwidth = 5e-3'
    )
    path = tmp_path / "four_bar.toml"
    path.write_text(text + extra)
    return str(path)


@pytest.mark.parametrize("level", ["equilibrium", "loaded"])
def test_eval_json_adds_hinges_and_energy(tmp_path, capsys, level):
    path = steel_four_bar(tmp_path)
    code = main(["eval", path, "--input", "A0=0.1", "--level", level, "--json"])
    out, err = capsys.readouterr()
    assert code == 0, err
    data = json.loads(out)
    keys = {
        "level",
        "backend",
        "inputs",
        "params",
        "angles",
        "points",
        "links",
        "dyads",
        "hinges",
        "energy",
    }
    # both report the designer's quantities (tests/test_equilibrium_reported.py,
    # tests/test_loaded_reported.py), "buckling" only with loads; equilibrium its error estimate
    reported = {"stiffness", "compliance", "plates"}
    reported |= {"error_estimate"} if level == "equilibrium" else set()
    assert set(data) == keys | reported
    assert data["level"] == level
    assert set(data["hinges"]) == {"A0", "A", "B0", "B"}
    for h in data["hinges"].values():
        assert set(h) == {"moment", "force"} and len(h["force"]) == 2
    assert data["energy"] > 0
    c = data["points"]["C"]
    assert c["compliant"][0] == pytest.approx(c["rigid"][0] + c["deviation"][0], rel=1e-15)


def test_eval_text_lists_plate_loads(tmp_path, capsys):
    code = main(["eval", steel_four_bar(tmp_path), "--input", "A0=0.1", "--level", "equilibrium"])
    out, _ = capsys.readouterr()
    assert code == 0
    assert "point C" in out and "plate loads" in out and "elastic energy" in out
    assert "estimated relative error" in out


@pytest.mark.parametrize("level", ["equilibrium", "loaded"])
def test_physical_level_without_stiffness_names_key_and_hinge(tmp_path, capsys, level):
    path = tmp_path / "four_bar.toml"
    path.write_text(M.without_stiffness(EXAMPLES / "four_bar.toml"))
    code = main(["eval", str(path), "--input", "A0=0.1", "--level", level])
    err = capsys.readouterr().err
    assert code == 2
    assert "four_bar.toml" in err and "'A0'" in err and "'E'" in err and "fix:" in err


def test_partial_stiffness_names_the_missing_key(tmp_path, capsys):
    text = M.without_stiffness(EXAMPLES / "four_bar.toml").replace(
        'length = "l"', 'length = "l"\nE = 210e9\nwidth = 5e-3'
    )
    text = text.replace('plate_angle = "0"\n', 'plate_angle = "0"\nthickness = 1e-4\n', 1)
    path = tmp_path / "partial.toml"
    path.write_text(text)
    code = main(["eval", str(path), "--input", "A0=0.1", "--level", "equilibrium"])
    err = capsys.readouterr().err
    assert code == 2 and "'thickness'" in err and "'A0'" in err


def test_param_override_that_thickens_the_plate_past_its_length_is_bad_input(tmp_path, capsys):
    path = steel_four_bar(tmp_path).replace("four_bar.toml", "thick.toml")
    Path(path).write_text(
        Path(tmp_path / "four_bar.toml")
        .read_text()
        .replace('thickness = "l/10"', "thickness = 1e-4")
    )
    code = main(["eval", path, "--input", "A0=0.1", "--level", "loaded", "--param", "l=5e-5"])
    err = capsys.readouterr().err
    assert code == 2 and "thickness" in err and "--param" in err


@pytest.mark.parametrize(
    "backend", [b for b in BACKENDS if "equilibrium" not in backends.get(b).levels]
)
def test_equilibrium_runs_on_the_sympy_backend_only(tmp_path, capsys, backend):
    code = main(
        [
            "eval",
            steel_four_bar(tmp_path),
            "--input",
            "A0=0.1",
            "--level",
            "equilibrium",
            "--backend",
            backend,
        ]
    )
    err = capsys.readouterr().err
    assert code == 2 and backends_with(levels="equilibrium") == ("sympy",) and "sympy" in err


@pytest.mark.parametrize("backend", backends_with(generated=True, levels="loaded"))
def test_loaded_prints_the_same_json_on_every_backend(tmp_path, capsys, backend):
    path = steel_four_bar(tmp_path)
    outputs = []
    for chosen in ("sympy", backend):
        code = main(
            ["eval", path, "--input", "A0=0.1", "--level", "loaded", "--json", "--backend", chosen]
        )
        out, err = capsys.readouterr()
        assert code == 0, err
        outputs.append(json.loads(out))
    ours, generated = outputs
    assert generated["backend"] == backend
    assert generated["hinges"] == ours["hinges"] and generated["energy"] == ours["energy"]
    want, got = ours["points"]["C"]["deviation"], generated["points"]["C"]["deviation"]
    assert math.dist(want, got) <= 1e-12 * math.hypot(*want)


def test_unreachable_input_exits_3_like_the_kinematic_levels(tmp_path, capsys):
    path = tmp_path / "non_grashof.toml"
    path.write_text(
        M.NON_GRASHOF.replace(
            'length = "l"', 'length = "l"\nE = 210e9\nthickness = "l/10"\nwidth = 5e-3'
        )
    )
    messages = []
    for level in ("exact", "equilibrium", "loaded"):
        assert main(["eval", str(path), "--input", "A0=1.5", "--level", level]) == 3
        err = capsys.readouterr().err
        # exact on a file whose plates have E, thickness and width warns first (one line)
        warned = [line for line in err.splitlines() if line.startswith("symkin: warning:")]
        assert len(warned) == (level == "exact")
        assert all("ignores the plates' forces" in line for line in warned)
        messages.append(err.split("\n", 1)[1] if warned else err)
    assert messages[0] == messages[1] == messages[2]


@pytest.mark.parametrize("hinge_beam", ["elastica", "reissner"])
def test_a_hinge_beam_key_overrides_the_defaults(hinge_beam):
    # [defaults] says one theory, the hinge the other: the hinge's own key decides (the
    # transverse compliance gains F l/(κGA) only for a Reissner plate).
    other = "reissner" if hinge_beam == "elastica" else "elastica"
    text = lone_plate(load='[[load]]\npoint = "T"\nforce = ["F", 0]\n', beam=other)
    text = text.replace("input = true\n", f'input = true\nbeam = "{hinge_beam}"\n')
    mech = symkin.loads(text, "lone.toml")
    assert mech.hinge("A").beam == hinge_beam
    result = symkin.evaluate(symkin.analyze(mech), {"A": 0}, "equilibrium", params={"F": 1e-3})
    compliance = 0.01**3 / (12 * bending_stiffness(5, 0.3, 1e-3))
    if hinge_beam == "reissner":
        compliance += 0.01 / shear_stiffness(5, 0.3, 1e-3)
    assert result.points["T"].deviation[0] == pytest.approx(1e-3 * compliance * 1e3, rel=1e-6)
