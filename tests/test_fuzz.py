"""A seeded, bounded fuzz harness (issue 11): mutants of the example mechanisms through `check`
(and, for a sample of the valid ones, `eval` in every backend) must never exit 1 (a bug), only 0,
2 (bad input, with a fix line) or 3 (no assembly). Run with SYMKIN_FUZZ=N for N mutants (default
200, about two minutes).
"""

from __future__ import annotations

import collections
import json
import os
import random
import re
import sys

import pytest
from conftest import EXAMPLES, ROOT
from evaluators import BACKENDS

from symkin import load
from symkin.cli.commands import main

sys.path.insert(0, str(ROOT / "benchmarks"))
import families

MUTANTS = int(os.environ.get("SYMKIN_FUZZ", "200"))
EVALUATED = 12  # valid mutants also evaluated, every backend

NUMBERS = [
    "0",
    "-1",
    "0.0",
    "1e-320",
    "1e308",
    "1e309",
    "-1e309",
    "1" * 4400,
    "2.5e-3",
    '"nan"',
    '"inf"',
    '"1/0"',
    '"log(-1)"',
    '"exp(800)"',
    '"sqrt(-2)"',
    '"asin(2)"',
    '"l**64"',
    '"l**l**l"',
    '"theta"',
    '"theta_1"',
    '"delta_2"',
    '"__import__(1)"',
    '"x.y"',
    '"pi*1e300*1e10"',
    "[]",
    "{}",
    "true",
    '""',
    '"0.001*(1+1e-15)"',
    '"log(log(log(2)))"',
    "123456789012345678901234567890",
]
STRINGS = [
    '"numpy"',
    '"class"',
    '"_x"',
    '"' + "a" * 300 + '"',
    '"cou\\u001b[2Jpler"',
    '"C\\u202e"',
    '""',
    "[1]",
    "{}",
    "3",
    '"frame"',
    '"prbm"',
    '"table"',
    '"expr"',
    '"elastica_force"',
    '"rigid"',
    '"small_deflection"',
    '"../x.csv"',
    '"/dev/zero"',
]
LINES = [
    "input = true",
    "input = false",
    'model = "prbm"\npreset = []',
    "mass = 1",
    'ground = "nowhere"',
    '[[link]]\nname = "extra"',
    "[parameters]\nl = 2",
    "theta = 1e-3",
    'plate_angle = "pi"',
    'length = "-l"',
    "chords = []",
    'model = "expr"\nf = "l"\ng = "theta"',
    'model = "table"\nfile = "/dev/zero"',
]


def mutate(text: str, rng: random.Random) -> str:
    lines = text.splitlines()
    for _ in range(rng.randint(1, 3)):
        kind = rng.randrange(6)
        i = rng.randrange(len(lines))
        line = lines[i]
        if kind == 0 and re.search(r"-?\d+(\.\d+)?(e-?\d+)?", line):
            hits = list(re.finditer(r"-?\d+(\.\d+)?(e-?\d+)?", line))
            m = rng.choice(hits)
            lines[i] = line[: m.start()] + rng.choice(NUMBERS) + line[m.end() :]
        elif kind == 1 and '"' in line and "=" in line:
            key = line.split("=", 1)[0]
            lines[i] = key + "= " + rng.choice(STRINGS)
        elif kind == 2:
            del lines[i]
        elif kind == 3:
            lines.insert(i, lines[rng.randrange(len(lines))])
        elif kind == 4:
            lines.insert(i, rng.choice(LINES))
        else:
            j = rng.randrange(len(lines))
            lines[i], lines[j] = lines[j], lines[i]
        if not lines:
            lines = ["format = 1"]
    return "\n".join(lines) + "\n"


COORDINATE = re.compile(r"-?\d+\.\d+(e-?\d+)?|-?\d+(?=[,\]])")


def cad_digits(text: str, rng: random.Random) -> str:
    """Every coordinate of `at = [x, y]` as CAD exports it: moved by up to 1e-7 of its size and
    written with 15-17 significant digits (the geometry that once broke generated code)."""

    def one(m: re.Match) -> str:
        x = float(m.group(0))
        x += (abs(x) or 1e-3) * rng.uniform(-1e-7, 1e-7)
        return f"{x:.{rng.randint(15, 17)}g}"

    return re.sub(
        r"^at = \[([^\]]*)\]",
        lambda m: "at = [" + COORDINATE.sub(one, m.group(1)) + "]",
        text,
        flags=re.M,
    )


def sources() -> list[str]:
    """The examples and small members of the scale families (benchmarks/families.py)."""
    return [p.read_text() for p in sorted(EXAMPLES.glob("*.toml"))] + [
        families.ladder(3),
        families.fan(2),
    ]


def run(capsys, args) -> tuple[int, str]:
    try:
        code = main(args)
    except SystemExit as exc:  # argparse
        code = exc.code
    _out, err = capsys.readouterr()
    return code, err


def test_fuzzed_mechanisms_never_crash(tmp_path, capsys):
    rng = random.Random(11)
    texts = sources()
    counts: collections.Counter = collections.Counter()
    bugs = []
    valid = []
    for k in range(MUTANTS):
        path = tmp_path / f"m{k}.toml"
        path.write_text(mutate(rng.choice(texts), rng))
        code, err = run(capsys, ["check", str(path)])
        counts[f"check exit {code}"] += 1
        if code == 2 and "fix:" not in err:
            bugs.append((path.read_text(), "exit 2 without a fix line: " + err))
        if code not in (0, 2, 3):
            bugs.append((path.read_text(), err))
        elif code == 0:
            valid.append(path)
    for path in rng.sample(valid, min(EVALUATED, len(valid))):
        text = path.read_text()
        for backend in BACKENDS:
            args = ["eval", str(path), "--backend", backend]
            for name in load(path).inputs:
                args += ["--input", f"{name}=0.1"]
            code, err = run(capsys, args)
            counts[f"eval exit {code}"] += 1
            if code not in (0, 2, 3):
                bugs.append((text, err))
    print(dict(sorted(counts.items())))
    assert counts["check exit 1"] == 0
    assert sum(v for k, v in counts.items() if k.startswith("check")) == MUTANTS
    assert counts["check exit 0"] and counts["check exit 2"], counts
    assert not bugs, (
        f"{len(bugs)} mutants exit 1 or lack a fix line, e.g.\n{bugs[0][1]}\n---\n{bugs[0][0]}"
    )


def test_cad_digit_geometry_evaluates_in_every_backend(tmp_path, capsys):
    """Valid mutants with many-digit coordinates (one per source family) evaluate with exit 0
    in every backend, and the backends agree."""
    rng = random.Random(7)
    texts = sources()
    for k, text in enumerate([texts[0], texts[-2], texts[-1]]):
        path = tmp_path / f"cad{k}.toml"
        path.write_text(cad_digits(text, rng))
        assert re.search(r"\d\.\d{14}", path.read_text())
        assert run(capsys, ["check", str(path)])[0] == 0
        norms = []
        for backend in BACKENDS:
            args = ["eval", str(path), "--backend", backend, "--json"]
            for name in load(path).inputs:
                args += ["--input", f"{name}=0.1"]
            try:
                code = main(args)
            except SystemExit as exc:
                code = exc.code
            out, err = capsys.readouterr()
            assert code == 0, (backend, err)
            norms.append(json.loads(out)["points"])
        for got in norms[1:]:
            for name, point in got.items():
                want = norms[0][name]["norm"]
                assert abs(point["norm"] - want) <= 1e-9 * abs(want), name


@pytest.fixture(autouse=True)
def _private_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("SYMKIN_CACHE", str(tmp_path / "cache"))
