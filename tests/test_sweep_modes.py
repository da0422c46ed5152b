"""`symkin sweep --level loaded` on a file whose links carry mass (docs/cli.md): each sample's
lowest first natural frequency over the input grid, from the generated numpy module's modes(),
against `symkin modes` (symkin.studies.modes, the sympy path) at the sampled parameters and the
fixed-guided legs' formula (tests/test_modes.py), and its spread in JSON as the contract's
{"frequencies": {"f1": {"mean", "std", "p1", "min"}}}."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from test_modes import leaf_stiffness, stage

import symkin
from symkin.cli.commands import main
from symkin.studies import sweep, variation
from symkin.studies.modes import modes

GRID = ["push=-0.2:0.2:3"]


@pytest.fixture(scope="module")
def swept(tmp_path_factory):
    path = tmp_path_factory.mktemp("sweep") / "stage.toml"
    path.write_text(stage())
    mech = symkin.load(path)
    ev = symkin.compile(mech, backend="numpy", levels=["loaded"], sensitivity=False)
    vary = variation.parse_vary(["m=±0.02"], mech, ev.defaults)
    grid = variation.parse_grid(GRID, mech)
    result = sweep.run(
        ev, mech, vary, grid, 5, seed=2, scheduler=sweep.parse_scheduler("sync"), level="loaded"
    )
    return path, mech, ev, vary, grid, result


def lowest(mech, grid, params=None) -> float:
    """The sympy path's lowest first frequency over the grid."""
    return min(
        modes(mech, {"push": float(row[0])}, "loaded", params, 1).frequencies[0]
        for row in grid.rows
    )


def test_every_samples_first_frequency_is_the_sympy_paths(swept):
    _, mech, ev, vary, grid, result = swept
    assert result.failed == 0 and result.first is not None
    assert result.nominal_first == pytest.approx(lowest(mech, grid), rel=1e-9)
    task = sweep.Task(
        ev,
        "loaded",
        grid.rows,
        tuple((p, s, ev.defaults[p]) for p, s in vary.items()),
        2,
        5,
        sweep.geometry_checks(mech),
        tuple(p.symbol for p in mech.parameters),
    )
    params, _ = sweep.sample_block(task, 0)
    m = list(ev.sources.params).index("m")
    for k in range(5):
        mass = float(params[k, m])
        assert mass != ev.defaults["m"]
        assert result.first[k] == pytest.approx(lowest(mech, grid, {"m": mass}), rel=1e-9)
    # at zero push the two legs sway as the formula says, for every sampled mass; the pushed
    # configurations (a 0.2 N side force) are slightly softer or stiffer, never far
    for k in range(5):
        mass = float(params[k, m])
        formula = math.sqrt(2 * leaf_stiffness() / mass) / (2 * math.pi)
        assert result.first[k] == pytest.approx(formula, rel=1e-3)
    stats = result.frequency_statistics()
    assert stats["min"] <= stats["p1"] <= stats["mean"] and stats["std"] > 0
    assert stats["min"] == pytest.approx(np.min(result.first), rel=1e-15)


def test_json_and_text_carry_the_first_frequency(swept, capsys):
    path, *_, result = swept
    doc = result.as_json()
    assert set(doc["frequencies"]) == {"f1"}
    assert set(doc["frequencies"]["f1"]) == {"mean", "std", "p1", "min"}
    assert "lowest first natural frequency over the grid (Hz" in sweep.text(result)
    args = ["sweep", str(path), "--level", "loaded", "--vary", "m=±0.02", "--samples", "3"]
    args += ["--backend", "numpy", "--json", "--scheduler", "sync"]
    for item in GRID:
        args += ["--input", item]
    code = main(args)
    out, err = capsys.readouterr()
    assert code == 0, err
    assert json.loads(out)["frequencies"]["f1"]["min"] > 0
