"""Plausibility of a mechanism file (docs/physics.md, "Overloads and buckling"): mistakes a
designer makes that the file's grammar accepts, each refused with exit 2 naming what is wrong and
the likely fix."""

from __future__ import annotations

import pytest
from cli_runs import symkin_cli
from conftest import EXAMPLES

import symkin
from symkin.core.errors import InputError

FOUR_BAR = (EXAMPLES / "four_bar.toml").read_text()


@pytest.mark.parametrize("angle, shown", [("90", "90.0"), ("-400", "-400.0"), ('"7"', "7.0")])
def test_a_plate_angle_beyond_a_full_turn_suggests_degrees(angle, shown):
    text = FOUR_BAR.replace('plate_angle = "0"', f"plate_angle = {angle}")
    with pytest.raises(InputError) as err:
        symkin.loads(text, "m.toml")
    message = str(err.value)
    assert f"[[hinge]] 'B': plate_angle = {shown} rad is beyond a full turn" in message, message
    assert f'plate_angle = "{shown}*deg"' in message


def test_a_full_turn_itself_is_accepted():
    symkin.loads(FOUR_BAR.replace('plate_angle = "0"', 'plate_angle = "2*pi"'), "m.toml")


def test_a_plate_angle_given_later_is_checked_too(tmp_path):
    path = tmp_path / "m.toml"
    path.write_text(
        FOUR_BAR.replace("l = 1e-3 ", "l = 1e-3\nb_angle = 0 ").replace(
            'plate_angle = "0"', 'plate_angle = "b_angle"'
        )
    )
    run = symkin_cli("eval", str(path), "--input", "A0=0.1", "--param", "b_angle=45")
    assert run.returncode == 2 and "--param" in run.stderr, run.stderr
    assert "beyond a full turn" in run.stderr


def test_a_hinge_on_the_wrong_link_is_named():
    """Hinge A moved onto frame-crank (the pair A0 joins): the mobility no longer matches the
    one input; the message names the two hinges and the pair, not only the input count."""
    text = FOUR_BAR.replace('links = ["crank", "coupler"]', 'links = ["frame", "crank"]', 1)
    with pytest.raises(InputError) as err:
        symkin.loads(text, "m.toml")
    message = str(err.value)
    assert "two hinges join frame and crank: 'A0' and 'A'" in message, message
    assert "one of them is likely on the wrong link" in message


def test_a_buckling_search_that_cannot_finish_loses_nothing_else(monkeypatch):
    """A side output fails alone (docs/physics.md: side outputs never lose the main answer): the
    search raising (as it did past its budget on a fixed-guided beam at 0.9 of its buckling
    load, exit 3) leaves the equilibrium reported, `buckling` null with the reason."""
    import json

    from symkin.core.errors import AssemblyError
    from symkin.physics import equilibrium

    lever = str(EXAMPLES.parent / "tests" / "mechanisms" / "lever_amplifier.toml")
    argv = ["eval", lever, "--level", "equilibrium", "--input", "P0=0.01", "--json"]
    whole = json.loads(symkin_cli(*argv).stdout)
    assert whole["buckling"] is None and "buckling_note" not in whole  # none up to its limit

    def gives_up(mech, *args, **kwargs):
        assert kwargs.get("seconds") == float("inf")  # bounded by its steps, not the clock
        raise AssemblyError(f"{mech.path}: the buckling search could not follow the load factor")

    monkeypatch.setattr(equilibrium, "buckling_factor", gives_up)
    run = symkin_cli(*argv)
    assert run.returncode == 0, run.stderr
    data = json.loads(run.stdout)
    assert data["buckling"] is None
    assert data["buckling_note"] == "the buckling search could not follow the load factor"
    assert data["points"] == whole["points"]
    text = symkin_cli(*argv[:-1]).stdout
    assert "buckling: not found (the buckling search could not follow the load factor)" in text
