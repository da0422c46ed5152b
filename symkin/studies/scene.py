"""Scene files (docs/scene.md): what a simulation scene or a controller needs of a mechanism —
its points, each with a tolerance over its own input range against its own reference, and the
inputs it holds fixed — and the evaluator that meets it at the least cost.

Every variant (symkin.kinematics.variants) is measured per point, as `symkin tradeoff` measures
them; each point takes the cheapest variant that meets its tolerance over its range, the cost being
the operation count of the routines one evaluation of that point's pruned part runs
(docs/pruning.md), a deterministic figure, so the same scene gives the same files. Points whose
variants share a part are then merged into one evaluator when that costs less than evaluating
them apart. `symkin derive FILE --scene SCENE` emits one evaluator per chosen variant, each
pruned to its points, and a scene evaluator `<name>` that calls them and returns every point.
"""

from __future__ import annotations

import dataclasses
import math
import tomllib
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import sympy as sp

from ..codegen import pipeline
from ..core import backends
from ..core import levels as level_table
from ..core.errors import AssemblyError, InputError, suggest
from ..kinematics.variants import Variant, analysis_for, default_variants
from ..model.entry_checks import MAX_NAME, name_problem
from ..model.mechanism import Mechanism
from ..model.reader import with_points

FORMAT = 1
TOP_KEYS = ("format", "name", "reference", "samples", "backend", "ranges", "fix", "point")
POINT_KEYS = (
    "name",
    "link",
    "at",
    "tolerance",
    "relative_tolerance",
    "reference",
    "ranges",
    "precision",
)
REFERENCES = ("exact", "equilibrium")
#: The backends a scene file may name (its evaluators: the numpy module always, and this one).
BACKENDS = backends.having(scenes=True)
PRECISIONS = ("float64", "float32")
DEFAULT_SAMPLES = 25
#: Newton steps an iterative closure typically takes from its first-order start (the cost of its
#: routine counts this many times).
NEWTON_STEPS = 3
#: The longest variant suffix a group's name adds to the scene's name.
SUFFIX = len("_first_order_small_deflection_f32")


@dataclass(frozen=True)
class ScenePoint:
    """One point the scene needs and how well."""

    name: str
    tolerance: float
    relative: bool  # relative (else absolute, file length unit)
    reference: str  # exact or equilibrium
    ranges: tuple[tuple[str, tuple[float, float]], ...]  # every free input, file order
    precision: str  # the lowest precision allowed

    def meets(self, absolute: float, relative: float) -> bool:
        return (relative if self.relative else absolute) <= self.tolerance

    @property
    def tolerance_text(self) -> str:
        return (
            f"{self.tolerance:g} relative"
            if self.relative
            else f"{self.tolerance:g} (file length unit)"
        )


@dataclass(frozen=True)
class Scene:
    """A validated scene file over its mechanism (with the points the scene adds)."""

    path: str
    name: str
    mechanism: Mechanism
    backend: str
    samples: int
    fixed: tuple[tuple[str, sp.Expr], ...]  # input -> exact angle, file order
    points: tuple[ScenePoint, ...]

    @property
    def point_names(self) -> tuple[str, ...]:
        return tuple(p.name for p in self.points)


@dataclass(frozen=True)
class Measured:
    """One variant's worst errors per scene point (absolute, relative) over the point's range."""

    variant: Variant
    absolute: dict[str, float]
    relative: dict[str, float]


@dataclass(frozen=True)
class Group:
    """Points computed by one variant in one evaluator."""

    variant: Variant
    points: tuple[str, ...]  # scene order
    cost: int  # weighted operations of one evaluation


@dataclass(frozen=True)
class Choice:
    """What a scene derivation chose: the groups, each point's measured errors, and the cost
    of the cheapest single variant meeting every point (None: no single variant does)."""

    groups: tuple[Group, ...]
    errors: dict[str, tuple[float, float]]  # point -> (absolute, relative), its variant's
    single: Group | None
    references: dict[str, int]  # point -> samples the reference assembled


def load(path: str | Path, mech: Mechanism) -> Scene:
    """Read and validate a scene file for `mech`; InputError (exit 2) on anything wrong."""
    path = Path(path)
    shown = str(path)
    try:
        text = path.read_bytes().decode("utf-8")
    except OSError as exc:
        raise InputError(
            f"cannot read the scene file ({exc.strerror or exc})",
            file=shown,
            entry="--scene",
            hint="check the path",
        ) from None
    except UnicodeDecodeError as exc:
        raise InputError(
            f"not UTF-8 text (byte {exc.start})", file=shown, hint="save the file as UTF-8"
        ) from None
    return loads(text, mech, shown)


def loads(text: str, mech: Mechanism, file: str = "<scene>") -> Scene:
    """Validate a scene given as TOML text (`file` names it in error messages)."""
    try:
        data = tomllib.loads(text)
    except (tomllib.TOMLDecodeError, ValueError, RecursionError) as exc:
        raise InputError(
            f"TOML syntax error: {str(exc)[:200]}",
            file=file,
            hint="fix the TOML syntax (docs/scene.md)",
        ) from None
    return _Reader(file, text, mech).read(data)


class _Reader:
    """One pass over a parsed scene, raising on the first problem (file, entry and fix)."""

    def __init__(self, file: str, text: str, mech: Mechanism) -> None:
        self.file, self.text, self.mech = file, text, mech

    def error(self, message: str, entry: str, hint: str) -> InputError:
        return InputError(message, file=self.file, entry=entry, hint=hint)

    def keys(self, table: Mapping, allowed: Sequence[str], entry: str) -> None:
        for key in table:
            if key not in allowed:
                raise self.error(
                    f"unknown key '{key}'",
                    entry,
                    suggest(key, allowed) or "allowed keys: " + ", ".join(allowed),
                )

    def choice(
        self, table: Mapping, key: str, allowed: Sequence[str], default: str, entry: str
    ) -> str:
        value = table.get(key, default)
        if value not in allowed:
            raise self.error(
                f"'{key}' must be one of {', '.join(allowed)}, got {value!r}",
                entry,
                f'write {key} = "{allowed[0]}"',
            )
        return value

    def angle(self, value: object, entry: str) -> float | sp.Expr:
        from .configuration import exact_value

        if isinstance(value, bool) or not isinstance(value, (int, float, str)):
            raise self.error(
                f"an angle must be a number or an expression, got {value!r}",
                entry,
                'write e.g. 0.1 or "pi/30" (radians)',
            )
        number = exact_value(value, entry, self.file)
        if not (number.is_real and abs(sp.N(number, 30)) <= sp.pi):
            raise self.error(
                f"the angle {value!r} is not within [-pi, pi]",
                entry,
                "give the input's rotation from the as-fabricated pose, rad",
            )
        return number

    def value(self, name: str, value: object, entry: str) -> float | sp.Expr:
        """An input's value in a range: an input hinge's angle (rad, within ±π), an actuator's
        stroke (the file's length unit) or force (N), any finite number."""
        from .configuration import exact_value

        if not any(a.name == name for a in self.mech.actuators):
            return self.angle(value, entry)
        if isinstance(value, bool) or not isinstance(value, (int, float, str)):
            raise self.error(
                f"a stroke or force must be a number or an expression, got {value!r}",
                entry,
                "write e.g. 0.02 (a stroke, the file's length unit) or 1.5 (a force, N)",
            )
        number = exact_value(value, entry, self.file)
        if not (number.is_real and number.is_finite):
            raise self.error(f"{value!r} is not a finite number", entry, "give a finite value")
        return number

    def ranges(self, table: object, entry: str, free: Sequence[str]) -> dict:
        if not isinstance(table, dict):
            raise self.error(
                "ranges must be a table of input = [lo, hi]",
                entry,
                "write e.g. ranges = { O = [-0.2, 0.2] } (radians)",
            )
        out = {}
        drives = self.mech.drives  # the input hinges and the actuators (not their surrogates)
        for name, span in table.items():
            where = f"{entry} '{name}'"
            if name not in drives:
                raise self.error(
                    f"'{name}' is not an input hinge or actuator",
                    where,
                    suggest(name, drives) or "inputs: " + ", ".join(drives),
                )
            if name not in free:
                raise self.error(
                    f"the input {name} is fixed ([fix]) and cannot range",
                    where,
                    f"drop the range of {name} or its [fix] entry",
                )
            if not isinstance(span, list) or len(span) != 2:
                raise self.error(
                    f"a range must be [lo, hi], got {span!r}",
                    where,
                    f"write {name} = [-0.2, 0.2] (radians)",
                )
            lo, hi = (float(sp.N(self.value(name, v, where), 17)) for v in span)
            if not lo < hi:
                raise self.error(f"empty range [{lo:g}, {hi:g}]", where, "give lo < hi")
            out[name] = (lo, hi)
        return out

    def positive(self, value: object, entry: str, key: str) -> float:
        if (
            isinstance(value, bool)
            or not isinstance(value, (int, float))
            or not (math.isfinite(value) and value > 0)
        ):
            raise self.error(
                f"'{key}' must be a positive number, got {value!r}",
                entry,
                f"write e.g. {key} = 1e-6",
            )
        return float(value)

    def read(self, data: Mapping) -> Scene:
        from .tradeoff import DEFAULT_RANGE

        mech = self.mech
        self.keys(data, TOP_KEYS, "top level")
        if data.get("format") != FORMAT or isinstance(data.get("format"), bool):
            raise self.error(
                f"unsupported or missing format {data.get('format')!r}",
                "format",
                f"write format = {FORMAT} as the first line",
            )
        name = data.get("name", f"{mech.name}_scene")
        if not isinstance(name, str):
            raise self.error(
                f"'name' must be text, got {name!r}", "name", 'write name = "my_scene"'
            )
        problem = name_problem(name, MAX_NAME - SUFFIX)
        if problem is not None:
            raise self.error(problem[0], "name", problem[1])
        stiff = mech.has_stiffness
        default_reference = "equilibrium" if stiff else "exact"
        reference = self.choice(data, "reference", REFERENCES, default_reference, "reference")
        backend = self.choice(data, "backend", BACKENDS, "c", "backend")
        samples = data.get("samples", DEFAULT_SAMPLES)
        if isinstance(samples, bool) or not isinstance(samples, int) or not 2 <= samples <= 1000:
            raise self.error(
                f"'samples' must be a whole number from 2 to 1000, got {samples!r}",
                "samples",
                f"write samples = {DEFAULT_SAMPLES}",
            )
        fix = data.get("fix", {})
        if not isinstance(fix, dict):
            raise self.error(
                "[fix] must be a table of input = angle",
                "[fix]",
                "write [fix] on a line of its own, then K = 0.0 lines (radians)",
            )
        from .configuration import unfixable

        fixed = {}
        for input_name, value in fix.items():
            where = f"[fix] '{input_name}'"
            refused = unfixable(mech, input_name)
            if refused is not None:
                hint = refused[1]
                if input_name not in mech.inputs + mech.drives:  # a misspelt name
                    hinges = [h for h in mech.inputs if h not in mech.surrogates]
                    hint = suggest(input_name, hinges) or hint
                raise self.error(refused[0], where, hint)
            fixed[input_name] = self.angle(value, where)
        free = [h for h in mech.drives if h not in fixed]
        if not free:
            raise self.error(
                "every input is fixed",
                "[fix]",
                "leave at least one input free (a pose needs no evaluator)",
            )
        # a stroke ranges over ± its default span (Mechanism.stroke_spans); a force has no
        # default (N: the file says nothing of its size)
        strokes = mech.stroke_spans()
        scene_ranges = {
            h: (-strokes[h], strokes[h]) if h in strokes else DEFAULT_RANGE for h in free
        }
        scene_ranges.update(self.ranges(data.get("ranges", {}), "[ranges]", free))
        forces = [a.name for a in mech.actuators if a.drive == "force"]
        if any(f not in data.get("ranges", {}) for f in forces):
            f = next(f for f in forces if f not in data.get("ranges", {}))
            raise self.error(
                f"the force actuator {f} needs a range",
                "[ranges]",
                f"write {f} = [lo, hi] in [ranges] (N)",
            )
        tables = data.get("point", [])
        if not isinstance(tables, list) or not all(isinstance(t, dict) for t in tables):
            raise self.error(
                "'point' must be an array of tables written as [[point]]",
                "[[point]]",
                "write each point as a [[point]] table",
            )
        if not tables:
            raise self.error(
                "the scene names no point",
                "[[point]]",
                'add a [[point]] with name = "..." and a tolerance',
            )
        added = []
        points = []
        seen: set[str] = set()
        known = [p.name for p in mech.points]
        for i, table in enumerate(tables):
            entry = f"[[point]] #{i + 1}"
            self.keys(table, POINT_KEYS, entry)
            pname = table.get("name")
            if not isinstance(pname, str) or not pname.strip():
                raise self.error(
                    "missing or empty 'name'",
                    entry,
                    'write name = "..." (a point of the file, or a new one with link and at)',
                )
            entry = f"[[point]] #{i + 1} '{pname}'"
            if pname in seen:
                raise self.error(
                    f"the point '{pname}' is named twice", entry, "give every point once"
                )
            seen.add(pname)
            if "link" in table or "at" in table:
                added.append({k: table[k] for k in ("name", "link", "at") if k in table})
            elif pname not in known:
                raise self.error(
                    f"the mechanism has no point '{pname}'",
                    entry,
                    (
                        suggest(pname, known) or "points: " + ", ".join(known)
                        if known
                        else "the file has no [[point]]"
                    )
                    + '; or define it here with link = "..." and at = [x, y]',
                )
            given = [k for k in ("tolerance", "relative_tolerance") if k in table]
            if len(given) != 1:
                raise self.error(
                    "give exactly one of 'tolerance' (absolute, the file's length "
                    "unit) and 'relative_tolerance'",
                    entry,
                    "write e.g. tolerance = 1e-9 or relative_tolerance = 0.01",
                )
            tol = self.positive(table[given[0]], entry, given[0])
            ref = self.choice(table, "reference", REFERENCES, reference, entry)
            if ref == "equilibrium" and not stiff:
                raise self.error(
                    "the equilibrium reference needs every plate's stiffness (E, thickness, width)",
                    entry,
                    'use reference = "exact", or give the plates\' stiffness (docs/physics.md)',
                )
            precision = self.choice(table, "precision", PRECISIONS, "float64", entry)
            if precision not in backends.get(backend).precisions:
                able = backends.having(scenes=True, precisions=precision)
                raise self.error(
                    f"{precision} variants exist in {' and '.join(able)} only",
                    entry,
                    f'set backend = "{able[0]}" at the top level, or drop precision',
                )
            spans = dict(scene_ranges)
            spans.update(self.ranges(table.get("ranges", {}), f"{entry} ranges", free))
            points.append(
                ScenePoint(
                    pname,
                    tol,
                    given[0] == "relative_tolerance",
                    ref,
                    tuple((h, spans[h]) for h in free),
                    precision,
                )
            )
        force = next((a.name for a in mech.actuators if a.drive == "force"), None)
        kinematic = next((pt.name for pt in points if pt.reference != "equilibrium"), None)
        if force is not None and kinematic is not None:
            raise self.error(
                f"the force actuator {force} drives the physical levels alone: point "
                f"{kinematic} cannot measure against a kinematic reference",
                f"[[point]] '{kinematic}'",
                'write reference = "equilibrium"',
            )
        if added:
            mech = with_points(mech, added, self.file, self.text)
        return Scene(
            self.file,
            name,
            mech,
            backend,
            samples,
            tuple((h, fixed[h]) for h in mech.inputs if h in fixed),
            tuple(points),
        )


def measure(
    scene: Scene, progress: Callable[[str], None] | None = None
) -> tuple[list[Measured], dict[str, int]]:
    """Every allowed variant's worst errors per point, each over the point's own samples against
    its own reference at 30 digits (the variant's numpy evaluator, pruned to the scene's points);
    and per point the samples its reference assembled."""
    from ..graph.pruning import for_levels
    from ..graph.structure import build
    from ..kinematics.analysis import Analysis
    from .evaluation import evaluate
    from .tradeoff import sample, worst_errors

    say = progress or (lambda message: None)
    mech = scene.mechanism
    fixed_text = {h: sp.sstr(v) for h, v in scene.fixed}
    fixed_value = {h: float(sp.N(v, 17)) for h, v in scene.fixed}
    # the samples and reference deviations of each (range, reference) the points ask for
    keyed: dict[tuple, list[str]] = {}
    for pt in scene.points:
        keyed.setdefault((pt.ranges, pt.reference), []).append(pt.name)
    samples: dict[str, list[dict[str, float]]] = {}
    wanted: dict[str, list[tuple[float, float]]] = {}
    for (ranges, reference), names in keyed.items():
        say(f"reference for {', '.join(names)}: {scene.samples} samples at level {reference}")
        analysis = Analysis(build(mech), names)
        kept, devs = [], []
        for s in sample(dict(ranges), scene.samples):
            given = {k: repr(v) for k, v in s.items()} | fixed_text
            try:
                ev = evaluate(analysis, given, reference, dps=30)
            except AssemblyError:
                continue
            kept.append(s | fixed_value)
            devs.append({n: ev.points[n].deviation for n in names})
        if not kept:
            raise InputError(
                "no sample of the point's range can be assembled",
                file=scene.path,
                entry=f"[[point]] '{names[0]}'",
                hint="choose ranges inside the assembly range",
            )
        for name in names:
            samples[name] = kept
            wanted[name] = [(float(d[name][0]), float(d[name][1])) for d in devs]
    # a force actuator drives the physical levels alone (docs/levels.md, "Actuators")
    forces = any(a.drive == "force" for a in mech.actuators)
    allowed = [
        v
        for v in default_variants(
            stiffness=any(pt.reference == "equilibrium" for pt in scene.points)
        )
        if (v.precision == "float64" or any(pt.precision == "float32" for pt in scene.points))
        and (not forces or v.level in level_table.LOADED)
    ]
    out = []
    names = list(scene.point_names)
    for v in allowed:
        say(f"measuring variant {v.name}")
        pruned, _ = for_levels(mech, names, [v.level])
        _, module = pipeline.build(
            analysis_for(pruned, v, names),
            "numpy",
            "scene",
            v.precision,
            points=names,
            levels=[v.level],
            sensitivity=False,
            reported=False,
        )
        accepted = set(module.INPUTS) | set(module.PRUNED_INPUTS)
        absolute, relative = {}, {}
        for name in names:
            rows = samples[name]
            arrays = {h: np.array([r[h] for r in rows]) for h in rows[0] if h in accepted}
            got = module.evaluate(arrays, v.level, links=False)["points"][name]["deviation"]
            got = np.broadcast_to(np.asarray(got, dtype=float), (2, len(rows)))
            absolute[name], relative[name] = worst_errors(got, wanted[name])
        out.append(Measured(v, absolute, relative))
    return out, {n: len(samples[n]) for n in names}


def cost(routines: Mapping, level: str, closed_form: bool, steps: int) -> int:
    """Weighted operation count of one evaluation: every routine the evaluation of `level` runs
    once, the Newton closures NEWTON_STEPS times (`loaded`: its one-half-plate system and plate
    relations; the two-half-plate variant, used only where one is refused, not counted), the
    rigid closure `steps` continuation steps of NEWTON_STEPS when it has no closed form."""
    total = 0
    for name, r in routines.items():
        if (
            name.startswith("sens_")
            or name == "links"
            or (name.startswith("loaded_") and name.endswith("2"))
        ):
            continue
        weight = 1
        if name in ("newton", "loaded_system1", "loaded_plates1", "plate_relation4"):
            weight = NEWTON_STEPS
        if name in ("rigid_res", "linear") and not closed_form:
            weight = NEWTON_STEPS * steps
        total += weight * r.ops
    return total


def choose(
    scene: Scene,
    measured: Sequence[Measured],
    counts: Mapping[str, int],
    progress: Callable[[str], None] | None = None,
) -> Choice:
    """Each point's cheapest variant meeting its tolerance, then merges of groups whose joint
    evaluator costs less than theirs apart; a point no variant meets is bad input (exit 2)."""
    from ..codegen.plan import plan
    from ..core.settings import SOLVER
    from ..graph.pruning import for_levels

    say = progress or (lambda message: None)
    mech = scene.mechanism
    by_name = {pt.name: pt for pt in scene.points}
    fixed = dict(scene.fixed)
    memo: dict[tuple, int] = {}

    def price(v: Variant, points: tuple[str, ...]) -> int:
        # a float32 variant runs the float64 one's routines
        key = (dataclasses.replace(v, precision="float64"), frozenset(points))
        if key not in memo:
            pruned, _ = for_levels(mech, points, [v.level])
            held = {h: a for h, a in fixed.items() if h in pruned.inputs}
            p = plan(
                analysis_for(pruned, v, points), points, [v.level], sensitivity=False, fixed=held
            )
            largest = max(
                max(abs(lo), abs(hi)) for pt in points for _, (lo, hi) in by_name[pt].ranges
            )
            largest = max([largest] + [abs(float(a)) for a in held.values()])
            memo[key] = cost(p.routines, v.level, p.closed_form, SOLVER.continuation_steps(largest))
        return memo[key]

    def allowed(v: Variant, points) -> bool:
        return all(v.precision == "float64" or by_name[p].precision == "float32" for p in points)

    def meets(m: Measured, points) -> bool:
        return allowed(m.variant, points) and all(
            by_name[p].meets(m.absolute[p], m.relative[p]) for p in points
        )

    def rank(m: Measured, points: tuple[str, ...]) -> tuple:
        # cheapest; at equal operations float32 first (numpy runs it faster; only where every
        # point allows it), then the most accurate, then by name
        worst = max(
            m.relative[p] if by_name[p].relative else m.absolute[p] / by_name[p].tolerance
            for p in points
        )
        return (price(m.variant, points), m.variant.precision != "float32", worst, m.variant.name)

    table = {m.variant: m for m in measured}
    chosen: dict[str, Variant] = {}
    for pt in scene.points:
        good = [m for m in measured if meets(m, (pt.name,))]
        if not good:
            err = (
                (lambda m: m.relative[pt.name]) if pt.relative else (lambda m: m.absolute[pt.name])
            )
            best = min((m for m in measured if allowed(m.variant, (pt.name,))), key=err)
            raise InputError(
                f"no variant meets the tolerance {pt.tolerance_text} of the point over its "
                f"range (the most accurate, {best.variant.name}, reaches {err(best):.3g} against "
                f"the {pt.reference} reference)",
                file=scene.path,
                entry=f"[[point]] '{pt.name}'",
                hint="loosen the tolerance, narrow the ranges"
                + (
                    ", or measure against the equilibrium reference with stiffness data"
                    if pt.reference == "exact"
                    else ""
                ),
            )
        say(f"point {pt.name}: {len(good)} variant(s) meet {pt.tolerance_text}")
        chosen[pt.name] = min(good, key=lambda m: rank(m, (pt.name,))).variant
    groups: dict[Variant, tuple[str, ...]] = {}
    for name in scene.point_names:
        groups[chosen[name]] = groups.get(chosen[name], ()) + (name,)
    while len(groups) > 1:
        best = None
        keys = sorted(groups)
        for i, a in enumerate(keys):
            for b in keys[i + 1 :]:
                joint = tuple(n for n in scene.point_names if n in groups[a] + groups[b])
                apart = price(a, groups[a]) + price(b, groups[b])
                for v in (a, b):
                    if meets(table[v], joint):
                        saving = apart - price(v, joint)
                        if saving > 0 and (best is None or saving > best[0]):
                            best = (saving, a, b, v, joint)
        if best is None:
            break
        _, a, b, v, joint = best
        say(f"merging {', '.join(joint)} into one {v.name} evaluator (saves {best[0]} ops)")
        del groups[a], groups[b]
        groups[v] = joint
    ordered = sorted(groups.items(), key=lambda item: scene.point_names.index(item[1][0]))
    result = tuple(Group(v, pts, price(v, pts)) for v, pts in ordered)
    errors = {
        p: (table[g.variant].absolute[p], table[g.variant].relative[p])
        for g in result
        for p in g.points
    }
    singles = [m for m in measured if meets(m, scene.point_names)]
    single = None
    if singles:
        m = min(singles, key=lambda m: rank(m, scene.point_names))
        single = Group(m.variant, scene.point_names, price(m.variant, scene.point_names))
    return Choice(result, errors, single, dict(counts))


def group_name(scene: Scene, group: Group) -> str:
    """The name of a group's evaluator: the scene's, then the variant's."""
    return f"{scene.name}_{group.variant.name.replace('/', '_')}"


def notes(scene: Scene, choice: Choice, group: Group | None = None) -> list[str]:
    """Lines for the headers and reports: every point's choice and measured error (a group's
    only, when given), and what one variant for every point would cost."""
    source = Path(scene.path).name
    lines = [
        f"Scene {source}: each point computed by the cheapest variant meeting its "
        "tolerance over its range (cost: weighted operations of one evaluation, "
        "docs/scene.md);"
    ]
    by_name = {pt.name: pt for pt in scene.points}
    for g in choice.groups:
        if group is not None and g != group:
            continue
        for name in g.points:
            pt = by_name[name]
            absolute, relative = choice.errors[name]
            span = ", ".join(f"{h} in [{lo:g}, {hi:g}]" for h, (lo, hi) in pt.ranges)
            lines.append(
                f"  point {name}: variant {g.variant.name}, worst error {absolute:.3g} "
                f"(relative {relative:.3g}) against the {pt.reference} level at 30 "
                f"digits over {span} ({choice.references[name]} samples); tolerance "
                f"{pt.tolerance_text};"
            )
    if group is None:
        total = sum(g.cost for g in choice.groups)
        if choice.single is not None:
            lines.append(
                f"  cost {total} against {choice.single.cost} for the cheapest single "
                f"variant meeting every point ({choice.single.variant.name})."
            )
        else:
            lines.append(f"  cost {total}; no single variant meets every point.")
    return lines


def generate(
    scene: Scene,
    emit: Sequence[str],
    progress: Callable[[str], None] | None = None,
    column_width: float | None = None,
    appendix: bool = False,
) -> tuple[dict[str, bytes], Choice]:
    """File name -> content of the scene's evaluators (one per chosen variant and the scene
    evaluator over them) and reports, and the choice made; nothing is written."""
    from ..codegen.literals import to_double
    from ..codegen.plan import SceneGroup, ScenePlan
    from ..graph.structure import build
    from .derive import generate_plan

    say = progress or (lambda message: None)
    # the numpy modules, and the scene's own backend's evaluators (no C for backend numpy)
    emit = [e for e in emit if e not in pipeline.REGISTRY or e in ("numpy", scene.backend)]
    measured, counts = measure(scene, say)
    choice = choose(scene, measured, counts, say)
    mech = scene.mechanism
    files: dict[str, bytes] = {}
    groups = []
    fixed = {h: sp.sstr(v) for h, v in scene.fixed}
    by_name = {pt.name: pt for pt in scene.points}
    for g in choice.groups:
        name = group_name(scene, g)
        say(f"deriving {name} for {', '.join(g.points)}")
        spans: dict[str, tuple[float, float]] = {}
        for p in g.points:
            for h, (lo, hi) in by_name[p].ranges:
                a, b = spans.get(h, (lo, hi))
                spans[h] = (min(a, lo), max(b, hi))
        # (a float32 variant is chosen only with backend numpy, which emits no C)
        out, p = generate_plan(
            dataclasses.replace(mech, name=name),
            emit,
            g.points,
            variant=g.variant,
            notes=notes(scene, choice, g),
            column_width=column_width,
            spans=spans,
            fixed=fixed,
            progress=say,
            appendix=appendix,
        )
        files.update(out)
        groups.append(
            SceneGroup(
                name=name,
                variant=g.variant.name,
                level=level_table.get(g.variant.level),
                inputs=p.drives or p.inputs,  # with actuators: their strokes, not surrogates
                # the evaluator's public points (an actuator's point of action is its own)
                points=tuple(x for x in p.points if x not in {a.point for a in mech.actuators}),
                parameters=tuple(q.name for q in p.parameters),
                precision=g.variant.precision,
                cost=g.cost,
            )
        )
    structure = build(mech)
    used = {h for g in groups for h in g.inputs}
    inputs = tuple(h for h in (mech.drives if mech.actuators else structure.hinges) if h in used)
    scene_plan = ScenePlan(
        name=scene.name,
        source=Path(mech.path).name,
        scene=Path(scene.path).name,
        inputs=inputs,
        points=scene.point_names,
        parameters=tuple((p.name, to_double(p.value)) for p in mech.parameters),
        fixed=tuple((h, to_double(v)) for h, v in scene.fixed),
        ignored=tuple(h for h in mech.drives if h not in used and h not in fixed),
        groups=tuple(groups),
        notes=tuple(notes(scene, choice)),
        actuators=tuple(
            (a.name, "N" if a.drive == "force" else mech.units)
            for a in mech.actuators
            if a.name in inputs
        ),
    )
    for backend, row in pipeline.REGISTRY.items():
        if backend in emit:
            texts = row.emit_scene(scene_plan)
            files.update(zip(row.file_names(scene.name), (t.encode() for t in texts), strict=True))
    return files, choice


def derive(
    path: str | Path,
    scene: str | Path,
    out_dir: str | Path = ".",
    emit: Sequence[str] = ("latex", *pipeline.BACKENDS),
    progress: Callable[[str], None] | None = None,
    column_width: float | None = None,
    appendix: bool = False,
) -> list[Path]:
    """`symkin derive FILE --scene SCENE`: load both, generate, write every file at once; the
    paths written."""
    from ..model.reader import load as load_mechanism
    from .derive import write_files

    mech = load_mechanism(path)
    files, _ = generate(load(scene, mech), emit, progress, column_width, appendix)
    return write_files(files, out_dir)
