"""Independent physical reference solver for compliant mechanisms (a test oracle).

Test support, not a test file. It solves the physics that symkin's ``equilibrium`` level claims to
solve (docs/physics.md), from scratch, with mpmath: every non-``rigid``
hinge is a geometrically exact, inextensible Euler–Bernoulli plate (elastica) clamped in its two
links and straight as fabricated; ``rigid`` hinges are ideal pins at ``at``; loads are dead loads;
input hinges have their angle prescribed by an actuator whose torque is an unknown. symkin is used
only to read the mechanism's geometry (``symkin.load``/``loads``); the rigid pin linkage used for
the deviation comes from the independent kinematic oracle ``tests/reference_solver.py``.

Conventions (docs/file-format.md, docs/physics.md)
----------------------------
Hinge a joins P = links[0] and M = links[1]; its plate runs from P's clamp ``at − l/2·u`` to M's
clamp ``at + l/2·u``, u = (cos plate_angle, sin plate_angle). θ_a = φ_M − φ_P. A link's pose
(x, y, φ) maps an as-fabricated point p to (x, y) + Rot(φ)·p. Per plate we report the force
(frame axes) and the moment (about the M clamp, CCW) that link M exerts on the plate at its M end:
a plate bent by a pure moment through θ > 0 has moment +EI·θ/l. For a pin, "force" is the force
link M exerts on link P through the pin and "moment" is 0. The actuator torque τ of an input
hinge acts CCW on M and CW on P (so τ = +EI·θ/l holds a lone plate at θ). Deviation of a point =
compliant − rigid position, the rigid mechanism being the pin linkage with revolutes at the plate
midpoints and the same input angles.

Two independent methods
-----------------------
(a) :class:`Equilibrium` — shooting. Per plate, in σ = s/l ∈ [0, 1], with ψ the tangent angle,
    f = F·l²/EI the scaled force that M exerts on the plate (constant along it) and μ = l·ψ':
        ψ'' = f_x sin ψ − f_y cos ψ,   r' = l (cos ψ, sin ψ),   moment m = EI·μ/l,
    (from m' = −t × F). The ODE is integrated by a Taylor-series method in fixed-point integer
    arithmetic (exact-to-the-last-bit convolutions, adaptive order ≤ 60 and step), together with
    its variational equations, so Newton gets an exact Jacobian. Unknowns: every moving link's
    pose, every plate's (μ(0), f_x, f_y), every pin's force, every actuator torque; equations:
    every plate's clamp closure at M (position and angle), every pin's closure, every input angle,
    and the force and moment balance of every moving link (a mixed, force-based formulation).
(b) :class:`ChainEquilibrium` — energy. Every plate is a chain of N rigid segments of length
    h = l/N (absolute angles ψ_1..ψ_N) with rotational springs EI/h between segments and 2EI/h to
    the clamps (half cells). The total potential (springs − work of the dead loads) is made
    stationary under the closure constraints (plate chains, pins, input angles) by Lagrange
    multipliers (which are the plate forces, pin forces and actuator torques); Newton on the KKT
    system with each plate's tridiagonal block eliminated. The chain is the Strang splitting of
    (a)'s ODE, so its error expands in even powers of h: Richardson extrapolation over
    N = N0·2^j removes h², h⁴, ... Stability is checked on the KKT inertia (the reduced stiffness
    must stay positive definite), not on a determinant sign: the two methods share no mechanics.

Continuation and stability
--------------------------
Both start from the as-fabricated, unloaded pose (all zero) and scale inputs and loads together,
q = λ·q_target, loads = λ·load_factor·loads, λ: 0 → 1, with a tangent predictor, a Newton
corrector and step halving. (a) rejects a step where sign det J changes, (b) one where the KKT
inertia changes (the equilibrium stopped being a strict minimum); after too many halvings an
:class:`InstabilityError` names the load factor reached and, when one plate carries most of the
critical mode, the hinge. :class:`ContinuationError` is raised when Newton fails for another reason
(e.g. an input beyond the assembly range).

Precision
---------
The deviation is ~1e-6..1e-10 of the positions, so both methods work at d digits with
d = (digits lost between position and deviation) + ``min_digits`` + 10, found after a first solve
at 30 digits. (a) reports as ``error_estimate`` the relative change of the deviation between d and
d + 10 digits (the returned values are the d + 10 ones); (b) the difference of the last two
Richardson extrapolants. Values are mpmath ``mpf``; numbers given (angles, stiffness, loads) may
be str (expressions over the file parameters for stiffness and loads), int, sympy or float (taken
as the decimal it prints as, 0.1 → 1/10, like the file reader).

Use
---
    mech = symkin.load("examples/four_bar.toml")
    eq = Equilibrium(mech, stiffness=(210e9, 5e-3, "l/10"),           # E, width, thickness
                     loads=[point_load(mech, "C", ("0.5", "-1"))], params={"l": "1e-3"})
    res = eq.solve({"A0": "0.1"})             # or ChainEquilibrium(...) with the same arguments
    res["points"]["C"]["deviation"], res["hinges"]["A"]["moment"], res["energy"]

An input given as None is released (no actuator; its rigid reference stays at 0): a cantilever.
Plates that stretch and shear (Reissner's beam) are in tests/reference_beams.py, which reuses this
module: ``shoot`` takes their gam = EI/(κGA·l²) beside eps, and each plate's gam is read from the
owner's ``_shear_ratio`` (absent here: 0).

Validity and measured accuracy
------------------------------
(a) and (b) agree on the deviation to 1e-27..5e-20 (relative) on the four-bar and six-bar
examples with l/L from 1e-3 to 0.05 and inputs 0.01..0.5 rad, with or without loads, and to 6e-17
at l/L = 0.2 (tests/test_reference_physics.py lists the cases). Both reproduce the
Bisshopp–Drucker and Mattiasson cantilever tables to their last digit. Cost: 0.2–2 s per solve
for (a), 1–4 s for (b). Plain shooting gets ill-conditioned (its Jacobian grows like
exp(√α)) for plate load indices α = |F|·l²/EI beyond ~100 and slows down there; mechanism plates
carry α ~ θ·l/L ≪ 1, the cantilever tables go to α = 10.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from operator import mul
from typing import Any

import mpmath
import sympy as sp
from reference_solver import Reference

__all__ = [
    "ChainEquilibrium",
    "ContinuationError",
    "Equilibrium",
    "InstabilityError",
    "Load",
    "PhysicsError",
    "point_load",
]


class PhysicsError(RuntimeError):
    """Base class of the physical reference's failures."""


class ContinuationError(PhysicsError):
    """The continuation from the as-fabricated pose could not reach the requested state."""

    def __init__(self, message: str, load_factor: float):
        super().__init__(message)
        self.load_factor = load_factor


class InstabilityError(ContinuationError):
    """The equilibrium path lost stability (limit point or bifurcation) before λ = 1."""

    def __init__(self, message: str, load_factor: float, hinge: str | None):
        super().__init__(message, load_factor)
        self.hinge = hinge


@dataclass(frozen=True)
class Load:
    """A dead load on ``link``: ``force`` (frame axes, N) at the as-fabricated point ``at`` and a
    CCW ``moment`` (N·m). Numbers may be str/int/sympy expressions over the file parameters."""

    link: str
    at: tuple
    force: tuple
    moment: Any = 0


def point_load(mech, point: str, force: Sequence, moment: Any = 0) -> Load:
    """A :class:`Load` at a named [[point]] of the mechanism."""
    p = mech.point(point)
    return Load(p.link, tuple(p.at), tuple(force), moment)


# ------------------------------------------------------------------------------------------
# numbers and geometry
# ------------------------------------------------------------------------------------------
def _mpf(expr, dps: int) -> mpmath.mpf:
    """A sympy number (no free symbols) or int/str as an mpf at ``dps`` digits."""
    if isinstance(expr, mpmath.mpf):
        return +expr
    if isinstance(expr, float):
        expr = repr(expr)  # the decimal the user wrote, like the file reader
    if isinstance(expr, (int, str)):
        return mpmath.mpf(expr)
    expr = sp.sympify(expr)
    if expr.free_symbols:
        raise ValueError(f"not a number: {expr}")
    if expr.is_Rational:
        return mpmath.mpf(int(expr.p)) / int(expr.q)
    return mpmath.mpf(sp.Float(sp.N(expr, dps + 15), dps + 15))


def _rot(phi, p):
    c, s = mpmath.cos(phi), mpmath.sin(phi)
    return (c * p[0] - s * p[1], s * p[0] + c * p[1])


def _cross(a, b):
    return a[0] * b[1] - a[1] * b[0]


class _Plate:
    __slots__ = (
        "EI",
        "alpha",
        "at",
        "cm0",
        "cp0",
        "eps",
        "gam",
        "input",
        "l",
        "m",
        "name",
        "p",
        "pin",
        "u",
    )


class _Mech:
    """The mechanism's numbers at one precision (geometry, stiffness, loads)."""

    def __init__(self, owner: _Base, dps: int):
        with mpmath.workdps(dps):
            self.dps = dps
            num = owner._num
            self.hinges: list[_Plate] = []
            for h in owner.mech.hinges:
                r = _Plate()
                r.name, r.p, r.m, r.input = h.name, h.links[0], h.links[1], h.input
                r.alpha = num(h.plate_angle, dps)
                r.l = num(h.length, dps)
                r.u = (mpmath.cos(r.alpha), mpmath.sin(r.alpha))
                r.at = (num(h.at[0], dps), num(h.at[1], dps))
                r.cp0 = (r.at[0] - r.l / 2 * r.u[0], r.at[1] - r.l / 2 * r.u[1])
                r.cm0 = (r.at[0] + r.l / 2 * r.u[0], r.at[1] + r.l / 2 * r.u[1])
                r.pin = h.model == "rigid"
                r.EI = None if r.pin else num(owner._ei[h.name], dps)
                # EI/(EA·l²) = t²/(12 l²) of an extensible plate, 0 when inextensible
                r.eps = (
                    num(owner._ea_ratio[h.name], dps) / r.l**2
                    if owner.extensible and not r.pin
                    else 0
                )
                # EI/(κGA·l²) of a plate that shears (tests/reference_beams.py), else 0
                shear = getattr(owner, "_shear_ratio", {}).get(h.name)
                r.gam = num(shear, dps) / r.l**2 if shear is not None and not r.pin else 0
                self.hinges.append(r)
            self.plates = [r for r in self.hinges if not r.pin]
            self.pins = [r for r in self.hinges if r.pin]
            self.points = {
                p.name: (p.link, (num(p.at[0], dps), num(p.at[1], dps))) for p in owner.mech.points
            }
            self.loads = [
                (
                    ld.link,
                    (num(ld.at[0], dps), num(ld.at[1], dps)),
                    (num(ld.force[0], dps), num(ld.force[1], dps)),
                    num(ld.moment, dps),
                )
                for ld in owner.loads
            ]
            coords = [abs(c) for r in self.hinges for c in (*r.cp0, *r.cm0)]
            coords += [abs(c) for _, xy in self.points.values() for c in xy]
            self.scale = max(coords + [r.l for r in self.hinges])
            if self.plates:
                self.force_ref = max(r.EI / (r.l * self.scale) for r in self.plates)
                self.torque_ref = max(r.EI / r.l for r in self.plates)
            else:
                self.force_ref = self.torque_ref = mpmath.mpf(1)


class _Base:
    """Shared front end of both methods: parameters, stiffness, loads, inputs, rigid reference and
    the deviation. The mechanics live in the subclasses."""

    method = "?"

    def __init__(
        self,
        mech,
        stiffness: Mapping | tuple,
        loads: Sequence = (),
        params: Mapping | None = None,
        extensible: bool = False,
    ) -> None:
        self.mech = mech
        self.extensible = extensible
        self.kinematic = Reference(mech, params)  # parameter values + the rigid pin linkage
        self.values = self.kinematic.values
        self.ground = mech.ground
        self.moving = [lk.name for lk in mech.links if lk.name != mech.ground]
        self.link_index = {name: i for i, name in enumerate(self.moving)}
        names = {p.name: p.symbol for p in mech.parameters}
        if isinstance(stiffness, tuple):
            stiffness = {h.name: stiffness for h in mech.hinges if h.model != "rigid"}
        self._ei, self._ea_ratio = {}, {}
        for h in mech.hinges:
            if h.model == "rigid":
                continue
            if h.name not in stiffness:
                raise KeyError(f"hinge {h.name!r} is a plate: give its (E, width, thickness)")
            E, b, t = (self._expr(v, names) for v in stiffness[h.name])
            self._ei[h.name] = E * b * t**3 / 12
            self._ea_ratio[h.name] = t**2 / 12  # EI/EA
        unknown = set(stiffness) - set(self._ei)
        if unknown:
            raise KeyError(f"stiffness given for {sorted(unknown)}, which are not plates")
        self.loads = []
        for ld in loads:
            ld = ld if isinstance(ld, Load) else Load(*ld)
            if ld.link not in self.link_index and ld.link != self.ground:
                raise KeyError(f"load on unknown link {ld.link!r}")
            # every number as an exact sympy value (floats as the decimal they print as)
            self.loads.append(
                Load(
                    ld.link,
                    tuple(self._expr(v, names) for v in ld.at),
                    tuple(self._expr(v, names) for v in ld.force),
                    self._expr(ld.moment, names),
                )
            )
        self._cache: dict[int, _Mech] = {}

    def _expr(self, value, names):
        if isinstance(value, float):
            value = repr(value)
        expr = (
            sp.sympify(value, locals=names, rational=True)
            if isinstance(value, str)
            else sp.sympify(value)
        )
        return expr.subs(self.values)

    def _num(self, expr, dps):
        return _mpf(sp.sympify(expr).subs(self.values), dps)

    def numbers(self, dps: int) -> _Mech:
        if dps not in self._cache:
            self._cache[dps] = _Mech(self, dps)
        return self._cache[dps]

    def _targets(self, inputs: Mapping, dps: int) -> dict:
        """Input hinge → target angle (mpf), or None for a released (unactuated) input."""
        inputs = dict(inputs)
        names = [h.name for h in self.mech.hinges if h.input]
        unknown = [k for k in inputs if k not in names]
        if unknown:
            raise KeyError(f"{unknown} are not input hinges; inputs: {names}")
        with mpmath.workdps(dps):
            return {
                k: (None if inputs.get(k, 0) is None else _mpf(inputs.get(k, 0), dps))
                for k in names
            }

    # -- the rigid reference and the deviation --------------------------------------------
    def _rigid(self, targets: dict, dps: int) -> dict:
        q = {k: (0 if v is None else v) for k, v in targets.items()}
        return self.kinematic.solve(q, model_override="rigid", dps=dps)

    def _point_positions(self, poses: dict, nums: _Mech) -> dict:
        out = {}
        for name, (link, p) in nums.points.items():
            x, y, phi = poses[link]
            r = _rot(phi, p)
            out[name] = (x + r[0], y + r[1])
        return out

    def _deviation(self, comp_points: dict, rigid: dict) -> tuple[dict, int]:
        """Points' rigid, compliant and deviation entries and the digits lost in the subtraction."""
        nums = self.numbers(mpmath.mp.dps)
        pts, lost = {}, 0
        for name, c in comp_points.items():
            r = rigid["points"][name]
            d = (c[0] - r[0], c[1] - r[1])
            pts[name] = {"rigid": r, "compliant": c, "deviation": d}
            mag = mpmath.sqrt(d[0] ** 2 + d[1] ** 2)
            if mag > 0:
                lost = max(lost, math.ceil(float(mpmath.log10(nums.scale / mag))))
        return pts, lost


# ------------------------------------------------------------------------------------------
# (a) shooting: Taylor series in fixed point
# ------------------------------------------------------------------------------------------
def _fix(x, bits: int) -> int:
    return int(mpmath.nint(mpmath.ldexp(x, bits)))


def _unfix(n: int, bits: int) -> mpmath.mpf:
    return mpmath.ldexp(mpmath.mpf(n), -bits)


def _horner(cs: list, h: int, bits: int) -> int:
    acc = 0
    for c in reversed(cs):
        acc = ((acc * h) >> bits) + c
    return acc


def shoot(
    u0, mu0, fx, fy, bits: int, jac: bool = True, energy: bool = False, eps=0, kmax: int = 60, gam=0
) -> tuple:
    """Integrate one plate over σ ∈ [0, 1] from ψ(0) = u0, ψ'(0) = mu0, x = y = 0:

        ψ'' = (1 + e − g)(f_x sin ψ − f_y cos ψ),
        (x, y)' = (1 + e)(cos ψ, sin ψ) + g_s·(−sin ψ, cos ψ),

    e = eps·n_t the axial strain N/EA (n_t = f_x cos ψ + f_y sin ψ, eps = EI/(EA·l²); 0:
    inextensible), g_s = gam·n_s the shear strain Q/(κGA) (n_s = −f_x sin ψ + f_y cos ψ,
    gam = EI/(κGA·l²); 0: shear-rigid) and g = gam·n_t (Reissner's plane beam; ψ is the angle
    of the cross-section). Returns ((ψ(1), x(1), y(1), ψ'(1)), J, ∫(ψ'² + eps·n_t² + gam·n_s²)
    dσ or None, steps), J[i][j] the derivative of output i with respect to (u0, mu0, fx, fy)[j]
    (variational equations). Numbers are fixed-point integers scaled by 2^bits inside (exact
    convolutions, one rounding per coefficient); the truncation of every series is kept below
    2^-(bits-12).
    """
    one = 1 << bits
    tolbits = bits - 12
    U, MU, X, Y = _fix(u0, bits), _fix(mu0, bits), 0, 0
    FX, FY = _fix(fx, bits), _fix(fy, bits)
    EPS = _fix(eps, bits) if eps else 0
    GAM = _fix(gam, bits) if gam else 0
    KAP = EPS - GAM
    # strain terms, with cc = cos²ψ, sc = sin ψ cos ψ and κ = eps − gam: ψ'' gets
    # κ[(fx² − fy²) sc + fx fy (1 − 2 cc)], x' gets κ(fx cc + fy sc) + gam·fx,
    # y' gets κ(fx sc − fy cc) + eps·fy
    A2 = (FX * FX - FY * FY) >> bits
    B2 = (FX * FY) >> bits
    nd = 4 if jac else 0
    V = [one if p == 0 else 0 for p in range(nd)]  # ∂ψ/∂p
    VP = [one if p == 1 else 0 for p in range(nd)]  # ∂ψ'/∂p
    DX, DY = [0] * nd, [0] * nd
    W = 0  # ∫ψ'² + ε n_t² dσ
    sig, steps = 0, 0

    def conv(a, b, k):
        return sum(map(mul, a[: k + 1], b[k::-1])) >> bits

    while sig < one:
        H = one - sig
        lh = math.log2(H) - bits
        cu, su = mpmath.cos(_unfix(U, bits)), mpmath.sin(_unfix(U, bits))
        u, C, S = [U, MU], [_fix(cu, bits)], [_fix(su, bits)]
        cc, sc = [], []  # series of cos²ψ and sin ψ cos ψ
        ju = [0, MU]  # j·u_j
        xs, ys = [X], [Y]
        v = [[V[p], VP[p]] for p in range(nd)]
        dxs = [[DX[p]] for p in range(nd)]
        dys = [[DY[p]] for p in range(nd)]
        k = 0
        while True:
            # order k gives u_{k+2}, x_{k+1}, y_{k+1}, C_{k+1}, S_{k+1} (and the variations)
            d = (k + 1) * (k + 2) << bits
            delta = one if k == 0 else 0
            num = FX * S[k] - FY * C[k]
            dx_k, dy_k = C[k] << bits, S[k] << bits
            if EPS or GAM:
                cc.append(conv(C, C, k))
                sc.append(conv(S, C, k))
                num += KAP * ((A2 * sc[k] + B2 * (delta - 2 * cc[k])) >> bits)
                dx_k += KAP * ((FX * cc[k] + FY * sc[k]) >> bits) + GAM * FX * delta // one
                dy_k += KAP * ((FX * sc[k] - FY * cc[k]) >> bits) + EPS * FY * delta // one
            u.append(num // d)
            ju.append((k + 2) * u[k + 2])
            xs.append(dx_k // ((k + 1) << bits))
            ys.append(dy_k // ((k + 1) << bits))
            for p in range(nd):
                vp = v[p]
                P = conv(C, vp, k)  # (cos ψ · v)_k
                Q = conv(S, vp, k)  # (sin ψ · v)_k
                num = FX * P + FY * Q
                ddx, ddy = -Q << bits, P << bits
                if p == 2:
                    num += S[k] << bits
                elif p == 3:
                    num -= C[k] << bits
                if EPS or GAM:
                    Pc = conv(cc, vp, k)  # (cos²ψ · v)_k
                    Ps = conv(sc, vp, k)  # (sin ψ cos ψ · v)_k
                    dsc = 2 * Pc - vp[k]  # ∂(sin ψ cos ψ) = (2cos²ψ − 1) v
                    dcc = -2 * Ps  # ∂(cos²ψ) = −2 sin ψ cos ψ v
                    e = A2 * dsc - 2 * B2 * dcc
                    ex = FX * dcc + FY * dsc
                    ey = FX * dsc - FY * dcc
                    if p == 2:  # ∂/∂fx of A2 = 2fx, B2 = fy
                        e += 2 * FX * sc[k] + FY * (delta - 2 * cc[k])
                        ex += cc[k] << bits
                        ey += sc[k] << bits
                        ddx += GAM * delta  # ∂(gam·fx)/∂fx
                    elif p == 3:
                        e += -2 * FY * sc[k] + FX * (delta - 2 * cc[k])
                        ex += sc[k] << bits
                        ey -= cc[k] << bits
                        ddy += EPS * delta  # ∂(eps·fy)/∂fy
                    num += (KAP * e) >> bits
                    ddx += (KAP * ex) >> bits
                    ddy += (KAP * ey) >> bits
                vp.append(num // d)
                dxs[p].append(ddx // ((k + 1) << bits))
                dys[p].append(ddy // ((k + 1) << bits))
            k += 1
            # (sin ψ)' = cos ψ · ψ',  (cos ψ)' = −sin ψ · ψ'
            C.append(-(sum(map(mul, ju[1 : k + 1], reversed(S))) // (k << bits)))
            S.append(sum(map(mul, ju[1 : k + 1], reversed(C[:k]))) // (k << bits))
            if k >= 4:
                worst = -math.inf
                for seq in (u, C, S, *v):
                    for j in (len(seq) - 1, len(seq) - 2):
                        if seq[j]:
                            worst = max(worst, abs(seq[j]).bit_length() - bits + j * lh)
                if worst < -tolbits or k >= kmax:
                    break
        h = H
        if k >= kmax:
            # shorten the step so that the last terms fall below the tolerance
            lg = math.inf
            for seq in (u, C, S, *v):
                for j in range(len(seq) - 3, len(seq)):
                    if seq[j]:
                        lg = min(lg, (-tolbits - (abs(seq[j]).bit_length() - bits)) / j)
            h = min(H, int(2.0 ** (lg + bits) / 2))
            if h < one >> 20:
                raise ContinuationError("plate integration: step size collapsed", math.nan)
        Un = _horner(u, h, bits)
        MUn = _horner(ju[1:], h, bits)
        X, Y = _horner(xs, h, bits), _horner(ys, h, bits)
        for p in range(nd):
            vp = v[p]
            V[p] = _horner(vp, h, bits)
            VP[p] = _horner([j * vp[j] for j in range(1, len(vp))], h, bits)
            DX[p], DY[p] = _horner(dxs[p], h, bits), _horner(dys[p], h, bits)
        if energy:
            mu = ju[1:]
            n = len(mu)
            sq = [conv(mu, mu, i) for i in range(n)]
            if EPS or GAM:
                # cos²ψ, sin ψ cos ψ to the order of C (higher terms are below the tolerance);
                # eps·n_t² + gam·n_s² = κ(fx² cc + 2 fx fy sc − fy² cc) + gam·fx² + eps·fy²
                while len(cc) < len(C):
                    cc.append(conv(C, C, len(cc)))
                    sc.append(conv(S, C, len(sc)))
                for i in range(min(n, len(C))):
                    q2 = (
                        (FX * FX >> bits) * cc[i] + 2 * B2 * sc[i] - (FY * FY >> bits) * cc[i]
                    ) >> bits
                    if i == 0:
                        q2 = KAP * q2 + GAM * (FX * FX >> bits) + EPS * (FY * FY >> bits)
                    else:
                        q2 = KAP * q2
                    sq[i] += q2 >> bits
            W += _horner([0] + [sq[i] // (i + 1) for i in range(n)], h, bits)
        U, MU = Un, MUn
        sig += h
        steps += 1
    out = tuple(_unfix(z, bits) for z in (U, X, Y, MU))
    J = [[_unfix(z[p], bits) for p in range(nd)] for z in (V, DX, DY, VP)]
    return out, J, (_unfix(W, bits) if energy else None), steps


# ------------------------------------------------------------------------------------------
# dense LU in mpmath (partial pivoting), reusable for several right-hand sides
# ------------------------------------------------------------------------------------------
class _LU:
    """LU factors of a square mpf matrix; ``sign`` is sign(det); singular → ZeroDivisionError."""

    def __init__(self, A: list) -> None:
        n = len(A)
        A = [list(row) for row in A]
        big = max((abs(a) for row in A for a in row), default=mpmath.mpf(0))
        tiny = big * mpmath.mpf(10) ** (-(mpmath.mp.dps - 3))
        perm = list(range(n))
        sign = 1
        for k in range(n):
            piv = max(range(k, n), key=lambda i: abs(A[i][k]))
            if abs(A[piv][k]) <= tiny:
                raise ZeroDivisionError("singular matrix")
            if piv != k:
                A[k], A[piv] = A[piv], A[k]
                perm[k], perm[piv] = perm[piv], perm[k]
                sign = -sign
            pr = A[k]
            if pr[k] < 0:
                sign = -sign
            inv = 1 / pr[k]
            for i in range(k + 1, n):
                row = A[i]
                f = row[k] * inv
                row[k] = f
                if f:
                    for j in range(k + 1, n):
                        row[j] -= f * pr[j]
        self.A, self.perm, self.sign, self.n = A, perm, sign, n

    def solve(self, b: list) -> list:
        A, n = self.A, self.n
        y = [b[p] for p in self.perm]
        for i in range(n):
            row = A[i]
            s = y[i]
            for j in range(i):
                s -= row[j] * y[j]
            y[i] = s
        for i in range(n - 1, -1, -1):
            row = A[i]
            s = y[i]
            for j in range(i + 1, n):
                s -= row[j] * y[j]
            y[i] = s / row[i]
        return y


# ------------------------------------------------------------------------------------------
# continuation driver shared in shape (not in mechanics) by both methods
# ------------------------------------------------------------------------------------------
class _Continuation:
    """λ from 0 to 1 with a tangent predictor, Newton corrector and step halving.

    The subclass provides ``_newton(state, lam, tol) -> (state, info) | None``,
    ``_tangent(state, lam) -> delta`` (d state/dλ, or None), ``_stability(info)`` (a value that
    must not change along the path), ``_distance(a, b)`` (scaled size of a correction) and
    ``_critical(state, lam)`` (name of the hinge carrying the critical mode, or None).
    """

    max_dlam: float = 1.0
    min_dlam: float = 1e-7
    max_attempts: int = 400

    def _continue(self, state, span: float, has_loads: bool, tol_mid):
        lam = mpmath.mpf(0)
        res = self._newton(state, lam, tol_mid)
        if res is None:
            raise ContinuationError(
                f"{self.mech.name}: the as-fabricated pose is not a regular "
                "solution (singular at λ = 0)",
                0.0,
            )
        state, info = res
        mark0 = self._stability(info)
        self._check_start(info)
        dmax = min(self.max_dlam, 0.1 / span if span > 0 else 1.0)
        if has_loads:
            dmax = min(dmax, 0.25)
        dlam = mpmath.mpf(dmax)
        steps = rejected = 0
        last_reason = ""
        grow = True
        while lam < 1:
            if steps + rejected >= self.max_attempts:
                raise ContinuationError(
                    f"{self.mech.name}: continuation too slow, λ = {float(lam):.9g} after "
                    f"{steps + rejected} steps (last rejection: {last_reason or 'none'})",
                    float(lam),
                )
            new = min(mpmath.mpf(1), lam + dlam)
            tan = self._tangent(state, lam, info)
            pred = state if tan is None else [a + (new - lam) * b for a, b in zip(state, tan)]
            res = self._newton(pred, new, tol_mid)
            reason = ""
            if res is None:
                reason = "Newton did not converge"
            elif self._stability(res[1]) != mark0:
                reason = "stability changed (" + self._describe(res[1], mark0) + ")"
            elif self._distance(res[0], pred) > 0.2:
                reason = "corrector jumped"
            if reason:
                rejected += 1
                last_reason = reason
                dlam /= 2
                grow = False
                if dlam < self.min_dlam:
                    lf = float(lam)
                    hinge = self._critical(state, lam)
                    where = f" at hinge {hinge}" if hinge else ""
                    if "stability" in last_reason or hinge:
                        raise InstabilityError(
                            f"{self.mech.name}: equilibrium path lost stability{where} at load "
                            f"factor λ = {lf:.9g} ({last_reason})",
                            lf,
                            hinge,
                        )
                    raise ContinuationError(
                        f"{self.mech.name}: continuation stuck at λ = {lf:.9g} ({last_reason})", lf
                    )
                continue
            state, info = res
            lam = new
            steps += 1
            if grow:
                dlam = min(mpmath.mpf(dmax), dlam * 2)
            grow = True
        return state, info, {"steps": steps, "rejected": rejected}

    def _describe(self, info, mark0) -> str:
        return f"{mark0} -> {self._stability(info)}"

    def _check_start(self, info) -> None:
        """Hook: raise if the as-fabricated pose is not a stable equilibrium (where checkable)."""


def _fmt(x) -> str:
    return mpmath.nstr(x, 6)


# ------------------------------------------------------------------------------------------
# the common solve(): continuation at 30 digits, then polishing at the digits the deviation needs
# ------------------------------------------------------------------------------------------
class _Solver(_Base, _Continuation):
    dps0 = 30

    def solve(self, inputs: Mapping, load_factor: Any = 1, min_digits: int = 20) -> dict:
        """Equilibrium at the input angles ``inputs`` (hinge → θ; missing inputs 0; None releases
        the actuator, and the rigid reference then keeps that hinge at 0) under ``load_factor`` ×
        the loads. See the class docstring of :class:`Equilibrium` for the result."""
        dps = self.dps0
        targets = self._targets(inputs, dps)
        with mpmath.workdps(dps):
            self._set(dps, targets, _mpf(load_factor, dps))
            span = max([float(abs(v)) for v in targets.values() if v is not None] + [0.0])
            state, _, cont = self._continue(
                self._zero(), span, bool(self.loads), mpmath.mpf(10) ** -12
            )
            _, lost = self._deviation(self._points(state), self._rigid(targets, dps))
        target_dps = max(dps, lost + min_digits + 10)
        return self._final(state, inputs, load_factor, target_dps, cont)

    def _set(self, dps, targets, load_factor):
        self.nums = self.numbers(dps)
        self.targets = {k: (None if v is None else +v) for k, v in targets.items()}
        self.load_factor = +load_factor


class Equilibrium(_Solver):
    """Method (a): elastica plates by Taylor-series shooting, mixed force formulation.

    ``Equilibrium(mech, stiffness, loads=(), params=None, extensible=False)``: ``stiffness``
    maps every non-rigid hinge to (E, width, thickness) (numbers or expressions over the file
    parameters, e.g. ``(210e9, 5e-3, "l/10")``), or is one such tuple for all of them; ``loads``
    a list of :class:`Load` (or (link, at, force, moment) tuples); ``params`` overrides file
    parameters. ``extensible=True`` lets every plate stretch by N/EA (EA = E·width·thickness;
    the energy then includes N²/(2EA)): a diagnostic variant, not the contract's elastica.

    ``solve(inputs, load_factor=1)`` returns::

        {"method": "shooting", "dps": d, "inputs": {H: q or None}, "load_factor": f,
         "points": {P: {"rigid": (x, y), "compliant": (x, y), "deviation": (dx, dy)}},
         "poses": {link: (x, y, φ)}, "angles": {H: θ},
         "hinges": {H: {"moment": M, "force": (Fx, Fy)}}, "actuators": {H: τ},
         "energy": E, "error_estimate": e, "continuation": {"steps", "rejected", "stable"}}
    """

    method = "shooting"

    # -- layout ---------------------------------------------------------------------------
    def _layout(self):
        nums = self.nums
        n3 = 3 * len(self.moving)
        self.c_plate = n3
        self.c_pin = n3 + 3 * len(nums.plates)
        self.c_act = self.c_pin + 2 * len(nums.pins)
        self.actuated = [r for r in nums.hinges if r.input and self.targets[r.name] is not None]
        self.n = self.c_act + len(self.actuated)

    def _zero(self):
        self._layout()
        return [mpmath.mpf(0)] * self.n

    def _pose(self, X, link):
        if link == self.ground:
            return mpmath.mpf(0), mpmath.mpf(0), mpmath.mpf(0)
        c = 3 * self.link_index[link]
        return X[c], X[c + 1], X[c + 2]

    def _points(self, X):
        return self._point_positions(
            {lk.name: self._pose(X, lk.name) for lk in self.mech.links}, self.nums
        )

    @staticmethod
    def _bits():
        return int(mpmath.mp.prec) + 24

    # -- residual and Jacobian -----------------------------------------------------------
    def _system(self, X, lam, energy=False):
        """R(X; λ), dR/dX, dR/dλ and per-plate shooting data, at the current precision."""
        nums, n = self.nums, self.n
        zero = mpmath.mpf(0)
        R = [zero] * n
        J = [[zero] * n for _ in range(n)]
        dR = [zero] * n
        Fr, L, Tr = nums.force_ref, nums.scale, nums.torque_ref
        bal = {name: 3 * i for i, name in enumerate(self.moving)}  # rows of link balances
        # rows: 3 balances per moving link, then 3 closures per plate, 2 per pin, 1 per actuator

        def col(link):
            return None if link == self.ground else 3 * self.link_index[link]

        def add_force(link, F, at, dF_cols, dat):
            """Add force F at point `at` on link's balance; dF_cols: [(col, dFx, dFy)], dat:
            [(col, dat_x, dat_y)] (derivatives of F and of the point)."""
            if link == self.ground:
                return
            b = bal[link]
            R[b] += F[0] / Fr
            R[b + 1] += F[1] / Fr
            R[b + 2] += _cross(at, F) / (Fr * L)
            for c, fx_, fy_ in dF_cols:
                J[b][c] += fx_ / Fr
                J[b + 1][c] += fy_ / Fr
                J[b + 2][c] += (at[0] * fy_ - at[1] * fx_) / (Fr * L)
            for c, ax, ay in dat:
                J[b + 2][c] += (ax * F[1] - ay * F[0]) / (Fr * L)

        def add_moment(link, Mz, dcols):
            if link == self.ground:
                return
            b = bal[link] + 2
            R[b] += Mz / (Fr * L)
            for c, dm in dcols:
                J[b][c] += dm / (Fr * L)

        shots = {}
        energy_total = zero
        bits = self._bits()
        for i, r in enumerate(nums.plates):
            cu = self.c_plate + 3 * i
            mu0, fx, fy = X[cu], X[cu + 1], X[cu + 2]
            xp, yp, pp = self._pose(X, r.p)
            xm, ym, pm = self._pose(X, r.m)
            cP, cM = col(r.p), col(r.m)
            rp = _rot(pp, r.cp0)
            rm = _rot(pm, r.cm0)
            rPc = (xp + rp[0], yp + rp[1])
            rMc = (xm + rm[0], ym + rm[1])
            (u1, x1, y1, mu1), Js, W, _ = shoot(
                pp + r.alpha, mu0, fx, fy, bits, True, energy, eps=r.eps, gam=r.gam
            )
            shots[r.name] = (u1, mu1, Js)
            l, EI = r.l, r.EI
            if energy:
                energy_total += EI / (2 * l) * W
            rw = 3 * i + 3 * len(self.moving)  # closure rows
            # closure: (rPc + l·(x1, y1) − rMc)/l = 0 and ψ(1) − φ_M − α = 0
            R[rw] = (rPc[0] + l * x1 - rMc[0]) / l
            R[rw + 1] = (rPc[1] + l * y1 - rMc[1]) / l
            R[rw + 2] = u1 - pm - r.alpha
            for k in range(3):  # rows x, y, ψ
                src = (1, 2, 0)[k]  # shoot outputs (ψ, x, y, μ)
                J[rw + k][cu] += Js[src][1]
                J[rw + k][cu + 1] += Js[src][2]
                J[rw + k][cu + 2] += Js[src][3]
                if cP is not None:  # ψ(0) = φ_P + α
                    J[rw + k][cP + 2] += Js[src][0]
            if cP is not None:
                J[rw][cP] += 1 / l
                J[rw + 1][cP + 1] += 1 / l
                J[rw][cP + 2] += -rp[1] / l
                J[rw + 1][cP + 2] += rp[0] / l
            if cM is not None:
                J[rw][cM] -= 1 / l
                J[rw + 1][cM + 1] -= 1 / l
                J[rw][cM + 2] -= -rm[1] / l
                J[rw + 1][cM + 2] -= rm[0] / l
                J[rw + 2][cM + 2] -= 1
            # loads on the links: P gets +F at its clamp and the moment m(0) = EI·μ0/l,
            # M gets −F at its clamp and −m(1) = −EI·μ(1)/l
            fs = EI / l**2
            F = (fx * fs, fy * fs)
            dF = [(cu + 1, fs, zero), (cu + 2, zero, fs)]
            if cP is not None:
                add_force(r.p, F, rPc, dF, [(cP, 1, 0), (cP + 1, 0, 1), (cP + 2, -rp[1], rp[0])])
                add_moment(r.p, EI * mu0 / l, [(cu, EI / l)])
            if cM is not None:
                negF = (-F[0], -F[1])
                ndF = [(cu + 1, -fs, zero), (cu + 2, zero, -fs)]
                add_force(
                    r.m, negF, rMc, ndF, [(cM, 1, 0), (cM + 1, 0, 1), (cM + 2, -rm[1], rm[0])]
                )
                dmu1 = [
                    (cu, -EI / l * Js[3][1]),
                    (cu + 1, -EI / l * Js[3][2]),
                    (cu + 2, -EI / l * Js[3][3]),
                ]
                if cP is not None:
                    dmu1.append((cP + 2, -EI / l * Js[3][0]))
                add_moment(r.m, -EI * mu1 / l, dmu1)
        base = 3 * len(self.moving) + 3 * len(nums.plates)
        for i, r in enumerate(nums.pins):
            cg = self.c_pin + 2 * i
            G = (X[cg] * Fr, X[cg + 1] * Fr)
            xp, yp, pp = self._pose(X, r.p)
            xm, ym, pm = self._pose(X, r.m)
            cP, cM = col(r.p), col(r.m)
            ap, am = _rot(pp, r.at), _rot(pm, r.at)
            rw = base + 2 * i
            R[rw] = (xp + ap[0] - xm - am[0]) / L
            R[rw + 1] = (yp + ap[1] - ym - am[1]) / L
            if cP is not None:
                J[rw][cP] += 1 / L
                J[rw + 1][cP + 1] += 1 / L
                J[rw][cP + 2] += -ap[1] / L
                J[rw + 1][cP + 2] += ap[0] / L
                add_force(
                    r.p,
                    G,
                    (xp + ap[0], yp + ap[1]),
                    [(cg, Fr, zero), (cg + 1, zero, Fr)],
                    [(cP, 1, 0), (cP + 1, 0, 1), (cP + 2, -ap[1], ap[0])],
                )
            if cM is not None:
                J[rw][cM] -= 1 / L
                J[rw + 1][cM + 1] -= 1 / L
                J[rw][cM + 2] -= -am[1] / L
                J[rw + 1][cM + 2] -= am[0] / L
                add_force(
                    r.m,
                    (-G[0], -G[1]),
                    (xm + am[0], ym + am[1]),
                    [(cg, -Fr, zero), (cg + 1, zero, -Fr)],
                    [(cM, 1, 0), (cM + 1, 0, 1), (cM + 2, -am[1], am[0])],
                )
        base += 2 * len(nums.pins)
        for i, r in enumerate(self.actuated):
            ct = self.c_act + i
            tau = X[ct] * Tr
            pp = self._pose(X, r.p)[2]
            pm = self._pose(X, r.m)[2]
            rw = base + i
            q = self.targets[r.name]
            R[rw] = pm - pp - lam * q
            dR[rw] = -q
            if col(r.m) is not None:
                J[rw][col(r.m) + 2] += 1
                add_moment(r.m, tau, [(ct, Tr)])
            if col(r.p) is not None:
                J[rw][col(r.p) + 2] -= 1
                add_moment(r.p, -tau, [(ct, -Tr)])
        # dead loads: λ·load_factor·(F at the load point, moment)
        for link, p0, F, Mz in nums.loads:
            if link == self.ground:
                continue
            x, y, phi = self._pose(X, link)
            c = col(link)
            rp = _rot(phi, p0)
            at = (x + rp[0], y + rp[1])
            s = lam * self.load_factor
            b = bal[link]
            R[b] += s * F[0] / Fr
            R[b + 1] += s * F[1] / Fr
            R[b + 2] += s * (Mz + _cross(at, F)) / (Fr * L)
            dR[b] += self.load_factor * F[0] / Fr
            dR[b + 1] += self.load_factor * F[1] / Fr
            dR[b + 2] += self.load_factor * (Mz + _cross(at, F)) / (Fr * L)
            J[b + 2][c] += s * F[1] / (Fr * L)
            J[b + 2][c + 1] += -s * F[0] / (Fr * L)
            J[b + 2][c + 2] += s * (-rp[1] * F[1] - rp[0] * F[0]) / (Fr * L)
        return R, J, dR, shots, energy_total

    # -- Newton, continuation hooks ----------------------------------------------------------
    def _norm(self, d, X):
        """Scaled size of a correction: positions / mechanism size, angles as they are, plate
        and pin loads relative to 1 + their size."""
        L = self.nums.scale
        n3 = 3 * len(self.moving)
        out = mpmath.mpf(0)
        for i, v in enumerate(d):
            scaled = (abs(v) / L if i % 3 != 2 else abs(v)) if i < n3 else abs(v) / (1 + abs(X[i]))
            out = max(out, scaled)
        return out

    def _newton(self, X, lam, tol, max_iter=25):
        X = list(X)
        last = None
        for it in range(max_iter):
            R, J, dR, _shots, _ = self._system(X, lam)
            try:
                lu = _LU(J)
            except ZeroDivisionError:
                return None
            d = lu.solve([-v for v in R])
            step = self._norm(d, X)
            if step > 1:
                return None
            X = [a + b for a, b in zip(X, d)]
            if step <= tol:
                return X, {"sign": lu.sign, "lu": lu, "dR": dR}
            if last is not None and step > last / 2 and it >= 2:
                if step <= tol * 10**6:  # rounding floor of an ill-conditioned J
                    return X, {"sign": lu.sign, "lu": lu, "dR": dR}
                if step > last:
                    return None
            last = step
        return None

    def _tangent(self, X, lam, info):
        return info["lu"].solve([-v for v in info["dR"]])

    def _stability(self, info):
        return info["sign"]

    def _describe(self, info, mark0):
        return f"sign of det J {mark0:+d} -> {info['sign']:+d}"

    def _distance(self, a, b):
        L = self.nums.scale
        out = 0.0
        for i, (x, y) in enumerate(zip(a, b)):
            s = L if i < 3 * len(self.moving) and i % 3 != 2 else 1
            out = max(out, float(abs(x - y) / s / (1 + abs(y) / s)))
        return out

    def _critical(self, X, lam):
        """The plate carrying most of the critical mode (inverse iteration on J), if one does."""
        _R, J, _dR, shots, _ = self._system(X, lam)
        try:
            lu = _LU(J)
        except ZeroDivisionError:
            return None
        v = [mpmath.mpf(1) + mpmath.mpf(i) / 7 for i in range(self.n)]
        for _ in range(4):
            v = lu.solve(v)
            big = max(abs(a) for a in v)
            v = [a / big for a in v]
        share = {}
        for i, r in enumerate(self.nums.plates):
            cu = self.c_plate + 3 * i
            Js = shots[r.name][2]
            du0 = v[3 * self.link_index[r.p] + 2] if r.p != self.ground else 0
            dmu1 = Js[3][0] * du0 + Js[3][1] * v[cu] + Js[3][2] * v[cu + 1] + Js[3][3] * v[cu + 2]
            share[r.name] = abs(v[cu]) + abs(dmu1)
        total = sum(share.values())
        if not total:
            return None
        name = max(share, key=lambda k: share[k])
        return name if share[name] > total / 2 else None

    # -- final polish and the result --------------------------------------------------------
    def _final(self, state, inputs, load_factor, dps, cont):
        out = []
        for d in (dps, dps + 10):
            targets = self._targets(inputs, d)
            with mpmath.workdps(d):
                self._set(d, targets, _mpf(load_factor, d))
                self._layout()
                res = self._newton([+x for x in state], mpmath.mpf(1), mpmath.mpf(10) ** (8 - d))
                if res is None:
                    raise ContinuationError(
                        f"{self.mech.name}: Newton failed polishing at {d} digits", 1.0
                    )
                state = res[0]
                out.append(self._result(state, targets, d, cont, res[1]))
        return _with_error_estimate(out[0], out[1])

    def _result(self, X, targets, dps, cont, info):
        nums = self.nums
        _R, _J, _dR, shots, energy = self._system(X, mpmath.mpf(1), energy=True)
        poses = {lk.name: self._pose(X, lk.name) for lk in self.mech.links}
        pts, _ = self._deviation(self._points(X), self._rigid(targets, dps))
        hinges = {}
        for i, r in enumerate(nums.plates):
            cu = self.c_plate + 3 * i
            fs = r.EI / r.l**2
            hinges[r.name] = {
                "moment": r.EI / r.l * shots[r.name][1],
                "force": (X[cu + 1] * fs, X[cu + 2] * fs),
            }
        for i, r in enumerate(nums.pins):
            cg = self.c_pin + 2 * i
            hinges[r.name] = {
                "moment": mpmath.mpf(0),
                "force": (X[cg] * nums.force_ref, X[cg + 1] * nums.force_ref),
            }
        acts = {r.name: X[self.c_act + i] * nums.torque_ref for i, r in enumerate(self.actuated)}
        angles = {r.name: poses[r.m][2] - poses[r.p][2] for r in nums.hinges}
        return {
            "method": self.method,
            "dps": dps,
            "inputs": dict(targets),
            "load_factor": self.load_factor,
            "points": pts,
            "poses": poses,
            "angles": angles,
            "hinges": hinges,
            "actuators": acts,
            "energy": energy,
            "continuation": {**cont, "stable": True, "det_sign": info["sign"]},
        }


def _with_error_estimate(low: dict, high: dict) -> dict:
    """``high`` with ``error_estimate`` = the relative change of the deviations from ``low``."""
    err = 0.0
    with mpmath.workdps(high["dps"]):
        for name, p in high["points"].items():
            dh, dl = p["deviation"], low["points"][name]["deviation"]
            num = mpmath.sqrt((dh[0] - dl[0]) ** 2 + (dh[1] - dl[1]) ** 2)
            den = mpmath.sqrt(dh[0] ** 2 + dh[1] ** 2)
            err = max(err, float(num / den) if den else float(num))
    high["error_estimate"] = err
    return high


# ------------------------------------------------------------------------------------------
# (b) Hencky chains, potential energy with Lagrange multipliers, Richardson over N
# ------------------------------------------------------------------------------------------
class ChainEquilibrium(_Solver):
    """Method (b): every plate a chain of N rigid segments with springs EI/h (2EI/h at the
    clamps); stationary potential energy under the closure constraints (KKT, Newton); the result
    extrapolated over N = ``n0``·2^j, j = 0..``levels``−1 (error expansion in h², h⁴, ...).

    Same constructor and result as :class:`Equilibrium` (``method`` = "chain"); the result also
    holds ``"levels"``: the N used. Stability is the inertia of the KKT matrix (the reduced
    stiffness positive definite), checked at every continuation step of the coarsest chain.
    """

    method = "chain"

    def __init__(self, *args, n0: int = 16, levels: int = 4, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        if self.extensible:
            raise NotImplementedError("the chain method models inextensible plates only")
        self.n0, self.levels = n0, levels
        self.N = n0

    # -- layout: [poses (3 per moving link) | multipliers | ψ of every plate] ----------------
    def _layout(self):
        nums = self.nums
        self.n_x = 3 * len(self.moving)
        self.actuated = [r for r in nums.hinges if r.input and self.targets[r.name] is not None]
        self.w_plate = self.n_x
        self.w_pin = self.w_plate + 2 * len(nums.plates)
        self.w_act = self.w_pin + 2 * len(nums.pins)
        self.n_o = self.w_act + len(self.actuated)
        self.n_c = self.n_o - self.n_x
        self.psi0 = [self.n_o + i * self.N for i in range(len(nums.plates))]
        self.n = self.n_o + self.N * len(nums.plates)

    def _zero(self):
        self.N = self.n0
        self._layout()
        state = [mpmath.mpf(0)] * self.n
        for i, r in enumerate(self.nums.plates):
            for j in range(self.N):
                state[self.psi0[i] + j] = +r.alpha
        return state

    def _pose(self, X, link):
        if link == self.ground:
            return mpmath.mpf(0), mpmath.mpf(0), mpmath.mpf(0)
        c = 3 * self.link_index[link]
        return X[c], X[c + 1], X[c + 2]

    def _col(self, link):
        return None if link == self.ground else 3 * self.link_index[link]

    def _points(self, X):
        return self._point_positions(
            {lk.name: self._pose(X, lk.name) for lk in self.mech.links}, self.nums
        )

    # -- one Newton step on the KKT system -----------------------------------------------------
    def _kkt(self, Z, lam):
        """Gradient g = ∇Π − Aᵀλ, constraints c, and the KKT blocks at Z, λ (continuation)."""
        nums, N = self.nums, self.N
        zero = mpmath.mpf(0)
        n_o = self.n_o
        S = [[zero] * n_o for _ in range(n_o)]  # outer block of K = [[H, Aᵀ], [A, 0]]
        g = [zero] * n_o  # [g_X | c] (the outer residual)
        dg = [zero] * n_o  # d/dλ of the outer residual
        plates = []
        s_load = lam * self.load_factor

        def link_terms(link, point0, lam_vec, w_cols, sign):
            """A closure term sign·((x, y) + Rot(φ)·point0) of constraints w_cols (x, y rows)
            with multipliers lam_vec: its A entries, its −λ·∇²c, its −Aᵀλ in g_X, its value."""
            c = self._col(link)
            x, y, phi = self._pose(Z, link)
            rp = _rot(phi, point0)
            val = (sign * (x + rp[0]), sign * (y + rp[1]))
            if c is None:
                return val
            dphi = (-rp[1] * sign, rp[0] * sign)
            for k in range(2):
                wc = w_cols[k]
                S[wc][c + k] += sign
                S[c + k][wc] += sign
                S[wc][c + 2] += dphi[k]
                S[c + 2][wc] += dphi[k]
                g[c + k] -= lam_vec[k] * sign
                g[c + 2] -= lam_vec[k] * dphi[k]
            # −λ·∂²c/∂φ² with ∂²(Rot(φ)p)/∂φ² = −Rot(φ)p
            S[c + 2][c + 2] += sign * (lam_vec[0] * rp[0] + lam_vec[1] * rp[1])
            return val

        for i, r in enumerate(nums.plates):
            k = r.EI * N / r.l
            h = r.l / N
            wc = (self.w_plate + 2 * i, self.w_plate + 2 * i + 1)
            lv = (Z[wc[0]], Z[wc[1]])
            p0 = self.psi0[i]
            psi = Z[p0 : p0 + N]
            phiP = self._pose(Z, r.p)[2]
            phiM = self._pose(Z, r.m)[2]
            ext = [phiP + r.alpha] + psi + [phiM + r.alpha]
            kj = [2 * k] + [k] * (N - 1) + [2 * k]
            mom = [kj[j] * (ext[j + 1] - ext[j]) for j in range(N + 1)]  # joint moments
            cs = [(mpmath.cos(a), mpmath.sin(a)) for a in psi]
            # chain closure c = start + h Σ t(ψ) − end
            a = link_terms(r.p, r.cp0, lv, wc, 1)
            b = link_terms(r.m, r.cm0, lv, wc, -1)
            cx = a[0] + b[0] + h * mpmath.fsum(c for c, _ in cs)
            cy = a[1] + b[1] + h * mpmath.fsum(s for _, s in cs)
            g[wc[0]] += cx
            g[wc[1]] += cy
            # springs on the links: ∂E/∂φ_P = −m_0, ∂E/∂φ_M = m_N; ∂²E/∂φ² = 2k
            cP, cM = self._col(r.p), self._col(r.m)
            if cP is not None:
                g[cP + 2] += -mom[0]
                S[cP + 2][cP + 2] += 2 * k
            if cM is not None:
                g[cM + 2] += mom[N]
                S[cM + 2][cM + 2] += 2 * k
            # inner block: tridiagonal H_ψψ, gradient, couplings B (N × 4)
            diag = [kj[j] + kj[j + 1] + h * (lv[0] * cs[j][0] + lv[1] * cs[j][1]) for j in range(N)]
            gpsi = [
                mom[j] - mom[j + 1] - h * (-lv[0] * cs[j][1] + lv[1] * cs[j][0]) for j in range(N)
            ]
            cols = [None if cP is None else cP + 2, None if cM is None else cM + 2, wc[0], wc[1]]
            plates.append((i, k, h, diag, gpsi, cs, cols, mom))
        for i, r in enumerate(nums.pins):
            wc = (self.w_pin + 2 * i, self.w_pin + 2 * i + 1)
            lv = (Z[wc[0]], Z[wc[1]])
            a = link_terms(r.p, r.at, lv, wc, 1)
            b = link_terms(r.m, r.at, lv, wc, -1)
            g[wc[0]] += a[0] + b[0]
            g[wc[1]] += a[1] + b[1]
        for i, r in enumerate(self.actuated):
            wc = self.w_act + i
            q = self.targets[r.name]
            phiP = self._pose(Z, r.p)[2]
            phiM = self._pose(Z, r.m)[2]
            g[wc] += phiM - phiP - lam * q
            dg[wc] += -q
            for link, sgn in ((r.m, 1), (r.p, -1)):
                c = self._col(link)
                if c is not None:
                    S[wc][c + 2] += sgn
                    S[c + 2][wc] += sgn
                    g[c + 2] -= Z[wc] * sgn
        for link, p0, F, Mz in nums.loads:
            c = self._col(link)
            if c is None:
                continue
            _x, _y, phi = self._pose(Z, link)
            rp = _rot(phi, p0)
            # V = −s (F·r + Mz φ)
            g[c] += -s_load * F[0]
            g[c + 1] += -s_load * F[1]
            g[c + 2] += -s_load * (_cross(rp, F) + Mz)
            dg[c] += -self.load_factor * F[0]
            dg[c + 1] += -self.load_factor * F[1]
            dg[c + 2] += -self.load_factor * (_cross(rp, F) + Mz)
            S[c + 2][c + 2] += s_load * (F[0] * rp[0] + F[1] * rp[1])
        return S, g, dg, plates

    @staticmethod
    def _tridiag(diag, off):
        """LDLᵀ of the symmetric tridiagonal matrix (diag, constant off-diagonal `off`):
        returns (d, l, negatives)."""
        d = [diag[0]]
        lo = [None]
        neg = 1 if d[0] < 0 else 0
        for j in range(1, len(diag)):
            lj = off / d[j - 1]
            lo.append(lj)
            d.append(diag[j] - lj * off)
            if d[-1] < 0:
                neg += 1
        return d, lo, neg

    @staticmethod
    def _trisolve(d, lo, b):
        n = len(d)
        z = list(b)
        for j in range(1, n):
            z[j] -= lo[j] * z[j - 1]
        x = [zz / dd for zz, dd in zip(z, d)]
        for j in range(n - 2, -1, -1):
            x[j] -= lo[j + 1] * x[j + 1]
        return x

    def _reduce(self, Z, lam):
        """Eliminate every plate's ψ block: the reduced outer matrix, its right-hand sides and
        what is needed to recover δψ and the inertia."""
        S, g, dg, plates = self._kkt(Z, lam)
        rhs = [-v for v in g]
        drhs = [-v for v in dg]
        neg_inner = {}
        back = []
        for i, k, h, diag, gpsi, cs, cols, _mom in plates:
            N = len(diag)
            d, lo, neg = self._tridiag(diag, -k)
            neg_inner[self.nums.plates[i].name] = neg
            # B columns: φ_P (−2k at ψ_1), φ_M (−2k at ψ_N), w_x (−h sin ψ), w_y (h cos ψ)
            zeros = [mpmath.mpf(0)] * N
            Bc = []
            for t, c in enumerate(cols):
                if c is None:
                    Bc.append(None)
                    continue
                if t == 0:
                    col = list(zeros)
                    col[0] = -2 * k
                elif t == 1:
                    col = list(zeros)
                    col[N - 1] = -2 * k
                elif t == 2:
                    col = [-h * s for _, s in cs]
                else:
                    col = [h * c_ for c_, _ in cs]
                Bc.append(col)
            Y = [None if col is None else self._trisolve(d, lo, col) for col in Bc]
            y = self._trisolve(d, lo, [-v for v in gpsi])
            for a_, ca in enumerate(cols):
                if ca is None:
                    continue
                Ba = Bc[a_]
                rhs[ca] -= mpmath.fdot(Ba, y)
                for b_, cb in enumerate(cols):
                    if cb is None:
                        continue
                    S[ca][cb] -= mpmath.fdot(Ba, Y[b_])
            back.append((i, d, lo, y, Y, cols, Bc))
        return S, rhs, drhs, back, neg_inner

    def _step(self, Z, lam):
        """Newton step: (δZ, info)."""
        S, rhs, drhs, back, neg_inner = self._reduce(Z, lam)
        lu = _LU(S)
        dZ = self._expand(lu.solve(rhs), back, True)
        return dZ, {"S": S, "lu": lu, "drhs": drhs, "back": back, "neg_inner": neg_inner}

    def _expand(self, do, back, with_rhs):
        """Full correction from the outer one: δψ = H⁻¹(rhs_ψ − B·δo) per plate (without the
        H⁻¹rhs_ψ part for a tangent), and δλ = −w for the multipliers."""
        dZ = list(do) + [mpmath.mpf(0)] * (self.n - self.n_o)
        for i, d, _lo, y, Y, cols, _Bc in back:
            p0 = self.psi0[i]
            dpsi = list(y) if with_rhs else [mpmath.mpf(0)] * len(d)
            for t, c in enumerate(cols):
                if c is not None:
                    dpsi = [a - do[c] * b for a, b in zip(dpsi, Y[t])]
            dZ[p0 : p0 + len(dpsi)] = dpsi
        for j in range(self.n_x, self.n_o):
            dZ[j] = -dZ[j]
        return dZ

    def _norm(self, d):
        L = self.nums.scale
        out = mpmath.mpf(0)
        for j in range(self.n_x):
            out = max(out, abs(d[j]) / L if j % 3 != 2 else abs(d[j]))
        for j in range(self.n_o, self.n):
            out = max(out, abs(d[j]))
        return out

    def _newton(self, Z, lam, tol, max_iter=25):
        Z = list(Z)
        last = None
        for it in range(max_iter):
            try:
                dZ, info = self._step(Z, lam)
            except ZeroDivisionError:
                return None
            step = self._norm(dZ)
            if step > 1:
                return None
            Z = [a + b for a, b in zip(Z, dZ)]
            if step <= tol or (
                last is not None and step > last / 2 and it >= 2 and step <= tol * 10**6
            ):
                info["mark"] = self._inertia(info)
                return Z, info
            if last is not None and step > last and it >= 2:
                return None
            last = step
        return None

    def _inertia(self, info):
        """Negative eigenvalues of the KKT matrix: every plate's H_ψψ (LDLᵀ pivots) plus the
        reduced outer matrix (float64 eigenvalues after symmetric equilibration)."""
        import numpy as np

        S = np.array([[float(v) for v in row] for row in info["S"]])
        D = np.ones(len(S))
        for _ in range(8):  # Ruiz: D S D with rows and columns of size ~1
            M = np.abs(D[:, None] * S * D[None, :]).max(axis=1)
            M[M == 0] = 1
            D /= np.sqrt(M)
        ev = np.linalg.eigvalsh(D[:, None] * S * D[None, :])
        return int((ev < 0).sum()) + sum(info["neg_inner"].values())

    def _stability(self, info):
        return info["mark"]

    def _check_start(self, info):
        if info["mark"] != self.n_c:
            raise InstabilityError(
                f"{self.mech.name}: the as-fabricated pose is not a stable equilibrium "
                f"({info['mark']} negative eigenvalues of the KKT matrix, {self.n_c} expected): "
                "a free mode (e.g. a released input between pins)",
                0.0,
                None,
            )

    def _describe(self, info, mark0):
        return (
            f"{mark0} -> {info['mark']} negative eigenvalues of the KKT matrix, "
            f"{self.n_c} for a stable equilibrium"
        )

    def _tangent(self, Z, lam, info):
        return self._expand(info["lu"].solve(info["drhs"]), info["back"], False)

    def _distance(self, a, b):
        L = self.nums.scale
        out = 0.0
        for j, (x, y) in enumerate(zip(a, b)):
            s = L if j < self.n_x and j % 3 != 2 else 1
            out = max(out, float(abs(x - y) / s / (1 + abs(y) / s)))
        return out

    def _critical(self, Z, lam):
        """A plate whose own block lost definiteness, else the plate holding most of the bending
        energy of the (float64) eigenvector of the smallest eigenvalue of the reduced matrix."""
        import numpy as np

        try:
            _, info = self._step(Z, lam)
        except ZeroDivisionError:
            return None
        bad = [name for name, neg in info["neg_inner"].items() if neg]
        if len(bad) == 1:
            return bad[0]
        S = np.array([[float(v) for v in row] for row in info["S"]])
        ev, vec = np.linalg.eigh(S)
        v = vec[:, int(np.argmin(np.abs(ev)))]
        share = {}
        for i, d, _lo, _y, Y, cols, _Bc in info["back"]:
            r = self.nums.plates[i]
            N = len(d)
            dpsi = np.zeros(N)
            for t, c in enumerate(cols):
                if c is not None:
                    dpsi -= v[c] * np.array([float(e) for e in Y[t]])
            ends = [
                v[cols[0]] if cols[0] is not None else 0.0,
                v[cols[1]] if cols[1] is not None else 0.0,
            ]
            ext = np.concatenate([[ends[0]], dpsi, [ends[1]]])
            kj = np.array([2.0] + [1.0] * (N - 1) + [2.0]) * float(r.EI * N / r.l)
            share[r.name] = float((kj * np.diff(ext) ** 2).sum())
        total = sum(share.values())
        if not total:
            return None
        name = max(share, key=lambda k: share[k])
        return name if share[name] > total / 2 else None

    # -- refinement, Richardson extrapolation and the result -----------------------------------
    def _refine(self, Z, N_old):
        """The state for 2·N_old segments: every plate's angles linearly interpolated (in arc
        length, the clamp angles as end values) from the N_old solution."""
        nums = self.nums
        old_psi0 = [self.n_o + i * N_old for i in range(len(nums.plates))]
        out = list(Z[: self.n_o])
        for i, r in enumerate(nums.plates):
            psi = Z[old_psi0[i] : old_psi0[i] + N_old]
            phiP = self._pose(Z, r.p)[2]
            phiM = self._pose(Z, r.m)[2]
            s = [mpmath.mpf(0)] + [(j + mpmath.mpf(1) / 2) / N_old for j in range(N_old)] + [1]
            v = [phiP + r.alpha] + list(psi) + [phiM + r.alpha]
            N = 2 * N_old
            j = 0
            for jj in range(N):
                t = (jj + mpmath.mpf(1) / 2) / N
                while s[j + 1] < t:
                    j += 1
                w = (t - s[j]) / (s[j + 1] - s[j])
                out.append(v[j] + w * (v[j + 1] - v[j]))
        return out

    def _values(self, Z, targets, dps):
        """Every reported quantity of one chain solution, flattened to {key: mpf}."""
        nums = self.nums
        _S, _g, _dg, plates = self._kkt(Z, mpmath.mpf(1))
        poses = {lk.name: self._pose(Z, lk.name) for lk in self.mech.links}
        out = {}
        for name, p in self._deviation(self._points(Z), self._rigid_cache)[0].items():
            out[("points", name, "compliant", 0)] = p["compliant"][0]
            out[("points", name, "compliant", 1)] = p["compliant"][1]
            out[("points", name, "deviation", 0)] = p["deviation"][0]
            out[("points", name, "deviation", 1)] = p["deviation"][1]
        energy = mpmath.mpf(0)
        for i, k, _h, _diag, _gpsi, _cs, _cols, mom in plates:
            r = nums.plates[i]
            wc = self.w_plate + 2 * i
            out[("hinges", r.name, "moment")] = mom[-1]
            out[("hinges", r.name, "force", 0)] = Z[wc]
            out[("hinges", r.name, "force", 1)] = Z[wc + 1]
            kj = [2 * k] + [k] * (len(mom) - 2) + [2 * k]
            energy += mpmath.fsum(m * m / (2 * kk) for m, kk in zip(mom, kj))
        out[("energy",)] = energy
        for i, r in enumerate(nums.pins):
            wc = self.w_pin + 2 * i
            out[("hinges", r.name, "moment")] = mpmath.mpf(0)
            out[("hinges", r.name, "force", 0)] = Z[wc]
            out[("hinges", r.name, "force", 1)] = Z[wc + 1]
        for i, r in enumerate(self.actuated):
            out[("actuators", r.name)] = Z[self.w_act + i]
        for name, pose in poses.items():
            for k in range(3):
                out[("poses", name, k)] = pose[k]
        for r in nums.hinges:
            out[("angles", r.name)] = poses[r.m][2] - poses[r.p][2]
        return out

    def _final(self, state, inputs, load_factor, dps, cont):
        targets = self._targets(inputs, dps)
        levels = []
        with mpmath.workdps(dps):
            self._set(dps, targets, _mpf(load_factor, dps))
            self._rigid_cache = self._rigid(targets, dps)
            Z = [+x for x in state]
            for j in range(self.levels):
                if j:
                    Z = self._refine(Z, self.N)
                    self.N *= 2
                self._layout()
                res = self._newton(Z, mpmath.mpf(1), mpmath.mpf(10) ** (8 - dps))
                if res is None:
                    raise ContinuationError(
                        f"{self.mech.name}: Newton failed for N = {self.N}", 1.0
                    )
                Z, info = res
                if info["mark"] != self.n_c:
                    raise InstabilityError(
                        f"{self.mech.name}: chain with N = {self.N} is not a stable equilibrium",
                        1.0,
                        None,
                    )
                levels.append(self._values(Z, targets, dps))
            Ns = [self.n0 * 2**j for j in range(self.levels)]
            self.N = self.n0
            best, second = _richardson(levels)
            res = _unflatten(best)
            pts = {}
            for name, rp in self._rigid_cache["points"].items():
                pts[name] = {
                    "rigid": rp,
                    "compliant": res["points"][name]["compliant"],
                    "deviation": res["points"][name]["deviation"],
                }
            err = 0.0
            for name in pts:
                d1 = [best[("points", name, "deviation", k)] for k in range(2)]
                d2 = [second[("points", name, "deviation", k)] for k in range(2)]
                size = mpmath.sqrt(d1[0] ** 2 + d1[1] ** 2)
                diff = mpmath.sqrt((d1[0] - d2[0]) ** 2 + (d1[1] - d2[1]) ** 2)
                err = max(err, float(diff / size) if size else float(diff))
            return {
                "method": self.method,
                "dps": dps,
                "inputs": dict(targets),
                "load_factor": self.load_factor,
                "points": pts,
                "poses": res["poses"],
                "angles": res["angles"],
                "hinges": res["hinges"],
                "actuators": res.get("actuators", {}),
                "energy": res["energy"],
                "error_estimate": err,
                "levels": Ns,
                "continuation": {**cont, "stable": True, "kkt_negative": self.n_c},
            }


def _richardson(levels: list[dict]) -> tuple[dict, dict]:
    """Richardson table over h_j = h_0/2^j for an error expansion in h², h⁴, ...: returns the
    most extrapolated values T[J][J] and the next best T[J][J−1]."""
    J = len(levels) - 1
    table = [dict(levels[0])]
    rows = [table]
    for j in range(1, J + 1):
        row = [dict(levels[j])]
        for m in range(1, j + 1):
            f = mpmath.mpf(4) ** m - 1
            prev, lower = row[m - 1], rows[j - 1][m - 1]
            row.append({k: prev[k] + (prev[k] - lower[k]) / f for k in prev})
        rows.append(row)
    last = rows[J]
    return last[J], last[J - 1] if J else last[J]


def _unflatten(flat: dict) -> dict:
    out: dict = {}
    for key, v in flat.items():
        if key == ("energy",):
            out["energy"] = v
            continue
        head, name, *rest = key
        if head in ("actuators", "angles"):
            out.setdefault(head, {})[name] = v
        elif head == "poses":
            out.setdefault("poses", {}).setdefault(name, [None] * 3)[rest[0]] = v
        elif head == "hinges":
            entry = out.setdefault("hinges", {}).setdefault(name, {"force": [None, None]})
            if rest[0] == "moment":
                entry["moment"] = v
            else:
                entry["force"][rest[1]] = v
        elif head == "points":
            out.setdefault("points", {}).setdefault(name, {}).setdefault(rest[0], [None, None])[
                rest[1]
            ] = v
    for entry in out.get("hinges", {}).values():
        entry["force"] = tuple(entry["force"])
    for name, pose in out.get("poses", {}).items():
        out["poses"][name] = tuple(pose)
    for entry in out.get("points", {}).values():
        for k in entry:
            entry[k] = tuple(entry[k])
    return out
