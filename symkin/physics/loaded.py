"""The `loaded` level evaluated with mpmath (the `sympy` backend), from the derivation of
symkin.physics.statics: rigid angles → A^T μ = Q → plate compliance → Newton on δ → ΔR."""

from __future__ import annotations

from collections.abc import Mapping

import mpmath
import sympy as sp

from ..errors import AssemblyError
from . import bridge
from .statics import LoadedDerivation

#: Working precision of the evaluation, decimal digits.
DPS = 40


def derivation(analysis, **options) -> LoadedDerivation:
    """The LoadedDerivation of an Analysis (options: beam_column, extensible), cached on it."""
    cache = analysis.__dict__.setdefault("_physics", {})
    key = ("loaded", *sorted(options.items()))
    if key not in cache:
        cache[key] = LoadedDerivation(analysis.structure, [p.name for p in analysis.points],
                                      **options)
    return cache[key]


def evaluate(analysis, inputs: Mapping[str, object], params: Mapping[str, object] | None = None,
             dps: int = DPS, **options):
    """One configuration at the `loaded` level (CONTRACT §7); `options` select a variant of the
    derivation (statics.LoadedDerivation: beam_column, extensible)."""
    from ..analysis import PointResult
    from .result import HingeLoad, PhysicalEvaluation
    from .stiffness import check_values

    der = derivation(analysis, **options)
    la = der.analysis
    kin = la.kin
    prefix = "loaded" + "".join(f":{k}={v}" for k, v in sorted(options.items())) + ":"

    def fn(key, exprs, args):
        return bridge.function(analysis, prefix + key, exprs, args)

    values = analysis.parameter_values(params)
    check_values(analysis.mechanism, values, "loaded")
    given = {kin.structure.hinge_label(n): v for n, v in bridge.inputs(analysis, inputs).items()}
    comp = [s for a in sorted(der.compliance) for s in der.compliance[a]]
    with mpmath.workdps(dps):
        pvals = bridge.mp_values([values[s] for s in la.params], dps)
        ivals = {a: mpmath.mpf(sp.N(v, dps + 5)) for a, v in given.items()}
        theta = bridge.rigid_angles(analysis, pvals, ivals)
        base = [*la.params, *la.thetas]
        at_rigid = [*pvals, *(theta[a] for a in sorted(theta))]
        path = analysis.mechanism.path
        mu0 = _multipliers(der.first_statics, der.mu0, fn, "AT0", base, at_rigid, path) \
            if der.mu0 else []
        mu = _multipliers(der.statics, der.mu, fn, "AT", [*base, *der.mu0], [*at_rigid, *mu0],
                          path)
        base, at_rigid = [*base, *der.mu0], [*at_rigid, *mu0]
        loads = der.plate_loads
        disp = [e for a in sorted(der.compliance) for e in loads[a].displacement]
        args = [*base, *der.mu]
        cvals = list(fn("compliance", disp, args)(*at_rigid, *mu)) if disp else []
        args_c = [*args, *comp]
        known = [*at_rigid, *mu, *cvals]
        delta = _newton(la, fn, args_c, known, analysis.mechanism.path, dps)
        full = [*known, *(delta[a] for a in kin.unknowns)]
        args_d = [*args_c, *la.deltas]
        points = {}
        for p in la.points:
            rig = fn(f"rigid:{p.name}", list(la.point_rigid(p.name)), args_d)(*full)
            dev = fn(f"loaded:{p.name}", list(la.point_deviation(p.name, "exact")), args_d)(*full)
            points[p.name] = PointResult((float(rig[0]), float(rig[1])),
                                         (float(rig[0] + dev[0]), float(rig[1] + dev[1])),
                                         (float(dev[0]), float(dev[1])))
        s = analysis.mechanism.unit_scale
        hinges = {}
        energy = mpmath.mpf(0)
        for a in sorted(kin.hinges):
            h = kin.hinges[a]
            force = fn(f"force:{a}", list(loads[a].force), args)(*at_rigid, *mu)
            moment = fn(f"moment:{a}", der.end_moment(a), args_d)(*full)
            energy += fn(f"energy:{a}", der.energy(a), args_d)(*full)
            hinges[h.name] = HingeLoad((float(force[0]), float(force[1])),
                                       float(moment * mpmath.mpf(sp.N(s, dps))))
        names = {a: h.name for a, h in kin.hinges.items()}
        return PhysicalEvaluation(
            level="loaded", backend="sympy",
            inputs={names[a]: float(ivals[a]) for a in sorted(ivals)},
            angles_rigid={names[a]: float(theta[a]) for a in sorted(theta)},
            angles_compliant={names[a]: float(theta[a] + delta.get(a, 0)) for a in sorted(theta)},
            points=points, hinges=hinges, energy=float(energy * mpmath.mpf(sp.N(s, dps))),
            error_estimate=None)


def _multipliers(statics, symbols, fn, key: str, args: list, values: list, path: str) -> list:
    """The multipliers of A^T μ = Q at the rigid pose (none for an open chain)."""
    a_t, q = statics
    if not symbols:
        return []
    try:
        return list(mpmath.lu_solve(mpmath.matrix(fn(key, a_t.tolist(), args)(*values)),
                                    mpmath.matrix(fn(key + ":Q", list(q), args)(*values))))
    except ZeroDivisionError:
        raise AssemblyError(f"{path}: the mechanism is at a toggle position (singular loop "
                            "Jacobian) for these inputs") from None


def _newton(la, fn, args: list, known: list, path: str, dps: int) -> dict:
    """δ of the loaded closure: from its first-order solution, Newton to the working precision."""
    kin = la.kin
    if not la.deltas:
        return {}
    a_lin, r_lin = la.linear_system
    A = mpmath.matrix(fn("lin_A", a_lin.tolist(), args)(*known))
    r = mpmath.matrix(fn("lin_r", list(r_lin), args)(*known))
    x = -mpmath.lu_solve(A, r)
    f = fn("residual", list(la.residual), [*args, *la.deltas])
    jac = fn("jacobian", la.jacobian.tolist(), [*args, *la.deltas])
    tight = mpmath.mpf(10) ** (4 - dps)
    for _ in range(40):
        vals = [*known, *x]
        try:
            step = mpmath.lu_solve(mpmath.matrix(jac(*vals)), mpmath.matrix(f(*vals)))
        except ZeroDivisionError:
            raise AssemblyError(f"{path}: singular loaded loop Jacobian (toggle position) for "
                                "these inputs") from None
        x = x - step
        if mpmath.norm(step, mpmath.inf) <= tight * mpmath.norm(x, mpmath.inf):
            return {a: x[k] for k, a in enumerate(kin.unknowns)}
    raise AssemblyError(f"{path}: the loaded loops did not converge (40 Newton steps)")
