"""The file's parameter names live in a namespace of their own (docs/file-format.md, [parameters]).

A property test over names drawn from every internal prefix: the names are harvested from what
symkin itself builds for the mechanism (the symbols of the derivation, the CSE temporaries, the
renamed parameters, every identifier of the generated numpy module and C source), so a name
symkin starts to use later is covered without editing this file. A mechanism that calls its
parameters by those names — some used in the plate lengths, angles and coordinates, the others
unused — must give the independent solver's deviation in every backend.
"""

from __future__ import annotations

import ast
import keyword
import random
import re

import mechanisms as M
import pytest
from conftest import EXAMPLES
from evaluators import BACKENDS, KINEMATIC, Generated, generated, rel_err, require
from reference_solver import Reference

import symkin
from symkin.codegen import pipeline
from symkin.model import expressions
from symkin.model.hinges import PLATE_LENGTH, THETA
from symkin.studies import derive
from symkin.studies.evaluation import evaluate

IDENTIFIER = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")


def internal_names(key: str) -> set[str]:
    """Every name symkin gives a symbol or an identifier while deriving mechanism `key`."""
    g = generated(key)
    an = g.analysis
    exprs = [
        *an.residual,
        *an.jacobian,
        *an.linear_system[0],
        *an.linear_system[1],
        *an.rigid_residual,
    ]
    names = {THETA.name, PLATE_LENGTH.name}
    for symbol, expr in an.rigid.assignments:
        names.add(symbol.name)
        exprs.append(expr)
    for p in an.points:
        exprs += [*an.point_rigid(p.name)]
        for level in ("paper", "first_order", "exact"):
            exprs += [*an.point_deviation(p.name, level)]
    names |= {s.name for e in exprs for s in e.free_symbols}
    (source,) = pipeline.emit(g.plan, "numpy", g.mech.path)
    for node in ast.walk(ast.parse(source)):
        for field in ("id", "name", "arg", "attr"):
            value = getattr(node, field, None)
            if isinstance(value, str):
                names.add(value)
    names |= set(IDENTIFIER.findall("\n".join(pipeline.emit(g.plan, "c", g.mech.path))))
    return names


def drawn(names: set[str], seed: int) -> list[str]:
    """Per prefix (a name without its trailing digits), up to three members and one new index:
    every internal prefix is represented, and so are indices symkin has not reached yet."""
    rng = random.Random(seed)
    families: dict[str, list[str]] = {}
    for n in sorted(names):
        families.setdefault(n.rstrip("0123456789"), []).append(n)
    out = set()
    for prefix, members in families.items():
        out.update(rng.sample(members, min(3, len(members))))
        if prefix != members[0] or len(members) > 1:
            out.add(f"{prefix}{rng.randint(0, 99)}")
    # parameter names the reader refuses anyway: built-in names, non-identifiers
    return sorted(n for n in out if IDENTIFIER.fullmatch(n) and n not in expressions.RESERVED)


def renamed(text: str, names: list[str], seed: int) -> str:
    """`text` (a mechanism with one parameter l = 1e-3 used as every plate length) with a
    parameter for every name: some used (the plate lengths are averages of them, the plate
    angles and one coordinate are scaled by ratios of them), the others unused."""
    rng = random.Random(seed)
    usable = [n for n in names if not keyword.iskeyword(n)]
    used = rng.sample(usable, min(24, len(usable)))
    lines = [f"{n} = 1e-3" if n in used else f"{n} = 0.37" for n in names]
    mean = "(" + " + ".join(used[:16]) + f")/{len(used[:16])}"
    ratio = f"({used[16]}/{used[17]})*({used[18]}*{used[19]})/({used[20]}*{used[21]})"
    assert re.search(r"^l = 1e-3\b", text, re.M) and 'length = "l"' in text
    text = re.sub(r"^l = 1e-3\b.*$", lambda m: "\n".join(lines), text, count=1, flags=re.M)
    text = text.replace('length = "l"', f'length = "{mean}"')
    # the plates' thickness (the stiffness data, when the file has it) follows their length
    text = text.replace('thickness = "l/10"', f'thickness = "({mean})/10"')
    # every plate angle and the first hinge's x coordinate scaled by a ratio that is 1
    text = re.sub(
        r'plate_angle = "([^"]*)"', lambda m: f'plate_angle = "({m.group(1)})*{ratio}"', text
    )
    text = re.sub(
        r"at = \[([-0-9.e]+), ", lambda m: f'at = ["{m.group(1)}*{ratio}", ', text, count=1
    )
    return text


CASES = {
    "four_bar": ((EXAMPLES / "four_bar.toml").read_text(), {"A0": "0.2"}),
    "triad": (M.TRIAD_SIX_BAR, {"O1": "0.1"}),
}


@pytest.mark.parametrize("key", sorted(CASES))
def test_parameters_named_like_internal_symbols(key):
    text, inputs = CASES[key]
    names = drawn(internal_names(key), seed=11)
    # the harvest reaches every kind of internal name
    for expected in ("theta", "theta_1", "delta_2", "_tmp0", "p_0"):
        assert any(n.rstrip("0123456789") == expected.rstrip("0123456789") for n in names), expected
    hostile = symkin.loads(renamed(text, names, seed=5), "hostile.toml")
    assert len(hostile.parameters) == len(names)
    want = Reference(symkin.loads(text)).deviation(inputs)
    # the plan `evaluate` builds for a kinematic level: without sensitivities (their ~900
    # columns) and without the physical levels (the reduced equilibrium's routines), most of
    # the derivation and not what this test is about
    g = Generated(mech=hostile, sensitivity=False, levels=list(KINEMATIC))
    an = g.analysis
    for backend in BACKENDS:
        require(backend)
        got = evaluate(an, inputs, "exact", backend=backend)
        for name, point in got.points.items():
            ref = want["points"][name]
            assert rel_err(point.deviation, ref["deviation"]) <= 1e-9, (backend, name)
            assert rel_err(point.rigid, ref["rigid"]) <= 1e-12, (backend, name)
        for hinge, angle in got.angles_compliant.items():
            assert abs(angle - float(want["angles"]["compliant"][hinge])) <= 1e-12
    # the report prints a parameter named like one of its own symbols (θ_a, δ_a, ...) as
    # literal text, never as that symbol. The names checked are the plate lengths', which the
    # report prints at every level; the kinematic levels spare the physical reference of a
    # stiff file (nine 40-digit `equilibrium` solves over ~900 parameters: minutes, not seconds).
    tex = derive.generate(hostile, ("latex",), levels=KINEMATIC)[f"{hostile.name}.tex"].decode()
    used = {s.name for h in hostile.hinges for s in h.length.free_symbols}
    for name in used:
        if re.fullmatch(r"(theta|delta)_\d+", name):
            # (an underscore may carry a line-break hint, \_\penalty0{})
            literal = re.escape(r"\text{\itshape ") + re.escape(name).replace(
                "_", r"\\_(?:\\penalty0\{\})?"
            )
            assert re.search(literal + r"\}", tex), name


def test_a_parameter_is_never_an_internal_symbol():
    p = expressions.ParameterSymbol("theta")
    assert p != THETA and p.name == THETA.name and str(p) == "theta"
    assert (
        expressions.ParameterSymbol("theta_1")
        != symkin.analyze(symkin.load(EXAMPLES / "four_bar.toml")).kin.theta[1]
    )
