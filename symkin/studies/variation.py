"""How parameters and inputs vary in `symkin tolerance` and `symkin sweep` (docs/cli.md): the
`--vary NAME=SPREAD` and `--input H=LO:HI:N` options, parsed by a whitelist.

A spread is one of

    ±A  or  +-A       uniform within ±A around the parameter's value (A% : A percent of it)
    uniform(LO, HI)   uniform between LO and HI
    normal(MU, SIGMA) normal with mean MU and standard deviation SIGMA

with A, LO, HI, MU, SIGMA numbers or expressions of numbers (`pi`, `deg`, `sqrt`, ... as in a
mechanism file, through the same whitelist parser; nothing is executed). A spread describes a
parameter's value with every other parameter at its nominal value. A parameter whose default
reads varied ones follows them, its own spread on top: a sample draws each varied parameter's
offset from its nominal value, and the parameters are then set in file order, each from its
default (or value) plus its offset (docs/sensitivity.md).
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from ..core.errors import InputError
from ..model.mechanism import Mechanism
from .configuration import exact_value

KINDS = ("pm", "uniform", "normal")
#: Grid points of an input given as LO:HI (without :N).
DEFAULT_POINTS = 25
#: The input range when an input is not given.
DEFAULT_RANGE = (-0.2, 0.2)
#: The most evaluations (grid configurations, times samples in a sweep) one command runs unless
#: `--max-evaluations` raises it: refused before any work, so one mistyped number cannot take
#: the machine (1e9 grid values alone are 8 GB of float64; docs/cli.md).
MAX_EVALUATIONS = 10**8
_CALL = re.compile(r"^\s*(normal|uniform)\s*\((.*)\)\s*$", re.DOTALL)


@dataclass(frozen=True)
class Spread:
    """How one parameter varies around its nominal value."""

    name: str
    kind: str  # "pm", "uniform" or "normal"
    a: float  # pm: half-width; uniform: low; normal: mean
    b: float  # uniform: high; normal: sigma (pm: unused)
    text: str  # as given

    def offsets(self, rng: np.random.Generator, n: int, nominal: float) -> np.ndarray:
        """n draws of the value minus `nominal`."""
        if self.kind == "pm":
            return rng.uniform(-self.a, self.a, n)
        if self.kind == "uniform":
            return rng.uniform(self.a, self.b, n) - nominal
        return rng.normal(self.a, self.b, n) - nominal

    @property
    def half_width(self) -> float:
        """The tolerance ±a of a `pm` spread (what `tolerance` stacks up)."""
        return self.a


def parse_vary(
    items: Sequence[str] | None,
    mech: Mechanism,
    nominal: Mapping[str, float],
    kinds: Sequence[str] = KINDS,
    option: str = "--vary",
) -> dict[str, Spread]:
    """NAME=SPREAD options, one per parameter, in file order; `nominal` gives each parameter's
    value (for A%). Bad input (exit 2) names the option and what to write instead."""
    names = [p.name for p in mech.parameters]
    example = f"{option} {names[0] if names else 'l'}=±1e-5"
    if not items:
        raise InputError(
            "no parameter to vary",
            file=mech.path,
            entry=option,
            hint=f"give at least one, e.g. {example}"
            if names
            else "the file has no [parameters]: make the dimensions to vary parameters",
        )
    found: dict[str, Spread] = {}
    for item in items:
        name, sep, text = item.partition("=")
        name = name.strip()
        if not sep or not text.strip():
            raise InputError(
                f"'{item}' is not NAME=SPREAD",
                file=mech.path,
                entry=option,
                hint=f"write e.g. {example}",
            )
        if name not in names:
            raise InputError(
                f"'{name}' is not a parameter of the file",
                file=mech.path,
                entry=option,
                hint="parameters: " + (", ".join(names) or "none"),
            )
        if name in found:
            raise InputError(
                f"'{name}' is varied twice",
                file=mech.path,
                entry=option,
                hint="give one spread per parameter",
            )
        found[name] = _spread(name, text.strip(), mech, nominal[name], option)
        if found[name].kind not in kinds:
            allowed = " or ".join(
                {"pm": "±A", "uniform": "uniform(LO,HI)", "normal": "normal(MU,SIGMA)"}[k]
                for k in kinds
            )
            raise InputError(
                f"'{item}': this command takes {allowed}",
                file=mech.path,
                entry=option,
                hint=f"write e.g. {example}",
            )
    return {n: found[n] for n in names if n in found}


def _spread(name: str, text: str, mech: Mechanism, nominal: float, option: str) -> Spread:
    entry = f"{option} {name}"

    def number(value: str) -> float:
        x = float(exact_value(value.strip(), entry, mech.path))
        if not math.isfinite(x):
            raise InputError(f"'{value}' is not a finite number", file=mech.path, entry=entry)
        return x

    for prefix in ("±", "+-", "+/-"):
        if text.startswith(prefix):
            body = text[len(prefix) :].strip()
            percent = body.endswith("%")
            a = number(body[:-1] if percent else body)
            a = abs(nominal) * a / 100 if percent else a
            if not a > 0:
                raise InputError(
                    f"'{text}': the half-width must be positive",
                    file=mech.path,
                    entry=entry,
                    hint="write e.g. ±1e-5 or ±2%"
                    + (
                        " (a percentage of a parameter of value 0 is 0)"
                        if percent and nominal == 0
                        else ""
                    ),
                )
            return Spread(name, "pm", a, 0.0, text)
    match = _CALL.match(text)
    if match is None:
        raise InputError(
            f"'{text}' is not a spread",
            file=mech.path,
            entry=entry,
            hint="write ±A, A%, uniform(LO,HI) or normal(MU,SIGMA)",
        )
    kind, args = match.group(1), _split(match.group(2))
    if len(args) != 2:
        raise InputError(
            f"{kind}() takes two numbers, got {len(args)}",
            file=mech.path,
            entry=entry,
            hint=f"write {kind}(" + ("LO,HI)" if kind == "uniform" else "MU,SIGMA)"),
        )
    a, b = (number(v) for v in args)
    if kind == "uniform" and not a < b:
        raise InputError(
            f"'{text}': empty interval", file=mech.path, entry=entry, hint="give LO < HI"
        )
    if kind == "normal" and not b > 0:
        raise InputError(
            f"'{text}': sigma must be positive",
            file=mech.path,
            entry=entry,
            hint="give a positive standard deviation",
        )
    return Spread(name, kind, a, b, text)


def _split(text: str) -> list[str]:
    """Arguments separated by the commas outside parentheses."""
    parts, depth, start = [], 0, 0
    for i, ch in enumerate(text):
        if ch == "(":
            depth += 1
        elif ch == ")":
            depth -= 1
        elif ch == "," and depth == 0:
            parts.append(text[start:i])
            start = i + 1
    parts.append(text[start:])
    return [p for p in parts if p.strip()] if text.strip() else []


@dataclass(frozen=True)
class Grid:
    """The input values: per input (in the mechanism's input order) its sample values; the
    configurations are every combination."""

    values: dict[str, np.ndarray]

    @property
    def rows(self) -> np.ndarray:
        """(n, n_inputs): every combination, the last input varying fastest; without inputs
        (a structure) one configuration, (1, 0)."""
        if not self.values:
            return np.zeros((1, 0))
        mesh = np.meshgrid(*self.values.values(), indexing="ij")
        return np.stack([m.reshape(-1) for m in mesh], axis=1)

    def as_json(self) -> dict:
        return {k: [float(v[0]), float(v[-1]), len(v)] for k, v in self.values.items()}


def check_evaluations(
    mech: Mechanism,
    counts: Mapping[str, int],
    limit: int = MAX_EVALUATIONS,
    samples: int = 1,
) -> None:
    """Refuse (exit 2), before any array is made, a grid of `counts` values per input (times
    `samples` parameter sets) above `limit` evaluations, naming the option and the memory the
    inputs and results alone would take (float64 input rows and two coordinates per point)."""
    total = math.prod(counts.values()) * samples
    if total <= limit:
        return
    width = len(counts) + 2 * max(1, len(mech.points))
    memory = total * 8 * width
    entry = "--input" if samples == 1 else "--input, --samples"
    given = " x ".join(f"{n} ({h})" for h, n in counts.items() if n > 1) or "1"
    if samples > 1:
        given += f" x {samples} samples"
    raise InputError(
        f"{given} = {total:.3g} evaluations, more than the limit of {limit:.3g} "
        f"(its inputs and results alone would take at least {_bytes(memory)} of memory)",
        file=mech.path,
        entry=entry,
        hint="use fewer points (H=LO:HI:N) or samples, or raise the limit with "
        "--max-evaluations N if the machine has the memory",
    )


def _bytes(n: float) -> str:
    """A byte count in the largest unit that keeps it at least 1 (B, kB, MB, GB, TB, ...)."""
    units = ("B", "kB", "MB", "GB", "TB", "PB", "EB")
    k = 0
    while n >= 1000 and k < len(units) - 1:
        n /= 1000
        k += 1
    return f"{n:.3g} {units[k]}"


def parse_grid(
    items: Sequence[str] | None,
    mech: Mechanism,
    option: str = "--input",
    points: int = DEFAULT_POINTS,
    limit: int = MAX_EVALUATIONS,
    samples: int = 1,
) -> Grid:
    """H=V, H=LO:HI or H=LO:HI:N options (radians, or a stroke actuator's file unit;
    expressions allowed); an input hinge not given spans DEFAULT_RANGE with `points` values, an
    actuator ± its default stroke span (Mechanism.stroke_spans). More than `limit` evaluations
    (the configurations times `samples`) are refused before the grid is made."""
    inputs = mech.drives
    strokes = mech.stroke_spans()
    given: dict[str, np.ndarray] = {}
    counts: dict[str, int] = {}
    for item in items or ():
        name, sep, span = item.partition("=")
        name = name.strip()
        if not sep or name not in inputs:
            raise InputError(
                f"'{item}' is not INPUT=LO:HI:N for an input hinge or actuator",
                file=mech.path,
                entry=option,
                hint="inputs: " + ", ".join(inputs),
            )
        if name in given:
            raise InputError(f"'{name}' given twice", file=mech.path, entry=option)
        parts = span.split(":")
        if len(parts) not in (1, 2, 3) or not all(p.strip() for p in parts):
            raise InputError(
                f"'{item}' is not {name}=V, {name}=LO:HI or {name}=LO:HI:N",
                file=mech.path,
                entry=option,
                hint=f"write e.g. {name}=-0.2:0.2:41",
            )
        ends = [float(exact_value(p.strip(), f"{option} {name}", mech.path)) for p in parts[:2]]
        count = 1 if len(parts) == 1 else points
        if len(parts) == 3:
            try:
                count = int(parts[2])
            except ValueError:
                count = 0
            if count < 1:
                raise InputError(
                    f"'{parts[2]}' is not a positive number of points",
                    file=mech.path,
                    entry=f"{option} {name}",
                    hint=f"write e.g. {name}=-0.2:0.2:41",
                )
        if len(ends) == 2 and not ends[0] < ends[1]:
            raise InputError(
                f"empty range {ends[0]:g}:{ends[1]:g}",
                file=mech.path,
                entry=f"{option} {name}",
                hint="give LO < HI",
            )
        actuated = name in strokes or any(a.name == name for a in mech.actuators)
        if not actuated and any(not abs(v) <= math.pi for v in ends):  # a force is in N
            raise InputError(
                f"'{item}' goes beyond a half turn",
                file=mech.path,
                entry=f"{option} {name}",
                hint="an input is its plate's rotation from the as-fabricated "
                "pose: keep it within -pi..pi",
            )
        counts[name] = count
        given[name] = np.array(ends[:2])
    check_evaluations(mech, {n: counts.get(n, points) for n in inputs}, limit, samples)
    default = {n: (-strokes[n], strokes[n]) if n in strokes else DEFAULT_RANGE for n in inputs}
    values = {}
    for n in inputs:
        ends = given.get(n, np.array(default[n]))
        values[n] = (
            ends[:1] if len(ends) == 1 else np.linspace(ends[0], ends[1], counts.get(n, points))
        )
    return Grid(values)
