"""`symkin sweep --level loaded` (docs/cli.md): besides every point's worst |ΔR|, every plate's
largest stress and every point's smallest diagonal stiffness over the input grid per sample,
from the generated module's report; checked against symkin's Python `loaded` level (its own
plate shooting, its stiffness by the implicit-function theorem on its own derivation in mpmath)
at the nominal parameters and at sampled ones."""

from __future__ import annotations

import json

import numpy as np
import pytest
from conftest import ROOT
from evaluators import require_compiler

import symkin
from symkin.cli.commands import main
from symkin.studies import sweep, variation

FIVE = ROOT / "tests" / "mechanisms" / "five_bar_params.toml"
GRID = ["O1=0:0.03:2", "O2=-0.02"]


def python_stress(an, rows, params=None) -> dict[str, float]:
    """Every plate's largest stress over the configurations `rows` by the Python level."""
    return python_extremes(an, rows, params)[0]


def python_extremes(an, rows, params=None) -> tuple[dict[str, float], dict[str, np.ndarray]]:
    """Every plate's largest stress and every point's smallest diagonal stiffness over the
    configurations `rows` by the Python level."""
    stress: dict[str, float] = {}
    stiff: dict[str, np.ndarray] = {}
    for row in rows:
        res = symkin.evaluate(
            an, {"O1": repr(float(row[0])), "O2": repr(float(row[1]))}, "loaded", params
        )
        for name, plate in res.plates.items():
            stress[name] = max(stress.get(name, 0.0), plate.stress)
        for name, k in res.stiffness.items():
            diagonal = np.diag(np.array(k, dtype=float))
            stiff[name] = np.minimum(stiff.get(name, diagonal), diagonal)
    return stress, stiff


@pytest.fixture(scope="module")
def five():
    require_compiler()
    mech = symkin.load(FIVE)
    an = symkin.analyze(mech)
    ev = symkin.compile(an, levels=["loaded"], sensitivity=False)
    vary = variation.parse_vary(["t=±5e-6"], mech, ev.defaults)
    grid = variation.parse_grid(GRID, mech)
    result = sweep.run(
        ev, mech, vary, grid, 6, seed=3, scheduler=sweep.parse_scheduler("sync"), level="loaded"
    )
    return mech, an, ev, vary, grid, result


def test_the_nominal_stress_is_the_python_levels(five):
    mech, an, _, _, grid, result = five
    assert set(result.plates) == {h.name for h in mech.hinges}
    want = python_stress(an, grid.rows)
    for name in result.plates:
        got = result.nominal_stress[name]
        assert abs(got - want[name]) <= 1e-8 * want[name], (name, got, want[name])


def test_the_nominal_stiffness_is_the_python_levels(five):
    _, an, ev, _, grid, result = five
    _, want = python_extremes(an, grid.rows)
    assert set(result.stiff) == set(want) == set(ev.points)
    for name in result.stiff:
        got = np.array(result.nominal_stiffness[name])
        assert np.all(np.abs(got - want[name]) <= 1e-8 * np.abs(want[name])), (name, got)


def test_every_samples_stress_is_the_python_levels_at_its_parameters(five):
    mech, an, ev, vary, grid, result = five
    assert result.failed == 0 and result.stress is not None
    task = sweep.Task(
        ev,
        "loaded",
        grid.rows,
        tuple((p, s, ev.defaults[p]) for p, s in vary.items()),
        3,
        6,
        sweep.geometry_checks(mech),
        tuple(p.symbol for p in mech.parameters),
        result.plates,
        result.stiff,
    )
    params, valid = sweep.sample_block(task, 0)
    assert valid.all()
    t = list(ev.sources.params).index("t")
    for k in (0, 1):
        assert params[k, t] != ev.defaults["t"]
        want, stiff = python_extremes(an, grid.rows, {"t": repr(float(params[k, t]))})
        for j, name in enumerate(result.plates):
            got = result.stress[k, j]
            assert abs(got - want[name]) <= 1e-8 * want[name], (k, name, got, want[name])
        for j, name in enumerate(result.stiff):
            got = result.stiffness[k, j]
            assert np.all(np.abs(got - stiff[name]) <= 1e-8 * np.abs(stiff[name])), (k, name)
    # thicker plates bend to the same angles with more stress, and are stiffer: the spreads
    # are not zero
    stats = result.stress_statistics(result.plates[0])
    assert stats["std"] is not None and stats["std"] > 0
    stats = result.stiffness_statistics(result.stiff[0])
    assert all(stats[key]["std"] > 0 for key in sweep.STIFFNESS)


def test_json_and_text_carry_the_stress(five, capsys):
    *_, result = five
    doc = result.as_json()
    assert set(doc["plates"]) == set(result.plates)
    for stats in doc["plates"].values():
        assert {"mean", "std", "p50", "p99", "p999", "max", "nominal"} <= set(stats)
    assert set(doc["stiffness"]) == set(result.stiff)
    for stats in doc["stiffness"].values():
        assert set(stats) == set(sweep.STIFFNESS)
        for key in sweep.STIFFNESS:
            assert {"mean", "std", "p50", "p1", "p01", "min", "nominal"} == set(stats[key])
            assert stats[key]["min"] <= stats[key]["p1"] <= stats[key]["p50"]
    assert "largest stress over the grid (Pa)" in sweep.text(result)
    assert "smallest stiffness over the grid" in sweep.text(result)
    args = ["sweep", str(FIVE), "--level", "loaded", "--vary", "t=±5e-6", "--samples", "4"]
    for item in GRID:
        args += ["--input", item]
    code = main([*args, "--json", "--scheduler", "sync"])
    out, err = capsys.readouterr()
    assert code == 0, err
    assert set(json.loads(out)["plates"]) == set(result.plates)
    assert set(json.loads(out)["stiffness"]) == set(result.stiff)
