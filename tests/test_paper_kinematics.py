"""The paper's structural results, symbolically: (4.7) for the three examples and (4.8) at level
`paper` (with erratum 2: the four-bar's coupler point gets Δz_1 + Δz_2, not Δz_1)."""

from __future__ import annotations

import pytest
import sympy as sp
from conftest import EXAMPLES

import symkin
from symkin.kinematics.positions import c_symbol as c
from symkin.kinematics.positions import paper_positions
from symkin.kinematics.positions import z_symbol as z


def structure(name):
    return symkin.structure(symkin.load(EXAMPLES / f"{name}.toml"))


# R_i as printed in Hasan & Lilov (2008), section 4, typed in from the paper.
PAPER_R = {
    "four_bar": [
        z(1) + c(0, 1) - c(1, 1),
        z(1) + z(2) + c(0, 1) + c(1, 2) - c(1, 1) - c(2, 2),
        z(3) + c(0, 3) - c(3, 3),
    ],
    "stephenson_six_bar": [
        c(0, 1) + z(1) - c(1, 1),
        z(1) + z(2) + c(0, 1) - c(1, 1) + c(1, 2) - c(2, 2),
        c(0, 3) + z(3) - c(3, 3),
        z(3) + z(4) - c(3, 3) + c(0, 3) + c(3, 4) - c(4, 4),
        z(3) + z(5) + c(0, 3) + c(3, 5) - c(3, 3) - c(5, 5),
    ],
    "nine_bar_platform": [
        z(1) + c(0, 1) - c(1, 1),
        z(1) + z(2) + c(0, 1) + c(1, 2) - c(1, 1) - c(2, 2),
        z(1) + z(2) + z(3) + c(0, 1) + c(1, 2) + c(2, 3) - c(1, 1) - c(2, 2) - c(3, 3),
        z(1)
        + z(2)
        + z(3)
        + z(4)
        + c(0, 1)
        + c(1, 2)
        + c(2, 3)
        + c(3, 4)
        - c(1, 1)
        - c(2, 2)
        - c(3, 3)
        - c(4, 4),
        z(1)
        + z(2)
        + z(3)
        + z(4)
        + z(5)
        + c(0, 1)
        + c(1, 2)
        + c(2, 3)
        + c(3, 4)
        + c(4, 5)
        - c(1, 1)
        - c(2, 2)
        - c(3, 3)
        - c(4, 4)
        - c(5, 5),
        # The paper's R_6 is garbled ("+ c_36 - (c_6 c_ii)"); (4.7) gives c_56 and -Σ c_ii.
        z(1)
        + z(2)
        + z(3)
        + z(4)
        + z(5)
        + z(6)
        + c(0, 1)
        + c(1, 2)
        + c(2, 3)
        + c(3, 4)
        + c(4, 5)
        + c(5, 6)
        - c(1, 1)
        - c(2, 2)
        - c(3, 3)
        - c(4, 4)
        - c(5, 5)
        - c(6, 6),
        z(1)
        + z(2)
        + z(3)
        + z(7)
        + c(0, 1)
        + c(1, 2)
        + c(2, 3)
        + c(3, 7)
        - c(1, 1)
        - c(2, 2)
        - c(3, 3)
        - c(7, 7),
        z(1)
        + z(2)
        + z(3)
        + z(7)
        + z(8)
        + c(0, 1)
        + c(1, 2)
        + c(2, 3)
        + c(3, 7)
        + c(7, 8)
        - c(1, 1)
        - c(2, 2)
        - c(3, 3)
        - c(7, 7)
        - c(8, 8),
    ],
}


@pytest.mark.parametrize("name", sorted(PAPER_R))
def test_link_positions_4_7_match_the_paper(name):
    R = paper_positions(structure(name))
    assert len(R) == len(PAPER_R[name])
    for got, want in zip(R, PAPER_R[name]):
        assert sp.expand(got - want) == 0


@pytest.mark.parametrize(
    "name, point", [("four_bar", "C"), ("stephenson_six_bar", "D"), ("nine_bar_platform", "F")]
)
def test_paper_level_deviation_is_dz1_plus_dz2(name, point):
    """ΔR of the characteristic point on link 2 = Δz_1 + Δz_2 rotated into the absolute frame."""
    from symkin.kinematics.analysis import Analysis

    an = Analysis(structure(name))
    kin = an.kin
    got = an.point_deviation(point, "paper")
    h1, h2 = kin.hinges[1], kin.hinges[2]
    want = [
        a + b for a, b in zip(h1.delta_z(kin.theta[1], 0), h2.delta_z(kin.theta[2], kin.phi(1)))
    ]
    for g, w in zip(got, want):
        assert sp.simplify(g - w) == 0
    # Δz_a (3.3) itself: the plate deviation, rotated by the reference link's angle.
    dz2 = h2.delta_z(kin.theta[2], kin.theta[1])
    local = (
        h2.df.subs(symkin.model.hinges.THETA, kin.theta[2]),
        h2.dg.subs(symkin.model.hinges.THETA, kin.theta[2]),
    )
    rotated_u = (sp.cos(h2.angle + kin.theta[1]), sp.sin(h2.angle + kin.theta[1]))
    normal = (-rotated_u[1], rotated_u[0])
    for k in range(2):
        assert (
            sp.simplify(sp.expand_trig(dz2[k] - (local[0] * rotated_u[k] + local[1] * normal[k])))
            == 0
        )


@pytest.mark.parametrize("name", sorted(PAPER_R))
def test_plate_data_and_hinge_vectors_in_the_as_fabricated_pose(name):
    """With every θ = 0, z_a (3.2) of each model equals c_{i-(a)a} - c_{i+(a)a}, the plate."""
    from symkin.kinematics.analysis import Analysis

    an = Analysis(structure(name))
    kin = an.kin
    mech = kin.mechanism
    for a, h in kin.hinges.items():
        data = kin.plate_data(a)
        assert data["q_star"] == 0
        plate = [
            sp.nsimplify(v)
            for v in (
                data["c_minus"][0] - data["c_plus"][0],
                data["c_minus"][1] - data["c_plus"][1],
            )
        ]
        z0 = h.z(sp.Rational(1, 10**30), 0)  # θ → 0 (the model's f, g at a tiny angle)
        for k in range(2):
            assert abs(sp.N((z0[k] - plate[k]).subs(mech.defaults), 30)) < 1e-25
        # the plate direction e_1^{i+(a)a} points from C_{i+(a)a} to C_{i-(a)a}
        length = sp.N(h.length.subs(mech.defaults), 30)
        e1 = (sp.cos(data["alpha_plus"]), sp.sin(data["alpha_plus"]))
        for k in range(2):
            assert abs(sp.N((length * e1[k] - plate[k]).subs(mech.defaults), 30)) < 1e-25
