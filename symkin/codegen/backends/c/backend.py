"""C99 backend: `<name>.h` / `<name>.c`, libm only, no allocation, no globals but constants."""

from __future__ import annotations

import sympy as sp
from sympy.printing.c import C99CodePrinter

from .... import levels as level_table
from .... import special
from ....templating import render
from ...literals import to_double
from ...plan import Plan
from ..common import header_lines, parameter_symbols, renamed, special_functions, used_symbols
from . import kernels


class Printer(C99CodePrinter):
    """C99 printer without the non-standard M_PI / M_SQRT2 ... macros (strict -std=c99 has none)."""

    def __init__(self, settings=None) -> None:
        super().__init__(settings)
        self.math_macros = {}

    def _print_Pi(self, expr):  # noqa: N802 - sympy's printer protocol
        return "3.141592653589793238462643383279503"

    def _print_Exp1(self, expr):  # noqa: N802
        return "2.718281828459045235360287471352662"

    def _print_Float(self, expr):  # noqa: N802
        # literals.float_literals made every Float a double: print the shortest exact decimal.
        return repr(float(expr))

    def _print_Function(self, expr):  # noqa: N802
        """symkin's special functions are the static `symkin_<name>` of backends/c/kernels."""
        if special.is_special(expr):
            args = ", ".join(self._print(a) for a in expr.args)
            return f"symkin_{type(expr).__name__}({args})"
        return super()._print_Function(expr)


def routine_source(routine, printer: Printer) -> dict:
    """Template data for one routine as a static C function writing into `out`."""
    free = used_symbols(routine)
    unpack = []
    for arg in routine.arguments:
        for k, s in enumerate(arg.symbols):
            if s in free:
                unpack.append(f"const double {s.name} = {arg.name}[{k}];")
    lines = [f"const double {s.name} = {printer.doprint(e)};" for s, e in routine.assignments]
    outputs = [printer.doprint(sp.sympify(e)) for e in routine.outputs]
    used = {a.name for a in routine.arguments if set(a.symbols) & free}
    return {"name": routine.name, "doc": routine.doc, "ops": routine.ops,
            "args": [(a.name, a.name in used) for a in routine.arguments],
            "unpack": unpack, "lines": lines, "outputs": outputs}


def emit(plan: Plan, source: str) -> tuple[str, str]:
    """The header and source texts."""
    an = plan.analysis
    kin = an.kin
    name = plan.mechanism.name
    names = parameter_symbols(plan)
    printer = Printer()
    routines = [routine_source(renamed(r, names), printer) for r in plan.routines.values()]
    context = dict(
        header=header_lines(plan, source), name=name, NAME=name.upper(),
        inputs=[kin.hinges[a].name for a in kin.inputs],
        hinges=[kin.hinges[a].name for a in sorted(kin.hinges)],
        limits=[(a - 1, repr(float(sp.N(h.limit, 20)))) for a, h in sorted(kin.hinges.items())
                if h.limit is not None],
        parameters=[(p.name, repr(to_double(p.value))) for p in an.mechanism.parameters],
        points=list(plan.points), levels=plan.levels, all_levels=level_table.LEVELS,
        n_theta=len(an.thetas), input_index=[a - 1 for a in kin.inputs],
        unknown_index=[a - 1 for a in kin.unknowns], k=len(kin.unknowns),
        n_dyads=len(an.rigid.dyads), closed_form=plan.closed_form,
        needs_loops=plan.needs_loops, routines={r["name"]: r for r in routines},
        kernels=[kernels.source(k) for k in special_functions(plan)],
    )
    return render("c/header.h.j2", **context), render("c/source.c.j2", **context)
