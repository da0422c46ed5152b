"""What tests/test_runtime_c.py and tests/test_runtime_numpy.py check the runtimes against: an
elimination written out in Python floats and the toy mechanism of tests/runtime_driver.c by
mpmath at 30 digits.

The toy mechanism: theta_0 the input, theta_1 and theta_2 the unknowns of a closure
    G(theta) = (theta_1 - p0 theta_0, theta_1 + theta_2 - theta_0),  A = [1 0; 1 1],
a compliant closure E(delta) = (d0 + d0^3 - 0.1 theta_1, d0 + d1 - 0.05 theta_2 - p1), one point
(cos theta_1, sin theta_2) with deviation delta (paper: (0.1 theta_1, 0.05 theta_2)), one link
turned by theta_1 + theta_2; at the loaded level (3) a stand-in for the reduced equilibrium's
driver gives delta = (theta_1 / 50 + p1 / 1000, -3 theta_2 / 100) and the deviation
(delta_0 + delta_1, 2 delta_0), and refuses p1 theta_0 > 1.
"""

from __future__ import annotations

import math

import mpmath


def eliminate(a: list[list[float]], b: list[list[float]]) -> list[list[float]] | None:
    """Gaussian elimination with partial pivoting (the first row of largest |pivot|), row by
    row in Python floats; None for a zero or non-finite pivot."""
    n = len(a)
    a = [row[:] for row in a]
    b = [row[:] for row in b]
    for c in range(n):
        p = max(range(c, n), key=lambda i: (abs(a[i][c]), -i))
        if not (abs(a[p][c]) > 0.0) or not math.isfinite(abs(a[p][c])):
            return None
        a[c], a[p] = a[p], a[c]
        b[c], b[p] = b[p], b[c]
        for i in range(c + 1, n):
            f = a[i][c] / a[c][c]
            a[i] = [x - f * y if j > c else x for j, (x, y) in enumerate(zip(a[i], a[c]))]
            b[i] = [x - f * y for x, y in zip(b[i], b[c])]
    x = [[0.0] * len(b[0]) for _ in range(n)]
    for r in range(len(b[0])):
        for i in range(n - 1, -1, -1):
            s = b[i][r]
            for j in range(i + 1, n):
                s -= a[i][j] * x[j][r]
            x[i][r] = s / a[i][i]
    return x


def toy(theta0, p0, p1, level: int) -> dict:
    """The toy mechanism's pose and outputs at `level` by mpmath (30 digits): theta, delta, the
    point's rigid position and deviation, the link's rotation."""
    with mpmath.workdps(30):
        return _toy(theta0, p0, p1, level)


def _toy(theta0, p0, p1, level: int) -> dict:
    t0, p0, p1 = mpmath.mpf(theta0), mpmath.mpf(p0), mpmath.mpf(p1)
    t1 = p0 * t0
    t2 = t0 - t1
    a = mpmath.matrix([[1, 0], [1, 1]])

    if level == 0:
        dev = [t1 / 10, t2 / 20]
        delta = [0, 0]
    elif level == 1:
        delta = list(mpmath.lu_solve(a, mpmath.matrix([t1 / 10, t2 / 20 + p1])))
    elif level == 2:
        d0 = mpmath.findroot(lambda d: d + d**3 - t1 / 10, t1 / 10)
        delta = [d0, t2 / 20 + p1 - d0]
    else:
        delta = [t1 / 50 + p1 / 1000, -3 * t2 / 100]
    if level in (1, 2):
        dev = delta
    elif level == 3:
        dev = [delta[0] + delta[1], 2 * delta[0]]
    return {
        "theta": [t0, t1, t2],
        "delta": delta,
        "rigid": [mpmath.cos(t1), mpmath.sin(t2)],
        "dev": dev,
        "link": t1 + t2,
    }


def close(got, want, tol=1e-14) -> bool:
    return all(abs(g - float(w)) <= tol * max(1.0, abs(float(w))) for g, w in zip(got, want))


def toy_partials(theta0, p0, p1, level: int, key: str) -> list[list[float]]:
    """d toy[key] / d(p0, p1, theta_0) by mpmath at 30 digits, per variable: (d(x), d(y)); p1's
    default being 2 p0, the derivative by p0 is the total one that carries p1 along."""
    with mpmath.workdps(30):
        x = (mpmath.mpf(p0), mpmath.mpf(p1), mpmath.mpf(theta0))
        out = []
        for v in range(3):
            order = tuple(int(i == v) for i in range(3))
            out.append(
                [
                    mpmath.diff(lambda a, b, t, c=c: _toy(t, a, b, level)[key][c], x, order)
                    for c in range(2)
                ]
            )
        out[0] = [out[0][c] + 2 * out[1][c] for c in range(2)]
        return [[float(w) for w in row] for row in out]
