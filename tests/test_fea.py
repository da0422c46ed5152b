"""symkin fea (docs/fea.md): the CalculiX deck, and ccx's answers against independent references.

References, none taken from the code under test:
- a plate bent by a pure end moment is a circular arc (closed form), shortened in the
  St. Venant-Kirchhoff continuum by the centre-line law -c (kappa t)^2, c = (3 - nu/(1 - nu))/24:
  relative to the arc's deviation -12 c (t/l)^2 (docs/fea.md);
- Bisshopp & Drucker (1945), Q. Appl. Math. 3, 272-275: the cantilever under a transverse dead
  end load, alpha = F L^2/EI = 1: 1 - x/L = 0.05643, y/L = 0.30172; alpha = 2: 0.16064, 0.49346;
- the `exact` kinematic level of an open chain of unloaded circular-arc plates (each plate under a
  pure moment is exactly an arc);
- symkin's `equilibrium` level (inextensible elastica) on closed loops, within the bound of the
  effects the elastica leaves out, each on the part of the deviation it acts on
  (:func:`continuum_bound`).

Every run of ccx uses a coarse graded mesh (20 x 2 or 40 x 2 elements per plate, grading 0.8:
0.05-0.09 % from the converged deviation in the mesh study of docs/fea.md), a few seconds each.
Without ccx the tests that need it are skipped, unless CI=true: then they fail.
"""

from __future__ import annotations

import math
import os
import shutil

import mechanisms as M
import numpy as np
import pytest
from conftest import EXAMPLES, ROOT

import symkin
from symkin import fea
from symkin.cli.commands import main
from symkin.fea import ccx
from symkin.fea import deck as fdeck

MECHANISMS = ROOT / "tests" / "fea"
COARSE = fea.Mesh(20, 2, 0.8)
needs_ccx = pytest.mark.skipif(
    shutil.which("ccx") is None and os.environ.get("CI") != "true",
    reason="CalculiX ccx (Debian package calculix-ccx) not installed",
)


def svk_shortening(t_over_l: float, nu: float = 0.3) -> float:
    """-12 c (t/l)^2: the relative change of a bent plane-strain St. Venant-Kirchhoff plate's
    end deviation against the inextensible arc (centre-line length change -c (kappa t)^2,
    c = (1 - nu/(1 - nu))/8 from the strip's energy, docs/physics.md "Model error")."""
    return -12 * (1 - nu / (1 - nu)) / 8 * t_over_l**2


#: The clamp faces' effect on a bent plate's end deviation, over t/l: the rigid links the
#: continuum plate is fused into shorten its bending length by O(t). Measured 0.038-0.044 t/l on a
#: single plate under pure rotation (t/l = 0.02-0.1, test below); the bound is 0.05 t/l.
CLAMP = 0.05


#: The shear share of a plane-strain clamped-guided plate's transverse compliance, over
#: (t/l)^2: 12 E' I/(kappa G A l^2) = 2/((1 - nu) kappa), kappa = 5/6, nu = 0.3.
SHEAR = 2 / ((1 - 0.3) * 5 / 6)


def continuum_bound(setup, inputs) -> dict[str, float]:
    """How far a plane-strain continuum's deviation may lie from the elastica's, per point
    (absolute, file unit): the sum of the magnitudes of what the elastica leaves out, each on
    the part of the deviation it acts on (docs/fea.md). The kinematic part (the `exact` level's
    circular arcs) changes by the centre-line term 12 c (t/l)^2 and the clamp faces' CLAMP t/l;
    the force part (`equilibrium`
    minus `exact`: the plates' compliance under the loop forces and loads) by shear
    SHEAR (t/l)^2, the clamp faces' stiffening 0.1 t/l (measured: 0.073 t/l) and axial
    stretch rho (t/l)^2, rho the largest |N/V| of a plate (its axial over its transverse end
    force: stretch N l/EA against bending V l^3/(12 EI)); and the mesh, 0.1 %. t/l and rho
    are the largest over the plates."""
    ex = symkin.evaluate(setup.analysis, inputs, level="exact")
    eq = symkin.evaluate(setup.analysis, inputs, level="equilibrium")
    tau = max(p.thickness / p.length for p in setup.conf.plates)
    rho = 0.0
    for p in setup.conf.plates:
        turn = eq.links[p.p_link].compliant + eq.angles_compliant[p.hinge] / 2
        c, s = math.cos(turn), math.sin(turn)
        chord = (c * p.u[0] - s * p.u[1], s * p.u[0] + c * p.u[1])
        fx, fy = eq.hinges[p.hinge].force
        n, v = fx * chord[0] + fy * chord[1], -fx * chord[1] + fy * chord[0]
        rho = max(rho, abs(n) / max(abs(v), 1e-3 * math.hypot(fx, fy), 1e-300))
    out = {}
    for name, point in eq.points.items():
        kin, dev = ex.points[name].deviation, point.deviation
        force = math.hypot(dev[0] - kin[0], dev[1] - kin[1])
        out[name] = (
            (-svk_shortening(tau) + CLAMP * tau) * math.hypot(*kin)
            + (SHEAR * tau**2 + 0.1 * tau + rho * tau**2) * force
            + 1e-3 * math.hypot(*dev)
        )
    return out


def solve(path, inputs, mesh=COARSE, params=None, released=()):
    setup = fea.prepare(path, inputs, params)
    deck = fea.write_deck(setup, mesh, released)
    return setup, fea.deviations(deck, ccx.run(deck, setup.mechanism.name))


def relative(a, b) -> float:
    return math.hypot(a[0] - b[0], a[1] - b[1]) / math.hypot(*b)


# -- the deck ------------------------------------------------------------------------------------


def test_deck_is_deterministic_and_readable(tmp_path):
    """Two runs write byte-identical decks; every line fits ccx (132 characters, numbers of at
    most 20); comments name the hinges, links and points; the counts follow the mesh."""
    for k in (1, 2):
        assert (
            main(
                [
                    "fea",
                    str(EXAMPLES / "four_bar.toml"),
                    "--input",
                    "A0=10*deg",
                    "-o",
                    str(tmp_path / str(k)),
                    "--mesh",
                    "6,2,0.5",
                ]
            )
            == 0
        )
    one = (tmp_path / "1" / "four_bar.inp").read_bytes()
    assert one == (tmp_path / "2" / "four_bar.inp").read_bytes()
    text = one.decode("ascii")
    lines = text.splitlines()
    assert all(len(line) <= 132 for line in lines)
    data = [line for line in lines if line[:1].isdigit() or line[:1] == "-"]
    assert all(len(field.strip()) <= 20 for line in data for field in line.split(","))
    for name in (
        "hinge 'A0'",
        "hinge 'B'",
        "link 'crank'",
        "link 'coupler'",
        "point 'C'",
        "*RIGID BODY",
        "*STEP, NLGEOM",
        "*STATIC",
        "C3D20R",
    ):
        assert name in text
    # the node block: each plate's (2 NL + 1)(2 NT + 1) - NL NT positions on the two faces,
    # (NL + 1)(NT + 1) corners in the middle, then the links' nodes; two lines per element
    nl, nt, plates = 6, 2, 4
    start, links, end = (
        lines.index("*NODE"),
        lines.index(next(line for line in lines if line.startswith("** the links"))),
        next(i for i, line in enumerate(lines) if line.startswith("*ELEMENT")),
    )
    plate_nodes = [line for line in lines[start:links] if not line.startswith("*")]
    assert len(plate_nodes) == plates * (
        2 * ((2 * nl + 1) * (2 * nt + 1) - nl * nt) + (nl + 1) * (nt + 1)
    )
    setup = fea.prepare(EXAMPLES / "four_bar.toml", {"A0": "10*deg"})
    deck = fea.write_deck(setup, fea.Mesh(nl, nt, 0.5))
    assert deck.text == text and deck.elements == nl * nt * plates
    assert deck.nodes == len([line for line in lines[start:end] if not line.startswith("*")])


def test_mesh_positions_are_graded_and_symmetric():
    """Corners at xi - a sin(2 pi xi)/(2 pi): the end elements (1 - a)/(1 + a) times the
    middle ones, midside nodes halfway, symmetric about the middle."""
    a = 0.8
    pos = fea.Mesh(10, 4, a).positions(10)
    assert len(pos) == 21 and pos[0] == 0 and pos[-1] == 1
    assert pos[2] == pytest.approx(0.1 - a * math.sin(0.2 * math.pi) / (2 * math.pi))
    fine = fea.Mesh(1000, 4, a).positions(1000)
    assert (fine[2] - fine[0]) / (fine[1002] - fine[1000]) == pytest.approx(
        (1 - a) / (1 + a), rel=1e-4
    )
    assert all(abs(a + b - 1) < 1e-12 for a, b in zip(pos, reversed(pos)))
    assert all(
        pos[2 * k + 1] == pytest.approx((pos[2 * k] + pos[2 * k + 2]) / 2) for k in range(10)
    )


@needs_ccx
def test_a_run_larger_than_ten_minutes_of_ccx_is_refused_first(tmp_path, capsys):
    """`--mesh 2000,10` was inside the per-plate cap and still on ccx's first increment after
    300 s on the nine-bar: a run's mesh is capped in all (plates x NL x NT), refused before any
    derivation or file, naming --mesh."""
    import time

    out = tmp_path / "out"
    argv = ["fea", str(EXAMPLES / "nine_bar_platform.toml"), "--input", "O=0.05"]
    start = time.monotonic()
    code = main([*argv, "-o", str(out), "--mesh", "2000,10", "--run"])
    assert code == 2 and time.monotonic() - start < 5
    err = capsys.readouterr().err
    assert "--mesh: 10 plates x 2000 x 10 = 200000 elements" in err, err
    assert not out.exists()
    # the largest mesh the cap lets run on the nine-bar (80 x 8: about 10 minutes measured) is
    # accepted by the check itself
    from symkin.fea import command

    command.check_run_size(argv[1], fdeck.parse_mesh("80,8"))


@pytest.mark.parametrize("mesh", ["0,4", "4", "a,b", "4,4,1", "4,4,-0.1", "1000,100"])
def test_bad_mesh_is_bad_input(tmp_path, capsys, mesh):
    out = tmp_path / "out"
    assert (
        main(
            [
                "fea",
                str(EXAMPLES / "four_bar.toml"),
                "--input",
                "A0=0.1",
                "-o",
                str(out),
                f"--mesh={mesh}",
            ]
        )
        == 2
    )
    assert "--mesh" in capsys.readouterr().err
    assert not out.exists()


@pytest.mark.parametrize(
    "args, words",
    [
        ([], "A0"),  # the input is missing
        (["--input", "A1=0.1"], "A1"),  # no such hinge
        (["--input", "A0=0.1", "--param", "nope=1"], "nope"),
    ],
)
def test_bad_input_writes_nothing(tmp_path, capsys, args, words):
    out = tmp_path / "out"
    assert main(["fea", str(EXAMPLES / "four_bar.toml"), "-o", str(out), *args]) == 2
    err = capsys.readouterr().err
    assert "four_bar.toml" in err or "--input" in err or "--param" in err
    assert words in err and not out.exists()


def test_a_plate_without_stiffness_is_bad_input(tmp_path, capsys):
    out = tmp_path / "out"
    assert (
        main(
            ["fea", str(EXAMPLES / "four_bar_dimensions.toml"), "--input", "A0=0.1", "-o", str(out)]
        )
        == 2
    )
    err = capsys.readouterr().err
    assert "four_bar_dimensions.toml" in err and "'E'" in err and "fix:" in err
    assert not out.exists()


def test_unreachable_input_exits_3(tmp_path, capsys):
    """The four-bar driven at its rocker beyond the rocker's range: exit 3 before any file."""
    text = (EXAMPLES / "four_bar.toml").read_text()
    text = text.replace('plate_angle = "pi/2"\ninput = true\n', 'plate_angle = "pi/2"\n', 1)
    text = text.replace(
        'at = [0.1, 0.0]\nplate_angle = "pi/2"\n',
        'at = [0.1, 0.0]\nplate_angle = "pi/2"\ninput = true\n',
    )
    path = tmp_path / "rocker.toml"
    path.write_text(text)
    out = tmp_path / "out"
    assert main(["fea", str(path), "--input", "B0=1.5", "-o", str(out)]) == 3
    assert "assembly range" in capsys.readouterr().err
    assert not out.exists()


def test_a_loop_of_pins_and_a_deep_chain_are_refused():
    """Pins are rigid-body reference nodes: a loop of pins alone has no tree of them, and a
    chain of three pins in a row (frame -B0- rocker -B- coupler -A- crank) cascades deeper
    than ccx 2.20 handles (docs/fea.md); both are bad input naming the hinge."""
    base = (EXAMPLES / "four_bar.toml").read_text()
    rigid = base.replace('[defaults]\nmodel = "circular_arc"', '[defaults]\nmodel = "rigid"')
    with pytest.raises(symkin.InputError, match="loop of rigid hinges"):
        fdeck.anchors(symkin.loads(rigid, "loop.toml"))
    chain = rigid.replace(
        'at = [0.0, 0.0]\nplate_angle = "pi/2"\n',
        'at = [0.0, 0.0]\nplate_angle = "pi/2"\nmodel = "circular_arc"\n',
    )
    with pytest.raises(symkin.InputError, match="two pins in a row") as err:
        fdeck.anchors(symkin.loads(chain, "chain.toml"))
    assert "[[hinge]] 'A'" in str(err.value)


def test_without_ccx_run_is_bad_input(tmp_path, capsys, monkeypatch):
    monkeypatch.setenv("PATH", str(tmp_path / "empty"))
    out = tmp_path / "out"
    assert (
        main(["fea", str(EXAMPLES / "four_bar.toml"), "--input", "A0=0.1", "-o", str(out), "--run"])
        == 2
    )
    err = capsys.readouterr().err
    assert "calculix-ccx" in err and "ccx" in err
    assert not out.exists()


# -- ccx against the references ------------------------------------------------------------------


@needs_ccx
@pytest.mark.parametrize("t_over_l, theta", [(0.1, 0.2), (0.05, 0.2), (0.05, -0.05)])
def test_single_plate_is_a_shortened_circular_arc(t_over_l, theta):
    """Pure rotation of the arm: the plate's end sits on the circular arc, its deviation from
    the midpoint pin |d| (cos theta/2, sin theta/2) with |d|/l = 2 sin(theta/2)/theta -
    cos(theta/2), scaled by 1 - 12 c (t/l)^2 within the clamp faces' O(t/l) effect (CLAMP t/l)
    and the mesh (0.05 %); both components scaled alike (the arc's shape is kept)."""
    l = 0.01
    _, dev = solve(MECHANISMS / "single_plate.toml", {"H": theta}, params={"t": repr(l * t_over_l)})
    d = l * (2 * math.sin(theta / 2) / theta - math.cos(theta / 2))
    arc = (d * math.cos(theta / 2), d * math.sin(theta / 2))
    rel = [dev["T"][k] / arc[k] - 1 for k in (0, 1)]
    assert abs(rel[0] - rel[1]) < 2e-5
    assert abs(rel[0] - svk_shortening(t_over_l)) < CLAMP * t_over_l + 5e-4


@needs_ccx
def test_millimetre_file_gives_the_same_model():
    """units = "mm": the deck is in metres all the same, the deviation comes back in mm."""
    text = (MECHANISMS / "single_plate.toml").read_text()
    mm = text.replace('ground = "frame"', 'ground = "frame"\nunits = "mm"')
    mm = mm.replace("l = 0.01 ", "l = 10   ").replace("width = 0.01 ", "width = 10   ")
    assert mm.count("= 10 ") == 2
    metres = fea.prepare(symkin.loads(text, "m.toml"), {"H": 0.3})
    millimetres = fea.prepare(symkin.loads(mm, "mm.toml"), {"H": 0.3})
    a, b = fea.write_deck(metres, COARSE), fea.write_deck(millimetres, COARSE)
    assert a.text.split("*NODE")[1] == b.text.split("*NODE")[1]
    dev_m = fea.deviations(a, ccx.run(a, "m"))["T"]
    dev_mm = fea.deviations(b, ccx.run(b, "mm"))["T"]
    assert dev_mm == pytest.approx((1e3 * dev_m[0], 1e3 * dev_m[1]), rel=1e-12)


@needs_ccx
@pytest.mark.parametrize("t_over_l", [0.1, 0.05])
def test_clamped_guided_plate_under_a_small_force(t_over_l):
    """The arm held at H = 0 and pushed across by V: the plate is clamped-guided, the arm moves
    by V l^3/(12 E' I) + V l/(kappa G b t) (Euler-Bernoulli and Timoshenko shear, kappa = 5/6,
    linear: the deflection is 1e-4 l). The continuum's rigid clamp faces stiffen it by O(t/l):
    between 0 and 0.1 t/l (the mesh adds 0.05 %)."""
    l, b, E, nu = 0.01, 0.01, 200e9, 0.3
    t = t_over_l * l
    ei = E / (1 - nu**2) * b * t**3 / 12
    v = 1e-4 * l * 12 * ei / l**3
    _, dev = solve(MECHANISMS / "single_plate.toml", {"H": 0}, params={"t": repr(t), "V": repr(v)})
    beam = v * l**3 / (12 * ei) + v * l / (5 / 6 * E / (2 * (1 + nu)) * b * t)
    stiffening = 1 - dev["T"][1] / beam
    assert -5e-4 < stiffening < 0.1 * t_over_l + 5e-4
    assert abs(dev["T"][0]) < 1e-3 * abs(dev["T"][1])


@needs_ccx
def test_relative_input_on_an_open_chain():
    """Two plates in series, the second input relative to a moving link (an *EQUATION between
    rotation nodes): the tip deviates like the exact level's composed arcs, scaled by
    1 - 12 c (t/l)^2 (t = l/20) within the single plate's tolerance."""
    inputs = {"S": 0.2, "E": -0.3}
    setup, dev = solve(MECHANISMS / "serial_pair.toml", inputs)
    exact = symkin.evaluate(setup.analysis, inputs, level="exact").points["T"].deviation
    rel = [dev["T"][k] / exact[k] - 1 for k in (0, 1)]
    assert abs(rel[0] - rel[1]) < 2e-5
    assert abs(rel[0] - svk_shortening(0.05)) < CLAMP * 0.05 + 5e-4


@needs_ccx
@pytest.mark.parametrize("alpha, short, rise", [(1, 0.05643, 0.30172), (2, 0.16064, 0.49346)])
def test_cantilever_matches_bisshopp_drucker(alpha, short, rise):
    """A released plate (t = l/100) under a transverse dead load at its tip, alpha = F l^2/EI
    with EI = E' b t^3/12 (plane strain): the tip's shortening and rise within 0.15 % of the
    published values (clamp faces ~0.08 t/l, shear 0.9 (t/l)^2, the mesh 0.04 %, the table's
    fifth digit)."""
    l = 0.01
    _, dev = solve(
        MECHANISMS / "cantilever.toml",
        {"H": 0},
        fea.Mesh(40, 2, 0.8),
        {"alpha": str(alpha)},
        released=("H",),
    )
    x, y = dev["T"]
    assert -x / l == pytest.approx(short, rel=1.5e-3)
    assert y / l == pytest.approx(rise, rel=1.5e-3)


@needs_ccx
def test_four_bar_against_equilibrium_from_the_command_line(tmp_path, capsys):
    """The example four-bar (t = l/10) through `symkin fea --run --json`: the JSON of
    docs/fea.md, ccx's results kept beside the deck, and the FE deviation within
    continuum_bound of `equilibrium`."""
    out = tmp_path / "out"
    assert (
        main(
            [
                "fea",
                str(EXAMPLES / "four_bar.toml"),
                "--input",
                "A0=0.2",
                "-o",
                str(out),
                "--mesh",
                "20,2,0.8",
                "--run",
                "--json",
                "--quiet",
            ]
        )
        == 0
    )
    import json

    data = json.loads(capsys.readouterr().out)
    assert data["mesh"] == [20, 2] and data["ccx_seconds"] > 0
    point = data["points"]["C"]
    assert set(point) == {"fea", "equilibrium", "loaded", "difference"}
    assert set(point["difference"]) == {"equilibrium", "loaded"}
    miss = math.hypot(
        point["equilibrium"][0] - point["fea"][0], point["equilibrium"][1] - point["fea"][1]
    )
    assert point["difference"]["equilibrium"] == pytest.approx(miss / math.hypot(*point["fea"]))
    setup = fea.prepare(EXAMPLES / "four_bar.toml", {"A0": 0.2})
    assert miss < continuum_bound(setup, {"A0": 0.2})["C"]
    assert {p.name for p in out.iterdir()} == {"four_bar.inp", "four_bar.frd", "four_bar.dat"}


@needs_ccx
@pytest.mark.parametrize(
    "file, inputs",
    [
        ("parallel_stage.toml", {"F1": 0.05}),  # t = l/20, a payload on the stage
        ("four_bar_pins.toml", {"A0": 0.2}),  # two pins, chained
        (
            EXAMPLES / "nine_bar_platform.toml",  # three relative inputs, force-dominated
            {"O": 0.02, "A": -0.02, "B": 0.01, "K": 0.02},
        ),
    ],
)
def test_mechanisms_against_equilibrium(file, inputs):
    setup, dev = solve(MECHANISMS / file, inputs)
    eq = symkin.evaluate(setup.analysis, inputs, level="equilibrium")
    bound = continuum_bound(setup, inputs)
    for name, d in dev.items():
        e = eq.points[name].deviation
        assert math.hypot(e[0] - d[0], e[1] - d[1]) < bound[name]


@needs_ccx
def test_ccx_not_converging_exits_3_quoting_it(tmp_path, capsys, monkeypatch):
    """Two increments allowed where the ramp takes four: ccx stops; the command exits 3 with
    ccx's own *ERROR line and the load factor reached, and keeps ccx's output beside the deck
    (no results)."""
    monkeypatch.setattr(fdeck, "MAX_INCREMENTS", 2)
    out = tmp_path / "out"
    assert (
        main(
            [
                "fea",
                str(MECHANISMS / "single_plate.toml"),
                "--input",
                "H=0.5",
                "-o",
                str(out),
                "--mesh",
                "10,1",
                "--run",
                "--quiet",
            ]
        )
        == 3
    )
    err = capsys.readouterr().err
    assert "*ERROR" in err and "increments" in err and "load factor 0.5 of 1" in err
    assert "single_plate.log" in err
    assert (out / "single_plate.log").exists() and not (out / "single_plate.frd").exists()


# -- actuators -----------------------------------------------------------------------------------


def driven(drive: str) -> symkin.Mechanism:
    """The parallelogram with F1 passive and a piezo on the stage pushing along x."""
    return symkin.loads(M.parallelogram_driven(drive), f"parallelogram_{drive}.toml")


def test_actuator_deck_names_it_and_constrains_its_point():
    """A stroke: an *EQUATION on the stage's reference node (at the actuator's point) with a
    prescribed auxiliary node, the surrogate hinge left free; a force: a *CLOAD there."""
    stroke = fea.write_deck(fea.prepare(driven("stroke"), {"piezo": 2e-3}), COARSE).text
    assert "** actuator 'piezo' on 'stage': a stroke of 0.002 m" in stroke
    assert "reference node, at actuator 'piezo's point\n" in stroke
    # the auxiliary node's comment, the equation, the prescribed stroke
    eq = stroke.split("** actuator 'piezo': 'stage' at node ")[2].splitlines()
    ref = eq[0].split()[0]
    assert eq[1:3] == ["*EQUATION", "2"] and eq[3].startswith(f"{ref}, 1, 1, ")
    assert "input '" not in stroke  # S1 (the surrogate) is not prescribed
    force = fea.write_deck(fea.prepare(driven("force"), {"piezo": 0.3}), COARSE).text
    assert "a force of 0.3 N" in force and "*EQUATION\n2\n" not in force
    load = force.split("** actuator 'piezo': pushes 'stage' at node ")[1].splitlines()
    assert load[1] == f"{load[0].split()[0]}, 1, 0.3"


def test_actuator_on_a_pinned_link_is_refused(tmp_path, capsys):
    """The actuator's point must be its link's reference node, which a pin already is: exit 2
    naming the actuator, nothing written."""
    text = (MECHANISMS / "four_bar_pins.toml").read_text()
    head, tail = text.split('name = "A0"', 1)
    text = head + 'name = "A0"' + tail.replace("input = true\n", "", 1)
    text += '\n[[actuator]]\nname = "push"\nlink = "coupler"\nat = [0.06, 0.09]\n'
    text += "direction = [1.0, 0.0]\n"
    path = tmp_path / "pinned.toml"
    path.write_text(text)
    out = tmp_path / "out"
    assert main(["fea", str(path), "--input", "push=1e-4", "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert "[[actuator]] #1 'push'" in err and "the pin 'A'" in err
    assert not out.exists()


@needs_ccx
def test_stroke_actuator_against_equilibrium():
    """A stroke-driven parallelogram: the FE holds the stroke and its deviation lies within
    continuum_bound of `equilibrium`'s at that stroke."""
    setup = fea.prepare(driven("stroke"), {"piezo": 2e-3})
    result = fea.compare(setup, fea.write_deck(setup, COARSE))
    eq = symkin.evaluate(setup.analysis, {"piezo": 2e-3}, level="equilibrium")
    assert result.strokes["piezo"] == pytest.approx(2e-3, rel=1e-9)
    d, e = result.fea["P"], eq.points["P"].deviation
    assert math.hypot(e[0] - d[0], e[1] - d[1]) < continuum_bound(setup, {"piezo": 2e-3})["P"]
    # `loaded` takes the stroke too (tests/test_loaded_actuators.py): beside equilibrium's
    assert not result.failed
    q = result.levels["loaded"]["P"]
    assert math.hypot(e[0] - q[0], e[1] - q[1]) <= 1e-6 * math.hypot(*e)


@needs_ccx
def test_force_actuator_against_equilibrium():
    """A force-driven parallelogram: the FE's stroke against the stroke `equilibrium` produces,
    and the FE deviation against the rigid linkage at the FE's own stroke within
    continuum_bound of `equilibrium`'s (taken against the rigid linkage at its stroke). The
    bound is the stroke-driven one's at equilibrium's stroke (the same equilibrium)."""
    setup = fea.prepare(driven("force"), {"piezo": 0.3})
    result = fea.compare(setup, fea.write_deck(setup, COARSE))
    eq = symkin.evaluate(setup.analysis, {"piezo": 0.3}, level="equilibrium")
    s = eq.actuators["piezo"].stroke
    stroke_setup = fea.prepare(driven("stroke"), {"piezo": s})
    bound = continuum_bound(stroke_setup, {"piezo": s})["P"]
    d, e = result.fea["P"], eq.points["P"].deviation
    assert result.level_strokes["piezo"] == pytest.approx(s, rel=1e-12)
    s_fe = result.strokes["piezo"]
    assert abs(s_fe - s) / abs(s) < bound / math.hypot(*e)
    # the continuum is stiffer: it stops at a slightly shorter stroke, where the deviation (~ s^2)
    # is smaller; at the FE's own stroke the stroke-driven `equilibrium` is within the bound ...
    at_fe = symkin.evaluate(stroke_setup.analysis, {"piezo": s_fe}, level="equilibrium")
    f = at_fe.points["P"].deviation
    assert math.hypot(f[0] - d[0], f[1] - d[1]) < bound
    # ... and against the force-driven one, the bound plus the deviation's change over the
    # stroke miss
    shift = math.hypot(f[0] - e[0], f[1] - e[1])
    assert math.hypot(e[0] - d[0], e[1] - d[1]) < bound + shift


@needs_ccx
def test_stroke_along_a_slant_direction_on_the_four_bar():
    """The example four-bar pushed on its rocker along (0.6, 0.8) (A0 made passive, as
    tests/test_actuators.py builds it): the two-term *EQUATION holds the stroke, and the FE
    deviation lies within continuum_bound of `equilibrium`'s."""
    text = (EXAMPLES / "four_bar.toml").read_text()
    head, tail = text.split('name = "A0"', 1)
    text = head + 'name = "A0"' + tail.replace("input = true\n", "", 1)
    text += '\n[[actuator]]\nname = "pusher"\nlink = "rocker"\nat = [0.1, 0.05]\n'
    text += "direction = [0.6, 0.8]\n"
    setup = fea.prepare(symkin.loads(text, "four_bar_pusher.toml"), {"pusher": 1e-3})
    deck = fea.write_deck(setup, COARSE)
    assert "*EQUATION\n3\n" in deck.text  # d_y u_y + d_x u_x - A = 0
    result = fea.compare(setup, deck)
    assert result.strokes["pusher"] == pytest.approx(1e-3, rel=1e-9)
    eq = symkin.evaluate(setup.analysis, {"pusher": 1e-3}, level="equilibrium")
    bound = continuum_bound(setup, {"pusher": 1e-3})
    for name, d in result.fea.items():
        e = eq.points[name].deviation
        assert math.hypot(e[0] - d[0], e[1] - d[1]) < bound[name]


@needs_ccx
def test_a_structure_under_a_force_actuator():
    """The leaf-spring parallelogram of single plates (a structure, docs/levels.md): its rigid
    pose is the as-fabricated one, its force actuator a load. The continuum's stage moves by the
    linear frame of two Timoshenko legs (written out here: clamped-guided bending with shear,
    the legs' stretch letting the stage turn) to within (t/L)^2, and drops by Awtar's
    (3/5) y^2/L; the stroke is the push point's displacement, 0 in the rigid pose."""
    force, span, gap = 0.02, 0.040, 0.025
    ei, ea = 210e9 * 10e-3 * 0.5e-3**3 / 12, 210e9 * 10e-3 * 0.5e-3
    kga = 5 / 6 * 105e9 * 10e-3 * 0.5e-3
    phi = 12 * ei / (kga * span**2)
    bend = (
        ei / (span**3 * (1 + phi)) * np.array([[12, -6 * span], [-6 * span, (4 + phi) * span**2]])
    )
    stiffness = np.zeros((3, 3))
    for x in (0.0, gap):
        across = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])
        along = np.array([0.0, 1.0, x - gap / 2])
        stiffness += across.T @ bend @ across + ea / span * np.outer(along, along)
    y = np.linalg.solve(stiffness, [force, 0.0, 0.0])[0]
    setup = fea.prepare(
        ROOT / "tests" / "mechanisms" / "leaf_parallelogram.toml", {"push": force}, {"F": "0"}
    )
    result = fea.compare(setup, fea.write_deck(setup, COARSE))
    dx, dy = result.fea["P"]
    assert dx == pytest.approx(y, rel=(0.5e-3 / span) ** 2)
    assert dy == pytest.approx(-0.6 * dx**2 / span, rel=2e-3)
    assert result.strokes["push"] == pytest.approx(dx, rel=1e-6)
    eq = symkin.evaluate(setup.analysis, {"push": force}, level="equilibrium", params={"F": "0"})
    assert result.level_strokes["push"] == pytest.approx(eq.actuators["push"].stroke, rel=1e-12)
