"""symkin.codegen.routines.optimize: the CSE'd straight-line program computes what the routine
states (checked by running it against the expressions it came from), and a routine optimised
again is the result found before only when it is the same routine."""

from __future__ import annotations

import math
import random

import sympy as sp

from symkin.codegen import routines
from symkin.codegen.routines import Argument, Routine, layout, optimize

X = sp.symbols("x0:3", real=True)
TWO = sp.Integer(2)


def _routine(two: sp.Expr = TWO, name: str = "r", symbols=X) -> Routine:
    x, y, z = symbols
    s = sp.Symbol("s", real=True)
    common = sp.sin(x + y) * z
    return Routine(
        name=name,
        arguments=(Argument("inputs", tuple(symbols)),),
        assignments=((s, common + two * sp.cos(x + y)),),
        outputs=(s * common, common**two + s, sp.exp(common) - sp.cos(x + y)),
        blocks=layout(("out", 3, 1)),
    )


def _run(r: Routine, values: dict) -> list[float]:
    """The straight-line program, statement by statement, in floats."""
    env = dict(values)
    for symbol, expr in r.assignments:
        env[symbol] = float(expr.subs(env))
    return [float(e.subs(env)) for e in r.outputs]


def test_the_program_computes_the_routine():
    r = _routine()
    opt = optimize(r)
    assert len(opt.assignments) > len(r.assignments)  # sin(x + y) z and cos(x + y) shared
    rng = random.Random(5)
    for _ in range(5):
        values = {s: rng.uniform(-2, 2) for s in X}
        want = _run(r, values)
        got = _run(opt, values)
        assert all(math.isclose(a, b, rel_tol=1e-13, abs_tol=1e-15) for a, b in zip(got, want))
    # every temporary is assigned before its first use
    seen = set(X)
    for symbol, expr in opt.assignments:
        assert expr.free_symbols <= seen, symbol
        seen.add(symbol)
    assert all(e.free_symbols <= seen for e in opt.outputs)


def test_the_same_routine_again_is_the_result_found_before():
    first = optimize(_routine())
    again = optimize(_routine())  # built anew, equal field by field
    assert again is first
    assert routines._optimize(_routine(), "_tmp") == first  # what a fresh pass gives


def test_a_routine_that_differs_anywhere_gets_its_own_pass():
    base = optimize(_routine())
    others = [
        _routine(two=sp.Float(2.0)),  # a Float where the other has an Integer
        _routine(name="other"),
        _routine(symbols=sp.symbols("x0:3", positive=True)),  # the same names, other assumptions
    ]
    for r in others:
        got = optimize(r)
        assert got is not base
        assert got == routines._optimize(r, "_tmp")
    assert optimize(_routine(), prefix="_t") != base


def test_hoisted_routine_computes_the_routine_and_keeps_fixed_terms_out_of_the_loop():
    """routines.hoist (the C exact closure's Newton loop, docs/generated-code.md): the fixed
    arguments' terms once in <name>_pre, the loop reading them from `pre`; together they compute
    what the routine states, and the loop calls no function of the fixed symbols alone."""
    t = sp.symbols("t0:2", real=True)
    d = sp.symbols("d0:2", real=True)
    p = sp.Symbol("p0", real=True)
    a = sp.Symbol("a", real=True)
    r = Routine(
        name="closure",
        arguments=(Argument("theta", t), Argument("delta", d), Argument("params", (p,))),
        assignments=((a, sp.sin(t[0] + d[0]) * p),),
        outputs=(
            a + sp.cos(t[1]) * sp.sin(d[1]) + p * sp.exp(t[0]),
            a * sp.cos(t[0] + t[1]) - d[0] ** 2,
        ),
        blocks=layout(("F", 2, 1)),
    )
    opt = optimize(r)
    pre, loop = routines.hoist(opt, "delta")
    assert pre.name == "closure_pre" and loop.name == "closure"
    assert [x.name for x in loop.arguments] == ["pre", "delta", "params"]
    assert loop.arguments[2].symbols == ()  # read through `pre` alone
    carried = set(loop.arguments[0].symbols)
    for _, e in loop.assignments:
        for f in e.atoms(sp.Function):
            assert f.free_symbols & set(d) or f.free_symbols & {s for s, _ in loop.assignments}
    rng = random.Random(7)
    for _ in range(5):
        values = {s: rng.uniform(-1, 1) for s in (*t, *d, p)}
        want = [float(e.subs({a: sp.sin(t[0] + d[0]) * p}).subs(values)) for e in r.outputs]
        carried_values = dict(zip(pre.arguments[0].symbols, [values[s] for s in t]))
        carried_values[p] = values[p]
        pre_out = _run(pre, carried_values)
        env = dict(zip(loop.arguments[0].symbols, pre_out))
        env.update({s: values[s] for s in d})
        got = _run(loop, env)
        assert carried <= set(env)
        assert all(math.isclose(x, y, rel_tol=1e-13, abs_tol=1e-15) for x, y in zip(got, want))
