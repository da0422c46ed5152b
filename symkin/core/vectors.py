"""Plane vectors as (x, y) tuples of sympy expressions, and the rotations the kinematics needs.

Rotations of a small angle d from a known pose are written (Rot(d) - I) v with 1 - cos d =
2 sin²(d/2), so a difference of two nearby positions never cancels.
"""

from __future__ import annotations

import sympy as sp

Vec = tuple[sp.Expr, sp.Expr]
ZERO: Vec = (sp.Integer(0), sp.Integer(0))


def add(*vs: Vec) -> Vec:
    return (sp.Add(*(v[0] for v in vs)), sp.Add(*(v[1] for v in vs)))


def sub(a: Vec, b: Vec) -> Vec:
    return (a[0] - b[0], a[1] - b[1])


def scale(k: sp.Expr, v: Vec) -> Vec:
    return (k * v[0], k * v[1])


def rot(phi: sp.Expr, v: Vec) -> Vec:
    """Rot(phi) v."""
    if phi == 0:
        return v
    c, s = sp.cos(phi), sp.sin(phi)
    return (c * v[0] - s * v[1], s * v[0] + c * v[1])


def rot_minus_identity(d: sp.Expr, v: Vec) -> Vec:
    """(Rot(d) - I) v, cancellation-free for small d."""
    if d == 0:
        return ZERO
    c1, s = -2 * sp.sin(d / 2) ** 2, sp.sin(d)
    return (c1 * v[0] - s * v[1], s * v[0] + c1 * v[1])


def perp(v: Vec) -> Vec:
    """v rotated by +90 degrees (the derivative of Rot(phi) v with respect to phi, at phi = 0)."""
    return (-v[1], v[0])


def cross(a: Vec, b: Vec) -> sp.Expr:
    return a[0] * b[1] - a[1] * b[0]


def dot(a: Vec, b: Vec) -> sp.Expr:
    return a[0] * b[0] + a[1] * b[1]


def unit(angle: sp.Expr) -> Vec:
    return (sp.cos(angle), sp.sin(angle))
