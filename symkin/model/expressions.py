"""Whitelist parser for the expression strings of a mechanism file (docs/file-format.md).

The text is parsed with :func:`ast.parse` (parsing only, nothing is executed) and the syntax tree is
walked node by node: numbers, the names the caller allows, + - * / **, unary minus and calls of the
listed functions become sympy objects; any other node is rejected. Decimal literals become exact
rationals, so a high-precision evaluation sees exactly the geometry the user wrote.
"""

from __future__ import annotations

import ast
import math
import re
from collections.abc import Callable, Mapping
from typing import TYPE_CHECKING

import sympy as sp

if TYPE_CHECKING:
    import mpmath

from ..core.errors import suggest

#: Functions an expression may call, by name, with their number of arguments.
FUNCTIONS: dict[str, tuple[Callable[..., sp.Expr], int]] = {
    "sin": (sp.sin, 1),
    "cos": (sp.cos, 1),
    "tan": (sp.tan, 1),
    "asin": (sp.asin, 1),
    "acos": (sp.acos, 1),
    "atan": (sp.atan, 1),
    "atan2": (sp.atan2, 2),
    "sqrt": (sp.sqrt, 1),
    "exp": (sp.exp, 1),
    "log": (sp.log, 1),
}
#: Constants every expression may use.
CONSTANTS: dict[str, sp.Expr] = {"pi": sp.pi, "deg": sp.pi / 180}
#: Names that parameters may not take, because expressions give them a meaning already.
RESERVED = frozenset(FUNCTIONS) | frozenset(CONSTANTS)

IDENTIFIER = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")
MAX_LENGTH = 2000  # characters in one expression
MAX_EXPONENT = 64  # |exponent| allowed in a**b, so no expression can blow up memory
MAX_BITS = 4096  # |log2| of any exact number an expression may build (10**+-1233)
SHOWN = 60  # characters of an expression quoted in an error message

_BINARY = {ast.Add: sp.Add, ast.Sub: None, ast.Mult: sp.Mul, ast.Div: None, ast.Pow: None}


# sympy ships no type information, so mypy sees sp.Symbol as Any.
class ParameterSymbol(sp.Symbol):  # type: ignore[misc]
    """The symbol of a file's parameter: a class of its own, so a parameter named like one of
    symkin's internal symbols (theta, theta_1, delta_2, dyad1_reach, _tmp0, p_0, ...) is never
    equal to it. It prints as its name; code printers see it only renamed (p_k) or dummified."""

    def __new__(cls, name: str, **assumptions: bool) -> ParameterSymbol:
        assumptions.setdefault("real", True)
        symbol: ParameterSymbol = super().__new__(cls, name, **assumptions)
        return symbol


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


def _shown(text: str) -> str:
    """`text` as quoted in an error message: long expressions are cut short."""
    text = text.strip()
    return text if len(text) <= SHOWN else text[: SHOWN - 3] + "..."


def parse(
    text: str, names: Mapping[str, sp.Expr], values: Mapping[sp.Symbol, sp.Expr] | None = None
) -> sp.Expr:
    """Parse `text` into a sympy expression; `names` maps the allowed variable names to symbols.

    `values` (symbol -> default value) lets the size limits on powers and exp() see the values of
    parameters too, so that substituting the defaults can never build an astronomically large
    number either.
    """
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
        raise ExpressionError(f"'{_shown(text)}' is not a valid expression ({detail})") from None
    try:
        return _Converter(text, names, values or {}).visit(tree.body)
    except RecursionError:
        raise ExpressionError(f"'{_shown(text)}' is nested too deeply") from None


class _Converter:
    """Turns an allowed syntax tree into sympy; raises ExpressionError on anything else."""

    def __init__(
        self, text: str, names: Mapping[str, sp.Expr], values: Mapping[sp.Symbol, sp.Expr]
    ) -> None:
        self.text = _shown(text)
        self.names = names
        self.values = values

    def approx(self, expr: sp.Expr) -> sp.Expr | None:
        """A floating value of `expr` (parameters at their defaults), or None if it has none."""
        if expr.free_symbols - set(self.values):
            return None
        value = expr.evalf(15, subs=dict(self.values)) if expr.free_symbols else expr.evalf(15)
        return value if value.is_number and value.is_finite else None

    def sized(self, expr: sp.Expr) -> sp.Expr:
        """Reject an exact number with more than MAX_BITS bits (a product of huge literals)."""
        for atom in expr.atoms(sp.Rational):
            if max(abs(atom.p).bit_length(), atom.q.bit_length()) > MAX_BITS:
                raise self.reject(
                    f"a number beyond 2**(+-{MAX_BITS})", "use smaller numbers, or exp() and log()"
                )
        return expr

    def reject(self, what: str, hint: str = "") -> ExpressionError:
        allowed = "numbers, parameter names, pi, deg, + - * / **, and calls of " + ", ".join(
            FUNCTIONS
        )
        return ExpressionError(
            f"'{self.text}': {what} is not allowed"
            + (f"; {hint}" if hint else f" (allowed: {allowed})")
        )

    def visit(self, node: ast.AST) -> sp.Expr:
        if isinstance(node, ast.Constant):
            if isinstance(node.value, bool) or not isinstance(node.value, (int, float)):
                raise self.reject(f"the literal {node.value!r}")
            try:
                return number(node.value)
            except ExpressionError as exc:
                raise ExpressionError(f"'{self.text}': {exc}") from None
        if isinstance(node, ast.Name):
            if node.id in self.names:
                return self.names[node.id]
            if node.id in CONSTANTS:
                return CONSTANTS[node.id]
            if node.id in FUNCTIONS:
                raise self.reject(f"the function name '{node.id}' without a call")
            hint = suggest(node.id, [*self.names, *CONSTANTS])
            raise ExpressionError(
                f"'{self.text}': unknown name '{node.id}'"
                + (f"; {hint}" if hint else "; define it in [parameters] before it is used")
            )
        if isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.USub, ast.UAdd)):
            operand = self.visit(node.operand)
            return -operand if isinstance(node.op, ast.USub) else operand
        if isinstance(node, ast.BinOp) and type(node.op) in _BINARY:
            return self.sized(self.binary(node))
        if isinstance(node, ast.Call):
            return self.sized(self.call(node))
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
            if any(
                isinstance(n, ast.BinOp) and isinstance(n.op, ast.Pow) for n in ast.walk(node.right)
            ):
                raise self.reject("a power in an exponent", "write the exponent out")
            right = self.visit(node.right)
            # The exponent's value (parameters at their defaults) is bounded, and so is the size
            # of the power when its base has a value too: checked before sympy builds it, since
            # sympy evaluates powers of exact numbers at once, e.g. (9**64)**64.
            exponent = self.approx(right)
            if exponent is not None and abs(exponent) > MAX_EXPONENT:
                raise self.reject(
                    f"an exponent of magnitude above {MAX_EXPONENT}", "use exp() and log() instead"
                )
            base = self.approx(left)
            if exponent is not None and base is not None and not base.is_zero:
                bits = abs(sp.re(exponent)) * abs(sp.log(abs(base), 2))
                if bits > MAX_BITS:
                    raise self.reject(
                        f"a power beyond 2**(+-{MAX_BITS})",
                        "use exp() and log(), or smaller numbers",
                    )
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
            raise self.reject(
                f"calling '{name}'",
                (hint + "; " if hint else "") + "allowed functions: " + ", ".join(FUNCTIONS),
            )
        if node.keywords or any(isinstance(a, ast.Starred) for a in node.args):
            raise self.reject(f"keyword or starred arguments to '{name}'")
        func, arity = FUNCTIONS[name]
        if len(node.args) != arity:
            raise self.reject(
                f"calling '{name}' with {len(node.args)} argument(s)", f"'{name}' takes {arity}"
            )
        args = [self.visit(a) for a in node.args]
        if name in ("log", "sqrt", "asin", "acos"):
            # checked numerically before sympy sees it: sympy's complex logarithms of nested
            # negative arguments take unbounded time
            try:
                x = numeric(args[0], self.values, 30)
            except NoValue:
                x = None
            except NotReal:
                raise self.reject(
                    "an argument that leaves the real numbers", "every value must stay real"
                ) from None
            if x is not None and (
                (name == "log" and x <= 0)
                or (name == "sqrt" and x < 0)
                or (name in ("asin", "acos") and abs(x) > 1)
            ):
                raise self.reject(
                    f"{name}() of {float(x):.6g}, which leaves the real numbers",
                    "every value must stay real",
                )
        if name == "exp":
            # sympy turns exp(k*log(b)) into b**k at once: bound the argument like a power.
            value = self.approx(args[0])
            if value is not None and abs(sp.re(value)) > MAX_BITS * math.log(2):
                raise self.reject(
                    f"exp() of an argument beyond {MAX_BITS}*log(2)",
                    "the value would not fit any number format",
                )
        return func(*args)


# -- numeric values, bounded work ------------------------------------------------------------------

#: Largest magnitude a value may have: it must fit a float64 (the generated code's numbers).
FLOAT64_MAX = 1.7976931348623157e308
NUMERIC_DPS = 60  # digits of the numeric evaluation of file values


class NotReal(ValueError):
    """An expression whose value leaves the real numbers (or is undefined) at some step."""


class NoValue(NotReal):
    """A symbol without a value (the expression cannot be evaluated yet)."""


_MPMATH = {
    sp.sin: "sin",
    sp.cos: "cos",
    sp.tan: "tan",
    sp.asin: "asin",
    sp.acos: "acos",
    sp.atan: "atan",
    sp.exp: "exp",
    sp.log: "log",
}


def substitute(expr: object, values: Mapping[sp.Symbol, object]) -> sp.Expr:
    """`expr` with the parameter `values` put in, as `subs(values)` gives it, passing subs only
    the symbols `expr` holds: subs walks the expression once per entry, and a file may have
    hundreds of parameters."""
    e = sp.sympify(expr)
    return e.subs({s: values[s] for s in e.free_symbols if s in values})


def numeric(
    expr: sp.Expr, values: Mapping[sp.Symbol, object], dps: int = NUMERIC_DPS
) -> mpmath.mpf:
    """The value of `expr` (symbols from `values`) as a real mpmath number at `dps` digits,
    computed node by node in bounded time (never sympy's exact or complex arithmetic); NotReal
    when any step leaves the reals (log of a negative, sqrt of a negative, asin(2), 0/0)."""
    import mpmath

    def real(x: mpmath.mpf | mpmath.mpc) -> mpmath.mpf:
        if isinstance(x, mpmath.mpc) or not mpmath.isfinite(x):
            raise NotReal(f"{x}")
        return x

    def walk(e: sp.Expr) -> mpmath.mpf:
        if e.is_Symbol:
            if e not in values:
                raise NoValue(f"no value for {e}")
            v = values[e]
            return real(v) if isinstance(v, mpmath.mpf) else walk(sp.sympify(v))
        if e.is_Rational:
            return mpmath.mpf(e.p) / e.q
        if e.is_Float:
            return mpmath.mpf(e)
        if e is sp.pi:
            return +mpmath.pi
        if e is sp.E:
            return +mpmath.e
        if e.is_Add:
            return real(mpmath.fsum(walk(a) for a in e.args))
        if e.is_Mul:
            out = mpmath.mpf(1)
            for a in e.args:
                out = real(out * walk(a))
            return out
        if e.is_Pow:
            base, exponent = walk(e.base), walk(e.exp)
            if base == 0 and exponent < 0:
                raise NotReal("division by zero")
            if base < 0 and exponent != int(exponent):
                raise NotReal("a fractional power of a negative number")
            return real(mpmath.power(base, exponent))
        if isinstance(e, sp.Abs):  # sympy's own: sqrt(x**2) of a real symbol is Abs(x)
            return abs(walk(e.args[0]))
        if isinstance(e, sp.atan2):
            y, x = walk(e.args[0]), walk(e.args[1])
            return real(mpmath.atan2(y, x))
        name = _MPMATH.get(e.func)
        if name is not None:
            x = walk(e.args[0])
            if (name == "log" and x <= 0) or (name in ("asin", "acos") and abs(x) > 1):
                raise NotReal(f"{name} of {mpmath.nstr(x, 6)}")
            return real(getattr(mpmath, name)(x))
        raise NotReal(f"cannot evaluate {type(e).__name__}")

    with mpmath.workdps(dps):
        try:
            return walk(sp.sympify(expr))
        except (ZeroDivisionError, OverflowError, ValueError) as exc:
            if isinstance(exc, NotReal):
                raise
            raise NotReal(str(exc)) from None
