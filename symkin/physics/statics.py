"""The `loaded` level's derivation (CONTRACT §7, docs/physics.md): plate end loads from the statics
of the pin linkage, each plate's force compliance added to its circular arc, loops closed exactly.

All sympy, in the symbols the kinematic levels use (theta_a: rigid hinge angles, delta_a: their
compliant corrections, the parameters) and three more families, each a named intermediate:

1. Statics of the rigid pin linkage at the rigid pose, with a torsional spring k_a = EI_a/l_a in
   every plate and the file's dead loads: virtual work over the non-input hinge angles with the
   loop closure as constraint gives A^T μ = Q, where A is the rigid loop Jacobian (the matrix of
   the first-order level) and Q_a = −k_a θ_a + s_a Σ_loads [(X − R_a) × F + M] the generalized
   forces (R_a the pin, s_a the paper orientation, the loads on links beyond hinge a). The
   multipliers `mu_k` (angular, x, y per loop) are the moment and force the loop's chord
   transmits: the pin force on i+(c) is −μ, on i−(c) +μ.
2. Hinge forces n_a (what link M exerts on the plate at its M end, frame axes): a chord's from its
   μ, a tree hinge's from the balance of the links beyond it (the loads and chord forces on them).
3. Per plate the components (N, V) of n_a along and across its mid-direction R(θ_a/2)u (in P's
   plate frame), and its force compliance, the clamped–guided plate's end displacement at fixed
   end rotation: `compliance_x_a`, `compliance_y_a` = R(θ_a/2)·(N l/EA, V l³/(12 EI)) in P's plate
   frame, added to the circular arc's Δf, Δg. Then the loops are closed exactly by the `exact`
   level's Newton on δ, the compliance held at its rigid-pose value.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from functools import cached_property

import sympy as sp

from .. import vectors as V
from ..analysis import Analysis
from ..hinge_models import plate_functions
from ..structure import Structure
from .stiffness import PlateStiffness, is_plate, plate_stiffness


@dataclass(frozen=True)
class PlateLoad:
    """One hinge's loads at the rigid pose: force n (frame axes), its components (N, V) along and
    across the plate's mid-direction, the compliance symbols and their expressions."""

    label: int
    force: V.Vec
    axial: sp.Expr
    shear: sp.Expr
    compliance: tuple[sp.Symbol, sp.Symbol] | None
    displacement: V.Vec | None


class LoadedDerivation:
    """The `loaded` level of a structure: statics, plate loads and the loaded loop closure."""

    def __init__(self, structure: Structure, points=None) -> None:
        self.structure = structure
        self.mechanism = mech = structure.mechanism
        self.stiffness: dict[str, PlateStiffness] = plate_stiffness(mech, "loaded")
        label = {name: a for a, name in enumerate(structure.hinges, start=1)}
        self.compliance = {label[h.name]: (sp.Symbol(f"compliance_x_{label[h.name]}", real=True),
                                           sp.Symbol(f"compliance_y_{label[h.name]}", real=True))
                           for h in mech.hinges if is_plate(h)}

        def plate(hinge):
            """The physical plate: circular arc (pure moment) plus its force compliance."""
            if not is_plate(hinge):
                return plate_functions(hinge)
            pf = plate_functions(hinge, shape="circular_arc")
            ex, ey = self.compliance[label[hinge.name]]
            return dataclasses.replace(pf, f=pf.f + ex, g=pf.g + ey, df=pf.df + ex,
                                       dg=pf.dg + ey)

        #: The loaded closure: the exact level's equations with the plates of `plate`.
        self.analysis = Analysis(structure, points, plate)
        self.kin = self.analysis.kin
        loops = len(self.kin.chords)
        self.mu = tuple(sp.Symbol(f"mu_{k}", real=True) for k in range(1, 3 * loops + 1))

    # -- 1. statics --------------------------------------------------------------------------------
    def spring(self, a: int) -> sp.Expr:
        """k_a = EI_a/l_a for a plate, 0 for a pin."""
        h = self.kin.hinges[a]
        stiff = self.stiffness.get(h.name)
        return stiff.EI / stiff.length if stiff else sp.Integer(0)

    @cached_property
    def generalized_forces(self) -> sp.Matrix:
        """Q over the non-input hinge angles: −k_a θ_a plus the loads' moments about the pin."""
        kin, s = self.kin, self.structure
        scale = self.mechanism.unit_scale
        link = {name: i for i, name in enumerate(s.links)}
        rows = []
        for a in kin.unknowns:
            h = kin.hinges[a]
            q = -self.spring(a) * kin.theta[a]
            pivot = kin.rigid_position(h.P, h.centre)
            for load in self.mechanism.loads:
                j = link[load.link]
                if a in s.tree_path(j):
                    arm = V.sub(kin.rigid_position(j, load.at), pivot)
                    q += h.sign * (V.cross(arm, load.force) + load.moment / scale)
            rows.append(q)
        return sp.Matrix(rows)

    @cached_property
    def statics(self) -> tuple[sp.Matrix, sp.Matrix]:
        """(A^T, Q) with A^T μ = Q: A the rigid loop Jacobian of the first-order level."""
        a_matrix, _ = self.analysis.linear_system
        return a_matrix.T, self.generalized_forces

    # -- 2. hinge forces ---------------------------------------------------------------------------
    def chord_force(self, c: int) -> V.Vec:
        """μ_x, μ_y of the loop of chord c: the pin force on i-(c) (−μ on i+(c))."""
        k = 3 * (c - self.structure.n - 1)
        return self.mu[k + 1], self.mu[k + 2]

    @cached_property
    def plate_loads(self) -> dict[int, PlateLoad]:
        """n_a, (N, V) and the compliance displacement of every hinge, at the rigid pose."""
        kin, s = self.kin, self.structure
        link = {name: i for i, name in enumerate(s.links)}
        on_link: dict[int, list[V.Vec]] = {i: [] for i in range(s.n + 1)}
        for load in self.mechanism.loads:
            on_link[link[load.link]].append(load.force)
        for c in kin.chords:
            f = self.chord_force(c)
            on_link[s.i_plus[c - 1]].append(V.scale(-1, f))
            on_link[s.i_minus[c - 1]].append(f)
        out = {}
        for a, h in kin.hinges.items():
            if a in kin.chords:
                force = V.scale(-h.sign, self.chord_force(a))
            else:
                beyond = [i for i in range(1, s.n + 1) if a in s.tree_path(i)]
                force = V.scale(h.sign, V.add(*(f for i in beyond for f in on_link[i])))
            mid = kin.phi(h.P) + h.angle + kin.theta[a] / 2
            axial = V.dot(force, V.unit(mid))
            shear = V.dot(force, V.perp(V.unit(mid)))
            comp = self.compliance.get(a)
            disp = None
            if comp is not None:
                stiff = self.stiffness[h.name]
                along = (axial * stiff.length / stiff.EA, shear * stiff.length ** 3 / (12 * stiff.EI))
                disp = V.rot(kin.theta[a] / 2, along)
            out[a] = PlateLoad(a, force, axial, shear, comp, disp)
        return out

    # -- results -----------------------------------------------------------------------------------
    def end_moment(self, a: int) -> sp.Expr:
        """Moment link M exerts on the plate at its M end (N·u): EI θ/l − V l/2 at the compliant
        angle θ (the clamped–guided plate under its shear force)."""
        kin = self.kin
        stiff = self.stiffness.get(kin.hinges[a].name)
        if stiff is None:
            return sp.Integer(0)
        theta = kin.theta[a] + (kin.delta[a] if a in kin.unknowns else 0)
        return stiff.EI * theta / stiff.length - self.plate_loads[a].shear * stiff.length / 2

    def energy(self, a: int) -> sp.Expr:
        """Elastic energy of plate a (N·u): bending EI θ²/(2l) plus the force work of its
        compliance, (N² l/EA + V² l³/(12 EI))/2."""
        kin = self.kin
        stiff = self.stiffness.get(kin.hinges[a].name)
        if stiff is None:
            return sp.Integer(0)
        theta = kin.theta[a] + (kin.delta[a] if a in kin.unknowns else 0)
        load = self.plate_loads[a]
        return (stiff.EI * theta ** 2 / (2 * stiff.length)
                + (load.axial ** 2 * stiff.length / stiff.EA
                   + load.shear ** 2 * stiff.length ** 3 / (12 * stiff.EI)) / 2)
