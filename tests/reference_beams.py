"""Independent reference for geometrically exact plane beams: Reissner's and the elastica.

Test support, not a test file: the oracle for symkin's beam theories (docs/physics.md). Every
plate is a geometrically exact plane beam clamped in its two links, straight as fabricated, either
Reissner's (1972) — it bends, stretches and shears, linearly in its strains — or the inextensible,
shear-free elastica. It reuses the mechanism assembly of tests/reference_physics.py (links, pins,
actuators, dead loads, continuation, the rigid pin linkage of tests/reference_solver.py) and adds
the stretch and shear of every plate to both of its methods; symkin is used only to read the
mechanism file (``symkin.load``/``loads``).

Formulation (Reissner 1972, plane beam)
----------------------------------------
Along a plate, s the arc length of the undeformed plate, ψ the angle of its cross-section, n the
force that link M exerts on the plate (constant: no distributed load), m(s) the bending moment:

    N = n·(cos ψ, sin ψ),   Q = n·(−sin ψ, cos ψ),   ε = N/EA,   γ = Q/(κGA),   ψ' = m/EI,
    r' = (1 + ε)(cos ψ, sin ψ) + γ(−sin ψ, cos ψ),   m' = −(r' × n)_z = −Q·(1 + N (1/EA − 1/κGA)).

The last identity: (cos ψ, sin ψ) × n = Q and (−sin ψ, cos ψ) × n = −N. With EA, κGA → ∞ it is
the elastica's EI ψ'' = n_x sin ψ − n_y cos ψ. The energy is ∫ m²/(2EI) + N²/(2EA) + Q²/(2κGA) ds.
The clamps hold the cross-section: ψ(0) = φ_P + α and ψ(l) = φ_M + α (α the plate angle).

Section, from a hinge's E, width b, thickness t and ν (docs/physics.md, "Units and stiffness"):
EI = E'·b·t³/12, EA = E'·b·t with E' = E/(1 − ν²) when b ≥ 5t (plane strain) else E, and
κGA = κ·G·b·t with κ = 5/6 and G = E/(2(1 + ν)) — the plain shear modulus: the plane-strain
factor acts on the in-plane normal stiffness only (a plate in plane strain shears with G, as
the continuum does). In the file's length unit u (``units``, size s metres) EI is in N·u²,
EA and κGA in N; a load's moment (N·m) enters as M/s, and the results' moments, actuator torques
and energy are converted back to N·m and J.

Conventions
-----------
Those of tests/reference_physics.py and docs/physics.md: per hinge the force (frame axes) and the
moment (about the M clamp, CCW) that link M exerts on the plate at its M end — a plate bent by a
pure moment through θ > 0 has moment +EI·θ/l (for Reissner too: a pure moment neither stretches
nor shears); the actuator torque τ of an input hinge acts CCW on M. Deviation = compliant − rigid,
the rigid mechanism being the pin linkage with revolutes at the plate midpoints.

Methods
-------
(a) :class:`BeamEquilibrium` — the shooting method of reference_physics (Taylor series in fixed
    point with variational equations, mixed force formulation): its plate integrator ``shoot``
    takes eps = EI/(EA·l²) and gam = EI/(κGA·l²) and integrates, in σ = s/l and f = n·l²/EI,

        ψ'' = (1 + (eps − gam)·f_N)·(f_x sin ψ − f_y cos ψ),
        (x, y)' = (1 + eps·f_N)(cos ψ, sin ψ) + gam·f_Q·(−sin ψ, cos ψ).

(b) :class:`BeamChainEquilibrium` — the Hencky chain of reference_physics (N rigid segments,
    springs EI/h, potential energy with the closure constraints as Lagrange multipliers w = the
    plate forces), every segment j now also stretching by ε_j and shearing by γ_j with energy
    h·(EA ε_j² + κGA γ_j²)/2: its end is advanced by h·[(1 + ε_j) t_j + γ_j e_j]. ε and γ are
    eliminated exactly (ε_j = N_j/EA, γ_j = Q_j/κGA at the stationary point), which leaves the
    saddle function L = Π − w·c₀ − Σ_j h·(N_j²/EA + Q_j²/κGA)/2: the KKT matrix gains a negative
    definite block in the plate's multipliers, the segment angles' block stays tridiagonal, and
    the inertia test of stability is unchanged (the eliminated block is positive definite). The
    scheme is still the symmetric (Störmer–Verlet) splitting of the ODE: its error runs in h²,
    h⁴, ..., and Richardson extrapolation over N = 16·2^j removes it (measured below).

For one plate, independently of both: :func:`cantilever_quadrature`, the first integral of the
equations above, EI ψ'²/2 + N + N²·(1/EA − 1/κGA)/2 = const (the Reissner analogue of the
elastica's elliptic-integral solution, cf. Batista, arXiv:1508.04424, 2015), integrated by
Gauss–Legendre quadrature after a substitution that removes the tip's square-root singularity;
and :func:`cantilever` / :func:`cantilever_posed`, the shooting integrator with Newton on the
root moment (end loads given) or on all three root loads (end pose given). :class:`Section` gives a
plate's EI, EA, κGA from its material and size.

Validation (tests/test_reference_beams.py)
------------------------------------------
- pure end moment: the exact circular arc, moment EI·θ/l, energy EI·θ²/(2l), no force, for both
  beams, by the single-plate solvers and by both mechanism methods; an axial end force: straight,
  longer by F·l/EA, energy F²l/(2EA);
- the elastica cantilever against Bisshopp & Drucker (1945) and Mattiasson (1981) to their
  published digits, by shooting and by the quadrature;
- Reissner cantilever, small loads: Timoshenko's tip deflection F l³/(3EI) + F l/(κGA), axial
  F l/EA, the clamped–guided stiffness 1/(l³/(12EI) + l/(κGA)), and a perturbation series
  through α⁴ derived with sympy in the test (remainder O(α⁵));
- large loads with exaggerated stretch and shear (EI/(EA l²) = 0.01, EI/(κGA l²) = 0.03; load
  indices up to 5, end moments, axial components): shooting and quadrature agree to 1e-31 at
  30 digits (1e-41 at 40), and the posed solver returns the loads;
- mechanisms: (a) and (b) agree on every point's deviation, every hinge's force and moment, the
  actuator torques, the links' rotations and the energy, on the four-bar (A0 = 0.05 and 0.3, with
  and without (0.5, −1) N on C), the parallelogram stage (with and without a load on the stage)
  and a stubby released cantilever at load index 3, which the quadrature confirms; the actuator
  torque is the derivative of the potential energy; the file's loads and units are honoured
  (the four-bar written in mm gives the same physics); beam = "elastica" reproduces
  reference_physics.Equilibrium.

Measured accuracy and cost
--------------------------
(a) against (b), relative: deviation 3e-24..2e-20 on the four-bar, 1e-18 on the parallelogram
stage; hinge forces and moments 1e-28..5e-23; energy 2e-28..6e-24. (a)'s own error estimate
(the change from d to d + 10 digits) is below 1e-31; (b)'s Richardson estimate 1e-19..5e-16 is
pessimistic. The chain's error expands in even powers of h with stretch and shear too: its
Richardson table converges like the elastica's. Cost, one core: a mechanism solve takes 0.1–0.3 s
by (a), 0.6–1 s by (b) (N = 16..128); one cantilever 0.01–0.7 s by shooting, 0.2–1.5 s by the
quadrature and the posed solver at 30 digits. tests/test_reference_beams.py: 25 s of CPU.

Use
---
    mech = symkin.load("examples/four_bar.toml")
    eq = BeamEquilibrium(mech)            # E, thickness, width, nu and loads from the file
    res = eq.solve({"A0": "0.1"})         # Reissner plates by default
    BeamEquilibrium(mech, beam="elastica").solve({"A0": "0.1"})
    BeamChainEquilibrium(mech, (210e9, 5e-3, "l/10", "0.3"), loads=[...]).solve(...)

``stiffness`` is None (the file's E, thickness, width, nu of every plate), one (E, width,
thickness[, nu]) tuple for all plates, or a dict hinge → tuple; ``loads`` None (the file's
[[load]] entries) or a list of :class:`reference_physics.Load`; ``beam`` "reissner" or
"elastica" for every plate, a dict hinge → theory (missing: "reissner"), or None (each hinge's
``beam`` key once the file reader has one, else "reissner"). ``stretch`` and ``shear`` (default:
on for the "reissner" plates) switch the two effects separately for every plate, for
diagnostics.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import mpmath
import sympy as sp
from reference_physics import (
    _LU,
    ChainEquilibrium,
    ContinuationError,
    Equilibrium,
    Load,
    _mpf,
    shoot,
)

__all__ = [
    "BEAMS",
    "KAPPA",
    "BeamChainEquilibrium",
    "BeamEquilibrium",
    "Section",
    "cantilever",
    "cantilever_posed",
    "cantilever_quadrature",
]

#: Timoshenko's shear coefficient of a rectangular section (the contract's κ)
KAPPA = sp.Rational(5, 6)
#: a plate at least this many thicknesses wide bends in plane strain (docs/physics.md)
WIDE = 5
BEAMS = ("reissner", "elastica")
DEFAULT_NU = sp.Rational(3, 10)


# ------------------------------------------------------------------------------------------
# the section
# ------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Section:
    """EI, EA and κGA of a plate of width b and thickness t (exact sympy numbers, SI when the
    inputs are; in N·u², N, N with ``scale`` = the file unit's size in metres)."""

    EI: sp.Expr
    EA: sp.Expr
    kGA: sp.Expr
    plane_strain: bool

    @classmethod
    def of(cls, E, width, thickness, nu=DEFAULT_NU, kappa=KAPPA, scale=1) -> Section:
        E, b, t, nu = (
            sp.sympify(repr(v) if isinstance(v, float) else v, rational=isinstance(v, (str, float)))
            for v in (E, width, thickness, nu)
        )
        wide = bool(b >= WIDE * t)
        Ep = E / (1 - nu**2) if wide else E
        G = E / (2 * (1 + nu))
        s2 = sp.sympify(scale) ** 2
        return cls(
            Ep * b * t**3 / 12 * s2, Ep * b * t * s2, sp.sympify(kappa) * G * b * t * s2, wide
        )


# ------------------------------------------------------------------------------------------
# mechanisms: both methods of reference_physics with Reissner plates
# ------------------------------------------------------------------------------------------
class _Beams:
    """Front end shared by both methods: sections from material data, the beam theory, the
    file's loads and units. The mechanics live in reference_physics and in the subclasses."""

    def __init__(
        self,
        mech,
        stiffness: Mapping | tuple | None = None,
        loads: Sequence | None = None,
        params: Mapping | None = None,
        beam: str | Mapping | None = None,
        *,
        stretch: bool | None = None,
        shear: bool | None = None,
        kappa: Any = KAPPA,
        **kwargs,
    ) -> None:
        plates = [h for h in mech.hinges if h.model != "rigid"]
        # the beam theory per plate: the argument (one for all, or hinge → theory), else the
        # hinge's own `beam` key where the file reader has one, else Reissner's
        self.beam = {}
        for h in plates:
            if isinstance(beam, Mapping):
                theory = beam.get(h.name, "reissner")
            else:
                theory = beam or getattr(h, "beam", None) or "reissner"
            if theory not in BEAMS:
                raise ValueError(f"{h.name}: beam must be one of {BEAMS}, not {theory!r}")
            self.beam[h.name] = theory
        if isinstance(beam, Mapping) and set(beam) - set(self.beam):
            raise KeyError(f"beam given for {sorted(set(beam) - set(self.beam))}, not plates")
        if stiffness is None:
            missing = [
                (h.name, k)
                for h in plates
                for k in ("E", "thickness", "width")
                if getattr(h, k) is None
            ]
            if missing:
                raise KeyError(f"no stiffness given and the file lacks {missing}")
            stiffness = {h.name: (h.E, h.width, h.thickness, h.nu) for h in plates}
        elif isinstance(stiffness, tuple):
            stiffness = {h.name: stiffness for h in plates}
        if loads is None:
            loads = [Load(ld.link, tuple(ld.at), tuple(ld.force), ld.moment) for ld in mech.loads]
        # the base class checks the hinges and converts the loads; its EI is replaced below
        super().__init__(
            mech,
            dict.fromkeys(stiffness, (12, 1, 1)),
            loads=loads,
            params=params,
            extensible=False,
            **kwargs,
        )
        self.scale = mech.unit_scale
        self.loads = [
            Load(ld.link, ld.at, ld.force, ld.moment / self.scale) for ld in self.loads
        ]  # N·m → N·u
        names = {p.name: p.symbol for p in mech.parameters}
        self.sections: dict[str, Section] = {}
        self._shear_ratio = {}
        for name, spec in stiffness.items():
            if len(spec) not in (3, 4):
                raise ValueError(f"{name}: give (E, width, thickness[, nu])")
            E, b, t = (self._expr(v, names) for v in spec[:3])
            nu = self._expr(spec[3], names) if len(spec) == 4 else DEFAULT_NU
            sec = Section.of(E, b, t, nu, self._expr(kappa, names), self.scale)
            self.sections[name] = sec
            self._ei[name] = sec.EI
            reissner = self.beam[name] == "reissner"
            # EI/EA = t²/12 for a plate that stretches, 0 for one that does not
            stretches = reissner if stretch is None else stretch
            self._ea_ratio[name] = sec.EI / sec.EA if stretches else sp.Integer(0)
            if reissner if shear is None else shear:
                self._shear_ratio[name] = sec.EI / sec.kGA
        # reference_physics' numbers read eps per plate only when the owner is extensible
        self.extensible = any(v != 0 for v in self._ea_ratio.values())

    def solve(self, inputs: Mapping, load_factor: Any = 1, min_digits: int = 20) -> dict:
        """As reference_physics' solve; moments, torques and energy in N·m and J."""
        res = super().solve(inputs, load_factor, min_digits)
        res["beam"] = dict(self.beam)
        if self.scale != 1:
            with mpmath.workdps(res["dps"]):
                s = _mpf(self.scale, res["dps"])
                for h in res["hinges"].values():
                    h["moment"] = h["moment"] * s
                res["actuators"] = {k: v * s for k, v in res["actuators"].items()}
                res["energy"] = res["energy"] * s
        return res


class BeamEquilibrium(_Beams, Equilibrium):
    """Method (a): shooting (reference_physics' integrator with the plates' eps and gam).

    ``BeamEquilibrium(mech, stiffness=None, loads=None, params=None, beam=None)``; the result
    is reference_physics.Equilibrium's plus ``"beam"`` (hinge → the plate's beam theory)."""


class BeamChainEquilibrium(_Beams, ChainEquilibrium):
    """Method (b): Hencky chains whose segments also stretch and shear (see the module
    docstring); Richardson over N = ``n0``·2^j, j < ``levels``. Same result as (a)."""

    def _compliance(self, r):
        """(1/EA, 1/κGA) of plate r in the file's unit, 0 for a stiffness switched off."""
        scale = r.l**2 / r.EI
        return r.eps * scale, r.gam * scale

    def _kkt(self, Z, lam):
        S, g, dg, plates = super()._kkt(Z, lam)
        self._wcols = {}
        for i, _k, h, diag, gpsi, cs, _cols, _mom in plates:
            r = self.nums.plates[i]
            a, b = self._compliance(r)
            c0 = self.w_plate + 2 * i
            wx, wy = Z[c0], Z[c0 + 1]
            kc = a - b
            bx, by = [], []
            cx = cy = sxx = sxy = syy = mpmath.mpf(0)
            for j, (c, s) in enumerate(cs):
                N = wx * c + wy * s
                Q = -wx * s + wy * c
                if a or b:
                    # L gains −h(aN² + bQ²)/2: ∂/∂ψ = −h·kc·N·Q, ∂²/∂ψ² = −h·kc·(Q² − N²)
                    diag[j] -= h * kc * (Q * Q - N * N)
                    gpsi[j] -= h * kc * N * Q
                # ∂c/∂ψ_j of the closure h[(1 + aN) t + bQ e] (t = (c, s), e = (−s, c))
                bx.append(h * (-s + kc * (Q * c - N * s)))
                by.append(h * (c + kc * (Q * s + N * c)))
                cx += a * N * c - b * Q * s
                cy += a * N * s + b * Q * c
                sxx += a * c * c + b * s * s
                sxy += (a - b) * c * s
                syy += a * s * s + b * c * c
            g[c0] += h * cx
            g[c0 + 1] += h * cy
            S[c0][c0] -= h * sxx
            S[c0][c0 + 1] -= h * sxy
            S[c0 + 1][c0] -= h * sxy
            S[c0 + 1][c0 + 1] -= h * syy
            self._wcols[i] = (bx, by)
        return S, g, dg, plates

    def _reduce(self, Z, lam):
        """reference_physics' elimination of the ψ blocks, with the closure's ψ-derivatives of
        the stretching and shearing segments in the multipliers' coupling columns."""
        S, g, dg, plates = self._kkt(Z, lam)
        rhs = [-v for v in g]
        drhs = [-v for v in dg]
        neg_inner = {}
        back = []
        for i, k, _h, diag, gpsi, _cs, cols, _mom in plates:
            N = len(diag)
            d, lo, neg = self._tridiag(diag, -k)
            neg_inner[self.nums.plates[i].name] = neg
            zeros = [mpmath.mpf(0)] * N
            Bc = []
            for t, c in enumerate(cols):
                if c is None:
                    Bc.append(None)
                elif t == 0:
                    col = list(zeros)
                    col[0] = -2 * k
                    Bc.append(col)
                elif t == 1:
                    col = list(zeros)
                    col[N - 1] = -2 * k
                    Bc.append(col)
                else:
                    Bc.append(self._wcols[i][t - 2])
            Y = [None if col is None else self._trisolve(d, lo, col) for col in Bc]
            y = self._trisolve(d, lo, [-v for v in gpsi])
            for a_, ca in enumerate(cols):
                if ca is None:
                    continue
                Ba = Bc[a_]
                rhs[ca] -= mpmath.fdot(Ba, y)
                for b_, cb in enumerate(cols):
                    if cb is not None:
                        S[ca][cb] -= mpmath.fdot(Ba, Y[b_])
            back.append((i, d, lo, y, Y, cols, Bc))
        return S, rhs, drhs, back, neg_inner

    def _values(self, Z, targets, dps):
        out = super()._values(Z, targets, dps)
        extra = mpmath.mpf(0)
        for i, r in enumerate(self.nums.plates):
            a, b = self._compliance(r)
            if not (a or b):
                continue
            c0 = self.w_plate + 2 * i
            wx, wy = Z[c0], Z[c0 + 1]
            h = r.l / self.N
            p0 = self.psi0[i]
            for psi in Z[p0 : p0 + self.N]:
                c, s = mpmath.cos(psi), mpmath.sin(psi)
                N, Q = wx * c + wy * s, -wx * s + wy * c
                extra += h * (a * N * N + b * Q * Q) / 2
        out[("energy",)] += extra
        return out


# ------------------------------------------------------------------------------------------
# one plate (scaled: EI = 1, l = 1; force f = F·l²/EI, moment μ = M·l/EI)
# ------------------------------------------------------------------------------------------
def _bits() -> int:
    return int(mpmath.mp.prec) + 24


def _newton_root_moment(mu, fx, fy, m1, eps, gam, tol):
    for _ in range(60):
        out, J, _, _ = shoot(0, mu, fx, fy, _bits(), True, False, eps=eps, gam=gam)
        d = -(out[3] - m1) / J[3][1]
        mu += d
        if abs(d) <= tol * (1 + abs(mu)):
            return mu
    raise ContinuationError("cantilever: Newton on the root moment failed", 1.0)


def cantilever(fx, fy, m1=0, *, eps=0, gam=0, dps: int = 40, steps: int = 4) -> dict:
    """A plate clamped at σ = 0 (ψ = 0), dead end loads at σ = 1: force (fx, fy) (frame axes,
    scaled by l²/EI) and moment m1 (scaled by l/EI). eps = EI/(EA l²), gam = EI/(κGA l²) (0, 0:
    the elastica). Shooting with Newton on the root moment μ0, continued in the loads from zero
    at 20 digits, then polished at ``dps``. Returns {"x", "y", "psi" (the tip pose), "mu0",
    "energy" (in EI/l), "dps"}."""
    mu = mpmath.mpf(0)
    with mpmath.workdps(20):
        args = [_mpf(v, 20) for v in (fx, fy, m1)]
        for k in range(1, steps + 1):
            lam = mpmath.mpf(k) / steps
            mu = _newton_root_moment(
                mu, *(lam * v for v in args), _mpf(eps, 20), _mpf(gam, 20), mpmath.mpf(10) ** -14
            )
    with mpmath.workdps(dps):
        fx, fy, m1, eps, gam = (_mpf(v, dps) for v in (fx, fy, m1, eps, gam))
        mu = _newton_root_moment(+mu, fx, fy, m1, eps, gam, mpmath.mpf(10) ** (6 - dps))
        out, _, W, _ = shoot(0, mu, fx, fy, _bits(), False, True, eps=eps, gam=gam)
        return {"psi": out[0], "x": out[1], "y": out[2], "mu0": mu, "energy": W / 2, "dps": dps}


def _arc(theta):
    """End pose (ψ, x, y) of a unit plate bent by a pure moment through θ (the circular arc)."""
    if abs(theta) < mpmath.mpf(10) ** (-mpmath.mp.dps // 4):
        return [theta, 1 - theta**2 / 6, theta / 2 - theta**3 / 24]
    return [theta, mpmath.sin(theta) / theta, 2 * mpmath.sin(theta / 2) ** 2 / theta]


def cantilever_posed(x1, y1, psi1, *, eps=0, gam=0, dps: int = 40, steps: int = 8) -> dict:
    """A plate clamped at σ = 0 (ψ = 0, origin) whose other end is held at (x1, y1) with its
    section at angle psi1 (lengths over l): the end loads, by Newton on (μ0, f_x, f_y). The end
    is moved from the straight pose along arc(λ·psi1) + λ·(target − arc(psi1)), λ: 0 → 1, arc
    the force-free circular arc: the intermediate poses need small forces (a pose path that
    ignored the shortening of a bent inextensible plate would need huge axial forces and wander
    onto buckled branches). Returns {"mu0", "fx", "fy" (the force at the end, l²/EI), "mu1" (the
    end moment, l/EI), "energy" (EI/l), "dps"}."""
    with mpmath.workdps(dps):
        target = [_mpf(v, dps) for v in (psi1, x1, y1)]
        eps, gam = _mpf(eps, dps), _mpf(gam, dps)
        offset = [t - a for t, a in zip(target, _arc(target[0]))]
        u = [mpmath.mpf(0)] * 3  # μ0, fx, fy
        sols = [list(u)]
        for k in range(1, steps + 1):
            lam = mpmath.mpf(k) / steps
            goal = [a + lam * o for a, o in zip(_arc(lam * target[0]), offset)]
            if k == 1:
                # linear beam theory: ψ1 = μ0 − f_y/2, y1 = μ0/2 − f_y/6 + gam·f_y (a start
                # off the straight plate, where the elastica is singular in the axial force)
                fy = (goal[2] - goal[0] / 2) / (mpmath.mpf(1) / 12 + gam)
                u = [goal[0] + fy / 2, mpmath.mpf(0), fy]
            else:
                # extrapolate the loads along the path: the inextensible plate's shortening is
                # second order in its bending, which one Newton step alone would put on f_x
                u = [2 * a - b for a, b in zip(sols[-1], sols[-2])]
            tol = mpmath.mpf(10) ** (6 - (dps if k == steps else 20))
            for _ in range(60):
                out, J, _, _ = shoot(0, u[0], u[1], u[2], _bits(), True, False, eps=eps, gam=gam)
                R = [out[0] - goal[0], out[1] - goal[1], out[2] - goal[2]]
                A = [[J[row][1], J[row][2], J[row][3]] for row in (0, 1, 2)]
                d = _LU(A).solve([-v for v in R])
                u = [a + b for a, b in zip(u, d)]
                if max(abs(v) for v in d) <= tol * (1 + max(abs(v) for v in u)):
                    break
            else:
                raise ContinuationError("cantilever_posed: Newton failed", float(lam))
            sols.append(list(u))
        out, _, W, _ = shoot(0, u[0], u[1], u[2], _bits(), False, True, eps=eps, gam=gam)
        return {"mu0": u[0], "fx": u[1], "fy": u[2], "mu1": out[3], "energy": W / 2, "dps": dps}


def cantilever_quadrature(fx, fy, m1=0, *, eps=0, gam=0, dps: int = 40, steps: int = 4) -> dict:
    """The problem of :func:`cantilever` by the first integral, for a section angle ψ that runs
    monotonically from 0 to its tip value ψ1 (no inflection point, as in the cantilever tables;
    an end moment against the end rotation raises ValueError):

        ψ'²/2 + V(ψ) = m1²/2 + V(ψ1),   V = f_N + (eps − gam)·f_N²/2,   f_N = f·(cos ψ, sin ψ),

    so that 1 = ∫ dψ/ψ' and (x, y) = ∫ r'(ψ) dψ/ψ'. With ψ = ψ1·(1 − τ²) the integrands are
    analytic on τ ∈ [0, 1] (the square-root singularity at a moment-free tip is removed); the
    difference V(ψ1) − V(ψ) is formed without cancellation. mpmath.quad (Gauss–Legendre)
    evaluates them, mpmath.findroot (secant) solves for ψ1, continued in the loads from zero at
    20 digits, then at ``dps`` + 10. Shares no code with the shooting: an independent check of
    it. Returns {"x", "y", "psi", "length" (= 1, the check of the root), "dps"}."""

    def integral(psi1, f, which):
        gx, gy, mm, e, g = f
        n1 = gx * mpmath.cos(psi1) + gy * mpmath.sin(psi1)

        def integrand(tau):
            psi = psi1 * (1 - tau * tau)
            mid = (psi1 + psi) / 2
            # f_N(ψ1) − f_N(ψ) = 2 sin((ψ1 − ψ)/2)·(−f_x sin mid + f_y cos mid)
            dn = (
                2
                * mpmath.sin(psi1 * tau * tau / 2)
                * (-gx * mpmath.sin(mid) + gy * mpmath.cos(mid))
            )
            nn = n1 - dn  # f_N(ψ)
            drop = dn * (1 + (e - g) * (n1 + nn) / 2)  # V(ψ1) − V(ψ)
            w = 2 * abs(psi1) * tau / mpmath.sqrt(mm * mm + 2 * drop)  # dσ/dτ
            if which == 0:
                return w
            c, s = mpmath.cos(psi), mpmath.sin(psi)
            nq = -gx * s + gy * c  # f_Q(ψ)
            if which == 1:
                return w * ((1 + e * nn) * c - g * nq * s)
            return w * ((1 + e * nn) * s + g * nq * c)

        return mpmath.quad(integrand, [0, 1], method="gauss-legendre")

    with mpmath.workdps(20):
        f = [_mpf(v, 20) for v in (fx, fy, m1, eps, gam)]
        lam, dlam, path = mpmath.mpf(0), mpmath.mpf(1) / steps, [(0, mpmath.mpf(0))]
        while lam < 1:
            new = min(mpmath.mpf(1), lam + dlam)
            fk = [new * v for v in f[:3]] + f[3:]
            if len(path) == 1:  # linear theory
                start = (fk[2] + fk[1] / 2, (fk[2] + fk[1] / 2) * mpmath.mpf("0.9"))
            else:  # extrapolate the path
                (l0, p0), (l1, p1) = path[-2:]
                start = (p1, p1 + (p1 - p0) * (new - l1) / (l1 - l0))
            try:
                root = mpmath.findroot(
                    lambda p: integral(p, fk, 0) - 1,
                    start,
                    solver="secant",
                    tol=mpmath.mpf(10) ** -30,
                )
                ok = isinstance(root, mpmath.mpf)
            except (ValueError, ZeroDivisionError):
                ok = False
            if not ok:
                dlam /= 2
                if dlam < mpmath.mpf(10) ** -4:
                    raise ContinuationError("cantilever_quadrature: no root", float(lam))
                continue
            lam = new
            path.append((lam, root))
    with mpmath.workdps(dps + 10):
        f = [_mpf(v, dps + 10) for v in (fx, fy, m1, eps, gam)]
        psi = +path[-1][1]
    with mpmath.workdps(dps + 10):
        f = [_mpf(v, dps + 10) for v in (fx, fy, m1, eps, gam)]
        psi = mpmath.findroot(
            lambda p: integral(p, f, 0) - 1,
            (psi, psi * (1 + 1e-12)),
            solver="secant",
            tol=mpmath.mpf(10) ** (-2 * dps - 10),
        )
        if f[2] * psi < 0:
            raise ValueError(
                "cantilever_quadrature: the section angle is not monotonic (the "
                "end moment opposes the end rotation)"
            )
        return {
            "psi": psi,
            "x": integral(psi, f, 1),
            "y": integral(psi, f, 2),
            "length": integral(psi, f, 0),
            "dps": dps,
        }
