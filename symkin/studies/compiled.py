"""`symkin.compile`: a mechanism's generated evaluator, in memory (docs/generated-code.md).

    ev = symkin.compile("examples/four_bar.toml")                 # the generated C
    res = ev.evaluate({"A0": numpy.linspace(-0.2, 0.2, 1001)})   # one C call for all points
    ev.sensitivity({"A0": 0.2})["C"]["l"]                         # d(dx, dy)/dl

Nothing is written: the C is compiled in a temporary folder that is removed as soon as the
library is loaded, and the numpy module (which also gives the parameter defaults) is executed
from its text. An evaluator pickles as its generated texts, never as a loaded library, so Dask
can ship it to worker processes and to other machines; each process compiles it on first use,
once (the C needs a compiler there too).

The results have the shapes of the generated numpy module's `evaluate`, `sensitivity` and
`sensitivity_full`, whichever backend runs them; the links' rotations are left out (the
generated module's `evaluate` and `<name>_evaluate_pose` have them).
"""

from __future__ import annotations

import hashlib
import threading
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType

import numpy as np

from ..codegen import toolchain
from ..core import levels as level_table
from ..core.errors import InputError
from ..graph.pruning import for_levels
from ..graph.structure import build
from ..kinematics.analysis import Analysis
from ..model.mechanism import Mechanism, load

BACKENDS = ("c", "numpy")


@dataclass(frozen=True)
class Sources:
    """What an evaluator is made of: the generated texts and the names they use."""

    name: str
    backend: str  # "c" or "numpy"
    header: str  # C header and source ("" for numpy)
    source: str
    numpy: str  # the numpy module (parameter defaults, numpy backend)
    inputs: tuple[str, ...]
    params: tuple[str, ...]
    points: tuple[str, ...]
    hinges: tuple[str, ...]
    levels: tuple[str, ...]
    sensitivity: bool

    @property
    def digest(self) -> str:
        text = "\0".join((self.backend, self.header, self.source, self.numpy))
        return hashlib.sha256(text.encode()).hexdigest()[:24]


#: The loaded evaluators of this process, by digest: compiled once per process.
_LOADED: dict[str, tuple[ModuleType, toolchain.Library | None]] = {}
_LOCK = threading.Lock()


class Compiled:
    """A generated evaluator of one mechanism (see the module docstring)."""

    def __init__(self, sources: Sources) -> None:
        self.sources = sources
        self.name = sources.name
        self.backend = sources.backend
        self.inputs = sources.inputs
        self.points = sources.points
        self.hinges = sources.hinges
        self.levels = sources.levels

    def __reduce__(self):
        return Compiled, (self.sources,)

    def __repr__(self) -> str:
        return f"<symkin.compile {self.name!r} ({self.backend}), levels {', '.join(self.levels)}>"

    # -- what is loaded --------------------------------------------------------------------------
    def _loaded(self) -> tuple[ModuleType, toolchain.Library | None]:
        key = self.sources.digest
        found = _LOADED.get(key)
        if found is None:
            with _LOCK:
                found = _LOADED.get(key)
                if found is None:
                    s = self.sources
                    module = toolchain.numpy_module_in_memory(s.numpy, s.name)
                    lib = None
                    if s.backend == "c":
                        lib = toolchain.Library(
                            toolchain.load_transient(s.name, s.header, s.source),
                            s.name,
                            len(s.inputs),
                            len(s.params),
                            len(s.points),
                            len(s.hinges),
                        )
                    found = _LOADED[key] = (module, lib)
        return found

    @property
    def module(self) -> ModuleType:
        """The generated numpy module (in memory)."""
        return self._loaded()[0]

    @property
    def library(self) -> toolchain.Library:
        """The loaded C library (backend c)."""
        lib = self._loaded()[1]
        if lib is None:
            raise ValueError("a numpy evaluator has no C library")
        return lib

    # -- parameters ------------------------------------------------------------------------------
    @property
    def defaults(self) -> dict[str, float]:
        """Every parameter's default, in file order."""
        return dict(self.module.PARAMETERS)

    def parameters(
        self, given: Mapping[str, float] | None = None, shifts: Mapping[str, float] | None = None
    ) -> list[float]:
        """Parameter values in file order: `given` ones, the others from their defaults; a
        shift is added to a parameter once its value is set, so the parameters whose defaults
        read it follow (the generated module's `parameters`)."""
        return [float(v) for v in self.module.parameters(given, shifts)]

    def code(self, level: str | None, sensitivity: bool = False) -> str:
        """`level` checked against the generated ones (None: `exact` when generated, else the
        most faithful; with `sensitivity`, among the levels that have sensitivities)."""
        if level is None:
            names = [
                n for n in self.levels if not sensitivity or level_table.get(n).sensitivity
            ] or list(self.levels)
            level = level_table.DEFAULT if level_table.DEFAULT in names else names[-1]
        if level not in self.levels:
            raise ValueError(f"level must be one of {self.levels}, got {level!r}")
        return level

    # -- many configurations at one parameter vector ----------------------------------------------
    def evaluate_rows(
        self, x: np.ndarray, level: str | None = None, params: Sequence[float] | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """x (n, n_inputs) -> (status (n,), out (n, 6 n_points)): per row and point rigid x, y,
        compliant x, y, deviation x, y, as the C evaluator writes them; status 0 where it
        succeeded (NaN rows elsewhere). `params`: every parameter's value (None: defaults)."""
        level = self.code(level)
        if self.backend == "c":
            status, out, _ = self.library.evaluate_rows(x, params, level_table.get(level).code)
            return status, out
        res = self.module.evaluate(self._columns(x), level, self._named(params))
        out = np.empty((x.shape[0], 6 * len(self.points)))
        for i, p in enumerate(self.points):
            for j, key in enumerate(("rigid", "compliant", "deviation")):
                out[:, 6 * i + 2 * j : 6 * i + 2 * j + 2] = res["points"][p][key].T
        return np.where(res["ok"], 0, 1).astype(np.intc), out

    def sensitivity_rows(
        self, x: np.ndarray, level: str | None = None, params: Sequence[float] | None = None
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """x (n, n_inputs) -> (status, values (n, 6 n_points), deviation and rigid
        derivatives (n, n_points, n_variables, 2)); variables: the parameters, then the
        inputs."""
        level = self.code(level, sensitivity=True)
        if self.backend == "c":
            return self.library.sensitivity_rows(x, params, level_table.get(level).code)
        res = self.module.sensitivity_full(self._columns(x), level, self._named(params))
        n = x.shape[0]
        values = np.empty((n, 6 * len(self.points)))
        dev = np.empty((n, len(self.points), len(self.sources.params) + len(self.inputs), 2))
        rig = np.empty_like(dev)
        for i, p in enumerate(self.points):
            for j, key in enumerate(("rigid", "compliant", "deviation")):
                values[:, 6 * i + 2 * j : 6 * i + 2 * j + 2] = res["points"][p][key].T
            for out, kind in ((dev, "deviation"), (rig, "rigid")):
                table = res[kind][p]
                for v, name in enumerate(self.sources.params):
                    out[:, i, v] = table["params"][name].T
                for v, name in enumerate(self.inputs):
                    out[:, i, len(self.sources.params) + v] = table["inputs"][name].T
        return np.where(res["ok"], 0, 1).astype(np.intc), values, dev, rig

    # -- the generated module's interface ---------------------------------------------------------
    def evaluate(
        self,
        inputs: Mapping[str, object],
        level: str | None = None,
        params: Mapping[str, float] | None = None,
    ) -> dict:
        """As the generated module's `evaluate` (docs/generated-code.md), in one C call."""
        if self.backend == "numpy":
            return self.module.evaluate(inputs, self.code(level), params)
        x, shape = self._rows(inputs)
        status, out, angles = self.library.evaluate_rows(
            x, self.parameters(params), level_table.get(self.code(level)).code, angles=True
        )
        m = len(self.hinges)
        return {
            "points": {
                p: {
                    key: _shaped(out[:, 6 * i + 2 * j : 6 * i + 2 * j + 2], shape)
                    for j, key in enumerate(("rigid", "compliant", "deviation"))
                }
                for i, p in enumerate(self.points)
            },
            "ok": (status == 0).reshape(shape),
            "angles": {
                kind: {h: angles[:, off + a].reshape(shape) for a, h in enumerate(self.hinges)}
                for kind, off in (("rigid", 0), ("compliant", m))
            },
            "links": {},
        }

    def sensitivity(
        self,
        inputs: Mapping[str, object],
        level: str | None = None,
        params: Mapping[str, float] | None = None,
    ) -> dict:
        """{P: {p: a}}: d(dx, dy)/dp, a of shape (2, *broadcast shape) (docs/sensitivity.md)."""
        full = self.sensitivity_full(inputs, level, params)
        return {p: full["deviation"][p]["params"] for p in self.points}

    def sensitivity_full(
        self,
        inputs: Mapping[str, object],
        level: str | None = None,
        params: Mapping[str, float] | None = None,
    ) -> dict:
        """As the generated module's `sensitivity_full`: the points, ok, and "deviation" and
        "rigid": {P: {"params": {p: a}, "inputs": {H: a}}}."""
        if not self.sources.sensitivity:
            raise ValueError("this evaluator was compiled without sensitivities")
        if self.backend == "numpy":
            return self.module.sensitivity_full(inputs, self.code(level, sensitivity=True), params)
        x, shape = self._rows(inputs)
        status, values, dev, rig = self.library.sensitivity_rows(
            x, self.parameters(params), level_table.get(self.code(level, sensitivity=True)).code
        )
        names = self.sources.params

        def table(data: np.ndarray, i: int) -> dict:
            col = {v: _shaped(data[:, i, v], shape) for v in range(data.shape[2])}
            return {
                "params": {q: col[v] for v, q in enumerate(names)},
                "inputs": {h: col[len(names) + v] for v, h in enumerate(self.inputs)},
            }

        return {
            "points": {
                p: {
                    key: _shaped(values[:, 6 * i + 2 * j : 6 * i + 2 * j + 2], shape)
                    for j, key in enumerate(("rigid", "compliant", "deviation"))
                }
                for i, p in enumerate(self.points)
            },
            "ok": (status == 0).reshape(shape),
            "deviation": {p: table(dev, i) for i, p in enumerate(self.points)},
            "rigid": {p: table(rig, i) for i, p in enumerate(self.points)},
        }

    # -- helpers ---------------------------------------------------------------------------------
    def _rows(self, inputs: Mapping[str, object]) -> tuple[np.ndarray, tuple[int, ...]]:
        # the file's inputs pruning dropped (they move none of the points) are ignored
        if set(inputs) - set(self.module.PRUNED_INPUTS) != set(self.inputs):
            raise ValueError(f"inputs must be exactly {self.inputs}, got {tuple(sorted(inputs))}")
        arrays = np.broadcast_arrays(*(np.asarray(inputs[n], dtype=float) for n in self.inputs))
        shape = arrays[0].shape
        return np.stack([a.reshape(-1) for a in arrays], axis=1), shape

    def _columns(self, x: np.ndarray) -> dict[str, np.ndarray]:
        x = np.asarray(x, dtype=float)
        return {n: x[:, j] for j, n in enumerate(self.inputs)}

    def _named(self, params: Sequence[float] | None) -> dict[str, float] | None:
        return None if params is None else dict(zip(self.sources.params, params))


def _shaped(columns: np.ndarray, shape: tuple[int, ...]) -> np.ndarray:
    """(n, k) or (n,) row data as (k, *shape) or shape."""
    if columns.ndim == 1:
        return columns.reshape(shape)
    return columns.T.reshape((columns.shape[1],) + shape)


def compile(
    mechanism: Mechanism | Analysis | str | Path,
    backend: str = "c",
    points: Sequence[str] | None = None,
    levels: Sequence[str] | None = None,
    sensitivity: bool = True,
    fixed: Mapping[str, object] | None = None,
) -> Compiled:
    """The generated evaluator of a mechanism (file, Mechanism or Analysis), in memory: the
    requested points and levels (all by default), with its sensitivities unless told not to or
    inputs are `fixed` (input -> angle: held constant, folded into the evaluator)."""
    from ..codegen.backends.c import backend as c_backend
    from ..codegen.backends.numpy import backend as numpy_backend
    from ..codegen.plan import plan
    from .evaluation import check_fabricated_pose, fixed_angles

    if backend not in BACKENDS:
        raise InputError(
            f"unknown backend '{backend}'",
            entry="--backend",
            hint="backends: " + ", ".join(BACKENDS),
        )
    pruned: tuple[str, ...] = ()
    if isinstance(mechanism, Analysis):
        analysis = mechanism
        held = fixed_angles(analysis.mechanism, fixed)
    else:
        mech = mechanism if isinstance(mechanism, Mechanism) else load(mechanism)
        held = fixed_angles(mech, fixed)
        if points is not None:  # only the loops that move the points (docs/pruning.md)
            mech, pruning = for_levels(mech, points, levels)
            pruned = pruning.dropped_inputs
        analysis = Analysis(build(mech), points)
    check_fabricated_pose(analysis)
    mech = analysis.mechanism
    held = {k: v for k, v in held.items() if k in analysis.mechanism.inputs}
    p = plan(
        analysis,
        points,
        levels,
        sensitivity=sensitivity,
        links=False,
        fixed=held,
        pruned_inputs=pruned,
    )
    source = Path(mech.path).name
    header, code = c_backend.emit(p, source) if backend == "c" else ("", "")
    return Compiled(
        Sources(
            name=mech.name,
            backend=backend,
            header=header,
            source=code,
            numpy=numpy_backend.emit(p, source),
            inputs=p.inputs,
            params=tuple(q.name for q in p.parameters),
            points=p.points,
            hinges=p.hinges,
            levels=tuple(lv.name for lv in p.levels),
            sensitivity=p.sensitivity,
        )
    )
