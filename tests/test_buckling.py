"""Loads beyond buckling at the `equilibrium` level (docs/physics.md, "Overloads and buckling").

- `buckling_factor` (symkin.physics.equilibrium): the fixed–guided column against its closed-form
  critical load (Euler's for the elastica; P (1 + P (1/κGA − 1/EA)) = π² EI/l² for Reissner's
  beam); the Scott–Russell amplifier of tests/mechanisms against the independent reference
  (tests/reference_physics.py, which stops at the same limit point); infinite without loads or in
  tension.
- Overloads fail fast: twice the column's critical load exits 3 naming the factor 2; a load a
  thousand times the critical one (units that slipped) exits 3 in seconds naming 1000 and the
  units; the Scott–Russell amplifier beyond its limit point exits 3 naming the factor of the
  reference's limit point, both when the estimate sends it to the probe and when the
  continuation meets it; at 80 % of it the equilibrium is solved and agrees with the reference.
- The continuation's budget ends in exit 3.
"""

from __future__ import annotations

import math
import re
import time

import mechanisms as M
import pytest
import sympy as sp
from conftest import ROOT
from mechanisms import column_buckling_load, lone_plate
from reference_physics import ContinuationError, Equilibrium, Load

import symkin
from symkin.cli.commands import main
from symkin.physics import equilibrium
from symkin.studies.configuration import parameter_values

COLUMN_LOAD = '[[load]]\npoint = "T"\nforce = [0, "-F"]\n'
SCOTT_RUSSELL = ROOT / "tests" / "mechanisms" / "scott_russell.toml"
LEVER = ROOT / "tests" / "mechanisms" / "lever_amplifier.toml"


def factor_of(err: str) -> float:
    """The factor an overload message names: 'the loads are X times the first buckling load'."""
    return float(re.search(r"the loads are (\S+) times the first buckling load", err).group(1))


def column(beam: str, force: float):
    mech = symkin.loads(lone_plate(load=COLUMN_LOAD, beam=beam), "column.toml")
    return mech, parameter_values(mech, {"F": repr(force)})


def scott_russell_elastica():
    """The amplifier with elastica plates (the in-tree reference's physics), and that reference
    with its loads; the file is in mm: EI in N·mm² takes E' in N/mm² (docs/physics.md)."""
    mech = symkin.loads(M.with_beam(SCOTT_RUSSELL.read_text(), "elastica"), "scott_russell.toml")
    modulus = sp.Rational(70 * 10**9) / (1 - sp.Rational(33, 100) ** 2) / 10**6
    loads = [Load(ld.link, tuple(ld.at), tuple(ld.force), ld.moment) for ld in mech.loads]
    return mech, Equilibrium(mech, (modulus, 10, sp.Rational(1, 4)), loads=loads)


@pytest.fixture(scope="module")
def scott_russell_limit() -> float:
    """The factor on the file's 5 N preload at which the independent reference's continuation
    (loads alone, input at 0) stops at its limit point."""
    _, reference = scott_russell_elastica()
    with pytest.raises(ContinuationError) as stop:
        reference.solve({"RA0": "0"}, load_factor=10)
    return 10 * stop.value.load_factor


# -- the buckling factor ----------------------------------------------------------------------


@pytest.mark.parametrize("beam", ["reissner", "elastica"])
def test_buckling_factor_of_the_column_is_its_critical_load(beam):
    mech, values = column(beam, column_buckling_load(beam) / 4)
    found = equilibrium.buckling_factor(mech, values, {"A": sp.Integer(0)})
    assert found.factor == pytest.approx(4, rel=1e-6)
    assert found.hinge == "A"


@pytest.mark.parametrize("beam", ["reissner", "elastica"])
def test_linearised_estimate_is_within_a_factor_two_of_the_column_critical_load(beam):
    # The estimate only triggers the probe and refuses gross overloads (docs/physics.md): the
    # mixed formulation's Jacobian is far from linear in the loads (≈ 0.6 of the critical load).
    mech, values = column(beam, 1.0)
    stiffness = equilibrium.plate_stiffness(mech, "equilibrium")
    system = equilibrium.build(
        mech, values, {"A": sp.Integer(0)}, stiffness, lambda v: float(sp.N(v, 20))
    )
    estimate = equilibrium.buckling_estimate(system)
    assert 0.5 < estimate.factor / column_buckling_load(beam) < 2
    assert estimate.hinge == "A"


def test_buckling_factor_of_the_scott_russell_amplifier_is_the_reference_limit_point(
    scott_russell_limit,
):
    mech, _ = scott_russell_elastica()
    found = equilibrium.buckling_factor(mech, parameter_values(mech, None), {"RA0": sp.Integer(0)})
    assert found.factor == pytest.approx(scott_russell_limit, rel=2e-6)
    assert found.hinge == "RA0"


@pytest.mark.parametrize("loaded", [False, True])
def test_no_buckling_without_loads_or_in_tension(loaded):
    # F = -5 N pulls the column: no factor up to BUCKLING_LIMIT makes it singular.
    mech = symkin.loads(lone_plate(load=COLUMN_LOAD if loaded else ""), "column.toml")
    values = parameter_values(mech, {"F": "-5"})
    found = equilibrium.buckling_factor(mech, values, {"A": sp.Rational(1, 10)})
    assert found == equilibrium.Buckling(math.inf, None)


# -- overloads fail fast ----------------------------------------------------------------------


def eval_equilibrium(capsys, path, inputs: list[str], params: list[str]) -> tuple[int, str, float]:
    args = ["eval", str(path), "--level", "equilibrium"]
    for i in inputs:
        args += ["--input", i]
    for p in params:
        args += ["--param", p]
    start = time.monotonic()
    code = main(args)
    seconds = time.monotonic() - start
    return code, capsys.readouterr().err, seconds


@pytest.mark.parametrize("beam", ["reissner", "elastica"])
@pytest.mark.parametrize("times", [2.0, 1000.0])
def test_a_column_beyond_its_critical_load_exits_3_naming_the_factor(tmp_path, capsys, beam, times):
    path = tmp_path / "column.toml"
    path.write_text(lone_plate(load=COLUMN_LOAD, beam=beam))
    force = times * column_buckling_load(beam)
    code, err, seconds = eval_equilibrium(capsys, path, ["A=0"], [f"F={force!r}"])
    assert code == 3, err
    assert "'A'" in err and 'units = "mm"' in err and "Traceback" not in err
    if times == 2:  # the probe finds the critical point itself
        assert factor_of(err) == pytest.approx(2, rel=1e-3)
        assert "singular" in err
    else:  # refused on the linearised estimate at once
        assert times / 2 < factor_of(err) < 2 * times
        assert "estimate" in err
    assert seconds < 30


def test_units_that_slipped_exit_3_within_seconds(tmp_path, capsys):
    # The lever's return spring given as 10 N instead of 0.01 N: refused on the linearised
    # estimate at once (the loads alone would bend the foil plates far past any elastic strain).
    code, err, seconds = eval_equilibrium(capsys, LEVER, ["P0=0.01"], ["F_pre=10"])
    assert code == 3, err
    assert factor_of(err) > 10 and "hinge 'F'" in err and 'units = "mm"' in err
    assert seconds < 30


def test_beyond_the_limit_point_the_probe_names_the_reference_factor(
    tmp_path, capsys, scott_russell_limit
):
    # Ten times the preload: the linearised estimate (≈ 8 times the preload) sends the loads to
    # the probe, which stops at the limit point.
    path = tmp_path / "scott_russell.toml"
    path.write_text(M.with_beam(SCOTT_RUSSELL.read_text(), "elastica"))
    code, err, seconds = eval_equilibrium(capsys, path, ["RA0=0"], ["F_pre=50"])
    assert code == 3, err
    assert factor_of(err) == pytest.approx(10 / scott_russell_limit, rel=1e-3)
    assert "hinge 'RA0'" in err and seconds < 30


def test_beyond_the_limit_point_the_continuation_stops_there(tmp_path, capsys, scott_russell_limit):
    # Six times the preload: below the linearised estimate, so the continuation itself meets the
    # limit point (and does not jump past it to a distant equilibrium).
    path = tmp_path / "scott_russell.toml"
    path.write_text(M.with_beam(SCOTT_RUSSELL.read_text(), "elastica"))
    code, err, seconds = eval_equilibrium(capsys, path, ["RA0=0"], ["F_pre=30"])
    assert code == 3, err
    reached = float(err.split("load factor t = ")[1].split()[0])
    assert reached == pytest.approx(scott_russell_limit / 6, rel=1e-5)
    assert "'RA0'" in err and seconds < 30


def test_at_80_percent_of_the_limit_point_the_equilibrium_is_solved(scott_russell_limit):
    mech, reference = scott_russell_elastica()
    factor = 0.8 * scott_russell_limit
    an = symkin.analyze(mech)
    ours = symkin.evaluate(an, {"RA0": 0}, "equilibrium", params={"F_pre": repr(5 * factor)})
    want = reference.solve({"RA0": "0"}, load_factor=sp.Float(factor, 30))["points"]["B"]
    got = ours.points["B"].deviation
    expected = [float(v) for v in want["deviation"]]
    assert math.dist(got, expected) < 1e-9 * math.hypot(*expected)


def test_the_continuation_budget_ends_in_exit_3(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(equilibrium, "TIME_BUDGET", 0.0)
    path = tmp_path / "column.toml"
    path.write_text(lone_plate(load=COLUMN_LOAD))
    code, err, _ = eval_equilibrium(capsys, path, ["A=0.1"], ["F=1"])
    assert code == 3 and "within its budget" in err and "Traceback" not in err
