"""A link's mass, inertia and centre of mass (docs/file-format.md, "[[link]]"): read as numbers
or expressions over the parameters, refused with exit 2 naming the file, the link and the fix,
and printed by `symkin check`."""

from __future__ import annotations

import pytest
from cli_runs import symkin_cli
from conftest import EXAMPLES

import symkin
from symkin.core.errors import InputError

FOUR_BAR = (EXAMPLES / "four_bar.toml").read_text()
COUPLER = '[[link]]\nname = "coupler"\n'


def with_coupler(keys: str) -> str:
    assert COUPLER in FOUR_BAR
    return FOUR_BAR.replace(COUPLER, COUPLER + keys + "\n")


def test_mass_inertia_and_centre_are_read_as_expressions():
    mech = symkin.loads(
        with_coupler('mass = "2*l"\ninertia = 3e-6\ncentre = ["l", 0.05]'), "m.toml"
    )
    link = mech.link("coupler")
    values = mech.defaults
    assert link.massive and float(link.mass.subs(values)) == pytest.approx(2e-3)
    assert float(link.inertia) == pytest.approx(3e-6)
    assert [float(v.subs(values)) for v in link.centre] == pytest.approx([1e-3, 0.05])
    assert not mech.link("crank").massive and mech.link("crank").mass is None


@pytest.mark.parametrize(
    "keys, said, fix",
    [
        ("mass = 0", "mass must be positive (kg), got 0", "mass = 0.12"),
        ("mass = -1\ncentre = [0, 0]", "mass must be positive (kg), got -1", "mass = 0.12"),
        ("mass = 0.1", "'mass' without 'centre'", "add centre = [x, y]"),
        ("inertia = 1e-6", "'inertia' without 'mass'", "add mass = ..."),
        ("centre = [0, 0]", "'centre' without 'mass'", "add mass = ..."),
        (
            "mass = 0.1\ncentre = [0, 0]\ninertia = -1e-6",
            "inertia must be zero or positive",
            "kg·m²",
        ),
        ("mass = 0.1\ncentre = [0]", "'centre' must be a list of two coordinates", "[x, y]"),
        ('mass = "sqrt(-1)"\ncentre = [0, 0]', "'mass': 'sqrt(-1)'", "expression"),
        ("mass = 0.1\ncentre = [0, 0]\nmas = 2", "unknown key 'mas'", "mass"),
    ],
)
def test_bad_masses_exit_2_naming_the_link_and_the_fix(tmp_path, keys, said, fix):
    if keys == "mass = 0":
        keys += "\ncentre = [0, 0]"
    path = tmp_path / "m.toml"
    path.write_text(with_coupler(keys))
    run = symkin_cli("check", str(path))
    assert run.returncode == 2, run.stderr
    assert str(path) in run.stderr and "coupler" in run.stderr, run.stderr
    assert said in run.stderr and "fix:" in run.stderr and fix in run.stderr, run.stderr


def test_a_mass_on_the_ground_is_refused():
    text = FOUR_BAR.replace(
        '[[link]]\nname = "frame"\n', '[[link]]\nname = "frame"\nmass = 1\ncentre = [0, 0]\n'
    )
    with pytest.raises(InputError) as err:
        symkin.loads(text, "m.toml")
    assert "'frame'" in str(err.value) and "does not move" in str(err.value)


def test_a_param_override_is_checked_too(tmp_path):
    path = tmp_path / "m.toml"
    text = with_coupler('mass = "mc"\ncentre = [0.05, 0.05]').replace(
        "l = 1e-3", "l = 1e-3\nmc = 0.1"
    )
    path.write_text(text)
    assert symkin.load(path).link("coupler").massive
    run = symkin_cli("eval", str(path), "--input", "A0=0.1", "--param", "mc=-0.5")
    assert run.returncode == 2 and "--param" in run.stderr, run.stderr
    assert "mass must be positive" in run.stderr and "coupler" in run.stderr


def test_check_prints_the_masses(tmp_path):
    path = tmp_path / "m.toml"
    path.write_text(with_coupler("mass = 0.25\ninertia = 2e-5\ncentre = [0.05, 0.06]"))
    run = symkin_cli("check", str(path))
    assert run.returncode == 0, run.stderr
    line = next(s for s in run.stdout.splitlines() if " coupler" in s)
    assert "mass 0.25 kg, inertia 2e-05 kg·m² about its centre (0.05, 0.06)" in line, line
