"""Every file in tests/bad/ is rejected cleanly: exit code 2, a short message naming the file and
the
offending entry, no traceback, nothing executed. The good examples pass `check` and `matrices`.

Each bad file is the four-bar of examples/four_bar.toml with one fault; its first comment line
says which. The expected fragments below are written from the files, not from symkin's output.
"""

from __future__ import annotations

import json
import shutil
import subprocess
import time
from pathlib import Path

import pytest
from cli_runs import symkin_cli

import symkin

ROOT = Path(__file__).resolve().parent.parent
BAD = Path(__file__).resolve().parent / "bad"
EXAMPLES = sorted((ROOT / "examples").glob("*.toml"))

# file stem -> fragments that stderr must contain (after the file's own name is taken out, so a
# file called missing_name.toml cannot pass the 'name' check by its name alone). A tuple inside
# the tuple lists alternatives, any one of which will do.
EXPECTED: dict[str, tuple] = {
    # TOML and the top level
    "toml_syntax_error": (("toml_syntax_error.toml:34", "line 34"),),
    "unknown_top_level_key": ("author",),
    "missing_format": ("'format'",),
    "wrong_format": ("format", "2"),
    "format_float": ("format", "1.0"),
    "missing_name": ("'name'",),
    "name_not_identifier": ("four-bar v2",),
    "ground_unknown_link": ("ground", "frme", "frame"),
    # unknown keys, with the near-miss suggestion where there is one
    "unknown_key_hinge": ("'A'", "lenght", "'length'"),
    "unknown_key_link": ("coupler", "mass"),
    "unknown_key_point": ("'C'", "lnk", "'link'"),
    # names
    "duplicate_link_name": ("'coupler'",),
    "duplicate_hinge_name": ("'A'",),
    "duplicate_point_name": ("'C'",),
    "hinge_unknown_link": ("'B'", "rocer", "rocker"),
    "hinge_self_loop": ("'B'", "coupler"),
    "point_unknown_link": ("'C'", "couplr", "coupler"),
    "disconnected_link": ("slider",),
    # numbers and expressions
    "plate_length_zero": ("'A'", "length"),
    "plate_length_negative": ("'A'", "length"),
    "length_division_by_zero": ("'A'", "length", "1/0"),
    "length_overflow": ("'A'", "length"),
    "length_log_zero": ("'A'", "length"),
    "unknown_parameter": ("'A'", "length", "l_hinge"),
    "parameter_forward_reference": ("'l'", "half"),
    "power_bomb": ("'A'", "length", "9**9**9**9"),
    "power_bomb_nested": ("'A'", "length"),
    "power_bomb_parameter": (("p2", "p3", "p4"),),
    "power_bomb_exp": ("'A'", "length"),
    # expressions that try to run code
    "inject_import": ("'A'", "plate_angle", "__import__"),
    "inject_attribute": ("'A'", "plate_angle", "pi.real"),
    "inject_dunder_class": ("'C'", "__class__"),
    "inject_lambda": ("'A'", "plate_angle", "lambda"),
    "call_eval": ("'A'", "plate_angle", "eval"),
    "call_open": ("w_open", "open"),
    # mobility and inputs
    "too_many_inputs": ("input", "A0"),
    "too_few_inputs": ("input",),
    "mobility_zero": ("mobility",),
    # hinge models
    "unknown_hinge_model": ("'A'", "circle_arc", "circular_arc"),
    "prbm_gamma_too_large": ("'A'", "gamma", "1.5"),
    "prbm_unknown_preset": ("'A'", "torque"),
    "model_param_not_taken": ("'A'", "gamma", "circular_arc"),
    "table_missing_csv": ("'A'", "no_such_table.csv"),
    "table_bad_row": ("'A'", "table_bad_row.csv:4"),
    "expr_f0_not_l": ("'A'", "f(0)"),
    # plate stiffness, the rigid pin and the length unit (docs/physics.md)
    "thickness_not_below_length": ("'A'", "thickness", "length"),
    "youngs_modulus_negative": ("'A'", "E", "-2.1e+11"),
    "poisson_ratio_half": ("'B'", "nu", "0.5"),
    "allowable_stress_negative": ("allowable_stress", "-2.5e+08", "positive"),
    "width_zero": ("'B0'", "width"),
    "thickness_log_zero": ("'A'", "thickness"),
    "defaults_thickness_negative": ("<file>:14: [defaults]", "thickness must be positive"),
    "unknown_key_stiffness": ("'A'", "thicknes", "'thickness'"),
    "pin_unknown": ("'A'", "pin", "center"),
    "beam_unknown": ("'A'", "beam", "timoshenko", "reissner", "elastica"),
    "beam_not_a_name": ("'A0'", "beam", "1", "reissner"),
    "units_unknown": ("units", "inch"),
    # loads
    "load_unknown_point": ("[[load]] #1", "'D'"),
    "load_unknown_link": ("[[load]] #1", "coupla", "coupler"),
    "load_without_force_or_moment": ("[[load]] #1", "force", "moment"),
    "load_point_and_link": ("[[load]] #1", "point", "link"),
    "load_link_without_at": ("[[load]] #1", "at"),
    "load_force_division_by_zero": ("[[load]] #1", "force", "1/0"),
    "load_moment_log_zero": ("[[load]] #1", "moment"),
    "unknown_key_load": ("[[load]] #1", "forse", "'force'"),
    # actuators (docs/file-format.md, "[[actuator]]")
    "actuator_on_frame": ("[[actuator]] #1", "'pusher'", "frame", "moving link"),
    "actuator_unknown_link": ("[[actuator]] #1", "rocer", "rocker"),
    "actuator_zero_direction": ("'pusher'", "direction", "zero"),
    "actuator_direction_division_by_zero": ("'pusher'", "direction", "1/0"),
    "actuator_unknown_drive": ("'pusher'", "push", "stroke", "force"),
    "actuator_name_of_hinge": ("[[actuator]] #1", "'B'", "hinge"),
    "actuator_name_of_parameter": ("[[actuator]] #1", "'l'", "parameter"),
    "actuator_too_many_inputs": ("input", "A0", "pusher", "mobility is 1"),
    "actuator_at_unknown_parameter": ("'pusher'", "at", "'w'"),
    "actuator_does_not_drive": ("'pusher'", "does not drive", "direction"),
    # labeling
    "chord_on_basic_chain": ("chord", "'A'"),
    "chords_disconnect_tree": ("chords", "crank"),
    "chord_unknown_hinge": ("chords", "BB"),
}

# Files whose payload would create a file in the working directory if it were ever executed.
MARKERS = {
    "inject_import": "SYMKIN_MARKER_import",
    "inject_lambda": "SYMKIN_MARKER_lambda",
    "call_open": "SYMKIN_MARKER_open",
}
BOMBS = ("power_bomb", "power_bomb_nested", "power_bomb_parameter", "power_bomb_exp")

BAD_FILES = sorted(BAD.glob("*.toml"))


def run_cli(
    *args: str, cwd: Path | None = None, timeout: float = 60
) -> subprocess.CompletedProcess:
    return symkin_cli(*args, cwd=cwd, timeout=timeout)


def test_corpus_is_complete():
    stems = {p.stem for p in BAD_FILES}
    assert len(stems) >= 28
    assert stems == set(EXPECTED), "every bad file needs exactly one EXPECTED entry"
    assert set(MARKERS) <= stems and set(BOMBS) <= stems
    for path in BAD_FILES:
        assert path.read_text().startswith("# Bad mechanism file"), path.name


@pytest.mark.parametrize("path", BAD_FILES, ids=lambda p: p.stem)
def test_bad_file_is_rejected_cleanly(path: Path, tmp_path: Path):
    # Run on a copy in an empty working directory (with the CSV files the corpus holds), so that
    # anything the file managed to execute would leave a trace there.
    shutil.copy(path, tmp_path / path.name)
    for csv in BAD.glob("*.csv"):
        shutil.copy(csv, tmp_path / csv.name)
    before = sorted(p.name for p in tmp_path.iterdir())

    start = time.perf_counter()
    result = run_cli("check", path.name, cwd=tmp_path)
    elapsed = time.perf_counter() - start

    err = result.stderr
    assert result.returncode == 2, f"exit {result.returncode}; stderr:\n{err}"
    assert err.strip(), "no message on stderr"
    assert "Traceback" not in err
    assert len(err.strip().splitlines()) <= 6, err
    assert max(len(line) for line in err.splitlines()) < 400, err
    assert result.stdout == ""
    assert path.name in err, f"stderr does not name the file:\n{err}"

    rest = err.replace(path.name, "<file>")
    for fragment in EXPECTED[path.stem]:
        options = fragment if isinstance(fragment, tuple) else (fragment,)
        assert any(o in rest for o in options), f"none of {options} in stderr:\n{err}"

    assert sorted(p.name for p in tmp_path.iterdir()) == before, "the run created files"
    if path.stem in MARKERS:
        assert not (tmp_path / MARKERS[path.stem]).exists()
    if path.stem in BOMBS:
        assert elapsed < 15, f"power bomb took {elapsed:.1f} s to reject"


def test_toml_syntax_error_names_the_line():
    result = run_cli("check", str(BAD / "toml_syntax_error.toml"))
    assert result.returncode == 2
    assert "toml_syntax_error.toml:34" in result.stderr


def test_near_miss_key_gets_a_suggestion():
    result = run_cli("check", str(BAD / "unknown_key_hinge.toml"))
    assert "did you mean 'length'" in result.stderr


@pytest.mark.parametrize(
    "stem",
    [
        "unknown_key_hinge",
        "inject_import",
        "power_bomb",
        "power_bomb_parameter",
        "duplicate_hinge_name",
        "too_few_inputs",
        "table_missing_csv",
        "hinge_self_loop",
    ],
)
def test_load_raises_input_error(stem: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch):
    monkeypatch.chdir(tmp_path)
    path = BAD / f"{stem}.toml"
    start = time.perf_counter()
    with pytest.raises(symkin.InputError) as info:
        symkin.load(path)
    assert time.perf_counter() - start < 10
    error = info.value
    assert error.exit_code == 2
    assert error.file == str(path)
    assert str(path) in str(error)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("stem", ["chord_on_basic_chain", "chords_disconnect_tree"])
def test_structure_errors_are_input_errors(stem: str):
    # These files are a valid mechanism; only the labeling they ask for is impossible.
    with pytest.raises(symkin.InputError) as info:
        symkin.structure(symkin.load(BAD / f"{stem}.toml"))
    assert info.value.exit_code == 2
    assert "chord" in str(info.value)


def test_loads_names_the_given_file():
    text = (BAD / "unknown_key_link.toml").read_text()
    with pytest.raises(symkin.InputError, match=r"^mine\.toml:\d+: .*'mass'"):
        symkin.loads(text, "mine.toml")


@pytest.mark.parametrize("path", EXAMPLES, ids=lambda p: p.stem)
def test_example_checks(path: Path):
    result = run_cli("check", str(path))
    assert result.returncode == 0, result.stderr
    assert result.stderr == ""
    assert result.stdout.strip()


@pytest.mark.parametrize("path", EXAMPLES, ids=lambda p: p.stem)
def test_example_matrices_json(path: Path):
    result = run_cli("matrices", "--json", str(path))
    assert result.returncode == 0, result.stderr
    data = json.loads(result.stdout)
    assert set(data) == {"links", "hinges", "i_plus", "i_minus", "incidence", "loops", "paths"}
    n, m = len(data["links"]) - 1, len(data["hinges"])
    assert len(data["i_plus"]) == len(data["i_minus"]) == m
    assert [len(row) for row in data["incidence"]] == [m] * (n + 1)
    assert [len(row) for row in data["loops"]] == [m] * (m - n)
    assert [len(row) for row in data["paths"]] == [n] * m


FOUR_BAR = (ROOT / "examples" / "four_bar.toml").read_text()


def four_bar_with(parameters: str) -> str:
    """The four-bar example with extra [parameters] lines."""
    assert "l = 1e-3" in FOUR_BAR
    return FOUR_BAR.replace("l = 1e-3", "l = 1e-3\n" + parameters, 1)


@pytest.mark.parametrize(
    "parameters, culprit",
    [
        ('q = "((((9**64)**64)**64)**64)**64"', "'q'"),  # nesting around the exponent limit
        ('q = "exp(1000000000*log(9))"', "'q'"),  # sympy makes this 9**1000000000
        ('a = 9\nb = 1e9\nq = "(a**b + 1)/a**b"', "'q'"),  # an exponent from a parameter
        ('b = 1e9\nq = "exp(b*log(9))"', "'q'"),
        ('p1 = "9**64"\np2 = "p1**64"\np3 = "p2**64"\np4 = "p3**64"\np5 = "p4**64"', "'p"),
        ('q = "' + "*".join(["9**60"] * 250) + '"', "'q'"),  # a long product of big numbers
        ('q = "exp(exp(exp(10)))"', "'q'"),
    ],
)
def test_no_expression_can_build_a_huge_number(parameters: str, culprit: str):
    start = time.perf_counter()
    with pytest.raises(symkin.InputError) as info:
        symkin.loads(four_bar_with(parameters), "bomb.toml")
    assert time.perf_counter() - start < 5
    assert culprit in str(info.value)


def test_reasonable_powers_still_work():
    mech = symkin.loads(four_bar_with('n = 3\nq = "l**n + (2**10)**6 + sqrt(2)**64 + 9**64"'))
    assert mech.parameters[-1].value > 9**64


def test_long_expression_is_quoted_short():
    with pytest.raises(symkin.InputError) as info:
        symkin.loads(four_bar_with('q = "' + "1+" * 600 + 'open(1)"'), "long.toml")
    message = str(info.value)
    assert "long.toml" in message and "'q'" in message
    assert max(len(line) for line in message.splitlines()) < 400


def test_deeply_nested_toml_is_bad_input():
    text = FOUR_BAR + "\n[junk]\nx = " + "[" * 5000 + "]" * 5000 + "\n"
    with pytest.raises(symkin.InputError) as info:
        symkin.loads(text, "deep.toml")
    assert "deep.toml" in str(info.value)
