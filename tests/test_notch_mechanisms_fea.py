"""Notch mechanisms against CalculiX (docs/physics.md, "Notch mechanisms against a continuum";
docs/fea.md, "Material law"): `symkin fea --law`, its neo-Hookean deck, and one notch mechanism
solved by ccx at a coarse mesh against `equilibrium`.

References written here: the neo-Hookean constants from E and ν (C10 = G/2, D1 = 2/K), the
small-strain limit both laws share (a first-order response equal under either law), the axial
compliance of a circular notch as an mpmath integral of 1/(E′bT(x)), and the issue's bar (the
deviation of `equilibrium` within 3 % of the FE's). benchmarks/notch_mechanisms.py runs the full
study (three mechanisms, two inputs, with and without a dead load, both laws, two meshes).
Without ccx the tests that need it are skipped, unless CI=true: then they fail.
"""

from __future__ import annotations

import math
import os
import shutil

import mpmath
import pytest
from conftest import ROOT

import symkin
from symkin import fea
from symkin.cli.commands import main
from symkin.fea import ccx
from symkin.physics import model_error

needs_ccx = pytest.mark.skipif(
    shutil.which("ccx") is None and os.environ.get("CI") != "true",
    reason="CalculiX ccx (Debian package calculix-ccx) not installed",
)

MECHANISMS = ROOT / "tests" / "mechanisms"
STAGE = MECHANISMS / "notch_parallelogram.toml"
E, NU = 210e9, 0.3  # the notch files' steel
R, T, B = 1e-3, 1e-4, 1e-2  # their notches: radius, neck, width (m)


def norm(v) -> float:
    return math.hypot(v[0], v[1])


def test_a_bad_law_is_bad_input(tmp_path, capsys):
    code = main(["fea", str(STAGE), "--input", "F1=0.02", "-o", str(tmp_path), "--law", "rubber"])
    err = capsys.readouterr().err
    assert code == 2
    assert "notch_parallelogram.toml" in err and "--law" in err and "'rubber'" in err
    assert "svk" in err and "neo-hookean" in err
    assert not list(tmp_path.iterdir())  # nothing written


def test_the_law_with_modes_is_bad_input(tmp_path, capsys):
    code = main(
        ["fea", str(STAGE), "--input", "F1=0.02", "-o", str(tmp_path), "--law", "neo-hookean"]
        + ["--modes", "2"]
    )
    assert code == 2
    assert "--law" in capsys.readouterr().err


def test_the_neo_hookean_deck(tmp_path):
    """C10 = E/(4(1 + ν)) and D1 = 6(1 − 2ν)/E in megapascals (ccx would replace a D1 below
    1e-10 by its default), the payload in meganewtons; otherwise the St. Venant–Kirchhoff deck."""
    setup = fea.prepare(STAGE, {"F1": 0.02}, {"P": 2.0})
    mesh = fea.Mesh(4, 2, 0.8)
    svk = fea.write_deck(setup, mesh).text.splitlines()
    nh = fea.write_deck(setup, mesh, law="neo-hookean").text.splitlines()
    assert "*HYPERELASTIC, NEO HOOKE" not in svk and svk.count("*ELASTIC") == 4
    assert nh.count("*HYPERELASTIC, NEO HOOKE") == 4 and "*ELASTIC" not in nh
    at = nh.index("*HYPERELASTIC, NEO HOOKE")
    c10, d1 = (float(v) for v in nh[at + 1].split(","))
    G, K = E / (2 * (1 + NU)), E / (3 * (1 - 2 * NU))  # Pa
    assert c10 == pytest.approx(G / 2 / 1e6, rel=1e-12)
    assert d1 == pytest.approx(2 / K * 1e6, rel=1e-12) and d1 > 1e-10
    loads_svk = [line for line in svk if line.endswith(", 2, -2")]
    loads_nh = [line for line in nh if line.endswith(", 2, -2e-06")]
    assert len(loads_svk) == 1 and loads_nh == [loads_svk[0].replace("-2", "-2e-06")]
    changed = {k for k, (a, b) in enumerate(zip(svk, nh, strict=True)) if a != b}
    # the units line, the plates' comments and material cards, the payload
    assert len(changed) == 1 + 4 * 3 + 1


@needs_ccx
def test_both_laws_share_the_small_strain_response():
    """The stage under a 1 N payload with its input held at 0: each leg's two notches carry
    0.5 N along their axes, a first-order response that both laws must give alike (the
    neo-Hookean deck in pascals sank 28 % less: docs/fea.md, "Material law"), near the notches'
    axial beam compliance ∫dx/(E′bT(x)) (mpmath; the continuum is measured 6.9 % softer)."""
    setup = fea.prepare(STAGE, {"F1": 0.0}, {"P": 1.0})
    sink = {}
    for law in fea.LAWS:
        deck = fea.write_deck(setup, fea.Mesh(8, 2, 0.8), law=law)
        sink[law] = fea.deviations(deck, ccx.run(deck, "notch_stage"))["P"][1]  # mm
    assert sink["neo-hookean"] == pytest.approx(sink["svk"], rel=1e-4)
    mpmath.mp.dps = 30
    r, t = mpmath.mpf(R), mpmath.mpf(T)
    span = mpmath.quad(lambda x: 1 / (t + 2 * (r - mpmath.sqrt(r * r - x * x))), [-r, 0, r])
    beam = 2 * 0.5 * float(span) / (E / (1 - NU**2) * B) * 1e3  # two notches, mm
    assert -sink["svk"] / beam == pytest.approx(1.07, abs=0.03)


@needs_ccx
def test_equilibrium_within_3_percent_of_calculix_on_the_notch_four_bar():
    """The notch four-bar at A0 = 0.02 rad under 1 N on its coupler point, 20 × 2 elements per
    notch (a few seconds of ccx; the 80 × 8 run is 0.48 % from it, benchmarks/
    notch_mechanisms.py): `equilibrium` within the issue's 3 % of the St. Venant–Kirchhoff FE,
    its model_error covering its difference from either law, and the two laws' deviations apart
    by the few percent the issue reports (4–10 %)."""
    file = MECHANISMS / "notch_four_bar.toml"
    setup = fea.prepare(file, {"A0": 0.02}, {"P": 1.0})
    fe = {}
    for law in fea.LAWS:
        deck = fea.write_deck(setup, fea.Mesh(20, 2, 0.8), law=law)
        fe[law] = fea.deviations(deck, ccx.run(deck, "notch_four_bar"))["C"]
    ev = symkin.evaluate(setup.analysis, setup.inputs, level="equilibrium", params=setup.overrides)
    eq = ev.points["C"].deviation

    def diff(a, b) -> float:
        return math.hypot(a[0] - b[0], a[1] - b[1]) / norm(b)

    assert diff(eq, fe["svk"]) < 0.03
    spread = diff(fe["neo-hookean"], fe["svk"])
    assert 0.04 < spread < 0.10
    assert ev.model_error["C"] > max(diff(eq, fe[law]) for law in fea.LAWS)
    # every hinge a notch: the law's part is LAW_SPREAD times the whole centre-line part
    parts = ev.model_error_parts["C"]
    assert parts["law"] == pytest.approx(model_error.LAW_SPREAD * parts["centre_line"], rel=1e-9)
    assert spread < parts["law"] < 2 * spread  # it covers the laws' distance, not grossly
