"""Deviation of the characteristic points at the three levels of CONTRACT §3, and its evaluation.

The compliant pose is written as the rigid one plus a difference: θ^c_a = θ^r_a + δ_a for every
hinge that is not an input. All levels are sympy expressions in the rigid angles θ, the
differences δ and the parameters:

- ``paper``: ΔX = Σ Δz_b over the direct path to the point's link, at the rigid angles (4.8).
- ``first_order``: δ from the loop closure linearised about the rigid pose (the rigid loop
  Jacobian times δ equals -Φ Δz), then ΔX = Σ δφ_i Rot(φ_i) J W_i + Σ Δz_b.
- ``exact``: δ from the full compliant loop closure, written as
  Σ_i Rot(φ_i)(Rot(δφ_i) - I) V_i + Φ Δz(θ + δ) = 0, which holds no rigid part that could cancel,
  solved by Newton with the closed-form Jacobian; ΔX = Σ_i Rot(φ_i)(Rot(δφ_i) - I) W_i + Σ Δz_b.

The `sympy` backend evaluates these expressions with mpmath at `dps` digits (40 by default), so
its float64 results are correctly rounded references for the generated evaluators.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from functools import cached_property, lru_cache

import mpmath
import sympy as sp

from . import expressions, special
from . import rigid as rigid_solver
from . import vectors as V
from .errors import AssemblyError, InputError
from .kinematics import Kinematics
from .mechanism import THETA
from .structure import Structure

LEVELS = ("paper", "first_order", "exact")
BACKENDS = ("sympy", "numpy", "c")


@dataclass(frozen=True)
class PointResult:
    rigid: tuple[float, float]
    compliant: tuple[float, float]
    deviation: tuple[float, float]


@dataclass(frozen=True)
class Evaluation:
    """One configuration evaluated at one level (CONTRACT §4 `eval` JSON via :meth:`as_json`)."""

    level: str
    backend: str
    inputs: dict[str, float]
    angles_rigid: dict[str, float]
    angles_compliant: dict[str, float]
    points: dict[str, PointResult]
    dyads: tuple[dict, ...] = field(default=())

    def as_json(self) -> dict:
        return {
            "level": self.level,
            "backend": self.backend,
            "inputs": dict(self.inputs),
            "angles": {"rigid": dict(self.angles_rigid),
                       "compliant": dict(self.angles_compliant)},
            "points": {name: {"rigid": list(p.rigid), "compliant": list(p.compliant),
                              "deviation": list(p.deviation)} for name, p in self.points.items()},
        }


class Analysis:
    """The symbolic deviation of a mechanism's points at every level, and its evaluation."""

    def __init__(self, structure: Structure, points: Sequence[str] | None = None,
                 plate=None) -> None:
        self.structure = structure
        self.mechanism = mech = structure.mechanism
        self.kin = kin = Kinematics(structure, plate)
        self.rigid = rigid_solver.solve(kin)
        names = [p.name for p in mech.points]
        for p in points or ():
            if p not in names:
                raise InputError(f"unknown point '{p}'", file=mech.path, entry="--points",
                                 hint="points: " + ", ".join(names))
        self.points = tuple(p for p in mech.points if points is None or p.name in points)
        self.link = {name: i for i, name in enumerate(structure.links)}
        self.params = tuple(p.symbol for p in mech.parameters)
        self.thetas = tuple(kin.theta[a] for a in range(1, structure.m + 1))
        self.deltas = tuple(kin.delta[a] for a in kin.unknowns)

    # -- symbolic pieces ---------------------------------------------------------------------------
    def compliant_angles(self) -> dict[int, sp.Expr]:
        kin = self.kin
        return {a: kin.theta[a] + (kin.delta[a] if a in kin.unknowns else 0) for a in kin.theta}

    def delta_phi(self, link: int) -> sp.Expr:
        """δφ_link = Σ of the paper-oriented δ over the direct path (inputs have δ = 0)."""
        kin = self.kin
        return sp.Add(*(kin.hinges[b].sign * kin.delta[b] for b in
                        self.structure.tree_path(link) if b in kin.unknowns))

    @cached_property
    def residual(self) -> sp.Matrix:
        """Exact compliant loop closure in δ: angular rows, then x, y rows per loop."""
        kin = self.kin
        angles = self.compliant_angles()
        rows: list[sp.Expr] = []
        for c in kin.chords:
            rows.append(kin.angular_closure(c, {a: angles[a] - kin.theta[a] for a in angles}))
            rigid_part = [V.rot(kin.phi(i), V.rot_minus_identity(self.delta_phi(i), w))
                          for i, w in kin.loop_weights(c).items()]
            rows.extend(V.add(*rigid_part, kin.loop_deviation(c, angles)))
        return sp.Matrix(rows)

    @cached_property
    def rigid_residual(self) -> sp.Matrix:
        """Rigid loop closure relative to the as-fabricated pose, in the rigid angles θ:
        Φ q and Σ_i (Rot(φ_i) - I) V_i per loop, exact there since the fabricated pose closes."""
        kin = self.kin
        rows: list[sp.Expr] = []
        for c in kin.chords:
            rows.append(kin.angular_closure(c))
            rows.extend(V.add(*(V.rot_minus_identity(kin.phi(i), w)
                                for i, w in kin.loop_weights(c).items())))
        return sp.Matrix(rows)

    @cached_property
    def jacobian(self) -> sp.Matrix:
        """∂F/∂δ of the exact closure, built from its structure rather than by differentiating:
        rigid part: column a gets s_a Rot(φ_i + δφ_i) J V_i from each link i whose path holds a;
        plates: Δz_b gives its model derivative (a = b) and J Δz_b (a on the path of P_b)."""
        return self._closure_jacobian(exact=True)

    @cached_property
    def linear_system(self) -> tuple[sp.Matrix, sp.Matrix]:
        """(A, r): the first-order closure A δ + r = 0; A is the rigid loop Jacobian at δ = 0,
        r = Φ Δz at the rigid pose."""
        rows_r: list[sp.Expr] = []
        for c in self.kin.chords:
            rows_r.append(sp.Integer(0))
            rows_r.extend(self.kin.loop_deviation(c))
        return self._closure_jacobian(exact=False), sp.Matrix(rows_r)

    def _closure_jacobian(self, exact: bool) -> sp.Matrix:
        kin, s = self.kin, self.structure
        col = {a: k for k, a in enumerate(kin.unknowns)}
        on_path = {i: set(s.tree_path(i)) & set(col) for i in range(s.n + 1)}
        angles = self.compliant_angles() if exact else kin.theta
        rows: list[list[sp.Expr]] = []
        for c in kin.chords:
            loop = s.loops[c - s.n - 1]
            angular = [sp.Integer(0)] * len(col)
            px, py = [sp.Integer(0)] * len(col), [sp.Integer(0)] * len(col)

            def add(a: int, vec: V.Vec) -> None:
                px[col[a]] += vec[0]
                py[col[a]] += vec[1]

            for b in range(1, s.m + 1):
                if loop[b - 1] and b in col:
                    angular[col[b]] += int(loop[b - 1]) * kin.hinges[b].sign
            for i, w in kin.loop_weights(c).items():
                turn = kin.phi(i) + (self.delta_phi(i) if exact else 0)
                d = V.rot(turn, V.perp(w))
                for a in on_path[i]:
                    add(a, V.scale(kin.hinges[a].sign, d))
            if exact:
                for b in range(1, s.m + 1):
                    coeff = int(loop[b - 1])
                    if not coeff:
                        continue
                    h = kin.hinges[b]
                    phi_p = kin.phi(h.P) + self.delta_phi(h.P)
                    dz = h.delta_z(angles[b], phi_p)
                    for a in on_path[h.P]:
                        add(a, V.scale(coeff * kin.hinges[a].sign, V.perp(dz)))
                    if b in col:
                        rate = V.add(V.scale(_theta_derivative(h.df).subs(THETA, angles[b]), h.u),
                                     V.scale(_theta_derivative(h.dg).subs(THETA, angles[b]),
                                             V.perp(h.u)))
                        add(b, V.scale(coeff * h.sign, V.rot(phi_p, rate)))
            rows.extend([angular, px, py])
        return sp.Matrix(rows) if rows else sp.zeros(0, len(col))

    def point_deviation(self, name: str, level: str) -> V.Vec:
        """ΔX of the named point at `level`, in θ (rigid angles), δ and the parameters."""
        kin = self.kin
        point = self.mechanism.point(name)
        k = self.link[point.link]
        if level == "paper":
            return kin.path_deviation(k)
        weights = kin.weights(k, point.at)
        if level == "first_order":
            lin = [V.scale(self.delta_phi(i), V.rot(kin.phi(i), V.perp(w)))
                   for i, w in weights.items()]
            return V.add(*lin, kin.path_deviation(k))
        exact = [V.rot(kin.phi(i), V.rot_minus_identity(self.delta_phi(i), w))
                 for i, w in weights.items()]
        return V.add(*exact, kin.path_deviation(k, self.compliant_angles()))

    def point_rigid(self, name: str) -> V.Vec:
        point = self.mechanism.point(name)
        return self.kin.rigid_position(self.link[point.link], point.at)

    # -- numbers ----------------------------------------------------------------------------------
    def _fn(self, key: str, exprs, args) -> object:
        """Lambdified (mpmath) function, cached per key."""
        cache = self.__dict__.setdefault("_lambdas", {})
        if key not in cache:
            cache[key] = sp.lambdify(args, exprs, modules=[special.mpmath_namespace(), "mpmath"])
        return cache[key]

    def parameter_values(self, overrides: Mapping[str, object] | None = None) -> dict:
        """Exact values of every parameter: overrides, then defaults re-evaluated in file order."""
        overrides = dict(overrides or {})
        known = {p.name for p in self.mechanism.parameters}
        for key in overrides:
            if key not in known:
                raise InputError(f"unknown parameter '{key}'", file=self.mechanism.path,
                                 entry="--param", hint="parameters: " + (", ".join(sorted(known))
                                                                          or "none"))
        values: dict[sp.Symbol, sp.Expr] = {}
        changed = False
        for p in self.mechanism.parameters:
            raw = overrides.get(p.name)
            if raw is not None:
                values[p.symbol] = _exact(raw, f"--param {p.name}", self.mechanism.path)
                changed = True
            elif not changed:
                values[p.symbol] = p.value
            else:
                # A default re-evaluated with overridden values: numerically (60 digits), so an
                # override can never make sympy build a huge exact number (e.g. l**n, n = 1e9).
                value = p.expr.evalf(60, subs=values)
                if not (value.is_real and value.is_finite):
                    raise InputError(f"parameter '{p.name}' = {p.expr} evaluates to {value} with "
                                     "the overrides", file=self.mechanism.path, entry="--param",
                                     hint="choose override values that keep it finite")
                values[p.symbol] = value
        return values

    def _inputs(self, inputs: Mapping[str, object]) -> dict[int, sp.Expr]:
        kin, mech = self.kin, self.mechanism
        names = {kin.hinges[a].name: a for a in kin.inputs}
        for key in inputs:
            if key not in names:
                raise InputError(f"'{key}' is not an input hinge", file=mech.path,
                                 entry="--input", hint="inputs: " + ", ".join(names))
        missing = [n for n in names if n not in inputs]
        if missing:
            raise InputError(f"no value for the input(s) {', '.join(missing)}", file=mech.path,
                             entry="--input", hint="give every input, e.g. --input "
                             + " --input ".join(f"{n}=0.1" for n in missing))
        return {names[k]: _exact(v, f"--input {k}", mech.path) for k, v in inputs.items()}

    def evaluate(self, inputs: Mapping[str, object], level: str = "exact",
                 params: Mapping[str, object] | None = None, dps: int = 40) -> Evaluation:
        """Evaluate one configuration with mpmath at `dps` digits (the `sympy` backend); the
        physical levels `loaded` and `equilibrium` are computed by symkin.physics."""
        from .physics import LEVELS as PHYSICAL

        if level in PHYSICAL:
            from .physics import evaluate as physical

            return physical(self, inputs, level, params)
        if level not in LEVELS:
            raise InputError(f"unknown level '{level}'", entry="--level",
                             hint="levels: " + ", ".join(LEVELS + PHYSICAL))
        given = self._inputs(inputs)
        exact_params = self.parameter_values(params)
        with mpmath.workdps(dps):
            pvals = [mpmath.mpf(sp.N(exact_params[s], dps + 5)) for s in self.params]
            ivals = {a: mpmath.mpf(sp.N(v, dps + 5)) for a, v in given.items()}
            theta, dyads = self._rigid_angles(pvals, ivals)
            self._check_limits(theta, ivals)
            delta = self._deltas(level, pvals, theta)
            self._check_limits({a: theta[a] + delta.get(a, 0) for a in theta}, ivals)
            args = [*self.params, *self.thetas, *self.deltas]
            values = [*pvals, *(theta[a] for a in sorted(theta)),
                      *(delta.get(a, mpmath.mpf(0)) for a in self.kin.unknowns)]
            points = {}
            for p in self.points:
                rig = self._fn(f"rigid:{p.name}", list(self.point_rigid(p.name)), args)(*values)
                dev = self._fn(f"{level}:{p.name}", list(self.point_deviation(p.name, level)),
                               args)(*values)
                points[p.name] = PointResult(
                    (float(rig[0]), float(rig[1])),
                    (float(rig[0] + dev[0]), float(rig[1] + dev[1])),
                    (float(dev[0]), float(dev[1])))
            names = {a: self.kin.hinges[a].name for a in self.kin.hinges}
            return Evaluation(
                level=level, backend="sympy",
                inputs={names[a]: float(ivals[a]) for a in sorted(ivals)},
                angles_rigid={names[a]: float(theta[a]) for a in sorted(theta)},
                angles_compliant={names[a]: float(theta[a] + delta.get(a, 0))
                                  for a in sorted(theta)},
                points=points, dyads=tuple(dyads))

    def _rigid_angles(self, pvals: list, ivals: dict) -> tuple[dict, list]:
        """Rigid hinge angles θ^r (file orientation) for the given inputs, and dyad states."""
        kin, sol = self.kin, self.rigid
        env = dict(zip(self.params, pvals))
        env.update({kin.theta[a]: v for a, v in ivals.items()})
        dyads = []
        if not sol.closed_form:
            return self._rigid_newton(pvals, ivals), dyads
        for symbol, expr in sol.assignments:
            fn = self._fn(f"assign:{symbol.name}", expr, sorted(expr.free_symbols, key=str))
            env[symbol] = fn(*(env[s] for s in sorted(expr.free_symbols, key=str)))
            dyad = next((d for d in sol.dyads if d.reach == symbol), None)
            if dyad is not None and env[symbol] < 0:
                raise self._cannot_close(dyad, ivals)
        for d in sol.dyads:
            dyads.append({"hinges": [kin.hinges[a].name for a in d.hinges],
                          "loop": kin.hinges[d.chord].name, "branch": d.branch,
                          "toggle_margin": float(env[d.margin])})
        phi = {}
        for link, expr in sol.phi.items():
            fn = self._fn(f"phi:{link}", expr, sorted(expr.free_symbols, key=str))
            phi[link] = fn(*(env[s] for s in sorted(expr.free_symbols, key=str)))
        theta = dict(ivals)
        for a in kin.unknowns:
            h = kin.hinges[a]
            theta[a] = _wrap(phi[h.M] - phi[h.P])
        return theta, dyads

    def _check_limits(self, theta: dict, ivals: dict) -> None:
        """A hinge model valid only for |θ| < limit (elastica_force) must not be driven past it."""
        for a, h in self.kin.hinges.items():
            if h.limit is not None and not abs(theta[a]) < mpmath.mpf(sp.N(h.limit, 30)):
                at = ", ".join(f"{self.kin.hinges[b].name}={float(v):g}"
                               for b, v in sorted(ivals.items()))
                raise AssemblyError(
                    f"{self.mechanism.path}: at {at} the hinge '{h.name}' would bend to "
                    f"{float(theta[a]):.6g} rad, beyond its model '{h.hinge.model}', which holds "
                    f"for |theta| < {float(sp.N(h.limit)):.6g} rad")

    def _cannot_close(self, dyad, ivals) -> AssemblyError:
        kin = self.kin
        at = ", ".join(f"{kin.hinges[a].name}={float(v):g}" for a, v in sorted(ivals.items()))
        from .reports import loop_text
        return AssemblyError(
            f"{self.mechanism.path}: the loop of hinge '{kin.hinges[dyad.chord].name}' "
            f"({loop_text(self.structure, dyad.chord)}) cannot close at {at}: the dyad "
            f"{'-'.join(kin.hinges[a].name for a in dyad.hinges)} is beyond its toggle position "
            "(outside the assembly range)")

    def _rigid_newton(self, pvals: list, ivals: dict) -> dict:
        """Rigid angles by Newton with continuation from the as-fabricated pose (non-dyad groups)."""
        kin = self.kin
        args = [*self.params, *self.thetas]
        f = self._fn("rigid_residual", list(self.rigid_residual), args)
        # ∂/∂θ of the rigid closure is A of the first-order system (the same structure).
        jac = self._fn("rigid_jacobian", self.linear_system[0].tolist(), args)
        steps = max(1, int(max([abs(v) for v in ivals.values()] + [0]) / 0.05) + 1)
        x = {a: mpmath.mpf(0) for a in kin.unknowns}
        for step in range(1, steps + 1):
            t = mpmath.mpf(step) / steps
            theta = {**{a: v * t for a, v in ivals.items()}, **x}
            x = self._newton(f, jac, pvals, theta, kin.unknowns, "rigid")
            if x is None:
                at = ", ".join(f"{kin.hinges[a].name}={float(v * t):g}" for a, v in
                               sorted(ivals.items()))
                raise AssemblyError(f"{self.mechanism.path}: the rigid loops cannot close at {at} "
                                    "(no convergence: outside the assembly range or at a toggle "
                                    "position)")
        return {**ivals, **{a: _wrap(v) for a, v in x.items()}}

    def _newton(self, f, jac, pvals: list, theta: dict, unknowns: Sequence[int],
                what: str) -> dict | None:
        """Newton iteration on the θ of `unknowns`; None when it does not converge."""
        x = mpmath.matrix([theta[a] for a in unknowns])
        tol = mpmath.mpf(10) ** (-mpmath.mp.dps + 6)
        for _ in range(60):
            values = [*pvals, *(theta[a] for a in sorted(theta))]
            try:
                step = mpmath.lu_solve(mpmath.matrix(jac(*values)), mpmath.matrix(f(*values)))
            except ZeroDivisionError:
                return None
            x = x - step
            for k, a in enumerate(unknowns):
                theta[a] = x[k]
            if mpmath.norm(step, mpmath.inf) <= tol * (1 + mpmath.norm(x, mpmath.inf)):
                return {a: x[k] for k, a in enumerate(unknowns)}
        return None

    def _deltas(self, level: str, pvals: list, theta: dict) -> dict:
        """δ of the non-input hinges: zero (paper), linear (first_order) or Newton (exact)."""
        if level == "paper" or not self.deltas:
            return {}
        args = [*self.params, *self.thetas]
        values = [*pvals, *(theta[a] for a in sorted(theta))]
        a_lin, r_lin = self.linear_system
        A = mpmath.matrix(self._fn("lin_A", a_lin.tolist(), args)(*values))
        r = mpmath.matrix(self._fn("lin_r", list(r_lin), args)(*values))
        try:
            d = -mpmath.lu_solve(A, r)
        except ZeroDivisionError:
            raise AssemblyError(f"{self.mechanism.path}: the mechanism is at a toggle position "
                                "(singular loop Jacobian) for these inputs") from None
        delta = {a: d[k] for k, a in enumerate(self.kin.unknowns)}
        if level == "first_order":
            return delta
        args_d = [*args, *self.deltas]
        f = self._fn("residual", list(self.residual), args_d)
        jac = self._fn("jacobian", self.jacobian.tolist(), args_d)
        x = mpmath.matrix([delta[a] for a in self.kin.unknowns])
        tight = mpmath.mpf(10) ** (-mpmath.mp.dps + 4)
        loose = mpmath.mpf(10) ** (-(mpmath.mp.dps // 2))
        previous = None
        for _ in range(40):
            vals = [*values, *x]
            try:
                step = mpmath.lu_solve(mpmath.matrix(jac(*vals)), mpmath.matrix(f(*vals)))
            except ZeroDivisionError:
                raise AssemblyError(f"{self.mechanism.path}: singular compliant loop Jacobian "
                                    "(toggle position) for these inputs") from None
            x = x - step
            size, change = mpmath.norm(x, mpmath.inf), mpmath.norm(step, mpmath.inf)
            # Converged, or stalled at the working precision's noise floor far below float64.
            if change <= tight * size or size == 0 or (
                    previous is not None and change >= previous / 2 and change <= loose * size):
                return {a: x[k] for k, a in enumerate(self.kin.unknowns)}
            previous = change
        raise AssemblyError(f"{self.mechanism.path}: the compliant loops did not converge "
                            "(no convergence in 40 Newton steps)")


@lru_cache(maxsize=None)
def _theta_derivative(expr: sp.Expr) -> sp.Expr:
    """d/dθ of a hinge model's Δf or Δg (its kernels differentiate into stable kernels)."""
    return sp.diff(expr, THETA)


def _wrap(angle):
    """Angle wrapped into (-π, π]: hinge angles are rotations from the as-fabricated pose."""
    two_pi = 2 * mpmath.pi
    return angle - two_pi * mpmath.nint(angle / two_pi)


def _exact(value: object, entry: str, file: str) -> sp.Expr:
    """An input or parameter value (number or whitelisted expression string) as an exact number."""
    try:
        expr = (expressions.parse(value, {}) if isinstance(value, str)
                else expressions.number(value))  # type: ignore[arg-type]
    except expressions.ExpressionError as exc:
        raise InputError(str(exc), file=file, entry=entry,
                         hint="give a number or an expression such as 10*deg") from None
    if not (expr.is_real and expr.is_finite):
        raise InputError(f"{value!r} is not a finite real number", file=file, entry=entry)
    return expr
