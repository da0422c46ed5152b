"""The model error of the physical levels (docs/physics.md, "Model error"): an estimate of how far
a level's beam theory is from a continuum model of the same plates, per point, relative to |ΔR|.

A beam theory leaves out effects of order (t/l)²: the centre line of a bent continuum changes
length, −c·(κt)² (St. Venant–Kirchhoff in plane strain: c = (1 − ν/(1 − ν))/8); an inextensible,
shear-free plate (the elastica, at either physical level where the hinge says so) also leaves out
its stretch N·l/EA and shear V·l/(κGA); and every beam leaves out how the plate meets its links
(rigid clamp faces stiffen it by O(t/l)) and how wide it is (plane strain only where l ≪ b).
Each is, per plate, a small displacement of M's clamp against P's with their rotations kept. In
a mechanism whose inputs are held such a displacement is taken up by the linkage itself (the
plates' bending is soft beside it), so its effect on a point is the pin linkage's linear
response: one least-squares solve of the linearised pin constraints at the level's pose.

The estimate is the magnitude of the signed sum of the effects whose sign the continuum fixes
(centre line; stretch and shear for an inextensible level) plus the magnitudes of those whose
sign depends on what the beam does not know (the clamps, the width): an estimate, not a bound.
It costs a few sympy substitutions and one small dense solve, no equilibrium.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
import sympy as sp

from ..core.settings import EPS64, SOLVER
from ..model import notch_correction
from ..model.hinges import pivot_distance
from ..model.mechanism import Mechanism
from ..model.notches import Notch
from ..model.sections import WIDE, SectionNumbers
from .result import HingeLoad
from .stiffness import plate_stiffness

#: The clamp faces' effect on a plate, as measured against a plane-strain continuum with rigid
#: clamp faces (docs/fea.md): on the transverse compliance 0.073 t/l; on a pure-moment arc's
#: deviation what the single plate's FE shortening leaves beside the centre line,
#: 0.026–0.041 t/l at t/l = 0.0125–0.1 (docs/physics.md); rounded up.
CLAMP_TRANSVERSE = 0.08
CLAMP_BENDING = 0.045
#: A full-width plate with l ≈ b is 2–4 % softer than plane strain (docs/physics.md): its
#: stiffness is uncertain by about ν²·min(1, l/(3b)) (ν²/3 ≈ 3 % at l = b, ν = 0.3).
WIDTH_SHARE = 3.0
#: A notch mechanism's deviation against a continuum depends on the continuum's finite-strain
#: law: CalculiX's neo-Hookean solid differs from its St. Venant–Kirchhoff one (whose centre-line
#: term the signed part counts) by 2.87–3.15 times that centre-line term of the notches on every
#: case measured (a notch four-bar, parallelogram and lever at 0.02–0.05 rad with and without a
#: dead load: docs/physics.md, "Notch mechanisms against a continuum";
#: benchmarks/notch_mechanisms.py), rounded up with room for geometries not measured. Counted
#: as a magnitude, on notch hinges only (plates were not measured against both laws).
LAW_SPREAD = 3.5


def centre_line_coefficient(nu: float) -> float:
    """c of the centre-line strain −c·(κt)² of a plane-strain St. Venant–Kirchhoff plate bent by
    a pure moment (κ its curvature, t its thickness): (1 − ν/(1 − ν))/8, from the strip's
    energy minimised over its through-thickness field (docs/physics.md; 1/8 at ν = 0, 0.0714 at
    ν = 0.3: the radial stress of the bent strip triples the Poisson term of the estimate that
    leaves it out)."""
    return (1 - nu / (1 - nu)) / 8


def level_stretches(mech: Mechanism, level: str) -> dict[str, bool]:
    """By plate, whether `level`'s plates stretch and shear: at `equilibrium` and `loaded` (whose
    plate relation takes the Reissner plate's stretch and shear) each hinge's `beam` says
    (docs/physics.md)."""
    physical = level in ("equilibrium", "loaded")
    return {h.name: physical and h.beam == "reissner" for h in mech.hinges}


@dataclass(frozen=True)
class ModelError:
    """Per point: the estimate (relative to |ΔR|) and its parts, each relative to |ΔR|:
    `centre_line`, `stretch_shear` (0 for a level whose plates stretch and shear), `clamp`,
    `width`, `notch` (what a notch's corrected beam leaves, 0 for a plate), `law` (the
    continuum's finite-strain law on the notches' centre lines, 0 without notches)."""

    total: dict[str, float]
    parts: dict[str, dict[str, float]]
    shift: dict[str, tuple[float, float]]  # the signed part: continuum minus beam, estimated


@dataclass(frozen=True)
class _Plate:
    name: str
    P: int
    M: int
    pivot: tuple[float, float]
    u: tuple[float, float]
    length: float
    t: float
    nu: float
    uncertain_modulus: float  # relative uncertainty of E' from the width
    section: SectionNumbers  # its end displacements under loads (model.sections)
    notch: float = 0.0  # a notch's beam against the continuum, relative (notch_correction)
    drift: float = 0.0  # the error of a circular notch's centre drift per radian (file unit)
    is_notch: bool = False  # a notch (model.notches.Notch): its centre line counts for `law`


def _number(expr, values) -> float:
    return float(sp.N(sp.sympify(expr).xreplace(values), 20))


def size(mech: Mechanism, values: Mapping[sp.Symbol, sp.Expr]) -> float:
    """The mechanism's size as the loaded level's truncation estimate takes it
    (physics.reduced.Reduced.length): the largest distance between hinge centres, at least the
    shortest plate (a lone hinge: its plate)."""
    centres = [(_number(h.at[0], values), _number(h.at[1], values)) for h in mech.hinges]
    lengths = [_number(h.length, values) for h in mech.hinges if h.is_plate]
    spread = max([math.dist(a, b) for a in centres for b in centres], default=0.0)
    spread = spread or max(lengths, default=0.0)
    return max(spread, min(lengths, default=spread))


def least_deviation(deviations: Mapping[str, tuple[float, float]], length: float) -> float:
    """The least |ΔR| a point's model error is relative to: est_share of the largest point
    deviation and est_size times the mechanism's size (`length`), as the loaded level's
    truncation estimate (docs/physics.md, "Model error"): a point at or near the centre of a
    link's rotation (a three-leaf flexure's hub) barely moves, and its own deviation, rounding,
    would make any error look infinite."""
    largest = max((math.hypot(*d) for d in deviations.values()), default=0.0)
    rules = SOLVER.loaded
    return max(rules.est_share * largest, rules.est_size_eps * EPS64 * length)


def _link_index(mech: Mechanism) -> dict[str, int]:
    """Moving links by position, the ground -1."""
    moving = [lk.name for lk in mech.links if lk.name != mech.ground]
    return {name: k for k, name in enumerate(moving)} | {mech.ground: -1}


def _plates(mech: Mechanism, values: Mapping[sp.Symbol, sp.Expr], level: str) -> list[_Plate]:
    stiff = plate_stiffness(mech, level, uniform=False)
    index = _link_index(mech)
    out = []
    for h in mech.hinges:
        if not h.is_plate:
            continue
        sec = SectionNumbers.of(stiff[h.name].section, values)
        length, t, b, nu = sec.length, sec.t, sec.b, sec.nu
        angle = _number(h.plate_angle, values)
        u = (math.cos(angle), math.sin(angle))
        at = (_number(h.at[0], values), _number(h.at[1], values))
        d = length / 2 - _number(pivot_distance(h), values)
        # a narrow plate (E' = E) lies between plane stress and plane strain: ν² either way
        uncertain = nu**2 * min(1.0, length / (WIDTH_SHARE * b)) if b >= WIDE * t else nu**2
        notch, drift = _notch_error(h, stiff[h.name].section, values)
        out.append(
            _Plate(
                h.name,
                index[h.links[0]],
                index[h.links[1]],
                (at[0] + d * u[0], at[1] + d * u[1]),
                u,
                length,
                t,
                nu,
                uncertain,
                sec,
                notch,
                drift,
                isinstance(stiff[h.name].section, Notch),
            )
        )
    return out


def _notch_error(hinge, section, values: Mapping[sp.Symbol, sp.Expr]) -> tuple[float, float]:
    """What a notch's beam leaves against a plane-strain continuum (docs/physics.md, "Model
    error"): the relative error of its compliances after the continuum correction (or without
    it: `continuum_correction = false`, a corner-filleted plate), and for a circular notch the
    error of its centre's drift under a moment, |k_beam − k_FE| R θ per radian θ, R k the beam's
    ∫₀^R (R − x)dx/EI / ∫dx/EI."""
    profile = getattr(section, "profile", "uniform")
    if not isinstance(section, Notch):  # a plate, or a profile registered elsewhere
        return 0.0, 0.0
    at = section.at(values)
    tau = 0.0
    if profile in notch_correction.NOTCHES:
        keys = {k: getattr(at, f) for k, f in at.correction_keys.items()}
        tau = float(notch_correction.neck_ratio(profile, at.thickness, **keys))
    relative = notch_correction.remaining(profile, tau, bool(at.continuum))
    if profile != "circular":
        return relative, 0.0
    half = at.length / 2
    turn = float(at.quad(lambda x, t: sp.Max(half - x, 0) / at._EI(t), {}))
    whole = float(at.quad(lambda x, t: 1 / at._EI(t), {}))
    return relative, notch_correction.centre_gap(tau) * turn / whole


def _rotate(phi: float, v: tuple[float, float]) -> np.ndarray:
    c, s = math.cos(phi), math.sin(phi)
    return np.array([c * v[0] - s * v[1], s * v[0] + c * v[1]])


def estimate(
    mech: Mechanism,
    values: Mapping[sp.Symbol, sp.Expr],
    level: str,
    stretches: Mapping[str, bool],
    rotations: Mapping[str, float],
    angles: Mapping[str, float],
    hinges: Mapping[str, HingeLoad],
    deviations: Mapping[str, tuple[float, float]],
) -> ModelError:
    """The model error of one configuration at `level` (docs/physics.md): `values` the exact
    parameter values; `stretches` by plate whether the level's plates stretch and shear
    (:func:`level_stretches`); `rotations` every link's rotation (rad), `angles` every hinge's
    angle, `hinges` the plates' end loads and `deviations` the points' ΔR, all from the level."""
    links = [lk.name for lk in mech.links if lk.name != mech.ground]
    plates = _plates(mech, values, level)
    scale = float(mech.unit_scale)
    phi = [rotations[name] for name in links]
    n = len(links)

    def arm(k: int, p0: tuple[float, float]) -> np.ndarray:
        """d(position)/dφ of the material point p0 (as fabricated) of link k."""
        return _rotate(phi[k] + math.pi / 2, p0)

    # The linearised pin linkage: unknowns (δx, δy, δφ) per moving link; rows: each hinge's
    # pin (2: M's pivot minus P's = the imposed displacement), each input's angle (1: held).
    index = _link_index(mech)
    pivots = {p.name: p.pivot for p in plates}
    rows: list[np.ndarray] = []
    hinge_rows: dict[str, int] = {}
    for h in mech.hinges:
        if h.name in pivots:
            pivot = pivots[h.name]
        else:
            pivot = (_number(h.at[0], values), _number(h.at[1], values))
        hinge_rows[h.name] = len(rows)
        for comp in range(2):
            row = np.zeros(3 * n)
            for k, sign in ((index[h.links[1]], 1.0), (index[h.links[0]], -1.0)):
                if k >= 0:
                    row[3 * k + comp] += sign
                    row[3 * k + 2] += sign * arm(k, pivot)[comp]
            rows.append(row)
        if h.input:
            row = np.zeros(3 * n)
            for k, sign in ((index[h.links[1]], 1.0), (index[h.links[0]], -1.0)):
                if k >= 0:
                    row[3 * k + 2] += sign
            rows.append(row)
    matrix = np.array(rows) if rows else np.zeros((0, 3 * n))
    # Each point's response to a unit displacement at each hinge: R = C · pinv(matrix) · E.
    pinv = np.linalg.pinv(matrix) if n else np.zeros((0, 0))
    points = {  # those the level evaluated (a scene's reference asks for its own alone)
        p.name: (index[p.link], (_number(p.at[0], values), _number(p.at[1], values)))
        for p in mech.points
        if p.name in deviations
    }

    def response(k: int, p0) -> np.ndarray:
        """(2, rows): the point's displacement per unit right-hand side."""
        if k < 0:
            return np.zeros((2, len(rows)))
        c = np.zeros((2, 3 * n))
        c[0, 3 * k], c[1, 3 * k + 1] = 1.0, 1.0
        c[:, 3 * k + 2] = arm(k, p0)
        return c @ pinv

    # Per plate, the displacements of M's clamp against P's (file unit, frame axes).
    signed: dict[str, np.ndarray] = {}  # centre line, and stretch and shear where left out
    centre: dict[str, np.ndarray] = {}
    clamp: dict[str, np.ndarray] = {}
    width: dict[str, np.ndarray] = {}
    notch: dict[str, np.ndarray] = {}  # a notch's compliance and centre drift (unsigned)
    # Without loads a uniform change of E' changes nothing (the loop forces scale with the
    # stiffness, the compliances inversely): only the plates' differences count.
    loaded = any(_number(v, values) != 0 for ld in mech.loads for v in (*ld.force, ld.moment))
    floor = 0.0 if loaded else min((p.uncertain_modulus for p in plates), default=0.0)
    for p in plates:
        theta = angles[p.name]
        chord = _rotate((phi[p.P] if p.P >= 0 else 0.0) + theta / 2, p.u)
        across = np.array([-chord[1], chord[0]])
        load = hinges[p.name]
        force = np.array(load.force)
        normal, transverse = float(force @ chord), float(force @ across)
        # −c ∫T²κ² ds with the moment linear along the plate, from its end moment at M and the
        # bend angle θ = ∫κ ds (a uniform plate: κ_P + κ_M = 2θ/l)
        sec = p.section
        shorter = sec.centre_line(centre_line_coefficient(p.nu), theta, load.moment / scale)
        centre[p.name] = shorter * chord
        left_out = np.zeros(2)
        if not stretches[p.name]:
            left_out = sec.stretch(normal) * chord + sec.shear(transverse) * across
        signed[p.name] = centre[p.name] + left_out
        bending = sec.guided(transverse)
        arc = p.length * theta**2 / 12  # the arc's deviation from the pin, along the chord
        ratio = p.t / p.length
        clamp[p.name] = np.stack(
            [
                CLAMP_BENDING * ratio * abs(arc) * chord,
                CLAMP_TRANSVERSE * ratio * abs(bending) * across,
            ]
        )
        compliance = bending * across
        if stretches[p.name]:
            compliance = compliance + sec.stretch(normal) * chord
            compliance = compliance + sec.shear(transverse) * across
        width[p.name] = (p.uncertain_modulus - floor) * compliance
        notch[p.name] = np.stack([p.notch * compliance, p.drift * abs(theta) * across])
    total, parts, shift = {}, {}, {}
    least = least_deviation(deviations, size(mech, values))
    moving = any(math.hypot(*d) > 0 for d in deviations.values())
    for name, (k, p0) in points.items():
        resp = response(k, p0)

        def effect(d: np.ndarray, hinge: str) -> np.ndarray:
            r = hinge_rows[hinge]
            return resp[:, r : r + 2] @ d

        sum_signed = sum((effect(signed[p.name], p.name) for p in plates), np.zeros(2))
        shift[name] = (float(sum_signed[0]), float(sum_signed[1]))
        # relative to |ΔR|, at least the floor; every point at rest (the as-fabricated pose):
        # nothing to be relative to
        norm = max(math.hypot(*deviations[name]), least) if moving else 0.0
        if norm == 0:
            total[name] = 0.0
            parts[name] = dict.fromkeys(
                ("centre_line", "stretch_shear", "clamp", "width", "notch", "law"), 0.0
            )
            continue
        sum_centre = sum((effect(centre[p.name], p.name) for p in plates), np.zeros(2))
        sum_law = sum((effect(centre[p.name], p.name) for p in plates if p.is_notch), np.zeros(2))
        law = LAW_SPREAD * float(np.linalg.norm(sum_law))
        clamps = sum(
            float(np.linalg.norm(effect(clamp[p.name][i], p.name)))
            for p in plates
            for i in range(2)
        )
        widths = float(
            np.linalg.norm(sum((effect(width[p.name], p.name) for p in plates), np.zeros(2)))
        )
        notches = sum(
            float(np.linalg.norm(effect(notch[p.name][i], p.name)))
            for p in plates
            for i in range(2)
        )
        signed_norm = float(np.linalg.norm(sum_signed))
        total[name] = (signed_norm + clamps + widths + notches + law) / norm
        parts[name] = {
            "centre_line": float(np.linalg.norm(sum_centre)) / norm,
            "stretch_shear": float(np.linalg.norm(sum_signed - sum_centre)) / norm,
            "clamp": clamps / norm,
            "width": widths / norm,
            "notch": notches / norm,
            "law": law / norm,
        }
    return ModelError(total, parts, shift)
