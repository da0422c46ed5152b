"""Loads far beyond buckling (docs/physics.md, "Overloads and buckling"; the designer's
defaults, "Plausibility"): a load a hundred times what the plates carry (a slipped unit) says by
what factor and to check the file's units, at `loaded` (whose refusal said only "no
convergence") as at `equilibrium`; a solved equilibrium whose buckling factor is far below 1
prints one warning line. The reference for the factor: the lumped sway load of the
parallelogram stage under a payload, W = 4 EI/(l (L − l/3)) (the legs pivoting about the plates'
midpoints, the stage dropping by (L − l/3) q²/2; tests/test_loaded_actuators.py measures it
against the equilibrium to 0.16 %)."""

from __future__ import annotations

import re

import mechanisms as M
from cli_runs import symkin_cli
from conftest import EXAMPLES

E_PRIME, WIDTH, THICK, PLATE, LEG = 210e9 / (1 - 0.3**2), 10e-3, 0.15e-3, 5e-3, 0.040
SWAY = 4 * E_PRIME * WIDTH * THICK**3 / 12 / (PLATE * (LEG - PLATE / 3))  # N


def test_loaded_names_the_overload_and_the_units(tmp_path):
    """A 500 N payload on the parallelogram stage (37 times its sway load): `loaded` exits 3
    naming the factor (the linearised estimate, within 3 % of the lumped sway load's) and the
    units to check, instead of asking for `equilibrium` (which refuses it too)."""
    payload = 500.0
    path = tmp_path / "stage.toml"
    path.write_text(
        M.parallelogram_driven("force", f'\n[[load]]\npoint = "P"\nforce = [0.0, -{payload}]\n')
    )
    run = symkin_cli("eval", str(path), "--level", "loaded", "--input", "piezo=0.5")
    assert run.returncode == 3, run.stderr
    found = re.search(r"the loads are ([0-9.]+) times the first buckling load", run.stderr)
    assert found, run.stderr
    assert abs(float(found.group(1)) / (payload / SWAY) - 1) < 0.03, (
        found.group(1),
        payload / SWAY,
    )
    assert 'check the file\'s units (units = "m": lengths in m, forces in N' in run.stderr
    assert "ask for --level equilibrium" not in run.stderr
    assert len(run.stderr.strip().splitlines()) == 1


def test_a_buckling_factor_far_below_one_warns_in_one_line(monkeypatch):
    """An equilibrium reported with a buckling factor of 0.05 (the loads 20 times what buckles
    the mechanism: a post-buckled path) warns in one line naming the factor and the units; at
    0.5 it does not."""
    from symkin.physics import equilibrium

    lever = str(EXAMPLES.parent / "tests" / "mechanisms" / "lever_amplifier.toml")
    argv = ["eval", lever, "--level", "equilibrium", "--input", "P0=0.01"]
    for factor, warned in ((0.05, True), (0.5, False)):
        monkeypatch.setattr(
            equilibrium,
            "buckling_factor",
            lambda *args, f=factor, **kwargs: equilibrium.Buckling(f, "F"),
        )
        run = symkin_cli(*argv)
        assert run.returncode == 0, run.stderr
        lines = [x for x in run.stderr.splitlines() if x.startswith("symkin: warning:")]
        if not warned:
            assert not lines, run.stderr
            continue
        assert len(lines) == 1, run.stderr
        assert "the loads are 20 times the first buckling load of the mechanism" in lines[0]
        assert "(its buckling factor 0.05, hinge 'F')" in lines[0]
        assert "check the file's units (units = " in lines[0]
        assert lines[0].endswith("(PlausibilityWarning)")
