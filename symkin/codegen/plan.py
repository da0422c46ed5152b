"""The routines a generated evaluator is made of, derived from an :class:`Analysis`.

    rigid        inputs, params        -> φ_M - φ_P of every hinge, dyad reach and margin
                                          (closed form; absent when a group is not a dyad)
    rigid_res    theta, params         -> rigid loop closure relative to the as-fabricated pose,
                                          Σ (Rot(φ_i) - I) V_i and Φ q (polish / continuation)
    linear       theta, params         -> A (rigid loop Jacobian), r = Φ Δz at the rigid pose
    newton       theta, delta, params  -> F, ∂F/∂δ of the exact compliant closure
    rigid_points theta, params         -> rigid x, y of every requested point
    dev_<level>  theta, delta, params  -> deviation x, y of every requested point

Only what the requested points and levels need is derived: a point whose direct path holds only
input hinges needs no loop solved at any level.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass


from .. import levels as level_table
from ..analysis import Analysis
from ..levels import Level
from .literals import float_literals
from .routines import Argument, Routine, flatten, optimize


@dataclass(frozen=True)
class Plan:
    """Everything a backend template needs, backend-neutral."""

    analysis: Analysis
    points: tuple[str, ...]
    levels: tuple[Level, ...]
    needs_loops: bool                  # some requested level/point needs the loop solution
    closed_form: bool                  # rigid solution by dyads (else Newton + continuation)
    routines: dict[str, Routine]
    n_unknowns: int                    # k = number of non-input hinges (size of δ)
    notes: tuple[str, ...] = ()        # e.g. the variant a tolerance chose, for the headers

    @property
    def mechanism(self):
        return self.analysis.mechanism


def plan(analysis: Analysis, points: Sequence[str] | None = None,
         levels: Sequence[str] | None = None, cse: bool = True,
         notes: Sequence[str] = ()) -> Plan:
    """Derive the routines for the requested points and levels (all by default)."""
    an, kin = analysis, analysis.kin
    names = tuple(p.name for p in an.points if points is None or p.name in points)
    levels = tuple(lv for lv in level_table.LEVELS if levels is None or lv.name in levels)
    inputs = Argument("inputs", tuple(kin.theta[a] for a in kin.inputs))
    params = Argument("params", an.params)
    theta = Argument("theta", an.thetas)
    delta = Argument("delta", an.deltas)

    def moved_by_loops(name: str) -> bool:
        link = an.link[an.mechanism.point(name).link]
        return any(b in kin.unknowns for b in an.structure.tree_path(link))

    needs_loops = bool(an.deltas) and any(lv.needs_delta for lv in levels) and any(
        moved_by_loops(n) for n in names)
    routines: dict[str, Routine] = {}
    sol = an.rigid
    if sol.closed_form and kin.unknowns:
        outs = [sol.phi[kin.hinges[a].M] - sol.phi[kin.hinges[a].P] for a in kin.unknowns]
        outs += [d.reach for d in sol.dyads] + [d.margin for d in sol.dyads]
        routines["rigid"] = Routine("rigid", (inputs, params), sol.assignments, tuple(outs),
                                    "closed-form rigid solution (dyads)")
    if kin.unknowns:
        routines["rigid_res"] = Routine("rigid_res", (theta, params), (),
                                        tuple(an.rigid_residual),
                                        "rigid loop closure relative to the as-fabricated pose")
        a_lin, r_lin = an.linear_system
        routines["linear"] = Routine("linear", (theta, params), (),
                                     flatten(a_lin.tolist()) + tuple(r_lin),
                                     "rigid loop Jacobian A and r = Phi dz")
    if needs_loops and any(lv.name == "exact" for lv in levels):
        routines["newton"] = Routine("newton", (theta, delta, params), (),
                                     tuple(an.residual) + flatten(an.jacobian.tolist()),
                                     "exact compliant closure F(delta) and dF/ddelta")
    routines["rigid_points"] = Routine(
        "rigid_points", (theta, params), (),
        tuple(e for n in names for e in an.point_rigid(n)), "rigid positions of the points")
    for lv in levels:
        args = (theta, delta, params) if lv.needs_delta else (theta, params)
        routines[f"dev_{lv.name}"] = Routine(
            f"dev_{lv.name}", args, (),
            tuple(e for n in names for e in an.point_deviation(n, lv.name)),
            f"deviation of the points at level {lv.name}")
    # Numbers reach the printers as correctly rounded doubles (exact rationals stay in mpmath).
    routines = {k: Routine(r.name, r.arguments,
                           tuple((s, float_literals(e)) for s, e in r.assignments),
                           tuple(float_literals(e) for e in r.outputs), r.doc)
                for k, r in routines.items()}
    if cse:
        routines = {k: optimize(r) for k, r in routines.items()}
    return Plan(an, names, levels, needs_loops, sol.closed_form, routines, len(an.deltas),
                tuple(notes))
