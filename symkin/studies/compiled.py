"""`symkin.compile`: a mechanism's generated evaluator, in memory (docs/generated-code.md).

    ev = symkin.compile("examples/four_bar.toml")                 # the generated C
    res = ev.evaluate({"A0": numpy.linspace(-0.2, 0.2, 1001)})   # one C call for all points
    ev.sensitivity({"A0": 0.2})["C"]["l"]                         # d(dx, dy)/dl

Nothing is written: the C is compiled in a temporary folder that is removed as soon as the
library is loaded, and the numpy module is executed from its text. A C evaluator never loads the
numpy module unless asked for it (:attr:`Compiled.module`): the parameters' defaults and values
come from the module's parameter section alone (templates/numpy/parameters.py.j2). An
evaluator pickles as its generated texts, never as a loaded library, so Dask can ship it to
worker processes and to other machines; each process compiles it on first use, once (the C
needs a compiler there too).

The results have the shapes of the generated numpy module's `evaluate`, `sensitivity` and
`sensitivity_full`, whichever backend runs them; the links' rotations are left out (the
generated module's `evaluate` and `<name>_evaluate_pose` have them).
"""

from __future__ import annotations

import inspect
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType, SimpleNamespace
from typing import Any

import numpy as np

from ..codegen import pipeline, plan_cache, toolchain
from ..codegen.backends.numpy import backend as numpy_backend
from ..core import levels as level_table
from ..graph.pruning import for_levels
from ..graph.structure import build
from ..kinematics.analysis import Analysis
from ..model.mechanism import Mechanism
from ..model.reader import load


@dataclass(frozen=True)
class Sources:
    """What an evaluator is made of: the generated texts and the names they use."""

    name: str
    backend: str  # a generated-code backend (symkin.codegen.pipeline.BACKENDS)
    texts: tuple[str, ...]  # what the backend emitted, in the order of its files (() for numpy)
    numpy: str  # the numpy module (the numpy backend's evaluator; else Compiled.module alone)
    #: the numpy module's parameter section alone (PARAMETERS, parameters()): the parameters'
    #: values for a backend whose evaluator is not the module
    parameter_source: str
    pruned: tuple[str, ...]  # the file's inputs that move none of the points (accepted, ignored)
    inputs: tuple[str, ...]
    params: tuple[str, ...]
    points: tuple[str, ...]
    hinges: tuple[str, ...]
    levels: tuple[str, ...]
    sensitivity: bool
    #: the level used when none is given: the module's DEFAULT_LEVEL (levels.default_for)
    default_level: str = level_table.KINEMATIC_DEFAULT

    @property
    def files(self) -> dict[str, str]:
        """File name -> text of what the backend emitted (the numpy backend's: its module)."""
        texts = self.texts or (self.numpy,)
        return dict(zip(pipeline.backend(self.backend).file_names(self.name), texts, strict=True))

    @property
    def header(self) -> str:
        """The C header ("" for a backend that emits none)."""
        return self.files.get(f"{self.name}.h", "")

    @property
    def source(self) -> str:
        """The C source ("" for a backend that emits none)."""
        return self.files.get(f"{self.name}.c", "")


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
        # loaded on first use, never pickled: the evaluator, the numpy module, the parameters
        self._evaluator: Any = None
        self._module: ModuleType | None = None
        self._parameter_section: Any = None

    def __reduce__(self) -> tuple[type[Compiled], tuple[Sources]]:
        return Compiled, (self.sources,)

    def __repr__(self) -> str:
        return f"<symkin.compile {self.name!r} ({self.backend}), levels {', '.join(self.levels)}>"

    # -- what is loaded --------------------------------------------------------------------------
    def _loaded(self) -> Any:
        """The backend's evaluator (the numpy module for numpy): loaded once per process,
        nothing written (pipeline.load, transient)."""
        if self._evaluator is None:
            s = self.sources
            texts = s.texts if not self._row.is_module else (s.numpy,)
            self._evaluator = pipeline.load(s.backend, s.name, texts, self.shape, transient=True)
        return self._evaluator

    @property
    def _parameters(self) -> Any:
        """What gives the parameters' defaults and values: the module where it is the evaluator,
        else its parameter section alone (executed in memory once per process)."""
        if self._row.is_module:
            return self.module
        if self._parameter_section is None:
            namespace: dict[str, Any] = {"__name__": f"symkin_parameters_{self.name}"}
            exec(self.sources.parameter_source, namespace)  # generated by symkin, as the module
            self._parameter_section = SimpleNamespace(**namespace)
        return self._parameter_section

    @property
    def _row(self) -> pipeline.Backend:
        return pipeline.backend(self.backend)

    @property
    def shape(self) -> pipeline.Shape:
        """The names its arguments and results are laid out by."""
        s = self.sources
        return pipeline.Shape(s.inputs, s.params, s.points, s.hinges)

    @property
    def module(self) -> ModuleType:
        """The generated numpy module (in memory; loaded on first use, for a C evaluator too)."""
        if self._module is None:
            if self._row.is_module:
                self._module = self._loaded()
            else:
                s = self.sources
                self._module = pipeline.load("numpy", s.name, (s.numpy,), transient=True)
        return self._module

    @property
    def library(self) -> toolchain.Library:
        """The loaded C library (backend c)."""
        library = self._loaded()
        if not isinstance(library, toolchain.Library):
            raise ValueError(f"a {self.backend} evaluator has no C library")
        return library

    # -- parameters ------------------------------------------------------------------------------
    @property
    def defaults(self) -> dict[str, float]:
        """Every parameter's default, in file order."""
        return dict(self._parameters.PARAMETERS)

    def parameters(
        self, given: Mapping[str, float] | None = None, shifts: Mapping[str, float] | None = None
    ) -> list[float]:
        """Parameter values in file order: `given` ones, the others from their defaults; a
        shift is added to a parameter once its value is set, so the parameters whose defaults
        read it follow (the generated module's `parameters`)."""
        return [float(v) for v in self.parameter_values(given, shifts)]

    def parameter_values(
        self, given: Mapping[str, object] | None = None, shifts: Mapping[str, object] | None = None
    ) -> list[Any]:
        """As :meth:`parameters`, with values and shifts that may be arrays (many parameter sets
        at once): each value a float or an array."""
        values: list[Any] = self._parameters.parameters(given, shifts)
        return values

    def code(self, level: str | None, sensitivity: bool = False) -> str:
        """`level` checked against the generated ones (None: the generated module's
        DEFAULT_LEVEL, docs/levels.md "The default level"; with `sensitivity`, that level when
        it has sensitivities, else `exact` when generated, else the most faithful that has)."""
        if level is None:
            names = [
                n for n in self.levels if not sensitivity or level_table.get(n).sensitivity
            ] or list(self.levels)
            level = next(
                n
                for n in (self.sources.default_level, level_table.KINEMATIC_DEFAULT, names[-1])
                if n in names
            )
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
        return self._row.rows(self._loaded(), self.shape, x, params, self.code(level), False)[:2]

    def evaluate_grid(
        self,
        params: np.ndarray,
        x: np.ndarray,
        level: str | None = None,
        out: np.ndarray | None = None,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Every row of params (n_sets, n_params) at every row of x (n, n_inputs): (status
        (n_sets, n), out (n_sets, n, 6 n_points)) as :meth:`evaluate_rows` writes them; `out`
        may be given, to reuse (the C's single call fills it)."""
        return self._row.grid(self._loaded(), self.shape, params, x, self.code(level), out)

    def sensitivity_rows(
        self, x: np.ndarray, level: str | None = None, params: Sequence[float] | None = None
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """x (n, n_inputs) -> (status, values (n, 6 n_points), deviation and rigid
        derivatives (n, n_points, n_variables, 2)); variables: the parameters, then the
        inputs."""
        level = self.code(level, sensitivity=True)
        return self._row.sensitivity_rows(self._loaded(), self.shape, x, params, level)

    # -- the generated module's interface ---------------------------------------------------------
    def evaluate(
        self,
        inputs: Mapping[str, object],
        level: str | None = None,
        params: Mapping[str, float] | None = None,
        *,
        report: bool = True,
        buckling: bool = False,
    ) -> dict[str, Any]:
        """As the generated module's `evaluate` (docs/generated-code.md), in one C call. The
        numpy backend adds at `loaded` what the level reports: `report=False` leaves it out,
        `buckling=True` adds the buckling factor (its search: tens of Newton solves per
        configuration, so only when asked: docs/generated-code.md); the C backend's result holds the
        deviations and angles alone."""
        if self._row.is_module:
            options: dict[str, bool] = {}
            if buckling or not report:  # the signature read only off the module's defaults
                takes = inspect.signature(self.module.evaluate).parameters
                # a module without the loaded level's report has nothing to add or leave out
                asked = (("report", report), ("buckling", buckling))
                options = {k: on for k, on in asked if k in takes}
            result: dict[str, Any] = self.module.evaluate(
                inputs, self.code(level), params, **options
            )
            return result
        x, shape = self._rows(inputs)
        status, out, angles = self._row.rows(
            self._loaded(), self.shape, x, self.parameters(params), self.code(level), True
        )
        assert angles is not None  # asked for (the last argument)
        m = len(self.hinges)
        return {
            "points": {
                p: {
                    key: _shaped(out[:, 6 * i + 2 * j : 6 * i + 2 * j + 2], shape)
                    for j, key in enumerate(("rigid", "compliant", "deviation"))
                }
                for i, p in enumerate(self.points)
            },
            # 4: beyond the rigid reach, solved with NaN deviations (the numpy module's
            # "reference" False; docs/generated-code.md)
            "ok": ((status == 0) | (status == 4)).reshape(shape),
            "angles": {
                kind: {h: angles[:, off + a].reshape(shape) for a, h in enumerate(self.hinges)}
                for kind, off in (("rigid", 0), ("compliant", m))
            },
            "links": {},
            "reference": (status != 4).reshape(shape),
        }

    def sensitivity(
        self,
        inputs: Mapping[str, object],
        level: str | None = None,
        params: Mapping[str, float] | None = None,
    ) -> dict[str, dict[str, np.ndarray]]:
        """{P: {p: a}}: d(dx, dy)/dp, a of shape (2, *broadcast shape) (docs/sensitivity.md)."""
        full = self.sensitivity_full(inputs, level, params)
        return {p: full["deviation"][p]["params"] for p in self.points}

    def sensitivity_full(
        self,
        inputs: Mapping[str, object],
        level: str | None = None,
        params: Mapping[str, float] | None = None,
    ) -> dict[str, Any]:
        """As the generated module's `sensitivity_full`: the points, ok, and "deviation" and
        "rigid": {P: {"params": {p: a}, "inputs": {H: a}}}."""
        if not self.sources.sensitivity:
            raise ValueError("this evaluator was compiled without sensitivities")
        if self._row.is_module:
            level = self.code(level, sensitivity=True)
            result: dict[str, Any] = self.module.sensitivity_full(inputs, level, params)
            return result
        x, shape = self._rows(inputs)
        status, values, dev, rig = self._row.sensitivity_rows(
            self._loaded(),
            self.shape,
            x,
            self.parameters(params),
            self.code(level, sensitivity=True),
        )
        names = self.sources.params

        def table(data: np.ndarray, i: int) -> dict[str, dict[str, np.ndarray]]:
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
        if set(inputs) - set(self.sources.pruned) != set(self.inputs):
            raise ValueError(f"inputs must be exactly {self.inputs}, got {tuple(sorted(inputs))}")
        if not self.inputs:  # a structure: one configuration per call (its parameters')
            return np.zeros((1, 0)), ()
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
    from .configuration import check_fabricated_pose, fixed_angles

    pipeline.backend(backend)  # an unknown one is bad input before any work
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
    # nothing written, not even the plan or its texts (docs/generated-code.md)
    with plan_cache.memory_only():
        p = pipeline.plan_for(
            analysis,
            points=points,
            levels=levels,
            sensitivity=sensitivity,
            links=False,
            fixed=held,
            pruned_inputs=pruned,
        )
        source = Path(mech.path).name
        row = pipeline.backend(backend)
        numpy = pipeline.emit(p, "numpy", source)[0]
        texts = () if row.is_module else pipeline.emit(p, backend, source)
        # the levels the backend's code holds (the C's `loaded` takes uniform plates)
        held_levels = pipeline.backend_plan(p, backend)
        parameter_source = "" if row.is_module else numpy_backend.emit_parameters(p)
    return Compiled(
        Sources(
            name=mech.name,
            backend=backend,
            texts=texts,
            numpy=numpy,
            parameter_source=parameter_source,
            pruned=p.pruned_inputs,
            inputs=p.drives or p.inputs,
            params=tuple(q.name for q in p.parameters),
            points=p.shown_points,
            hinges=p.hinges,
            levels=tuple(lv.name for lv in held_levels.levels),
            sensitivity=p.sensitivity,
            default_level=held_levels.default_level,
        )
    )
