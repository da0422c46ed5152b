"""Loop-closure equations (symkin.kinematics.loop_equations) against the paper's section 5,
symbolically.

The paper's equations are typed in below in the paper's own symbols (lengths r1, a, b1, ...,
relative angles q1, q2, ...). They are mapped onto symkin's:

- every paper length is the distance between the corresponding hinge centres of the example
  (exact rationals, so the lengths are exact surds);
- the paper measures angles from link-aligned frames: the x axis of link i points along one of its
  loop vectors (the one the paper writes without a constant angle) and the ground's along
  O_A O_B. With γ_i the as-fabricated direction of that axis, measured from the ground's axis,
  the paper's relative angle of hinge a is q_a = q^symkin_a + γ_{i-(a)} - γ_{i+(a)}, where
  q^symkin_a = sign·θ_a is the rotation from the as-fabricated pose;
- components are rotated into the paper's ground frame (x along O_A O_B; the rotation is zero in
  all three examples, but is applied anyway);
- a chord's angle (q4 of the four-bar, q6/q7, q9/q10) is eliminated with symkin's angular closure
  (5.1), because symkin writes every link rotation φ_i along the tree.

A difference is shown to be zero by expanding the trigonometric functions of sums (r cos(φ + β)
becomes x cos φ - y sin φ with the exact vector components) and simplifying each coefficient of the
resulting polynomial in cos θ_a, sin θ_a.
"""

from __future__ import annotations

import mpmath
import pytest
import sympy as sp
from conftest import EXAMPLES
from mechanisms import FIVE_BAR, SERIAL_ARM, TRIAD_SIX_BAR, WATT_II

import symkin
from symkin.kinematics.loop_equations import LoopEquations, latex, loop_equations
from symkin.kinematics.positions import Kinematics

Q = {a: sp.Symbol(f"q{a}", real=True) for a in range(1, 11)}
q1, q2, q3, q4, q5, q6, q7, q8, q9, q10 = (Q[a] for a in range(1, 11))


# -- helpers ---------------------------------------------------------------------------------------
def kinematics(name: str) -> Kinematics:
    return Kinematics(symkin.structure(symkin.load(EXAMPLES / f"{name}.toml")))


def equations(kin: Kinematics) -> dict[int, LoopEquations]:
    return {eq.chord: eq for eq in loop_equations(kin)}


class Paper:
    """The map from the paper's symbols onto symkin's, for one loop of one example."""

    def __init__(
        self, kin: Kinematics, ground: tuple[str, str], frames: dict[int, tuple[str, str]]
    ) -> None:
        self.kin = kin
        s = kin.structure
        self.rho = self.direction(*ground)  # paper's x axis in symkin's frame
        # γ_i: as-fabricated direction of link i's paper x axis, from the paper's x axis.
        self.gamma = {0: sp.Integer(0)}
        self.gamma.update({i: self.direction(*pq) - self.rho for i, pq in frames.items()})
        self.q = {}
        for a in range(1, s.m + 1):
            ip, im = s.i_plus[a - 1], s.i_minus[a - 1]
            if ip in self.gamma and im in self.gamma:
                self.q[Q[a]] = kin.q(a) + self.gamma[im] - self.gamma[ip]
        # Chord angles by (5.1), so that every angle is a tree angle, as in symkin's φ_i.
        self.chord = {}
        for c in kin.chords:
            theta = kin.theta[c]
            self.chord[theta] = sp.solve(kin.angular_closure(c), theta)[0]

    def centre(self, name: str) -> tuple[sp.Expr, sp.Expr]:
        return self.kin.hinges[self.kin.structure.hinge_label(name)].centre

    def direction(self, p: str, q: str) -> sp.Expr:
        (px, py), (qx, qy) = self.centre(p), self.centre(q)
        return sp.atan2(qy - py, qx - px)

    def length(self, p: str, q: str) -> sp.Expr:
        (px, py), (qx, qy) = self.centre(p), self.centre(q)
        return sp.sqrt((qx - px) ** 2 + (qy - py) ** 2)

    def angle(self, p1: str, p2: str, q1_: str, q2_: str) -> sp.Expr:
        """∠(P1P2, Q1Q2): the direction of Q1Q2 minus that of P1P2 (as fabricated)."""
        return self.direction(q1_, q2_) - self.direction(p1, p2)

    def __call__(self, expr: sp.Expr, chords: bool = True) -> sp.Expr:
        """A paper expression in symkin's angles (tree angles only, unless `chords` is False)."""
        expr = sp.sympify(expr).xreplace(self.q)
        return expr.xreplace(self.chord) if chords else expr

    def components(self, x: sp.Expr, y: sp.Expr) -> tuple[sp.Expr, sp.Expr]:
        """symkin's absolute components, rotated into the paper's ground frame."""
        c, s = sp.cos(self.rho), sp.sin(self.rho)
        return c * x + s * y, -s * x + c * y


def vanishes(expr: sp.Expr) -> bool:
    """True when `expr`, a trigonometric polynomial in the θ's with surd coefficients, is zero."""
    expr = sp.expand(sp.expand_trig(sp.expand(expr)))
    thetas = sorted((s for s in expr.free_symbols if s.name.startswith("theta_")), key=str)
    cs = {t: (sp.Dummy(f"c{t.name}"), sp.Dummy(f"s{t.name}")) for t in thetas}
    expr = expr.xreplace(
        {sp.cos(t): c for t, (c, _) in cs.items()} | {sp.sin(t): s for t, (_, s) in cs.items()}
    )
    gens = [g for pair in cs.values() for g in pair]
    if not gens:
        return sp.simplify(sp.radsimp(expr)) == 0
    # Reduce modulo sin² = 1 - cos²: polynomials of degree <= 1 in each sin θ_a are a basis, so
    # the zero function has only zero coefficients there.
    reduced: dict[tuple[int, ...], sp.Expr] = {}
    terms = list(sp.Poly(expr, *gens).terms())
    while terms:
        monom, coeff = terms.pop()
        monom = list(monom)
        for k in range(1, len(gens), 2):
            if monom[k] >= 2:
                monom[k] -= 2
                lower = list(monom)
                lower[k - 1] += 2  # s² = 1 - c²
                terms.extend([(tuple(monom), coeff), (tuple(lower), -coeff)])
                break
        else:
            reduced[tuple(monom)] = reduced.get(tuple(monom), 0) + coeff
    for coeff in reduced.values():
        coeff = sp.radsimp(sp.expand(coeff))
        if coeff != 0 and sp.simplify(coeff) != 0:
            return False
    return True


def same_angle(paper: Paper, mine: sp.Eq, psi: sp.Expr, num: sp.Expr, den: sp.Expr) -> bool:
    """mine: φ_j + β_j = atan2(Y, X); the paper's ψ = atan2(num, den) means the same angle.

    ψ - (φ_j + β_j) must be a constant δ and (den, num) = Rot(δ)(X, Y): then
    atan2(num, den) = atan2(Y, X) + δ (mod 2π), the quadrant included.
    """
    delta = sp.expand(paper(psi) - mine.lhs)
    assert not any(s.name.startswith("theta_") for s in delta.free_symbols), delta
    Y, X = mine.rhs.args
    # δ holds the turn from symkin's frame to the paper's, so X, Y need no rotation of their own.
    cd, sd = sp.cos(delta), sp.sin(delta)
    return vanishes(paper(den) - (cd * X - sd * Y)) and vanishes(paper(num) - (sd * X + cd * Y))


def check_loop(paper: Paper, eq: LoopEquations, sign: int, angular, x, y) -> None:
    """(5.1) and the positional pair: the paper's = sign · symkin's (sign: the walking sense)."""
    assert sp.expand(paper(angular, chords=False) - sign * eq.angular) == 0
    mx, my = paper.components(eq.x, eq.y)
    assert vanishes(paper(x) - sign * mx)
    assert vanishes(paper(y) - sign * my)


def check_squared(paper: Paper, eq: LoopEquations, lhs, rhs) -> None:
    assert vanishes(paper(lhs - rhs) - (eq.squared.lhs - eq.squared.rhs))


# -- four-bar (Fig. 2): (5.4), (5.5), (5.6) and the squared form ---------------------------------
@pytest.fixture(scope="module")
def four_bar():
    kin = kinematics("four_bar")
    paper = Paper(kin, ("A0", "B0"), {1: ("A0", "A"), 2: ("A", "B"), 3: ("B0", "B")})
    r1, r2, r4, r6 = (
        paper.length("A0", "B0"),
        paper.length("A0", "A"),
        paper.length("B0", "B"),
        paper.length("A", "B"),
    )
    return kin, equations(kin)[4], paper, (r1, r2, r4, r6)


def test_four_bar_5_4_and_5_5(four_bar):
    _kin, eq, paper, (r1, r2, r4, r6) = four_bar
    check_loop(
        paper,
        eq,
        +1,
        # "(5.4) takes the form" means (5.1) (erratum 3); the relation is (5.5):
        q1 + q2 - q3 + q4,
        r2 * sp.cos(q1) + r6 * sp.cos(q1 + q2) - r4 * sp.cos(q3) - r1,
        r2 * sp.sin(q1) + r6 * sp.sin(q1 + q2) - r4 * sp.sin(q3),
    )


def test_four_bar_squared_form(four_bar):
    _kin, eq, paper, (r1, r2, r4, r6) = four_bar
    assert eq.eliminated == 3  # the rocker: the paper eliminates q3 too
    check_squared(
        paper,
        eq,
        r4**2 - (r1**2 + r2**2 + r6**2),
        2 * r2 * r6 * sp.cos(q2) - 2 * r1 * r2 * sp.cos(q1) - 2 * r1 * r6 * sp.cos(q1 + q2),
    )


def test_four_bar_5_6_solved_angle(four_bar):
    _kin, eq, paper, (r1, r2, _r4, r6) = four_bar
    # (5.6) with r1 for the printed "r" (erratum 3) and atan2 for arctan (erratum 6).
    num = r2 * sp.sin(q1) + r6 * sp.sin(q1 + q2)
    den = r2 * sp.cos(q1) + r6 * sp.cos(q1 + q2) - r1
    assert same_angle(paper, eq.solved_angle, q3, num, den)
    # Arctan loses the quadrant: atan2(-num, -den) is a different angle (off by π).
    assert not same_angle(paper, eq.solved_angle, q3, -num, -den)


# -- six-bar Stephenson I (Fig. 4): (5.7)–(5.14) ---------------------------------------------------
@pytest.fixture(scope="module")
def six_bar():
    kin = kinematics("stephenson_six_bar")
    eqs = equations(kin)
    # Paper frames: link 1 along O_A C (a appears as a cos(q1 - α)), link 2 along C D, link 3 along
    # O_B E (c cos(q3 + β)), link 4 along E D (-g cos(q3 + q4)) and link 5 along B A (the AB term
    # is written -b cos(q1 + q6), with the loop walked O_A A B O_B).
    paper = Paper(
        kin,
        ("O_A", "O_B"),
        {1: ("O_A", "C"), 2: ("C", "D"), 3: ("O_B", "E"), 4: ("E", "D"), 5: ("B", "A")},
    )
    L = paper.length
    dims = {
        "a": L("O_A", "A"),
        "b": L("A", "B"),
        "c": L("O_B", "B"),
        "d": L("O_A", "O_B"),
        "e": L("O_A", "C"),
        "f": L("O_B", "E"),
        "g": L("E", "D"),
        "h": L("C", "D"),
        "alpha": paper.angle("O_A", "A", "O_A", "C"),
        "beta": paper.angle("O_B", "E", "O_B", "B"),
    }
    return kin, eqs, paper, dims


def test_six_bar_loop_1_5_7_and_5_8(six_bar):
    _kin, eqs, paper, k = six_bar
    a, b, c, d, alpha, beta = (k[n] for n in ("a", "b", "c", "d", "alpha", "beta"))
    check_loop(
        paper,
        eqs[6],
        +1,
        q1 - q3 - q5 + q6,
        a * sp.cos(q1 - alpha) - b * sp.cos(q1 + q6) - c * sp.cos(q3 + beta) - d,
        a * sp.sin(q1 - alpha) - b * sp.sin(q1 + q6) - c * sp.sin(q3 + beta),
    )


def test_six_bar_loop_1_squared_5_10_and_solved_5_9(six_bar):
    kin, eqs, paper, k = six_bar
    a, b, c, d, alpha, beta = (k[n] for n in ("a", "b", "c", "d", "alpha", "beta"))
    # The default rule eliminates the last free link (5, AB); the paper eliminates q3 (link 3).
    assert eqs[6].eliminated == 5
    eq = eqs[6].eliminating(3)
    check_squared(
        paper,
        eq,
        c**2 - (a**2 + b**2 + d**2),
        -2 * a * b * sp.cos(q6 + alpha)
        - 2 * a * d * sp.cos(q1 - alpha)
        + 2 * b * d * sp.cos(q1 + q6),
    )
    # (5.9) with atan2 (erratum 6): q3 + β = atan2(num, den).
    num = a * sp.sin(q1 - alpha) - b * sp.sin(q1 + q6)
    den = a * sp.cos(q1 - alpha) - b * sp.cos(q1 + q6) - d
    assert same_angle(paper, eq.solved_angle, q3 + beta, num, den)
    # The same, through loop_equations' `eliminate` argument.
    again = {e.chord: e for e in loop_equations(kin, eliminate={6: 3, 7: 2})}[6]
    assert again.squared == eq.squared and again.solved_angle == eq.solved_angle


def test_six_bar_loop_2_5_11_and_5_12(six_bar):
    _kin, eqs, paper, k = six_bar
    d, e, f, g, h = (k[n] for n in "defgh")
    check_loop(
        paper,
        eqs[7],
        +1,
        q1 + q2 - q3 - q4 + q7,
        e * sp.cos(q1) + h * sp.cos(q1 + q2) - g * sp.cos(q3 + q4) - f * sp.cos(q3) - d,
        e * sp.sin(q1) + h * sp.sin(q1 + q2) - g * sp.sin(q3 + q4) - f * sp.sin(q3),
    )


def test_six_bar_loop_2_squared_5_13_and_solved_5_14(six_bar):
    _kin, eqs, paper, k = six_bar
    d, e, f, g, h = (k[n] for n in "defgh")
    assert eqs[7].eliminated == 4  # default rule; the paper eliminates link 2
    eq = eqs[7].eliminating(2)
    lhs = h**2 - (d**2 + e**2 + f**2 + g**2)

    def rhs(ef_angle):
        return (
            -2 * e * g * sp.cos(q1 - (q3 + q4))
            - 2 * e * f * sp.cos(ef_angle)
            + 2 * f * g * sp.cos(q4)
            - 2 * d * e * sp.cos(q1)
            + 2 * d * g * sp.cos(q3 + q4)
            + 2 * d * f * sp.cos(q3)
        )

    # docs/errata.md, item 7: (5.13) prints cos(q1 + q3) in the e f term; squaring (5.11) gives
    # cos(q1 - q3). The corrected form holds, the printed one does not.
    check_squared(paper, eq, lhs, rhs(q1 - q3))
    assert not vanishes(paper(lhs - rhs(q1 + q3)) - (eq.squared.lhs - eq.squared.rhs))
    # (5.14): h cos(q1 + q2) = -(e cos q1 - g cos(q3 + q4) - f cos q3 - d), so with atan2
    # (erratum 6) q1 + q2 = atan2(-num, -den); atan2(num, den) is off by π.
    num = e * sp.sin(q1) - g * sp.sin(q3 + q4) - f * sp.sin(q3)
    den = e * sp.cos(q1) - g * sp.cos(q3 + q4) - f * sp.cos(q3) - d
    assert same_angle(paper, eq.solved_angle, q1 + q2, -num, -den)
    assert not same_angle(paper, eq.solved_angle, q1 + q2, num, den)


# -- nine-bar platform (Fig. 6): (5.15)–(5.20) -----------------------------------------------------
NINE_BAR_LOOP_1 = {
    1: ("O", "A"),
    2: ("A", "B"),
    3: ("B", "K"),
    4: ("K", "G"),
    5: ("G", "H"),
    6: ("H", "I"),
}
# The paper writes both h1 = |BK| (loop 1) and b3 = |BC| (loop 2) at the angle q1 + q2 + q3 of the
# ternary link 3, i.e. it drops the constant angle KBC (the six-bar keeps its α and β). In the
# example B, K and C are not collinear, so link 3's paper frame is taken along B K in loop 1 and
# along B C in loop 2.
NINE_BAR_LOOP_2 = {1: ("O", "A"), 2: ("A", "B"), 3: ("B", "C"), 7: ("C", "D"), 8: ("D", "E")}


@pytest.fixture(scope="module")
def nine_bar():
    kin = kinematics("nine_bar_platform")
    return kin, equations(kin)


def sums(a: int, b: int) -> sp.Expr:
    return sp.Add(*(Q[i] for i in range(a, b + 1)))


def test_nine_bar_loop_1_5_15_and_5_16(nine_bar):
    kin, eqs = nine_bar
    paper = Paper(kin, ("O", "I"), NINE_BAR_LOOP_1)
    L = paper.length
    b1, b2, h1, b4, b5, b6, a = (
        L("O", "A"),
        L("A", "B"),
        L("B", "K"),
        L("K", "G"),
        L("G", "H"),
        L("H", "I"),
        L("O", "I"),
    )
    angles = [q1, q1 + q2, sums(1, 3), sums(1, 4), sums(1, 5)]
    lengths = [b1, b2, h1, b4, b5]
    # The paper walks O A B K G H I against the chord u9 (directed from the ground): sign -1.
    check_loop(
        paper,
        eqs[9],
        -1,
        q1 + q2 + q3 + q4 + q5 + q6 - q9,
        sum(r * sp.cos(t) for r, t in zip(lengths, angles)) + b6 * sp.cos(q9) - a,
        sum(r * sp.sin(t) for r, t in zip(lengths, angles)) + b6 * sp.sin(q9),
    )


def test_nine_bar_loop_1_squared_and_solved_5_17(nine_bar):
    kin, eqs = nine_bar
    paper = Paper(kin, ("O", "I"), NINE_BAR_LOOP_1)
    L = paper.length
    b1, b2, h1, b4, b5, b6, a = (
        L("O", "A"),
        L("A", "B"),
        L("B", "K"),
        L("K", "G"),
        L("G", "H"),
        L("H", "I"),
        L("O", "I"),
    )
    eq = eqs[9]
    assert eq.eliminated == 6
    c = sp.cos
    rhs = (
        2 * b1 * b2 * c(q2)
        + 2 * b1 * h1 * c(q2 + q3)
        + 2 * b1 * b4 * c(sums(2, 4))
        + 2 * b1 * b5 * c(sums(2, 5))
        + 2 * b2 * h1 * c(q3)
        + 2 * b2 * b4 * c(q3 + q4)
        + 2 * b2 * b5 * c(sums(3, 5))
        + 2 * h1 * b4 * c(q4)
        + 2 * h1 * b5 * c(q4 + q5)
        + 2 * b4 * b5 * c(q5)
        - 2 * a * b1 * c(q1)
        - 2 * a * b2 * c(q1 + q2)
        - 2 * a * h1 * c(sums(1, 3))
        - 2 * a * b4 * c(sums(1, 4))
        - 2 * a * b5 * c(sums(1, 5))
    )
    others = b1**2 + b2**2 + h1**2 + b4**2 + b5**2 + a**2
    # Erratum 4: the left side is b6² - (...), not the printed b7² - (...).
    check_squared(paper, eq, b6**2 - others, rhs)
    assert not vanishes(paper(L("C", "D") ** 2 - others - rhs) - (eq.squared.lhs - eq.squared.rhs))
    # (5.17): the printed fraction is cos-sum over sin-sum (erratum 4: swapped); from (5.16),
    # b6 (cos q9, sin q9) = -(C, S), so q9 = atan2(-S, -C) (erratum 6, with the signs).
    angles = [q1, q1 + q2, sums(1, 3), sums(1, 4), sums(1, 5)]
    lengths = [b1, b2, h1, b4, b5]
    S = sum(r * sp.sin(t) for r, t in zip(lengths, angles))
    C = sum(r * sp.cos(t) for r, t in zip(lengths, angles)) - a
    assert same_angle(paper, eq.solved_angle, q9, -S, -C)
    assert not same_angle(paper, eq.solved_angle, q9, -C, -S)  # the printed (swapped) one


def test_nine_bar_loop_2_5_18_and_5_19(nine_bar):
    kin, eqs = nine_bar
    paper = Paper(kin, ("O", "E"), NINE_BAR_LOOP_2)
    L = paper.length
    b1, b2, b3, b7, b8, c = (
        L("O", "A"),
        L("A", "B"),
        L("B", "C"),
        L("C", "D"),
        L("D", "E"),
        L("O", "E"),
    )
    angles = [q1, q1 + q2, sums(1, 3), q7 + sums(1, 3)]
    lengths = [b1, b2, b3, b7]
    check_loop(
        paper,
        eqs[10],
        -1,
        q1 + q2 + q3 + q7 + q8 - q10,
        sum(r * sp.cos(t) for r, t in zip(lengths, angles)) + b8 * sp.cos(q10) - c,
        sum(r * sp.sin(t) for r, t in zip(lengths, angles)) + b8 * sp.sin(q10),
    )


def test_nine_bar_loop_2_squared_and_solved_5_20(nine_bar):
    kin, eqs = nine_bar
    paper = Paper(kin, ("O", "E"), NINE_BAR_LOOP_2)
    L = paper.length
    b1, b2, b3, b7, b8, c = (
        L("O", "A"),
        L("A", "B"),
        L("B", "C"),
        L("C", "D"),
        L("D", "E"),
        L("O", "E"),
    )
    eq = eqs[10]
    assert eq.eliminated == 8
    cos = sp.cos
    rhs = (
        2 * b1 * b2 * cos(q2)
        + 2 * b1 * b3 * cos(q2 + q3)
        + 2 * b1 * b7 * cos(q2 + q3 + q7)
        + 2 * b2 * b3 * cos(q3)
        + 2 * b2 * b7 * cos(q3 + q7)
        + 2 * b3 * b7 * cos(q7)
        - 2 * b1 * c * cos(q1)
        - 2 * b2 * c * cos(q1 + q2)
        - 2 * b3 * c * cos(sums(1, 3))
        - 2 * b7 * c * cos(q7 + sums(1, 3))
    )
    # Erratum 5: left side b8² - (b1² + b2² + b3² + b7² + c²), and no b3 b4 or b3 b5 terms.
    check_squared(paper, eq, b8**2 - (b1**2 + b2**2 + b3**2 + b7**2 + c**2), rhs)
    b4, b5 = L("K", "G"), L("G", "H")
    printed = rhs + 2 * b3 * b4 * cos(q4) + 2 * b3 * b5 * cos(q4 + q5)
    assert not vanishes(
        paper(b8**2 - (b1**2 + b2**2 + b3**2 + b7**2 + c**2) - printed)
        - (eq.squared.lhs - eq.squared.rhs)
    )
    # (5.20) with atan2: b8 (cos q10, sin q10) = -(C, S), so q10 = atan2(-S, -C).
    angles = [q1, q1 + q2, sums(1, 3), q7 + sums(1, 3)]
    lengths = [b1, b2, b3, b7]
    S = sum(r * sp.sin(t) for r, t in zip(lengths, angles))
    C = sum(r * sp.cos(t) for r, t in zip(lengths, angles)) - c
    assert same_angle(paper, eq.solved_angle, q10, -S, -C)
    assert not same_angle(paper, eq.solved_angle, q10, S, C)


# -- generic properties ----------------------------------------------------------------------------
def test_terms_are_the_loop_weights_in_polar_form():
    for name in ("four_bar", "stephenson_six_bar", "nine_bar_platform"):
        kin = kinematics(name)
        for eq in loop_equations(kin):
            weights = kin.loop_weights(eq.chord)
            assert eq.links == tuple(sorted(i for i, w in weights.items() if w != (0, 0)))
            for t, phi in zip(eq.terms, eq.phi):
                wx, wy = weights[t.link]
                assert sp.simplify(t.r * sp.cos(t.beta) - wx) == 0
                assert sp.simplify(t.r * sp.sin(t.beta) - wy) == 0
                assert (t.r.is_positive, phi) == (True, kin.phi(t.link) if t.link else 0)


def test_no_loops_no_equations():
    kin = Kinematics(symkin.structure(symkin.loads(SERIAL_ARM)))
    assert loop_equations(kin) == ()


GENERIC = {
    "five_bar": (FIVE_BAR, [{"O1": "0.2", "O2": "-0.15"}, {"O1": "-0.1", "O2": "0.05"}]),
    "watt_ii": (WATT_II, [{"O1": "0.3"}, {"O1": "-0.25"}]),
    "triad_six_bar": (TRIAD_SIX_BAR, [{"O1": "0.1"}]),
}


@pytest.mark.parametrize("name", sorted(GENERIC))
def test_equations_are_the_positional_closure(name):
    """x, y are the components of Σ Rot(φ_i) V_i; `angular` is (5.1); the rule's link is free."""
    kin = Kinematics(symkin.structure(symkin.loads(GENERIC[name][0])))
    fixed = {
        i
        for i in range(kin.structure.n + 1)
        if all(kin.hinges[b].is_input for b in kin.structure.tree_path(i))
    }
    for eq in loop_equations(kin):
        px, py = kin.positional_closure(eq.chord, rigid=True)
        assert vanishes(eq.x - px) and vanishes(eq.y - py)
        assert sp.expand(eq.angular - kin.angular_closure(eq.chord)) == 0
        assert eq.eliminated not in fixed and eq.eliminated == max(set(eq.links) - fixed)


def test_squared_form_is_implied_by_the_positional_pair():
    """rhs - lhs = x² + y² - 2 r_j (x cos(φ_j + β_j) + y sin(φ_j + β_j)), identically."""
    kin = Kinematics(symkin.structure(symkin.loads(FIVE_BAR)))
    for eq in loop_equations(kin):
        for j in (eq.eliminated, eq.links[1]):
            e = eq.eliminating(j)
            u = e.angle(j)
            r_j = e.term(j).r
            identity = (
                e.squared.rhs
                - e.squared.lhs
                - (e.x**2 + e.y**2 - 2 * r_j * (e.x * sp.cos(u) + e.y * sp.sin(u)))
            )
            assert vanishes(identity)


@pytest.mark.parametrize("name", sorted(GENERIC))
def test_equations_vanish_at_the_rigid_solution(name):
    from symkin.kinematics.analysis import Analysis
    from symkin.studies.configuration import parameter_values

    text, cases = GENERIC[name]
    structure = symkin.structure(symkin.loads(text))
    analysis = Analysis(structure)
    kin = analysis.kin
    params = parameter_values(structure.mechanism)
    eqs = loop_equations(kin)
    assert eqs
    for inputs in cases:
        rigid = symkin.evaluate(analysis, inputs, "paper").angles_rigid
        with mpmath.workdps(30):
            values = {kin.theta[structure.hinge_label(n)]: mpmath.mpf(v) for n, v in rigid.items()}
            values.update({s: mpmath.mpf(sp.N(v, 35)) for s, v in params.items()})

            def at(expr):
                expr = sp.sympify(expr)
                args = sorted(expr.free_symbols, key=str)
                return sp.lambdify(args, expr, "mpmath")(*(values[a] for a in args))

            tol = mpmath.mpf("1e-14")  # the rigid angles come back as float64
            for eq in eqs:
                assert abs(at(eq.angular)) < tol
                assert abs(at(eq.x)) < tol and abs(at(eq.y)) < tol
                for j in eq.links[1:]:
                    e = eq.eliminating(j)
                    assert abs(at(e.squared.lhs - e.squared.rhs)) < tol
                    diff = at(e.solved_angle.lhs) - at(e.solved_angle.rhs)
                    assert abs(diff - 2 * mpmath.pi * mpmath.nint(diff / (2 * mpmath.pi))) < 1e-12


def test_eliminating_rejects_the_ground_and_strangers():
    kin = kinematics("four_bar")
    eq = loop_equations(kin)[0]
    with pytest.raises(ValueError):
        eq.eliminating(0)
    with pytest.raises(ValueError):
        loop_equations(kin, eliminate={1: 2})


def test_latex_block():
    kin = kinematics("four_bar")
    text = latex(loop_equations(kin)[0], kin)
    assert text.startswith("\\begin{aligned}") and "chord 4 (B)" in text
    assert "\\operatorname{atan}_{2}" in text or "atan2" in text
