"""Side outputs never lose the main answer (docs/physics.md, "Overloads and buckling"): at
`loaded` as at `equilibrium`, a buckling search that fails leaves the equilibrium reported with
`"buckling": null` and a `"buckling_note"`, exit 0, the deviations as without the failure, the
same bytes every run."""

from __future__ import annotations

import json

from cli_runs import symkin_cli
from conftest import EXAMPLES

LEVER = str(EXAMPLES.parent / "tests" / "mechanisms" / "lever_amplifier.toml")


def test_a_loaded_buckling_search_that_fails_loses_nothing_else(monkeypatch):
    from symkin.physics import reduced_reported

    argv = ["eval", LEVER, "--level", "loaded", "--input", "P0=0.01", "--json"]
    whole = symkin_cli(*argv)
    assert whole.returncode == 0, whole.stderr
    before = json.loads(whole.stdout)

    def fails(*args, **kwargs):
        raise ZeroDivisionError("float division by zero")

    monkeypatch.setattr(reduced_reported, "buckling_factor", fails)
    runs = [symkin_cli(*argv) for _ in range(2)]
    assert all(r.returncode == 0 for r in runs), runs[0].stderr
    assert runs[0].stdout == runs[1].stdout  # the same bytes every run
    data = json.loads(runs[0].stdout)
    assert data["buckling"] is None
    assert data["buckling_note"] == (
        "the buckling search failed (ZeroDivisionError: float division by zero)"
    )
    assert data["points"] == before["points"] and data["plates"] == before["plates"]
    text = symkin_cli(*argv[:-1])
    assert "buckling: not found (the buckling search failed" in text.stdout
