"""The C evaluator's <name>_modes (docs/generated-code.md, "Natural frequencies in generated
code"; templates/c/modes.c: the compliance as the loaded report's, a cyclic Jacobi eigen-solve)
against the generated numpy module's modes() (numpy.linalg.eigh, another eigen-solver) and the
formulas of tests/test_modes.py and tests/test_modes_spring.py: the oblique spring on a pushed,
preloaded stage with inertia (actuators, a spring), two stacked stages on force actuators (two
massive links, rotations without inertia), the lumped parallelogram held at its input hinge (no
actuators: the pose's path), and a load beyond buckling (return 2, NaN)."""

from __future__ import annotations

import ctypes
import math

import numpy as np
import pytest
from evaluators import require_compiler
from test_modes import EI, PARALLELOGRAM, leaf_stiffness, stacked
from test_modes_spring import SIDEWAYS, hz, oblique

import symkin
from symkin.codegen import pipeline
from symkin.graph.structure import build
from symkin.kinematics.analysis import Analysis

AGREE = 1e-9  # C against numpy: frequencies relative, shapes relative to max(1, |entry|)


class CModes:
    """A file's C library and numpy module, <name>_modes called through ctypes."""

    def __init__(self, text: str, name: str):
        require_compiler()
        mech = symkin.loads(text, f"{name}.toml")
        self.plan = pipeline.plan_covering(
            Analysis(build(mech)), "loaded", levels=["loaded"], sensitivity=False
        )
        self.lib = pipeline.evaluator(self.plan, "c", "test", links=False).lib
        self.numpy = pipeline.evaluator(self.plan, "numpy", "test")
        self.defaults = {p.name: float(p.value) for p in mech.parameters}
        md = self.plan.loaded.modes
        self.links, self.points = md.links, md.points
        self.n = 3 * len(self.links)

    def __call__(self, inputs: dict[str, float], params: dict[str, float] | None = None):
        """(return code, frequencies, {link: (modes, 3)}, {point: (modes, 2)})."""
        size = self.n + 2 * len(self.points)
        out = (ctypes.c_double * (self.n * (1 + size)))()
        names = self.plan.drives if self.plan.actuators else self.plan.inputs
        x = (ctypes.c_double * len(names))(*(inputs[h] for h in names))
        values = self.defaults | (params or {})
        p = (ctypes.c_double * max(1, len(values)))(*values.values())
        rc = getattr(self.lib, f"{self.plan.name}_modes")(x, p, out)
        v = np.array(list(out))
        shapes = v[self.n :].reshape(self.n, size)
        links = {n: shapes[:, 3 * k : 3 * k + 3] for k, n in enumerate(self.links)}
        points = {
            n: shapes[:, self.n + 2 * k : self.n + 2 * k + 2] for k, n in enumerate(self.points)
        }
        return rc, v[: self.n], links, points

    def agree(self, inputs, params=None):
        """Every frequency and shape entry against the numpy module's modes() (all of them:
        the infinite ones too, their shapes NaN in both); the C answer."""
        rc, freq, links, points = self(inputs, params)
        assert rc == 0
        ref = self.numpy.modes(inputs, params=params, count=self.n)
        assert bool(ref["ok"])
        want = np.asarray(ref["frequencies"], float)
        assert np.array_equal(np.isinf(freq), np.isinf(want))
        finite = np.isfinite(want)
        assert freq[finite] == pytest.approx(want[finite], rel=AGREE)
        for got, reference in ((links, ref["links"]), (points, ref["points"])):
            for name, shape in got.items():
                expected = np.asarray(reference[name], float)
                assert np.isnan(shape[~finite]).all() and np.isnan(expected[~finite]).all()
                scale = np.maximum(1, np.abs(expected[finite]))
                assert np.max(np.abs(shape[finite] - expected[finite]) / scale) <= AGREE, name
        return freq, links, points


@pytest.fixture(scope="module")
def sprung():
    return CModes(oblique("stroke"), "sprung")


def test_an_oblique_spring_on_a_preloaded_stage(sprung):
    for push, k, load in ((0.2, 300.0, 3.0), (-0.1, 0.5, 0.0), (0.0, 30.0, 1.0)):
        freq, links, _ = sprung.agree({"push": push}, {"ks": k, "P": load})
        assert np.isfinite(freq).all() and np.all(np.diff(freq) > 0)
        assert np.max(np.abs(links["stage"][0, :2])) == 1.0  # normalised as the command's
    # the third mode, a pure rotation at rest and unloaded, normalised to +1 rad
    freq, links, _ = sprung.agree({"push": 0.0}, {"ks": 1e-6, "P": 0.0})
    assert links["stage"][2, 2] == 1.0


def test_the_spring_beside_the_legs():
    sideways = CModes(SIDEWAYS, "sideways")
    legs = 2 * leaf_stiffness()
    for k in (0.3, 300.0):
        freq, _, _ = sideways.agree({"push": 0.0}, {"ks": k})
        assert freq[0] == pytest.approx(hz(legs + 1e3 * k, 0.1), rel=AGREE)
        assert math.isinf(freq[2])  # the stage's rotation: no inertia


def test_two_stacked_stages_and_their_chain():
    chain = CModes(stacked(), "stacked")
    freq, _, _ = chain.agree({"p1": 0.0, "p2": 0.2})
    assert np.isfinite(freq[:4]).all() and np.isinf(freq[4:]).all()
    freq, _, _ = chain.agree({"p1": 0.0, "p2": 0.0})
    m1, m2, k = 0.3, 0.1, 2 * leaf_stiffness()
    a, b, c = m1 * m2, -(2 * k * m2 + k * m1), k * k
    for s, f in zip((-1, 1), freq[:2]):
        w2 = (-b + s * math.sqrt(b * b - 4 * a * c)) / (2 * a)
        assert f == pytest.approx(math.sqrt(w2) / (2 * math.pi), rel=1e-4)


def test_an_input_hinge_held_and_a_load_beyond_buckling():
    text = PARALLELOGRAM.replace(
        '[[link]]\nname = "stage"\n', '[[link]]\nname = "stage"\nmass = 0.1\ncentre = [15, 40]\n'
    )
    held = CModes(text, "held")
    for angle in (0.0, 0.05):
        held.agree({"F1": angle})
    # the oblique stage past its legs' Euler load: no frequencies, as modes()' ok False
    stage = CModes(oblique("stroke"), "beyond")
    beyond = 1.2 * 2 * math.pi**2 * EI / (40e-3) ** 2
    rc, freq, links, _ = stage({"push": 0.0}, {"ks": 1e-6, "P": beyond})
    ref = stage.numpy.modes({"push": 0.0}, params={"ks": 1e-6, "P": beyond}, count=3)
    assert rc == 2 and not bool(ref["ok"])
    assert np.isnan(freq).all() and np.isnan(links["stage"]).all()
