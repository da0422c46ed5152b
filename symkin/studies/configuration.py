"""Values from the user, as exact numbers: inputs (input hinges and actuators), parameter
overrides (the others' defaults re-evaluated), held inputs; and the check that the input hinges
determine the pose. Every backend of `symkin eval` and the studies read their values here, so a
bad value is the same error (exit 2, naming the option) everywhere (docs/cli.md).

A :class:`Configuration` is one configuration as `symkin eval` names it (level, inputs,
parameters), parsed and validated once by :func:`configure`; the levels and backends take it.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass

import mpmath
import numpy as np
import sympy as sp

from ..core import levels
from ..core.errors import AssemblyError, InputError, suggest
from ..kinematics.analysis import Analysis
from ..model import expressions
from ..model.mechanism import Mechanism, check_values


def exact_value(value: object, entry: str, file: str) -> sp.Expr:
    """An input or parameter value (number, whitelisted expression string, or an exact sympy
    number symkin made itself) as an exact number."""
    try:
        if isinstance(value, sp.Rational | sp.Float):
            expr = value
        elif isinstance(value, str):
            expr = expressions.parse(value, {})
        else:
            expr = expressions.number(value)  # type: ignore[arg-type]
    except expressions.ExpressionError as exc:
        raise InputError(
            str(exc), file=file, entry=entry, hint="give a number or an expression such as 10*deg"
        ) from None
    if not (expr.is_real and expr.is_finite):
        raise InputError(f"{value!r} is not a finite real number", file=file, entry=entry)
    try:
        size = abs(expressions.numeric(expr, {}))
    except expressions.NotReal:
        raise InputError(
            f"{value!r} is not a finite real number",
            file=file,
            entry=entry,
            hint="give a number or an expression such as 10*deg",
        ) from None
    if size > expressions.FLOAT64_MAX:
        raise InputError(
            f"{value!r} is beyond a float64 (|value| < 1.8e308)",
            file=file,
            entry=entry,
            hint="give a value the generated code can hold",
        )
    return expr


def parameter_values(
    mechanism: Mechanism, overrides: Mapping[str, object] | None = None
) -> dict[sp.Symbol, sp.Expr]:
    """Exact values of every parameter: overrides, then defaults re-evaluated in file order."""
    overrides = dict(overrides or {})
    known = {p.name for p in mechanism.parameters}
    for key in overrides:
        if key not in known:
            raise InputError(
                f"unknown parameter '{key}'",
                file=mechanism.path,
                entry="--param",
                hint="parameters: " + (", ".join(sorted(known)) or "none"),
            )
    values: dict[sp.Symbol, sp.Expr] = {}
    changed = False
    for p in mechanism.parameters:
        raw = overrides.get(p.name)
        if raw is not None:
            values[p.symbol] = exact_value(raw, f"--param {p.name}", mechanism.path)
            changed = True
        elif not changed:
            values[p.symbol] = p.value
        else:
            # A default re-evaluated with overridden values: numerically (60 digits), so an
            # override can never make sympy build a huge exact number (e.g. l**n, n = 1e9).
            try:
                value = sp.Float(expressions.numeric(p.expr, values), expressions.NUMERIC_DPS)
            except expressions.NotReal:
                value = sp.nan
            if not (value.is_real and value.is_finite) or abs(value) > expressions.FLOAT64_MAX:
                raise InputError(
                    f"parameter '{p.name}' = {p.expr} evaluates to {value} with the overrides",
                    file=mechanism.path,
                    entry="--param",
                    hint="choose override values that keep it finite",
                )
            values[p.symbol] = value
    if changed:
        check_values(mechanism, values, "--param")
    return values


def parameter_floats(mechanism: Mechanism, values: Mapping[sp.Symbol, sp.Expr]) -> dict[str, float]:
    """Parameter values by name, as the doubles the generated evaluators receive."""
    return {p.name: float(sp.N(values[p.symbol], 20)) for p in mechanism.parameters}


def input_values(analysis: Analysis, inputs: Mapping[str, object]) -> dict[int, sp.Expr]:
    """Exact input angles by hinge label; every input hinge, and nothing else, must be given."""
    kin, mech = analysis.kin, analysis.mechanism
    names = {kin.hinges[a].name: a for a in kin.inputs}
    for key in inputs:
        if key not in names:
            raise InputError(
                f"'{key}' is not an input hinge",
                file=mech.path,
                entry="--input",
                hint="inputs: " + ", ".join(names),
            )
    missing = [n for n in names if n not in inputs]
    if missing:
        raise InputError(
            f"no value for the input(s) {', '.join(missing)}",
            file=mech.path,
            entry="--input",
            hint="give every input, e.g. --input " + " --input ".join(f"{n}=0.1" for n in missing),
        )
    values = {names[k]: exact_value(v, f"--input {k}", mech.path) for k, v in inputs.items()}
    _check_half_turns(analysis, values)
    return values


def _check_half_turns(analysis: Analysis, values: Mapping[int, sp.Expr]) -> None:
    """Refuse (exit 3) an input angle beyond a half turn, naming the same pose within one."""
    kin, mech = analysis.kin, analysis.mechanism
    for a, value in values.items():
        if (sp.Abs(value) - sp.pi).is_positive:
            name = kin.hinges[a].name
            same = ""
            if abs(value) < 1e6:
                wrapped = value - 2 * sp.pi * sp.floor(value / (2 * sp.pi) + sp.Rational(1, 2))
                same = f"; the same pose is {name}={float(sp.N(wrapped, 20)):.9g}"
            raise AssemblyError(
                f"{mech.path}: --input {name}={float(sp.N(value, 20)):.9g} rad: an input is "
                f"the rotation of its plate from the as-fabricated pose, |angle| <= pi"
                f"{same}"
            )


def check_fabricated_pose(analysis: Analysis) -> None:
    """Refuse (exit 2) input hinges that do not determine the pose: in the as-fabricated pose
    (θ = 0, where every loop closes by construction) the rigid loop Jacobian A must be regular;
    a singular A leaves some non-input hinges free, so no evaluation can succeed."""
    kin = analysis.kin
    if not kin.unknowns:
        return
    at_rest = dict.fromkeys(analysis.thetas, 0)
    rows = analysis.linear_system[0].xreplace(at_rest).subs(analysis.mechanism.defaults).tolist()
    with mpmath.workdps(30):
        a = mpmath.matrix([[mpmath.mpf(sp.N(e, 35)) for e in row] for row in rows])
        for i in range(a.rows):  # angular rows are pure numbers, positional lengths
            scale = max(abs(a[i, j]) for j in range(a.cols))
            for j in range(a.cols):
                a[i, j] = a[i, j] / scale if scale else a[i, j]
        # A float64 SVD settles every well-conditioned case (rounding moves the singular values
        # by ~1e-16 of the largest); only a nearly singular A needs the 30-digit one, which
        # costs seconds on a 60 x 60 system (a ladder of 20 loops).
        sigma64 = np.linalg.svd(np.array(a.tolist(), dtype=float), compute_uv=False)
        if sigma64.size and sigma64[-1] > 1e-8 * sigma64[0]:
            return
        _, sigma, vt = mpmath.svd_r(a)
        k = min(range(len(sigma)), key=lambda i: sigma[i])
        if sigma[k] > mpmath.mpf(10) ** -20 * max(sigma):
            return
        free = [
            kin.hinges[a_].name
            for j, a_ in enumerate(kin.unknowns)
            if abs(vt[k, j]) > mpmath.mpf(10) ** -10
        ]
    inputs = ", ".join(analysis.mechanism.inputs)
    raise InputError(
        f"the input hinges {inputs} do not determine the pose: in the as-fabricated pose the "
        f"loops leave {', '.join(free)} free to move (singular loop Jacobian)",
        file=analysis.mechanism.path,
        entry="input",
        hint=f"mark other hinges as inputs, e.g. one of {', '.join(free)} instead of one of "
        f"{inputs}",
    )


def actuator_values(mech: Mechanism, inputs: Mapping[str, object]) -> dict[str, sp.Expr]:
    """The exact value of every input the user gives (input hinges and actuators, by name):
    each given once, nothing else."""
    names = mech.drives
    for key in inputs:
        if key not in names:
            raise InputError(
                f"'{key}' is not an input (an input hinge or an actuator)",
                file=mech.path,
                entry="--input",
                hint=(suggest(key, names) + "; " if suggest(key, names) else "")
                + "inputs: "
                + ", ".join(names),
            )
    missing = [n for n in names if n not in inputs]
    if missing:
        raise InputError(
            f"no value for the input(s) {', '.join(missing)}",
            file=mech.path,
            entry="--input",
            hint="give every input, e.g. --input " + " --input ".join(f"{n}=0.1" for n in missing),
        )
    return {k: exact_value(v, f"--input {k}", mech.path) for k, v in inputs.items()}


def fixed_angles(mech: Mechanism, fixed: Mapping[str, object] | None) -> dict[str, sp.Expr]:
    """Input name -> exact angle of the inputs `fixed` holds (numbers or expressions such as
    'pi/8'); names that are not inputs are bad input (exit 2)."""
    held = {}
    for name, value in (fixed or {}).items():
        refused = unfixable(mech, name)
        if refused is not None:
            raise InputError(refused[0], file=mech.path, entry="--fix", hint=refused[1])
        held[name] = exact_value(value, "--fix", mech.path)
    return held


def unfixable(mech: Mechanism, name: str) -> tuple[str, str] | None:
    """(why, hint) where `name` cannot be held by derive --fix or a scene's [fix]: an actuator
    (its stroke or force stays an input of the evaluators), the hinge an actuator's stroke sets
    (its surrogate), or no input at all; None for an input hinge."""
    hinges = [h for h in mech.inputs if h not in mech.surrogates]
    listed = "input hinges: " + (", ".join(hinges) or "none")
    act = next((a for a in mech.actuators if name in (a.name, a.surrogate)), None)
    if act is not None and name == act.name:
        return (
            f"'{name}' is an actuator: only input hinges can be fixed, its "
            f"{act.drive} stays an input of the evaluators",
            f"give {name} at evaluation, or fix one of the {listed}",
        )
    if act is not None:
        return (
            f"'{name}' is the hinge whose angle the actuator '{act.name}' sets (its surrogate): "
            "only input hinges can be fixed",
            f"fix one of the {listed}",
        )
    if name not in mech.inputs:
        return f"'{name}' is not an input hinge", listed
    return None


@dataclass(frozen=True)
class Configuration:
    """One configuration of an analysis, parsed and validated once (:func:`configure`): the
    level's row, every parameter's exact value, every input's and the input hinges' angles.
    With actuators, `angles` holds the input hinges given beside them; the surrogates' angles
    are solved (symkin.studies.actuators) and added by :meth:`with_angles`."""

    analysis: Analysis
    level: levels.Level
    params: Mapping[sp.Symbol, sp.Expr]  # every parameter: the overrides, then the defaults
    overrides: tuple[str, ...]  # the parameters given (--param), in their order
    drives: Mapping[str, sp.Expr]  # every input given, by name: input hinges and actuators
    angles: Mapping[int, sp.Expr]  # input hinge label -> angle (rad)

    @property
    def mechanism(self) -> Mechanism:
        return self.analysis.mechanism

    @property
    def hinges(self) -> dict[str, sp.Expr]:
        """The input hinges' angles as given, by name (the actuators' strokes and forces left
        out)."""
        acts = {a.name for a in self.mechanism.actuators}
        return {k: v for k, v in self.drives.items() if k not in acts}

    @property
    def strokes(self) -> dict[str, sp.Expr]:
        """Every actuator's value as given (a stroke or a force), by name."""
        return {a.name: self.drives[a.name] for a in self.mechanism.actuators}

    def with_angles(self, angles: Mapping[str, float]) -> Configuration:
        """This configuration with input hinges' angles (by name) set to doubles the evaluation
        found (the actuators' surrogates, a continuation's scaled inputs), each the exact number
        its shortest decimal is, as a given one; every angle checked to be at most a half
        turn."""
        kin = self.analysis.kin
        labels = {kin.hinges[a].name: a for a in kin.inputs}
        given = {**self.angles, **{labels[n]: expressions.number(v) for n, v in angles.items()}}
        _check_half_turns(self.analysis, given)
        return dataclasses.replace(self, angles=given)


def configure(
    analysis: Analysis,
    inputs: Mapping[str, object],
    level: str | None = None,
    params: Mapping[str, object] | None = None,
) -> Configuration:
    """`symkin eval`'s configuration, parsed once: the level by name, the inputs (every input
    hinge, or with actuators every input hinge beside them and every actuator) and the
    parameter overrides; bad values exit 2 naming the option, inputs beyond a half turn 3;
    `level` None: the mechanism's default (levels.default_for)."""
    mech = analysis.mechanism
    row = levels.get(levels.choose(mech, level).name)
    if mech.actuators:
        drives = actuator_values(mech, inputs)
        kin = analysis.kin
        labels = {kin.hinges[a].name: a for a in kin.inputs}
        acts = {a.name for a in mech.actuators}
        angles = {labels[n]: v for n, v in drives.items() if n not in acts}
    else:
        angles = input_values(analysis, inputs)
        names = {a: analysis.kin.hinges[a].name for a in angles}
        drives = {names[a]: v for a, v in angles.items()}
    return Configuration(
        analysis, row, parameter_values(mech, params), tuple(params or ()), drives, angles
    )
