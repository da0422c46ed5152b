"""Independent high-precision reference solver for symkin mechanisms (a test oracle).

This module is test support, not a test file. It re-implements the mechanism semantics of
docs/file-format.md from scratch with mpmath, so that the tests can compare symkin's derivation with
it. symkin is used ONLY to parse the mechanism file (``symkin.load`` / ``symkin.loads``): the
exact sympy numbers of the file are evaluated here with mpmath. No graph theory, no incidence or
loop matrices, nothing from ``symkin.structure``: every link gets a full planar pose and every
hinge contributes its two constraint equations.

Formulation
-----------
Unknowns: for every moving link i the pose (x_i, y_i, φ_i) relative to the as-fabricated pose.
A point fixed in link i whose as-fabricated position is p0 sits at (x_i, y_i) + Rot(φ_i)·p0.
The ground link has the zero pose.

Hinge a joins P = links[0] and M = links[1]; u = (cos α, sin α), u⊥ = (−sin α, cos α) with α the
plate angle, l the plate length. P's clamp is cP0 = at − l/2·u (fixed in P), M's clamp is
cM0 = at + l/2·u (fixed in M). With θ = φ_M − φ_P and the hinge model (f(θ), g(θ)):

    [x_M, y_M] + Rot(φ_M)·cM0 − [x_P, y_P] − Rot(φ_P)·cP0 − Rot(φ_P)·(f(θ)·u + g(θ)·u⊥) = 0
                                                                                  (2 eq.)

and every input hinge adds φ_M − φ_P − q_a = 0 (1 eq.). For a mechanism whose number of inputs is
its mobility, 2m + #inputs = 3n: a square system, solved by Newton's method with an analytic
Jacobian and a dense LU with partial pivoting written here in plain mpmath.

Redundant loops
---------------
A parallelogram with a third parallel leg has 2m + #inputs > 3n (Grübler counts a structure)
but moves: some closure equations are dependent. Its mobility is 3n − rank(J_c), J_c the
Jacobian of the 2m closure equations (inputs left out) at the as-fabricated pose
(:func:`mobility`). When 2m + #inputs > 3n, the solver ranks the equations at the as-fabricated
pose (of the model being solved): it keeps every input row and picks 3n − #inputs independent
closure rows by a pivoted Gram–Schmidt (a rank-revealing QR of J_cᵀ, columns scaled to the
mechanism's size, rank threshold 10^-(dps/2)); it refuses the request when the inputs do not
fix the pose there (rank(J_c) ≠ 3n − #inputs, or an input dependent on the others). Newton then
runs on the square system of the kept rows, and after every continuation step the dropped
closure equations are evaluated: a step whose dropped residuals do not vanish (to about half
the digits in the middle of the path, dps − 8 at the end) is rejected, so an inconsistent
redundancy (a third leg of another length, which locks the rigid linkage) ends in
:class:`ReferenceAssemblyError` rather than an answer. ``solve`` reports the dropped residuals.
A square system takes exactly the former path (all rows, in order).

Branch (assembly mode)
----------------------
The solution is the one reached continuously from the as-fabricated pose (all poses zero, all
θ = 0, docs/file-format.md). ``solve`` steps the inputs along the straight line from 0 to the
targets in increments of at most ``max_step`` rad (largest input change per step, default
0.05), starting each Newton run from a first-order (tangent) predictor built from the previous
solution. A step is rejected, and halved, when Newton does not converge, when the correction
from the predictor is large, or when the sign of det(J) changes (the path crossed a singular,
i.e. toggle/fold, configuration, where the branch would otherwise be switched silently). When
the step falls below ``min_step`` a :class:`ReferenceAssemblyError` is raised: the input is
outside the assembly range reached from the as-fabricated pose, or the path runs through a
singular configuration.

Precision
---------
Everything runs at ``dps`` decimal digits (``mpmath.workdps``). Intermediate continuation steps
are converged to about dps/2 digits, the final point to about dps − 6 digits (Newton step norm
below 10^-(dps-6), positions scaled by the mechanism's characteristic length). Hinge-model
formulas that cancel for small θ (circular arc derivatives, expression models) are evaluated
internally with extra digits. ``deviation`` computes rigid and compliant positions and subtracts
them; the subtraction loses about log10(|position| / |deviation|) digits. It therefore checks the
number of digits lost after the first solve and, when fewer than ``min_digits`` (default 20)
significant digits of the deviation would remain, repeats both solves at
dps = digits lost + min_digits + 10 (e.g. tiny plates or tiny angles). The returned ``digits``
field is the estimated number of correct significant digits of the smallest nonzero deviation.

Results contain mpmath ``mpf`` values: do further arithmetic on them under
``mpmath.workdps(result["dps"])`` to keep their precision. Input values may be int, str
(decimal, parsed exactly at the working precision), sympy numbers, fractions or mpf; a Python
float is taken as its exact binary value (0.2 → 0.2000000000000000111...), so pass "0.2" or
sympy.Rational(1, 5) for the decimal number.
"""

from __future__ import annotations

import math
from fractions import Fraction

import mpmath
import sympy as sp

from symkin.model.hinges import PLATE_LENGTH, THETA
from symkin.model.mechanism import Mechanism

__all__ = [
    "OVERRIDE_MODELS",
    "Reference",
    "ReferenceAssemblyError",
    "ReferenceModelError",
    "load_unchecked",
    "mobility",
]

#: models accepted by ``model_override`` (prbm with its default "force" parameters)
OVERRIDE_MODELS = ("rigid", "circular_arc", "small_deflection", "prbm", "elastica_force")
PRBM_FORCE = (sp.Rational("0.8517"), sp.Rational("1.2385"))
#: largest accepted Newton correction after the predictor, in scaled units (length/scale, rad)
MAX_JUMP = 0.1


class ReferenceAssemblyError(RuntimeError):
    """The mechanism cannot be assembled at the requested inputs along the continuation path."""


class ReferenceModelError(NotImplementedError):
    """The reference does not evaluate this hinge model (or not at this angle)."""


# --------------------------------------------------------------------------------------------
# numbers
# --------------------------------------------------------------------------------------------
def _to_mpf(value, dps: int):
    """An exact-ish number (sympy, str, int, Fraction, float, mpf) as an mpf at the current prec."""
    if isinstance(value, mpmath.mpf):
        return +value
    if isinstance(value, bool):
        raise TypeError("a boolean is not a number")
    if isinstance(value, (int, float, str)):
        return mpmath.mpf(value)
    if isinstance(value, Fraction):
        return mpmath.mpf(value.numerator) / value.denominator
    expr = sp.sympify(value)
    if expr.free_symbols:
        raise ValueError(f"not a number: {expr} (free symbols {expr.free_symbols})")
    if expr.is_Rational:
        return mpmath.mpf(int(expr.p)) / int(expr.q)
    v = sp.N(expr, dps + 15)
    if v == 0:
        return mpmath.mpf(0)
    if not (v.is_real and v.is_finite):
        raise ValueError(f"not a finite real number: {expr} = {v}")
    return mpmath.mpf(sp.Float(v, dps + 15))


def _extra_digits(theta) -> int:
    """Digits lost to cancellation of order θ² in the small-angle formulas."""
    if theta == 0:
        return 0
    return max(0, int(-2 * mpmath.log10(abs(theta)))) + 5


# --------------------------------------------------------------------------------------------
# hinge models: each returns (f, g, df/dθ, dg/dθ) at the current precision
# --------------------------------------------------------------------------------------------
class _Model:
    name = "?"

    def __call__(self, theta):  # pragma: no cover - interface
        raise NotImplementedError


class _Rigid(_Model):
    name = "rigid"

    def __init__(self, length):
        self.l = length

    def __call__(self, t):
        h = self.l / 2
        c, s = mpmath.cos(t), mpmath.sin(t)
        return h * (1 + c), h * s, -h * s, h * c


class _CircularArc(_Model):
    name = "circular_arc"

    def __init__(self, length):
        self.l = length

    def __call__(self, t):
        l = self.l
        dps = mpmath.mp.dps
        if t == 0:
            return +l, mpmath.mpf(0), mpmath.mpf(0), l / 2
        if abs(t) < mpmath.mpf(10) ** (-dps):
            # Taylor: sinθ/θ = 1 − θ²/6 + …, (1 − cosθ)/θ = θ/2 − θ³/24 + …
            t2 = t * t
            return l * (1 - t2 / 6), l * (t / 2 - t * t2 / 24), -l * t / 3, l * (0.5 - t2 / 8)
        with mpmath.extradps(_extra_digits(t)):
            s, c = mpmath.sin(t), mpmath.cos(t)
            h2 = 2 * mpmath.sin(t / 2) ** 2  # 1 − cos θ without cancellation
            f = l * s / t
            g = l * h2 / t
            df = l * (t * c - s) / (t * t)
            dg = l * (t * s - h2) / (t * t)
        return +f, +g, +df, +dg


class _Prbm(_Model):
    name = "prbm"

    def __init__(self, length, gamma, c_theta):
        self.l, self.gamma, self.c = length, gamma, c_theta

    def __call__(self, t):
        l, gm, c = self.l, self.gamma, self.c
        big = t / c
        s, co = mpmath.sin(big), mpmath.cos(big)
        f = l * (1 - gm * 2 * mpmath.sin(big / 2) ** 2)  # l(1 − γ(1 − cos Θ))
        g = gm * l * s
        return f, g, -gm * l * s / c, gm * l * co / c


class _SmallDeflection(_Model):
    name = "small_deflection"

    def __init__(self, length):
        self.l = length

    def __call__(self, t):
        return +self.l, self.l * t / 2, mpmath.mpf(0), self.l / 2


class _ElasticaForce(_Model):
    """Cantilever of length l clamped along x, loaded at its tip by a force of fixed direction
    perpendicular to the undeformed plate; θ is the tip angle.

    Elastica: EI φ'' = −F cos φ, φ(0) = 0, φ'(l) = 0 (free end, no moment). First integral
    (l = 1): φ'² = 2α (sin θ − sin φ), α = F l²/EI. Substituting sin φ = S − t², S = sin θ,
    t = √S·u (Bisshopp–Drucker's quadrature, made regular) gives for |θ| < π/2

        J0(S) = ∫₀¹ du / √(1 − S²(1 − u²)²),   J1(S) = ∫₀¹ (1 − u²) du / √(1 − S²(1 − u²)²),
        f/l = x_tip/l = 1 / J0,   g/l = y_tip/l = S·J1 / J0,   α = 2 S J0².

    (Small θ: f → l, g → 2lθ/3, the linear cantilever.) Derivatives use dJk/dS under the integral.
    The tests cross-check this against a direct shooting integration of the ODE.
    """

    name = "elastica_force"

    def __init__(self, length):
        self.l = length

    def __call__(self, t):
        if abs(t) >= 1.5:
            raise ReferenceModelError(
                f"elastica_force reference covers |theta| < 1.5 rad, got {mpmath.nstr(t, 8)}"
            )
        with mpmath.extradps(10):
            S = mpmath.sin(t)
            S2 = S * S

            def w(u):
                return 1 - u * u

            def q(u):
                return 1 - S2 * w(u) ** 2

            j0 = mpmath.quad(lambda u: 1 / mpmath.sqrt(q(u)), [0, 1])
            j1 = mpmath.quad(lambda u: w(u) / mpmath.sqrt(q(u)), [0, 1])
            dj0 = mpmath.quad(lambda u: S * w(u) ** 2 / q(u) ** 1.5, [0, 1])
            dj1 = mpmath.quad(lambda u: S * w(u) ** 3 / q(u) ** 1.5, [0, 1])
            c = mpmath.cos(t)
            f = self.l / j0
            g = self.l * S * j1 / j0
            df = -self.l * dj0 / j0**2 * c
            dg = self.l * (j1 / j0 + S * (dj1 * j0 - j1 * dj0) / j0**2) * c
        return +f, +g, +df, +dg


class _Expr(_Model):
    """User expressions f(θ, l), g(θ, l): evaluated with enough extra digits to absorb the
    cancellation of the usual small-angle forms (up to order θ²); θ = 0 is replaced by a tiny
    angle 10^-(dps+5) (the expressions may divide by θ)."""

    name = "expr"

    def __init__(self, f, g):
        self.exprs = (f, g, sp.diff(f, THETA), sp.diff(g, THETA))
        self.funcs = [sp.lambdify(THETA, e, modules="mpmath") for e in self.exprs]

    def __call__(self, t):
        dps = mpmath.mp.dps
        if abs(t) < mpmath.mpf(10) ** (-(dps + 5)):
            t = mpmath.mpf(10) ** (-(dps + 5)) * (1 if t >= 0 else -1)
        extra = 3 * _extra_digits(t) // 2 + 20
        with mpmath.extradps(extra):
            out = []
            for func in self.funcs:
                v = mpmath.mpmathify(func(mpmath.mpf(t)))
                if isinstance(v, mpmath.mpc):
                    if abs(v.imag) > abs(v) * mpmath.mpf(10) ** (-dps):
                        raise ReferenceModelError(
                            f"expr model gives a complex value at theta = {mpmath.nstr(t, 8)}"
                        )
                    v = v.real
                if not mpmath.isfinite(v):
                    raise ReferenceModelError(
                        f"expr model is not finite at theta = {mpmath.nstr(t, 8)}"
                    )
                out.append(v)
        return tuple(+v for v in out)


# --------------------------------------------------------------------------------------------
# the reference mechanism
# --------------------------------------------------------------------------------------------
class _Hinge:
    """A hinge's numbers at one precision."""

    __slots__ = ("cm0", "cp0", "input", "length", "m", "model", "name", "p", "u", "v")


class Reference:
    """Independent mpmath solver of a symkin Mechanism (see the module docstring).

    ``Reference(mech, params=None)``: ``params`` optionally overrides parameter defaults by name
    (numbers or expression strings over earlier parameters); later parameters that depend on an
    overridden one follow it.
    """

    def __init__(
        self, mech: Mechanism, params: dict | None = None, *, check_count: bool = True
    ) -> None:
        self.mech = mech
        self.values = self._parameter_values(params or {})
        self.ground = mech.ground
        self.moving = [lk.name for lk in mech.links if lk.name != mech.ground]
        self.col = {name: 3 * i for i, name in enumerate(self.moving)}
        self.inputs = tuple(h.name for h in mech.hinges if h.input)
        self.n_unknowns = 3 * len(self.moving)
        self.n_equations = 2 * len(mech.hinges) + len(self.inputs)
        # fewer equations than unknowns: never enough inputs; more: a redundant closure is
        # accepted, the rank is checked per model at the as-fabricated pose (_rows)
        if check_count and self.n_equations < self.n_unknowns:
            raise ReferenceAssemblyError(
                f"{self.n_equations} equations (2 per hinge + 1 per input) for "
                f"{self.n_unknowns} unknowns (3 per moving link): the number of inputs is not "
                "the mobility"
            )
        self._cache: dict = {}
        self._row_cache: dict = {}

    # -- numbers ------------------------------------------------------------------------------
    def _parameter_values(self, params: dict) -> dict:
        known = {p.name for p in self.mech.parameters}
        for name in params:
            if name not in known:
                raise KeyError(f"unknown parameter {name!r}; known: {sorted(known)}")
        names = {p.name: p.symbol for p in self.mech.parameters}
        values: dict = {}
        for p in self.mech.parameters:
            if p.name in params:
                raw = params[p.name]
                if isinstance(raw, float):
                    raw = repr(raw)  # the decimal the user wrote, like the file reader
                if isinstance(raw, str):
                    expr = sp.sympify(raw, locals=names, rational=True)
                else:
                    expr = sp.sympify(raw)
            else:
                expr = p.expr
            values[p.symbol] = sp.sympify(expr).subs(values)
        return values

    def _num(self, expr, dps):
        return _to_mpf(sp.sympify(expr).subs(self.values), dps)

    def _model(self, h, model: str, length, dps):
        if model == "rigid":
            return _Rigid(length)
        if model == "circular_arc":
            return _CircularArc(length)
        if model == "small_deflection":
            return _SmallDeflection(length)
        if model == "prbm":
            gamma = h.param("gamma") if h.model == "prbm" else None
            c_theta = h.param("c_theta") if h.model == "prbm" else None
            gamma = PRBM_FORCE[0] if gamma is None else gamma
            c_theta = PRBM_FORCE[1] if c_theta is None else c_theta
            return _Prbm(length, self._num(gamma, dps), self._num(c_theta, dps))
        if model == "elastica_force":
            return _ElasticaForce(length)
        if model == "expr":
            lval = sp.sympify(h.length).subs(self.values)
            subs = {**self.values, PLATE_LENGTH: lval}
            return _Expr(sp.sympify(h.param("f")).subs(subs), sp.sympify(h.param("g")).subs(subs))
        raise ReferenceModelError(
            f"hinge {h.name!r}: the reference solver does not support model {model!r}"
        )

    def _setup(self, model_override, dps):
        if model_override is not None and model_override not in OVERRIDE_MODELS:
            raise ValueError(f"model_override must be one of {OVERRIDE_MODELS}")
        key = (model_override, dps)
        if key in self._cache:
            return self._cache[key]
        hinges = []
        for h in self.mech.hinges:
            r = _Hinge()
            r.name, r.p, r.m, r.input = h.name, h.links[0], h.links[1], h.input
            alpha = self._num(h.plate_angle, dps)
            length = self._num(h.length, dps)
            ax, ay = self._num(h.at[0], dps), self._num(h.at[1], dps)
            r.length = length
            r.u = (mpmath.cos(alpha), mpmath.sin(alpha))
            r.v = (-r.u[1], r.u[0])
            r.cp0 = (ax - length / 2 * r.u[0], ay - length / 2 * r.u[1])
            r.cm0 = (ax + length / 2 * r.u[0], ay + length / 2 * r.u[1])
            r.model = self._model(h, model_override or h.model, length, dps)
            hinges.append(r)
        points = {
            p.name: (p.link, (self._num(p.at[0], dps), self._num(p.at[1], dps)))
            for p in self.mech.points
        }
        coords = [abs(c) for r in hinges for c in (*r.cp0, *r.cm0)]
        coords += [abs(c) for _, xy in points.values() for c in xy]
        scale = max(coords + [r.length for r in hinges]) or mpmath.mpf(1)
        self._cache[key] = (hinges, points, scale)
        return self._cache[key]

    def _row_labels(self) -> list[str]:
        """Names of the rows of _system: 'H.x', 'H.y' per hinge, then 'H.input' per input."""
        out = [f"{h.name}.{c}" for h in self.mech.hinges for c in ("x", "y")]
        return out + [f"{h.name}.input" for h in self.mech.hinges if h.input]

    def _scaled_rows(self, J, scale):
        """J with rows divided by the size and position columns multiplied by it: positions in
        units of the mechanism's size, so the rank test compares like with like."""
        return [[a if j % 3 != 2 else a / scale for j, a in enumerate(row)] for row in J]

    @staticmethod
    def _pivoted_rows(rows, forced, candidates, tol):
        """Rank-revealing selection (pivoted modified Gram–Schmidt on the rows): the `forced`
        row indices first, then repeatedly the candidate with the largest component outside the
        span chosen so far, while that component exceeds `tol` times the row's norm. Returns
        (chosen indices in order, indices of forced rows found dependent)."""
        basis: list = []

        def residual(row):
            r = list(row)
            for _ in range(2):  # twice: re-orthogonalise (Kahan's rule)
                for b in basis:
                    d = mpmath.fsum(x * y for x, y in zip(r, b))
                    r = [x - d * y for x, y in zip(r, b)]
            return r

        def add(r):
            nrm = mpmath.sqrt(mpmath.fsum(x * x for x in r))
            basis.append([x / nrm for x in r])

        chosen, bad = [], []
        for i in forced:
            r = residual(rows[i])
            norm_i = mpmath.sqrt(mpmath.fsum(x * x for x in rows[i]))
            if mpmath.sqrt(mpmath.fsum(x * x for x in r)) <= tol * norm_i:
                bad.append(i)
                continue
            add(r)
            chosen.append(i)
        left = [i for i in candidates if mpmath.fsum(x * x for x in rows[i]) > 0]
        while left:
            best, best_val, best_r = None, mpmath.mpf(0), None
            for i in left:
                r = residual(rows[i])
                norm_i = mpmath.sqrt(mpmath.fsum(x * x for x in rows[i]))
                val = mpmath.sqrt(mpmath.fsum(x * x for x in r)) / norm_i
                if val > best_val:
                    best, best_val, best_r = i, val, r
            if best is None or best_val <= tol:
                break
            add(best_r)
            chosen.append(best)
            left.remove(best)
        return chosen, bad

    def _constraint_rank(self, model_override, dps) -> int:
        """Rank of the 2m closure rows (inputs left out) at the as-fabricated pose."""
        with mpmath.workdps(dps):
            hinges, _, scale = self._setup(model_override, dps)
            X = [mpmath.mpf(0)] * self.n_unknowns
            q = {k: mpmath.mpf(0) for k in self.inputs}
            _, J = self._system(X, q, hinges)
            rows = self._scaled_rows(J, scale)
            n_c = 2 * len(hinges)
            tol = mpmath.mpf(10) ** (-(dps // 2))
            chosen, _ = self._pivoted_rows(rows, [], range(n_c), tol)
            return len(chosen)

    def _rows(self, model_override, dps):
        """(kept row indices in _system order, dropped row indices) for this model. A square
        system keeps every row; an over-determined one is reduced at the as-fabricated pose
        (module docstring, "Redundant loops")."""
        key = (model_override, dps)
        if key not in self._row_cache:
            with mpmath.workdps(dps):
                self._row_cache[key] = self._select_rows(model_override, dps)
        return self._row_cache[key]

    def _select_rows(self, model_override, dps):
        n_rows = self.n_equations
        if n_rows == self.n_unknowns:
            out = (list(range(n_rows)), [])
        else:
            hinges, _, scale = self._setup(model_override, dps)
            X = [mpmath.mpf(0)] * self.n_unknowns
            q = {k: mpmath.mpf(0) for k in self.inputs}
            _, J = self._system(X, q, hinges)
            rows = self._scaled_rows(J, scale)
            n_c = 2 * len(hinges)
            tol = mpmath.mpf(10) ** (-(dps // 2))
            chosen, bad = self._pivoted_rows(rows, range(n_c, n_rows), range(n_c), tol)
            rank_c = self._constraint_rank(model_override, dps)
            mob = self.n_unknowns - rank_c
            labels = self._row_labels()
            which = f"{self.mech.name} ({model_override or 'file models'})"
            if bad:
                raise ReferenceAssemblyError(
                    f"{which}: the input(s) {[labels[i] for i in bad]} are fixed by the other "
                    "inputs at the as-fabricated pose: not independent generalized coordinates"
                )
            if len(chosen) != self.n_unknowns or mob != len(self.inputs):
                raise ReferenceAssemblyError(
                    f"{which}: mobility 3n - rank(J) = {self.n_unknowns} - {rank_c} = {mob} at "
                    f"the as-fabricated pose but {len(self.inputs)} input(s): the number of "
                    "inputs is not the mobility"
                )
            kept = sorted(chosen)
            out = (kept, [i for i in range(n_rows) if i not in set(kept)])
        return out

    # -- equations ----------------------------------------------------------------------------
    def _pose(self, X, link):
        if link == self.ground:
            return mpmath.mpf(0), mpmath.mpf(0), mpmath.mpf(0)
        c = self.col[link]
        return X[c], X[c + 1], X[c + 2]

    def _system(self, X, q, hinges):
        """Residual F(X; q) and Jacobian dF/dX (lists of mpf) at the current precision."""
        n = self.n_unknowns
        F = []
        J = []
        for r in hinges:
            xp, yp, pp = self._pose(X, r.p)
            xm, ym, pm = self._pose(X, r.m)
            theta = pm - pp
            f, g, df, dg = r.model(theta)
            cp, sp_ = mpmath.cos(pp), mpmath.sin(pp)
            cm, sm = mpmath.cos(pm), mpmath.sin(pm)
            # plate-frame vectors in P's as-fabricated orientation
            w = (f * r.u[0] + g * r.v[0], f * r.u[1] + g * r.v[1])
            dw = (df * r.u[0] + dg * r.v[0], df * r.u[1] + dg * r.v[1])
            # Rot(φ)·a = (c a0 − s a1, s a0 + c a1);   d/dφ Rot(φ)·a = (−s a0 − c a1, c a0 − s a1)
            rm_cm = (cm * r.cm0[0] - sm * r.cm0[1], sm * r.cm0[0] + cm * r.cm0[1])
            rp_cp = (cp * r.cp0[0] - sp_ * r.cp0[1], sp_ * r.cp0[0] + cp * r.cp0[1])
            rp_w = (cp * w[0] - sp_ * w[1], sp_ * w[0] + cp * w[1])
            rp_dw = (cp * dw[0] - sp_ * dw[1], sp_ * dw[0] + cp * dw[1])
            F.append(xm + rm_cm[0] - xp - rp_cp[0] - rp_w[0])
            F.append(ym + rm_cm[1] - yp - rp_cp[1] - rp_w[1])
            row_x = [mpmath.mpf(0)] * n
            row_y = [mpmath.mpf(0)] * n
            if r.m != self.ground:
                c = self.col[r.m]
                row_x[c] += 1
                row_y[c + 1] += 1
                # ∂/∂φ_M: d Rot(φM)cM0 − Rot(φP) dw (θ depends on φ_M with +1)
                row_x[c + 2] += -rm_cm[1] - rp_dw[0]
                row_y[c + 2] += rm_cm[0] - rp_dw[1]
            if r.p != self.ground:
                c = self.col[r.p]
                row_x[c] -= 1
                row_y[c + 1] -= 1
                # ∂/∂φ_P: −d Rot(φP)cP0 − d Rot(φP) w + Rot(φP) dw (θ depends on φ_P with −1)
                row_x[c + 2] += rp_cp[1] + rp_w[1] + rp_dw[0]
                row_y[c + 2] += -rp_cp[0] - rp_w[0] + rp_dw[1]
            J.append(row_x)
            J.append(row_y)
        for r in hinges:
            if not r.input:
                continue
            pp = self._pose(X, r.p)[2]
            pm = self._pose(X, r.m)[2]
            F.append(pm - pp - q[r.name])
            row = [mpmath.mpf(0)] * n
            if r.m != self.ground:
                row[self.col[r.m] + 2] += 1
            if r.p != self.ground:
                row[self.col[r.p] + 2] -= 1
            J.append(row)
        return F, J

    @staticmethod
    def _lu_solve(J, b):
        """Solve J x = b by Gaussian elimination with partial pivoting; also return sign(det J).
        Raise ZeroDivisionError when J is numerically singular."""
        n = len(b)
        A = [list(row) + [b[i]] for i, row in enumerate(J)]
        big = max((abs(a) for row in J for a in row), default=mpmath.mpf(0))
        tiny = big * mpmath.mpf(10) ** (-(mpmath.mp.dps - 5))
        sign = 1
        for k in range(n):
            piv = max(range(k, n), key=lambda i: abs(A[i][k]))
            if abs(A[piv][k]) <= tiny:
                raise ZeroDivisionError("singular Jacobian")
            if piv != k:
                A[k], A[piv] = A[piv], A[k]
                sign = -sign
            if A[k][k] < 0:
                sign = -sign
            pivot_row = A[k]
            inv = 1 / pivot_row[k]
            for i in range(k + 1, n):
                row = A[i]
                factor = row[k] * inv
                if factor:
                    for j in range(k + 1, n + 1):
                        row[j] -= factor * pivot_row[j]
        x = [mpmath.mpf(0)] * n
        for i in range(n - 1, -1, -1):
            s = A[i][n]
            row = A[i]
            for j in range(i + 1, n):
                s -= row[j] * x[j]
            x[i] = s / row[i]
        return x, sign

    def _norm(self, dX, scale):
        """Scaled max-norm: positions divided by the characteristic length, angles as is."""
        out = mpmath.mpf(0)
        for i, d in enumerate(dX):
            out = max(out, abs(d) / scale if i % 3 != 2 else abs(d))
        return out

    def _reduced(self, X, q, hinges, rows):
        """_system restricted to the kept rows (all of them for a square system)."""
        F, J = self._system(X, q, hinges)
        if rows is None or len(rows) == len(F):
            return F, J
        return [F[i] for i in rows], [J[i] for i in rows]

    def _newton(self, X, q, hinges, scale, tol, max_iter=30, rows=None):
        """Newton from X; return (X, sign det J at the solution) or None if it fails.
        `rows`: the kept rows of a redundant system (None: all)."""
        X = list(X)
        last = None
        for _ in range(max_iter):
            try:
                F, J = self._reduced(X, q, hinges, rows)
                dX, sign = self._lu_solve(J, [-v for v in F])
            except (ZeroDivisionError, ReferenceModelError):
                return None
            step = self._norm(dX, scale)
            if step > 1:  # a jump of a full mechanism size or a radian
                return None
            X = [a + b for a, b in zip(X, dX)]
            if step <= tol:
                return X, sign
            if last is not None and step > last / 4:
                if step <= tol * 10**6:
                    return X, sign  # at the rounding-noise floor (ill-conditioned J)
                if step > last:
                    return None  # diverging
            last = step
        return None

    # -- public API ---------------------------------------------------------------------------
    def _targets(self, inputs):
        unknown = [k for k in inputs if k not in self.inputs]
        if unknown:
            raise KeyError(f"{unknown} are not input hinges; inputs: {list(self.inputs)}")
        return {name: _to_mpf(inputs.get(name, 0), mpmath.mp.dps) for name in self.inputs}

    def solve(
        self,
        inputs: dict,
        model_override: str | None = None,
        dps: int = 40,
        max_step: float = 0.05,
        min_step: float = 1e-6,
    ) -> dict:
        """Solve the mechanism at the given input angles (hinge name → θ, missing inputs = 0).

        Returns a dict::

            {"model": model_override or "file",
             "dps": dps,
             "inputs": {hinge: q},                      # the targets as mpf
             "poses": {link: (x, y, phi)},              # every link, ground (0, 0, 0) included
             "angles": {hinge: theta},                  # θ_a = φ_M − φ_P for every hinge
             "points": {point: (x, y)},                 # absolute position of every [[point]]
             "steps": number of accepted continuation steps,
             "dropped": {row: residual}}                # redundant closure rows not solved for
                                                        # ('H.x' / 'H.y'), empty when square

        Raises ReferenceAssemblyError when the continuation from the as-fabricated pose cannot
        reach the inputs, ReferenceModelError for an unsupported hinge model.
        """
        with mpmath.workdps(dps):
            target = self._targets(inputs)
            hinges, points, scale = self._setup(model_override, dps)
            rows, dropped = self._rows(model_override, dps)
            n = self.n_unknowns
            X = [mpmath.mpf(0)] * n
            names = list(self.inputs)
            q = {k: mpmath.mpf(0) for k in names}
            tol_mid = mpmath.mpf(10) ** (-(dps // 2))
            tol_end = mpmath.mpf(10) ** (-(dps - 6))
            # dropped rows of a redundant closure must vanish with the kept ones (lengths, so
            # relative to the mechanism's size): loosely mid-path, to dps − 8 digits at the end
            drop_mid = scale * mpmath.mpf(10) ** (-(dps // 2 - 4))
            drop_end = scale * mpmath.mpf(10) ** (-(dps - 8))

            def dropped_residual(X, q):
                if not dropped:
                    return mpmath.mpf(0)
                F, _ = self._system(X, q, hinges)
                return max(abs(F[i]) for i in dropped)

            res = self._newton(X, q, hinges, scale, tol_end, rows=rows)
            if res is None:
                raise ReferenceAssemblyError(
                    f"{self.mech.name}: the as-fabricated pose is singular or not a solution "
                    "(Jacobian singular at all θ = 0)"
                )
            X, sign0 = res
            h = mpmath.mpf(max_step)
            t = mpmath.mpf(0)  # path parameter: q = t * target
            span = max([abs(v) for v in target.values()] + [mpmath.mpf(0)])
            steps = 0
            while t < 1:
                dt = min(1 - t, h / span) if span > 0 else 1 - t
                t_new = t + dt if t + dt < 1 - mpmath.mpf(10) ** (-(dps - 2)) else mpmath.mpf(1)
                q_new = {k: target[k] * t_new for k in names}
                final = t_new == 1
                # tangent predictor: J dX = (dq on the input rows)
                pred = X
                try:
                    F, J = self._reduced(X, q_new, hinges, rows)
                    dX, _ = self._lu_solve(J, [-v for v in F])
                    pred = [a + b for a, b in zip(X, dX)]
                except (ZeroDivisionError, ReferenceModelError):
                    pred = X
                res = self._newton(
                    pred, q_new, hinges, scale, tol_end if final else tol_mid, rows=rows
                )
                # reject: no convergence, det(J) changed sign (crossed a singular/toggle
                # configuration: the branch would switch), or a large correction (a jump);
                # for a redundant closure also dropped equations that do not hold
                ok = (
                    res is not None
                    and res[1] == sign0
                    and self._norm([a - b for a, b in zip(res[0], pred)], scale) <= MAX_JUMP
                )
                bad_drop = None
                if ok and dropped:
                    bad_drop = dropped_residual(res[0], q_new)
                    ok = bad_drop <= (drop_end if final else drop_mid)
                if not ok:
                    h /= 2
                    if h < min_step:
                        where = ", ".join(f"{k}={mpmath.nstr(target[k] * t, 10)}" for k in names)
                        why = (
                            "out of the assembly range, a toggle/singular configuration, or "
                            "Newton not converging"
                        )
                        if bad_drop is not None:
                            why = (
                                f"the redundant closure equations dropped at the as-fabricated "
                                f"pose do not hold (residual {mpmath.nstr(bad_drop, 5)}): the "
                                "redundant loops are inconsistent"
                            )
                        raise ReferenceAssemblyError(
                            f"{self.mech.name} ({model_override or 'file models'}): cannot "
                            f"continue from the as-fabricated pose to the inputs "
                            f"{ {k: mpmath.nstr(v, 10) for k, v in target.items()} }; stuck at "
                            f"{where} ({why})"
                        )
                    continue
                X, t = res[0], t_new
                steps += 1
                h = min(h * 2, mpmath.mpf(max_step))
            F, _ = self._system(X, target, hinges)
            resid = max([abs(v) for v in F] + [mpmath.mpf(0)])
            if resid > scale * mpmath.mpf(10) ** (-(dps - 8)):
                raise ReferenceAssemblyError(
                    f"{self.mech.name}: residual {mpmath.nstr(resid, 5)} "
                    "after Newton, not converged"
                )
            labels = self._row_labels()
            drop_res = {labels[i]: F[i] for i in dropped}
            poses = {lk.name: self._pose(X, lk.name) for lk in self.mech.links}
            angles = {r.name: poses[r.m][2] - poses[r.p][2] for r in hinges}
            pts = {}
            for name, (link, (px, py)) in points.items():
                x, y, phi = poses[link]
                c, s = mpmath.cos(phi), mpmath.sin(phi)
                pts[name] = (x + c * px - s * py, y + s * px + c * py)
            return {
                "model": model_override or "file",
                "dps": dps,
                "inputs": dict(target),
                "poses": poses,
                "angles": angles,
                "points": pts,
                "steps": steps,
                "dropped": drop_res,
            }

    def deviation(
        self, inputs: dict, dps: int = 40, min_digits: int = 20, max_dps: int = 1000
    ) -> dict:
        """Rigid (every hinge an ideal revolute) and compliant (file models) solutions at the same
        inputs, and the deviation compliant − rigid of every point.

        Returns::

            {"dps": digits used, "digits": estimated correct significant digits of the smallest
             nonzero deviation, "inputs": {hinge: q},
             "angles": {"rigid": {hinge: θ}, "compliant": {hinge: θ}},
             "points": {P: {"rigid": (x, y), "compliant": (x, y), "deviation": (dx, dy)}},
             "rigid": <solve() result>, "compliant": <solve() result>}

        When the first solve at ``dps`` leaves fewer than ``min_digits`` digits in a deviation,
        both solves are repeated at dps = lost + min_digits + 10 (see the module docstring).
        """
        while True:
            with mpmath.workdps(dps):
                rigid = self.solve(inputs, model_override="rigid", dps=dps)
                comp = self.solve(inputs, dps=dps)
                _, _, scale = self._setup(None, dps)
                pts = {}
                lost = 0
                for name in rigid["points"]:
                    r, c = rigid["points"][name], comp["points"][name]
                    d = (c[0] - r[0], c[1] - r[1])
                    pts[name] = {"rigid": r, "compliant": c, "deviation": d}
                    mag = max(abs(d[0]), abs(d[1]))
                    size = max(abs(r[0]), abs(r[1]), scale)
                    if mag > 0:
                        lost = max(lost, math.ceil(float(mpmath.log10(size / mag))))
                digits = dps - 6 - lost
                if digits >= min_digits or dps >= max_dps:
                    return {
                        "dps": dps,
                        "digits": digits,
                        "inputs": rigid["inputs"],
                        "angles": {"rigid": rigid["angles"], "compliant": comp["angles"]},
                        "points": pts,
                        "rigid": rigid,
                        "compliant": comp,
                    }
                dps = min(max_dps, lost + min_digits + 10)

    def fg(self, hinge: str, theta, model_override: str | None = None, dps: int = 40):
        """(f, g, f', g') of one hinge's model at θ (for diagnostics and tests)."""
        with mpmath.workdps(dps):
            hinges, _, _ = self._setup(model_override, dps)
            r = next(r for r in hinges if r.name == hinge)
            return r.model(_to_mpf(theta, dps))


# --------------------------------------------------------------------------------------------
# mobility and files that Grübler's count refuses
# --------------------------------------------------------------------------------------------
def mobility(
    mech: Mechanism, params: dict | None = None, model_override: str | None = "rigid", dps: int = 40
) -> tuple[int, int]:
    """(Grübler's 3n − 2m, 3n − rank J_c): J_c the Jacobian of the 2m closure equations (inputs
    left out) at the as-fabricated pose, by default of the rigid linkage (pins at the plate
    midpoints; ``model_override=None`` takes the file's models). The second number is the real
    (first-order) mobility: a parallelogram with a third parallel leg has (0, 1)."""
    ref = Reference(mech, params, check_count=False)
    grubler = 3 * len(ref.moving) - 2 * len(mech.hinges)
    return grubler, ref.n_unknowns - ref._constraint_rank(model_override, dps)


def load_unchecked(path) -> Mechanism:
    """Parse a mechanism file with symkin, also when its inputs do not number Grübler's mobility
    (a redundant closure such as a three-leg stage, which symkin of this time refuses): only the
    mobility rule is lifted, every other rule of the file format still applies."""
    import symkin
    import symkin.model.reader as parser

    try:
        return symkin.load(path)
    except symkin.InputError as exc:
        reader = getattr(parser, "_Reader", None)
        if "mobility" not in str(exc) or not hasattr(reader, "check_mobility"):
            raise
    original = reader.check_mobility
    reader.check_mobility = lambda self, mech: None
    try:
        return symkin.load(path)
    finally:
        reader.check_mobility = original
