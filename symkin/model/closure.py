"""The rank of the closure Jacobian of a mechanism's rigid linkage at the as-fabricated pose
(docs/levels.md, "Redundant loops"): the mobility, dependent inputs, and the hinges whose angles
the actuators' strokes fix (docs/levels.md, "Actuators").

It reads a mechanism through :class:`Linkage` (what :class:`~.mechanism.Mechanism` holds), so
that the Mechanism can keep its rank as a property without an import circle.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Protocol

import mpmath
import numpy as np
import sympy as sp

from . import expressions
from .entries import Actuator, Hinge, Link
from .hinges import pivot_distance


class Linkage(Protocol):
    """What the closure analysis reads of a mechanism (a :class:`~.mechanism.Mechanism`)."""

    @property
    def ground(self) -> str: ...

    @property
    def links(self) -> tuple[Link, ...]: ...

    @property
    def hinges(self) -> tuple[Hinge, ...]: ...

    @property
    def actuators(self) -> tuple[Actuator, ...]: ...

    @property
    def defaults(self) -> dict[sp.Symbol, sp.Expr]: ...


def surrogate_hinges(mech: Linkage) -> tuple[str, ...] | Actuator:
    """One hinge per actuator whose angle its stroke fixes: with the input hinges and the other
    surrogates it fixes the pose (the rank of the closure Jacobian reaches 3n), so the
    kinematics solve the rigid linkage from those angles and the strokes fix the surrogates'
    angles by a regular small system (docs/levels.md, "Actuators"). Hinges on the actuated
    link come first, then hinges on the frame, each in file order. Returns the actuator that
    does not drive the mechanism (its row adds nothing to the rank) instead, if one does not."""
    found = _jacobian_rows(mech)
    if found is None:
        return tuple(h.name for h in mech.hinges if not h.input)[: len(mech.actuators)]
    constraints, turn_of, actuator_row, full = (
        found.constraints,
        found.turn_of,
        found.actuator_row,
        found.full,
    )
    with mpmath.workdps(30):
        held = constraints + [turn_of(h) for h in mech.hinges if h.input]
        rows = held + [actuator_row(a) for a in mech.actuators]
        if _rank(rows) < full:
            for a in mech.actuators:
                others = [actuator_row(b) for b in mech.actuators if b is not a]
                if _rank(held + others) == _rank(rows):
                    return a
            return mech.actuators[0]
        linked = {a.link for a in mech.actuators}
        order = sorted(
            (h for h in mech.hinges if not h.input),
            key=lambda h: 0 if linked & set(h.links) else 1 if mech.ground in h.links else 2,
        )
        chosen: list[str] = []
        rank = _rank(held)
        for h in order:
            if len(chosen) == len(mech.actuators):
                break
            trial = _rank(held + [turn_of(h)])
            if trial > rank:
                held, rank = held + [turn_of(h)], trial
                chosen.append(h.name)
    if len(chosen) < len(mech.actuators):  # no hinge left that the strokes could stand for
        return mech.actuators[len(chosen)]
    return tuple(chosen)


@dataclass(frozen=True)
class _RigidRows:
    """The rigid linkage's constraint rows at the as-fabricated pose, in 30-digit numbers: 2
    per hinge (its pin at the rigid reference) by the 3n pose velocities of the moving links,
    the rotation column scaled by `size` (the largest pin coordinate)."""

    constraints: list[list[mpmath.mpf]]
    pins: list[tuple[mpmath.mpf, mpmath.mpf]]
    size: mpmath.mpf
    column: dict[str, int]  # a moving link's first column
    values: Mapping[sp.Symbol, sp.Expr]

    @property
    def full(self) -> int:
        """3n: the rank that fixes the pose."""
        return 3 * len(self.column)

    def turn_of(self, h: Hinge) -> list[mpmath.mpf]:
        """The row holding hinge h's relative rotation (an input)."""
        row = [mpmath.mpf(0)] * self.full
        for link, sign in ((h.links[1], 1), (h.links[0], -1)):
            if link in self.column:
                row[self.column[link] + 2] = sign
        return row

    def actuator_row(self, a: Actuator) -> list[mpmath.mpf]:
        """The rate of actuator a's stroke, d·v(at) = d·(v + ω × at), ω scaled as above."""
        row = [mpmath.mpf(0)] * self.full
        j = self.column[a.link]
        with mpmath.workdps(30):
            parts = [mp_at(e, self.values) for e in (*a.direction, *a.at)]
            # the reader has checked `at` and `direction` finite before the rank is taken
            dx, dy, x, y = (mpmath.mpf(0) if v is None else v for v in parts)
            row[j], row[j + 1], row[j + 2] = dx, dy, (dy * x - dx * y) / self.size
        return row


def _jacobian_rows(mech: Linkage) -> _RigidRows | None:
    """The rigid linkage's rows at the as-fabricated pose (None: values not finite)."""
    values = mech.defaults
    moving = [lk.name for lk in mech.links if lk.name != mech.ground]
    column = {name: 3 * k for k, name in enumerate(moving)}
    pins: list[tuple[mpmath.mpf, mpmath.mpf]] = []
    with mpmath.workdps(30):
        for h in mech.hinges:
            shift = h.length / 2 - pivot_distance(h)
            x, y = (
                mp_at(h.at[i] + shift * f(h.plate_angle), values)
                for i, f in enumerate((sp.cos, sp.sin))
            )
            if x is None or y is None:
                return None
            pins.append((x, y))
        size = max((abs(c) for pin in pins for c in pin), default=mpmath.mpf(0)) or mpmath.mpf(1)
        constraints = []
        for h, pin in zip(mech.hinges, pins):
            out = [[mpmath.mpf(0)] * (3 * len(moving)) for _ in range(2)]
            for link, sign in ((h.links[1], 1), (h.links[0], -1)):
                if link in column:
                    j = column[link]
                    out[0][j], out[0][j + 2] = sign, -sign * pin[1] / size
                    out[1][j + 1], out[1][j + 2] = sign, sign * pin[0] / size
            constraints += out
    return _RigidRows(constraints, pins, size, column, values)


@dataclass(frozen=True)
class ClosureRank:
    """The rank of the closure Jacobian of the rigid linkage at the as-fabricated pose."""

    rank: int  # of J_c: 2 rows per hinge, 3 columns per moving link
    mobility: int  # 3n - rank
    dependent: tuple[str, ...]  # inputs whose angle the others (and the loops) already fix
    candidates: tuple[str, ...]  # other hinges that would fix the pose in their place
    collinear: bool = False  # those hinges' pins lie on one line: a toggle position


def closure_rank_of(mech: Linkage) -> ClosureRank | None:
    """Rank of J_c, the Jacobian of the 2m pin constraints of the rigid linkage (each hinge a
    pin at its rigid reference, :func:`~symkin.model.hinges.pivot_distance`) by the 3n pose
    velocities of the moving links at the as-fabricated pose and the file's parameter values
    (None when those values are not finite numbers: the value checks report them). The
    mobility is 3n - rank (docs/levels.md): Grübler's 3n - 2m when the 2m constraints are
    independent, more when some are redundant (a parallelogram with a third leg has 0 and 1).
    With the inputs' rows (each holds its hinge's relative rotation) the rank must reach 3n:
    an input whose row adds nothing is dependent. :attr:`~.mechanism.Mechanism.closure_rank`
    keeps it, computed once per mechanism."""
    found = _jacobian_rows(mech)
    if found is None:
        return None
    constraints, pins, size, turn_of = found.constraints, found.pins, found.size, found.turn_of
    with mpmath.workdps(30):
        rank = _rank(constraints)
        full = found.full
        inputs = [h for h in mech.hinges if h.input]
        with_inputs = constraints + [turn_of(h) for h in inputs]
        dependent: tuple[str, ...] = ()
        candidates: tuple[str, ...] = ()
        collinear = False
        if inputs and rank + len(inputs) == full and _rank(with_inputs) < full:
            total = _rank(with_inputs)
            dependent = tuple(
                h.name
                for h in inputs
                if _rank(constraints + [turn_of(g) for g in inputs if g is not h]) == total
            )
            # the hinges the remaining free motion turns (the null space of J_c and the inputs)
            matrix = np.array([[float(x) for x in r] for r in with_inputs])
            _, sigma, vt = np.linalg.svd(matrix)
            null = vt[int(np.sum(sigma > 1e-8 * sigma[0])) :]
            turns = np.array([[float(x) for x in turn_of(h)] for h in mech.hinges]) @ null.T
            motion = np.abs(turns).max(axis=1) if null.size else np.zeros(len(mech.hinges))
            candidates = tuple(
                h.name
                for h, turn in zip(mech.hinges, motion)
                if not h.input and turn > 1e-6 * max(motion.max(), 1e-300)
            )
            free = [pin for h, pin in zip(mech.hinges, pins) if h.name in candidates]
            collinear = len(free) >= 3 and all(
                abs(
                    (b[0] - free[0][0]) * (free[1][1] - free[0][1])
                    - (b[1] - free[0][1]) * (free[1][0] - free[0][0])
                )
                <= mpmath.mpf(10) ** -12 * size**2
                for b in free[2:]
            )
    return ClosureRank(rank, full - rank, dependent, candidates, collinear)


def _rank(rows: list[list[mpmath.mpf]]) -> int:
    """Numerical rank of a matrix of 30-digit numbers: singular values above 1e-8 of the
    largest in float64 count at once; the smaller ones are settled by a 30-digit SVD (rank
    deficient below 1e-20 of the largest), which costs seconds on large matrices and is only
    needed near a singular pose or for redundant constraints."""
    if not rows or not rows[0]:
        return 0
    sigma = np.linalg.svd(np.array([[float(x) for x in r] for r in rows]), compute_uv=False)
    if not sigma.size or sigma[0] == 0:
        return 0
    if sigma[-1] > 1e-8 * sigma[0]:
        return int(sigma.size)
    exact = mpmath.svd_r(mpmath.matrix(rows), compute_uv=False)
    top = max(exact)
    return sum(1 for x in exact if x > mpmath.mpf(10) ** -20 * top)


def mp_at(expr: sp.Expr, values: Mapping[sp.Symbol, sp.Expr]) -> mpmath.mpf | None:
    """`expr` at the parameter values, 30 digits; None when it is not a finite real number."""
    value = sp.N(expressions.substitute(expr, values), 30)
    if not (value.is_real and value.is_finite):
        return None
    return mpmath.mpf(str(value))
