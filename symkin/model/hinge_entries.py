"""Reading a [[hinge]] of a mechanism file (docs/file-format.md, "Hinges"): the links it joins,
its plate's midpoint, angle and length, the hinge model and its parameters (a `table` model's
CSV file, an `expr` model's f and g), the reference pin, the beam theory and the stiffness keys,
each taken from the hinge or from [defaults] and checked where it was given.
"""

from __future__ import annotations

import csv
import functools
import io
import math
from collections.abc import Mapping
from pathlib import Path

import mpmath
import sympy as sp

from ..core.errors import suggest
from ..core.files import Unreadable, read_input
from .entries import STIFFNESS_RULES, Hinge, short
from .entry_checks import EntryChecks
from .hinges import (
    BEAMS,
    HINGE_KEYS,
    MODEL_KEYS,
    MODELS,
    PINS,
    PLATE_LENGTH,
    PRBM_PRESETS,
    THETA,
    UNIFORM_MODELS,
    ModelParameter,
    ModelSpec,
    removable_at_zero,
)
from .notches import NOTCHES, profile_keys

#: The keys of the hinge profiles (docs/file-format.md, "Notch hinges"): `profile` and what the
#: notch profiles take besides `thickness` (a uniform plate takes `length`).
PROFILE_KEYS = ("profile", *sorted({k for c in NOTCHES for k in c.keys if k != "length"}))
#: The notch-only key that switches the continuum correction off (docs/file-format.md).
CORRECTION_KEY = "continuum_correction"
DEFAULT_KEYS = (
    tuple(k for k in HINGE_KEYS if k not in ("name", "links", "at"))
    + MODEL_KEYS
    + PROFILE_KEYS
    + (CORRECTION_KEY,)
)
DEFAULT_MODEL = "circular_arc"
#: The default model of a hinge whose profile is not uniform.
NOTCH_MODEL = "pure_moment"
MAX_TABLE_BYTES = 1 << 20
#: The largest magnitude of a table's θ (rad), f/l and g/l: a plate's clamp is about a plate
#: length from its other one (a row of 1e308 gave a NaN fit that `check` accepted).
TABLE_MAGNITUDE = 1e3
#: An `expr` model is checked at 2 EXPR_SAMPLES + 1 angles over -π..π when it is read.
EXPR_SAMPLES = 32


def _is_float(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


class HingeEntries(EntryChecks):
    """The [[hinge]] tables of the file reader (:mod:`.reader`)."""

    def hinges(
        self,
        tables: list[Mapping[str, object]],
        defaults: Mapping[str, object],
        link_names: list[str],
    ) -> tuple[Hinge, ...]:
        if not tables:
            raise self.error(
                "a mechanism needs at least one [[hinge]]",
                "[[hinge]]",
                None,
                "add [[hinge]] tables with name, links and at (docs/file-format.md)",
            )
        out = [self.hinge(i, table, defaults, link_names) for i, table in enumerate(tables)]
        self.unique("hinge", [h.name for h in out], [h.line for h in out])
        return tuple(out)

    def hinge(
        self,
        i: int,
        table: Mapping[str, object],
        defaults: Mapping[str, object],
        link_names: list[str],
    ) -> Hinge:
        line = self.where.header("hinge", i)
        entry = f"[[hinge]] #{i + 1}"
        name = self.option_name(table, entry, line, "--input, --fix and --range")
        entry = f"[[hinge]] #{i + 1} '{name}'"
        profile = self.profile_name(table, defaults, entry, line)
        notch = profile != "uniform"
        fallback = defaults.get("model", DEFAULT_MODEL)
        if notch and (fallback in UNIFORM_MODELS or "model" not in defaults):
            fallback = NOTCH_MODEL  # [defaults]' plate model serves the file's uniform plates
        model = table.get("model", fallback)
        if not isinstance(model, str):
            raise self.error(
                f"'model' must be a model name string, got {model!r}"[:200],
                entry,
                line,
                "models: " + ", ".join(MODELS),
            )
        if model not in MODELS:
            raise self.error(
                f"unknown hinge model {model!r}",
                entry,
                line,
                suggest(str(model), MODELS) or "models: " + ", ".join(MODELS),
            )
        if notch and model in UNIFORM_MODELS:
            raise self.error(
                f"model '{model}' is a uniform plate's; the hinge's profile is {profile!r}",
                entry,
                line,
                f'remove model (a notch bends as model = "{NOTCH_MODEL}"), or use rigid, table '
                "or expr",
            )
        spec = MODELS[model]
        own_keys = ("thickness", *profile_keys(profile))
        for key in table:
            if key in ("length", *PROFILE_KEYS[1:]) and key not in own_keys:
                raise self.error(
                    f"'{key}' does not belong to the {profile} profile",
                    entry,
                    line,
                    self.profile_fix(key, profile),
                )
        if CORRECTION_KEY in table and not notch:
            raise self.error(
                f"'{CORRECTION_KEY}' applies to notch hinges only; this one is a uniform plate",
                entry,
                line,
                f"remove {CORRECTION_KEY} (a uniform plate's beam takes no correction)",
            )
        allowed = (
            HINGE_KEYS
            + ("profile", *own_keys, CORRECTION_KEY)
            + tuple(p.name for p in spec.parameters)
        )
        for key in table:
            if key not in allowed and key in MODEL_KEYS:
                raise self.error(
                    f"'{key}' is not a parameter of model '{model}'",
                    entry,
                    line,
                    f"remove it, or choose a model that takes '{key}'",
                )
        self.check_keys(table, allowed, entry, line)
        links = table.get("links")
        if (
            not isinstance(links, list)
            or len(links) != 2
            or not all(isinstance(x, str) for x in links)
        ):
            raise self.error(
                "'links' must name the two links it joins",
                entry,
                line,
                'write e.g. links = ["frame", "crank"]: two [[link]] names',
            )
        for link in links:
            if link not in link_names:
                raise self.error(
                    f"links names an unknown link '{link}'",
                    entry,
                    line,
                    suggest(link, link_names) or "declare it as a [[link]]",
                )
        if links[0] == links[1]:
            raise self.error(
                f"joins the link '{links[0]}' to itself",
                entry,
                line,
                "a hinge joins two different links",
            )
        if "at" not in table:
            raise self.error(
                "missing required key 'at'",
                entry,
                line,
                "add at = [x, y], the plate's midpoint in the as-fabricated pose",
            )
        at = self.vector(table["at"], entry, "at", line)
        merged = {**defaults, **table}
        where = self.origin("plate_angle", table, entry, line)
        plate_angle = self.expr(merged.get("plate_angle", 0), where[0], "plate_angle", where[1])
        self.finite(plate_angle, where[0], "plate_angle", where[1])
        profile_params: dict[str, sp.Expr] = {}
        continuum = merged.get(CORRECTION_KEY, True)
        if not isinstance(continuum, bool):
            where = self.origin(CORRECTION_KEY, table, entry, line)
            raise self.error(
                f"'{CORRECTION_KEY}' must be true or false, got {continuum!r}"[:200],
                *where,
                f"write {CORRECTION_KEY} = false for the plain beam, or remove it (the fitted "
                "correction, docs/physics.md)",
            )
        if notch:
            profile_params = self.profile_values(profile, table, merged, entry, line)
            length = self.notch_span(profile, profile_params, entry, line)
            profile_params.pop("length", None)
        else:
            if "length" not in merged:
                raise self.error(
                    "no plate length", entry, line, "set length in the hinge or in [defaults]"
                )
            where = self.origin("length", table, entry, line)
            length = self.expr(merged["length"], where[0], "length", where[1])
            if not self.finite(length, where[0], "length", where[1]) > 0:
                raise self.error(
                    f"plate length must be positive, got {length}",
                    *where,
                    "give the plate a positive length",
                )
        is_input = merged.get("input", False)
        if not isinstance(is_input, bool):
            raise self.error(
                f"'input' must be true or false, got {is_input!r}",
                entry,
                line,
                "write input = true or input = false",
            )
        params = self.model_params(spec, table, defaults, entry, line, length)
        pin = merged.get("pin", "midpoint")
        if pin not in PINS:
            raise self.error(
                f"'pin' must be one of {', '.join(PINS)}, got {pin!r}",
                entry,
                line,
                'pin = "midpoint" (the paper\'s rigid pin) or "prbm" (the '
                "model's pseudo-rigid-body pivot)",
            )
        stiffness = self.stiffness(table, merged, entry, line, length)
        beam = merged.get("beam", BEAMS[0])
        if beam not in BEAMS:
            raise self.error(
                f"'beam' must be one of {', '.join(BEAMS)}, got {beam!r}"[:200],
                entry,
                line,
                'beam = "reissner" (stretches and shears, the default) or "elastica" '
                "(inextensible, shear-free), docs/physics.md",
            )
        return Hinge(
            name,
            i,
            (links[0], links[1]),
            at,
            plate_angle,
            length,
            model,
            params,
            is_input,
            line,
            pin,
            **stiffness,
            beam=beam,
            profile=profile,
            profile_params=tuple(sorted(profile_params.items())),
            continuum_correction=continuum or not notch,
        )

    # -- profiles (docs/file-format.md, "Notch hinges") --------------------------------------------

    def profile_name(
        self,
        table: Mapping[str, object],
        defaults: Mapping[str, object],
        entry: str,
        line: int | None,
    ) -> str:
        """The hinge's `profile` (its own, else [defaults]', else "uniform"), a known one."""
        from .profiles import PROFILES

        profile = table.get("profile", defaults.get("profile", "uniform"))
        where = self.origin("profile", table, entry, line)
        if not isinstance(profile, str) or profile not in PROFILES:
            raise self.error(
                f"unknown profile {profile!r}"[:200],
                *where,
                (suggest(str(profile), PROFILES) if isinstance(profile, str) else None)
                or "profiles: " + ", ".join(PROFILES),
            )
        return profile

    @staticmethod
    def profile_fix(key: str, profile: str) -> str:
        """How to fix a profile key written on a hinge whose profile does not take it."""
        if key == "length":
            span = next(c.span_text for c in NOTCHES if c.profile == profile)
            return f"remove length: the span of a {profile} notch is {span}"
        owners = [c.profile for c in NOTCHES if key in c.keys]
        return (
            f'remove {key}, or write profile = "{owners[0]}" (the profile that takes it)'
            if owners
            else f"remove {key}"
        )

    def profile_values(
        self,
        profile: str,
        table: Mapping[str, object],
        merged: Mapping[str, object],
        entry: str,
        line: int | None,
    ) -> dict[str, sp.Expr]:
        """A notch's own keys (from the hinge or [defaults]), each a positive finite number, and
        its thickness, which the shape needs at every level."""
        out: dict[str, sp.Expr] = {}
        for key in (*profile_keys(profile), "thickness"):
            if key not in merged:
                raise self.error(
                    f"the {profile} profile needs '{key}'",
                    entry,
                    line,
                    f"add {key} = ... (file unit) to the hinge or to [defaults] "
                    "(docs/file-format.md, 'Notch hinges')",
                )
            where = self.origin(key, table, entry, line)
            expr = self.expr(merged[key], where[0], key, where[1])
            value = self.finite(expr, where[0], key, where[1])
            if not value > 0:
                raise self.error(
                    f"'{key}' of the {profile} profile must be positive, got {short(value)}"
                    + (" (the notch's thickness T(x) would not be positive)")
                    * (key == "thickness"),
                    *where,
                    f"give {key} a positive length in the file's unit",
                )
            if key != "thickness":
                out[key] = expr
        return out

    def notch_span(
        self,
        profile: str,
        params: Mapping[str, sp.Expr],
        entry: str,
        line: int | None,
    ) -> sp.Expr:
        """The span of a notch (its hinge's length), checked: fillets that fit the length. The
        shape's ratios may depend on parameters (the pure-moment series then takes them as
        expressions, model.notch_series)."""
        from .profiles import PROFILES

        cls = PROFILES[profile]
        span = cls.span(params)  # type: ignore[attr-defined]
        if profile == "corner_filleted":
            fillet, length = (self.finite(params[k], entry, k, line) for k in ("fillet", "length"))
            if not 2 * fillet <= length:
                raise self.error(
                    f"two fillets of radius {short(fillet)} do not fit the length {short(length)}",
                    entry,
                    line,
                    "make fillet at most length/2",
                )
        return span

    def origin(
        self, key: str, table: Mapping[str, object], entry: str, line: int | None
    ) -> tuple[str, int | None]:
        """Where a hinge's `key` was given: the hinge (`entry`, `line`) or, when the hinge does
        not give it, [defaults] and the key's line there (the place an error sends the user)."""
        if key in table:
            return entry, line
        return "[defaults]", self.where.key(key, "defaults")

    def stiffness(
        self,
        table: Mapping[str, object],
        merged: Mapping[str, object],
        entry: str,
        line: int | None,
        length: sp.Expr,
    ) -> dict[str, sp.Expr]:
        """E, thickness, width, nu, allowable_stress of a hinge (docs/physics.md; `table` the
        hinge's own keys, `merged` with [defaults]), each checked where given: E > 0, 0 <
        thickness < length, width > 0, 0 <= nu < 0.5, allowable_stress > 0 (with the default
        parameters)."""
        out: dict[str, sp.Expr] = {}
        for key, (ok, message, hint) in STIFFNESS_RULES.items():
            if key not in merged:
                continue
            where = self.origin(key, table, entry, line)
            expr = self.expr(merged[key], where[0], key, where[1])
            value = self.finite(expr, where[0], key, where[1])
            if not ok(value):
                raise self.error(f"{message}, got {key} = {short(value)}", *where, hint)
            out[key] = expr
        if "thickness" in out:
            t = self.finite(out["thickness"], entry, "thickness", line)
            lval = self.finite(length, entry, "length", line)
            if not t < lval:
                raise self.error(
                    f"thickness {short(t)} is not smaller than the plate length {short(lval)}",
                    entry,
                    line,
                    "a flexure plate is thin: make thickness < length (about length/10 or less)",
                )
        return out

    def model_params(
        self,
        spec: ModelSpec,
        table: Mapping[str, object],
        defaults: Mapping[str, object],
        entry: str,
        line: int | None,
        length: sp.Expr,
    ) -> tuple[tuple[str, object], ...]:
        values: dict[str, object] = {}
        given = {k: v for k, v in defaults.items() if spec.parameter(k)}
        given.update({k: v for k, v in table.items() if spec.parameter(k)})
        if spec.name == "prbm" and "preset" in given:
            preset = given["preset"]
            if not isinstance(preset, str) or preset not in PRBM_PRESETS:
                raise self.error(
                    f"unknown prbm preset {preset!r}",
                    entry,
                    line,
                    "presets: " + ", ".join(sorted(PRBM_PRESETS)),
                )
            given = {
                **PRBM_PRESETS[preset],
                **{k: v for k, v in given.items() if k in table or k not in PRBM_PRESETS[preset]},
            }
        for p in spec.parameters:
            if p.name not in given:
                if p.required:
                    raise self.error(
                        f"model '{spec.name}' needs '{p.name}'",
                        entry,
                        line,
                        f"add {p.name} = ... to the hinge",
                    )
                if p.default is None:
                    continue
                raw = p.default
            else:
                raw = given[p.name]
            values[p.name] = self.model_value(p, raw, entry, line)
        if spec.name == "table":
            file, degree = values["file"], values["degree"]
            assert isinstance(file, str) and isinstance(degree, int)  # model_value checked them
            values["rows"] = self.table_rows(file, degree, entry, line)
        if spec.name == "expr":
            self.check_expr_model(values["f"], values["g"], entry, line, length)
        return tuple(sorted(values.items()))

    def model_value(self, p: ModelParameter, raw: object, entry: str, line: int | None) -> object:
        if p.kind in ("number", "fraction"):
            value = self.expr(raw, entry, p.name, line)
            num = self.finite(value, entry, p.name, line)
            ok = num > 0 and (p.kind == "number" or num <= 1)
            if not ok:
                rng = "in (0, 1]" if p.kind == "fraction" else "positive"
                raise self.error(
                    f"'{p.name}' must be {rng}, got {short(num)}",
                    entry,
                    line,
                    f"give {p.name} a value {rng}",
                )
            return value
        if p.kind == "choice":
            if not isinstance(raw, str) or raw not in p.choices:
                raise self.error(
                    f"'{p.name}' must be one of {', '.join(p.choices)}, got {raw!r}",
                    entry,
                    line,
                    f'write {p.name} = "{p.choices[0]}" or another of these',
                )
            return raw
        if p.kind == "int":
            if isinstance(raw, bool) or not isinstance(raw, int) or not 1 <= raw <= 12:
                raise self.error(
                    f"'{p.name}' must be an integer from 1 to 12, got {raw!r}",
                    entry,
                    line,
                    f"write {p.name} = an integer from 1 to 12",
                )
            return raw
        if p.kind == "text":
            if not isinstance(raw, str) or not raw:
                raise self.error(
                    f"'{p.name}' must be a file name string, got {raw!r}",
                    entry,
                    line,
                    f'write {p.name} = "name.csv", a file beside the mechanism',
                )
            return raw
        # "expr": an expression in theta, l and the parameters
        names = {**self.names, "theta": THETA, "l": PLATE_LENGTH}
        if not isinstance(raw, str):
            raise self.error(
                f"'{p.name}' must be an expression string in theta and l",
                entry,
                line,
                f'write {p.name} = "..." with an expression in theta and l',
            )
        return self.expr(raw, entry, p.name, line, names)

    def check_expr_model(
        self, f: sp.Expr, g: sp.Expr, entry: str, line: int | None, length: sp.Expr
    ) -> None:
        """The plate must be straight at θ = 0: f(0) = l, g(0) = 0 (the as-fabricated pose),
        by the limit where the expression is 0/0 there (sin θ/θ: model.hinges.removable_at_zero);
        a pole at 0, or a value that is not finite anywhere on |θ| ≤ π, is bad input naming the
        key (every configuration passes through θ = 0, and an input reaches ±π at most)."""
        subs = {**self.defaults, PLATE_LENGTH: length.subs(self.defaults)}
        lval = sp.N(subs[PLATE_LENGTH], 30)
        for key, expr, want in (("f", f, lval), ("g", g, 0)):
            fix = f"write {key} so that it is finite at every angle up to a half turn"
            try:
                safe = removable_at_zero(expr.subs(subs), THETA)
            except ValueError as exc:
                raise self.error(f"'{key}': {exc}", entry, line, fix) from None
            at0 = sp.N(safe.subs(THETA, 0), 30)
            if not (at0.is_real and at0.is_finite) or abs(at0 - want) > 1e-6 * lval:
                raise self.error(
                    f"expression model gives {key}(0) = {short(at0)}, expected {short(want)}",
                    entry,
                    line,
                    "at theta = 0 the plate is straight: f(0) = l and g(0) = 0",
                )
            for angle in _poles(expr.subs(subs)):
                raise self.error(
                    f"'{key}' has a pole at theta = {short(sp.N(angle))}", entry, line, fix
                )
            bad = _not_finite_at(safe)
            if bad is not None:
                angle, value = bad
                raise self.error(
                    f"'{key}' is not a finite real number at theta = {short(angle)} "
                    f"(it gives {value})",
                    entry,
                    line,
                    fix,
                )

    def table_rows(
        self, name: str, degree: int, entry: str, line: int | None
    ) -> tuple[tuple[float, ...], ...]:
        content = self.table_text(name, entry, line)
        rows: list[tuple[float, ...]] = []
        for k, row in enumerate(csv.reader(io.StringIO(content)), start=1):
            if not row or not "".join(row).strip() or row[0].lstrip().startswith("#"):
                continue
            try:
                values = [float(x) for x in row]
            except ValueError:
                if not rows and k == 1:
                    continue  # a header row
                bad = next((x for x in row if not _is_float(x)), "")
                shown = bad if len(bad) <= 40 else bad[:37] + "..."
                raise self.error(
                    f"{name}:{k}: not a number: {shown!r}",
                    entry,
                    line,
                    "each row is theta, f/l, g/l",
                ) from None
            if len(values) != 3 or not all(math.isfinite(v) for v in values):
                raise self.error(
                    f"{name}:{k}: need three finite numbers theta, f/l, g/l",
                    entry,
                    line,
                    f"correct row {k} of {name}",
                )
            if any(abs(v) > TABLE_MAGNITUDE for v in values):
                raise self.error(
                    f"{name}:{k}: a value beyond {TABLE_MAGNITUDE:g} in magnitude "
                    f"({', '.join(f'{v:g}' for v in values)})",
                    entry,
                    line,
                    f"theta is in radians and f/l, g/l in plate lengths, all of order 1: correct "
                    f"row {k} of {name}",
                )
            rows.append(tuple(values))
        if len({r[0] for r in rows}) < degree + 1:
            raise self.error(
                f"table '{name}' has {len(rows)} rows with distinct theta; a degree "
                f"{degree} fit needs at least {degree + 1}",
                entry,
                line,
                "add rows or lower 'degree'",
            )
        return tuple(rows)

    def table_text(self, name: str, entry: str, line: int | None) -> str:
        """The text of a table file: a regular file inside the mechanism's folder (relative
        path, no '..', symbolic links resolved inside it too), at most MAX_TABLE_BYTES."""
        hint = "give a CSV path relative to the mechanism file, inside its folder"
        rel = Path(name)
        if rel.is_absolute() or ".." in rel.parts:
            raise self.error(
                f"table file '{name}' must be inside the mechanism's folder "
                "(a relative path without '..')",
                entry,
                line,
                hint,
            )
        base = self.base_dir.resolve()
        path = (base / rel).resolve()
        if path != base and base not in path.parents:
            raise self.error(
                f"table file '{name}' leads outside the mechanism's folder (a symbolic link)",
                entry,
                line,
                hint,
            )
        try:
            raw = read_input(path, MAX_TABLE_BYTES)
        except Unreadable as exc:
            why = exc.reason.replace("cannot read the file", "cannot read it")
            large = why.startswith("larger")
            raise self.error(
                f"table file '{name}': {why}",
                entry,
                line,
                "a table needs a few hundred rows at most" if large else hint,
            ) from None
        try:
            return raw.decode("utf-8")
        except UnicodeDecodeError as exc:
            raise self.error(
                f"table file '{name}' is not UTF-8 text (byte {exc.start})", entry, line, hint
            ) from None


@functools.lru_cache(maxsize=256)
def _poles(expr: sp.Expr) -> list[sp.Expr]:
    """The singular points of `expr` in θ on [-π, π] other than 0 (that one is the removable
    singularity model.hinges.removable_at_zero handles, or a pole it refuses), as far as
    sympy's `singularities` finds them (rational and trigonometric expressions); the angle
    samples of check_expr_model catch what it leaves."""
    from sympy.calculus.singularities import singularities

    try:
        found = singularities(expr, THETA, sp.Interval(-sp.pi, sp.pi))
    except (NotImplementedError, ValueError, TypeError):
        return []
    if not isinstance(found, sp.FiniteSet):
        return []
    return sorted((a for a in found if a != 0), key=lambda a: float(sp.N(a)))


@functools.lru_cache(maxsize=256)
def _not_finite_at(expr: sp.Expr) -> tuple[float, object] | None:
    """The first of 2 EXPR_SAMPLES + 1 angles over -π..π where `expr` (in θ alone) is not a
    finite real number, and its value there; None when it is finite everywhere. Evaluated once
    per expression (the hinges of a file mostly share theirs) by mpmath at 20 digits."""
    fn = sp.lambdify(THETA, expr, "mpmath")
    with mpmath.workdps(20):
        for k in range(-EXPR_SAMPLES, EXPR_SAMPLES + 1):
            angle = mpmath.pi * k / EXPR_SAMPLES
            try:
                value = fn(angle)
            except (ZeroDivisionError, ValueError, OverflowError):
                return float(angle), "no value"
            if not isinstance(value, mpmath.mpf) or not mpmath.isfinite(value):
                return float(angle), mpmath.nstr(value, 6)
    return None
