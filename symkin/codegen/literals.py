"""Numbers as generated code must see them: correctly rounded float64 literals.

The derivation keeps exact arithmetic (a coordinate of 0.0851234567 m is the rational
851234567/10^10, and the dyad formulas hold square roots of huge integers built from such
rationals), which is what the 40-digit mpmath evaluation wants. A C or numpy printer would print
those integers as they are (`integer constant is too large` in C, object arrays in numpy), so
every numeric subexpression is folded here, once, into the double nearest to its exact value
(evaluated with 40 digits, then rounded), and the printers write each double as the shortest
decimal that reads back to it (`repr`).

Small integers stay integers (exponents, signs, `2*x`), and rational exponents stay exact, so
`x**(1/2)` still prints as `sqrt(x)`.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import sympy as sp

from ..core.errors import InputError
from ..model.special import axial

#: Integers up to this magnitude are exact in a double and stay integers.
EXACT_INT = 2**53
#: Digits of the evaluation that is rounded to a double (far beyond double's 17).
DIGITS = 40


def to_double(value: sp.Expr | float | int) -> float:
    """The double nearest to a real numeric expression (evaluated with DIGITS digits first)."""
    number = sp.N(sp.sympify(value), DIGITS)
    if not (number.is_real and number.is_finite):
        raise InputError(
            f"the constant {sp.sstr(value)[:60]} evaluates to {number}, which no float64 can hold",
            hint="keep parameters and geometry within float64 range (|x| < 1.8e308)",
        )
    result = float(number)
    if not math.isfinite(result):
        raise InputError(
            f"the constant {sp.sstr(value)[:60]} = {sp.N(number, 6)} overflows float64",
            hint="keep parameters and geometry within float64 range (|x| < 1.8e308)",
        )
    return result


def _double(value: sp.Expr) -> sp.Float:
    return sp.Float(to_double(value), 17) if to_double(value) != 0 else sp.Integer(0)


def _simple(e: sp.Expr) -> bool:
    """A number the printers already write exactly: a small integer."""
    return e.is_Integer and abs(int(e)) < EXACT_INT


def float_literals(expr: sp.Expr, memo: dict | None = None) -> sp.Expr:
    """`expr` with every numeric subexpression replaced by its correctly rounded double.

    The numeric factors of a product (and terms of a sum) are folded together, so the product of
    two constants is rounded once, not twice. Pass one `memo` dict to many calls over
    expressions that share subtrees (a plan's routines) so each subtree is folded once."""
    return fold_numbers(expr, _simple, _double, memo)


def fold_numbers(
    expr: sp.Expr,
    keep: Callable[[sp.Expr], bool],
    replace: Callable[[sp.Expr], sp.Expr],
    memo: dict | None = None,
) -> sp.Expr:
    """`expr` with every maximal numeric subexpression that `keep` rejects replaced by
    `replace(it)`; the numeric factors of a product and terms of a sum are taken together, and
    small rational exponents stay exact (so x**(1/2) still prints as a square root).

    `memo` (optional, shared between calls with the same keep/replace) caches folded subtrees and
    which subtrees are constant, so the work is linear in the size of the expression DAG."""
    expr = sp.sympify(expr)
    if not isinstance(expr, sp.Basic) or (expr.is_Atom and not expr.is_number):
        return expr
    memo = {} if memo is None else memo
    mapping = memo.setdefault("folded", {})
    constant = memo.setdefault("constant", {})

    def const(e: sp.Basic) -> bool:
        """No free symbols (computed once per subtree; sympy does not cache free_symbols)."""
        known = constant.get(e)
        if known is None:
            known = not e.free_symbols if e.is_Atom else all(const(a) for a in e.args)
            constant[e] = known
        return known

    def fold(e: sp.Expr) -> sp.Expr:
        new = mapping.get(e)
        if new is None:
            new = mapping[e] = _fold(e)
        return new

    def _fold(e: sp.Expr) -> sp.Expr:
        if const(e) and e.is_number:
            return e if keep(e) else replace(e)
        if e.is_Atom:
            return e
        if e.is_Pow:
            base, exp = e.args
            new_exp = exp if exp.is_Rational and _simple_rational(exp) else fold(exp)
            return sp.Pow(fold(base), new_exp)
        if e.is_Mul or e.is_Add:
            numeric = [a for a in e.args if const(a)]
            rest = [fold(a) for a in e.args if not const(a)]
            if numeric:
                number = e.func(*numeric)
                if not keep(number):
                    number = replace(number)
                rest.append(number)
            return e.func(*rest)
        args = [fold(a) for a in e.args]
        return e.func(*args) if args != list(e.args) else e

    return fold(expr)


def _simple_rational(q: sp.Rational) -> bool:
    return abs(q.p) < EXACT_INT and q.q < EXACT_INT


def literal(value: float) -> str:
    """A C and Python literal that reads back as exactly `value` (the shortest round-trip
    decimal, with a '.0' where repr would print an integer)."""
    text = repr(float(value))
    if text in ("inf", "-inf", "nan"):
        raise ValueError(f"non-finite constant {text}")
    if "." not in text and "e" not in text:
        text += ".0"
    return text


def horner(coeffs: list[float], var: str) -> str:
    """Source text of sum coeffs[k] var^k in Horner form (valid Python and C)."""
    text = literal(coeffs[-1])
    for c in reversed(coeffs[:-1]):
        text = f"{literal(c)} + {var} * ({text})"
    return text


def recurrence(constants, var: str) -> list[str]:
    """The steps b <- (b - a_j)/var of a kernel's float recurrence (docs/numerics.md), one per
    constant a_j, as statements valid in Python and C (without the C semicolon)."""
    out = []
    for a in (float(a) for a in constants):
        if a == 0:
            out.append(f"b = b / {var}")
        elif a > 0:
            out.append(f"b = (b - {literal(a)}) / {var}")
        else:
            out.append(f"b = (b + {literal(-a)}) / {var}")
    return out


def _sparse_horner(coeffs: list[float], var: str) -> str:
    """Horner text of sum coeffs[k] var^k that skips the zero coefficients."""
    coeffs = list(coeffs)
    while len(coeffs) > 1 and coeffs[-1] == 0:
        coeffs.pop()
    text = literal(coeffs[-1])
    for c in reversed(coeffs[:-1]):
        text = f"{var} * ({text})" if c == 0 else f"{literal(c)} + {var} * ({text})"
    return text


def horner2(rows: list[list[float]], outer: str, inner: str) -> str:
    """Source text of sum_i outer^i sum_j rows[i][j] inner^j, nested Horner in both variables
    that skips zero coefficients (valid Python and C)."""
    parts = [_sparse_horner(row, inner) for row in rows]
    while len(parts) > 1 and parts[-1] == "0.0":
        parts.pop()
    text = parts[-1]
    for part in reversed(parts[:-1]):
        text = f"{outer} * ({text})" if part == "0.0" else f"({part}) + {outer} * ({text})"
    return text


def estrin(
    coeffs: list[float], var: str, name: Callable[[int], str] | None = None
) -> tuple[str, int]:
    """Source text of sum coeffs[k] var^k in Estrin's form (valid Python and C): halves joined by
    the powers var^2, var^4, ... (a short dependency chain, where Horner's is as long as the
    polynomial), var^k named name(k) (default: var followed by k), and the highest such power
    it uses (1: none)."""
    if len(coeffs) == 1:
        return literal(coeffs[0]), 1
    if len(coeffs) == 2:
        return f"{literal(coeffs[0])} + {var} * {literal(coeffs[1])}", 1
    half = 1 << (len(coeffs) - 1).bit_length() - 1
    low, _ = estrin(coeffs[:half], var, name)
    high, top = estrin(coeffs[half:], var, name)
    power = var if half == 1 else (name(half) if name else f"{var}{half}")
    return f"({low}) + ({high}) * {power}", max(top, half)


def estrin_powers(
    top: int, var: str, name: Callable[[int], str] | None = None
) -> list[tuple[str, str]]:
    """The (name, value) pairs of the powers var^2 .. var^top an Estrin text uses, in order, as
    C and Python text."""
    names = name or (lambda k: f"{var}{k}")
    out, power = [], 2
    while power <= top:
        half = var if power == 2 else names(power // 2)
        out.append((names(power), f"{half} * {half}"))
        power *= 2
    return out


def x_power(k: int) -> str:
    """The name of (x^2)^k in the kernels' Estrin form: x4, x8, ..."""
    return f"x{2 * k}"


def near_text(form: axial.NearForm, var: str = "p") -> str:
    """A kernel's near form p^j P(d) r^m s^n as C and Python text in `var`, d = var -
    NEAR_CENTRE, r = 1/(var + pi^2), s = 1/(var + 4 pi^2) and d's powers (near_names defines
    them)."""
    m, n = form.poles
    factors = [var] * form.zero + ["r"] * m + ["s"] * n
    text = f"({estrin(list(form.coeffs), 'd')[0]})"
    return f"{text} * ({' * '.join(factors)})" if factors else text


def near_names(form: axial.NearForm | None = None, var: str = "p") -> list[tuple[str, str]]:
    """The (name, value) pairs near_text uses, as C and Python text, in order (all of them
    without a `form`: d^2 .. d^8, r and s)."""
    top = estrin(list(form.coeffs), "d")[1] if form else 8
    out = [("d", f"{var} - {literal(axial.NEAR_CENTRE)}"), *estrin_powers(top, "d")]
    if form is None or form.poles[0]:
        out.append(("r", f"1.0 / ({var} + {literal(axial.PI2)})"))
    if form is None or form.poles[1]:
        out.append(("s", f"1.0 / ({var} + {literal(axial.FOUR_PI2)})"))
    return out


def far_text(form: axial.FarForm) -> str:
    """A kernel's far form (S_n (1 + tau) - sigma B_n) / (S_d (1 + tau) - sigma B_d) as C and
    Python text in u, tau, sigma (names the caller defines)."""

    def part(rows: tuple[list[list[float]], list[list[float]]]) -> str:
        s, b = (horner2(r, "sigma", "u") for r in rows)
        return f"({s}) * (1.0 + tau)" + ("" if b == "0.0" else f" - sigma * ({b})")

    return f"({part(form.num)}) / ({part(form.den)})"


def far_names(sqrt: str = "sqrt") -> list[tuple[str, str]]:
    """The far form's names from p and h = bcol_h(p) = 1 - tanh(sqrt(p)/2), as C and Python
    text (`sqrt` the language's square root)."""
    return [("u", f"0.5 * {sqrt}(p)"), ("tau", "1.0 - h"), ("sigma", "h * (2.0 - h)")]


def near_doc(form: axial.NearForm) -> str:
    """One line on a near form, for comments."""
    return (
        f"for {literal(axial.NEAR_LOW)} < p < {literal(axial.NEAR_HIGH)} an economised "
        f"polynomial ({len(form.coeffs)} terms) with the poles divided out"
    )


def h_doc() -> str:
    """One line on bcol_h, for comments."""
    return (
        f"h(p) = T(p) = tanh(u)/u, u = sqrt(p)/2 (tan(v)/v, v = sqrt(-p)/2, below 0) for p < "
        f"{literal(axial.NEAR_HIGH)}, 1 - tanh(u) from it on"
    )
