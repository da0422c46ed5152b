"""What the physical levels take from the kinematic derivation (symkin.analysis.Analysis): the
checked inputs and parameter values, the rigid hinge angles at working precision, and mpmath
functions of its expressions. One place to adapt when the evaluation layer moves."""

from __future__ import annotations

from collections.abc import Mapping

import mpmath
import sympy as sp

from .. import special


def inputs(analysis, given: Mapping[str, object]) -> dict[str, sp.Expr]:
    """The input angles as exact numbers, by hinge name (exit 2 on a missing or unknown one)."""
    return {analysis.kin.hinges[a].name: v for a, v in analysis._inputs(given).items()}


def rigid_angles(analysis, pvals: list, ivals: Mapping[int, object]) -> dict[int, object]:
    """Rigid hinge angles θ^r by label at the current mpmath precision (exit 3 when the loops
    cannot close: the message of every other level)."""
    theta, _ = analysis._rigid_angles(pvals, dict(ivals))
    return theta


def deltas(analysis, pvals: list, theta: Mapping[int, object]) -> dict[int, object]:
    """δ of the non-input hinges from the `exact` level's Newton on the analysis's closure, with
    `pvals` the values of analysis.params."""
    return analysis._deltas("exact", list(pvals), dict(theta))


def function(analysis, key: str, exprs, args):
    """An mpmath function of sympy `exprs` in `args`, built once per analysis and key."""
    cache = analysis.__dict__.setdefault("_physics_lambdas", {})
    if key not in cache:
        cache[key] = sp.lambdify(args, exprs, modules=[special.mpmath_namespace(), "mpmath"])
    return cache[key]


def mp_values(exprs, dps: int) -> list:
    """Exact sympy numbers as mpf at `dps` digits."""
    return [mpmath.mpf(sp.N(e, dps + 5)) for e in exprs]
