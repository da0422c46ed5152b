"""Plate stiffness from a hinge's E, thickness, width and nu (docs/physics.md).

EI = E'·b·t³/12 and EA = E'·b·t with E' = E/(1 − ν²) for a wide plate (b ≥ 5 t: the plate bends
in plane strain, its anticlastic curvature suppressed) and E' = E for a narrower one. Both are
sympy expressions in the parameter symbols, written in the file's length unit u (EI in N·u², EA
in N), so the physics runs in the file's unit like the kinematics: a length given in mm stays in
mm and the unit's size s (metres per u) enters only here, EI_u = EI/s², and in the loads'
moments, M_u = M/s.
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

from ..core.errors import InputError
from ..model.mechanism import STIFFNESS_REQUIRED as REQUIRED
from ..model.mechanism import Hinge, Mechanism

#: A plate at least this many thicknesses wide bends in plane strain: E' = E/(1 - nu^2).
WIDE = 5


@dataclass(frozen=True)
class PlateStiffness:
    """Bending and axial stiffness of one plate in the file's unit (EI: N·u², EA: N)."""

    hinge: str
    length: sp.Expr
    EI: sp.Expr
    EA: sp.Expr


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
        out[h.name] = PlateStiffness(
            h.name, h.length, e * h.width * h.thickness**3 * s2 / 12, e * h.width * h.thickness * s2
        )
    return out
