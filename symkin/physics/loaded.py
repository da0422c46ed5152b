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
    path = analysis.mechanism.path
    loads = der.plate_loads
    with mpmath.workdps(dps):
        pvals = bridge.mp_values([values[s] for s in analysis.params], dps)
        ivals = {a: mpmath.mpf(sp.N(v, dps + 5)) for a, v in given.items()}
        theta = bridge.rigid_angles(analysis, pvals, ivals)
        # the closure's constants in the order of la.params: parameters, mu0, mu, compliance
        known = [*pvals]
        thetas = [theta[a] for a in sorted(theta)]

        def at_rigid(key, exprs):
            n = len(known)
            return fn(key, exprs, [*la.params[:n], *la.thetas])(*known, *thetas)

        for symbols, statics, key in ((der.mu0, der.first_statics, "mu0"),
                                      (der.mu, der.statics, "mu")):
            known += _multipliers(statics, symbols, at_rigid, key, path)
        disp = [e for a in sorted(der.compliance) for e in loads[a].displacement]
        known += list(at_rigid("compliance", disp)) if disp else []
        delta = bridge.deltas(la, known, theta)
        args = [*la.params, *la.thetas, *la.deltas]
        full = [*known, *thetas, *(delta[a] for a in kin.unknowns)]
        points = {}
        for p in la.points:
            rig = fn(f"rigid:{p.name}", list(la.point_rigid(p.name)), args)(*full)
            dev = fn(f"loaded:{p.name}", list(la.point_deviation(p.name, "exact")), args)(*full)
            points[p.name] = PointResult((float(rig[0]), float(rig[1])),
                                         (float(rig[0] + dev[0]), float(rig[1] + dev[1])),
                                         (float(dev[0]), float(dev[1])))
        s = mpmath.mpf(sp.N(analysis.mechanism.unit_scale, dps))
        hinges = {}
        energy = mpmath.mpf(0)
        for a in sorted(kin.hinges):
            force = fn(f"force:{a}", list(loads[a].force), args)(*full)
            moment = fn(f"moment:{a}", der.end_moment(a), args)(*full)
            energy += fn(f"energy:{a}", der.energy(a), args)(*full)
            hinges[kin.hinges[a].name] = HingeLoad((float(force[0]), float(force[1])),
                                                   float(moment * s))
        names = {a: h.name for a, h in kin.hinges.items()}
        return PhysicalEvaluation(
            level="loaded", backend="sympy",
            inputs={names[a]: float(ivals[a]) for a in sorted(ivals)},
            angles_rigid={names[a]: float(theta[a]) for a in sorted(theta)},
            angles_compliant={names[a]: float(theta[a] + delta.get(a, 0)) for a in sorted(theta)},
            points=points, hinges=hinges, energy=float(energy * s), error_estimate=None)


def _multipliers(statics, symbols, at_rigid, key: str, path: str) -> list:
    """The multipliers of A^T μ = Q at the rigid pose (none for an open chain)."""
    a_t, q = statics
    if not symbols:
        return []
    try:
        return list(mpmath.lu_solve(mpmath.matrix(at_rigid(key + ":AT", a_t.tolist())),
                                    mpmath.matrix(at_rigid(key + ":Q", list(q)))))
    except ZeroDivisionError:
        raise AssemblyError(f"{path}: the mechanism is at a toggle position (singular loop "
                            "Jacobian) for these inputs") from None
