"""Plate stiffness from a hinge's E, thickness, width and nu (docs/physics.md).

EI = E'·b·t³/12 and EA = E'·b·t with E' = E/(1 − ν²) for a wide plate (b ≥ 5 t: the plate bends
in plane strain, its anticlastic curvature suppressed) and E' = E for a narrower one; the shear
stiffness κGA = κ·G·b·t with Timoshenko's κ = 5/6 of a rectangle and G = E/(2(1 + ν)) (plane
strain leaves the in-plane shear modulus alone). All are sympy expressions in the parameter
symbols, written in the file's length unit u (EI in N·u², EA and κGA in N), so the physics runs
in the file's unit like the kinematics: a length given in mm stays in mm and the unit's size s
(metres per u) enters only here, EI_u = EI/s², and in the loads' moments, M_u = M/s.
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

from ..core.errors import InputError
from ..model.entries import STIFFNESS_REQUIRED as REQUIRED
from ..model.entries import Hinge
from ..model.mechanism import Mechanism

#: A plate at least this many thicknesses wide bends in plane strain: E' = E/(1 - nu^2).
WIDE = 5
#: Timoshenko's shear coefficient of a rectangular section.
SHEAR_COEFFICIENT = sp.Rational(5, 6)


@dataclass(frozen=True)
class PlateStiffness:
    """Bending, axial and shear stiffness of one plate in the file's unit (EI: N·u², EA and
    κGA: N) and its beam theory (`beam`, model.hinges.BEAMS)."""

    hinge: str
    length: sp.Expr
    EI: sp.Expr
    EA: sp.Expr
    kGA: sp.Expr
    beam: str

    @property
    def stretches(self) -> bool:
        """A Reissner plate stretches and shears; the elastica does neither."""
        return self.beam == "reissner"


def modulus(hinge: Hinge) -> sp.Expr:
    """E' = E/(1 − ν²) when width ≥ WIDE·thickness (plane strain), else E."""
    return sp.Piecewise(
        (hinge.E / (1 - hinge.nu**2), hinge.width >= WIDE * hinge.thickness), (hinge.E, True)
    )


def plate_stiffness(mech: Mechanism, level: str) -> dict[str, PlateStiffness]:
    """EI and EA of every plate (hinges that are not `rigid`), by hinge name; a plate without E,
    thickness or width is bad input for `level` (exit 2, naming the key and the hinge)."""
    out = {}
    s2 = mech.unit_scale**2
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
        e = modulus(h)
        area = h.width * h.thickness * s2
        shear = SHEAR_COEFFICIENT * h.E / (2 * (1 + h.nu)) * area
        out[h.name] = PlateStiffness(
            h.name, h.length, e * area * h.thickness**2 / 12, e * area, shear, h.beam
        )
    return out
