"""The alternative `sympy.lambdify`: symkin's routines before CSE, the dyad assignments
substituted, lambdified with symkin's float64 kernels and `math`, driven in Python by the same
steps as the generated C (closed-form rigid angles, the polish, first-order δ, Newton on δ)."""

from __future__ import annotations

import math

import numpy as np
from common import POLICY


def substituted(routine) -> list:
    """The routine's outputs with its named assignments substituted (one closed-form expression
    per output)."""
    import sympy as sp

    env: dict = {}
    for symbol, expr in routine.assignments:
        env[symbol] = sp.sympify(expr).xreplace(env)
    return [sp.sympify(o).xreplace(env) for o in routine.outputs]


class Pipeline:
    """What the generated evaluators do, with the routines given as Python callables:
    closed-form rigid angles, [rigid polish], first-order δ, Newton on δ, point positions."""

    def __init__(self, plan, fns: dict, polish: int = POLICY["polish"]):
        self.fns = fns
        self.m = len(plan.hinges)
        self.k = len(plan.unknown_index)
        self.nd = plan.n_dyads
        self.input_index = list(plan.input_index)
        self.unknown_index = list(plan.unknown_index)
        self.needs_loops = plan.needs_loops
        self.polish = polish
        self.params = [p.value for p in plan.parameters]

    def __call__(self, x) -> list[float]:
        k, p = self.k, self.params
        theta = [0.0] * self.m
        for j, i in enumerate(self.input_index):
            theta[i] = float(x[j])
        if k:
            sol = self.fns["rigid"](*x, *p)
            if any(r < 0 for r in sol[k : k + self.nd]):
                raise ArithmeticError("cannot assemble")
            for j, i in enumerate(self.unknown_index):
                theta[i] = math.remainder(sol[j], 2 * math.pi)
            for _ in range(self.polish):  # the C template's Newton polish steps
                res = self.fns["rigid_res"](*theta, *p)
                res = [
                    math.remainder(r, 2 * math.pi) if n % 3 == 0 else r for n, r in enumerate(res)
                ]
                lin = self.fns["linear"](*theta, *p)
                step = np.linalg.solve(
                    np.array(lin[: k * k], dtype=float).reshape(k, k), np.array(res, dtype=float)
                )
                for j, i in enumerate(self.unknown_index):
                    theta[i] -= float(step[j])
        delta = [0.0] * k
        if self.needs_loops:
            lin = self.fns["linear"](*theta, *p)
            a = np.array(lin[: k * k], dtype=float).reshape(k, k)
            delta = list(np.linalg.solve(a, -np.array(lin[k * k :], dtype=float)))
            previous = math.inf
            for _ in range(POLICY["iterations"]):
                nw = self.fns["newton"](*theta, *delta, *p)
                step = np.linalg.solve(
                    np.array(nw[k:], dtype=float).reshape(k, k), np.array(nw[:k], dtype=float)
                )
                delta = [d - s for d, s in zip(delta, step)]
                size = max(abs(d) for d in delta)
                change = float(np.max(np.abs(step)))
                if (
                    change <= POLICY["stop"] * size
                    or size == 0.0
                    or (
                        change >= POLICY["stall_ratio"] * previous
                        and change <= POLICY["stall"] * size
                    )
                ):
                    break
                previous = change
            else:
                raise ArithmeticError("no convergence")
        rigid = self.fns["rigid_points"](*theta, *p)
        return list(self.fns["dev_exact"](*theta, *delta, *p)), rigid


def lambdify_alternative(plan, cse: bool, polish: int = POLICY["polish"]):
    """`sympy.lambdify` (modules: symkin's float64 kernels, then `math`; one scalar call per point;
    `cse` as given) of the same closed-form expressions: the rigid dyad assignments substituted
    into the angle, reach and margin outputs, the loop Jacobian A and r, the exact closure F and
    dF/dδ, the deviation; driven by the same Newton loop in Python (numpy.linalg.solve for the
    small systems)."""
    import sympy as sp

    from symkin.codegen.backends.numpy import kernels as np_kernels

    # conjugate: substituting the dyad assignments turns Abs(x)**2 into x*conjugate(x), which
    # `math` lacks; for real floats it is the identity.
    modules = [dict(np_kernels.float64_namespace(), conjugate=lambda z: z.conjugate()), "math"]
    fns = {}
    for key in ("rigid", "rigid_res", "linear", "newton", "rigid_points", "dev_exact"):
        r = plan.routines.get(key)
        if r is None:
            continue
        args = [s for a in r.arguments for s in a.symbols]
        outs = substituted(r)
        fns[key] = sp.lambdify(args, outs, modules=modules, cse=cse)
    return Pipeline(plan, fns, polish=polish)
