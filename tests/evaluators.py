"""Test support: the generated numpy and C evaluators of the test mechanisms, built once."""

from __future__ import annotations

import os
import shutil

import mechanisms as M
import mpmath
import pytest
from conftest import EXAMPLES

import symkin
from symkin.codegen import pipeline
from symkin.core import backends, levels
from symkin.studies.configuration import parameter_values

SOURCES = {
    "four_bar": EXAMPLES / "four_bar.toml",
    "six_bar": EXAMPLES / "stephenson_six_bar.toml",
    "nine_bar": EXAMPLES / "nine_bar_platform.toml",
    "serial_arm": M.SERIAL_ARM,
    "five_bar": M.FIVE_BAR,
    "watt_ii": M.WATT_II,
    "triad": M.TRIAD_SIX_BAR,
    "non_grashof": M.NON_GRASHOF,
}
INPUTS = {
    "four_bar": {"A0": "0.2"},
    "six_bar": {"O_A": "0.2"},
    "nine_bar": {"O": "0.05", "A": "0.03", "B": "-0.02", "K": "0.04"},
    "serial_arm": {"S": "0.3", "E": "-0.2"},
    "five_bar": {"O1": "0.15", "O2": "-0.1"},
    "watt_ii": {"O1": "0.25"},
    "triad": {"O1": "0.1"},
    "non_grashof": {"A0": "0.3"},
}


#: Every backend and the generated-code ones, drawn from the backend table (symkin.core.backends;
#: tests/test_backends.py pins it): a new backend runs through every test that takes these.
BACKENDS = backends.NAMES
GENERATED = backends.GENERATED


def backends_with(**wanted: object) -> tuple[str, ...]:
    """The backends with the capabilities `wanted` (symkin.core.backends.having), e.g.
    ``backends_with(generated=True, force_sensitivities="loaded")``."""
    return backends.having(**wanted)


def require(backend: str) -> None:
    """What `backend` needs on this machine: a C compiler where it compiles (require_compiler)."""
    if backends.get(backend).compiler:
        require_compiler()


def require_compiler():
    if shutil.which(os.environ.get("CC", "cc")) is None:
        if os.environ.get("CI") == "true":
            pytest.fail("no C compiler on the CI machine: .ci/run must install gcc")
        pytest.skip("no C compiler")


#: The kinematic levels: the plan `evaluate` derives for one of them leaves the physical ones out.
KINEMATIC = ("paper", "first_order", "exact")


class Generated:
    """A mechanism with its analysis, numpy module and compiled C library."""

    def __init__(self, key=None, mech=None, sensitivity=True, levels=None):
        """`sensitivity` False and `levels` (names) derive less where a test needs less:
        symkin.evaluate finds this plan then (pipeline.plan_covering)."""
        if mech is None:
            source = SOURCES[key]
            mech = symkin.load(source) if not isinstance(source, str) else symkin.loads(source)
        self.mech = mech
        self.analysis = symkin.analyze(self.mech)
        # emitted for the file's own path, as evaluate's are: one compile serves both
        self.plan, self.numpy = pipeline.build(
            self.analysis, "numpy", self.mech.path, sensitivity=sensitivity, levels=levels
        )
        self._lib = None
        self._evaluators: dict[str, object] = {}

    def evaluator(self, backend):
        """The plan's evaluator from generated-code `backend` (its registry row loads it)."""
        require(backend)
        if backend not in self._evaluators:
            self._evaluators[backend] = pipeline.evaluator(
                self.plan, backend, self.mech.path, links=False
            )
        return self._evaluators[backend]

    def pose(self, backend, inputs, level, overrides=None):
        """(status, the points' deviations) through generated-code `backend`: its registry
        row's pose (pipeline.Backend.pose), the layout every backend answers in."""
        shape = pipeline.Shape.of(self.plan, links=False)
        x = [float(inputs[n]) for n in shape.inputs]
        ev, params = self.evaluator(backend), self.params(overrides)
        status, out, _, _ = pipeline.backend(backend).pose(ev, shape, x, params, level)
        return status, {n: (out[6 * i + 4], out[6 * i + 5]) for i, n in enumerate(shape.points)}

    def run(self, backend, inputs, level, overrides=None):
        """The points' deviations through generated-code `backend` (solved: status 0)."""
        status, deviations = self.pose(backend, inputs, level, overrides)
        assert status == 0, backend
        return deviations

    @property
    def lib(self):
        if self._lib is None:
            require_compiler()
            self._lib = pipeline.evaluator(self.plan, "c", self.mech.path, links=False)
        return self._lib

    def params(self, overrides=None):
        values = parameter_values(self.mech, overrides)
        return [float(mpmath.mpf(str(values[s].evalf(30)))) for s in self.analysis.params]

    def run_numpy(self, inputs, level, overrides=None):
        p = dict(zip((q.name for q in self.mech.parameters), self.params(overrides)))
        res = self.numpy.evaluate({k: float(v) for k, v in inputs.items()}, level, p)
        return {n: tuple(float(v) for v in res["points"][n]["deviation"]) for n in self.plan.points}

    def run_c(self, inputs, level, overrides=None):
        x = [float(inputs[self.analysis.kin.hinges[a].name]) for a in self.analysis.kin.inputs]
        status, out, _ = self.lib.evaluate(x, self.params(overrides), levels.get(level).code)
        assert status == 0
        return {n: (out[6 * i + 4], out[6 * i + 5]) for i, n in enumerate(self.plan.points)}


_CACHE: dict[str, Generated] = {}


def generated(key) -> Generated:
    if key not in _CACHE:
        _CACHE[key] = Generated(key)
    return _CACHE[key]


def rel_err(got, want) -> float:
    with mpmath.workdps(50):
        diff = mpmath.sqrt(sum((mpmath.mpf(g) - mpmath.mpf(w)) ** 2 for g, w in zip(got, want)))
        return float(diff / mpmath.sqrt(sum(mpmath.mpf(w) ** 2 for w in want)))
