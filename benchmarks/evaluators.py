"""Per point, exact level, for one example: symkin's generated C and numpy against lambdify,
scipy and SymForce, every alternative first checked against the C evaluator; then the
throughput of numpy on many points against the C loop."""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
from common import EXACT, EXAMPLES, POLICY, ROOT, TOL, Sizes, best_time, log, relerr
from lambdify_alt import lambdify_alternative, substituted
from scipy_alt import scipy_alternative
from symforce_alt import SFBench, symforce_build
from symkin_c import CBench, compile_c

from symkin.core.levels import LEVELS


def bench_example(example: str, sizes: Sizes, sf: dict, workroot: Path) -> dict:
    """Every alternative's time per point at the exact level, checked, and the throughput."""
    import symkin
    from symkin.codegen import pipeline
    from symkin.codegen.plan import plan as make_plan

    log(f"evaluators: {example}")
    mech = symkin.load(ROOT / "examples" / f"{example}.toml")
    an = symkin.analyze(mech)
    ranges = EXAMPLES[example]
    names = list(mech.inputs)
    rng = np.random.default_rng(1)

    def sample(n):
        return np.column_stack([rng.uniform(*ranges[k], n) for k in names])

    p = pipeline.plan_for(an)
    source = f"{example}.toml"
    header, code = pipeline.emit(p, "c", source)
    work = workroot / example
    work.mkdir(parents=True, exist_ok=True)
    cb = CBench(compile_c(work, mech.name, header, code), mech.name, len(names), len(p.points))
    npmod = pipeline.evaluator(p, "numpy", source)
    res: dict = {
        "inputs": {k: list(v) for k, v in ranges.items()},
        "point": p.points[0],
        "k_unknowns": len(an.deltas),
        "needs_loops": p.needs_loops,
        "closed_form": p.closed_form,
        "checks": {},
        "per_point_s": {},
        "notes": {},
    }

    # the C evaluator, checked against the mpmath reference (40 digits)
    check_x = sample(5)
    _, c_out, fails = cb.run(check_x, EXACT)
    assert fails == 0, f"{example}: C evaluator failed on the check points"
    c_dev = c_out[:, 0, 4:6]
    errs = []
    for i in range(2):
        ref = symkin.evaluate(an, dict(zip(names, map(float, check_x[i]))), "exact")
        errs.append(relerr(c_dev[i], ref.points[p.points[0]].deviation))
    res["checks"]["c_vs_mpmath"] = max(errs)

    n_c = sizes.points
    xs = sample(n_c)
    _, _, fails = cb.run(xs, EXACT)
    assert fails == 0, f"{example}: C evaluator failed on {fails} of the sample points"
    for lv in LEVELS:
        if lv.generated:
            res["per_point_s"][f"c_{lv.name}"] = cb.per_point(xs, lv.code, sizes.c_time)
    t_c = res["per_point_s"]["c"] = res["per_point_s"]["c_exact"]

    # numpy module, vectorized over the sampled points
    np_in = {k: xs[:, j] for j, k in enumerate(names)}
    out = npmod.evaluate(
        {k: v[:5] for k, v in {k: check_x[:, j] for j, k in enumerate(names)}.items()}, "exact"
    )
    res["checks"]["numpy"] = max(
        relerr(out["points"][p.points[0]]["deviation"][:, i], c_dev[i]) for i in range(5)
    )
    t_np, _ = best_time(lambda: npmod.evaluate(np_in, "exact"), 3, 0.0)
    res["per_point_s"]["numpy_vectorized_1e4"] = t_np / n_c

    # lambdify of the same closed form: plain (substituted, no CSE) and with cse=True
    if p.closed_form:
        raw = make_plan(an, cse=False)
        res["closed_form_ops"] = {
            "symkin_rigid_after_cse": p.routines["rigid"].ops if "rigid" in p.routines else 0
        }
        if "rigid" in raw.routines:
            import sympy as sp

            res["closed_form_ops"]["rigid_substituted"] = int(
                sum(sp.count_ops(e) for e in substituted(raw.routines["rigid"]))
            )
        variants = (
            ("lambdify", False, POLICY["polish"]),
            ("lambdify_cse", True, POLICY["polish"]),
            ("lambdify_cse_no_polish", True, 0),
        )
        for key, cse, polish in variants:
            t0 = time.perf_counter()
            lam = lambdify_alternative(raw, cse, polish)
            res.setdefault("setup_s", {})[key] = time.perf_counter() - t0
            res["checks"][key] = max(relerr(lam(check_x[i])[0], c_dev[i]) for i in range(5))
            n_l = 20 if key == "lambdify" else 100
            t, _ = best_time(lambda: [lam(x) for x in xs[:n_l]], 3, sizes.lambdify_time)
            res["per_point_s"][key] = t / n_l
    else:
        res["notes"]["lambdify"] = res["notes"]["lambdify_cse"] = (
            "no closed form (not all groups are dyads)"
        )

    # scipy.optimize.root on the loop equations
    sci = scipy_alternative(an)
    res["checks"]["scipy"] = max(relerr(sci(check_x[i]), c_dev[i]) for i in range(5))
    t, _ = best_time(lambda: [sci(x) for x in xs[:20]], 3, sizes.scipy_time)
    res["per_point_s"]["scipy_root"] = t / 20

    # SymForce
    if sf.get("available") and p.closed_form:
        try:
            sfw = work / "symforce"
            sfw.mkdir(exist_ok=True)
            lib, gen = symforce_build(make_plan(an, cse=False), sfw)
            sb = SFBench(lib, len(names), len(p.points), [q.value for q in p.parameters])
            _, sf_out, sf_fail = sb.run(check_x)
            assert sf_fail == 0, "SymForce evaluator failed on the check points"
            res["checks"]["symforce"] = max(relerr(sf_out[i, 0, 4:6], c_dev[i]) for i in range(5))
            res["per_point_s"]["symforce"] = sb.per_point(xs, sizes.c_time)
            res["symforce_codegen_s"] = gen
        except Exception as exc:  # report, do not abort the whole run
            res["notes"]["symforce"] = f"failed: {type(exc).__name__}: {str(exc)[:300]}"
    elif not sf.get("available"):
        res["notes"]["symforce"] = sf.get("note") or "SymForce not available"

    res["verified"] = {k: v <= TOL.get(k, 1e-12) for k, v in res["checks"].items()}
    res["verified"]["c_vs_mpmath"] = res["checks"]["c_vs_mpmath"] <= 1e-12
    res["ratios"] = {
        k: v / t_c for k, v in res["per_point_s"].items() if k != "c" and not k.startswith("c_")
    }

    # throughput: numpy on many points in one call vs the C loop over the same points
    n_big = sizes.throughput
    big = sample(n_big)
    c_secs = min(cb.run(big, EXACT)[0] for _ in range(2))
    big_in = {k: big[:, j] for j, k in enumerate(names)}
    t0 = time.perf_counter()
    out = npmod.evaluate(big_in, "exact")
    np_secs = time.perf_counter() - t0
    res["throughput"] = {
        "points": n_big,
        "c_loop_s": c_secs,
        "numpy_s": np_secs,
        "ratio_numpy_over_c": np_secs / c_secs,
        "numpy_ok_fraction": float(np.mean(out["ok"])),
    }
    del out
    return res
