"""The whitelist expression parser: what it accepts, what it rejects, and that nothing runs."""

from __future__ import annotations

import time

import pytest
import sympy as sp

from symkin.model.expressions import ExpressionError, number, parse

L = sp.Symbol("l", real=True)
NAMES = {"l": L}


@pytest.mark.parametrize(
    "text, expected",
    [
        ("2e-3", sp.Rational(1, 500)),
        ("0.1 + 0.2", sp.Rational(3, 10)),  # exact decimals: no 0.30000000000000004
        ("pi/2", sp.pi / 2),
        ("60*deg", sp.pi / 3),
        ("2*l", 2 * L),
        ("-l**2", -(L**2)),
        ("atan2(1, 1)", sp.pi / 4),
        ("sqrt(4) + exp(0) + log(1)", sp.Integer(3)),
        ("sin(0) + cos(0) + tan(0) + asin(0) + acos(1) + atan(0)", sp.Integer(1)),
    ],
)
def test_accepted_expressions(text, expected):
    assert sp.simplify(parse(text, NAMES) - expected) == 0


def test_numbers_are_exact():
    assert number(0.1) == sp.Rational(1, 10)
    assert number(3) == 3
    with pytest.raises(ExpressionError):
        number(float("inf"))
    with pytest.raises(ExpressionError):
        number(True)


@pytest.mark.parametrize(
    "text, fragment",
    [
        ("__import__('os').system('true')", "attribute access"),
        ("__import__('os')", "calling '__import__'"),
        ("pi.real", "attribute access"),
        ("().__class__", "attribute access"),
        ("(lambda: 1)()", "calling anything but a listed function"),
        ("lambda x: x", "lambda"),
        ("eval('1')", "calling 'eval'"),
        ("open('x')", "calling 'open'"),
        ("[1][0]", "Subscript"),
        ("'text'", "literal"),
        ("1 if l else 2", "IfExp"),
        ("l < 2", "Compare"),
        ("sin(x=1)", "keyword"),
        ("sin(1, 2)", "argument"),
        ("sin", "without a call"),
        ("L", "unknown name 'L'"),
        ("1/0", "division by zero"),
        ("2**100", "exponent"),
        ("9**9**9**9", "a power in an exponent"),
        ("", "empty"),
        ("1 +", "not a valid expression"),
        ("(" * 500 + "1" + ")" * 500, "nested"),
        ("1j", "literal"),
    ],
)
def test_rejected_expressions(text, fragment):
    with pytest.raises(ExpressionError) as info:
        parse(text, NAMES)
    assert fragment.lower() in str(info.value).lower()


def test_power_bomb_is_rejected_fast():
    start = time.perf_counter()
    with pytest.raises(ExpressionError):
        parse("9**9**9**9", NAMES)
    with pytest.raises(ExpressionError):
        parse("(9**9)**(9**9)", NAMES)
    assert time.perf_counter() - start < 1.0


def test_unknown_name_suggests_the_near_one():
    with pytest.raises(ExpressionError, match="did you mean 'l'"):
        parse("2*ll", NAMES)
