"""symkin fea --modes (docs/fea.md, "Natural frequencies"): the frequency step's deck, ccx's
eigenvalue table, and a ccx frequency run of a leaf-spring parallelogram stage against
references written here: (1/2π)√(24EI/(L³m)) for its sway, (1/2π)√(2EA/(Lm)) for its axial
mode, Rayleigh's quotient for what the leaves' own mass (steel) takes off them, and
`symkin modes` at both levels. The run uses a coarse graded mesh (20 x 2, a second or two);
without ccx it is skipped, unless CI=true: then it fails (tests/strict_skips.py).
"""

from __future__ import annotations

import json
import math
import os
import re
import shutil

import pytest
import test_modes as stage_file
from conftest import ROOT

import symkin
from symkin import fea
from symkin.cli.commands import main
from symkin.fea import ccx, frequency

needs_ccx = pytest.mark.skipif(
    shutil.which("ccx") is None and os.environ.get("CI") != "true",
    reason="CalculiX ccx (Debian package calculix-ccx) not installed",
)
COARSE = fea.Mesh(20, 2, 0.8)
LEVER = ROOT / "tests" / "mechanisms" / "lever_amplifier_mass.toml"


def nodes(text: str) -> dict[int, tuple[float, float, float]]:
    """The deck's node coordinates."""
    block = text.split("*NODE\n", 1)[1].split("*ELEMENT", 1)[0]
    out = {}
    for line in block.splitlines():
        if line[:1].isdigit():
            n, x, y, z = line.split(",")
            out[int(n)] = (float(x), float(y), float(z))
    return out


def body_members(text: str, link: str) -> set[int]:
    """The member nodes of `link`'s rigid body, every *NSET block of its set."""
    name = re.search(rf"\*\* link '{link}': reference node.*\n\*NSET, NSET=(LINK\d+)", text)
    assert name is not None
    members: set[int] = set()
    for block in re.findall(rf"\*NSET, NSET={name.group(1)}\n((?:[\d, ]+\n)+)", text):
        members |= {int(v) for v in block.replace("\n", "").split(",") if v.strip()}
    assert f"*RIGID BODY, NSET={name.group(1)}," in text
    return members


def test_the_deck_carries_the_masses_and_a_last_frequency_step():
    """The stage of tests/test_modes.py with an inertia: its mass as two halves at the centre
    -/+ √(I/m) along x (the same mass, centre and inertia), both member nodes of its rigid
    body; the plates at the negligible density; the frequency step a perturbation step after
    the static one, last."""
    m, inertia = 0.1, 2e-5
    setup = fea.prepare(symkin.loads(stage_file.stage(inertia), "stage.toml"), {"push": 0})
    modal = frequency.write(setup, COARSE, count=3)
    text = modal.deck.text
    halves = re.findall(r"\*ELEMENT, TYPE=MASS, ELSET=(MASS1_\d)\n(\d+), (\d+)\n", text)
    assert len(halves) == 2
    where = nodes(text)
    arm = math.sqrt(inertia / m)
    centre = (stage_file.SPACING / 2 * 1e-3, stage_file.LEG / 2 * 1e-3)
    placed = sorted(where[int(node)] for _, _, node in halves)
    assert placed[0] == pytest.approx((centre[0] - arm, centre[1], 0), abs=1e-15)
    assert placed[1] == pytest.approx((centre[0] + arm, centre[1], 0), abs=1e-15)
    masses = []
    for elset, element, _ in halves:
        value = re.search(rf"\*MASS, ELSET={elset}\n(\S+)\n", text)
        assert value is not None
        masses.append(float(value.group(1)))
        assert int(element) > modal.deck.elements  # after the plates' elements
    assert masses == pytest.approx([m / 2, m / 2], rel=1e-14)
    assert sum(masses) * arm**2 == pytest.approx(inertia, rel=1e-12)  # about the centre
    assert {int(node) for _, _, node in halves} <= body_members(text, "stage")
    assert text.count("*DENSITY\n1e-12\n") == len(setup.conf.plates) == 4
    static, freq = text.split("*STEP, PERTURBATION\n")
    assert static.count("*END STEP") == 1 and static.index("*STEP, NLGEOM") < static.index(
        "*END STEP"
    )
    assert freq == "*FREQUENCY\n3\n*END STEP\n"
    # massless plates: ccx is asked for no more modes than the links' massive freedoms (x, y, φ)
    assert frequency.write(setup, COARSE, count=5).requested == 3
    point = fea.prepare(symkin.loads(stage_file.stage(), "stage.toml"), {"push": 0})
    assert "*FREQUENCY\n2\n" in frequency.write(point, COARSE, count=3).deck.text
    # with the plates' density, as many as asked (their own modes come in)
    steel = frequency.write(setup, COARSE, count=5, density=7850)
    assert steel.requested == 5 and text.count("*DENSITY\n7850\n") == 0
    assert steel.deck.text.count("*DENSITY\n7850\n") == 4
    # the deck without --modes has neither
    plain = fea.write_deck(setup, COARSE).text
    assert "*FREQUENCY" not in plain and "TYPE=MASS" not in plain and "*DENSITY" not in plain


def test_a_lever_gets_its_mass_and_the_pusher_its_point_mass():
    """Two massive links: the lever (with inertia) as two halves, the pusher (none) as one
    point mass at its centre, each on its own rigid body; the parameters' values in mm."""
    setup = fea.prepare(symkin.load(LEVER), {"P0": 0.005})
    text = frequency.write(setup, COARSE, count=3).deck.text
    where = nodes(text)
    single = re.search(r"\*ELEMENT, TYPE=MASS, ELSET=MASS1_1\n\d+, (\d+)\n", text)
    assert single is not None and "MASS1_2" not in text
    assert where[int(single.group(1))] == pytest.approx((-0.02, -0.02, 0), abs=1e-15)
    assert int(single.group(1)) in body_members(text, "pusher")
    assert re.search(r"\*MASS, ELSET=MASS1_1\n0.005\n", text)
    arm = math.sqrt(0.02 * 0.1**2 / 12 / 0.02)
    lever = [int(n) for n in re.findall(r"ELSET=MASS2_\d\n\d+, (\d+)\n", text)]
    assert sorted(where[n][0] for n in lever) == pytest.approx([0.05 - arm, 0.05 + arm], abs=1e-15)
    assert set(lever) <= body_members(text, "lever")


def test_the_eigenvalue_table_and_its_noise():
    """ccx's .dat eigenvalue table (written here as ccx prints it): the frequencies are √ω²/2π;
    with massless plates a negative ω² and one far above the lowest (the plates' negligible
    mass) are left out; with a plate density every positive one counts."""
    dat = """
     E I G E N V A L U E   O U T P U T

 MODE NO    EIGENVALUE                       FREQUENCY
                                     REAL PART            IMAGINARY PART
                           (RAD/TIME)      (CYCLES/TIME     (RAD/TIME)

      1  -0.4456875E+17   0.0000000E+00   0.0000000E+00   0.2111131E+09
      2   0.5793306E+04   0.7611377E+02   0.1211388E+02   0.0000000E+00
      3   0.2309097E+09   0.1519571E+05   0.2418473E+04   0.0000000E+00
      4   0.1515434E+15   0.1231030E+08   0.1959244E+07   0.0000000E+00

     P A R T I C I P A T I O N   F A C T O R S
"""
    assert frequency.eigenvalues(dat) == [-0.4456875e17, 0.5793306e04, 0.2309097e09, 0.1515434e15]
    deck = fea.write_deck(
        fea.prepare(symkin.loads(stage_file.stage(), "stage.toml"), {"push": 0}), COARSE
    )
    massless = frequency.ModalDeck(deck, (), 5, 5, 0.0)
    found = frequency.frequencies(massless, dat)
    assert found == pytest.approx(
        [math.sqrt(0.5793306e04) / (2 * math.pi), math.sqrt(0.2309097e09) / (2 * math.pi)]
    )
    steel = frequency.ModalDeck(deck, (), 2, 5, 7850.0)
    assert len(frequency.frequencies(steel, dat)) == 2
    with pytest.raises(symkin.AssemblyError, match="no eigenvalues"):
        frequency.frequencies(massless, "no table")


@pytest.mark.parametrize(
    "extra, words",
    [
        (["--modes", "0"], "--modes"),
        (["--plate-density", "7850"], "--plate-density"),
        (["--modes", "3", "--plate-density", "-1"], "--plate-density"),
    ],
)
def test_bad_modal_requests_exit_2(tmp_path, capsys, extra, words):
    path = tmp_path / "stage.toml"
    path.write_text(stage_file.stage())
    out = tmp_path / "out"
    assert main(["fea", str(path), "--input", "push=0", "-o", str(out), *extra]) == 2
    err = capsys.readouterr().err
    assert words in err and "fix:" in err and "stage.toml" in err and not out.exists()


def test_modes_without_a_mass_exit_2(tmp_path, capsys):
    out = tmp_path / "out"
    plain = ROOT / "tests" / "mechanisms" / "parallelogram.toml"
    assert main(["fea", str(plain), "--input", "F1=0", "-o", str(out), "--modes", "3"]) == 2
    err = capsys.readouterr().err
    assert "no link has a mass" in err and "--modes" in err and "parallelogram.toml" in err
    assert not out.exists()


def test_modes_are_paired_by_their_mass_weighted_shapes():
    """Two FE modes listed in the other order than the level's: each is paired with the mode
    of its shape, (a'Mb)²/((a'Ma)(b'Mb)) computed here; a shape without mass motion, and one
    below the MAC threshold, pairs with none."""
    weights = [2.0, 2.0, 0.5]  # kg, kg, kg m²: one link
    x, y, turn = [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]
    fe = [frequency.Mode(1.0, y), frequency.Mode(2.0, x), frequency.Mode(3.0, [0.0, 0.0, 0.0])]
    level = [frequency.Mode(1.1, [1.0, 0.1, 0.0]), frequency.Mode(2.1, [0.05, -1.0, 0.0])]
    expected = (2 * 0.05 * 1) ** 2 / ((2 * 1) * (2 * (0.05**2 + 1)))  # x against level 2
    assert frequency.mac(x, level[1].shape, weights) == pytest.approx(expected)
    assert frequency.pair(fe, level, weights) == [
        (1, pytest.approx(1 / (1 + 0.05**2))),
        (0, pytest.approx(1 / (1 + 0.1**2))),
        (None, None),
    ]
    assert frequency.pair([frequency.Mode(1.0, turn)], level, weights) == [(None, None)]
    # an FE mode whose mass is mostly the plates' (a leaf's own mode) pairs with none, though
    # the links move alike; the same shape nearer in frequency is taken first
    plate = frequency.Mode(1.05, x, share=0.2)
    assert frequency.pair([plate], level, weights) == [(None, None)]
    near, far = frequency.Mode(1.0, x, share=0.99), frequency.Mode(5.0, x, share=0.9)
    assert [j for j, _ in frequency.pair([far, near], level, weights)] == [None, 0]


def rayleigh(f: float, share: float, plate_mass: float, mass: float) -> float:
    """f with `share` of the plates' mass added to the link's (Rayleigh's quotient with the
    static shape: 13/35 of a fixed-guided leaf swaying, 1/3 of a bar stretching)."""
    return f / math.sqrt(1 + share * plate_mass / mass)


@needs_ccx
def test_a_parallelogram_stage_in_calculix(tmp_path, capsys):
    """The leaf-spring stage of tests/test_modes.py (t/L = 0.005, m = 0.1 kg, driven by a
    force held at zero: it sways freely) through `symkin fea --modes 3 --run --json`. Its sway
    within 0.1 % of (1/2π)√(24EI/(L³m)) (the continuum's clamp faces stiffen a leaf by
    0.073 t/l, l = L/2: +0.04 % in frequency; the coarse mesh +0.05 %), its axial mode within
    0.1 % of (1/2π)√(2EA/(Lm)), and symkin's frequencies (both levels) beside them. With steel
    plates the leaves' mass lowers both as Rayleigh's quotient says (13/35 and 1/3 of it)."""
    m = 0.1
    path = tmp_path / "stage.toml"
    path.write_text(stage_file.stage())
    out = tmp_path / "out"
    argv = ["fea", str(path), "--input", "push=0", "-o", str(out), "--mesh", "20,2,0.8"]
    assert main([*argv, "--modes", "3", "--run", "--json", "--quiet"]) == 0
    data = json.loads(capsys.readouterr().out)["modes"]
    assert data["count"] == 3 and data["plate_density"] == 0
    assert data["fea_link_share"] == pytest.approx([1, 1], abs=1e-6)  # massless plates
    sway, axial = data["fea"]  # the stage's rotation has no inertia: two modes
    assert sway == pytest.approx(stage_file.sway(m), rel=1e-3)
    assert axial == pytest.approx(stage_file.axial(m), rel=1e-3)
    for level in ("loaded", "equilibrium"):
        assert data[level] == pytest.approx([stage_file.sway(m), stage_file.axial(m)], rel=1e-3)
        # paired by their shapes: the sway with the sway, the stretch with the stretch
        assert [p["mode"] for p in data["pairs"][level]] == [1, 2]
        assert all(p["mac"] > 0.999 for p in data["pairs"][level])
        for k in range(2):
            assert data["difference"][level][k] == pytest.approx(
                data[level][k] / data["fea"][k] - 1, abs=1e-12
            )
            assert abs(data["difference"][level][k]) < 1e-3
    assert (out / "stage.frd").exists() and (out / "stage.dat").exists()
    # the leaves' own mass: 2 leaves of steel, (L - gap) x t x b each
    setup = fea.prepare(path, {"push": 0})
    steel = frequency.write(setup, COARSE, count=6, density=7850)
    modes = frequency.fe_modes(steel, ccx.run(steel.deck, "steel").printed)
    found = [mode.frequency for mode in modes]
    leaves = 2 * (stage_file.LEG - stage_file.GAP) * stage_file.THICK * stage_file.WIDTH * 1e-9
    plate_mass = leaves * 7850
    assert found[0] == pytest.approx(rayleigh(sway, 13 / 35, plate_mass, m), rel=1e-4)
    # the leaves' own modes come in between; the stretch is the FE mode of the axial shape
    levels, _ = frequency.symkin_modes(setup, 2, steel.masses)
    weights = [m, m, 0.0]
    pairs = frequency.pair(modes, levels["loaded"], weights)
    stretch = next(k for k, (j, _) in enumerate(pairs) if j == 1)
    assert pairs[0][0] == 0 and stretch > 1
    assert found[stretch] == pytest.approx(rayleigh(axial, 1 / 3, plate_mass, m), rel=1e-4)
    assert [j for j, _ in pairs[1:stretch]] == [None] * (stretch - 1)  # the leaves' own
    # the leaves' own first bending mode (clamped-clamped, (22.37/2π)√(E'I/(ρA L⁴))) lies
    # between the two
    own = (
        22.37
        / (2 * math.pi)
        * math.sqrt(
            stage_file.EI
            / (7850 * stage_file.THICK * stage_file.WIDTH * 1e-6 * (stage_file.LEG * 1e-3) ** 4)
        )
    )
    assert found[1] == pytest.approx(own, rel=0.02)


@needs_ccx
def test_the_text_sets_the_frequencies_beside_the_levels(tmp_path, capsys):
    path = tmp_path / "stage.toml"
    path.write_text(stage_file.stage())
    argv = ["fea", str(path), "--input", "push=0", "-o", str(tmp_path), "--mesh", "10,1"]
    assert main([*argv, "--modes", "1", "--run", "--quiet"]) == 0
    text = capsys.readouterr().out
    assert "natural frequencies, every input held; massless plates" in text
    row = next(line for line in text.splitlines() if line.startswith("1 ")).split()
    assert len(row) == 14 and row[2:4] == ["100.0", "%"]  # the links carry all the mass
    assert row[4:6] == row[9:11] == ["mode", "1"]  # equilibrium, loaded
    fe, eq, diff = float(row[1]), float(row[6]), float(row[7])
    assert fe == pytest.approx(stage_file.sway(0.1), rel=3e-3)
    assert eq == pytest.approx(stage_file.sway(0.1), rel=1e-3)
    assert diff == pytest.approx(100 * (eq / fe - 1), abs=1e-3)


def test_a_loaded_mechanism_gets_the_note_on_rigid_links():
    """A load on a link (or a force actuator's force) is named in a note: ccx's frequency step
    leaves out the rigid bodies' geometric stiffness (docs/fea.md); unloaded, no note."""
    mech = symkin.loads(stage_file.stage(load=True), "stage.toml")
    loaded = frequency.loaded_note(fea.prepare(mech, {"push": 0}, {"P": 1}))
    assert len(loaded) == 1 and "geometric stiffness of the rigid links" in loaded[0]
    assert frequency.loaded_note(fea.prepare(mech, {"push": 0}, {"P": 0})) == ()


@needs_ccx
def test_a_preload_in_the_leaves_softens_calculix_as_symkin():
    """Half the buckling load 2π²EI/L² on the leaf-spring stage: the softening sits in the
    leaves' own compression, which ccx's frequency step keeps (the plates' stresses), so the
    FE's sway falls with symkin's, to the beam-column's P/(L (tan u/u - 1)) (written here)."""
    critical = 2 * math.pi**2 * stage_file.EI / (stage_file.LEG * 1e-3) ** 2
    mech = symkin.loads(stage_file.stage(load=True), "stage.toml")
    setup = fea.prepare(mech, {"push": 0}, {"P": 0.5 * critical})
    modal = frequency.write(setup, COARSE, count=1)
    fe = frequency.frequencies(modal, ccx.run(modal.deck, "preload").printed)[0]
    beam = math.sqrt(2 * stage_file.leaf_stiffness(0.25 * critical) / 0.1) / (2 * math.pi)
    assert fe == pytest.approx(beam, rel=2e-3)
    assert fe < 0.75 * stage_file.sway(0.1)


@needs_ccx
def test_a_two_loop_stage_in_calculix():
    """tests/mechanisms/double_parallelogram_mass.toml (two bodies with mass and inertia, both
    swaying freely) on a coarse mesh (10 x 1, about a second of ccx): its first three modes —
    the sways in phase and opposed (a two-mass chain), then the bodies turning — each paired
    by its shape with symkin's of the same rank, within the contract's 2 % (docs/fea.md: 0.06 to
    0.12 % mesh-converged); the FE's own shapes are a chain's (the stage, at the chain's end,
    moves more than the intermediate body in phase, and against it in the opposed mode)."""
    path = ROOT / "tests" / "mechanisms" / "double_parallelogram_mass.toml"
    setup = fea.prepare(path, {"p1": 0, "p2": 0})
    modal = frequency.write(setup, fea.Mesh(10, 1, 0.8), count=3)
    run = ccx.run(modal.deck, "double")
    levels, failed = frequency.symkin_modes(setup, 3, modal.masses)
    result = frequency.ModalComparison(
        frequency.fe_modes(modal, run.printed), levels, failed, modal
    )
    assert not failed and len(result.fea) == 3
    for level in ("loaded", "equilibrium"):
        assert [j for j, _ in result.pairs(level)] == [0, 1, 2]
        for k in range(3):
            assert abs(result.difference(k, level)) < 0.02  # type: ignore[arg-type]
    (mid1, _, _, stage1, _, _), (mid2, _, _, stage2, _, _) = (m.shape for m in result.fea[:2])
    assert stage1 / mid1 > 1 and stage2 / mid2 < 0  # in phase, then opposed
    assert all(m.share == pytest.approx(1, abs=1e-6) for m in result.fea)  # massless plates
