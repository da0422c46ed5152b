"""symkin.model.precedence: sympy's own precedence values (the reference: sympy's function) for
special values and for every subexpression of a mechanism's loaded equations, and printers with
the mixin writing the same text as sympy's own."""

from __future__ import annotations

import functools
from pathlib import Path

import pytest
import sympy as sp
from sympy.printing.c import C99CodePrinter
from sympy.printing.numpy import NumPyPrinter
from sympy.printing.precedence import PRECEDENCE, precedence
from sympy.printing.pycode import MpmathPrinter, PythonCodePrinter

import symkin
from symkin.model.precedence import FastPrecedence, precedence_of
from symkin.physics import reduced
from symkin.studies.configuration import parameter_values

ROOT = Path(__file__).resolve().parents[1]
x, y = sp.symbols("x y", real=True)


class low(sp.Function):
    """A function printed below a product's precedence (sympy's precedence_Mul checks for one)."""

    precedence = PRECEDENCE["Add"]


SPECIAL = [
    sp.Float("nan"),
    sp.Float("inf"),
    sp.Float("-inf"),
    sp.Float("-0.0"),
    sp.Float(0.0),
    sp.Float(1.5),
    sp.Float(-1.5),
    sp.Float("-1e-300"),
    sp.Integer(-3),
    sp.Rational(-1, 2),
    sp.zoo * x,
    sp.oo * x,
    -sp.oo * x,
    -2 * x,
    2 * x,
    -x * y,
    sp.Rational(-1, 2) * x * y,
    sp.Float(-2.5) * x,
    sp.Float(2.5) * sp.sin(x),
    -sp.sqrt(2) * x,
    sp.sqrt(2) * x,
    sp.I * x,
    -sp.I * x,
    (1 + sp.I) * x,
    (-1 - sp.I) * x,
    sp.Mul(-1, x, low(y), evaluate=False),
    sp.Mul(x, low(y), evaluate=False),
    sp.Mul(-1, sp.Integer(0), x, evaluate=False),
    sp.Mul(sp.zoo, x, evaluate=False),
    sp.Mul(sp.nan, x, evaluate=False),
    x - y,
    -x + 2,
    x**-2,
    sp.cos(x) ** sp.Rational(1, 2),
]


def test_special_values_and_products():
    for item in SPECIAL:
        assert precedence_of(item) == precedence(item), sp.srepr(item)


@functools.cache
def _loaded_equations() -> tuple[sp.Expr, ...]:
    """The residuals, Jacobian pieces and reported quantities of the parallelogram's loaded
    level with two half plates per plate: large expressions, Floats of both signs everywhere."""
    mech = symkin.load(ROOT / "tests" / "mechanisms" / "parallelogram.toml")
    r = reduced.Reduced(symkin.analyze(mech).kin, parameter_values(mech), segments=2)
    s = r._s
    rows = r._rows(s)
    return (*rows, *sp.Matrix(rows).jacobian(list(r.x)[:2]), *r._reported(r._se))


def test_every_subexpression_of_a_mechanisms_equations():
    seen = 0
    for e in _loaded_equations():
        for item in sp.preorder_traversal(e):
            assert precedence_of(item) == precedence(item), item
            seen += 1
    assert seen > 10_000


class _Sympy:
    """sympy's own parenthesize and _print_Add, ahead of the mixin's."""

    parenthesize = sp.printing.str.StrPrinter.parenthesize
    _print_Add = sp.printing.str.StrPrinter._print_Add


@pytest.mark.parametrize("base", [MpmathPrinter, PythonCodePrinter, NumPyPrinter, C99CodePrinter])
def test_printers_write_what_sympys_write(base):
    settings = {"order": "none", "allow_unknown_functions": True}
    fast = type("Fast", (FastPrecedence, base), {})(settings)
    plain = type("Plain", (_Sympy, base), {})(settings)
    exprs = [*SPECIAL[5:], *_loaded_equations()[:40]]
    for e in exprs:
        if e.has(sp.nan, sp.zoo):
            continue  # not printable as code
        assert fast.doprint(e) == plain.doprint(e)
