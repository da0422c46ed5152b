"""Which of a point's stiffness K and compliance C exists (docs/physics.md, "What equilibrium
reports"), written once for Python: symkin.physics.reported.stiffness_and_compliance (the
`loaded` and `equilibrium` levels) judges one point with it, and every generated numpy module
with the loaded level's report holds the text below the marker verbatim
(symkin.codegen.templating.shared) and judges every configuration's at once; so it imports only
numpy. The C runtime's twin is templates/c/reduced_report.c's sk_rep_stiffness.
"""

import numpy

# ---- symkin runtime: every generated module with the loaded level's report holds it ----

# symkin stiffness rule (symkin/physics/stiffness_rule.py, shared with the Python path): K = C^-1
# where C is regular in the plates' scales, else the outlier side does not exist.


def _inverses(a):
    """The inverse of every matrix of a (b, 3, 3) stack, NaN where one is singular."""
    try:
        return numpy.linalg.inv(a)
    except numpy.linalg.LinAlgError:
        out = numpy.full(a.shape, numpy.nan)
        for c in range(a.shape[0]):
            try:
                out[c] = numpy.linalg.inv(a[c])
            except numpy.linalg.LinAlgError:
                continue  # singular: NaN
        return out


def _stiffness_compliance(c, scales, singular):
    """(K, C) of every point compliance of a (b, 3, 3) stack, NaN where it does not exist: S =
    C scaled by `scales` (its rows', its columns': F/L, F/L, F and 1, 1, 1/L), singular where
    its 1-norm times its inverse's exceeds `singular` (or no inverse); then K NaN and C's
    entries within |S|/singular of zero exactly 0 where |S| <= |S^-1| (a direction held
    rigidly), else C NaN (a direction free); both NaN where C is not finite."""
    b = c.shape[0]
    stiff, comp = numpy.full((b, 3, 3), numpy.nan), numpy.full((b, 3, 3), numpy.nan)
    live = numpy.flatnonzero(numpy.all(numpy.isfinite(c), axis=(1, 2)))
    if not live.size:
        return stiff, comp
    rows, cols = scales
    cl = c[live]
    scaled = cl * rows[:, None] * cols
    size = numpy.abs(scaled).sum(axis=1).max(axis=1)
    inverse = _inverses(scaled)
    invertible = numpy.all(numpy.isfinite(inverse), axis=(1, 2))
    with numpy.errstate(invalid="ignore"):
        inverse_size = numpy.abs(inverse).sum(axis=1).max(axis=1)
    regular = invertible & (size * inverse_size <= singular)
    free = invertible & ~regular & (size > inverse_size)
    held = ~regular & ~free
    if regular.any():
        stiff[live[regular]] = numpy.linalg.inv(cl[regular])
        comp[live[regular]] = cl[regular]
    if free.any():
        stiff[live[free]] = inverse[free] * cols[:, None] * rows  # K = S^-1 scaled back
    if held.any():
        small = numpy.abs(scaled[held]) <= size[held][:, None, None] / singular
        comp[live[held]] = numpy.where(small, 0.0, cl[held])
    return stiff, comp
