"""The LaTeX report of the `loaded` level (docs/physics.md): what it prints is checked against
the independent physics, not against the code that printed it.

- The hinge forces the report prints in the chord's load, given the chord force of the
  independent elastica reference (tests/reference_physics.py), are every hinge's force there:
  the tree hinges' statics is exact at any pose.
- The stiffness table's EI is E'·b·t³/12 with E' = E/(1 − ν²), and its stretch and shear
  compliances EI/(EA l²) and EI/(κGA l²), computed here.
- The deviation figure's equilibrium points are the independent reference's deviations.
"""

from __future__ import annotations

import math

import mechanisms as M
import pytest
import sympy as sp
from conftest import EXAMPLES
from reference_physics import Equilibrium

import symkin
from symkin.codegen import pipeline
from symkin.codegen.plan import plan
from symkin.report import sections, sweeps
from symkin.studies.derive import generate

E, NU, WIDTH = 210e9, 0.3, 5e-3
LOADED = (EXAMPLES / "four_bar.toml").read_text() + (
    '\n[[load]]\npoint = "C"\nforce = [0.4, -1.5]\nmoment = 0.003\n'
    '\n[[load]]\nlink = "rocker"\nat = [0.09, 0.03]\nforce = [0.0, -0.5]\n'
)


def loads_of(mech):
    return [
        (
            ld.link,
            tuple(float(v) for v in ld.at),
            tuple(float(v) for v in ld.force),
            float(ld.moment),
        )
        for ld in mech.loads
    ]


def test_printed_hinge_forces_are_the_references_given_its_chord_force():
    mech = symkin.loads(LOADED, "four_bar.toml")
    statement = plan(symkin.analyze(mech), report=True).derivation
    ld = statement.loaded
    assert ld is not None and list(ld.chord_loads) == [4]
    reference = Equilibrium(mech, (E / (1 - NU**2), WIDTH, "l/10"), loads=loads_of(mech)).solve(
        {"A0": "0.2"}
    )
    forces = {
        name: [float(v) for v in reference["hinges"][name]["force"]]
        for name in statement.structure.hinges
    }
    nx, ny, _ = ld.chord_loads[4]
    chord = forces[statement.structure.hinges[3]]
    values = {nx: chord[0], ny: chord[1]}
    values.update({p.symbol: p.value for p in mech.parameters})
    largest = max(math.hypot(*f) for f in forces.values())
    assert len(ld.forces) == 4
    for a, force in ld.forces:
        want = forces[statement.structure.hinges[a - 1]]
        got = [float(sp.sympify(c).xreplace(values)) for c in force]
        assert math.hypot(got[0] - want[0], got[1] - want[1]) < 1e-9 * largest, (a, got, want)


def test_report_states_stiffness_loads_and_the_reduced_equilibrium():
    mech = symkin.loads(LOADED, "four_bar.toml")
    tex = generate(mech, emit=("latex",))["four_bar.tex"].decode()
    EI = E / (1 - NU**2) * WIDTH * 1e-4**3 / 12  # 9.615e-5 N m^2
    # t = l/10: EI/(EA l^2) = (t/l)^2/12; EI/(kGA l^2) = (t/l)^2/12 * 2(1 + nu)/((1 - nu^2) 5/6)
    stretch = 1e-2 / 12
    shear = stretch * 2 * (1 + NU) / ((1 - NU**2) * 5 / 6)
    row = next(line for line in tex.splitlines() if line.startswith("1 & A0 & $"))
    for value in (EI / 1e-5, stretch / 1e-4, shear / 1e-3):
        assert f"{value:.2f}" in row, (value, row)
    assert r"\subsection{Plate stiffness, loads and the level \emph{loaded}}" in tex
    assert r"$\delta_{2}$, $\delta_{3}$, $\delta_{4}$, $\mathbf{n}_{4}$, $\mu_{4}$." in tex
    for a in (1, 2, 3, 4):
        assert rf"\mathbf{{n}}_{{{a}}} &=" in tex and rf"\beta_{{{a}}} &=" in tex
    # the balance rows of the non-input tree hinges, the moment relation of the chord
    assert "not an input ($2$, $3$)" in tex and "not an input ($4$)" in tex
    assert "from equilibrium" in tex
    assert "statics" not in tex and r"\Lambda" not in tex


def test_without_stiffness_the_report_has_no_physics():
    text = M.without_stiffness(EXAMPLES / "four_bar.toml")
    tex = generate(symkin.loads(text, "four_bar.toml"), emit=("latex",))["four_bar.tex"].decode()
    assert "level \\emph{loaded}" not in tex and "from equilibrium" not in tex
    assert "equilibrium (elastica)" not in tex
    assert "Stress, actuation and model error" not in tex


@pytest.mark.parametrize("example", ["four_bar", "stephenson_six_bar"])
def test_figure_reference_points_are_the_elastica(example):
    """The report's sweep holds the `equilibrium` level at REFERENCE_SAMPLES inputs; two of them
    agree with the independent reference to 1e-8 relative, and `loaded` is within 1 % of it
    there (l/L <= 0.05)."""
    from symkin.studies.derive import physics_reference

    # the in-tree reference is the elastica: the example's plates made elastica (docs/physics.md)
    text = M.with_beam((EXAMPLES / f"{example}.toml").read_text(), "elastica")
    mech = symkin.loads(text, f"{example}.toml")
    an = symkin.analyze(mech)
    p, module = pipeline.build(an, "numpy", "x.toml", report=True)
    rep = sections.Report(p, "x.toml")
    spans = sweeps.sweep_spans(mech.inputs)
    runs, summary = sweeps.sweep(rep, module, spans, physics_reference(an))
    assert summary["physics"] and summary["reference_samples"] == sweeps.REFERENCE_SAMPLES
    h, data, _ = runs[0]
    at, ref = data.reference
    assert len(at) == sweeps.REFERENCE_SAMPLES
    reference = Equilibrium(mech, (E / (1 - NU**2), WIDTH, "l/10"))
    point = p.points[0]
    for k in (0, len(at) - 2):
        t = float(data.t[at[k]])
        want = [float(v) for v in reference.solve({h: repr(t)})["points"][point]["deviation"]]
        got = ref[point][:, k]
        assert math.hypot(got[0] - want[0], got[1] - want[1]) < 1e-8 * math.hypot(*want)
        loaded = data.deviation[point]["loaded"][:, at[k]]
        assert math.hypot(loaded[0] - want[0], loaded[1] - want[1]) < 1e-2 * math.hypot(*want)
