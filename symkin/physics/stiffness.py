"""Plate stiffness from a hinge's E, thickness, width and nu (docs/physics.md).

EI = E'·b·t³/12 and EA = E'·b·t with E' = E/(1 − ν²) for a wide plate (b ≥ 5 t: the plate bends
in plane strain, its anticlastic curvature suppressed) and E' = E for a narrower one; the shear
stiffness κGA = κ·G·b·t with Timoshenko's κ = 5/6 of a rectangle and G = E/(2(1 + ν)) (plane
strain leaves the in-plane shear modulus alone). All are sympy expressions in the parameter
symbols, written in the file's length unit u (EI in N·u², EA and κGA in N), so the physics runs
in the file's unit like the kinematics: a length given in mm stays in mm and the unit's size s
(metres per u) enters only here, EI_u = EI/s², and in the loads' moments, M_u = M/s.

The numbers come from each plate's section (symkin.model.sections, by its profile in
symkin.model.profiles: the uniform plate by default); a level whose beams are uniform refuses a
plate of another profile by name, unless it takes notches (`equilibrium` shoots them along
their section, `loaded`'s Python level takes their relation terms; the generated `loaded`
takes uniform plates).
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

from ..core.errors import InputError
from ..model.entries import STIFFNESS_REQUIRED as REQUIRED
from ..model.mechanism import Mechanism
from ..model.notches import Notch
from ..model.profiles import section_of
from ..model.sections import Section


@dataclass(frozen=True)
class PlateStiffness:
    """Bending, axial and shear stiffness of one plate in the file's unit (EI: N·u², EA and
    κGA: N), its beam theory (`beam`, model.hinges.BEAMS) and its section (model.sections).
    For a uniform plate EI, EA and κGA are its own; for another profile those of the uniform
    plate with the same end compliances under a moment, a normal force and a shear force:
    l/∫dx/EI, l/∫dx/EA, l/∫dx/κGA."""

    hinge: str
    length: sp.Expr
    EI: sp.Expr
    EA: sp.Expr
    kGA: sp.Expr
    beam: str
    section: Section

    @property
    def stretches(self) -> bool:
        """A Reissner plate stretches and shears; the elastica does neither."""
        return self.beam == "reissner"


def plate_stiffness(
    mech: Mechanism, level: str, uniform: bool = True, notches: bool = False
) -> dict[str, PlateStiffness]:
    """EI, EA and κGA of every plate (hinges that are not `rigid`) and its section, by hinge
    name; a plate without E, thickness or width is bad input for `level` (exit 2, naming the
    key and the hinge), and so is a plate whose profile is not uniform when `uniform` (the
    levels' beams are uniform) unless `notches` and it is a notch (model.notches: `equilibrium`
    shoots those along their section, physics.section_beams)."""
    out = {}
    for h in mech.hinges:
        if not h.is_plate:
            continue
        for key in REQUIRED:
            if getattr(h, key) is None:
                raise InputError(
                    f"no '{key}': --level {level} needs E, thickness and width of every plate",
                    file=mech.path,
                    line=h.line,
                    entry=f"[[hinge]] '{h.name}'",
                    hint=f"add {key} = ... to the hinge or to [defaults] (docs/physics.md), or "
                    'make the hinge model = "rigid" (a pin)',
                )
        sec = section_of(h, mech.unit_scale)
        if sec.uniform:
            ei, ea, shear = sec.EI(0), sec.EA(0), sec.kGA(0)
        elif uniform and not (notches and isinstance(sec, Notch)):
            generated = level == "loaded" and isinstance(sec, Notch)
            raise InputError(
                (
                    "--level loaded's generated code and sensitivities take uniform plates"
                    if generated
                    else f"--level {level} takes uniform plates"
                )
                + f": the hinge's profile is {sec.profile!r}",
                file=mech.path,
                line=h.line,
                entry=f"[[hinge]] '{h.name}'",
                hint="evaluate it with symkin eval --level loaded (the Python level takes "
                "notches: docs/physics.md, 'Notch hinges at `loaded`') or --level equilibrium"
                if generated
                else "ask for --level equilibrium, which shoots a notch along its section "
                "(docs/physics.md, 'Notch hinges')"
                if isinstance(sec, Notch)
                else "docs/architecture.md, 'A new profile', says what a level needs from one",
            )
        else:
            c = sec.compliance()
            ei, ea, shear = h.length / c.theta_M, h.length / c.x_N, h.length / c.y_V
        out[h.name] = PlateStiffness(h.name, h.length, ei, ea, shear, h.beam, sec)
    return out
