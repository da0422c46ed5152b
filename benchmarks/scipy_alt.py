"""The alternative `scipy.optimize.root`: the loop equations a user would write, solved for the
rigid and then the compliant pose, the deviation as the difference of the two positions."""

from __future__ import annotations

import numpy as np


def scipy_alternative(an):
    """`scipy.optimize.root` (hybr, xtol 1e-12) on the loop equations a user would write: per
    chord the angular closure Σ Φ q = 0 and the positional closure Σ Rot(φ_i) V_i (+ Φ Δz when
    compliant) = 0, lambdified with numpy, unknowns the non-input hinge angles. The rigid pose is
    solved from the as-fabricated pose (θ = 0), the compliant pose from the rigid one; the
    deviation is the compliant position (rigid position formula + Σ Δz over the path, at the
    compliant angles) minus the rigid position."""
    import sympy as sp
    from scipy.optimize import root

    from symkin.codegen.backends.numpy import kernels as np_kernels

    kin = an.kin
    modules = [np_kernels.numpy_namespace(), "numpy"]
    params = list(an.params)
    thetas = list(an.thetas)
    rows_r, rows_c = [], []
    for c in kin.chords:
        rows_r.append(kin.angular_closure(c))
        rows_r.extend(kin.positional_closure(c, rigid=True))
        rows_c.append(kin.angular_closure(c))
        rows_c.extend(kin.positional_closure(c))
    f_rigid = sp.lambdify(thetas + params, rows_r, modules=modules)
    f_comp = sp.lambdify(thetas + params, rows_c, modules=modules)
    point = an.points[0]
    link = an.link[point.link]
    rig = list(kin.rigid_position(link, point.at))
    comp = [a + b for a, b in zip(rig, kin.path_deviation(link))]
    f_pos_r = sp.lambdify(thetas + params, rig, modules=modules)
    f_pos_c = sp.lambdify(thetas + params, comp, modules=modules)
    pvals = [float(p.value) for p in an.mechanism.parameters]
    inputs = [a - 1 for a in kin.inputs]
    unknown = [a - 1 for a in kin.unknowns]
    m = len(thetas)

    def full(x, u):
        th = np.zeros(m)
        th[inputs] = x
        th[unknown] = u
        return th

    def solve(x):
        x = np.asarray(x, float)
        th0 = np.zeros(len(unknown))
        if unknown:
            sr = root(
                lambda u: np.asarray(f_rigid(*full(x, u), *pvals), float),
                th0,
                method="hybr",
                options={"xtol": 1e-12},
            )
            sc = root(
                lambda u: np.asarray(f_comp(*full(x, u), *pvals), float),
                sr.x,
                method="hybr",
                options={"xtol": 1e-12},
            )
            if not (sr.success and sc.success):
                raise ArithmeticError(f"root: {sr.message} / {sc.message}")
            ur, uc = sr.x, sc.x
        else:
            ur = uc = th0
        pr = np.asarray(f_pos_r(*full(x, ur), *pvals), float)
        pc = np.asarray(f_pos_c(*full(x, uc), *pvals), float)
        return list(pc - pr)

    return solve
