"""The plates' finite-strain law in a `symkin fea` deck (docs/fea.md, "Material law").

Both laws have the plate's E and ν as their small-strain limit; they differ at second order in the
strain, which is what a notch mechanism's deviation (second order in the angle) feels at a few
tenths of a percent of strain (docs/physics.md, "Notch mechanisms against a continuum"):

- `svk` (the default): `*ELASTIC`, which ccx under NLGEOM takes as St. Venant–Kirchhoff (the
  second Piola–Kirchhoff stress linear in the Green–Lagrange strain);
- `neo-hookean`: `*HYPERELASTIC, NEO HOOKE`, ccx's (Abaqus's) compressible neo-Hookean solid
  U = C10 (Ī1 − 3) + (J − 1)²/D1, whose initial shear and bulk moduli are 2 C10 and 2/D1: so
  C10 = G/2 = E/(4(1 + ν)) and D1 = 2/K = 6(1 − 2ν)/E.
"""

from __future__ import annotations

from ._symkin import InputError

#: The laws `--law` takes, the default first.
LAWS = ("svk", "neo-hookean")
DEFAULT_LAW = LAWS[0]

#: Newtons per force unit of the deck, per law. ccx replaces a compressibility coefficient D1
#: below 1e-10 (in the deck's units) by its default, 0.1/μ (a Poisson's ratio of about 0.475:
#: ccx 2.20, hyperelastics.f, with a *WARNING only); steel's D1 in pascals is about 1e-11, so the
#: neo-Hookean deck is written in meganewtons and megapascals (metres still): forces and moduli
#: scaled alike leave every displacement as it is (measured: docs/fea.md, "Material law").
FORCE_UNIT = {"svk": 1.0, "neo-hookean": 1e6}

#: What the deck's comments and the text output call them.
NAMES = {"svk": "St. Venant-Kirchhoff", "neo-hookean": "neo-Hookean"}


def parse_law(text: str, option: str = "--law", file: str | None = None) -> str:
    """`svk` or `neo-hookean` (any case); anything else is bad input (exit 2, naming `file`,
    the mechanism it is for)."""
    law = text.strip().lower()
    if law not in LAWS:
        raise InputError(
            f"'{text}' is not a material law",
            file=file,
            entry=option,
            hint=f"write {option} svk (St. Venant-Kirchhoff, *ELASTIC: the default) or "
            f"{option} neo-hookean (*HYPERELASTIC, NEO HOOKE); docs/fea.md, 'Material law'",
        )
    return law


def neo_hooke_constants(E: float, nu: float) -> tuple[float, float]:
    """(C10, D1) of the neo-Hookean solid with the small-strain moduli E, ν."""
    return E / (4 * (1 + nu)), 6 * (1 - 2 * nu) / E


def cards(E: float, nu: float, law: str, number) -> list[str]:
    """The material's cards (after `*MATERIAL`) for `law`; `number` formats a value."""
    if law == "svk":
        return ["*ELASTIC", f"{number(E)}, {number(nu)}"]
    if law == "neo-hookean":
        c10, d1 = neo_hooke_constants(E, nu)
        return ["*HYPERELASTIC, NEO HOOKE", f"{number(c10)}, {number(d1)}"]
    raise ValueError(f"unknown law {law!r}")
