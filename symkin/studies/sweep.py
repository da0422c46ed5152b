"""`symkin sweep` (docs/cli.md): Monte Carlo over fabrication tolerances, on Dask.

Each sample draws every varied parameter (symkin.studies.variation: its spread, the parameters whose
defaults read it following), checks the sampled geometry by the file's rules (positive plate
lengths, model parameters in range, the other checks of the file), evaluates the
mechanism at every configuration of the input grid with the generated evaluator, and keeps per
point the largest |ΔR| over the grid. A sample that breaks a rule, or cannot be assembled (or
does not converge) somewhere on the grid, is counted as failed (`failed`, of which `invalid`
broke a rule) and left out of the statistics, never dropped silently.

Reproducible bit for bit: samples are drawn in fixed blocks of BLOCK, block b from a generator
seeded with (seed, b), and every block is evaluated alone (same arrays, same C calls), so the
per-sample values, and the statistics computed from all of them in sample order, do not depend
on how the blocks are grouped into Dask tasks, how many workers run them or where.

Schedulers (`--scheduler`): `threads[:N]` (default: the local threaded scheduler on this
machine's cores; the C evaluator releases the GIL), `processes[:N]`, `sync` (one thread, for
debugging), or `tcp://HOST:PORT`, a running `distributed` scheduler (its workers need symkin,
and for the C backend a C compiler: the evaluator travels as its generated text and each worker
process compiles it once).
"""

from __future__ import annotations

import ctypes
import itertools
import math
import os
import re
import sys
import threading
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import sympy as sp

from ..codegen import pipeline
from ..core.errors import AssemblyError, InputError
from ..model.hinges import MODELS
from ..model.mechanism import Mechanism
from .compiled import Compiled
from .variation import Grid, Spread

#: Samples per seeded block: the unit of reproducibility (a Dask task runs whole blocks).
BLOCK = 256
#: The statistics reported per point, as (JSON key, percentile or None).
STATISTICS = (
    ("mean", None),
    ("std", None),
    ("p50", 50.0),
    ("p99", 99.0),
    ("p999", 99.9),
    ("max", 100.0),
)
#: The same at the low end, for a smallest stiffness (the soft samples are the ones that matter).
LOW_STATISTICS = (
    ("mean", None),
    ("std", None),
    ("p50", 50.0),
    ("p1", 1.0),
    ("p01", 0.1),
    ("min", 0.0),
)
#: The statistics of the first natural frequency (its low end: the soft samples matter).
FREQUENCY_STATISTICS = (("mean", None), ("std", None), ("p1", 1.0), ("min", 0.0))


@dataclass(frozen=True)
class Scheduler:
    """Where the chunks run."""

    kind: str  # "threads", "processes", "sync" or "distributed"
    workers: int  # local workers (distributed: those of the cluster, when known)
    address: str = ""

    @property
    def text(self) -> str:
        return (
            self.address
            if self.kind == "distributed"
            else ("sync" if self.kind == "sync" else f"{self.kind}:{self.workers}")
        )


def parse_scheduler(spec: str | None) -> Scheduler:
    """threads[:N] (default: this machine's cores), processes[:N], sync or tcp://HOST:PORT."""
    cores = os.cpu_count() or 1
    if spec is None or not spec.strip():
        return Scheduler("threads", cores)
    spec = spec.strip()
    if spec.startswith(("tcp://", "tls://")):
        host, sep, port = spec.split("://", 1)[1].rpartition(":")
        if not sep or not host or not port.isdigit():
            raise InputError(
                f"'{spec}' is not tcp://HOST:PORT",
                entry="--scheduler",
                hint="give the address the distributed scheduler prints, e.g. tcp://10.0.0.5:8786",
            )
        return Scheduler("distributed", 0, spec)
    kind, _, count = spec.partition(":")
    if kind == "sync" and not count:
        return Scheduler("sync", 1)
    if kind in ("threads", "processes"):
        if not count:
            return Scheduler(kind, cores)
        if count.isdigit() and int(count) > 0:
            return Scheduler(kind, int(count))
    raise InputError(
        f"unknown scheduler '{spec}'",
        entry="--scheduler",
        hint="threads[:N], processes[:N], sync or tcp://HOST:PORT",
    )


@dataclass(frozen=True)
class Task:
    """What a chunk needs; pickled to worker processes (the evaluator as its texts)."""

    evaluator: Compiled
    level: str
    inputs: np.ndarray  # (n, n_inputs): the grid
    vary: tuple[tuple[str, Spread, float], ...]  # (name, spread, nominal value), file order
    seed: int
    samples: int
    checks: tuple[tuple[str, sp.Expr, bool], ...]  # (rule, expression > 0, also <= 1)
    symbols: tuple[sp.Symbol, ...]  # the parameters the checks read
    plates: tuple[str, ...] = ()  # at `loaded`: the plates whose largest stress is kept
    stiff: tuple[str, ...] = ()  # at `loaded`: the points whose smallest stiffness is kept
    modes: bool = False  # at `loaded`, links with mass: the lowest first frequency is kept


#: The diagonal entries of a point's 3 x 3 stiffness a sweep keeps (the smallest over the grid):
#: along x, along y (N per file unit) and in rotation (N file unit per rad).
STIFFNESS = ("x", "y", "rotation")


def geometry_checks(mech: Mechanism) -> tuple[tuple[str, sp.Expr, bool], ...]:
    """The file's numeric rules that the parameters can break, as expressions that must be
    positive (and at most 1 for fractions): plate lengths and model parameters (the rules of
    symkin.model.mechanism.check_values; plates may sit closer together than their length)."""
    out = []
    for h in mech.hinges:
        out.append((f"the plate length of hinge '{h.name}'", sp.sympify(h.length), False))
        for key, raw in h.model_params:
            spec = MODELS[h.model].parameter(key)
            if spec is not None and spec.kind in ("number", "fraction"):
                out.append(
                    (f"'{key}' of hinge '{h.name}'", sp.sympify(raw), spec.kind == "fraction")
                )
        out += notch_checks(h)
    symbols = {p.symbol for p in mech.parameters}
    return tuple((rule, e, frac) for rule, e, frac in out if e.free_symbols & symbols)


def notch_checks(hinge: Any) -> list[tuple[str, sp.Expr, bool]]:
    """A notch's keys positive and its ratio inside the fitted series' range, where its keys
    are parameters (symkin.model.notch_series; check_values' rule)."""
    params = dict(getattr(hinge, "profile_params", ()) or ())
    if not params or hinge.model != "pure_moment":
        return []
    from ..model import notch_series
    from ..model.profiles import section_of

    keys = {"thickness": hinge.thickness, **params}
    out = [
        (f"'{key}' of hinge '{hinge.name}'", sp.sympify(raw), False)
        for key, raw in keys.items()
        if raw is not None
    ]
    tau = notch_series.notch_ratio(section_of(hinge, 1))
    name = f"{notch_series.ratio_name(section_of(hinge, 1))} of hinge '{hinge.name}'"
    low, high = notch_series.RANGE
    return [
        *out,
        (f"{name} above {low:g}", tau - low, False),
        (f"{name} below {high:g}", high - tau, False),
    ]


_CHECKS: dict[tuple, Callable] = {}
_CHECKS_LOCK = threading.Lock()


def _checker(task: Task) -> Callable:
    """The checks lambdified (numpy), once per process."""
    key = (task.checks, task.symbols)
    found = _CHECKS.get(key)
    if found is None:
        with _CHECKS_LOCK:
            found = _CHECKS.get(key)
            if found is None:
                exprs = [e for _, e, _ in task.checks]
                found = _CHECKS[key] = (
                    sp.lambdify(task.symbols, exprs, "numpy", dummify=True)
                    if exprs
                    else (lambda *args: [])
                )
    return found


def sample_block(task: Task, block: int) -> tuple[np.ndarray, np.ndarray]:
    """(params (n, n_params), valid (n,)) of the samples of `block`."""
    first = block * BLOCK
    n = min(BLOCK, task.samples - first)
    rng = np.random.default_rng([task.seed, block])
    shifts = {name: spread.offsets(rng, n, nominal) for name, spread, nominal in task.vary}
    values = task.evaluator.parameter_values(None, shifts)
    params = (
        np.stack([np.broadcast_to(np.asarray(v, dtype=float), (n,)) for v in values], axis=1)
        if values
        else np.zeros((n, 0))
    )
    valid = np.isfinite(params).all(axis=1)
    if task.checks:
        names = list(task.evaluator.sources.params)
        columns = [params[:, names.index(s.name)] for s in task.symbols]
        with np.errstate(all="ignore"):
            for (_, _, fraction), value in zip(task.checks, _checker(task)(*columns)):
                value = np.broadcast_to(np.asarray(value, dtype=float), (n,))
                valid &= value > 0
                if fraction:
                    valid &= value <= 1
    return params, valid


def run_blocks(
    task: Task, first: int, last: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Blocks first..last-1: (worst |ΔR| per sample and point (n, n_points), NaN where failed;
    flag per sample: 0 evaluated, 1 cannot be assembled (or no convergence) somewhere on the
    grid, 2 parameters that break the file's rules, 3 beyond the rigid reach of a force
    actuator's stroke somewhere on the grid (solved, no deviation; docs/physics.md); at
    `loaded`, every plate's largest stress over the grid per sample (n, n_plates) and the
    task's points' smallest diagonal stiffness (n, n_stiff, 3), NaN where failed; with masses,
    each sample's lowest first natural frequency over the grid (n,) Hz, NaN where failed or
    none)."""
    ev = task.evaluator
    n_points = len(ev.points)
    worst_all, flags_all, stress_all, stiff_all, first_all = [], [], [], [], []
    buffer = None
    for block in range(first, last):
        params, valid = sample_block(task, block)
        n = len(params)
        worst = np.full((n, n_points), np.nan)
        stress = np.full((n, len(task.plates)), np.nan)
        stiff = np.full((n, len(task.stiff), len(STIFFNESS)), np.nan)
        flags = np.where(valid, 0, 2).astype(np.int8)
        good = np.flatnonzero(valid)
        if len(good):
            # one call for the C, one vectorized call per parameter set for numpy
            status, buffer = ev.evaluate_grid(params[good], task.inputs, task.level, buffer)
            dx = buffer[:, :, 4::6]
            dy = buffer[:, :, 5::6]
            norm = np.sqrt(dx * dx + dy * dy)  # exact IEEE operations only
            failed = ((status != 0) & (status != 4)).any(axis=1)
            # beyond the rigid reach somewhere on the grid (status 4): solved, no worst deviation
            beyond = (status == 4).any(axis=1) & ~failed
            values = norm.max(axis=1)
            values[failed | beyond] = np.nan
            worst[good] = values
            flags[good[failed]] = 1
            flags[good[beyond]] = 3
            failed = failed | beyond
            for s in good[~failed] if task.plates or task.stiff else ():
                stress[s], stiff[s] = extremes(ev, task.inputs, params[s], task.plates, task.stiff)
        first_f = np.full(n, np.nan)
        if task.modes and len(good):
            kept = good[~failed]
            first_f[kept] = lowest_frequency(ev, task.inputs, params[kept])
        worst_all.append(worst)
        flags_all.append(flags)
        stress_all.append(stress)
        stiff_all.append(stiff)
        first_all.append(first_f)
    return (
        np.concatenate(worst_all),
        np.concatenate(flags_all),
        np.concatenate(stress_all),
        np.concatenate(stiff_all),
        np.concatenate(first_all),
    )


def largest_stress(
    ev: Compiled, inputs: np.ndarray, params: Sequence[float] | None, plates: Sequence[str]
) -> np.ndarray:
    """Every plate's largest stress (Pa) over the configurations `inputs` (n, n_inputs) at
    `loaded`, by the generated numpy module's report (docs/generated-code.md); NaN for a plate
    where some configuration failed. `params` every parameter's value (None: defaults)."""
    return extremes(ev, inputs, params, plates, ())[0]


def extremes(
    ev: Compiled,
    inputs: np.ndarray,
    params: Sequence[float] | None,
    plates: Sequence[str],
    points: Sequence[str],
) -> tuple[np.ndarray, np.ndarray]:
    """Over the configurations `inputs` (n, n_inputs) at `loaded`, by the generated numpy
    module's report (docs/generated-code.md): every plate's largest stress (Pa; n_plates) and
    every point's smallest diagonal stiffness (STIFFNESS; n_points x 3), NaN where some
    configuration failed or the stiffness is not finite. `params` every parameter's value
    (None: defaults)."""
    given = None if params is None else dict(zip(ev.sources.params, map(float, params)))
    res = ev.module.evaluate(
        {h: inputs[:, j] for j, h in enumerate(ev.inputs)},
        "loaded",
        given,
        links=False,
        **pipeline.evaluate_options(ev.module, buckling=False),
    )
    stress = np.full(len(plates), np.nan)
    for k, h in enumerate(plates):
        values = np.asarray(res["plates"][h]["stress"], dtype=float)
        if np.isfinite(values).all():
            stress[k] = values.max()
    stiff = np.full((len(points), len(STIFFNESS)), np.nan)
    for k, p in enumerate(points):
        matrix = np.asarray(res["stiffness"][p], dtype=float)  # (3, 3, n)
        diagonal = np.stack([matrix[i, i] for i in range(len(STIFFNESS))])
        if np.isfinite(diagonal).all():
            stiff[k] = diagonal.min(axis=-1)
    return stress, stiff


def frequency_backend(ev: Compiled) -> str:
    """Who computes a sweep's natural frequencies: the C evaluator's <name>_modes where the
    evaluator is C and has it ("c"), else the generated numpy module's modes() ("numpy")."""
    return "c" if ev.backend == "c" and _modes_sizes(ev) is not None else "numpy"


def _modes_sizes(ev: Compiled) -> tuple[int, int] | None:
    """(massive links, points) of the C evaluator's <name>_modes, from its header; None where
    it has none (docs/generated-code.md, "Natural frequencies in generated code")."""
    header = ev.sources.header
    if f"int {ev.name}_modes(" not in header:
        return None
    prefix = ev.name.upper()
    sizes = [
        re.search(rf"#define {prefix}_N_MODES_{what} (\d+)", header) for what in ("LINKS", "POINTS")
    ]
    if sizes[0] is None or sizes[1] is None:
        return None
    return int(sizes[0][1]), int(sizes[1][1])


def _lowest_frequency_c(ev: Compiled, inputs: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """lowest_frequency by the C evaluator's <name>_modes: one call per parameter set and
    configuration (its first frequency, NaN where it returns non-zero)."""
    sizes = _modes_sizes(ev)
    assert sizes is not None
    links, points = sizes
    count = 3 * links
    dptr = ctypes.POINTER(ctypes.c_double)
    fn = getattr(ev.library.lib, f"{ev.name}_modes")
    fn.restype, fn.argtypes = ctypes.c_int, [dptr, dptr, dptr]
    out = np.empty(count * (1 + 3 * links + 2 * points) or 1)
    x = np.ascontiguousarray(inputs, dtype=float).reshape(len(inputs), -1)
    found = np.full((len(rows), len(x)), np.nan)
    for k, values in enumerate(rows):
        p = np.ascontiguousarray(values, dtype=float)
        if not p.size:
            p = np.zeros(1)
        for j, row in enumerate(x):
            args = np.ascontiguousarray(row) if row.size else np.zeros(1)
            rc = fn(args.ctypes.data_as(dptr), p.ctypes.data_as(dptr), out.ctypes.data_as(dptr))
            if rc == 0:
                found[k, j] = out[0]
    return np.where(np.isnan(found).any(axis=-1), np.nan, found.min(axis=-1))


def lowest_frequency(ev: Compiled, inputs: np.ndarray, params: np.ndarray | None) -> np.ndarray:
    """Per parameter set (rows of `params` (k, n_params); None: the defaults, k = 1) the lowest
    first natural frequency (Hz) over the configurations `inputs` (n, n_inputs) at `loaded`, by
    the backend :func:`frequency_backend` names: the C evaluator's <name>_modes (one call per
    set and configuration), else the generated numpy module's modes() (docs/generated-code.md,
    "Natural frequencies in generated code"), every set at every configuration in one call; NaN
    where some configuration has none (not solved, or beyond buckling)."""
    if frequency_backend(ev) == "c":
        given = [ev.parameters()] if params is None else np.asarray(params, dtype=float)
        return _lowest_frequency_c(ev, inputs, np.asarray(given, dtype=float))
    rows = np.zeros((1, 0)) if params is None else np.asarray(params, dtype=float)
    given = (
        None
        if params is None
        else {p: rows[:, [j]] for j, p in enumerate(ev.sources.params)}  # (k, 1)
    )
    found = ev.module.modes(
        {h: inputs[None, :, j] for j, h in enumerate(ev.inputs)}, params=given, count=1
    )
    first = np.asarray(found["frequencies"][0], dtype=float)  # (k, n)
    first = np.where(np.asarray(found["ok"]), first, np.nan)
    out = first.min(axis=-1)
    return np.where(np.isnan(first).any(axis=-1), np.nan, out)


def _statistics(v: np.ndarray, which=STATISTICS) -> dict[str, float | None]:
    """mean, std (n - 1), p50, p99, p99.9 and max of `v` (`which`: LOW_STATISTICS for the low
    end), its non-finite values left out."""
    v = v[np.isfinite(v)]
    out: dict[str, float | None] = {}
    for key, q in which:
        if len(v) == 0 or (key == "std" and len(v) < 2):
            out[key] = None
        elif key == "mean":
            out[key] = float(np.mean(v))
        elif key == "std":
            out[key] = float(np.std(v, ddof=1))
        else:
            out[key] = float(np.percentile(v, q))
    return out


@dataclass(frozen=True)
class Sweep:
    """The result of `symkin sweep`."""

    name: str
    level: str
    backend: str
    grid: Grid
    vary: dict[str, str]  # p -> spread as given
    samples: int
    seed: int
    scheduler: str
    seconds: float  # wall time of the Monte Carlo (compile excluded)
    chunks: int
    values: np.ndarray = field(repr=False)  # (samples, n_points): worst |ΔR|, NaN where failed
    # (samples,): 0 ok, 1 cannot assemble, 2 invalid, 3 beyond the rigid reach (not failed)
    flags: np.ndarray = field(repr=False)
    nominal: dict[str, float] = field(default_factory=dict)  # worst |ΔR| at nominal values
    points: tuple[str, ...] = ()
    plates: tuple[str, ...] = ()  # at `loaded`: the plates whose largest stress is kept
    stress: np.ndarray | None = field(default=None, repr=False)  # (samples, n_plates), Pa
    nominal_stress: dict[str, float] = field(default_factory=dict)  # at nominal values
    stiff: tuple[str, ...] = ()  # at `loaded`: the points whose smallest stiffness is kept
    stiffness: np.ndarray | None = field(default=None, repr=False)  # (samples, n_stiff, 3)
    nominal_stiffness: dict[str, list[float]] = field(default_factory=dict)  # at nominal values
    # links with mass at `loaded`: each sample's lowest first natural frequency over the grid
    first: np.ndarray | None = field(default=None, repr=False)  # (samples,), Hz
    nominal_first: float | None = None  # at nominal values
    first_backend: str | None = None  # who computed them (frequency_backend): "c" or "numpy"

    @property
    def failed(self) -> int:
        return int(((self.flags != 0) & (self.flags != 3)).sum())

    @property
    def beyond_reach(self) -> int:
        """Samples beyond the rigid reach of a force actuator's stroke somewhere on the grid:
        solved, with no deviation (docs/physics.md, "Beyond the rigid reach")."""
        return int((self.flags == 3).sum())

    @property
    def invalid(self) -> int:
        return int((self.flags == 2).sum())

    def statistics(self, point: str) -> dict[str, float | None]:
        """mean, std (n - 1), p50, p99, p99.9 and max of the evaluated samples' worst |ΔR|."""
        out = _statistics(self.values[self.flags == 0, self.points.index(point)])
        out["nominal"] = self.nominal.get(point)
        return out

    def stress_statistics(self, plate: str) -> dict[str, float | None]:
        """The same statistics of the evaluated samples' largest stress of `plate` (Pa)."""
        assert self.stress is not None
        out = _statistics(self.stress[self.flags == 0, self.plates.index(plate)])
        out["nominal"] = self.nominal_stress.get(plate)
        return out

    def stiffness_statistics(self, point: str) -> dict[str, dict[str, float | None]]:
        """The low end's statistics (LOW_STATISTICS) of the evaluated samples' smallest
        stiffness of `point`, per diagonal entry (STIFFNESS)."""
        assert self.stiffness is not None
        k = self.stiff.index(point)
        out = {}
        for j, key in enumerate(STIFFNESS):
            out[key] = _statistics(self.stiffness[self.flags == 0, k, j], LOW_STATISTICS)
            out[key]["nominal"] = self.nominal_stiffness[point][j]
        return out

    def frequency_statistics(self) -> dict[str, float | None]:
        """mean, std, p1 and min of the evaluated samples' lowest first frequency (Hz)."""
        assert self.first is not None
        return _statistics(self.first[self.flags == 0], FREQUENCY_STATISTICS)

    def as_json(self) -> dict:
        return {
            "samples": self.samples,
            "failed": self.failed,
            "invalid": self.invalid,
            "beyond_reach": self.beyond_reach,
            "seed": self.seed,
            "scheduler": self.scheduler,
            "seconds": self.seconds,
            "chunks": self.chunks,
            "block": BLOCK,
            "level": self.level,
            "backend": self.backend,
            "inputs": self.grid.as_json(),
            "configurations": len(self.grid.rows),
            "vary": dict(self.vary),
            "points": {p: self.statistics(p) for p in self.points},
            **(
                {"plates": {h: self.stress_statistics(h) for h in self.plates}}
                if self.plates
                else {}
            ),
            **(
                {"stiffness": {p: self.stiffness_statistics(p) for p in self.stiff}}
                if self.stiff
                else {}
            ),
            **(
                {
                    "frequencies": {"f1": self.frequency_statistics()},
                    "frequencies_backend": self.first_backend,
                }
                if self.first is not None
                else {}
            ),
        }


def run(
    evaluator: Compiled,
    mech: Mechanism,
    vary: Mapping[str, Spread],
    grid: Grid,
    samples: int,
    seed: int = 0,
    scheduler: Scheduler | None = None,
    level: str | None = None,
    chunks: int | None = None,
    progress: bool = False,
    client=None,
) -> Sweep:
    """The Monte Carlo sweep (see the module docstring); `chunks` Dask tasks (default: about
    four per worker, whole blocks each). A distributed `client` (see `connect`) may be given;
    it is closed at the end. `level` None: the evaluator's default (Compiled.code)."""
    level = evaluator.code(level)
    scheduler = scheduler or parse_scheduler(None)
    nominal = evaluator.defaults
    plates: tuple[str, ...] = ()
    nominal_stress: dict[str, float] = {}
    stiff: tuple[str, ...] = ()
    nominal_stiffness: dict[str, list[float]] = {}
    modes = False
    nominal_first = None
    if level == "loaded" and "loaded" in evaluator.levels:
        # links with mass: the numpy module has modes() (the first frequency's spread)
        modes = hasattr(evaluator.module, "modes")
        if modes:
            found_first = float(lowest_frequency(evaluator, grid.rows, None)[0])
            nominal_first = found_first if np.isfinite(found_first) else None
        # the plates the generated module reports on (none without the level's report)
        first = {h: grid.rows[:1, j] for j, h in enumerate(evaluator.inputs)}
        module = evaluator.module
        found = module.evaluate(
            first, "loaded", links=False, **pipeline.evaluate_options(module, buckling=False)
        )
        plates = tuple(found.get("plates", ()))
        if plates:
            # the points whose stiffness is finite at every configuration (a point a held
            # stroke pins along its line, or one on the frame, has none)
            points = tuple(p for p in found.get("stiffness", ()) if p in evaluator.points)
            stress, stiffness = extremes(evaluator, grid.rows, None, plates, points)
            nominal_stress = {h: float(v) for h, v in zip(plates, stress) if np.isfinite(v)}
            stiff = tuple(p for p, k in zip(points, stiffness) if np.isfinite(k).all())
            nominal_stiffness = {
                p: [float(v) for v in k] for p, k in zip(points, stiffness) if p in stiff
            }
    task = Task(
        evaluator,
        level,
        grid.rows,
        tuple((p, s, nominal[p]) for p, s in vary.items()),
        int(seed),
        int(samples),
        geometry_checks(mech),
        tuple(p.symbol for p in mech.parameters),
        plates,
        stiff,
        modes,
    )
    blocks = math.ceil(samples / BLOCK)
    if client is None and scheduler.kind == "distributed":
        client = connect(scheduler)
    try:
        workers = scheduler.workers or (len(client.scheduler_info()["workers"]) if client else 1)
        count = max(1, min(blocks, chunks or 4 * max(1, workers)))
        edges = [round(k * blocks / count) for k in range(count + 1)]
        spans = [(a, b) for a, b in itertools.pairwise(edges) if b > a]
        start = time.perf_counter()
        if client is not None:
            parts = _distributed(client, task, spans, progress)
        else:
            parts = _local(scheduler, task, spans, progress)
        seconds = time.perf_counter() - start
    finally:
        if client is not None:
            client.close()
    values = np.concatenate([p[0] for p in parts])
    flags = np.concatenate([p[1] for p in parts])
    stress = np.concatenate([p[2] for p in parts])
    stiffness = np.concatenate([p[3] for p in parts])
    first = np.concatenate([p[4] for p in parts])
    status, out = evaluator.evaluate_rows(grid.rows, level)
    nominal_worst = {}
    if (status == 0).all():
        for i, p in enumerate(evaluator.points):
            nominal_worst[p] = float(np.max(np.hypot(out[:, 6 * i + 4], out[:, 6 * i + 5])))
    return Sweep(
        evaluator.name,
        level,
        evaluator.backend,
        grid,
        {p: s.text for p, s in vary.items()},
        int(samples),
        int(seed),
        scheduler.text,
        seconds,
        len(spans),
        values,
        flags,
        nominal_worst,
        tuple(evaluator.points),
        plates,
        stress if plates else None,
        nominal_stress,
        stiff,
        stiffness if stiff else None,
        nominal_stiffness,
        first if modes else None,
        nominal_first,
        frequency_backend(evaluator) if modes else None,
    )


def _local(
    scheduler: Scheduler, task: Task, spans: Sequence[tuple[int, int]], progress: bool
) -> list:
    import dask

    jobs = [dask.delayed(run_blocks, pure=False)(task, a, b) for a, b in spans]
    kind = "sync" if scheduler.kind == "sync" else scheduler.kind
    kwargs = {} if kind == "sync" else {"num_workers": scheduler.workers}
    if progress:
        from dask.diagnostics import ProgressBar

        with ProgressBar(out=sys.stderr, minimum=0.5):
            return list(dask.compute(*jobs, scheduler=kind, **kwargs))
    return list(dask.compute(*jobs, scheduler=kind, **kwargs))


def connect(scheduler: Scheduler):
    """A client of the running distributed scheduler; bad input (exit 2) when unreachable."""
    from distributed import Client

    try:
        return Client(scheduler.address, timeout="5s", set_as_default=False)
    except (OSError, TimeoutError) as exc:
        raise InputError(
            f"cannot reach the scheduler at {scheduler.address} ({exc})",
            entry="--scheduler",
            hint="start one (dask scheduler, then dask "
            "worker ADDRESS on each machine) or check the address",
        ) from None


def _distributed(client, task: Task, spans: Sequence[tuple[int, int]], progress: bool) -> list:
    shared = client.scatter(task, broadcast=True)
    futures = [client.submit(run_blocks, shared, a, b, pure=False) for a, b in spans]
    if progress:
        done = -1
        while done < len(futures):
            now = sum(f.done() for f in futures)
            if now != done:
                done = now
                print(
                    f"\rsymkin: sweep {done}/{len(futures)} chunks",
                    end="",
                    file=sys.stderr,
                    flush=True,
                )
            time.sleep(0.2)
        print(file=sys.stderr)
    return client.gather(futures)


def check_grid(evaluator: Compiled, grid: Grid, level: str) -> None:
    """Refuse (exit 3) a grid the nominal mechanism cannot reach everywhere, before the work."""
    status, _ = evaluator.evaluate_rows(grid.rows, level)
    bad = (status != 0) & (status != 4)  # 4: beyond the rigid reach, solved (no deviation)
    if bad.any():
        k = int(np.flatnonzero(bad)[0])
        at = ", ".join(f"{h}={v:g}" for h, v in zip(evaluator.inputs, grid.rows[k]))
        raise AssemblyError(
            f"{evaluator.name}: with the nominal parameters the mechanism "
            f"cannot be evaluated at {at} ({int(bad.sum())} of "
            f"{len(status)} configurations of the input grid); narrow --input"
        )


def text(result: Sweep) -> str:
    """The summary of `symkin sweep`."""
    ranges = (
        ", ".join(f"{k} in [{v[0]:g}, {v[1]:g}] ({v[2]})" for k, v in result.grid.as_json().items())
        or "its one configuration (a structure: no inputs)"
    )
    lines = [
        f"{result.name}: {result.samples} samples of "
        + ", ".join(f"{p} = {s}" for p, s in result.vary.items())
        + f"; worst |dR| over {ranges}; level {result.level} ({result.backend})",
        f"seed {result.seed}, scheduler {result.scheduler}, {result.chunks} chunks, "
        f"{result.seconds:.2f} s",
        f"failed: {result.failed}"
        + (
            f" ({result.invalid} with parameters that break the file's rules)"
            if result.invalid
            else ""
        )
        + (
            f"; beyond the rigid linkage's reach (no deviation): {result.beyond_reach}"
            if result.beyond_reach
            else ""
        ),
    ]
    header = "".join(f"{k:>12}" for k in ("nominal", "mean", "std", "p50", "p99", "p99.9", "max"))

    def row(name: str, s: Mapping[str, float | None], which=STATISTICS) -> str:
        cells = [s["nominal"]] + [s[k] for k, _ in which]
        return f"  {name:<10}" + "".join(
            f"{c:>12.4e}" if c is not None else f"{'-':>12}" for c in cells
        )

    lines += ["", f"  {'point':<10}" + header]
    lines += [row(p, result.statistics(p)) for p in result.points]
    if result.plates:
        lines += ["", "largest stress over the grid (Pa)", f"  {'plate':<10}" + header]
        lines += [row(h, result.stress_statistics(h)) for h in result.plates]
    if result.stiff:
        low = "".join(f"{k:>12}" for k in ("nominal", "mean", "std", "p50", "p1", "p0.1", "min"))
        lines += [
            "",
            "smallest stiffness over the grid (x, y: N per file unit; rotation: N file unit/rad)",
            f"  {'point':<10}" + low,
        ]
        for p in result.stiff:
            stats = result.stiffness_statistics(p)
            lines += [row(f"{p} {key}", stats[key], LOW_STATISTICS) for key in STIFFNESS]
    if result.first is not None:
        low = "".join(f"{k:>12}" for k in ("nominal", "mean", "std", "p1", "min"))
        stats = {**result.frequency_statistics(), "nominal": result.nominal_first}
        by = (
            f"the C evaluator's {result.name}_modes"
            if result.first_backend == "c"
            else "the generated numpy module's modes()"
        )
        lines += [
            "",
            f"lowest first natural frequency over the grid (Hz, by {by}; docs/physics.md, "
            "'Natural frequencies')",
            f"  {'':<10}" + low,
            row("f1", stats, FREQUENCY_STATISTICS),
        ]
    return "\n".join(lines) + "\n"


def plot(result: Sweep, path: str) -> None:
    """Histograms of every point's worst |ΔR| over the samples (format from the suffix)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from .tradeoff import save_figure

    n = len(result.points)
    fig, axes = plt.subplots(n, 1, figsize=(6.4, 2.6 * n + 0.6), squeeze=False)
    for ax, p in zip(axes[:, 0], result.points):
        v = result.values[result.flags == 0, result.points.index(p)]
        s = result.statistics(p)
        if len(v):
            ax.hist(v, bins=min(60, max(10, len(v) // 20)), color="0.6")
        for key, style in (("nominal", "k-"), ("mean", "b--"), ("p99", "r:")):
            if s[key] is not None:
                ax.axvline(s[key], color=style[0], linestyle=style[1:], label=key)
        ax.set_xlabel(f"largest |ΔR| of {p} over the input grid")
        ax.set_ylabel("samples")
        ax.legend(loc="upper right", fontsize="small")
    fig.suptitle(
        f"{result.name}: {result.samples} samples, level {result.level}"
        + (f", {result.failed} failed" if result.failed else "")
    )
    fig.tight_layout()
    save_figure(fig, path)
