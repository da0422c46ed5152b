"""The evaluator backends and what each can do (docs/generated-code.md, "Backends"): one table
that every layer reads, as :mod:`.levels` is for the levels.

A backend is how a configuration is evaluated: ``sympy`` the derivation itself in mpmath, or
one of the generated-code backends (``numpy``, ``c``: their emitters and loaders are the rows of
``symkin.codegen.pipeline.REGISTRY``). The command line, the studies and the tests ask a
backend's :class:`Capabilities` what it does (its levels, its sensitivities, the actuators it
takes, what it reports) instead of comparing its name; ``tests/test_backends.py`` pins the
table, so a capability that goes missing fails there rather than being skipped elsewhere.
"""

from __future__ import annotations

from dataclasses import dataclass

from . import levels
from .errors import InputError

#: What the `loaded` level reports beyond the deviations (docs/physics.md, "What loaded
#: reports"), by the generated module's keys: the input hinges' moments and stiffness, the
#: points' stiffness and compliance, the plates' stress, the actuators' stroke, force and
#: stiffness, and (with loads) the buckling factor. A backend's `reports` are what its own code
#: computes; `symkin eval` prints the derivation's report whichever the backend.
REPORTS: tuple[str, ...] = ("inputs", "stiffness", "compliance", "plates", "actuators", "buckling")


@dataclass(frozen=True)
class Capabilities:
    """One row of the backend table: what the backend evaluates, and how."""

    name: str  # --backend, symkin.evaluate(backend=...), symkin.compile(backend=...)
    title: str  # how messages name it ("the generated C evaluators")
    #: emitted from the plan and loaded (symkin.codegen.pipeline); else the derivation, in mpmath
    generated: bool
    levels: frozenset[str]  # the levels it evaluates
    sensitivities: frozenset[str]  # the levels at which it gives derivatives (docs/sensitivity.md)
    #: the number types it evaluates in ("mpmath": any number of digits, 40 by default)
    precisions: tuple[str, ...]
    actuators: frozenset[str]  # the levels at which it takes stroke actuators
    forces: frozenset[str]  # the levels at which it takes force actuators
    #: the levels at which it gives derivatives with force actuators driving
    force_sensitivities: frozenset[str]
    #: what its own code reports at `loaded` beyond the deviations (of :data:`REPORTS`)
    reports: frozenset[str]
    compiler: bool  # needs a C compiler (symkin.codegen.toolchain)
    batched: bool  # many configurations in one call (arrays of inputs)
    scenes: bool  # emits a scene's evaluator over its variants (docs/scene.md)


_GENERATED_LEVELS = frozenset(levels.GENERATED)
_GENERATED_SENSITIVITIES = frozenset(
    lv.name for lv in levels.LEVELS if lv.generated and lv.sensitivity
)

#: Every backend, the mpmath evaluation first, then the generated-code backends in the order of
#: every listing (CLI choices, hints, derive's files).
BACKENDS: tuple[Capabilities, ...] = (
    Capabilities(
        "sympy",
        title="sympy",
        generated=False,
        levels=frozenset(levels.NAMES),
        sensitivities=frozenset(lv.name for lv in levels.LEVELS if lv.sensitivity),
        precisions=("mpmath",),
        actuators=frozenset(levels.NAMES),
        forces=frozenset(lv.name for lv in levels.LEVELS if lv.needs_stiffness),
        force_sensitivities=frozenset(levels.LOADED),
        reports=frozenset(REPORTS),
        compiler=False,
        batched=False,
        scenes=False,
    ),
    Capabilities(
        "numpy",
        title="numpy",
        generated=True,
        levels=_GENERATED_LEVELS,
        sensitivities=_GENERATED_SENSITIVITIES,
        precisions=("float64", "float32"),
        actuators=_GENERATED_LEVELS,
        forces=frozenset(levels.LOADED),
        force_sensitivities=frozenset(levels.LOADED),
        reports=frozenset(REPORTS),
        compiler=False,
        batched=True,
        scenes=True,
    ),
    Capabilities(
        "c",
        title="C",
        generated=True,
        levels=_GENERATED_LEVELS,
        sensitivities=_GENERATED_SENSITIVITIES,
        precisions=("float64",),
        actuators=_GENERATED_LEVELS,
        forces=frozenset(levels.LOADED),
        force_sensitivities=frozenset(),  # templates/c/reduced_sens.c: stroke actuators alone
        reports=frozenset(REPORTS) - {"buckling"},  # <name>_loaded_report: no buckling search
        compiler=True,
        batched=True,
        scenes=True,
    ),
)

#: Every backend's name, in table order.
NAMES: tuple[str, ...] = tuple(b.name for b in BACKENDS)
#: The generated-code backends (symkin.codegen.pipeline.REGISTRY has a row for each).
GENERATED: tuple[str, ...] = tuple(b.name for b in BACKENDS if b.generated)
#: The backend `symkin eval` and `symkin.evaluate` use when none is given: the derivation.
DEFAULT = "sympy"

_BY_NAME = {b.name: b for b in BACKENDS}


def get(name: str, entry: str = "--backend") -> Capabilities:
    """The row of backend `name`; an unknown name is bad input (exit 2) naming the choices."""
    try:
        return _BY_NAME[name]
    except KeyError:
        raise InputError(
            f"unknown backend '{name}'", entry=entry, hint="backends: " + ", ".join(NAMES)
        ) from None


def having(**wanted: object) -> tuple[str, ...]:
    """The names of the backends whose capabilities match `wanted`, in table order: a boolean
    field equal to its value, a set field (levels, sensitivities, ...) holding the value, e.g.
    ``having(generated=True)``, ``having(force_sensitivities="loaded")``."""
    for key in wanted:
        if key not in Capabilities.__dataclass_fields__:
            raise TypeError(f"no capability {key!r}")

    def matches(b: Capabilities) -> bool:
        for key, want in wanted.items():
            have = getattr(b, key)
            if isinstance(have, frozenset | tuple):
                if want not in have:
                    return False
            elif have != want:
                return False
        return True

    return tuple(b.name for b in BACKENDS if matches(b))
