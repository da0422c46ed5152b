"""Closed-form sensitivities of the `loaded` level (docs/sensitivity.md): the derivatives of the
points' deviations by the file's parameters and the inputs, by the implicit-function theorem on
the reduced equilibrium R(x, θ, p) = 0 of symkin.physics.reduced.

At the solution x, with v a parameter or an input and θ every hinge's rigid angle (dθ/dv from
the rigid closure, as at the kinematic levels; an input's own angle moves by 1), the plates'
relation outputs o = rel(i) of their inputs i = (θ_c, p, f, ε_a, ε_s)(x, θ, p):

    di/dv|_x = ∂i/∂θ dθ/dv + ∂i/∂p                    (ε_a, ε_s read the parameters only)
    dR/dv|_x = ∂R/∂θ dθ/dv + ∂R/∂p + ∂R/∂o ∂rel/∂i di/dv|_x
    dx/dv    = −J⁻¹ dR/dv|_x                          (J the Newton Jacobian, plate relation in)
    dD/dv    = (∂D/∂x + ∂D/∂o ∂rel/∂i ∂i/∂x) dx/dv + ∂D/∂θ dθ/dv + ∂D/∂p + ∂D/∂o ∂rel/∂i di/dv|_x

(symkin.physics.reduced_rates, which `loaded`'s reported quantities and the generated numpy
modules run too).
The parameters are those of the file, the scales of x numbers (they only condition Newton).
:func:`partials` states the symbolic pieces for the generated code (symkin.codegen.plan's
loaded_sens<g>) and for :class:`LoadedSensitivity`, the sympy backend's evaluation.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from functools import cache

import numpy as np
import sympy as sp

from ..kinematics.analysis import Analysis
from ..model.derivatives import jacobian
from ..model.lambdified import lambdify
from ..model.sections import RelationTerms
from .plate_relation import notch_relation, relation
from .reduced import Reduced
from .reduced_rates import _red_inputs_x, _red_relation, _red_sensitivity, _red_theta_v


@dataclass(frozen=True)
class LoadedPartials:
    """The partial derivatives of one variant (half plates per plate) of the reduced equilibrium
    at fixed x and plate outputs: θ every hinge's rigid angle (label order) then the force
    actuators' forces (Reduced.angles), p the parameters, i every half plate's (θ_c, p, f, ε_a,
    ε_s), o its relation's (along, across, omega), D the points' deviations (x, y per point)."""

    R_theta: sp.Matrix  # n × m
    R_p: sp.Matrix  # n × n_p
    i_theta: sp.Matrix  # 5 n_s × m
    i_p: sp.Matrix  # 5 n_s × n_p
    D_x: sp.Matrix  # 2 n_P × n
    D_theta: sp.Matrix  # 2 n_P × m
    D_p: sp.Matrix  # 2 n_P × n_p
    D_o: sp.Matrix  # 2 n_P × 3 n_s

    def blocks(self) -> tuple[tuple[str, sp.Matrix], ...]:
        """The matrices by name, in the generated routine's order."""
        return (
            ("dR_dtheta", self.R_theta),
            ("dR_dp", self.R_p),
            ("din_dtheta", self.i_theta),
            ("din_dp", self.i_p),
            ("dD_dx", self.D_x),
            ("dD_dtheta", self.D_theta),
            ("dD_dp", self.D_p),
            ("dD_dout", self.D_o),
        )


def plate_inputs(r: Reduced) -> sp.Matrix:
    """Every half plate's (θ_c, p, f, ε_a, ε_s), as the plate relation reads them."""
    s = r._s
    return sp.Matrix(
        [
            v
            for a, j, _, _, ea, es in r.segs
            for v in (*s["pf"][a, j], sp.sympify(ea), sp.sympify(es))
        ]
    )


def partials(r: Reduced, params: Sequence[sp.Symbol], points: Sequence[str]) -> LoadedPartials:
    """The pieces of the module docstring for the symbolic reduced equilibrium `r` (built with
    symbolic=True), by the parameters `params`, for the deviations of `points`."""
    s = r._s
    # the force actuators' forces and a structure's strokes too
    thetas = [r.th[a] for a in sorted(r.hinges)] + r.given_symbols
    rows = sp.Matrix(r._rows(s))
    ins = plate_inputs(r)
    dev = sp.Matrix([c for name in points for c in r._deviation(s, *r.located(name))])
    outs = [v for a, j, *_ in r.segs for v in s["out"][a, j]]
    return LoadedPartials(
        jacobian(rows, thetas),
        jacobian(rows, params),
        jacobian(ins, thetas),
        jacobian(ins, params),
        jacobian(dev, r.x),
        jacobian(dev, thetas),
        jacobian(dev, params),
        jacobian(dev, outs),
    )


@cache
def eps_relation(
    terms: RelationTerms | None = None,
) -> tuple[tuple[sp.Symbol, ...], list[sp.Expr]]:
    """The plate relation's (order 4) partials by ε_a and ε_s: ∂(along, across, omega)/∂(ε_a,
    ε_s), row-major (3 × 2), over the symbols (θ, p, f, ε_a, ε_s); with `terms`, a notch's
    relation's (symkin.physics.plate_relation.notch_relation)."""
    th, p, f, ea, es = sp.symbols("theta p f e_a e_s", real=True)
    rel = (
        relation(th, p, f, ea, es, 4)
        if terms is None
        else notch_relation(th, p, f, ea, es, terms, 4)
    )
    return (th, p, f, ea, es), [
        sp.diff(v, w) for v in (rel.along, rel.across, rel.omega) for w in (ea, es)
    ]


def theta_rates(
    analysis: Analysis, theta_u: np.ndarray, n_params: int, inputs: Sequence[int], forces: int = 0
) -> np.ndarray:
    """dθ/dv of every hinge (label order) then of the `forces` force actuators' forces ×
    (parameters, then `inputs`, then the forces): the non-input hinges' rows from the rigid
    closure (`theta_u`, k × n_v), an input's own angle moving by 1, a held one by nothing, a
    force by 1 (symkin.physics.reduced_rates' _red_theta_v on a batch of one)."""
    kin = analysis.kin
    labels = sorted(kin.hinges)
    return _red_theta_v(
        np.asarray(theta_u, dtype=float)[None],
        1,
        len(labels),
        n_params + len(inputs),
        n_params,
        [labels.index(a) for a in kin.unknowns],
        [labels.index(a) for a in inputs],
        forces,
    )[0]


class LoadedSensitivity:
    """The sympy backend's `loaded` sensitivities of one analysis: per variant, the symbolic
    reduced equilibrium (parameters as symbols, scales at the file's defaults) and its pieces,
    lambdified (float64 kernels, as the solver's)."""

    def __init__(self, analysis: Analysis, modules) -> None:
        self.an = analysis
        self.modules = modules
        self.params = list(analysis.params)
        self.points = [p.name for p in analysis.points]
        self._variants: dict[int, tuple] = {}

    def _variant(self, count: int) -> tuple:
        if count in self._variants:
            return self._variants[count]
        an = self.an
        values = {p.symbol: p.value for p in an.mechanism.parameters}
        r = Reduced(an.kin, values, self.modules, count, symbolic=True)
        s = r._s
        outs = [v for a, j, *_ in r.segs for v in s["out"][a, j]]
        rows = sp.Matrix(r._rows(s))
        ins = plate_inputs(r)
        moving = sp.Matrix([v for a, j, *_ in r.segs for v in s["pf"][a, j]])
        part = partials(r, self.params, self.points)
        # the parameters renamed p_0, p_1, ... (as in generated code): a file's parameter may
        # be called like the equilibrium's own symbols (t, x_0, ...)
        rename = {q: sp.Symbol(f"p_{k}", real=True) for k, q in enumerate(self.params)}
        thetas = [r.th[a] for a in sorted(r.hinges)] + r.given_symbols
        args = [list(r.x), thetas, r.t, outs, list(rename.values())]
        modules = r._modules()  # taken after the derivation, as Reduced's
        exprs = [
            [sp.sympify(e).xreplace(rename) for e in m]
            for m in (
                jacobian(moving, r.x),
                jacobian(rows, r.x),
                jacobian(rows, outs),
                *(m for _, m in part.blocks()),
            )
        ]
        fn = lambdify(args, exprs, modules)
        ins_fn = lambdify(args[:3] + args[4:], [e.xreplace(rename) for e in ins], modules)
        # per half plate: a notch's relation is its own (Reduced.plate_fn), so are its ε partials
        eps_fn = []
        for terms in r.terms:
            symbols, eps = eps_relation(terms)
            eps_fn.append(sp.lambdify(symbols, eps, modules=modules))
        shapes = [(name, m.shape) for name, m in part.blocks()]
        found = self._variants[count] = (r, ins_fn, fn, eps_fn, shapes)
        return found

    def rates(
        self,
        x: np.ndarray,
        scale: np.ndarray,
        count: int,
        theta: Mapping[int, float],
        values: Sequence[float],
        theta_v: np.ndarray,
    ) -> np.ndarray:
        """dD/dv (2 n_P × n_v, the parameters' columns partial: no chain) at the solution x
        (scaled by `scale`, the solver's) of the variant with `count` half plates per plate, the
        rigid angles `theta`, parameter values `values` and dθ/dv `theta_v`
        (:func:`theta_rates`)."""
        r, ins_fn, fn, eps_fn, shapes = self._variant(count)
        n, ns, npar = r.size, len(r.segs), len(self.params)
        xs = [float(v) for v in np.asarray(x, dtype=float) * scale / r.scale] if n else []
        th = [float(v) for v in r.angles(theta)]
        # the plates' inputs first (the relation's outputs are arguments of the rest)
        ins = np.array(ins_fn(xs, th, 1.0, list(values)), dtype=float)
        outs, parts, eps = [], [], []
        for k in range(ns):
            i = [float(u) for u in ins[5 * k : 5 * k + 5]]
            v = r.plate_fn("plate4", k)(*i)  # a notch's own relation, else the uniform plate's
            outs += [float(u) for u in v[:3]]
            parts.append([float(u) for u in v[3:]])
            eps.append([float(u) for u in eps_fn[k](*i)])
        got = fn(xs, th, 1.0, outs, list(values))
        dins_x, jx, jo, *pieces = (np.array(g, dtype=float) for g in got)
        # the routine's blocks as a batch of one (symkin.physics.reduced_rates)
        blocks = {k: g.reshape(1, *shape) for (k, shape), g in zip(shapes, pieces)}
        jo = jo.reshape(1, n, 3 * ns)
        # J with the relation: ∂R/∂x + ∂R/∂o ∂rel/∂i ∂i/∂x
        di_x = _red_inputs_x(dins_x, n, ns, 1, 3)
        jac = jx.reshape(1, n, n) + jo @ _red_relation(parts, None, 1) @ di_x
        theta_v = np.asarray(theta_v, dtype=float)[None]
        rates = _red_sensitivity(jac, jo, parts, eps, dins_x, theta_v, npar, blocks, each=False)
        return rates[0]
