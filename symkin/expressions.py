"""Whitelist parser for the expression strings of a mechanism file (CONTRACT §1).

The text is parsed with :func:`ast.parse` (parsing only, nothing is executed) and the syntax tree is
walked node by node: numbers, the names the caller allows, + - * / **, unary minus and calls of the
listed functions become sympy objects; any other node is rejected. Decimal literals become exact
rationals, so a high-precision evaluation sees exactly the geometry the user wrote.
"""

from __future__ import annotations

import ast
import math
import re
from collections.abc import Mapping

import sympy as sp

from .errors import suggest

#: Functions an expression may call, by name, with their number of arguments.
FUNCTIONS: dict[str, tuple[object, int]] = {
    "sin": (sp.sin, 1), "cos": (sp.cos, 1), "tan": (sp.tan, 1),
    "asin": (sp.asin, 1), "acos": (sp.acos, 1), "atan": (sp.atan, 1),
    "atan2": (sp.atan2, 2), "sqrt": (sp.sqrt, 1), "exp": (sp.exp, 1), "log": (sp.log, 1),
}
#: Constants every expression may use.
CONSTANTS: dict[str, sp.Expr] = {"pi": sp.pi, "deg": sp.pi / 180}
#: Names that parameters may not take, because expressions give them a meaning already.
RESERVED = frozenset(FUNCTIONS) | frozenset(CONSTANTS)

IDENTIFIER = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")
MAX_LENGTH = 2000      # characters in one expression
MAX_EXPONENT = 64      # |literal exponent| allowed in a**b, so no expression can blow up memory

_BINARY = {ast.Add: sp.Add, ast.Sub: None, ast.Mult: sp.Mul, ast.Div: None, ast.Pow: None}


class ExpressionError(ValueError):
    """An expression string that is not allowed; the message says what to change."""


def number(value: int | float) -> sp.Expr:
    """Exact sympy number for a TOML/Python number: floats by their shortest decimal repr."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ExpressionError(f"expected a number, got {type(value).__name__} {value!r}")
    if isinstance(value, int):
        return sp.Integer(value)
    if not math.isfinite(value):
        raise ExpressionError(f"{value!r} is not a finite number")
    return sp.Rational(repr(value))


def parse(text: str, names: Mapping[str, sp.Expr]) -> sp.Expr:
    """Parse `text` into a sympy expression; `names` maps the allowed variable names to symbols."""
    if not isinstance(text, str):
        raise ExpressionError(f"expected an expression string, got {text!r}")
    if len(text) > MAX_LENGTH:
        raise ExpressionError(f"expression is longer than {MAX_LENGTH} characters")
    if not text.strip():
        raise ExpressionError("expression is empty")
    try:
        tree = ast.parse(text.strip(), mode="eval")
    except (SyntaxError, ValueError, RecursionError, MemoryError) as exc:
        detail = getattr(exc, "msg", None) or type(exc).__name__
        raise ExpressionError(f"'{text}' is not a valid expression ({detail})") from None
    try:
        return _Converter(text, names).visit(tree.body)
    except RecursionError:
        raise ExpressionError(f"'{text}' is nested too deeply") from None


class _Converter:
    """Turns an allowed syntax tree into sympy; raises ExpressionError on anything else."""

    def __init__(self, text: str, names: Mapping[str, sp.Expr]) -> None:
        self.text = text
        self.names = names

    def reject(self, what: str, hint: str = "") -> ExpressionError:
        allowed = ("numbers, parameter names, pi, deg, + - * / **, and calls of "
                   + ", ".join(FUNCTIONS))
        return ExpressionError(f"'{self.text}': {what} is not allowed" + (f"; {hint}" if hint
                               else f" (allowed: {allowed})"))

    def visit(self, node: ast.AST) -> sp.Expr:
        if isinstance(node, ast.Constant):
            if isinstance(node.value, bool) or not isinstance(node.value, (int, float)):
                raise self.reject(f"the literal {node.value!r}")
            try:
                return number(node.value)
            except ExpressionError as exc:
                raise self.reject(str(exc)) from None
        if isinstance(node, ast.Name):
            if node.id in self.names:
                return self.names[node.id]
            if node.id in CONSTANTS:
                return CONSTANTS[node.id]
            if node.id in FUNCTIONS:
                raise self.reject(f"the function name '{node.id}' without a call")
            hint = suggest(node.id, [*self.names, *CONSTANTS])
            raise ExpressionError(f"'{self.text}': unknown name '{node.id}'"
                                  + (f"; {hint}" if hint else
                                     "; define it in [parameters] before it is used"))
        if isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.USub, ast.UAdd)):
            operand = self.visit(node.operand)
            return -operand if isinstance(node.op, ast.USub) else operand
        if isinstance(node, ast.BinOp) and type(node.op) in _BINARY:
            return self.binary(node)
        if isinstance(node, ast.Call):
            return self.call(node)
        if isinstance(node, ast.Attribute):
            raise self.reject("attribute access ('.')")
        if isinstance(node, ast.Lambda):
            raise self.reject("a lambda")
        return self.reject_node(node)

    def reject_node(self, node: ast.AST) -> sp.Expr:
        raise self.reject(f"syntax of kind '{type(node).__name__}'")

    def binary(self, node: ast.BinOp) -> sp.Expr:
        left = self.visit(node.left)
        if isinstance(node.op, ast.Pow):
            # A power whose exponent holds another power, or a literal exponent beyond
            # MAX_EXPONENT, could make sympy build an astronomically large number.
            if any(isinstance(n, ast.BinOp) and isinstance(n.op, ast.Pow)
                   for n in ast.walk(node.right)):
                raise self.reject("a power in an exponent", "write the exponent out")
            right = self.visit(node.right)
            if right.is_number and abs(right) > MAX_EXPONENT:
                raise self.reject(f"an exponent of magnitude above {MAX_EXPONENT}",
                                  "use exp() and log() instead")
            return sp.Pow(left, right)
        right = self.visit(node.right)
        if isinstance(node.op, ast.Add):
            return left + right
        if isinstance(node.op, ast.Sub):
            return left - right
        if isinstance(node.op, ast.Mult):
            return left * right
        if right.is_zero:
            raise self.reject("division by zero", "change the divisor")
        return left / right

    def call(self, node: ast.Call) -> sp.Expr:
        if not isinstance(node.func, ast.Name):
            if isinstance(node.func, ast.Attribute):
                raise self.reject("attribute access ('.')")
            raise self.reject("calling anything but a listed function by name")
        name = node.func.id
        if name not in FUNCTIONS:
            hint = suggest(name, FUNCTIONS)
            raise self.reject(f"calling '{name}'",
                              (hint + "; " if hint else "") + "allowed functions: "
                              + ", ".join(FUNCTIONS))
        if node.keywords or any(isinstance(a, ast.Starred) for a in node.args):
            raise self.reject(f"keyword or starred arguments to '{name}'")
        func, arity = FUNCTIONS[name]
        if len(node.args) != arity:
            raise self.reject(f"calling '{name}' with {len(node.args)} argument(s)",
                              f"'{name}' takes {arity}")
        return func(*(self.visit(a) for a in node.args))
