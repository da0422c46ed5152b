"""The `loaded` and `loaded_refined` levels in the generated numpy and C evaluators
(docs/physics.md) against the
sympy backend's 40-digit evaluation of the same derivation; tests/test_physics_reference.py
holds that derivation against the independent elastica reference.

Cases: the three examples (steel plates), a load on a point with plates narrower than five
thicknesses (the modulus's other branch), an open chain (no loops: the loads alone bend the
plates), the first-order variant (beam_column=False), float32, and --param overrides.
"""

from __future__ import annotations

import mechanisms as M
import numpy as np
import pytest
from conftest import EXAMPLES
from evaluators import INPUTS, Generated, generated, rel_err

import symkin
from symkin.codegen import pipeline
from symkin.codegen.plan import plan
from symkin.studies import evaluation

LOADED_FOUR_BAR = (
    M.without_stiffness(EXAMPLES / "four_bar.toml").replace(
        'length = "l"\n', 'length = "l"\nE = 70e9\nthickness = "l/8"\nwidth = "l/2"\n'
    )  # narrower than 5 t: E' = E
    + '[[load]]\npoint = "C"\nforce = [0.4, -1.5]\nmoment = 0.003\n'
)
LOADED_ARM = (
    M.SERIAL_ARM.replace(
        'length = "l"\n', 'length = "l"\nE = 210e9\nthickness = "l/10"\nwidth = 4e-3\n'
    )
    + '[[load]]\npoint = "T"\nforce = [1.0, -2.0]\n'
)


def loaded_case(key: str) -> Generated:
    text = {"loaded_four_bar": LOADED_FOUR_BAR, "loaded_arm": LOADED_ARM}.get(key)
    return generated(key) if text is None else _cached(key, text)


_CASES: dict[str, Generated] = {}


def _cached(key: str, text: str) -> Generated:
    if key not in _CASES:
        _CASES[key] = Generated(mech=symkin.loads(text, f"{key}.toml"))
    return _CASES[key]


CASES = {
    "four_bar": INPUTS["four_bar"],
    "six_bar": INPUTS["six_bar"],
    "nine_bar": INPUTS["nine_bar"],
    "loaded_four_bar": {"A0": "-0.15"},
    "loaded_arm": {"S": "0.3", "E": "-0.2"},
}


@pytest.mark.parametrize("level", ["loaded", "loaded_refined"])
@pytest.mark.parametrize("key", sorted(CASES))
@pytest.mark.parametrize("backend", ["numpy", "c"])
def test_loaded_matches_the_sympy_backend(key, backend, level):
    g = loaded_case(key)
    assert level in [lv.name for lv in g.plan.levels]
    want = symkin.evaluate(g.analysis, CASES[key], level)
    got = (g.run_numpy if backend == "numpy" else g.run_c)(CASES[key], level)
    for name, dev in got.items():
        assert rel_err(dev, want.points[name].deviation) <= 1e-12, name


@pytest.mark.parametrize("backend", ["numpy", "c"])
def test_refined_alone_solves_the_loops_it_needs(backend):
    """The nine-bar's point F is moved by no loop at the kinematic levels, yet loaded_refined
    needs the loaded closure solved for its statics: a plan with that level alone compiles and
    agrees with the sympy backend near the toggle position (O = 0.3)."""
    g = generated("nine_bar")
    p = plan(g.analysis, levels=["loaded_refined"])
    assert not p.needs_loops and "loaded_newton" in p.routines
    inputs = {"O": "0.3", "A": "0", "B": "0", "K": "0"}
    want = symkin.evaluate(g.analysis, inputs, "loaded_refined").points["F"].deviation
    got = symkin.compile(g.mech, backend, levels=["loaded_refined"], sensitivity=False).evaluate(
        {k: np.array([float(v)]) for k, v in inputs.items()}
    )["points"]["F"]["deviation"][:, 0]
    assert rel_err([float(v) for v in got], want) <= 1e-12


def test_the_modulus_branch_and_the_load_reach_the_generated_code():
    """The narrow plates' E' = E and the load on C matter: without them the answer differs."""
    g = loaded_case("loaded_four_bar")
    assert g.plan.loaded.passes == 2
    got = g.run_c(CASES["loaded_four_bar"], "loaded")["C"]
    wide = symkin.loads(LOADED_FOUR_BAR.replace('width = "l/2"', "width = 5e-3"), "w.toml")
    unloaded = symkin.loads(LOADED_FOUR_BAR.split("[[load]]")[0], "u.toml")
    for other in (wide, unloaded):
        want = symkin.evaluate(symkin.analyze(other), CASES["loaded_four_bar"], "loaded")
        assert rel_err(got, want.points["C"].deviation) > 1e-3


@pytest.mark.parametrize("backend", ["numpy", "c"])
def test_loaded_with_parameter_overrides(backend):
    g = generated("four_bar")
    overrides = {"l": "4e-3"}  # thickness l/10 follows; 4 mm plates stay wide (5 mm)
    want = symkin.evaluate(g.analysis, INPUTS["four_bar"], "loaded", params=overrides)
    got = (g.run_numpy if backend == "numpy" else g.run_c)(INPUTS["four_bar"], "loaded", overrides)
    assert rel_err(got["C"], want.points["C"].deviation) <= 1e-12


def test_first_order_variant_matches_its_derivation():
    an = symkin.analyze(symkin.loads(LOADED_FOUR_BAR, "lf.toml"))
    p, module = pipeline.build(an, "numpy", "test", levels=["loaded"], beam_column=False)
    assert p.loaded.passes == 1 and "loaded_q0" not in p.routines
    got = module.evaluate({"A0": -0.15}, "loaded")["points"]["C"]["deviation"]
    want = evaluation.loaded(an, {"A0": "-0.15"}, beam_column=False).points["C"].deviation
    assert rel_err([float(v) for v in got], want) <= 1e-12


def test_float32_loaded_stays_in_float32():
    g = generated("four_bar")
    module = pipeline.evaluator(g.plan, "numpy", "test", "float32")
    res = module.evaluate({"A0": np.linspace(0.02, 0.3, 15)}, "loaded")
    dev = res["points"]["C"]["deviation"]
    assert dev.dtype == np.float32 and res["ok"].all()
    want = g.numpy.evaluate({"A0": np.linspace(0.02, 0.3, 15)}, "loaded")["points"]["C"]
    err = np.hypot(*(dev - want["deviation"])) / np.hypot(*want["deviation"])
    assert err.max() < 1e-3


def test_a_file_without_stiffness_generates_no_loaded_level():
    mech = symkin.loads(M.without_stiffness(EXAMPLES / "four_bar.toml"), "plain.toml")
    assert [lv.name for lv in plan(symkin.analyze(mech)).levels] == [
        "paper",
        "first_order",
        "exact",
    ]
    with pytest.raises(symkin.InputError, match="no 'E'"):
        plan(symkin.analyze(mech), levels=["loaded"])


@pytest.mark.parametrize("key", ["four_bar", "six_bar", "loaded_arm"])
@pytest.mark.parametrize("backend", ["numpy", "c"])
def test_loaded_link_rotations_match_the_sympy_backend(key, backend):
    g = loaded_case(key)
    want = symkin.evaluate(g.analysis, CASES[key], "loaded").links
    got = symkin.evaluate(g.analysis, CASES[key], "loaded", backend=backend).links
    assert want.keys() == got.keys()
    for name, link in want.items():
        assert got[name].rigid == pytest.approx(link.rigid, rel=1e-14, abs=1e-16)
        assert got[name].deviation == pytest.approx(link.deviation, rel=1e-12, abs=1e-18), name


@pytest.mark.parametrize("key", ["WATT_II", "FIVE_BAR", "TRIAD_SIX_BAR"])
@pytest.mark.parametrize("backend", ["numpy", "c"])
def test_physical_levels_on_other_topologies(key, backend):
    """A `rigid` pin among the plates, two inputs, a triad solved by continuation (no dyads):
    both closed-form physical levels agree with the sympy backend's 40-digit evaluation."""
    text = getattr(M, key).replace(
        'length = "l"', 'length = "l"\nE = 210e9\nthickness = "l/10"\nwidth = 5e-3\nnu = 0.3\n', 1
    )
    mech = symkin.loads(text, f"{key}.toml")
    an = symkin.analyze(mech)
    inputs = {n: 0.1 * (i + 1) for i, n in enumerate(mech.inputs)}
    ev = symkin.compile(mech, backend, sensitivity=False)
    for level in ("loaded", "loaded_refined"):
        want = symkin.evaluate(an, {k: repr(v) for k, v in inputs.items()}, level)
        got = ev.evaluate({k: np.array([v]) for k, v in inputs.items()}, level)
        assert got["ok"].all()
        for name, point in want.points.items():
            assert (
                rel_err([float(v) for v in got["points"][name]["deviation"][:, 0]], point.deviation)
                <= 1e-12
            ), (level, name)


def test_refined_reports_the_angles_of_the_other_generated_levels():
    """The nine-bar's point F needs no loop: the refined statics solves the loaded closure for
    itself, but an evaluator without the links reports delta = 0 there as at every level that
    solves no loop, C and numpy alike (C left the statics' delta behind once), and both agree
    on the deviation with the sympy backend."""
    g = generated("nine_bar")
    inputs = {"O": 0.2, "A": 0.05, "B": -0.1, "K": 0.1}
    arrays = {k: np.array([v]) for k, v in inputs.items()}
    want = symkin.evaluate(g.analysis, inputs, "loaded_refined").points["F"].deviation
    for backend in ("numpy", "c"):
        res = symkin.compile(g.mech, backend, sensitivity=False).evaluate(arrays, "loaded_refined")
        assert res["ok"].all()
        for hinge, rigid in res["angles"]["rigid"].items():
            assert np.array_equal(res["angles"]["compliant"][hinge], rigid), (backend, hinge)
        assert rel_err([float(v) for v in res["points"]["F"]["deviation"][:, 0]], want) <= 1e-12
