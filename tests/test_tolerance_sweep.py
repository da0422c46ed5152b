"""`symkin tolerance` and `symkin sweep` (docs/cli.md): the linear stack-up against Monte Carlo
evaluations of the mechanism itself, bit-identical sweeps whatever the scheduler, chunking or
workers (a real distributed.LocalCluster with two worker processes included), failed samples
counted, and bad options refused before any work.
"""

from __future__ import annotations

import json
import math

import mechanisms as M
import numpy as np
import pytest
from conftest import EXAMPLES
from evaluators import require_compiler

import symkin
from symkin.cli.commands import main
from symkin.studies import sweep, tolerance, variation
from symkin.studies.evaluation import evaluate

_STATE: dict = {}


def setup():
    """The parameterised four-bar, its mechanism, analysis and compiled C evaluator."""
    if not _STATE:
        require_compiler()
        mech = symkin.loads(M.PARAM_FOUR_BAR, "param_four_bar.toml")
        an = symkin.analyze(mech)
        _STATE.update(mech=mech, analysis=an, ev=symkin.compile(an, levels=["exact"]))
    require_compiler()
    return _STATE["mech"], _STATE["analysis"], _STATE["ev"]


def nominal(mech) -> dict[str, float]:
    return {p.name: float(p.value) for p in mech.parameters}


def spreads(mech, items: list[str], kinds=variation.KINDS):
    return variation.parse_vary(items, mech, nominal(mech), kinds)


def test_tolerance_against_the_mpmath_sensitivities():
    """w and r at the reported configuration, recomputed from the 40-digit sensitivities."""
    mech, an, ev = setup()
    vary = spreads(mech, ["l=±2e-5", "ax=±3e-5", "g=±1%", "tilt=±0.005"], ("pm",))
    grid = variation.parse_grid(["A0=-0.3:0.3:13"], mech)
    result = tolerance.run(ev, vary, grid, "exact")
    stack = result.points["C"].worst
    ref = evaluate(an, {"A0": stack.at["A0"]}, "exact", sensitivity=True)
    dev = ref.points["C"].deviation
    rates = {
        p: (
            dev[0] * ref.sensitivity.deviation["C"][p][0]
            + dev[1] * ref.sensitivity.deviation["C"][p][1]
        )
        / math.hypot(*dev)
        for p in vary
    }
    a = {p: s.half_width for p, s in vary.items()}
    assert a["g"] == pytest.approx(0.01 * 0.8517, rel=1e-15)
    w = sum(a[p] * abs(rates[p]) for p in vary)
    r = math.sqrt(sum((a[p] * rates[p]) ** 2 for p in vary))
    assert stack.worst_case == pytest.approx(w, rel=1e-9)
    assert stack.rss == pytest.approx(r, rel=1e-9)
    assert sum(stack.contributions.values()) == pytest.approx(1.0, rel=1e-12)
    assert list(stack.contributions.values()) == sorted(stack.contributions.values(), reverse=True)
    assert result.points["C"].worst.worst_case >= result.points["C"].rss.rss


def test_monte_carlo_std_matches_the_rss_stack_up():
    """Small normal spreads (sigma = a) at one input: the Monte Carlo std of |ΔR| is the RSS
    within its sampling error, and the mean is the nominal value."""
    mech, _, ev = setup()
    items = ["l=±1e-6", "ax=±2e-6", "bx=±2e-6", "g=±0.001", "tilt=±0.001"]
    tol = tolerance.run(
        ev, spreads(mech, items, ("pm",)), variation.parse_grid(["A0=0.25"], mech), "exact"
    )
    values = nominal(mech)
    normal = [
        f"{p.split('=')[0]}=normal({values[p.split('=')[0]]!r},{p.split('±')[1]})" for p in items
    ]
    samples = 4000
    result = sweep.run(
        ev,
        mech,
        spreads(mech, normal),
        variation.parse_grid(["A0=0.25"], mech),
        samples,
        seed=7,
        scheduler=sweep.parse_scheduler("threads:2"),
        level="exact",
    )
    stats = result.statistics("C")
    assert result.failed == 0
    rss = tol.points["C"].rss.rss
    sampling = rss / math.sqrt(2 * (samples - 1))  # std error of a normal std
    assert abs(stats["std"] - rss) < 4 * sampling, (stats["std"], rss)
    mean_error = rss / math.sqrt(samples)
    assert abs(stats["mean"] - tol.points["C"].peak.nominal) < 4 * mean_error


def test_worst_case_bounds_every_samples_linear_estimate():
    """For ±a spreads, every sample's first-order change Σ g_p e_p at every configuration is
    within the worst case there, and the evaluated change is that estimate up to second order."""
    mech, _, ev = setup()
    vary = spreads(mech, ["l=±5e-6", "ay=±1e-5", "tilt=±0.002", "cx=±1e-5"], ("pm",))
    grid = variation.parse_grid(["A0=-0.3:0.3:6"], mech)  # not the as-fabricated pose
    x = grid.rows
    status, values, dev, _ = ev.sensitivity_rows(x, "exact")
    assert (status == 0).all()
    names = list(ev.sources.params)
    d0 = values[:, 4:6]
    norm0 = np.hypot(d0[:, 0], d0[:, 1])
    g = {
        p: (d0[:, 0] * dev[:, 0, names.index(p), 0] + d0[:, 1] * dev[:, 0, names.index(p), 1])
        / norm0
        for p in vary
    }
    w = sum(s.half_width * np.abs(g[p]) for p, s in vary.items())
    task = sweep.Task(
        ev,
        "exact",
        x,
        tuple((p, s, nominal(mech)[p]) for p, s in vary.items()),
        3,
        512,
        sweep.geometry_checks(mech),
        tuple(q.symbol for q in mech.parameters),
    )
    checked = 0
    for block in range(2):
        params, valid = sweep.sample_block(task, block)
        assert valid.all()
        status, out = ev.library.evaluate_grid(params, x, 2)
        assert (status == 0).all()
        rng = np.random.default_rng([3, block])
        offsets = {p: s.offsets(rng, len(params), nominal(mech)[p]) for p, s in vary.items()}
        for k in range(len(params)):
            estimate = sum(g[p] * offsets[p][k] for p in vary)
            assert (np.abs(estimate) <= w * (1 + 1e-12)).all()
            actual = np.hypot(out[k, :, 4], out[k, :, 5]) - norm0
            assert (np.abs(actual - estimate) <= 0.02 * w).all()  # second order: tiny
            checked += 1
    assert checked == 512


def sweep_values(scheduler: str, chunks: int | None, client=None, samples: int = 700):
    mech, _, ev = setup()
    vary = spreads(mech, ["l=normal(1e-3,2e-5)", "ax=±3e-5", "g=uniform(0.84,0.86)"])
    grid = variation.parse_grid(["A0=-0.3:0.3:9"], mech)
    return sweep.run(
        ev,
        mech,
        vary,
        grid,
        samples,
        seed=11,
        scheduler=sweep.parse_scheduler(scheduler),
        level="exact",
        chunks=chunks,
        client=client,
    )


def test_same_seed_same_bits_whatever_the_scheduler_and_chunking():
    reference = sweep_values("sync", 1)
    assert reference.samples == 700 and reference.failed == 0
    for scheduler, chunks in (("threads:2", 3), ("threads:1", None), ("processes:2", 2)):
        other = sweep_values(scheduler, chunks)
        assert np.array_equal(other.values, reference.values), scheduler
        assert other.as_json()["points"] == reference.as_json()["points"]
    assert np.isfinite(reference.values).all()


def test_a_local_distributed_cluster_gives_the_same_statistics():
    """A real distributed.LocalCluster with two worker processes, reached by its address."""
    import distributed  # a dependency of symkin (pyproject)

    reference = sweep_values("threads:2", None)
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    ) as cluster:
        result = sweep_values(cluster.scheduler_address, None)
    assert result.scheduler.startswith("tcp://")
    assert np.array_equal(result.values, reference.values)
    assert result.as_json()["points"] == reference.as_json()["points"]


def test_failed_and_invalid_samples_are_counted():
    mech, _, ev = setup()
    # a crank as long as 0.08 cannot turn to 1.2 rad; a plate length below zero breaks a rule
    vary = spreads(mech, ["ay=uniform(0.02,0.08)", "l=uniform(-2e-4,1.8e-3)"])
    grid = variation.parse_grid(["A0=0:1.2:5"], mech)
    result = sweep.run(
        ev,
        mech,
        vary,
        grid,
        600,
        seed=1,
        scheduler=sweep.parse_scheduler("threads:2"),
        level="exact",
    )
    assert result.invalid > 0 and result.failed > result.invalid
    assert np.isnan(result.values[result.flags != 0]).all()
    assert np.isfinite(result.values[result.flags == 0]).all()
    doc = result.as_json()
    assert doc["failed"] == result.failed and doc["samples"] == 600
    # the statistics are those of the evaluated samples, recomputed here
    kept = result.values[result.flags == 0, 0]
    assert doc["points"]["C"]["max"] == float(kept.max())
    assert doc["points"]["C"]["mean"] == pytest.approx(float(kept.mean()), rel=1e-12)


def test_sweep_cli_json(tmp_path, capsys):
    require_compiler()
    path = tmp_path / "pfb.toml"
    path.write_text(M.PARAM_FOUR_BAR)
    plot = tmp_path / "h.png"
    code = main(
        [
            "sweep",
            str(path),
            "--vary",
            "l=normal(1e-3,1e-5)",
            "--vary",
            "bx=±1e-5",
            "--input",
            "A0=-0.2:0.2:5",
            "--samples",
            "300",
            "--seed",
            "4",
            "--json",
            "--plot",
            str(plot),
            "--scheduler",
            "threads:2",
        ]
    )
    out, err = capsys.readouterr()
    assert code == 0, err
    doc = json.loads(out)
    assert {"samples", "failed", "seed", "scheduler", "seconds", "points"} <= set(doc)
    assert set(doc["points"]["C"]) >= {"mean", "std", "p50", "p99", "p999", "max"}
    assert doc["samples"] == 300 and doc["seed"] == 4 and doc["scheduler"] == "threads:2"
    assert err == "" and plot.read_bytes().startswith(b"\x89PNG")


def test_tolerance_cli(tmp_path, capsys):
    require_compiler()
    path = tmp_path / "pfb.toml"
    path.write_text(M.PARAM_FOUR_BAR)
    code = main(
        [
            "tolerance",
            str(path),
            "--vary",
            "l=±1e-5",
            "--vary",
            "g=±1%",
            "--input",
            "A0=-0.2:0.2:5",
            "--json",
        ]
    )
    out, err = capsys.readouterr()
    assert code == 0, err
    doc = json.loads(out)
    point = doc["points"]["C"]
    assert {"worst_case", "rss", "contributions"} <= set(point)
    assert set(point["contributions"]) == {"l", "g"}
    code = main(["tolerance", str(path), "--vary", "l=±1e-5", "--input", "A0=0.2"])
    out, _ = capsys.readouterr()
    assert code == 0 and "share" in out and "worst case" in out


@pytest.mark.parametrize(
    "args,fragment",
    [
        (["--vary", "l=foo(1,2)"], "not a spread"),
        (["--vary", "l=normal(__import__('os'),1)"], "--vary l"),
        (["--vary", "nope=±1"], "not a parameter"),
        (["--vary", "l=normal(1e-3,-1)"], "sigma must be positive"),
        (["--vary", "l=uniform(2,1)"], "empty interval"),
        (["--vary", "l=±1e-5", "--input", "A0=0:9"], "beyond a half turn"),
        (["--vary", "l=±1e-5", "--samples", "1"], "--samples"),
        (["--vary", "l=±1e-5", "--plot", "/no/such/folder/x.png"], "--plot"),
        (["--vary", "l=±1e-5", "--scheduler", "nonsense"], "unknown scheduler"),
        (["--vary", "l=±1e-5", "--scheduler", "tcp://127.0.0.1:1"], "cannot reach"),
    ],
)
def test_sweep_refuses_bad_options_before_work(args, fragment, tmp_path, capsys):
    path = tmp_path / "pfb.toml"
    path.write_text(M.PARAM_FOUR_BAR)
    code = main(["sweep", str(path), *args])
    err = capsys.readouterr().err
    assert code == 2, err
    assert fragment in err and "fix:" in err


def test_tolerance_at_a_level_without_sensitivities_names_the_levels_that_have_them(capsys):
    """Every generated level has sensitivities (`loaded` too); `equilibrium` has none: the
    command line does not offer it (exit 2), and the check says so, naming the levels that
    have them."""
    path = str(EXAMPLES / "four_bar.toml")
    with pytest.raises(SystemExit) as stopped:
        main(["tolerance", path, "--vary", "l=±1e-5", "--level", "equilibrium"])
    err = capsys.readouterr().err
    assert stopped.value.code == 2 and "invalid choice" in err, err
    with pytest.raises(symkin.InputError) as found:
        tolerance.check_level("equilibrium")
    err = found.value.render()
    assert "the equilibrium level has no sensitivities" in err, err
    assert "paper, first_order, exact, loaded" in err
