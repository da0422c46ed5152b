"""The `equilibrium` level (docs/physics.md): the mechanism's plates as geometrically exact
beams (Reissner's or the elastica, each hinge's `beam`), solved for the pose that balances them,
the actuators and the loads.

Unknowns: the pose (x, y, φ) of every moving link (a point fixed in it at p0 as fabricated is at
(x, y) + Rot(φ) p0), the end loads (k0, λx, λy) of every plate (symkin.physics.beams), the force
of every pin (`rigid` hinges) and the torque of every input's actuator. Equations: each plate
reaches M's clamp in P's plate frame with M's rotation (3), each pin joins its two links (2), each
input hinge holds its angle (1), each moving link is in force and moment balance (3): a square
system, because the inputs number the mechanism's mobility.

It is solved by continuation in the load factor t (inputs and loads times t) from the straight,
unloaded, as-fabricated pose at t = 0: a tangent predictor and Newton's method in float64 with
the Jacobian by the complex step, the step halved when Newton fails, det J changes sign or the
corrector jumps (a plate buckles or the path passes a limit point: exit 3 naming the hinge whose
plate dominates the singular mode, and t), within a budget of steps and seconds. Loads beyond the
plates' first buckling load are caught before: a linearised estimate, then a probe of the loads
alone (`continuation`). At t = 1 Newton polishes the solution in mpmath at a precision chosen
from the digits the deviation loses against the positions, with the float64 Jacobian. The rigid
reference is the kinematic levels' rigid linkage (pins at hinge_models.pivot_distance), evaluated
at the same precision; the deviation is the difference of the two positions.

`buckling_factor` gives the contract's "buckling": the smallest factor on the file's loads at
which the tangent stiffness with the inputs held becomes singular, by continuation.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

import mpmath
import numpy as np
import sympy as sp

from ..core.errors import AssemblyError
from ..core.settings import SOLVER
from ..model.expressions import substitute
from ..model.hinges import pivot_distance
from ..model.mechanism import Mechanism
from ..model.notches import Notch
from . import arith, beams, reported, section_beams
from .result import ActuatorLoad, HingeLoad, InputLoad, PlateStress
from .stiffness import PlateStiffness, plate_stiffness

#: The level's continuation, Newton, polish and buckling search (symkin.core.settings,
#: EquilibriumSettings; docs/numerics.md, "The solver table"). The names below are its fields
#: that other modules and messages read.
RULES = SOLVER.equilibrium
MIN_STEP = RULES.min_step
MAX_TURN = RULES.max_turn
MAX_STEPS = RULES.max_steps
TIME_BUDGET = RULES.time_budget
RATE_GROWTH, RATE_MARGIN = RULES.rate_growth, RULES.rate_margin
BUCKLING_LIMIT = RULES.buckling_limit
STRAIN_LIMIT = RULES.strain_limit
PROBE_STEPS = RULES.probe_steps
GROSS_OVERLOAD = RULES.gross_overload


@dataclass
class _Hinge:
    """Numbers of one hinge: links (index into the poses, -1 the ground), clamps and pin as
    fabricated, plate direction, length and EI; `theta` the input angle (None if not an input)."""

    name: str
    P: int
    M: int
    clamp_p: tuple
    clamp_m: tuple
    pin: tuple
    cos_a: object
    sin_a: object
    length: object
    EI: object
    plate: bool
    theta: object = None
    # EI/(EA l²) and EI/(κGA l²) of a Reissner plate (beams.shoot), None for an elastica
    stretch: object = None
    shear: object = None
    # thickness over length, t/l = √(12 EI/(EA l²)), for the plate's strain (System.strain)
    slender: float = 0.0
    # a notch (model.notches): its section sampled for the shot (physics.section_beams) and its
    # stress-concentration factor; None and 1 for a uniform plate
    grid: object = None
    kt: float = 1.0


@dataclass
class _Load:
    link: int
    at: tuple
    force: tuple
    moment: object


@dataclass
class _Actuator:
    """An actuator (docs/file-format.md, "[[actuator]]"): on link `link` (index into the poses)
    at `at` as fabricated, along the unit `direction`; `value` its stroke (file unit) or force
    (N) by `drive`; `spring` a stroke's series stiffness (N per file unit; None: ideal), whose
    actual stroke is then value − force/spring."""

    name: str
    link: int
    at: tuple
    direction: tuple
    drive: str
    value: object
    spring: object = None

    @property
    def stroke(self) -> bool:
        return self.drive == "stroke"


@dataclass
class System:
    """The equilibrium equations of one mechanism at fixed parameters, in float or mpf numbers.

    Unknowns u (scaled to order one): per moving link x/L, y/L, φ; per plate k0, λx, λy; per pin
    fx/F, fy/F; per input τ/(F L). `residual(u, t)` works on a batch: u (N, B), t (B,)."""

    links: list[str]
    hinges: list[_Hinge]
    loads: list[_Load]
    points: dict[str, tuple]
    L: object
    F: object
    index: dict = field(default_factory=dict)
    # the path parameter t drives the inputs by a + b t and the loads by c + d t: (0, 1, 0, 1)
    # scales both together from the unloaded, as-fabricated pose; (1, 0, 0, 1) holds the inputs
    # and scales the loads (`buckling_factor`)
    schedule: tuple = (0.0, 1.0, 0.0, 1.0)
    # the actuators (docs/levels.md, "Actuators"): a stroke holds its point's displacement
    # along its line (one equation, its force one unknown, after the inputs'), a force is a
    # dead load along the line, scaled with the loads
    actuators: list = field(default_factory=list)

    def __post_init__(self) -> None:
        k = 3 * len(self.links)
        for h in self.hinges:
            self.index[h.name] = k
            k += 3 if h.plate else 2
        for h in self.hinges:
            if h.theta is not None:
                self.index["tau:" + h.name] = k
                k += 1
        for a in self.actuators:
            if a.stroke:
                self.index["act:" + a.name] = k
                k += 1
        self.size = k

    def stroke(self, u: np.ndarray, a: _Actuator):
        """The displacement of actuator `a`'s point along its line in the solution u (batch)."""
        x, y = self.place(u, a.link, a.at)
        return a.direction[0] * (x - a.at[0]) + a.direction[1] * (y - a.at[1])

    def along(self, schedule: tuple) -> System:
        """The same equations with another path (`schedule`)."""
        return dataclasses.replace(self, schedule=schedule, index=dict(self.index))

    def rate(self, u: np.ndarray) -> float:
        """The plates' largest |k0| + √(|λx| + |λy|): how hard they are to shoot (beams.shoot)."""
        out = 0.0
        for h in self.hinges:
            if h.plate:
                k = self.index[h.name]
                k0, lx, ly = (abs(float(np.real(u[k + j]))) for j in range(3))
                out = max(out, k0 + math.sqrt(lx + ly))
        return out

    def pose(self, u: np.ndarray, i: int):
        """(x, y, φ) of link i (zeros for the ground, i = -1)."""
        if i < 0:
            zero = u[0] * 0
            return zero, zero, zero
        return u[3 * i] * self.L, u[3 * i + 1] * self.L, u[3 * i + 2]

    def place(self, u: np.ndarray, i: int, p0: tuple):
        """Position now of the point fixed in link i that was at p0 as fabricated."""
        x, y, phi = self.pose(u, i)
        c, s = arith.cos(phi), arith.sin(phi)
        return x + c * p0[0] - s * p0[1], y + s * p0[0] + c * p0[1]

    def residual(
        self, u: np.ndarray, t: np.ndarray, tol: float, report: dict | None = None
    ) -> np.ndarray:
        """Equations in the order: hinges (plate 3, pin 2), inputs (1), link balances (3 each)."""
        rows: list = []
        n = len(self.links)
        zero = u[0] * 0
        fx, fy, mz = [zero] * n, [zero] * n, [zero] * n

        def apply(i: int, f: tuple, at: tuple, m) -> None:
            if i >= 0:
                fx[i] = fx[i] + f[0]
                fy[i] = fy[i] + f[1]
                mz[i] = mz[i] + at[0] * f[1] - at[1] * f[0] + m

        plates = [h for h in self.hinges if h.plate and h.grid is None]
        cut = [h for h in self.hinges if h.grid is not None]
        notches = {}
        if cut:
            rows3 = np.array([u[self.index[h.name] + j] for h in cut for j in range(3)])
            rows3 = rows3.reshape(len(cut), 3, *u.shape[1:])
            shot = section_beams.shoot_profiles(
                rows3[:, 0], rows3[:, 1], rows3[:, 2], [h.grid for h in cut], report is not None
            )
            notches = {h.name: k for k, h in enumerate(cut)}
        end = None
        if plates:
            loads = np.array([u[self.index[h.name] + j] for h in plates for j in range(3)])
            loads = loads.reshape(len(plates), 3, *u.shape[1:])
            stretch = shear = None
            if any(h.stretch is not None for h in plates):
                kind = object if arith.is_mp(u) else float
                shape = (len(plates),) + (1,) * (u.ndim - 1)
                stretch, shear = (
                    np.array([getattr(h, key) or 0 for h in plates], dtype=kind).reshape(shape)
                    for key in ("stretch", "shear")
                )
            end = beams.shoot(
                loads[:, 0],
                loads[:, 1],
                loads[:, 2],
                tol,
                energy=report is not None,
                stretch=stretch,
                shear=shear,
            )
        ends = {h.name: k for k, h in enumerate(plates)}
        for h in self.hinges:
            _, _, phi_p = self.pose(u, h.P)
            _, _, phi_m = self.pose(u, h.M)
            base = self.index[h.name]
            if h.plate:
                k = notches[h.name] if h.name in notches else ends[h.name]
                ends_of = shot if h.name in notches else end
                xp, yp = self.place(u, h.P, h.clamp_p)
                xm, ym = self.place(u, h.M, h.clamp_m)
                cb = arith.cos(phi_p) * h.cos_a - arith.sin(phi_p) * h.sin_a  # plate frame
                sb = arith.sin(phi_p) * h.cos_a + arith.cos(phi_p) * h.sin_a
                dx, dy = xm - xp, ym - yp
                rows += [
                    (cb * dx + sb * dy) / h.length - ends_of.x[k],
                    (-sb * dx + cb * dy) / h.length - ends_of.y[k],
                    phi_m - phi_p - ends_of.psi[k],
                ]
                scale = h.EI / h.length**2
                lx, ly = u[base + 1] * scale, u[base + 2] * scale
                force = (cb * lx - sb * ly, sb * lx + cb * ly)  # by M on the plate
                m_p = u[base] * h.EI / h.length  # on P at its clamp
                m_m = ends_of.omega[k] * h.EI / h.length  # by M on the plate
                apply(h.P, force, (xp, yp), m_p)
                apply(h.M, (-force[0], -force[1]), (xm, ym), -m_m)
                if report is not None:
                    report[h.name] = (force, m_m, ends_of.energy[k] * h.EI / (2 * h.length))
            else:
                xp, yp = self.place(u, h.P, h.pin)
                xm, ym = self.place(u, h.M, h.pin)
                rows += [(xp - xm) / self.L, (yp - ym) / self.L]
                force = (u[base] * self.F, u[base + 1] * self.F)
                apply(h.P, force, (xp, yp), 0)
                apply(h.M, (-force[0], -force[1]), (xp, yp), 0)
                if report is not None:
                    report[h.name] = (force, zero, zero)
        a, b, c, d = self.schedule
        drive, load = a + b * t, c + d * t
        for h in self.hinges:
            if h.theta is not None:
                _, _, phi_p = self.pose(u, h.P)
                _, _, phi_m = self.pose(u, h.M)
                rows.append(phi_m - phi_p - drive * h.theta)
                tau = u[self.index["tau:" + h.name]] * self.F * self.L
                apply(h.M, (zero, zero), (zero, zero), tau)
                apply(h.P, (zero, zero), (zero, zero), -tau)
        for a in self.actuators:
            at = self.place(u, a.link, a.at)
            if a.stroke:
                f = u[self.index["act:" + a.name]] * self.F
                lost = 0 if a.spring is None else f / a.spring  # the spring's give, f/k
                rows.append((self.stroke(u, a) - drive * a.value + lost) / self.L)
            else:
                f = load * a.value
            apply(a.link, (f * a.direction[0], f * a.direction[1]), at, zero)
        for ld in self.loads:
            at = self.place(u, ld.link, ld.at)
            apply(ld.link, (load * ld.force[0], load * ld.force[1]), at, load * ld.moment)
        for i in range(n):
            rows += [fx[i] / self.F, fy[i] / self.F, mz[i] / (self.F * self.L)]
        return np.array(rows)

    def jacobian(self, u: np.ndarray, t: float, tol: float) -> tuple[np.ndarray, np.ndarray]:
        """(∂R/∂u, ∂R/∂t) at a float point, by the complex step: one batched residual."""
        n = self.size
        batch = np.tile(u.astype(complex)[:, None], (1, n + 1))
        batch[np.arange(n), np.arange(n)] += 1j * arith.COMPLEX_STEP
        tt = np.full(n + 1, t, dtype=complex)
        tt[n] += 1j * arith.COMPLEX_STEP
        r = self.residual(batch, tt, tol)
        d = r.imag / arith.COMPLEX_STEP
        return d[:, :n], d[:, n]

    def strain(self, u: np.ndarray) -> tuple[float, str | None]:
        """The largest strain of the plates at their ends, bending plus stretch,
        |ψ'| t/(2l) + |n|/EA, and its hinge: from the unknowns alone (the M end's moment by the
        plate's moment balance, ω = k0 − X λy + Y λx with (X, Y) M's clamp over l)."""
        out, where = 0.0, None
        for h in self.hinges:
            if not h.plate:
                continue
            k = self.index[h.name]
            k0, lx, ly = (float(np.real(u[k + j])) for j in range(3))
            _, _, phi_p = self.pose(u, h.P)
            xp, yp = self.place(u, h.P, h.clamp_p)
            xm, ym = self.place(u, h.M, h.clamp_m)
            cb = math.cos(float(phi_p)) * float(h.cos_a) - math.sin(float(phi_p)) * float(h.sin_a)
            sb = math.sin(float(phi_p)) * float(h.cos_a) + math.cos(float(phi_p)) * float(h.sin_a)
            dx, dy = float(xm - xp) / float(h.length), float(ym - yp) / float(h.length)
            x, y = cb * dx + sb * dy, -sb * dx + cb * dy
            bend = max(abs(k0), abs(k0 - x * ly + y * lx)) * h.slender / 2
            value = bend + math.hypot(lx, ly) * h.slender**2 / 12
            if value > out:
                out, where = value, h.name
        return out, where

    def singular_hinge(self, jac: np.ndarray) -> str:
        """The hinge whose unknowns dominate the singular mode of `jac` (the smallest singular
        value's right vector): the plate that buckles or the pin at the limit point."""
        vector = np.linalg.svd(jac)[2][-1]
        best, size = self.hinges[0].name, -1.0
        for h in self.hinges:
            k = self.index[h.name]
            part = float(np.linalg.norm(vector[k : k + (3 if h.plate else 2)]))
            if part > size:
                best, size = h.name, part
        return best


def build(
    mech: Mechanism,
    values: Mapping[sp.Symbol, sp.Expr],
    inputs: Mapping[str, sp.Expr],
    stiffness: Mapping[str, PlateStiffness],
    convert,
) -> System:
    """The System of `mech` with parameter `values`, the input angles by hinge name and the
    actuators' strokes or forces by their names, EI of every plate and `convert` (exact number
    -> float or mpf). The actuators' surrogate hinges are not held (docs/levels.md)."""
    links = [lk.name for lk in mech.links if lk.name != mech.ground]
    index = {name: k for k, name in enumerate(links)}
    index[mech.ground] = -1

    def num(expr):
        return convert(substitute(expr, values))

    hinges = []
    for h in mech.hinges:
        length = sp.sympify(h.length)
        u = (sp.cos(h.plate_angle), sp.sin(h.plate_angle))
        d = pivot_distance(h)
        plate = h.is_plate
        section = stiffness[h.name].section if plate else None
        grid = None
        if isinstance(section, Notch):
            grid = section_beams.grid_of(section, values, stiffness[h.name].stretches)
        hinges.append(
            _Hinge(
                h.name,
                index[h.links[0]],
                index[h.links[1]],
                tuple(num(h.at[k] - length / 2 * u[k]) for k in range(2)),
                tuple(num(h.at[k] + length / 2 * u[k]) for k in range(2)),
                tuple(num(h.at[k] + (length / 2 - d) * u[k]) for k in range(2)),
                num(u[0]),
                num(u[1]),
                num(length),
                None if not plate else _reference(grid, num) if grid else num(stiffness[h.name].EI),
                plate,
                num(inputs[h.name]) if h.input and h.name not in mech.surrogates else None,
                *_compliances(
                    stiffness.get(h.name) if plate and grid is None else None, length, num
                ),
                _slender(stiffness.get(h.name) if plate else None, values, grid),
                grid,
                1.0 if grid is None else _float(substitute(section.stress_factor(), values)),
            )
        )
    s = mech.unit_scale
    loads = [
        _Load(
            index[ld.link],
            tuple(num(v) for v in ld.at),
            tuple(num(v) for v in ld.force),
            num(ld.moment / s),
        )
        for ld in mech.loads
    ]
    points = {p.name: (index[p.link], tuple(num(v) for v in p.at)) for p in mech.points}
    # each actuator's point of action, as the evaluators track it (mechanism.Actuator.point)
    points |= {a.point: (index[a.link], tuple(num(v) for v in a.at)) for a in mech.actuators}
    centres = [
        (float(sp.N(substitute(h.at[0], values))), float(sp.N(substitute(h.at[1], values))))
        for h in mech.hinges
    ]
    span = max(
        [math.dist(a, b) for a in centres for b in centres]
        + [float(sp.N(substitute(h.length, values))) for h in mech.hinges]
    )
    plates = [h for h in hinges if h.plate]
    force = max([float(h.EI) / (float(h.length) * span) for h in plates], default=1.0)
    actuators = [
        _Actuator(
            a.name,
            index[a.link],
            tuple(num(v) for v in a.at),
            tuple(num(v) for v in a.direction),
            a.drive,
            num(inputs[a.name]),
            None if a.spring is None else num(a.spring),
        )
        for a in mech.actuators
    ]
    return System(
        links,
        hinges,
        loads,
        points,
        convert(sp.Float(span, 17)),
        convert(sp.Float(force, 17)),
        actuators=actuators,
    )


def _reference(grid: section_beams.SectionGrid, num):
    """A notch's reference EI₀ as `num` converts numbers (its grid's digits: the shot and
    the loads use the same value, so its digits beyond do not matter)."""
    digits = section_beams.GRID_DIGITS
    return num(sp.Float(mpmath.nstr(grid.EI0, digits), digits))


def _compliances(stiff: PlateStiffness | None, length, num) -> tuple:
    """(EI/(EA l²), EI/(κGA l²)) of a Reissner plate, (None, None) for an elastica or a pin."""
    if stiff is None or not stiff.stretches:
        return None, None
    return num(stiff.EI / (stiff.EA * length**2)), num(stiff.EI / (stiff.kGA * length**2))


def _slender(stiff: PlateStiffness | None, values, grid=None) -> float:
    """t/l of a plate from its section, √(12 EI/(EA l²)); 0 for a pin. A notch's is its
    thinnest section's t/l times the largest EI₀/EI(x), so that |ψ'(0 or 1)| t/(2l) of
    System.strain bounds the neck's bending strain (the moment along it lies between its ends'
    for a hinge with no load along it)."""
    if stiff is None:
        return 0.0
    ratio = math.sqrt(float(sp.N(substitute(stiff.section.slender_squared(), values), 20)))
    if grid is not None:
        ratio *= max(float(v) for v in grid.samples["a"])
    return ratio


@dataclass(frozen=True)
class Solution:
    """A converged equilibrium: the unknowns at the working precision `dps` and the size of the
    last polishing step (scaled units), which bounds the error (Newton contracts it further)."""

    system: System
    u: np.ndarray
    dps: int
    last_step: float
    tol: float


@dataclass(frozen=True)
class Path:
    """Where a continuation stopped: the float64 unknowns `u` at the path parameter `t`, the
    Jacobian there, and why: "done" (the end was reached), "singular" (det J changes sign or
    Newton fails ever closer to t: a plate buckles or the path passes a limit point), "budget"
    (MAX_STEPS steps or the time allowed), "strain" (a plate strains beyond the limit asked)."""

    u: np.ndarray
    t: float
    jac: np.ndarray
    stop: str


def follow(
    system: System,
    u: np.ndarray,
    t: float,
    end: float,
    largest: float,
    seconds: float = TIME_BUDGET,
    strain: float = math.inf,
    steps: int = MAX_STEPS,
    tol: float = RULES.series_tol,
    approach: bool = False,
) -> Path:
    """Continuation along `system`'s path from the solution `u` at `t` to `end`: a tangent
    predictor and Newton in float64, the step halved when Newton fails, det J changes sign
    (with `approach`, when any eigenvalue of J crosses zero: _crossed) or the corrector jumps,
    down to MIN_STEP; at most `steps` accepted steps, MAX_STEPS attempts
    and `seconds` of wall clock; it stops where a plate strains more than `strain`
    (System.strain). With `approach`, no step goes more than half way to where J's smallest
    singular value, extrapolated from the last two steps, vanishes: a singular point is
    approached, never stepped over (a symmetric structure's sway, where Newton from a long
    step lands on a buckled branch whose det J has the old sign)."""
    deadline = time.monotonic() + seconds
    jac, slope = system.jacobian(u, t, tol)
    sign = np.linalg.slogdet(jac)[0]
    dt, accepted = largest, 0
    smallest = [(t, _smallest(jac))] if approach else []
    for _ in range(MAX_STEPS):
        if t >= end:
            return Path(u, t, jac, "done")
        if accepted >= steps or time.monotonic() > deadline:
            break
        if len(smallest) == 2:
            (t0, s0), (ta, sa) = smallest
            if sa < s0:  # falling: at most half way to its extrapolated zero
                capped = RULES.approach * sa * (ta - t0) / (s0 - sa)
                if capped >= MIN_STEP:
                    dt = min(dt, capped)
                elif sa < SINGULAR_RATIO:
                    return Path(u, t, jac, "singular")
                # else a dip that stays clear of zero: the step's own tests decide
        t1 = min(end, t + dt)
        guess = u - np.linalg.solve(jac, slope) * (t1 - t)
        # an iterate that needs far larger plate loads than the path so far is off the path
        limit = RATE_GROWTH * system.rate(u) + RATE_MARGIN
        new = _newton(system, guess, t1, tol, limit) if system.rate(guess) < limit else None
        if new is not None and _jumped(u, guess, new[0]):
            new = None
        if new is not None:
            jac_new, slope_new = system.jacobian(new[0], t1, tol)
            if np.linalg.slogdet(jac_new)[0] != sign or (approach and _crossed(jac, jac_new)):
                new = None
        if new is None:
            dt *= RULES.step_cut
            if dt < MIN_STEP:
                return Path(u, t, jac, "singular")
            continue
        u, t, jac, slope = new[0], t1, jac_new, slope_new
        dt, accepted = min(largest, dt * RULES.step_growth), accepted + 1
        if approach:
            smallest = [smallest[-1], (t, _smallest(jac))]
        if strain < math.inf and system.strain(u)[0] > strain:
            return Path(u, t, jac, "strain")
    return Path(u, t, jac, "done" if t >= end else "budget")


#: J's smallest singular value over its largest below which a falling one that the step control
#: cannot approach further counts as singular (the sway of the parallelogram stage stops at 1e-11).
SINGULAR_RATIO = RULES.singular_ratio


def _smallest(jac: np.ndarray) -> float:
    """J's smallest singular value over its largest (scale-free)."""
    sv = np.linalg.svd(jac, compute_uv=False)
    return float(sv[-1] / sv[0]) if sv[0] > 0 else 0.0


def _crossed(jac: np.ndarray, jac_new: np.ndarray) -> bool:
    """Whether eigenvalues of J passed through zero between two steps, an even number of them
    too (det J then keeps its sign: identical legs buckling at one load): an eigenvalue of
    J⁻¹J_new in the left half-plane. A real negative one μ makes J + s (J_new − J) singular at
    s = 1/(1 − μ) in (0, 1); the eigenvalues are free of the unknowns' scaling and near 1 over a
    short step that crosses nothing. A complex pair in the left half-plane (two crossing modes
    that interact) counts too: at worst a step halved that need not be."""
    try:
        ratios = np.linalg.eigvals(np.linalg.solve(jac, jac_new))
    except np.linalg.LinAlgError:
        return True
    return bool(np.any(ratios.real < 0))


def _jumped(u: np.ndarray, guess: np.ndarray, new: np.ndarray) -> bool:
    """Newton's correction took it farther than the predictor's step (plus rounding): it may
    have left the path for another branch (past a limit point, the path folds back and Newton
    can land on a distant equilibrium whose det J has the same sign)."""
    predicted = float(np.max(np.abs(guess - u)))
    return float(np.max(np.abs(new - guess))) > predicted + RULES.jump * (
        1 + float(np.max(np.abs(u)))
    )


def continuation(
    system: System, what: str, path: str, units: str = "m"
) -> tuple[np.ndarray, np.ndarray]:
    """Float64 solution at t = 1 from u = 0 at t = 0, and its Jacobian; AssemblyError (exit 3)
    when the loads are beyond the plates' first buckling load, when the path buckles, passes a
    limit point, or cannot be followed within the budget (MAX_STEPS, TIME_BUDGET).

    With loads, the linearised buckling factor λ at the as-fabricated pose comes first (three
    Jacobians). Loads beyond GROSS_OVERLOAD/λ exit at once. Loads beyond 1/λ are probed: the
    loads alone at that pose, at most PROBE_STEPS steps and up to STRAIN_LIMIT; a singular
    tangent stiffness, a strain past the limit or the step budget exit 3 naming the factor;
    where the probe reaches the full loads (the linear estimate was pessimistic) the inputs
    follow from there."""
    started = time.monotonic()

    def left() -> float:
        return TIME_BUDGET - (time.monotonic() - started)

    turn = max([abs(float(h.theta)) for h in system.hinges if h.theta is not None] + [0.0])
    largest = min(1.0, MAX_TURN / turn) if turn else RULES.first_step
    u, driven = np.zeros(system.size), system
    if system.loads:
        first = buckling_estimate(system)
        if first.factor < 1:
            loads = system.along((0.0, 0.0, 0.0, 1.0))
            probe = Path(u, 0.0, np.zeros(0), "gross")
            if first.factor * GROSS_OVERLOAD >= 1:
                probe = follow(
                    loads, u, 0.0, 1.0, first.factor / 2, left(), STRAIN_LIMIT, PROBE_STEPS
                )
            if probe.stop != "done":
                factor, hinge = first.factor, first.hinge
                how = "a linearised estimate"
                if probe.stop == "budget":
                    how += (
                        f"; the loads alone were followed to {probe.t:.3g} of them in "
                        f"{PROBE_STEPS} steps"
                    )
                if probe.stop == "singular":
                    factor, hinge = probe.t, loads.singular_hinge(probe.jac)
                    how = "where the loads alone make the tangent stiffness singular"
                elif probe.stop == "strain":
                    value, plate = loads.strain(probe.u)
                    how += (
                        f"; at {probe.t:.3g} of the loads the plate of hinge '{plate}' already "
                        f"strains by {value:.0%}"
                    )
                raise AssemblyError(
                    f"{path}: the loads are {1 / factor:.4g} times the first buckling load of "
                    f"the plates (hinge '{hinge}', at the as-fabricated pose: {how}); the "
                    "equilibrium is not computed beyond it: check the file's units "
                    f'(units = "{units}": lengths in {units}, forces in N, moments in N·m) and '
                    "the loads' values (docs/physics.md)"
                )
            u, driven = probe.u, system.along((0.0, 1.0, 1.0, 0.0))
    end = follow(driven, u, 0.0, 1.0, largest, left())
    if end.stop == "singular":
        name = driven.singular_hinge(end.jac)
        of = "inputs, the loads held" if driven is not system else "inputs and loads"
        raise AssemblyError(
            f"{path}: {what} cannot be followed beyond load factor t = {end.t:.6g} (of the "
            f"requested {of}): the hinge '{name}' buckles there or the mechanism passes a "
            "limit point (docs/physics.md)"
        )
    if end.stop == "budget":
        raise AssemblyError(
            f"{path}: {what} did not reach the requested inputs and loads within its budget "
            f"({MAX_STEPS} continuation steps, {TIME_BUDGET:g} s): stopped at load factor "
            f"t = {end.t:.6g}, near a toggle position, a limit point or a buckling load "
            "(docs/physics.md)"
        )
    return end.u, end.jac


def _newton(system: System, u: np.ndarray, t: float, tol: float, limit: float = math.inf):
    """Newton in float64 from `u`; (u, step) once the step stops shrinking, or None (also when
    an iterate's plate loads exceed `limit` in System.rate)."""
    previous = math.inf
    for _ in range(RULES.newton_iterations):
        jac, _ = system.jacobian(u, t, tol)
        try:
            step = np.linalg.solve(jac, system.residual(u[:, None], np.array([t]), tol)[:, 0])
        except np.linalg.LinAlgError:
            return None
        u = u - step
        size = float(np.max(np.abs(step)))
        if size <= RULES.newton_tol * (1 + float(np.max(np.abs(u)))) or (
            size >= previous * RULES.stall_ratio > 0 and size < RULES.stalled
        ):
            return u, size
        diverged = size > RULES.diverged or size > previous
        if not np.all(np.isfinite(u)) or diverged or system.rate(u) > limit:
            return None  # diverging, or growing: a shorter step will do better
        previous = size
    return None


@dataclass(frozen=True)
class Buckling:
    """The smallest factor on the file's loads at which the tangent stiffness of the mechanism
    (the equilibrium Jacobian, the inputs held) becomes singular — math.inf when there is none
    up to the factor searched — and the hinge whose plate dominates the singular mode."""

    factor: float
    hinge: str | None


def buckling_estimate(system: System, tol: float = RULES.series_tol) -> Buckling:
    """The first buckling factor of the loads, linearised at the unloaded, as-fabricated pose
    (inputs at zero): the smallest λ > 0 with (J0 + λ J1) v = 0, J0 the Jacobian there and J1
    its derivative along the loads' linear path u = λ u', u' = −J0⁻¹ ∂R/∂λ (a central
    difference). Classical linear buckling: exact for a column that stays straight, an estimate
    where the loads bend the plates from the start. Costs three Jacobians."""
    loads = system.along((0.0, 0.0, 0.0, 1.0))
    zero = np.zeros(loads.size)
    jac0, slope = loads.jacobian(zero, 0.0, tol)
    try:
        tangent = -np.linalg.solve(jac0, slope)
    except np.linalg.LinAlgError:
        return Buckling(0.0, loads.singular_hinge(jac0))
    h = RULES.tangent_step / max(1.0, float(np.max(np.abs(tangent))))
    jac1 = (loads.jacobian(h * tangent, h, tol)[0] - loads.jacobian(-h * tangent, -h, tol)[0]) / (
        2 * h
    )
    # (J0 + λ J1) v = 0  <=>  J0⁻¹ J1 v = −v/λ
    mu = np.linalg.eigvals(np.linalg.solve(jac0, jac1))
    real = mu[(mu.real < 0) & (np.abs(mu.imag) <= RULES.real_eigenvalue * np.abs(mu))].real
    if real.size == 0:
        return Buckling(math.inf, None)
    factor = float(-1 / real.min())
    return Buckling(factor, loads.singular_hinge(jac0 + factor * jac1))


def overload(
    mech: Mechanism, values: Mapping[sp.Symbol, sp.Expr], inputs: Mapping[str, sp.Expr]
) -> Buckling:
    """:func:`buckling_estimate` of `mech` at parameter `values` and the inputs by name (the
    loads' first buckling factor linearised at the as-fabricated pose; math.inf without loads):
    what the `loaded` level's refusal names when the loads are beyond it (docs/physics.md)."""
    system = build(mech, values, inputs, plate_stiffness(mech, "equilibrium"), _float)
    return buckling_estimate(system) if system.loads else Buckling(math.inf, None)


def units_hint(units: str) -> str:
    """What a load far beyond buckling suggests checking (docs/physics.md)."""
    return (
        f'check the file\'s units (units = "{units}": lengths in {units}, forces in N, moments '
        "in N·m) and the loads' values"
    )


def buckling_factor(
    mech: Mechanism,
    values: Mapping[sp.Symbol, sp.Expr],
    inputs: Mapping[str, sp.Expr],
    limit: float = BUCKLING_LIMIT,
    seconds: float = RULES.buckling_budget * TIME_BUDGET,
) -> Buckling:
    """The first buckling factor of `mech`'s loads at the input angles by hinge name, properly:
    continuation to the inputs without loads, then in the load factor λ from 0 to `limit` with
    the inputs held, until det J changes sign or the path ends in a limit point (located by
    step halving to MIN_STEP). math.inf when none is met up to `limit` (or the file has no
    loads); AssemblyError (exit 3) when the inputs cannot be reached or the search runs out of
    its budget. Cost: a few solves (a second or two on the examples)."""
    system = build(mech, values, inputs, plate_stiffness(mech, "equilibrium", notches=True), _float)
    if not system.loads:
        return Buckling(math.inf, None)
    started = time.monotonic()
    turn = max([abs(float(h.theta)) for h in system.hinges if h.theta is not None] + [0.0])
    driven = follow(
        system.along((0.0, 1.0, 0.0, 0.0)),
        np.zeros(system.size),
        0.0,
        1.0,
        min(1.0, MAX_TURN / turn) if turn else 1.0,
        seconds,
    )
    held = system.along((1.0, 0.0, 0.0, 1.0))
    if driven.stop == "done":
        left = seconds - (time.monotonic() - started)
        end = follow(held, driven.u, 0.0, limit, 1.0, left, approach=True)
        if end.stop == "done":
            return Buckling(math.inf, None)
        if end.stop == "singular":
            return Buckling(end.t, held.singular_hinge(end.jac))
    what = "the inputs without loads" if driven.stop != "done" else "the load factor"
    raise AssemblyError(
        f"{mech.path}: the buckling search could not follow {what} (stopped at "
        f"t = {driven.t if driven.stop != 'done' else end.t:.6g}, docs/physics.md)"
    )


def polish(system_mp: System, u: np.ndarray, jac: np.ndarray, dps: int) -> Solution:
    """Newton at `dps` digits from the float64 solution, each step solved with the float64
    Jacobian (its error contracts the correction by about 1e-12 per step)."""
    tol = float(mpmath.mpf(10) ** (-dps - RULES.polish_guard))
    with mpmath.workdps(dps):
        x = arith.mp_array(u)
        one = arith.mp_array([1])
        last = math.inf
        for _ in range(RULES.polish_iterations):
            r = system_mp.residual(x[:, None], one, tol)[:, 0]
            step = np.linalg.solve(jac, np.array([float(v) for v in r]))
            x = x - arith.mp_array(step)
            last = float(np.max(np.abs(step)))
            if last <= 10.0 ** (RULES.polish_digits - dps):
                break
        return Solution(system_mp, x, dps, last, tol)


def _mp_converter(dps: int):
    return lambda expr: mpmath.mpf(sp.N(expr, dps + 5))


def _float(expr) -> float:
    return float(sp.N(expr, 20))


@dataclass(frozen=True)
class Result:
    """One configuration at the `equilibrium` level, in floats: hinge angles and point positions
    (rigid, compliant, deviation) by name, the plates' end loads, the elastic energy (J) and an
    estimate of the largest relative error of the points' deviations."""

    angles_rigid: dict[str, float]
    angles_compliant: dict[str, float]
    points: dict[str, tuple[tuple[float, float], tuple[float, float], tuple[float, float]]]
    hinges: dict[str, HingeLoad]
    energy: float
    error_estimate: float
    # compliant − rigid angle of every hinge, taken at the working precision (not a difference
    # of the floats above: it keeps its relative accuracy for tiny plates)
    angle_deviations: dict[str, float] = field(default_factory=dict)
    # what the level reports for the designer (symkin.physics.reported): each input's actuator
    # moment and stiffness, each point's 3×3 tangent stiffness and compliance (None where it
    # does not exist: K of a point held rigidly in some direction), each plate's largest stress
    inputs: dict[str, InputLoad] = field(default_factory=dict)
    actuators: dict[str, ActuatorLoad] = field(default_factory=dict)
    stiffness: dict[str, list | None] = field(default_factory=dict)
    compliance: dict[str, list | None] = field(default_factory=dict)
    plates: dict[str, PlateStress] = field(default_factory=dict)


def solve(
    mech: Mechanism,
    values: Mapping[sp.Symbol, sp.Expr],
    inputs: Mapping[str, sp.Expr],
    rigid: Callable[[int, Mapping[str, object]], tuple[dict, dict] | None],
    extra_digits: int = 0,
) -> Result:
    """The equilibrium of `mech` (docs/physics.md) at parameter `values` and the input
    angles by hinge name (and the actuators' strokes or forces by name), against the rigid pin
    linkage: `rigid(dps, strokes)` gives its hinge angles and its point positions by name at
    `dps` digits (the kinematic levels' rigid solution, exit 3 out of range), at the actuators'
    strokes by name (a force actuator's: the stroke its force produced; None where no pose of
    the rigid linkage reaches that stroke, and then the rigid angles, positions and deviations
    are NaN). `extra_digits` raises
    the working precision (to check the error estimate)."""
    stiffness = plate_stiffness(mech, "equilibrium", notches=True)
    # the rigid linkage first (exit 3 out of its range before any continuation), unless a
    # force actuator's stroke is only known from the equilibrium
    forces = any(a.drive == "force" for a in mech.actuators)
    if not forces:
        _, rigid_points = rigid(20, {a.name: inputs[a.name] for a in mech.actuators})
    system = build(mech, values, inputs, stiffness, _float)
    u, jac = continuation(system, "the equilibrium", mech.path, mech.units)
    if forces:
        # beyond the rigid reach `rigid` gives None (docs/physics.md, "Beyond the rigid reach"):
        # the compliant pose stands, without a reference
        reached = rigid(20, _strokes(system, u))
        rigid_points = {} if reached is None else reached[1]
    # The digits the deviation loses against the positions decide the working precision.
    span = float(system.L)
    smallest = min(
        [
            math.hypot(
                *(
                    np.array(_where(system, u, p), dtype=float)
                    - np.array(rigid_points[p], dtype=float)
                )
            )
            for p in rigid_points
        ]
        + [span]
    )
    lost = max(0, math.ceil(math.log10(span / smallest))) if smallest > 0 else 0
    # A tiny input's deviation lies below the float64 solution's rounding, so the estimate above
    # sees noise (at A0 = 1e-32 the deviation came out as a 6.5e-27 floor): a deviation of order
    # θ or θ² loses at most about 2 log10(1/θ) digits more than the positions' own
    turns = [abs(float(sp.N(inputs[n], 20))) for n in mech.inputs if n in inputs]
    tiny = min([t for t in turns if t > 0], default=1.0)
    if tiny < RULES.tiny_input:
        lost = max(lost, 2 * math.ceil(-math.log10(tiny)) + RULES.tiny_guard)
    dps = min(RULES.max_digits, RULES.base_digits + lost) + extra_digits
    with mpmath.workdps(dps):
        solution = polish(build(mech, values, inputs, stiffness, _mp_converter(dps)), u, jac, dps)
    reached = rigid(dps, _strokes(solution.system, solution.u))
    if reached is None:  # NaN rigid angles and positions: no deviation
        nan = mpmath.mpf("nan")
        theta = {h.name: nan for h in solution.system.hinges}
        rigid_points = dict.fromkeys(solution.system.points, (nan, nan))
    else:
        theta, rigid_points = reached
    with mpmath.workdps(dps):
        report: dict = {}
        solution.system.residual(solution.u[:, None], arith.mp_array([1]), solution.tol, report)
        # The last Newton step bounds the solution's error (Newton shrinks it further); the
        # working precision bounds the rounding.
        bound = (2 * solution.last_step + 10.0 ** (RULES.rounding_digits - dps)) * span
        # a notch's shot is as accurate as its grid, whatever the digits (physics.section_beams)
        bound += sum(
            section_beams.SHOT_ERROR * float(h.length)
            for h in solution.system.hinges
            if h.grid is not None
        )
        points, error = {}, 0.0
        for name, (xr, yr) in rigid_points.items():
            xc, yc = _where(solution.system, solution.u, name)
            dev = (xc - xr, yc - yr)
            size = float(mpmath.hypot(*dev))
            error = max(error, bound / size if size else 0.0)
            if reached is None:
                error = math.nan
            points[name] = (
                (float(xr), float(yr)),
                (float(xc), float(yc)),
                (float(dev[0]), float(dev[1])),
            )
        s = mpmath.mpf(sp.N(mech.unit_scale, dps))
        plates = {h.name for h in solution.system.hinges if h.plate}
        # the designer's quantities, in float64 at the polished solution (its Jacobian again)
        at = np.array([float(v) for v in solution.u])
        tangent = system.jacobian(at, 1.0, RULES.series_tol)[0]
        hinge = {h.name: h for h in mech.hinges}
        moduli = {n: _float(substitute(stiffness[n].section.modulus(), values)) for n in plates}
        allowable = {
            n: None
            if hinge[n].allowable_stress is None
            else _float(substitute(hinge[n].allowable_stress, values))
            for n in plates
        }
        point_k, point_c = reported.point_stiffness(system, at, tangent)
        return Result(
            angles_rigid={h.name: float(theta[h.name]) for h in solution.system.hinges},
            angles_compliant={
                h.name: float(_angle(solution.system, solution.u, h.name))
                for h in solution.system.hinges
            },
            points=points,
            hinges={
                n: HingeLoad(
                    (float(report[n][0][0][0]), float(report[n][0][1][0])),
                    float(report[n][1][0] * s),
                )
                for n in report
            },
            energy=float(sum(report[n][2][0] for n in plates) * s),
            error_estimate=error,
            angle_deviations={
                h.name: float(_angle(solution.system, solution.u, h.name) - theta[h.name])
                for h in solution.system.hinges
            },
            inputs=reported.inputs(system, at, tangent, float(s)),
            actuators=reported.actuators(system, at, tangent),
            stiffness=point_k,
            compliance=point_c,
            plates=reported.plates(system, at, moduli, allowable),
        )


def _strokes(system: System, u: np.ndarray) -> dict:
    """Every actuator's stroke in the solution u, by name (a stroke actuator's is its input;
    with a spring the command, where the rigid reference sits: docs/physics.md)."""
    return {
        a.name: a.value if a.spring is not None else system.stroke(u[:, None], a)[0]
        for a in system.actuators
    }


def _position(system: System, name: str) -> int:
    return next(k for k, h in enumerate(system.hinges) if h.name == name)


def _where(system: System, u: np.ndarray, point: str):
    """Position of the named point in the solution u."""
    link, at = system.points[point]
    x, y = system.place(u[:, None], link, at)
    return x[0], y[0]


def _angle(system: System, u: np.ndarray, name: str):
    """Hinge angle θ = φ_M − φ_P in the solution u."""
    h = system.hinges[_position(system, name)]
    return system.pose(u[:, None], h.M)[2][0] - system.pose(u[:, None], h.P)[2][0]
