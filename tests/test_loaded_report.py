"""The LaTeX report of the `loaded` level (docs/physics.md): what it prints is checked against
the independent physics, not against the code that printed it.

- The statics the report states (the generalized forces Q⁰, the hinge forces in the multipliers
  Λ, A from the first-order level), solved at the rigid pose of the independent kinematic solver
  (tests/reference_solver.py), give every plate's end force within 0.5 % of the independent
  elastica reference (tests/reference_physics.py): the printed equations are the physics, to
  first order.
- The stiffness table's EI is E'·b·t³/12 with E' = E/(1 − ν²), computed here.
- The deviation figure's equilibrium points are the independent reference's deviations.
"""

from __future__ import annotations

import math

import mechanisms as M
import numpy as np
import pytest
import sympy as sp
from conftest import EXAMPLES
from reference_physics import Equilibrium
from reference_solver import Reference

import symkin
from symkin.codegen import pipeline
from symkin.codegen.backends.latex import report as latex_report
from symkin.codegen.plan import plan
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


def test_printed_statics_give_the_plate_forces_of_the_elastica():
    mech = symkin.loads(LOADED, "four_bar.toml")
    statement = plan(symkin.analyze(mech), report=True).derivation
    ld = statement.loaded
    assert ld is not None and ld.beam_column
    l = 1e-3
    EI = E / (1 - NU**2) * WIDTH * (l / 10) ** 3 / 12
    inputs = {"A0": "0.2"}
    angles = Reference(mech).solve(inputs, model_override="rigid")["angles"]
    values = {
        theta: sp.Float(str(angles[statement.structure.hinges[a - 1]]), 30)
        for a, theta in statement.theta.items()
    }
    values.update(dict.fromkeys(ld.springs.values(), EI / l))
    values.update({p.symbol: p.value for p in mech.parameters})
    A = np.array(statement.linear[0].xreplace(values).evalf(30).tolist(), dtype=float)
    Q = np.array([float(q.xreplace(values).evalf(30)) for _, q in ld.forces])
    multipliers = np.linalg.solve(A.T, Q)
    values.update(dict(zip(ld.multipliers, multipliers)))
    reference = Equilibrium(mech, (E / (1 - NU**2), WIDTH, "l/10"), loads=loads_of(mech)).solve(
        inputs
    )
    for a, force, _ in ld.hinge_forces:
        name = statement.structure.hinges[a - 1]
        want = [float(v) for v in reference["hinges"][name]["force"]]
        got = [float(sp.sympify(c).xreplace(values)) for c in force]
        assert math.hypot(got[0] - want[0], got[1] - want[1]) < 5e-3 * math.hypot(*want), (
            name,
            got,
            want,
        )


def test_report_states_stiffness_loads_and_statics():
    mech = symkin.loads(LOADED, "four_bar.toml")
    tex = generate(mech, emit=("latex",))["four_bar.tex"].decode()
    EI = E / (1 - NU**2) * WIDTH * 1e-4**3 / 12  # 9.615e-5 N m^2
    assert f"{EI / 1e-5:.2f}\\times 10^{{-5}}" in tex
    assert r"\subsection{Plate stiffness, loads and the level \emph{loaded}}" in tex
    for a in (2, 3, 4):  # the non-input hinges
        assert rf"Q^{{0}}_{{{a}}} &=" in tex
    for a in (1, 2, 3, 4):
        assert rf"\mathbf{{n}}_{{{a}}} &=" in tex
    # the rocker's load: its moment about B0 is (0.015 sin + 0.005 cos) theta_3, written out
    assert r"0.015 \sin {\theta_{3}} + 0.005 \cos {\theta_{3}}" in tex
    assert "from equilibrium" in tex


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
    rep = latex_report.Report(p, "x.toml")
    spans = latex_report.sweep_spans(mech.inputs)
    runs, summary = latex_report.sweep(rep, module, spans, physics_reference(an))
    assert summary["physics"] and summary["reference_samples"] == latex_report.REFERENCE_SAMPLES
    h, data, _ = runs[0]
    at, ref = data.reference
    assert len(at) == latex_report.REFERENCE_SAMPLES
    reference = Equilibrium(mech, (E / (1 - NU**2), WIDTH, "l/10"))
    point = p.points[0]
    for k in (0, len(at) - 2):
        t = float(data.t[at[k]])
        want = [float(v) for v in reference.solve({h: repr(t)})["points"][point]["deviation"]]
        got = ref[point][:, k]
        assert math.hypot(got[0] - want[0], got[1] - want[1]) < 1e-8 * math.hypot(*want)
        loaded = data.deviation[point]["loaded"][:, at[k]]
        assert math.hypot(loaded[0] - want[0], loaded[1] - want[1]) < 1e-2 * math.hypot(*want)
