"""symkin.model.derivatives.jacobian gives sympy's own derivatives, entry for entry (the
generated code is printed from them: the same expressions keep generated/ byte-identical)."""

from __future__ import annotations

from pathlib import Path

import pytest
import sympy as sp

import symkin
from symkin.model.derivatives import jacobian
from symkin.model.special import arck, cosr, sinr
from symkin.physics import reduced

ROOT = Path(__file__).resolve().parent.parent


def _sympys(rows, by) -> sp.Matrix:
    """Matrix.jacobian, sympy's diff entry by entry."""
    return sp.Matrix(list(rows)).jacobian(list(by))


def _same(a: sp.Matrix, b: sp.Matrix) -> None:
    assert a.shape == b.shape
    for i in range(a.rows):
        for j in range(a.cols):
            # structural equality: the same tree, not merely an equal value
            assert a[i, j] == b[i, j], (i, j, a[i, j], b[i, j])
            assert sp.srepr(a[i, j]) == sp.srepr(b[i, j])


def test_every_rule_and_the_fallback_match_diff() -> None:
    x, y, z = sp.symbols("x y z", real=True)
    p = sp.Symbol("p", positive=True)
    g = sp.Function("g")  # undefined: diff leaves Derivative/Subs, the fallback's case
    shared = sp.sin(x * y + sp.Float("0.25", 17)) * p
    rows = [
        shared + shared**2 - 3 * x,
        x**y + sp.sqrt(x**2 + p) - sp.exp(-z / p),
        arck(x * z) * sinr(3)(y) + cosr(2)(x - y),
        sp.Abs(x - y) + sp.Piecewise((x**2, x > 0), (y, True)),  # other nodes: sympy's diff
        g(x * y) + sp.atan2(y, x) * shared,
        # a Derivative already in the row (not canonical: y before x): diff canonicalises it
        x * sp.Derivative(g(x, y), y, x) + sp.sin(x) * sp.Derivative(g(x, y), y, x) ** 2,
        x * y * sp.exp(z) * sp.Float("1.5", 17),  # a product of several factors, in its order
        x * y * z * shared / (1 + x**2),
    ]
    by = [x, y, z, p]
    _same(jacobian(rows, by), _sympys(rows, by))


def test_rows_by_symbols_they_do_not_hold_are_zero() -> None:
    x, y = sp.symbols("x y")
    a = jacobian([x**2, sp.Integer(1)], [y, x])
    assert a == sp.Matrix([[0, 2 * x], [0, 0]])
    assert jacobian([], [x]).shape == (0, 1)
    assert jacobian([x], []).shape == (1, 0)


@pytest.mark.parametrize(
    "name", ["examples/piezo_amplifier.toml", "tests/mechanisms/parallelogram.toml"]
)
def test_the_reduced_equilibriums_jacobians_are_diffs(name: str) -> None:
    """Every piece of the loaded level's Newton and report (symbolic parameters, two half plates
    per plate), by x, the plate outputs and the reported quantities' parameters."""
    an = symkin.analyze(ROOT / name)
    values = {q.symbol: q.value for q in an.mechanism.parameters}
    r = reduced.Reduced(an.kin, values, segments=2, symbolic=True)
    s, se = r._s, r._se
    outs = [v for a, j, *_ in r.segs for v in s["out"][a, j]]
    rows = r._rows(s)
    ins = [v for a, j, *_ in r.segs for v in s["pf"][a, j]]
    ys = r._reported(se)
    for exprs, by in [
        (rows, r.x),
        (rows, outs),
        (ins, r.x),
        (r._rows(se), r.extra),
        (ys, list(r.x) + outs + list(r.extra)),
    ]:
        _same(jacobian(exprs, by), _sympys(exprs, by))
