"""`check` reports what evaluation will refuse, with a fix line; every backend refuses alike."""

from __future__ import annotations

import pytest
from conftest import EXAMPLES
from evaluators import BACKENDS, Generated

import symkin
from symkin.cli.commands import main

FOUR_BAR = (EXAMPLES / "four_bar.toml").read_text()


def nine_bar_input_moved_to_d() -> str:
    """The nine-bar with the input at K moved to D: D's angle is fixed by the loops already, so
    K, G and H are left free in the as-fabricated pose (a singular loop Jacobian)."""
    parts = (EXAMPLES / "nine_bar_platform.toml").read_text().split("[[hinge]]")
    for i, part in enumerate(parts):
        if 'name = "K"' in part:
            parts[i] = part.replace("input = true\n", "")
        if 'name = "D"' in part:
            parts[i] = part.rstrip("\n") + "\ninput = true\n\n"
    return "[[hinge]]".join(parts)


def run(args, capsys):
    code = main(args)
    return (code, *capsys.readouterr())


@pytest.mark.parametrize(
    "at, message",
    [
        # B on top of A: the coupler turns about the pair (plates may overlap: they are no
        # longer refused for it, docs/file-format.md)
        ("[0.015, 0.026]", "do not determine the pose"),
        ("[0.0575, 0.013]", "collinear"),  # B midway between A and B0: a toggle
    ],
)
def test_check_refuses_as_eval_does(tmp_path, capsys, at, message):
    path = tmp_path / "four_bar.toml"
    path.write_text(FOUR_BAR.replace("at = [0.085, 0.068]", f"at = {at}"))
    code, out, err = run(["check", str(path)], capsys)
    assert code == 2 and message in err and "fix:" in err and "valid" not in out
    code, _, err_eval = run(["eval", str(path), "--input", "A0=0.1"], capsys)
    assert code == 2 and err_eval == err


def test_inputs_that_leave_the_loops_singular_are_refused_by_check(tmp_path, capsys):
    path = tmp_path / "nine_d.toml"
    path.write_text(nine_bar_input_moved_to_d())
    code, out, err = run(["check", str(path)], capsys)
    assert code == 2 and "do not determine the pose" in err and "fix:" in err
    assert "K" in err and out == ""
    code, _, err = run(["derive", str(path), "-o", str(tmp_path / "out"), "--quiet"], capsys)
    assert code == 2 and not (tmp_path / "out").exists()


def test_the_examples_pass_the_check(capsys):
    for name in ("four_bar", "stephenson_six_bar", "nine_bar_platform"):
        code, out, _ = run(["check", str(EXAMPLES / f"{name}.toml")], capsys)
        assert code == 0 and "valid" in out.splitlines()[0]


@pytest.mark.parametrize("backend", BACKENDS)
def test_every_backend_refuses_a_dependent_input_alike(tmp_path, capsys, backend):
    """The reader refuses inputs that leave the pose free (the rank of the closure Jacobian,
    docs/levels.md), so every backend exits 2 with the same message."""
    path = tmp_path / "nine_d.toml"
    path.write_text(nine_bar_input_moved_to_d())
    args = ["eval", str(path), "--backend", backend]
    for name in ("O", "A", "B", "D"):
        args += ["--input", f"{name}=0"]
    code, out, err = run(args, capsys)
    assert code == 2 and out == ""
    # K, G and H lie on one line: with D held they form a dyad at its toggle position
    assert "do not determine the pose" in err and "dependent input" in err
    assert "K, G, H are collinear" in err and "fix: move the middle hinge off the line" in err


def test_numpy_module_on_0d_input_with_a_singular_system(monkeypatch):
    # the reader refuses the file (a dependent input): built past that rule, the generated
    # module still reports the singular loop Jacobian as not ok
    from symkin.model import reader

    monkeypatch.setattr(reader._Reader, "check_mobility", lambda self, mech: None)
    g = Generated(
        mech=symkin.loads(nine_bar_input_moved_to_d(), "nine_d.toml"),
        sensitivity=False,
        levels=["exact"],
    )
    res = g.numpy.evaluate({"O": 0.0, "A": 0.0, "B": 0.0, "D": 0.0}, "exact")
    assert res["ok"].shape == () and not res["ok"]
    assert all(v != v for v in res["points"]["F"]["deviation"])  # NaN
