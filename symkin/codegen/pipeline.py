"""One build-and-load pipeline for every generated evaluator: plan → emit → compile or import.

Every caller (``symkin eval --backend``, ``symkin.compile``, ``derive``, ``tradeoff``, scenes,
the tests and benchmarks) goes through here; a backend is one row of :data:`REGISTRY`:

    name     what it emits (files)        what it loads                      precisions
    numpy    <name>.py                    the module, executed in memory      float64, float32
    c        <name>.h, <name>.c           the library, compiled, via ctypes  float64

Each step is cached by content: a plan per Analysis and options (:func:`plan_for`), the texts
per plan, backend, source and precision (:func:`emit`; on disk too, beside a plan kept by
content), the loaded evaluator per digest of its texts (:func:`load`); the C library is also
cached on disk by :mod:`.toolchain` (or compiled in a temporary folder that is removed at once,
``transient=True``, when nothing may be written).

A new backend is a folder under ``backends/`` (printer, kernels, templates, ``emit``), one
:class:`Backend` row here (its emit adapter and its loader) and one row of the backend table,
:mod:`symkin.core.backends` (what it can do: levels, sensitivities, actuators, reports, ...).
"""

from __future__ import annotations

import dataclasses
import hashlib
import inspect
import threading
import weakref
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from types import ModuleType
from typing import Any

import numpy as np

from ..core import backends, levels
from ..core.errors import InputError
from ..kinematics.analysis import Analysis
from . import plan_cache, templating, toolchain
from .plan import Plan, ScenePlan, plan, with_derivation


@dataclass(frozen=True)
class Shape:
    """The names a loaded evaluator's arguments and results are laid out by (in order)."""

    inputs: tuple[str, ...]
    params: tuple[str, ...]
    points: tuple[str, ...]
    hinges: tuple[str, ...]
    links: tuple[str, ...] = ()  # the links whose rotations it reports

    @classmethod
    def of(cls, p: Plan, links: bool = True) -> Shape:
        """The shape of plan `p`'s evaluator; `links=False` leaves the links' rotations out."""
        return cls(
            p.drives or p.inputs,
            tuple(q.name for q in p.parameters),
            p.shown_points,
            p.hinges,
            p.reported_links if links else (),
        )


#: One configuration in the C evaluator's layout (docs/generated-code.md): status (0: solved),
#: 6 numbers per point (rigid x, y, compliant x, y, deviation x, y), the hinge angles (rigid then
#: compliant), 3 per reported link (rigid, compliant rotation, deviation).
Pose = tuple[int, list[float], list[float], list[float]]
#: n configurations: status (n,), out (n, 6 points), the hinge angles (n, 2 hinges) when asked.
Rows = tuple[np.ndarray, np.ndarray, np.ndarray | None]
#: Parameter sets by configurations: status (n_sets, n), out (n_sets, n, 6 points).
Grid = tuple[np.ndarray, np.ndarray]
#: n configurations with sensitivities: status (n,), values (n, 6 points), the deviation's and
#: the rigid position's derivatives (n, points, parameters then inputs, 2).
SensitivityRows = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]


@dataclass(frozen=True)
class Backend:
    """One row of the registry: how a backend emits a plan, loads what it emitted, and answers
    in the neutral layouts (:data:`Pose`, :data:`Rows`, :data:`SensitivityRows`, :data:`Grid`);
    what it can do is its row of the backend table (:attr:`capabilities`)."""

    name: str
    language: str  # what its files are written in, for messages
    files: tuple[str, ...]  # the file names it writes, "{name}" the mechanism's identifier
    loads: str  # what :func:`load` gives, in words
    #: what it loads is the generated Python module itself, which answers in the documented
    #: dicts (evaluate, sensitivity_full: docs/generated-code.md); else the neutral layouts alone
    is_module: bool
    #: (plan, source file name, precision) -> the texts, in the order of `files`
    emit: Callable[[Plan, str, str], tuple[str, ...]]
    #: a scene's plan -> the texts of its scene evaluator (docs/scene.md), in `files` order
    emit_scene: Callable[[ScenePlan], tuple[str, ...]]
    #: (mechanism identifier, texts, shape, transient) -> the loaded evaluator
    load: Callable[[str, tuple[str, ...], Shape | None, bool], Any]
    #: (evaluator, shape, inputs, parameter values, level) -> one configuration
    pose: Callable[[Any, Shape, Sequence[float], Sequence[float] | None, str], Pose]
    #: (evaluator, shape, inputs (n, inputs), parameter values or None, level, with angles)
    rows: Callable[[Any, Shape, np.ndarray, Sequence[float] | None, str, bool], Rows]
    sensitivity_rows: Callable[
        [Any, Shape, np.ndarray, Sequence[float] | None, str], SensitivityRows
    ]
    #: (evaluator, shape, parameter sets (n_sets, params), inputs (n, inputs), level, reused
    #: out or None) -> every parameter set at every configuration (a Monte Carlo sweep)
    grid: Callable[[Any, Shape, np.ndarray, np.ndarray, str, np.ndarray | None], Grid]

    @property
    def capabilities(self) -> backends.Capabilities:
        """What the backend can do: its row of the backend table (symkin.core.backends)."""
        return backends.get(self.name)

    @property
    def precisions(self) -> tuple[str, ...]:
        """The floating-point types its evaluators run in."""
        return self.capabilities.precisions

    def file_names(self, name: str) -> tuple[str, ...]:
        """The files of mechanism `name`."""
        return tuple(f.format(name=name) for f in self.files)


# -- numpy: the generated module answers with dicts of arrays ------------------------------------


def _emit_numpy(p: Plan, source: str, precision: str) -> tuple[str, ...]:
    from .backends.numpy import backend

    return (backend.emit(p, source, precision),)


def _emit_numpy_scene(p: ScenePlan) -> tuple[str, ...]:
    from .backends.numpy import backend

    return (backend.emit_scene(p),)


def _load_numpy(
    name: str, texts: tuple[str, ...], shape: Shape | None, transient: bool
) -> ModuleType:
    (module,) = texts  # the module knows its own names: no shape needed
    if transient:  # not entered in sys.modules (symkin.compile pickles as its texts)
        return toolchain.numpy_module_in_memory(module, name)
    return toolchain.import_numpy_module(module, name)


def _named(shape: Shape, params: Sequence[float] | None) -> dict[str, float] | None:
    return None if params is None else dict(zip(shape.params, params, strict=True))


def _columns(shape: Shape, x: np.ndarray) -> dict[str, np.ndarray]:
    x = np.asarray(x, dtype=float)
    return {n: x[:, j] for j, n in enumerate(shape.inputs)}


def _point_values(res: Mapping[str, Any], shape: Shape, n: int) -> np.ndarray:
    out = np.empty((n, 6 * len(shape.points)))
    for i, p in enumerate(shape.points):
        for j, key in enumerate(("rigid", "compliant", "deviation")):
            out[:, 6 * i + 2 * j : 6 * i + 2 * j + 2] = res["points"][p][key].T
    return out


def evaluate_options(module: Any, **options: bool) -> dict[str, bool]:
    """The keywords among `options` that the generated numpy `module`'s evaluate() takes: only
    a module with the `loaded` level's report has `report` and `buckling` (the loads' buckling
    search, tens of Newton solves per configuration), which callers reading the deviations or
    the stress alone turn off."""
    accepted = inspect.signature(module.evaluate).parameters
    return {k: v for k, v in options.items() if k in accepted}


def _numpy_pose(
    module: Any, shape: Shape, x: Sequence[float], params: Sequence[float] | None, level: str
) -> Pose:
    res = module.evaluate(
        dict(zip(shape.inputs, x)),
        level,
        _named(shape, params),
        **evaluate_options(module, report=False),
    )
    out = [
        float(v)
        for p in shape.points
        for key in ("rigid", "compliant", "deviation")
        for v in res["points"][p][key]
    ]
    angles = [
        float(res["angles"][kind][h]) for kind in ("rigid", "compliant") for h in shape.hinges
    ]
    links = [
        float(res["links"][n][key])
        for n in shape.links
        for key in ("rigid", "compliant", "deviation")
    ]
    return int(_status(res)), out, angles, links


def _status(res: Mapping[str, Any]) -> np.ndarray:
    """The C evaluator's return codes from a numpy module's result: 0, 1 where not "ok", 4 where
    the compliant pose has no rigid "reference" (beyond the rigid reach, docs/generated-code.md;
    its sensitivities are not "ok")."""
    ok = np.asarray(res["ok"])
    reference = np.asarray(res.get("reference", True))
    return np.where(reference, np.where(ok, 0, 1), 4).astype(np.intc)


def _numpy_rows(
    module: Any,
    shape: Shape,
    x: np.ndarray,
    params: Sequence[float] | None,
    level: str,
    angles: bool = False,
) -> Rows:
    res = module.evaluate(
        _columns(shape, x), level, _named(shape, params), **evaluate_options(module, report=False)
    )
    out = _point_values(res, shape, x.shape[0])
    turned = None
    if angles:
        turned = np.stack(
            [res["angles"][kind][h] for kind in ("rigid", "compliant") for h in shape.hinges],
            axis=1,
        )
    return _status(res), out, turned


def _numpy_sensitivity_rows(
    module: Any, shape: Shape, x: np.ndarray, params: Sequence[float] | None, level: str
) -> SensitivityRows:
    res = module.sensitivity_full(_columns(shape, x), level, _named(shape, params))
    n = x.shape[0]
    values = _point_values(res, shape, n)
    dev = np.empty((n, len(shape.points), len(shape.params) + len(shape.inputs), 2))
    rig = np.empty_like(dev)
    for i, p in enumerate(shape.points):
        for out, kind in ((dev, "deviation"), (rig, "rigid")):
            table = res[kind][p]
            for v, name in enumerate(shape.params):
                out[:, i, v] = table["params"][name].T
            for v, name in enumerate(shape.inputs):
                out[:, i, len(shape.params) + v] = table["inputs"][name].T
    return _status(res), values, dev, rig


def _numpy_grid(
    module: Any,
    shape: Shape,
    params: np.ndarray,
    x: np.ndarray,
    level: str,
    out: np.ndarray | None = None,
) -> Grid:
    """One vectorized call per parameter set (into `out` when it is the right size)."""
    size = (len(params), len(x), 6 * len(shape.points))
    if out is None or out.shape != size:
        out = np.empty(size)
    status = np.empty((len(params), len(x)), dtype=np.intc)
    for s, row in enumerate(params):
        status[s], out[s] = _numpy_rows(module, shape, x, row, level)[:2]
    return status, out


# -- C: the compiled library's batch entry points already use the neutral layouts ---------------


def _emit_c(p: Plan, source: str, precision: str) -> tuple[str, ...]:
    from .backends.c import backend

    return backend.emit(backend_plan(p, "c"), source)


def backend_plan(p: Plan, name: str) -> Plan:
    """The plan backend `name` emits: the C runtime's `loaded` takes uniform plates (core.levels
    NOTCH_BACKENDS), so for it a plan whose `loaded` has notches is the plan without the level
    (the C evaluators refuse it: symkin.codegen.loaded.generated_notches); a plan of that level
    alone is bad input there (exit 2)."""
    if name in levels.NOTCH_BACKENDS or p.loaded is None or not p.loaded.notches:
        return p
    kept = tuple(lv for lv in p.levels if lv.name not in levels.LOADED)
    if not kept:
        hinge = next(n.hinge for n in p.loaded.notches if n is not None)
        raise InputError(
            f"the generated {name} evaluators' loaded level takes uniform plates: hinge "
            f"'{hinge}' is a notch",
            entry=f"[[hinge]] '{hinge}'",
            hint="use --backend numpy (its loaded takes notches) or ask for a kinematic level",
        )
    routines = {
        k: r
        for k, r in p.routines.items()
        if not k.startswith(("loaded_", "plate_", "notch_", "modes_data"))
    }
    default = p.default_level if any(lv.name == p.default_level for lv in kept) else None
    return dataclasses.replace(
        p,
        levels=kept,
        routines=routines,
        loaded=None,
        default_level=default or levels.KINEMATIC_DEFAULT,
    )


def _emit_c_scene(p: ScenePlan) -> tuple[str, ...]:
    from .backends.c import backend

    return backend.emit_scene(p)


def _load_c(
    name: str, texts: tuple[str, ...], shape: Shape | None, transient: bool
) -> toolchain.Library:
    if shape is None:
        raise ValueError("loading a C library needs the shape of its arguments")
    header, code = texts
    lib = (
        toolchain.load_transient(name, header, code)
        if transient
        else toolchain.build(name, header, code)
    )
    return toolchain.Library(
        lib,
        name,
        len(shape.inputs),
        len(shape.params),
        len(shape.points),
        len(shape.hinges),
        len(shape.links),
    )


def _c_pose(
    lib: toolchain.Library,
    shape: Shape,
    x: Sequence[float],
    params: Sequence[float] | None,
    level: str,
) -> Pose:
    return lib.pose(x, params, levels.get(level).code)


def _c_rows(
    lib: toolchain.Library,
    shape: Shape,
    x: np.ndarray,
    params: Sequence[float] | None,
    level: str,
    angles: bool = False,
) -> Rows:
    return lib.evaluate_rows(x, params, levels.get(level).code, angles)


def _c_grid(
    lib: toolchain.Library,
    shape: Shape,
    params: np.ndarray,
    x: np.ndarray,
    level: str,
    out: np.ndarray | None = None,
) -> Grid:
    return lib.evaluate_grid(params, x, levels.get(level).code, out)


def _c_sensitivity_rows(
    lib: toolchain.Library,
    shape: Shape,
    x: np.ndarray,
    params: Sequence[float] | None,
    level: str,
) -> SensitivityRows:
    return lib.sensitivity_rows(x, params, levels.get(level).code)


#: The generated-code backends, by name; the order is the order of every listing (CLI choices,
#: hints, derive's files).
REGISTRY: dict[str, Backend] = {
    b.name: b
    for b in (
        Backend(
            "numpy",
            "numpy",
            ("{name}.py",),
            "the generated module, executed in memory",
            True,
            _emit_numpy,
            _emit_numpy_scene,
            _load_numpy,
            _numpy_pose,
            _numpy_rows,
            _numpy_sensitivity_rows,
            _numpy_grid,
        ),
        Backend(
            "c",
            "C99",
            ("{name}.h", "{name}.c"),
            "the compiled library, called through ctypes (toolchain.Library)",
            False,
            _emit_c,
            _emit_c_scene,
            _load_c,
            _c_pose,
            _c_rows,
            _c_sensitivity_rows,
            _c_grid,
        ),
    )
}
#: The names of the generated-code backends (the mpmath evaluation, ``sympy``, is not one).
BACKENDS: tuple[str, ...] = tuple(REGISTRY)


def backend(name: str, entry: str = "--backend") -> Backend:
    """The registry row of `name`; an unknown one is bad input (exit 2)."""
    try:
        return REGISTRY[name]
    except KeyError:
        raise InputError(
            f"unknown backend '{name}'", entry=entry, hint="backends: " + ", ".join(BACKENDS)
        ) from None


# -- plan ------------------------------------------------------------------------------------------

#: analysis -> (the plan's options as a hashable key -> its plan)
_PlanKey = tuple[tuple[str, object], ...]
_PLANS: weakref.WeakKeyDictionary[Analysis, dict[_PlanKey, Plan]] = weakref.WeakKeyDictionary()
_PLANS_LOCK = threading.RLock()
_PLAN_SIGNATURE = inspect.signature(plan)


def _key(value: object) -> object:
    """A hashable, order-preserving form of a plan option."""
    if isinstance(value, Mapping):
        return tuple((k, _key(v)) for k, v in sorted(value.items()))
    if isinstance(value, list | tuple):
        return tuple(_key(v) for v in value)
    return value


def _options(analysis: Analysis, options: Mapping[str, Any]) -> dict[str, Any]:
    """`options` of :func:`~.plan.plan` in one form per plan: defaults filled in (plan(an) and
    plan(an, sensitivity=True) are one plan), sequences as tuples, no fixed inputs as None
    (derive passes {} and a list of notes where evaluate passes None and ()), so the content
    digest finds the plan whichever caller derived it."""
    bound = _PLAN_SIGNATURE.bind(analysis, **options)
    bound.apply_defaults()
    out = {k: v for k, v in bound.arguments.items() if k != "analysis"}
    for k, v in out.items():
        if isinstance(v, list):
            out[k] = tuple(v)
    if not out.get("fixed"):
        out["fixed"] = None
    return out


def plan_for(analysis: Analysis, **options: Any) -> Plan:
    """:func:`~.plan.plan` of `analysis` with `options`, derived once per analysis and options
    (kept as long as the analysis is), and found by content where the same file was derived
    before (symkin.codegen.plan_cache)."""
    options_ = _options(analysis, options)
    key = tuple((k, _key(v)) for k, v in options_.items())
    with _PLANS_LOCK:
        plans = _PLANS.setdefault(analysis, {})
        found = plans.get(key)
        if found is None:
            make: Callable[[], Plan]
            if options_["notes"] or options_["report"]:
                # the headers' notes and the report's statement leave the routines as they are:
                # the plan without them is derived (or found) once and dressed
                bare = plan_for(analysis, **{**options_, "notes": (), "report": False})
                make = lambda: _dressed(bare, analysis, options_)  # noqa: E731
            else:
                make = lambda: plan(analysis, **options_)  # noqa: E731
            found = plans[key] = plan_cache.cached(analysis, options_, lambda: _counted(make()))
        return found


def _counted(p: Plan) -> Plan:
    """`p` with its routines' operation counts (the headers print them) counted now, so the plan
    kept on disk carries them: sympy's count_ops is ~8 % of a derivation, paid once, not again
    in every process that reads the plan back."""
    for r in p.routines.values():
        r.ops  # noqa: B018 (a cached property: counted and kept in the routine)
    return p


def _dressed(bare: Plan, analysis: Analysis, options: Mapping[str, Any]) -> Plan:
    """What plan(analysis, **options) gives, from `bare`, its plan without notes or report."""
    dressed = with_derivation(bare, analysis) if options["report"] else bare
    if options["notes"]:
        dressed = dataclasses.replace(dressed, notes=tuple(options["notes"]) + bare.notes)
    return dressed


def plan_covering(analysis: Analysis, level: str | None = None, **options: Any) -> Plan:
    """A plan whose evaluators compute what plan_for(analysis, **options)'s do at `level` (all
    its levels when None): one derived already for this analysis with the same options, or
    with sensitivities besides, or with more levels than `level`; else the plan with
    sensitivities found by content (symkin.codegen.plan_cache); else plan_for's. For
    evaluating, not for writing files (derive writes what was asked)."""
    asked = _options(analysis, options)
    want = {k: _key(v) for k, v in asked.items()}

    def covers(have: dict[str, object], p: Plan) -> bool:
        same = all(have[k] == v for k, v in want.items() if k not in ("sensitivity", "levels"))
        if level is None:
            levels_ok = have["levels"] == want["levels"]
        else:
            levels_ok = any(lv.name == level for lv in p.levels)
        return same and levels_ok and (p.sensitivity or not want["sensitivity"])

    with _PLANS_LOCK:
        derived = list(_PLANS.get(analysis, {}).items())
    for key, found in derived:
        if covers(dict(key), found):
            return found
    # kept by content: with sensitivities besides, or (for one level) every level
    wider = [{**asked, "sensitivity": True}]
    if level is not None:
        wider += [{**asked, "levels": None}, {**asked, "levels": None, "sensitivity": True}]
    tried = [want]  # plan_for looks the asked one up itself
    for options_ in wider:
        shape = {k: _key(v) for k, v in options_.items()}
        if shape not in tried:
            tried.append(shape)
            kept = plan_cache.find(analysis, options_, Plan)
            if kept is not None and covers(shape, kept):
                return kept
    return plan_for(analysis, **options)


# -- emit ------------------------------------------------------------------------------------------

#: plan -> ((backend, source, precision) -> its texts)
_TEXTS: weakref.WeakKeyDictionary[Plan, dict[tuple[str, str, str], tuple[str, ...]]] = (
    weakref.WeakKeyDictionary()
)
_TEXTS_LOCK = threading.RLock()


def emit(p: Plan, name: str, source: str, precision: str = "float64") -> tuple[str, ...]:
    """The texts backend `name` emits for plan `p` generated from file `source`, in the order of
    its files; once per plan, source and precision. A precision the backend does not run in is
    bad input."""
    b = backend(name)
    if precision not in b.precisions:
        raise InputError(
            f"the {name} backend evaluates in {', '.join(b.precisions)}, not {precision}",
            entry="--backend",
            hint="backends with "
            + precision
            + ": "
            + ", ".join(n for n, r in REGISTRY.items() if precision in r.precisions),
        )
    key = (name, source, precision)
    with _TEXTS_LOCK:
        texts = _TEXTS.setdefault(p, {})
        found = texts.get(key)
        if found is None:
            # kept on disk by the plan's content key: another process (each `symkin eval`,
            # each test worker) that reads the plan back finds its texts too
            found = texts[key] = plan_cache.derived_from(
                p,
                (name, source, precision, templating.digest()),
                lambda: tuple(b.emit(p, source, precision)),
                tuple,
            )
        return found


def files(p: Plan, name: str, source: str, precision: str = "float64") -> dict[str, str]:
    """File name -> text of what backend `name` emits for `p`."""
    return dict(
        zip(backend(name).file_names(p.name), emit(p, name, source, precision), strict=True)
    )


# -- load ------------------------------------------------------------------------------------------

_LOADED: dict[str, Any] = {}
_LOADED_LOCK = threading.Lock()


def digest(name: str, mechanism: str, texts: Sequence[str]) -> str:
    """The content digest of a backend's texts (what a loaded evaluator is cached under)."""
    return hashlib.sha256("\0".join((name, mechanism, *texts)).encode()).hexdigest()


def load(
    name: str,
    mechanism: str,
    texts: Sequence[str],
    shape: Shape | None = None,
    transient: bool = False,
) -> Any:
    """Backend `name`'s evaluator of the emitted `texts` of `mechanism` (its identifier).

    By default the C library comes from the compiled-code cache, verified on every load
    (:func:`.toolchain.build`), and the numpy module from the modules of this process by digest
    (:func:`.toolchain.import_numpy_module`). `transient`: nothing is left on disk or in
    sys.modules (the C is compiled in a temporary folder that is removed at once); the loaded
    evaluator is kept for this process by digest, so it is compiled once."""
    b = backend(name)
    texts = tuple(texts)
    if not transient:
        return b.load(mechanism, texts, shape, False)
    key = f"{digest(name, mechanism, texts)}{shape!r}{toolchain.cflags()!r}"
    found = _LOADED.get(key)
    if found is None:
        with _LOADED_LOCK:
            found = _LOADED.get(key)
            if found is None:
                found = _LOADED[key] = b.load(mechanism, texts, shape, True)
    return found


def evaluator(
    p: Plan,
    name: str,
    source: str,
    precision: str = "float64",
    links: bool = True,
    transient: bool = False,
) -> Any:
    """Plan `p` emitted by backend `name` and loaded: the numpy module or the C library."""
    return load(name, p.name, emit(p, name, source, precision), Shape.of(p, links), transient)


def build(
    analysis: Analysis,
    name: str,
    source: str,
    precision: str = "float64",
    links: bool = True,
    transient: bool = False,
    **options: Any,
) -> tuple[Plan, Any]:
    """The whole chain: the plan of `analysis` with `options` (see :func:`~.plan.plan`), and
    its evaluator from backend `name`."""
    p = plan_for(analysis, **options)
    return p, evaluator(p, name, source, precision, links, transient)
