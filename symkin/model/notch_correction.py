"""The continuum correction of a notch hinge's beam compliances (docs/physics.md, "Notch hinges:
the continuum correction").

A beam over the notch's profile T(x) — Euler–Bernoulli in bending, E' = E/(1 − ν²), plus
Timoshenko's shear ∫ dx/κGA in the deflection under a force — is stiffer than the plane-strain
continuum it stands for: the neck of a circular notch is as long as √(tR), not many times its
thickness t, and plane sections do not stay plane there. Measured with CalculiX on single
right-circular notches (benchmarks/notch_continuum.py, mesh-converged to 0.01 %), the continuum's
compliance over the beam's is a function of τ = t/R alone, fitted as

    factor = 1 + c1·τ + c2·τ²        (0.02 ≤ τ ≤ 0.5)

per compliance at the centre of M's end section: θ_M (rotation per end moment, ∫ dx/E'I),
θ_F = y_M (rotation per end force, ∫ (l − x) dx/E'I) and y_F (deflection per end force,
∫ (l − x)² dx/E'I + ∫ dx/κGA). The factor tends to 1 as τ → 0 (the thin-notch limit, where beam
theory is exact); beyond τ = 0.5 it is an extrapolation.

An elliptical notch takes the fit at its neck's radius of curvature a²/c (:func:`neck_ratio`):
measured against its own FE at t·c/a² = 0.025–0.25 and a/c = 0.4–4, within 0.45 % in θ_M and θ_F
and 1.0 % in y_F (the deep ellipses, a < c, farthest). A corner-filleted notch and a
uniform plate take no correction (factor 1): the uniform plate's continuum is within 0.1 % of its
beam (t/l = 0.025–0.05, rigid clamp faces); a corner-filleted one is 0.5–1.4 % softer than its
beam (the fillets' roots; t/l = 0.025–0.05, r/l = 0.05–0.25), not a function of t/r — left to
`model_error` (docs/physics.md).
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, replace
from typing import Any

from .sections import Compliance

#: Fitted coefficients (c1, c2) of factor = 1 + c1 τ + c2 τ², τ = t/R, per compliance of a
#: right-circular notch: least squares on the six mesh-converged CalculiX runs of
#: benchmarks/results-notch.json (t/R = 0.02, 0.05, 0.1, 0.2, 0.3, 0.5).
CIRCULAR: dict[str, tuple[float, float]] = {
    "theta_M": (0.40919098075729876, -0.31030597771777113),
    "theta_F": (0.40919098075729876, -0.31030597771777113),
    "y_F": (0.423184439191432, -0.4614065792385148),
}
#: The range of t/R the fit was made on.
RANGE = (0.02, 0.5)
#: The fit's largest relative residual against the FE over RANGE, per compliance.
RESIDUAL = {"theta_M": 2.7e-4, "theta_F": 2.7e-4, "y_F": 5.1e-4}
#: The profiles the fit applies to through their neck's t/R (the others: no correction).
NOTCHES = ("circular", "elliptical")
#: The profiles whose beam is taken as it is.
PLATES = ("uniform", "corner_filleted")


@dataclass(frozen=True)
class Correction:
    """Factors on the beam's compliances at the centre of M's end section: θ_M (∫ dx/E'I),
    θ_F = y_M (∫ (l − x) dx/E'I) and y_F (∫ (l − x)² dx/E'I + ∫ dx/κGA). Floats or sympy
    expressions, as τ was given."""

    theta_M: Any
    theta_F: Any
    y_F: Any

    @property
    def y_M(self) -> Any:
        """The factor on the deflection per end moment: θ_F's (Maxwell–Betti)."""
        return self.theta_F


#: No correction.
IDENTITY = Correction(1, 1, 1)


def _factor(name: str, tau: Any) -> Any:
    c1, c2 = CIRCULAR[name]
    return 1 + c1 * tau + c2 * tau**2


def continuum_correction(profile: str, t_over_R: Any = 0) -> Correction:
    """The factors on a notch's beam compliances (docs/physics.md, "Notch hinges: the continuum
    correction"): for "circular" and "elliptical", 1 + c1 τ + c2 τ² at τ = `t_over_R` (the neck's
    thickness over its radius of curvature: :func:`neck_ratio`), a float or a sympy expression;
    for "uniform" and "corner_filleted", 1."""
    if profile in PLATES:
        return IDENTITY
    if profile not in NOTCHES:
        raise ValueError(
            f"no continuum correction for profile {profile!r} "
            f"(known: {', '.join(NOTCHES + PLATES)})"
        )
    if isinstance(t_over_R, (int, float)) and t_over_R < 0:
        raise ValueError(f"t/R must be positive, not {t_over_R}")
    return Correction(*(_factor(name, t_over_R) for name in ("theta_M", "theta_F", "y_F")))


def neck_ratio(profile: str, thickness: Any, **keys: Any) -> Any:
    """τ of a notch: its thinnest thickness over the radius of curvature of its faces at the
    neck — `radius` for "circular", semi_axis²/depth for "elliptical" (the ellipse's curvature at
    its vertex; its beam-over-continuum error follows the circle's at that radius)."""
    if profile == "circular":
        return thickness / keys["radius"]
    if profile == "elliptical":
        return thickness * keys["depth"] / keys["semi_axis"] ** 2
    raise ValueError(f"profile {profile!r} has no neck radius (known: {', '.join(NOTCHES)})")


def corrected(compliance: Compliance, correction: Correction) -> Compliance:
    """A section's beam compliances (model.sections.Compliance) times the correction: θ_M and
    θ_F by theirs, the bending y_F and the shear y_V both by y_F's (its factor is on their sum,
    the Timoshenko deflection); the stretch x_N as it is (not measured)."""
    return replace(
        compliance,
        theta_M=compliance.theta_M * correction.theta_M,
        theta_F=compliance.theta_F * correction.theta_F,
        y_F=compliance.y_F * correction.y_F,
        y_V=compliance.y_V * correction.y_F,
    )


#: What remains of a notch's beam against the continuum, relative, per profile: the fit's
#: residual for a corrected circular notch (y_F's, the larger), the elliptical notches' spread
#: about the circle's fit (1.0 % in y_F), the corner-filleted plates' uncorrected 0.5–1.4 % in
#: θ_M and up to 1.7 % in y_F (docs/physics.md, "Notch hinges: the continuum correction").
REMAINING = {"circular": RESIDUAL["y_F"], "elliptical": 0.010, "corner_filleted": 0.017}
#: The beam's drift of a circular notch's centre under a pure moment, k = y_c/(R θ), against the
#: FE's, relative: (t/R, |beam − FE|/FE) of docs/physics.md's table, the gap linear between rows
#: and beyond the last.
CENTRE_GAP = ((0.0, 0.003), (0.05, 0.005), (0.2, 0.008), (0.3, 0.030), (0.5, 0.089))


def remaining(profile: str, t_over_R: float, correct: bool) -> float:
    """The relative error of a notch's beam compliances against a plane-strain continuum after
    the correction (`correct`) or without it: the fit's residual inside RANGE, the factor's
    distance from 1 without it (the uncorrected beam's own error) or beyond RANGE (an
    extrapolation: taken as large as the correction itself)."""
    if profile == "uniform":
        return 0.0
    if profile not in NOTCHES:
        return REMAINING[profile]
    gap = abs(float(continuum_correction(profile, t_over_R).y_F) - 1)
    gap = max(gap, abs(float(continuum_correction(profile, t_over_R).theta_M) - 1))
    if not correct or t_over_R > RANGE[1]:  # below RANGE the factor tends to 1: the fit holds
        return gap
    return REMAINING[profile]


def centre_gap(t_over_R: float) -> float:
    """|k_beam − k_FE|/k_FE of the notch's centre drift (CENTRE_GAP, interpolated)."""
    rows = CENTRE_GAP
    for (x0, y0), (x1, y1) in itertools.pairwise(rows):
        if t_over_R <= x1:
            return y0 + (y1 - y0) * (max(t_over_R, x0) - x0) / (x1 - x0)
    (x0, y0), (x1, y1) = rows[-2], rows[-1]
    return y1 + (y1 - y0) * (t_over_R - x1) / (x1 - x0)
