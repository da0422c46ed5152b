"""symkin.model.lambdified.lambdify: the function sympy.lambdify gives, its sums printed in
sympy's stored order; checked against sympy's own lambdify and mpmath at 40 digits."""

from __future__ import annotations

import math

import mpmath
import sympy as sp

from symkin.model.lambdified import lambdify
from symkin.model.special import arck, mpmath_namespace


def _exprs():
    x, y = sp.symbols("x y", real=True)
    terms = sum(sp.Float(f"0.{k}1", 30) * x**k * sp.cos(k * y) for k in range(1, 12))
    return [x, y], [terms + sp.pi, sp.sqrt(1 + x**2) * arck(y), [terms * y, sp.Integer(2)]]


def test_mpmath_functions_agree_with_sympys_lambdify_at_30_digits() -> None:
    args, exprs = _exprs()
    modules = [mpmath_namespace(), "mpmath"]
    ours = lambdify(args, exprs, modules)
    theirs = sp.lambdify(args, exprs, modules=modules, cse=True)
    with mpmath.workdps(40):
        a = ours(mpmath.mpf("0.3"), mpmath.mpf("-1.1"))
        b = theirs(mpmath.mpf("0.3"), mpmath.mpf("-1.1"))
        flat = [a[0], a[1], *a[2]]
        ref = [b[0], b[1], *b[2]]
        assert all(isinstance(u, mpmath.mpf) for u in flat[:3])  # mpmath, not floats
        for u, v in zip(flat, ref, strict=True):
            assert abs(u - v) <= mpmath.mpf(10) ** -30 * max(1, abs(v))
        # and against sympy's own evaluation of the expressions
        x, y = args
        exact = sp.N(exprs[0].subs({x: sp.Rational(3, 10), y: sp.Rational(-11, 10)}), 40)
        assert abs(flat[0] - mpmath.mpf(str(exact))) <= mpmath.mpf(10) ** -28


def test_float_functions_agree_to_rounding() -> None:
    args, exprs = _exprs()
    modules = [{"arck": lambda u: float(arck(sp.Float(u, 30)))}, "math"]
    a = lambdify(args, exprs, modules)(0.3, -1.1)
    b = sp.lambdify(args, exprs, modules=modules)(0.3, -1.1)
    for u, v in zip([a[0], a[1], *a[2]], [b[0], b[1], *b[2]], strict=True):
        assert isinstance(u, float | int)
        assert math.isclose(u, v, rel_tol=1e-14)


def test_a_module_object_gets_lambdifys_own_printer() -> None:
    """modules=[mpmath] (the module, not its name) is lambdify's: a 30-digit Float stays mpf."""
    x = sp.Symbol("x")
    fn = lambdify([x], sp.Float("0.1", 30) * x, [mpmath])
    with mpmath.workdps(30):
        assert abs(fn(mpmath.mpf(1)) - mpmath.mpf("0.1")) < mpmath.mpf(10) ** -28


def test_the_mpmath_evaluation_prints_each_function_once() -> None:
    """symkin.model.lambdified.mpmath_function: the same arguments and expressions (lists or
    tuples alike) give the function printed before; other expressions or another argument
    order a new one, whose values are its own (checked against sympy's evaluation)."""
    from symkin.model.lambdified import mpmath_function

    args, exprs = _exprs()
    first = mpmath_function(args, exprs)
    assert mpmath_function(list(args), [exprs[0], exprs[1], tuple(exprs[2])]) is first
    swapped = mpmath_function(args[::-1], exprs)
    other = mpmath_function(args, [exprs[0] + 1])
    assert swapped is not first and other is not first
    x, y = args
    with mpmath.workdps(40):
        at = {x: sp.Rational(3, 10), y: sp.Rational(-11, 10)}
        exact = mpmath.mpf(str(sp.N(exprs[0].subs(at), 40)))
        assert abs(first(mpmath.mpf("0.3"), mpmath.mpf("-1.1"))[0] - exact) < 1e-28
        assert abs(swapped(mpmath.mpf("-1.1"), mpmath.mpf("0.3"))[0] - exact) < 1e-28
        assert abs(other(mpmath.mpf("0.3"), mpmath.mpf("-1.1"))[0] - exact - 1) < 1e-28
