"""Single notch hinges: a plane-strain CalculiX continuum against the beam integrals over T(x)
(docs/physics.md, "Notch hinges: the continuum correction"; docs/fea.md, "One notch").

    python benchmarks/notch_continuum.py [--only study|points] [--out benchmarks/results-notch.json]
                                         [--decks DIR]

Every run is one notch (symkin.fea.notch_mesh): P's end face clamped, M's end face rigid, a
transverse force and then a pure moment at the centre of M's end section, small deflections,
millimetres. The beam integrals ∫ x^k / E'I(x) dx (Euler–Bernoulli, E' = E/(1 − ν²)) and
∫ dx/κGA(x) (Timoshenko, κ = 5/6) are mpmath quadratures at 40 digits. The continuum correction
of symkin.model.notch_correction is the least-squares fit of FE/beam written here (its
coefficients are printed; the module holds them, tests/test_notch_correction.py refits them from
this JSON).

ccx runs are cached in the JSON by their mesh and profile: a second call only runs what is
missing. One ccx at a time, one thread; about 10 minutes of processor time in all.
"""

from __future__ import annotations

import argparse
import json
import math
import platform
import sys
from pathlib import Path

import mpmath
import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from symkin.fea import notch_mesh  # noqa: E402

OUT = ROOT / "benchmarks" / "results-notch.json"
#: Material and width (MPa, mm): steel, unit width; the compliances scale as 1/(E b).
E, NU, WIDTH = 210_000.0, 0.3, 1.0
#: The circular notches' radius (mm) and thinnest thickness over radius.
RADIUS = 1.0
RATIOS = (0.02, 0.05, 0.1, 0.2, 0.3, 0.5)
#: The mesh study: elements across the thickness (columns about one thickness/across long).
STUDY = (4, 8, 16, 32)
#: The mesh the other profiles are run at (docs/physics.md), and the finer one that checks it on
#: a deep ellipse and a corner-filleted plate (the fillets' roots).
POINT_MESH = 16
CHECK_MESH = 32
DIGITS = 40


# -- profiles: T(x) over [0, span], x from P's end (docs/file-format.md's formulas, the centre
# at span/2)


def circular(t: float, r: float) -> tuple[float, object]:
    def depth(x: float) -> float:
        u = x - r
        return t + 2 * (r - math.sqrt(max(r * r - u * u, 0.0)))

    return 2 * r, depth


def elliptical(t: float, a: float, c: float) -> tuple[float, object]:
    def depth(x: float) -> float:
        u = (x - a) / a
        return t + 2 * c * (1 - math.sqrt(max(1 - u * u, 0.0)))

    return 2 * a, depth


def corner_filleted(t: float, length: float, r: float) -> tuple[float, object]:
    def depth(x: float) -> float:
        u = abs(x - length / 2) - (length / 2 - r)
        if u <= 0:
            return t
        return t + 2 * (r - math.sqrt(max(r * r - u * u, 0.0)))

    return length, depth


def uniform(t: float, length: float) -> tuple[float, object]:
    return length, lambda x: t


def mp_depth(kind: str, p: dict) -> tuple[mpmath.mpf, object, list]:
    """The same T(x) in mpmath, the span and the breakpoints of the quadrature."""
    t = mpmath.mpf(p["t"])
    if kind == "circular":
        r = mpmath.mpf(p["R"])
        w = mpmath.sqrt(t * r)
        pts = [0, r - 8 * w, r - w, r, r + w, r + 8 * w, 2 * r]
        return 2 * r, lambda x: t + 2 * (r - mpmath.sqrt(r * r - (x - r) ** 2)), pts
    if kind == "elliptical":
        a, c = mpmath.mpf(p["a"]), mpmath.mpf(p["c"])
        w = mpmath.sqrt(t * a * a / c)
        pts = [0, a - 8 * w, a - w, a, a + w, a + 8 * w, 2 * a]
        return 2 * a, lambda x: t + 2 * c * (1 - mpmath.sqrt(1 - ((x - a) / a) ** 2)), pts
    if kind == "uniform":
        return mpmath.mpf(p["l"]), lambda x: t, [0, mpmath.mpf(p["l"]) / 2, mpmath.mpf(p["l"])]
    length, r = mpmath.mpf(p["l"]), mpmath.mpf(p["r"])

    def depth(x):
        u = abs(x - length / 2) - (length / 2 - r)
        return t if u <= 0 else t + 2 * (r - mpmath.sqrt(r * r - u * u))

    return length, depth, [0, r, length / 2, length - r, length]


def beam(kind: str, p: dict) -> dict:
    """The beam's compliances at the centre of M's end (mm, N): Euler–Bernoulli θ_M, θ_F = y_M,
    y_F and the shear ∫dx/κGA; under a pure moment, the notch centre's deflection over R·θ."""
    with mpmath.workdps(DIGITS):
        span, depth, pts = mp_depth(kind, p)
        pts = sorted({mpmath.mpf(x) for x in pts if 0 <= x <= span})
        e1 = mpmath.mpf(E) / (1 - mpmath.mpf(NU) ** 2)
        g = mpmath.mpf(E) / (2 * (1 + mpmath.mpf(NU)))
        ei = lambda x: e1 * WIDTH * depth(x) ** 3 / 12  # noqa: E731
        q = lambda f: mpmath.quad(f, pts)  # noqa: E731
        theta_m = q(lambda x: 1 / ei(x))
        theta_f = q(lambda x: (span - x) / ei(x))
        y_f = q(lambda x: (span - x) ** 2 / ei(x))
        shear = q(lambda x: 1 / (mpmath.mpf(5) / 6 * g * WIDTH * depth(x)))
        half = [x for x in pts if x <= span / 2]
        centre = mpmath.quad(lambda x: (span / 2 - x) / ei(x), half)
        return {
            "theta_M": float(theta_m),
            "theta_F": float(theta_f),
            "y_F": float(y_f),
            "y_F_shear": float(shear),
            "centre_over_R_theta": float(centre / (theta_m * span / 2)),
        }


def key(kind: str, p: dict, across: int) -> str:
    return f"{kind} " + " ".join(f"{k}={v:g}" for k, v in p.items()) + f" n={across}"


def shape(kind: str, p: dict) -> tuple[float, object]:
    if kind == "circular":
        return circular(p["t"], p["R"])
    if kind == "elliptical":
        return elliptical(p["t"], p["a"], p["c"])
    if kind == "uniform":
        return uniform(p["t"], p["l"])
    return corner_filleted(p["t"], p["l"], p["r"])


DECKS: Path | None = None  # --decks DIR: every deck written there too


def run(cache: dict, kind: str, p: dict, across: int, out: Path) -> dict:
    k = key(kind, p, across)
    span, depth = shape(kind, p)
    deck = notch_mesh.single_notch(depth, span, WIDTH, E, NU, notch_mesh.NotchMesh(across))
    if DECKS is not None:
        DECKS.mkdir(parents=True, exist_ok=True)
        (DECKS / (k.replace(" ", "_") + ".inp")).write_text(deck.text)
    if k in cache["runs"]:
        return cache["runs"][k]
    r = notch_mesh.solve(deck)
    row = {
        "profile": kind,
        "params": p,
        "across": across,
        "nodes": r.nodes,
        "elements": r.elements,
        "seconds": round(r.seconds, 2),
        "y_F": r.y_F,
        "theta_F": r.theta_F,
        "theta_M": r.theta_M,
        "y_M": r.y_M,
        "centre_M": list(r.centre_M),
        "neck_stress_M": list(r.neck_stress_M),
    }
    cache["runs"][k] = row
    print(f"  {k}: {r.elements} elements, {r.seconds:.1f} s", file=sys.stderr)
    out.write_text(json.dumps(cache, indent=1, sort_keys=True) + "\n")
    return row


def compare(row: dict, b: dict, t: float) -> dict:
    """FE over beam: the factors the correction multiplies the beam's compliances by."""
    timo = b["y_F"] + b["y_F_shear"]
    sigma_nominal = 6 * 1.0 / (WIDTH * t * t)  # the deck's moment is 1 N mm
    return {
        "theta_M": row["theta_M"] / b["theta_M"],
        "theta_F": row["theta_F"] / b["theta_F"],
        "y_M": row["y_M"] / b["theta_F"],
        "y_F_timoshenko": row["y_F"] / timo,
        "y_F_euler_bernoulli": row["y_F"] / b["y_F"],
        "centre_fe": row["centre_M"][1] / (row["theta_M"] * shape_span(row) / 2),
        "centre_beam": b["centre_over_R_theta"],
        "Kt": max(abs(s) for s in row["neck_stress_M"]) / sigma_nominal,
    }


def shape_span(row: dict) -> float:
    return shape(row["profile"], row["params"])[0]


#: The fit: factor = 1 + c1 τ + c2 τ² per compliance (τ = t/R), least squares on the factors.
FITTED = ("theta_M", "theta_F", "y_F_timoshenko")


def fit(table: list[dict]) -> dict:
    tau = np.array([r["t/R"] for r in table])
    a = np.column_stack([tau, tau**2])
    out = {}
    for name in FITTED:
        f = np.array([r["ratio"][name] for r in table])
        coef, *_ = np.linalg.lstsq(a, f - 1, rcond=None)
        resid = (1 + a @ coef) - f
        out[name] = {
            "c1": float(coef[0]),
            "c2": float(coef[1]),
            "max_residual": float(np.max(np.abs(resid / f))),
        }
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", choices=("study", "points"))
    ap.add_argument("--out", type=Path, default=OUT)
    ap.add_argument("--decks", type=Path, help="write every deck (.inp) into this folder too")
    args = ap.parse_args()
    global DECKS
    DECKS = args.decks
    cache = json.loads(args.out.read_text()) if args.out.exists() else {}
    cache.setdefault("runs", {})
    cache["machine"] = {"python": platform.python_version(), "E": E, "nu": NU, "width": WIDTH}
    if args.only in (None, "study"):
        table = []
        print("| t/R | n across | elements | θ_M (rad/N mm) | Δ | y_F (mm/N) | Δ | K_t | Δ |")
        print("|---|---|---|---|---|---|---|---|---|")
        for tau in RATIOS:
            p = {"t": tau * RADIUS, "R": RADIUS}
            prev, prev_kt = None, 1.0
            for n in STUDY:
                row = run(cache, "circular", p, n, args.out)
                kt = max(abs(s) for s in row["neck_stress_M"]) * WIDTH * p["t"] ** 2 / 6
                d = (
                    ["", "", ""]
                    if prev is None
                    else [f"{(row[q] / prev[q] - 1) * 100:+.3f} %" for q in ("theta_M", "y_F")]
                    + [f"{(kt / prev_kt - 1) * 100:+.3f} %"]
                )
                print(
                    f"| {tau:g} | {n} | {row['elements']} | {row['theta_M']:.7g} | {d[0]} | "
                    f"{row['y_F']:.7g} | {d[1]} | {kt:.4f} | {d[2]} |"
                )
                prev, prev_kt = row, kt
            b = beam("circular", p)
            table.append(
                {"t/R": tau, "mesh": STUDY[-1], "beam": b, "ratio": compare(prev, b, p["t"])}
            )
        cache["circular"] = table
        cache["fit"] = fit(table)
        print()
        print(
            "| t/R | θ_M FE/EB | θ_F FE/EB | y_M FE/EB | y_F FE/Timoshenko | y_F FE/EB | "
            "centre FE | centre beam | K_t | (1+t/2R)^0.40 | (1+t/2R)^(9/20) |"
        )
        print("|---|---|---|---|---|---|---|---|---|---|---|")
        for r in table:
            q, tau = r["ratio"], r["t/R"]
            print(
                f"| {tau:g} | {q['theta_M']:.4f} | {q['theta_F']:.4f} | {q['y_M']:.4f} | "
                f"{q['y_F_timoshenko']:.4f} | {q['y_F_euler_bernoulli']:.4f} | "
                f"{q['centre_fe']:.4f} | {q['centre_beam']:.4f} | {q['Kt']:.4f} | "
                f"{(1 + tau / 2) ** 0.40:.4f} | {(1 + tau / 2) ** 0.45:.4f} |"
            )
        print()
        print(json.dumps(cache["fit"], indent=1))
    if args.only in (None, "points"):
        points = []
        cases = [
            ("elliptical", {"t": 0.1, "a": 2.0, "c": 1.0}),
            ("elliptical", {"t": 0.05, "a": 0.5, "c": 1.0}),
            ("elliptical", {"t": 0.06, "a": 0.6, "c": 1.5}),
            ("elliptical", {"t": 0.2, "a": 2.0, "c": 0.5}),
            ("elliptical", {"t": 0.15, "a": 1.0, "c": 0.25}),
            ("corner_filleted", {"t": 0.1, "l": 2.0, "r": 0.1}),
            ("corner_filleted", {"t": 0.1, "l": 2.0, "r": 0.5}),
            ("corner_filleted", {"t": 0.05, "l": 2.0, "r": 0.1}),
            ("uniform", {"t": 0.1, "l": 2.0}),
            ("uniform", {"t": 0.05, "l": 2.0}),
        ]
        fitc = cache.get("fit")
        print(
            "| profile | t/R_neck | θ_M FE/EB | θ_F FE/EB | y_F FE/Timoshenko | circular fit θ_M |"
        )
        print("|---|---|---|---|---|---|")
        for kind, p in cases:
            row = run(cache, kind, p, POINT_MESH, args.out)
            b = beam(kind, p)
            q = compare(row, b, p["t"])
            # the radius of curvature at the neck: a²/c (ellipse), r (fillet)
            r_neck = p["a"] ** 2 / p["c"] if kind == "elliptical" else p.get("r", math.inf)
            tau = p["t"] / r_neck
            guess = 1 + fitc["theta_M"]["c1"] * tau + fitc["theta_M"]["c2"] * tau**2 if fitc else 0
            points.append({"profile": kind, "params": p, "t/R_neck": tau, "beam": b, "ratio": q})
            print(
                f"| {kind} {p} | {tau:.4g} | {q['theta_M']:.4f} | {q['theta_F']:.4f} | "
                f"{q['y_F_timoshenko']:.4f} | {guess:.4f} |"
            )
        cache["points"] = points
        print()
        print(f"| profile | θ_M n={CHECK_MESH} vs n={POINT_MESH} | y_F | K_t |")
        print("|---|---|---|---|")
        for kind, p in (cases[2], cases[5]):
            a = run(cache, kind, p, POINT_MESH, args.out)
            b = run(cache, kind, p, CHECK_MESH, args.out)
            sa, sb = (max(abs(v) for v in r["neck_stress_M"]) for r in (a, b))
            print(
                f"| {kind} {p} | {(b['theta_M'] / a['theta_M'] - 1) * 100:+.4f} % | "
                f"{(b['y_F'] / a['y_F'] - 1) * 100:+.4f} % | {(sb / sa - 1) * 100:+.4f} % |"
            )
    args.out.write_text(json.dumps(cache, indent=1, sort_keys=True) + "\n")


if __name__ == "__main__":
    main()
