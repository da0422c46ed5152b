"""numpy backend: a module `<name>.py` that imports only numpy and the standard library."""

from __future__ import annotations

import sympy as sp
from sympy.printing.numpy import NumPyPrinter

from .... import special
from ....templating import render
from ...literals import float_literals, to_double
from ...plan import Plan
from ..common import header_lines, parameter_symbols, renamed, special_functions, used_symbols
from . import kernels


class Printer(NumPyPrinter):
    """NumPyPrinter that writes every Float as its shortest round-trip decimal and calls
    symkin's special functions by their names (defined in the module from backends/numpy)."""

    def _print_Float(self, expr):  # noqa: N802
        # NumPyPrinter prints 15 digits; every Float here is a double (literals.float_literals):
        # print the shortest decimal that reads back to it exactly.
        return repr(float(expr))

    def _print_Function(self, expr):  # noqa: N802
        if special.is_special(expr):
            return f"{type(expr).__name__}({', '.join(self._print(a) for a in expr.args)})"
        return super()._print_Function(expr)


def routine_source(routine, printer: Printer) -> dict:
    """Template data for one routine: unpacking lines, assignment lines and the outputs."""
    free = used_symbols(routine)
    unpack = []
    for arg in routine.arguments:
        if set(arg.symbols) & free:
            names = ", ".join(s.name if s in free else "_" for s in arg.symbols)
            unpack.append(f"{names}{',' if len(arg.symbols) == 1 else ''} = {arg.name}")
    lines = [f"{s.name} = {printer.doprint(e)}" for s, e in routine.assignments]
    outputs = [printer.doprint(sp.sympify(e)) for e in routine.outputs]
    return {"name": routine.name, "args": [a.name for a in routine.arguments], "doc": routine.doc,
            "unpack": unpack, "lines": lines, "outputs": outputs, "ops": routine.ops}


def emit(plan: Plan, source: str, dtype: str = "float64") -> str:
    """The numpy module's text; `dtype` float32 gives the single-precision variant."""
    an = plan.analysis
    kin = an.kin
    names = parameter_symbols(plan)
    printer = Printer({"fully_qualified_modules": True})
    routines = [routine_source(renamed(r, names), printer) for r in plan.routines.values()]
    defaults = []
    for p in an.mechanism.parameters:
        defaults.append({"name": p.name, "symbol": names[p.symbol].name,
                         "expr": printer.doprint(float_literals(p.expr.xreplace(names))),
                         "value": repr(to_double(p.value))})
    return render(
        "numpy/module.py.j2",
        header=header_lines(plan, source),
        inputs=[kin.hinges[a].name for a in kin.inputs],
        hinges=[kin.hinges[a].name for a in sorted(kin.hinges)],
        limits=[(a - 1, repr(float(sp.N(h.limit, 20)))) for a, h in sorted(kin.hinges.items())
                if h.limit is not None],
        points=list(plan.points), levels=plan.levels, parameters=defaults,
        n_theta=len(an.thetas),
        input_index=[a - 1 for a in kin.inputs], unknown_index=[a - 1 for a in kin.unknowns],
        n_dyads=len(an.rigid.dyads), closed_form=plan.closed_form,
        needs_loops=plan.needs_loops, n_loops=len(kin.chords),
        routines=routines, kernels=[kernels.source(k) for k in special_functions(plan)], dtype=dtype,
    )
