"""The docs/benchmarks.md block of the benchmarks and the targets they are held to."""

from __future__ import annotations

import math

from common import ROOT, log

START, END = "<!-- benchmarks:start -->", "<!-- benchmarks:end -->"


def fmt_ratio(x: float | None) -> str:
    """A ratio as the tables show it: 2,097×, 53×, 3.8×."""
    if x is None:
        return "—"
    if x >= 100:
        return f"{x:,.0f}×"
    if x >= 10:
        return f"{x:.0f}×"
    return f"{x:.2g}×" if x < 1 else f"{x:.1f}×"


def fmt_exp(x):
    """An exponent with two decimals, or a dash."""
    return "—" if x is None else f"{x:.2f}"


def render(results: dict) -> str:
    """The docs/benchmarks.md block of one run's results."""
    m = results["machine"]
    ev = results["evaluators"]
    ex = list(ev)
    sf = results["symforce"]
    lines = []
    quick = {
        "quick": " (`--quick`: smaller sizes)",
        "smoke": " (`--smoke`: a check that every part runs, not a measurement)",
    }.get(results.get("sizes", "quick" if results["quick"] else "full"), "")
    lines.append(
        f"Measured {results['date']} by `python benchmarks/run.py`{quick} in "
        f"{results['total_s'] / 60:.1f} min (symkin at commit {results['symkin_commit']}"
        f"{' with uncommitted changes' if results.get('symkin_dirty') else ''}) on: "
        f"{m['cpu']}, {m['cores']} cores, "
        f"{m['mem_total_gb']} GB, {m['system']}; Python {m['python']}, numpy {m['numpy']}, "
        f"sympy {m['sympy']}, scipy {m['scipy']}, SymForce "
        f"{sf['version'] or 'not installed'}; {m['cc']} (`{m['c_flags']}`). "
        "Raw numbers (absolute times too): `benchmarks/results.json`."
    )
    lines.append("")
    lines.append(
        "Per point, exact level: time of each alternative ÷ time of symkin's generated C "
        "(C timed inside C over 10^4 points; higher = symkin faster)."
    )
    lines.append("")
    lines.append("| alternative ÷ symkin C | " + " | ".join(ex) + " | target |")
    lines.append("| --- | " + " | ".join("---:" for _ in ex) + " | --- |")
    rows = [
        ("scipy.optimize.root on the loop equations", "scipy_root", "≥ 1000×"),
        ("sympy.lambdify of the closed form, dyads substituted", "lambdify", "≥ 50×"),
        ("the same with lambdify(cse=True)", "lambdify_cse", "≥ 50×"),
        ("symkin numpy, per point (10^4 vectorized)", "numpy_vectorized_1e4", ""),
        ("SymForce-generated C++, same algorithm", "symforce", ""),
    ]
    check_of = {
        "scipy_root": "scipy",
        "lambdify": "lambdify",
        "lambdify_cse": "lambdify_cse",
        "numpy_vectorized_1e4": "numpy",
        "symforce": "symforce",
    }
    notes = []
    for label, key, target in rows:
        cells = []
        for e in ex:
            r = ev[e]
            if key in r["ratios"]:
                ok = r["verified"].get(check_of[key], False)
                cells.append(fmt_ratio(r["ratios"][key]) + ("" if ok else " (unverified)"))
            else:
                cells.append("n/a")
                note = r["notes"].get(check_of[key])
                if note and f"{key}: {note}" not in notes:
                    notes.append(f"{key}: {note}")
        lines.append(f"| {label} | " + " | ".join(cells) + f" | {target} |")
    lines.append(
        "| symkin C at the paper level ÷ at the exact level | "
        + " | ".join(
            fmt_ratio(ev[e]["per_point_s"]["c_paper"] / ev[e]["per_point_s"]["c_exact"]) for e in ex
        )
        + " | |"
    )
    for n in notes:
        lines.append(f"\n(n/a — {n})")
    lines.append("")
    lines.append(
        "Throughput, exact level: symkin numpy on "
        f"{ev[ex[0]]['throughput']['points']:.0e} points in one call ÷ the C evaluator "
        "called on the same points in a C loop (target ≤ 3×).".replace("1e+06", "10^6").replace(
            "1e+05", "10^5"
        )
    )
    lines.append("")
    lines.append("| | " + " | ".join(ex) + " |")
    lines.append("| --- | " + " | ".join("---:" for _ in ex) + " |")
    lines.append(
        "| numpy ÷ C loop | "
        + " | ".join(fmt_ratio(ev[e]["throughput"]["ratio_numpy_over_c"]) for e in ex)
        + " |"
    )
    lines.append("")
    if not sf["available"]:
        lines.append(f"SymForce: {sf['note'] or 'not available'}.")
        lines.append("")
    dv = results["derivation"]
    lines.append(
        "Derivation (`symkin.studies.derive.generate`, all levels, emitters "
        f"{', '.join(dv['emitters'])}; each case in a fresh process; time excludes "
        "start-up and imports; memory = peak RSS (VmHWM) above the RSS after importing symkin "
        "and its emitter modules, so it includes what they import lazily, e.g. "
        "matplotlib for the figures; budget "
        f"{dv['budget_s']:.0f} s per case):"
    )
    lines.append("")
    lines.append(
        "| case | links / hinges / loops | hinges × mean path | time | of which LaTeX "
        "| peak memory |"
    )
    lines.append("| --- | --- | ---: | ---: | ---: | ---: |")
    for c in dv["examples"] + dv["serial"] + dv["ladder"]:
        label = c["case"] if c["kind"] == "example" else f"{c['kind']} {c['case']}"
        if c.get("over_budget"):
            lines.append(
                f"| {label} | {c['links']} / {c['hinges']} / {c['loops']} | "
                f"{c['size']:.0f} | over budget (> {c['budget_s']:.0f} s)"
                + (", not run" if c.get("skipped") else "")
                + " | | |"
            )
            continue
        if "error" in c:
            lines.append(f"| {label} | | | error | | |")
            continue
        extra = ""
        if c["kind"] == "example" and "cli" in c:
            extra = f" (CLI {c['cli']['wall_s']:.1f} s)"
        lines.append(
            f"| {label} | {c['links']} / {c['hinges']} / {c['loops']} | "
            f"{c['size']:.0f} | {c['derive_s']:.2f} s{extra} | "
            f"{c['derive_s'] - c['without_latex_s']:.2f} s | "
            f"{c['maxrss_mb'] - c['baseline_rss_mb']:.0f} MB |"
        )
    lines.append("")
    lines.append(
        "Growth exponent b of derivation time ∝ x^b (least squares on log-log over the "
        "three largest measured sizes; in brackets over all measured sizes, pulled down "
        "by the ~1.5 s constant of the small cases):"
    )
    lines.append("")
    lines.append(
        "| family | time vs x = hinges × mean path | same, two largest only | "
        "time vs x = hinges | time without LaTeX vs hinges × mean path | "
        "peak memory vs hinges |"
    )
    lines.append("| --- | ---: | ---: | ---: | ---: | ---: |")
    for fam in ("serial", "ladder"):
        e = dv["exponents"][fam]
        lines.append(
            f"| {fam} | {fmt_exp(e['time_vs_size_largest3'])} "
            f"({fmt_exp(e['time_vs_size'])}) | {fmt_exp(e['time_vs_size_last_step'])} | "
            f"{fmt_exp(e['time_vs_hinges_largest3'])} "
            f"({fmt_exp(e['time_vs_hinges'])}) | "
            f"{fmt_exp(e['core_vs_size_largest3'])} | "
            f"{fmt_exp(e['memory_vs_hinges_largest3'])} |"
        )
    lines.append("")
    lines.append("Targets:")
    lines.append("")
    for t in results["targets"]:
        lines.append(f"- {'met' if t['met'] else 'MISSED'}: {t['text']} — measured {t['measured']}")
    lines.append("")
    lines.append(
        "What is timed: *symkin C* — the generated `<name>_evaluate` (level 2), compiled with "
        "the flags above in its own translation unit, called from a C loop that reads "
        "`clock_gettime(CLOCK_MONOTONIC)` (no ctypes overhead). *numpy* — the generated module's "
        "`evaluate` on arrays. *lambdify* — `sympy.lambdify` (symkin's float64 kernels + `math`, "
        "scalar calls; plain, and with `cse=True`) of symkin's routines before CSE with the "
        "dyad assignments substituted into one expression per output, driven in Python by the "
        "same steps as the C (closed-form rigid angles, its Newton polish step(s), first-order δ, "
        "Newton on δ, `numpy.linalg.solve` for the small systems, rigid position and "
        "deviation); results.json also has `lambdify_cse_no_polish`. *scipy* — "
        "`scipy.optimize.root` (hybr, xtol 1e-12, finite-difference Jacobian) on the per-chord "
        "angular and positional loop closures lambdified with numpy, rigid pose from the "
        "as-fabricated pose, compliant pose from the rigid one, deviation = compliant − rigid "
        "point position. *SymForce* — the same routines generated by SymForce's C++ codegen "
        "(its own CSE, Eigen types, symkin's kernels via `override_methods`), driven by a C++ "
        "copy of symkin's algorithm (the same polish step(s), first-order start and Newton "
        "stopping rule, from symkin.core.settings), timed like the C. Each alternative's "
        "deviation is first checked "
        "against the C evaluator on 5 points (relative tolerance: numpy 1e-12, lambdify and "
        "SymForce 1e-9, scipy 1e-5), and the C against symkin's 40-digit mpmath evaluation."
    )
    return "\n".join(lines)


def targets(results: dict) -> list[dict]:
    """Each target of the benchmarks, met or not, with what was measured."""
    ev = results["evaluators"]
    out = []
    sci = {e: r["ratios"].get("scipy_root") for e, r in ev.items()}
    out.append(
        {
            "text": "exact-level C ≥ 1000× faster per point than scipy.optimize.root",
            "met": all(v is not None and v >= 1000 for v in sci.values()),
            "measured": ", ".join(f"{e} {fmt_ratio(v)}" for e, v in sci.items()),
        }
    )
    lam = {
        e: min(r["ratios"]["lambdify"], r["ratios"]["lambdify_cse"])
        for e, r in ev.items()
        if r["ratios"].get("lambdify") is not None
    }
    out.append(
        {
            "text": "≥ 50× faster than lambdify where a closed form exists (the faster of "
            "plain and cse=True)",
            "met": bool(lam) and all(v >= 50 for v in lam.values()),
            "measured": ", ".join(f"{e} {fmt_ratio(v)}" for e, v in lam.items()),
        }
    )
    th = {e: r["throughput"]["ratio_numpy_over_c"] for e, r in ev.items()}
    out.append(
        {
            "text": f"numpy on {ev[next(iter(ev))]['throughput']['points']:.0e} points "
            "within 3× of the C loop".replace("1e+06", "10^6").replace("1e+05", "10^5"),
            "met": all(v <= 3 for v in th.values()),
            "measured": ", ".join(f"{e} {fmt_ratio(v)}" for e, v in th.items()),
        }
    )
    dv = results["derivation"]
    nine = next((c for c in dv["examples"] if c["case"] == "nine_bar_platform"), None)
    if nine and "derive_s" in nine:
        cli = nine.get("cli", {}).get("wall_s")
        out.append(
            {
                "text": "`symkin derive` of the nine-bar, all levels and backends, < 5 s",
                "met": nine["derive_s"] < 5 and (cli is None or cli < 5),
                "measured": f"{nine['derive_s']:.2f} s in process, "
                f"{cli:.2f} s for the whole command (emitters "
                f"{', '.join(nine['emit'])})",
            }
        )
    s64 = next((c for c in dv["serial"] if c["case"] == "64"), None)
    if s64 is not None:
        met = not s64.get("over_budget") and s64.get("derive_s", 1e9) < 30
        out.append(
            {
                "text": "64-link serial chain < 30 s",
                "met": met,
                "measured": (f"{s64['derive_s']:.2f} s" if "derive_s" in s64 else "over budget"),
            }
        )
    for fam in ("serial", "ladder"):
        e = dv["exponents"][fam]["time_vs_size_largest3"]
        step = dv["exponents"][fam]["time_vs_size_last_step"]
        over = [c for c in dv[fam] if c.get("over_budget")]
        done = [c for c in dv[fam] if "derive_s" in c]
        text = (
            f"exponent {fmt_exp(e)} over the three largest measured, {fmt_exp(step)} "
            f"between the two largest"
        )
        bound = None
        if over and done:
            # the first over-budget member bounds the exponent from below
            last, first_over = done[-1], over[0]
            bound = math.log(first_over["budget_s"] / last["derive_s"]) / math.log(
                first_over["size"] / last["size"]
            )
            dv["exponents"][fam]["lower_bound_from_budget"] = bound
            text += (
                f"; {fam} {', '.join(c['case'] for c in over)} over budget (linear "
                f"growth from {fam} {last['case']} would take "
                f"{last['derive_s'] * first_over['size'] / last['size']:.0f} s, so the "
                "budget only bounds the exponent from below, by "
                f"{bound:.2f}: not shown)"
            )
        out.append(
            {
                "text": f"{fam}: derivation time about linear in hinges × path length "
                "(exponent ≤ 1.2, every size measured)",
                "met": (
                    e is not None and e <= 1.2 and step is not None and step <= 1.2 and not over
                ),
                "measured": text,
            }
        )
    return out


def write_page(block: str, start: str = START, end: str = END) -> bool:
    """Rewrite the block between two markers of docs/benchmarks.md; False when there are none."""
    path = ROOT / "docs" / "benchmarks.md"
    text = path.read_text()
    if start not in text or end not in text:
        log(f"docs/benchmarks.md has no {start} ... {end} markers: not written")
        return False
    head, rest = text.split(start, 1)
    _, tail = rest.split(end, 1)
    path.write_text(head + start + "\n" + block + "\n" + end + tail)
    return True
