"""`symkin sweep --level loaded --backend c` on a file whose links carry mass: the natural
frequencies come from the C evaluator's <name>_modes (not the numpy module's modes()), and the
output says which backend computed them. References: `symkin modes`'s sympy path at the sampled
parameters and the fixed-guided legs' formula (tests/test_modes.py)."""

from __future__ import annotations

import json
import math

import pytest
from evaluators import require_compiler
from test_modes import leaf_stiffness, stage
from test_sweep_modes import GRID, lowest

import symkin
from symkin.cli.commands import main
from symkin.studies import sweep, variation


@pytest.fixture(scope="module")
def swept_c(tmp_path_factory):
    require_compiler()
    path = tmp_path_factory.mktemp("sweep_c") / "stage.toml"
    path.write_text(stage())
    mech = symkin.load(path)
    ev = symkin.compile(mech, backend="c", levels=["loaded"], sensitivity=False)

    def refused(*args, **kwargs):
        raise AssertionError("the C sweep asked the numpy module for its frequencies")

    vary = variation.parse_vary(["m=±0.02"], mech, ev.defaults)
    grid = variation.parse_grid(GRID, mech)
    with pytest.MonkeyPatch.context() as patch:
        # the module stays for the plates' report, not for the modes
        patch.setattr(ev.module, "modes", refused)
        result = sweep.run(
            ev, mech, vary, grid, 4, seed=3, scheduler=sweep.parse_scheduler("sync"), level="loaded"
        )
    return path, mech, ev, vary, grid, result


def test_the_c_sweeps_frequencies_are_the_c_evaluators(swept_c):
    _, mech, ev, vary, grid, result = swept_c
    assert sweep.frequency_backend(ev) == "c" and result.first_backend == "c"
    assert result.failed == 0 and result.first is not None
    assert result.nominal_first == pytest.approx(lowest(mech, grid), rel=1e-9)
    task = sweep.Task(
        ev,
        "loaded",
        grid.rows,
        tuple((p, s, ev.defaults[p]) for p, s in vary.items()),
        3,
        4,
        sweep.geometry_checks(mech),
        tuple(p.symbol for p in mech.parameters),
    )
    params, _ = sweep.sample_block(task, 0)
    m = list(ev.sources.params).index("m")
    for k in range(4):
        mass = float(params[k, m])
        assert result.first[k] == pytest.approx(lowest(mech, grid, {"m": mass}), rel=1e-9)
        formula = math.sqrt(2 * leaf_stiffness() / mass) / (2 * math.pi)
        assert result.first[k] == pytest.approx(formula, rel=1e-3)
    assert result.as_json()["frequencies_backend"] == "c"
    assert "(Hz, by the C evaluator's stage_modes;" in sweep.text(result)


def test_the_command_says_which_backend_computed_them(swept_c, capsys):
    path = swept_c[0]
    for backend, words in (("c", "the C evaluator's"), ("numpy", "the generated numpy module's")):
        args = ["sweep", str(path), "--level", "loaded", "--vary", "m=±0.02", "--samples", "2"]
        args += ["--backend", backend, "--scheduler", "sync"]
        for item in GRID:
            args += ["--input", item]
        assert main(args) == 0
        out = capsys.readouterr().out
        assert f"(Hz, by {words}" in out, out
        assert main([*args, "--json"]) == 0
        assert json.loads(capsys.readouterr().out)["frequencies_backend"] == backend
