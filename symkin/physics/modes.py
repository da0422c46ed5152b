"""Natural frequencies and mode shapes of small oscillations about an equilibrium
(docs/physics.md, "Natural frequencies").

M q̈ + K_t q = 0, q the small displacements (x, y of the centre of mass, rotation φ) of the
links with mass, K_t the level's tangent stiffness with the inputs held (the loads' geometric
stiffness in it), M = diag(m, m, I) per link. The levels give the compliance C = K_t⁻¹ of
virtual loads (Fx, Fy, M) at the centres, the mass-free links and degrees of freedom (a link
without inertia turns freely under its centre's loads) relaxed: its block over the degrees of
freedom that carry mass is the compliance of the statically condensed stiffness (Guyan), exact
here because no mass sits on what is condensed. The eigenproblem is solved in the compliance
form, C_r M q = q/ω², symmetric as A = M^½ C_r M^½ v = v/ω² (q = M^-½ v, M-orthonormal), so a
direction the mechanism holds rigidly (no compliance at all) is an infinite frequency, left out,
and nothing is inverted. Every displacement of the mode, massless parts included, is the
response to the mode's inertia loads ω² M q: d = C[:, r] ω² M q. A stroke actuator with a
`spring` holds its command, the spring acting (docs/physics.md, "A stroke actuator with a
spring"): the levels' compliance has it.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from ..core.errors import AssemblyError
from ..core.settings import SOLVER
from ..model.entries import Link, Point
from ..model.mechanism import Mechanism
from .reported import System, _rows

RULES = SOLVER.modes
#: How the hidden point at a link's centre of mass is named (no file name holds a '@').
CENTRE = "@centre:"


def massive_links(mech: Mechanism) -> list[Link]:
    """The moving links that carry mass, in file order."""
    return [lk for lk in mech.links if lk.massive and lk.name != mech.ground]


def with_centre_points(mech: Mechanism) -> tuple[Mechanism, list[str]]:
    """`mech` with a hidden point (CENTRE + the link's name) at the centre of mass of every
    moving link with mass, and their names (none: `mech` itself)."""
    massive = massive_links(mech)
    n = len(mech.points)
    centres = tuple(
        Point(CENTRE + lk.name, n + k, lk.name, lk.centre, lk.line)  # type: ignore[arg-type]
        for k, lk in enumerate(massive)
    )
    if not centres:
        return mech, []
    return dataclasses.replace(mech, points=mech.points + centres), [p.name for p in centres]


@dataclass(frozen=True)
class Mode:
    """One natural mode: its frequency (Hz) and the displacement of every row of the
    compliance (per point: x, y in the file unit, φ in rad), normalised (see :func:`solve`)."""

    frequency: float
    shape: np.ndarray


def solve(
    compliance: np.ndarray,
    masses: Sequence[tuple[float, float]],
    scale: float,
    span: float,
    count: int | None = None,
) -> list[Mode]:
    """The natural modes, lowest first (at most `count`), of the links whose centres are the
    first len(masses) points of `compliance` (3P × 3P, file units: rows x, y (unit) and φ of
    each point, columns Fx, Fy (N) and M (N·unit) at each point), `masses` their (kg, kg·m²),
    `scale` metres per file unit, `span` the mechanism's size (file unit). A mode is
    normalised so that its largest centre translation is 1 (file unit) and positive; a pure
    rotation (translations below RULES.pure_rotation × rotation × span) so that its largest
    rotation is 1 rad. AssemblyError (exit 3) when the tangent stiffness is not positive (an
    unstable equilibrium: the loads beyond buckling)."""
    size = compliance.shape[0]
    # SI: lengths in m, moments in N·m; C_SI = D C D with D = (√s, √s, 1/√s) per point
    d = np.tile([math.sqrt(scale), math.sqrt(scale), 1 / math.sqrt(scale)], size // 3)
    c_si = compliance * d[:, None] * d[None, :]
    rows, weights = [], []
    for k, (mass, inertia) in enumerate(masses):
        rows += [3 * k, 3 * k + 1]
        weights += [mass, mass]
        if inertia > 0:
            rows.append(3 * k + 2)
            weights.append(inertia)
    root = np.sqrt(np.array(weights))
    reduced = c_si[np.ix_(rows, rows)]
    a = root[:, None] * (reduced + reduced.T) / 2 * root[None, :]
    mu, v = np.linalg.eigh(a)
    largest = float(np.max(np.abs(mu))) if mu.size else 0.0
    if largest == 0 or mu[0] < -RULES.rigid * largest:
        raise AssemblyError(
            "the equilibrium is unstable: the tangent stiffness with the inputs held is not "
            "positive (the loads are beyond buckling), so it has no natural frequencies "
            "(docs/physics.md, 'Natural frequencies')"
        )
    out = []
    for j in np.argsort(-mu):
        if mu[j] <= RULES.rigid * largest:
            continue  # held rigidly: an infinite frequency
        omega2 = 1 / float(mu[j])
        q = v[:, j] / root
        # the response of every row to the inertia loads ω² M q, back in the file's units
        shape = c_si[:, rows] @ (omega2 * np.array(weights) * q) / d
        out.append(Mode(math.sqrt(omega2) / (2 * math.pi), _normalised(shape, len(masses), span)))
        if count is not None and len(out) == count:
            break
    return out


def _normalised(shape: np.ndarray, links: int, span: float) -> np.ndarray:
    """`shape` scaled so that its largest centre translation (of the first `links` points) is
    +1, or its largest rotation +1 rad when it is a pure rotation."""
    moves = np.concatenate([shape[3 * k : 3 * k + 2] for k in range(links)])
    turns = shape[2 : 3 * links : 3]
    j = int(np.argmax(np.abs(moves)))
    if abs(moves[j]) <= RULES.pure_rotation * float(np.max(np.abs(turns))) * span:
        j = int(np.argmax(np.abs(turns)))
        return shape / turns[j]
    return shape / moves[j]


def equilibrium_compliance(
    system: System, u: np.ndarray, jac: np.ndarray, points: Sequence[str]
) -> np.ndarray:
    """The compliance (file units: rows x, y, φ of each point, columns Fx, Fy, M at each point)
    of `points` of symkin.physics.equilibrium's System at its solution u with the Jacobian J,
    the inputs held: a virtual load at a point enters its link's balance rows (as
    symkin.physics.reported.point_stiffness, every pair of points here)."""
    _, balance = _rows(system)
    L, F = float(system.L), float(system.F)
    n = len(points)
    places: dict[str, tuple[int, float, float, float, float]] = {}
    load = np.zeros((system.size, 3 * n))
    for k, name in enumerate(points):
        link, at = system.points[name]
        if link < 0:
            places[name] = (link, 0.0, 0.0, 0.0, 0.0)
            continue
        x, y = (float(v) for v in system.place(u, link, at))
        ox, oy = float(u[3 * link]) * L, float(u[3 * link + 1]) * L
        places[name] = (link, x, y, ox, oy)
        r = balance + 3 * link
        load[r, 3 * k] = load[r + 1, 3 * k + 1] = 1 / F
        load[r + 2, 3 * k : 3 * k + 3] = (-y / (F * L), x / (F * L), 1 / (F * L))
    du = -np.linalg.solve(jac, load)
    out = np.zeros((3 * n, 3 * n))
    for k, name in enumerate(points):
        link, x, y, ox, oy = places[name]
        if link < 0:
            continue  # a point of the frame does not move
        dphi = du[3 * link + 2]
        out[3 * k] = L * du[3 * link] - (y - oy) * dphi
        out[3 * k + 1] = L * du[3 * link + 1] + (x - ox) * dphi
        out[3 * k + 2] = dphi
    return out


def loaded_compliance(
    rates: np.ndarray, first: int, order: Sequence[str], points: Sequence[str]
) -> np.ndarray:
    """The same compliance from the `loaded` level's reported rates
    (symkin.physics.reduced.Reduced.reported: each point's deviation and its link's rotation
    by each point's virtual load, the points in `order`, from row and column `first`)."""
    at = {name: first + 3 * k for k, name in enumerate(order)}
    index = [at[name] + j for name in points for j in range(3)]
    return np.array(rates[np.ix_(index, index)], dtype=float)


def span_of(coordinates: Mapping[str, tuple[float, float]], floor: float) -> float:
    """The largest distance between any two of `coordinates`, at least `floor`."""
    values = list(coordinates.values())
    return max([math.dist(a, b) for a in values for b in values] + [floor])
