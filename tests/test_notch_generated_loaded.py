"""The generated numpy evaluator's `loaded` level on notch hinges (docs/physics.md, "Notch hinges
at `loaded`"; docs/levels.md): every notch's relation emitted with its section's terms folded in
as numbers, its sway poles, its stress from its section's shot times K_t, the buckling search and
the sensitivities, against references that are not the generated code:

- the `sympy` backend's `loaded` (the Python level, lambdified in 40-digit mpmath): every
  point's deviation, its 3×3 stiffness and every notch's stress to 1e-8 relative, on a four-bar
  and a parallelogram with circular notches (t/R = 0.1), the notch lever of examples/ (a piezo
  stroke behind a spring) and four-bars with elliptical and corner-filleted notches, with and
  without a dead load;
- `equilibrium` (the variable-section shot, Python): every notch's stress within 1 %;
- the Python level's compliance at the dead load's point: the deviation's sensitivity by the
  load's size is that compliance's column (the load acts there).

The C evaluators' `loaded` takes uniform plates: on a notch file it exits 2 naming the hinge,
their default level stays `exact` and their code holds the kinematic levels (generated/ for the
notch lever, tests/test_generated.py).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from cli_runs import symkin_cli
from conftest import EXAMPLES, ROOT

import symkin
from symkin.codegen import pipeline
from symkin.core import levels
from symkin.core.errors import InputError

ZOO = ROOT / "tests" / "mechanisms"

#: name -> (file, input, its values, the dead load's parameter and size or None)
FILES = {
    "notch_four_bar_si": (ZOO / "notch_four_bar_si.toml", "A0", 0.05, ("F", 2.0)),
    "notch_parallelogram_si": (ZOO / "notch_parallelogram_si.toml", "F1", 0.03, ("F", 5.0)),
    "notch_lever": (EXAMPLES / "notch_lever.toml", "piezo", 0.02, None),
    "notch_four_bar_elliptical": (ZOO / "notch_four_bar_elliptical.toml", "A0", 0.05, ("F", 2.0)),
    "notch_four_bar_filleted": (ZOO / "notch_four_bar_filleted.toml", "A0", 0.02, ("F", 2.0)),
}
#: (file, with the dead load)
CASES = [(name, False) for name in FILES] + [
    (name, True) for name, row in FILES.items() if row[3] is not None
]
#: the generated numpy against the 40-digit Python level (the relation's terms are 16-digit
#: floats there and here; the stress grid is the Python level's own floats)
AGREE = 1e-8


@pytest.fixture(scope="module")
def built():
    """Each file's analysis and numpy module (with sensitivities), derived on first use."""
    cache: dict = {}

    def get(name: str):
        if name not in cache:
            an = symkin.analyze(symkin.load(FILES[name][0]))
            _, module = pipeline.build(an, "numpy", "ngl_" + name)
            cache[name] = an, module
        return cache[name]

    return get


@pytest.fixture(scope="module")
def reference():
    """The sympy backend's `loaded` (40 digits) per case, evaluated on first use."""
    cache: dict = {}

    def get(name: str, loaded: bool, built):
        key = (name, loaded)
        if key not in cache:
            an, _ = built(name)
            _, inp, value, load = FILES[name]
            params = {load[0]: load[1]} if loaded else None
            cache[key] = symkin.evaluate(
                an, {inp: value}, level="loaded", params=params, backend="sympy"
            )
        return cache[key]

    return get


def _generated(module, name: str, loaded: bool) -> dict:
    _, inp, value, load = FILES[name]
    params = {load[0]: load[1]} if loaded else None
    out = module.evaluate({inp: np.array([value])}, "loaded", params=params, buckling=True)
    assert bool(np.all(out["ok"])), name
    return out


@pytest.mark.parametrize(
    ("name", "loaded"), CASES, ids=[f"{n}-{'F' if d else '0'}" for n, d in CASES]
)
def test_numpy_loaded_on_notches_against_the_python_level(built, reference, name, loaded):
    """Deviation, point stiffness (each row against its largest entry) and notch stress of the
    generated numpy module against the sympy backend's `loaded` to 1e-8 relative."""
    _, module = built(name)
    ref = reference(name, loaded, built)
    got = _generated(module, name, loaded)
    assert ref.level == "loaded"
    for point, p in ref.points.items():
        dev = np.array(
            [got["points"][point]["deviation"][0][0], got["points"][point]["deviation"][1][0]]
        )
        size = math.hypot(*p.deviation)
        assert size > 0
        assert math.dist(dev, p.deviation) <= AGREE * size, (name, point, dev, p.deviation)
    for point, k in ref.stiffness.items():
        if k is None:
            continue
        mine = np.asarray(got["stiffness"][point])[:, :, 0]
        for i, row in enumerate(np.asarray(k)):
            scale = np.max(np.abs(row))
            assert np.max(np.abs(mine[i] - row)) <= AGREE * scale, (name, point, i)
    for hinge, plate in ref.plates.items():
        stress = float(got["plates"][hinge]["stress"][0])
        assert stress == pytest.approx(plate.stress, rel=AGREE), (name, hinge)
        # where: a node of the grid (two nodes by the neck may nearly tie)
        section = float(got["plates"][hinge]["section"][0])
        assert section == pytest.approx(plate.section, abs=0.01), (name, hinge)
    if loaded:
        assert float(got["buckling"][0]) == ref.buckling or float(got["buckling"][0]) == (
            pytest.approx(ref.buckling, rel=1e-6)
        )


@pytest.mark.parametrize("name", ["notch_four_bar_si", "notch_four_bar_filleted"])
def test_numpy_notch_stress_within_one_percent_of_equilibrium(built, name):
    """Every notch's stress (K_t times the largest strain of its section's shot under the
    level's end loads) within 1 % of `equilibrium`'s, under the dead load."""
    an, module = built(name)
    _, inp, value, load = FILES[name]
    got = _generated(module, name, True)
    ref = symkin.evaluate(an, {inp: value}, level="equilibrium", params={load[0]: load[1]})
    for hinge, plate in ref.plates.items():
        stress = float(got["plates"][hinge]["stress"][0])
        assert stress == pytest.approx(plate.stress, rel=0.01), (name, hinge)


def test_numpy_sensitivity_by_the_dead_load_is_the_compliance(built, reference):
    """The deviation of C by the dead load F (acting at C along −y) is −(the Python level's
    compliance at C)'s y column: d(dx, dy)/dF = −(C_xy, C_yy)."""
    name = "notch_four_bar_si"
    _, module = built(name)
    ref = reference(name, True, built)
    _, inp, value, load = FILES[name]
    sens = module.sensitivity({inp: np.array([value])}, "loaded", params={load[0]: load[1]})
    got = np.array([sens["C"]["F"][0][0], sens["C"]["F"][1][0]])
    c = np.asarray(ref.compliance["C"])
    want = -c[:2, 1]
    assert np.max(np.abs(got - want)) <= 1e-7 * np.max(np.abs(want)), (got, want)


# -- the C evaluators and the default level -----------------------------------------------------


def test_the_c_loaded_refuses_a_notch_naming_it():
    """The C runtime's `loaded` takes uniform plates: asked for it, exit 2 naming the hinge and
    the backends that take notches."""
    path = ZOO / "notch_four_bar_si.toml"
    an = symkin.analyze(symkin.load(path))
    with pytest.raises(InputError, match="uniform plates") as err:
        symkin.evaluate(an, {"A0": 0.02}, level="loaded", backend="c")
    assert err.value.exit_code == 2 and "'A0'" in str(err.value)
    assert "--backend numpy" in str(err.value)


def test_a_notch_read_from_a_parameter_is_refused_by_the_generated_loaded(tmp_path):
    """The generated `loaded` folds a notch's section in as numbers: a notch whose radius and
    thickness are a parameter's expressions (its shape ratios numbers, as the file format asks)
    exits 2 naming the hinge and the parameter."""
    text = (ZOO / "notch_four_bar_si.toml").read_text()
    text = text.replace("F = 0\n", "F = 0\nR = 1e-3\n").replace("radius = 1e-3", 'radius = "R"')
    text = text.replace("thickness = 1e-4", 'thickness = "R/10"')
    path = tmp_path / "notch_radius.toml"
    path.write_text(text)
    an = symkin.analyze(symkin.load(path))
    with pytest.raises(InputError, match="parameter") as err:
        pipeline.build(an, "numpy", "ngl_radius", sensitivity=False, levels=("loaded",))
    assert err.value.exit_code == 2 and "'A0'" in str(err.value) and "R" in str(err.value)


def test_the_default_level_of_a_notch_file_in_generated_code():
    """numpy's `loaded` takes notches: a notch file's default there is `loaded`; the C's is
    `exact`, its reason naming the hinge, its profile and the backends that take it."""
    mech = symkin.load(EXAMPLES / "notch_lever.toml")
    assert levels.default_for(mech, generated="numpy").name == "loaded"
    c = levels.default_for(mech, generated="c")
    assert c.name == "exact" and c.default
    assert "'O' is circular" in c.reason and "numpy" in c.reason


def test_eval_tolerance_and_sweep_default_levels_on_a_notch_file():
    """numpy's `loaded` is the default of `eval --backend numpy`, `tolerance` (which runs numpy on
    a notch file) and `sweep --backend numpy`; the C backend's is `exact`."""
    file = str(EXAMPLES / "notch_lever.toml")
    run = symkin_cli("eval", file, "--input", "piezo=0.02", "--backend", "numpy")
    assert run.returncode == 0, run.stderr
    assert run.stdout.splitlines()[0].startswith("level: loaded (default"), run.stdout
    run = symkin_cli("eval", file, "--input", "piezo=0.02", "--backend", "c")
    assert run.returncode == 0, run.stderr
    assert run.stdout.splitlines()[0].startswith("level: exact (default"), run.stdout
    run = symkin_cli("tolerance", file, "--vary", "k=±1%", "--input", "piezo=0.02")
    assert run.returncode == 0, run.stderr
    assert run.stdout.splitlines()[0].startswith("level: loaded (default"), run.stdout
    assert "(numpy)" in run.stdout, run.stdout
    sweep = ("--vary", "k=±1%", "--input", "piezo=0.01:0.02:2", "--samples", "4")
    sweep += ("--scheduler", "sync")
    for backend, level in (("numpy", "loaded"), ("c", "exact")):
        run = symkin_cli("sweep", file, *sweep, "--backend", backend)
        assert run.returncode == 0, run.stderr
        assert run.stdout.splitlines()[0].startswith(f"level: {level} (default"), run.stdout


def test_numpy_buckling_factor_on_notches_against_the_python_level(built):
    """A load the notches cannot carry ten times (the parallelogram's stage pushed by 300 N): the
    generated search's buckling factor against the sympy backend's `loaded` (the same search,
    located to its buckling_locate: asked 1e-6 relative; measured 6.7674 in both)."""
    an, module = built("notch_parallelogram_si")
    inputs, params = {"F1": 0.03}, {"F": 300.0}
    ref = symkin.evaluate(an, inputs, level="loaded", params=params, backend="sympy")
    assert ref.buckling is not None and 1 < ref.buckling < 10
    got = module.evaluate({"F1": np.array([0.03])}, "loaded", params=params, buckling=True)
    assert float(got["buckling"][0]) == pytest.approx(ref.buckling, rel=1e-6)
