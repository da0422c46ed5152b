"""symkin's numpy runtime for notch hinges at the `loaded` level (docs/physics.md, "Notch hinges at
`loaded`"): a notch is one plate (never two halves: its module has one variant) with its own
relation, the routines notch_relation4_<k>, notch_values4_<k> and notch_values2_<k> of half
plate k (its section's terms folded in as numbers, symkin.codegen.loaded), its sway poles at
max(alpha, beta) times the uniform plate's (symkin.physics.reduced.Reduced.compression), and its
stress from the shot of its section under the same end loads times its K_t
(symkin.physics.reported.section_stress, symkin.physics.section_beams' float RK4 on the same
grid). The module's tables give per half plate (relation4, values4, values2, factor, kt, ratio,
grid, length) or None (a uniform plate). Only modules with notches hold it
(templates/numpy/module.py.j2), after templates/numpy/reduced.py: it redefines its _Batch,
which the loaded level's runtimes call by name; templates/numpy/reduced_notch_report.py the
report.
"""

import numpy
from reduced import _Batch, _red_column  # the module holds them all: reduced.py

from symkin.physics.reduced_solver import _red_sway

# ---- symkin runtime: every generated module with the loaded level on notches holds it ----

# notch hinges at the loaded level (templates/numpy/reduced_notch.py): reduced.py's system with
# each notch's own relation and sway poles

_RedUniform = _Batch


class _Batch(_RedUniform):
    """reduced.py's system, a notch's half plate through its own relation (no rest shortcut:
    the Python level evaluates it whole too)."""

    def _each(self, ins, slot, count):
        """Every half plate's `count` outputs of its relation (slot 0: values and partials at
        order 4, 1: values at order 4, 2: values at order 2), one half plate after the other."""
        b = ins[0].shape[0] if ins else 0
        out = []
        for k in range(self.plates):
            plate = ins[5 * k : 5 * k + 5]
            notch = self.t.notches[k]
            if notch is not None:
                out.append([_red_column(v, b) for v in notch[slot](plate)][:count])
                continue
            uniform = (self.t.relation4, self.t.values4, self.t.values2)[slot]
            if slot == 2:
                out.append([_red_column(v, b) for v in uniform(plate)])
                continue
            rest = (plate[1] == 0.0) & (plate[2] == 0.0)
            if numpy.all(rest):
                out.append([_red_column(v, b) for v in self.t.rest4(plate)][:count])
                continue
            found = [_red_column(v, b) for v in uniform(plate)]
            if numpy.any(rest):
                at_rest = self.t.rest4(plate)[:count]
                found = [numpy.where(rest, r, v) for r, v in zip(at_rest, found)]
            out.append(found)
        return out

    def _relation(self, ins):
        rel = self._each(ins, 0, 12)
        return rel, [r[j] for r in rel for j in range(3)]

    def _values4(self, ins):
        return [v for r in self._each(ins, 1, 3) for v in r]

    def _values2(self, ins):
        return [v for r in self._each(ins, 2, 3) for v in r]

    def _worst(self, ins, b):
        worst = numpy.zeros(b)
        for k in range(self.plates):
            w = _red_sway(ins[5 * k + 1], ins[5 * k + 3], ins[5 * k + 4], self.count)
            notch = self.t.notches[k]
            if notch is not None:
                w = w * notch[3]
            worst = numpy.where(w > worst, w, worst)
        return worst
