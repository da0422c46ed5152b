"""symkin/model/special/axial_forms.py, the beam-column kernels' float forms kept as source, is
what symkin.model.special.axial computes afresh (the Chebyshev fits at 40 digits, the far and
closed forms' exact polynomials), bit for bit; `pytest --update` rewrites it. The kernels'
accuracy against mpmath is tests/test_beam_column_kernels.py's."""

from __future__ import annotations

import difflib
from pathlib import Path

from symkin.model.special import axial, axial_forms

KEPT = Path(axial_forms.__file__)


def test_kept_forms_are_the_computed_ones(request):
    fresh = axial.forms_source()
    if request.config.getoption("--update"):
        KEPT.write_text(fresh)
    kept = KEPT.read_text()
    diff = "".join(
        difflib.unified_diff(kept.splitlines(True), fresh.splitlines(True), "kept", "computed", n=1)
    )
    assert kept == fresh, f"{KEPT} is out of date (pytest --update rewrites it):\n{diff[:3000]}"


def test_the_kernels_read_the_kept_forms():
    """Every base kernel and its first two derivatives: each form the backends print comes from
    the kept table (none is fitted in the process), equal to the fit."""
    for base in axial.BASES:
        for order in range(axial.KEPT_ORDERS):
            k = axial.kernel(base, order)
            assert k.near_form() == axial.NearForm(*axial_forms.NEAR[base, order])
            assert k.far_form() == axial.FarForm(*axial_forms.FAR[base, order])
            assert k.float_closed() == axial_forms.CLOSED[base, order]
    assert axial.t_near_form() == axial._fit_t_near()
    # a derivative beyond the table is fitted as before
    beyond = axial.kernel("s", axial.KEPT_ORDERS)
    assert beyond.near_form() == axial._fit_near("s", axial.KEPT_ORDERS)
    assert beyond.far_form() == axial._far_form(axial.closed_form("s", axial.KEPT_ORDERS))
