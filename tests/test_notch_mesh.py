"""symkin.fea.notch_mesh (docs/fea.md, "One notch"): the columns proportional to the local
thickness, the deck's outline, and one coarse ccx run of a circular notch against the committed
mesh-converged continuum (benchmarks/results-notch.json).

References, none taken from the code under test: ∫ dx/T between columns by mpmath quadrature, the
circular notch's T(x) written here from docs/file-format.md's formula, the deck's nodes read
back from its text, and the converged FE compliances of benchmarks/notch_continuum.py's mesh
study with the coarse mesh's measured error from the same study. Without ccx the run is
skipped, unless CI=true: then it fails.
"""

from __future__ import annotations

import itertools
import json
import math
import os
import shutil

import mpmath
import pytest
from conftest import ROOT

from symkin.fea import notch_mesh, profile_columns

needs_ccx = pytest.mark.skipif(
    shutil.which("ccx") is None and os.environ.get("CI") != "true",
    reason="CalculiX ccx (Debian package calculix-ccx) not installed",
)
RESULTS = ROOT / "benchmarks" / "results-notch.json"


def circular(t: float, r: float):
    """T(x) = t + 2(R − √(R² − (x − R)²)) over [0, 2R] (docs/file-format.md, "Notch hinges"; x
    from P's end)."""
    return lambda x: t + 2 * (r - math.sqrt(max(r * r - (x - r) ** 2, 0.0)))


@pytest.mark.parametrize("t", [0.02, 0.1, 0.5])
def test_columns_follow_the_local_thickness(t):
    """Every column holds the same ∫ dx/T (mpmath), so its width is proportional to T: the
    width over the thickness at its middle is the same within the profile's curvature."""
    depth = circular(t, 1.0)
    count = 40
    xs = profile_columns.columns(depth, 2.0, count)
    assert len(xs) == 2 * count + 1 and xs[0] == 0.0 and xs[-1] == 2.0
    corners = xs[::2]
    assert all(b > a for a, b in itertools.pairwise(corners))
    # midside nodes halfway
    assert all(math.isclose(xs[2 * k + 1], (xs[2 * k] + xs[2 * k + 2]) / 2) for k in range(count))
    # symmetric profile, symmetric columns
    for k in range(count + 1):
        assert corners[k] + corners[count - k] == pytest.approx(2.0, abs=1e-8)
    mpmath.mp.dps = 30
    r = mpmath.mpf(1)
    tt = mpmath.mpf(t)
    inv = lambda x: 1 / (tt + 2 * (r - mpmath.sqrt(r * r - (x - r) ** 2)))  # noqa: E731
    total = mpmath.quad(inv, [0, 1 - mpmath.sqrt(tt), 1, 1 + mpmath.sqrt(tt), 2])
    for a, b in itertools.pairwise(corners):
        pts = sorted({a, b, *(p for p in (1.0,) if a < p < b)})
        share = mpmath.quad(inv, pts) * count / total
        assert float(share) == pytest.approx(1.0, abs=2e-5)
    # at the neck a column is about a thickness long: ∫ dx/T = total/count there
    k = min(range(count), key=lambda k: abs(corners[k] - 1.0))
    width = corners[k + 1] - corners[k]
    assert width / float(total / count) == pytest.approx(depth(corners[k] + width / 2), rel=0.05)


def _nodes(text: str) -> dict[int, tuple[float, float, float]]:
    out = {}
    lines = text.splitlines()
    start = lines.index("*NODE, NSET=NALL") + 1
    for line in lines[start:]:
        if line.startswith("*"):
            break
        n, x, y, z = line.split(",")
        out[int(n)] = (float(x), float(y), float(z))
    return out


def _elements(text: str) -> list[list[int]]:
    lines = text.splitlines()
    start = next(k for k, line in enumerate(lines) if line.startswith("*ELEMENT")) + 1
    out = []
    k = start
    while not lines[k].startswith("*"):
        first = [int(v) for v in lines[k].rstrip(",").split(",")]
        second = [int(v) for v in lines[k + 1].split(",")]
        out.append(first[1:] + second)
        k += 2
    return out


def test_the_deck_is_the_notch_as_cut():
    """The deck's faces lie on ±T(x)/2, every element's corners turn counter-clockwise with a
    positive area, the element count is columns × across, P's face is clamped and M's face is
    tied to the reference node by two equations per node."""
    t, across = 0.1, 4
    depth = circular(t, 1.0)
    deck = notch_mesh.single_notch(depth, 2.0, 1.0, 210e3, 0.3, notch_mesh.NotchMesh(across))
    nodes = _nodes(deck.text)
    elements = _elements(deck.text)
    count = profile_columns.column_count(depth, 2.0, across)
    # ∫ dx/T of the circular notch times `across`, rounded up (the columns about T/across long)
    mpmath.mp.dps = 30
    total = mpmath.quad(
        lambda x: 1 / (t + 2 * (1 - mpmath.sqrt(1 - (x - 1) ** 2))), [0, 0.7, 1, 1.3, 2]
    )
    assert count == math.ceil(across * float(total))
    assert len(elements) == deck.elements == count * across
    assert len(nodes) == deck.nodes + 2  # and the reference and rotation nodes
    for n, (x, y, z) in nodes.items():
        if n > deck.nodes:
            assert (x, y, z) == (2.0, 0.0, 0.0)
            continue
        assert abs(y) <= depth(x) / 2 * (1 + 1e-9) + 1e-12
        assert z in (0.0, 0.5, 1.0)
    # the outline: on z = 0 the lowest and highest node of every column are on ∓T(x)/2
    columns: dict[float, list[float]] = {}
    for x, y, z in (nodes[n] for n in nodes if n <= deck.nodes):
        if z == 0.0:
            columns.setdefault(x, []).append(y)
    assert len(columns) == 2 * count + 1
    for x, ys in columns.items():
        assert min(ys) == pytest.approx(-depth(x) / 2, rel=1e-9)
        assert max(ys) == pytest.approx(depth(x) / 2, rel=1e-9)
        assert len(ys) in (across + 1, 2 * across + 1)
    for conn in elements:
        assert len(conn) == 20
        c = [nodes[n] for n in conn[:4]]
        area = sum(c[k][0] * c[(k + 1) % 4][1] - c[(k + 1) % 4][0] * c[k][1] for k in range(4)) / 2
        assert area > 0
    assert nodes[deck.centre][:2] == pytest.approx((1.0, 0.0), abs=1e-9)
    assert [nodes[n][1] for n in deck.neck] == pytest.approx([-t / 2, t / 2], rel=1e-9)
    clamp = [n for n, (x, _, _) in nodes.items() if x == 0.0]
    end = [n for n, (x, _, _) in nodes.items() if x == 2.0 and n <= deck.nodes]
    text = deck.text
    assert text.count("\n3\n") == len(end) and text.count("\n2\n") == len(end)
    assert len(clamp) == len(end) == 2 * (2 * across + 1) + across + 1
    assert "*STEP" in text and "NLGEOM" not in text


@needs_ccx
def test_a_coarse_circular_notch_against_the_converged_continuum():
    """t/R = 0.1 at 4 elements across (0.3 s of ccx): every compliance within the coarse mesh's
    error in the study (the committed runs at 4 and 32 across), Maxwell–Betti (θ_F = y_M) to
    ccx's 7 digits, and θ_M within 5 % of the Euler–Bernoulli integral (mpmath, written here)
    — the continuum is the softer."""
    runs = json.loads(RESULTS.read_text())["runs"]
    coarse = runs["circular t=0.1 R=1 n=4"]
    fine = runs["circular t=0.1 R=1 n=32"]
    deck = notch_mesh.single_notch(
        circular(0.1, 1.0), 2.0, 1.0, 210e3, 0.3, notch_mesh.NotchMesh(4)
    )
    got = notch_mesh.solve(deck)
    for name in ("y_F", "theta_F", "theta_M", "y_M"):
        known = abs(coarse[name] / fine[name] - 1)
        assert getattr(got, name) == pytest.approx(fine[name], rel=1.2 * known + 1e-6), name
    assert got.theta_F == pytest.approx(got.y_M, rel=1e-6)
    mpmath.mp.dps = 40
    e1 = mpmath.mpf(210e3) / (1 - mpmath.mpf("0.3") ** 2)
    theta = mpmath.quad(
        lambda x: 12 / (e1 * (mpmath.mpf("0.1") + 2 * (1 - mpmath.sqrt(1 - (x - 1) ** 2))) ** 3),
        [0, 0.5, 1, 1.5, 2],
    )
    assert 1.0 < got.theta_M / float(theta) < 1.05


@needs_ccx
def test_symkin_fea_meshes_a_notch_plate_as_cut():
    """The mechanism's deck (fea.deck) meshes a plate whose profile is not uniform with the
    thickness-following columns: the single plate of tests/fea/single_plate.toml given a circular
    notch's T(x) (R = 5 mm, t = 0.5 mm, b = 10 mm), H held at 0 and a 1 N transverse force on
    the arm: clamped-guided, the arm moves by V (y_F − θ_F²/θ_M). The reference is the committed
    single-notch continuum at t/R = 0.1 (n = 32, R = 1 mm, E b = 210000 N/mm), scaled by its
    E b (the compliances times E b are invariant under a change of size)."""
    import dataclasses

    from symkin import fea
    from symkin.fea import ccx

    setup = fea.prepare(
        ROOT / "tests" / "fea" / "single_plate.toml",
        {"H": 0.0},
        {"l": 0.01, "t": 0.0005, "V": 1.0},
    )
    r, t = 0.005, 0.0005
    (plate,) = setup.conf.plates
    notch = dataclasses.replace(plate, profile=circular(t, r))
    conf = dataclasses.replace(setup.conf, plates=(notch,))
    setup = dataclasses.replace(setup, conf=conf)
    deck = fea.write_deck(setup, fea.Mesh(40, 4, 0.8))
    # the columns follow the thickness: the plate's corner positions along x are columns()'s
    xs = sorted(
        {
            float(line.split(",")[1])
            for line in deck.text.splitlines()
            if line[:1].isdigit() and line.count(",") == 3
        }
    )
    expected = [x - r for x in profile_columns.columns(circular(t, r), 2 * r, 40)]
    assert all(any(abs(x - e) < 1e-12 for x in xs) for e in expected)
    got = fea.deviations(deck, ccx.run(deck, "notch_plate"))["T"]
    fine = json.loads(RESULTS.read_text())["runs"]["circular t=0.1 R=1 n=32"]
    guided = (fine["y_F"] - fine["theta_F"] ** 2 / fine["theta_M"]) * 210e3 / (200e3 * 10) * 1e-3
    assert abs(got[0]) < 1e-3 * abs(got[1])
    # measured 0.13 % apart (the guided deflection cancels 97 % of y_F: its errors grow 30-fold)
    assert got[1] == pytest.approx(guided, rel=5e-3)
