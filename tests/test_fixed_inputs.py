"""Fixed inputs (`derive --fix H=V`, `symkin.compile(..., fixed=...)`; docs/cli.md).

An input held at a constant angle leaves the evaluators' arguments and its value is folded into
the routines. Every check compares the evaluator with a fixed input against the 40-digit mpmath
evaluation of the whole file at that input's value (the sympy backend, no generated code): a
two-input five-bar (closed-form dyads), a triad six-bar beside a four-bar on one frame (no
closed form: continuation from the as-fabricated pose must carry the fixed input too), and the
nine-bar platform at its physical level `loaded`.
"""

from __future__ import annotations

import re
import subprocess
import sys

import mechanisms as M
import numpy as np
import pytest
from conftest import EXAMPLES
from evaluators import GENERATED, require

import symkin
from symkin.studies.evaluation import evaluate

# The triad six-bar and, 0.3 m to its right, the example four-bar with its own input A0.
TRIAD_AND_FOUR_BAR = M.text(
    "triad_four_bar",
    M.links("ground", "crank", "link1", "tri", "link2", "link3", "a", "c", "r")
    + M.hinge("O1", "ground", "crank", 0.0, 0.0, "pi/2", input=True)
    + M.hinge("A", "crank", "link1", 0.02, 0.02, "0")
    + M.hinge("B", "link1", "tri", 0.06, 0.05, "pi/4")
    + M.hinge("C", "tri", "link2", 0.1, 0.07, "0")
    + M.hinge("O4", "ground", "link2", 0.14, 0.01, "pi/2")
    + M.hinge("D", "tri", "link3", 0.08, 0.1, "pi/2")
    + M.hinge("O5", "ground", "link3", 0.03, 0.12, "0")
    + M.hinge("F0", "ground", "a", 0.3, 0.0, "pi/2", input=True)
    + M.hinge("F1", "a", "c", 0.315, 0.026, "pi/3")
    + M.hinge("F2", "ground", "r", 0.4, 0.0, "pi/2")
    + M.hinge("F3", "c", "r", 0.385, 0.068)
    + M.point("T", "tri", 0.09, 0.08)
    + M.point("Q", "c", 0.36, 0.09),
)


def _mech(text: str, name: str = "fixed.toml"):
    return symkin.loads(text, name)


def _reference(mech, inputs: dict, level: str, points) -> dict:
    an = symkin.analyze(mech)
    ev = evaluate(an, {k: str(v) for k, v in inputs.items()}, level)
    return {p: np.array(ev.points[p].deviation) for p in points}


def _check(mech, fixed: dict, free: list[dict], levels, backends=GENERATED, tol=1e-13):
    for backend in backends:
        require(backend)
        ev = symkin.compile(mech, backend=backend, fixed=fixed)
        assert set(ev.inputs) == set(mech.inputs) - set(fixed)
        for inputs in free:
            for level in levels:
                got = ev.evaluate({k: np.float64(v) for k, v in inputs.items()}, level)
                assert bool(np.all(got["ok"]))
                want = _reference(mech, {**inputs, **fixed}, level, ev.points)
                for p, w in want.items():
                    g = np.asarray(got["points"][p]["deviation"], dtype=float)
                    assert np.abs(g - w).max() <= tol * np.abs(w).max(), (backend, level, p)
    return ev


def test_five_bar_with_one_input_locked():
    mech = _mech(M.FIVE_BAR)
    ev = _check(
        mech, {"O2": "-0.1"}, [{"O1": 0.15}, {"O1": -0.2}], ("paper", "first_order", "exact")
    )
    full = symkin.compile(mech, backend="c", sensitivity=False)

    def ops(e, routine):
        return int(re.search(rf"\b{routine} (\d+)", e.sources.header).group(1))

    assert ops(ev, "rigid") < ops(full, "rigid") and ops(ev, "newton") < ops(full, "newton")
    assert (
        "Fixed inputs, folded into the evaluator (not its arguments): O2 = -1/10 rad."
        in ev.sources.header
    )


def test_continuation_carries_the_fixed_input():
    """No closed form (a triad): the rigid pose is reached by continuation in every input from
    the as-fabricated pose; the fixed crank (1.2 rad, 24 continuation steps) must follow (set at
    once, it leaves the first step's Newton too far to converge)."""
    mech = _mech(TRIAD_AND_FOUR_BAR)
    assert not symkin.analyze(mech).rigid.closed_form
    _check(mech, {"F0": "1.2"}, [{"O1": 0.1}, {"O1": -0.05}], ("exact",))


def test_fixed_inputs_at_the_physical_level():
    mech = symkin.load(EXAMPLES / "nine_bar_platform.toml")
    _check(
        mech,
        {"B": "0.02", "K": "-0.03"},
        [{"O": 0.1, "A": -0.05}],
        ("loaded",),
        backends=("numpy",),
        tol=1e-12,
    )


@pytest.mark.parametrize(
    "fixed, message",
    [
        ({"Q": "0.1"}, "'Q' is not an input hinge"),
        ({"O1": "0.1", "O2": "0.2"}, "every input is fixed"),
        ({"O2": "4"}, "not within"),
    ],
)
def test_bad_fixed_inputs_are_refused(fixed, message):
    with pytest.raises(symkin.InputError, match=message):
        symkin.compile(_mech(M.FIVE_BAR), backend="numpy", fixed=fixed)


def test_derive_fix_on_the_command_line(tmp_path):
    path = tmp_path / "five_bar.toml"
    path.write_text(M.FIVE_BAR)
    out = tmp_path / "out"
    done = subprocess.run(
        [
            sys.executable,
            "-m",
            "symkin",
            "derive",
            str(path),
            "-o",
            str(out),
            "--emit",
            "numpy,c",
            "--fix",
            "O2=-pi/30",
            "--quiet",
        ],
        capture_output=True,
        text=True,
    )
    assert done.returncode == 0, done.stderr
    header = (out / "five_bar.h").read_text()
    assert "#define FIVE_BAR_N_INPUTS 1" in header and "O2 = -pi/30 rad" in header
    bad = subprocess.run(
        [
            sys.executable,
            "-m",
            "symkin",
            "derive",
            str(path),
            "-o",
            str(out),
            "--fix",
            "O2=0.1",
            "--tolerance",
            "1e-3",
            "--quiet",
        ],
        capture_output=True,
        text=True,
    )
    assert bad.returncode == 2 and "fix:" in bad.stderr


def test_the_report_states_the_fixed_input_and_sweeps_the_free_one():
    from symkin.studies.derive import generate

    files = generate(_mech(M.FIVE_BAR), ["latex"], fixed={"O2": "-0.1"}, appendix=True)
    body = files["five_bar.tex"].decode()
    assert "Fixed inputs, folded into the evaluator" in body
    assert "O2 = -1/10 rad" in body.replace(r"\penalty0{}", "").replace("{}", "")
    # one deviation figure: O1 is the only input swept
    assert "five_bar-deviation.pdf" in files and "five_bar-deviation-2.pdf" not in files


def test_a_range_over_a_fixed_input_is_refused():
    from symkin.studies.derive import generate

    with pytest.raises(symkin.InputError, match="O2 is fixed") as err:
        generate(_mech(M.FIVE_BAR), ["latex"], fixed={"O2": "-0.1"}, spans={"O2": (-0.1, 0.1)})
    assert err.value.entry == "--range"
