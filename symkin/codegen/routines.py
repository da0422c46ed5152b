"""Routines: the functions every backend emits, as CSE'd straight-line programs of sympy
assignments.

A routine has named array arguments (inputs, params, theta, delta, ...), an ordered list of named
intermediates (already named as they were built, OpenSYMORO style) and outputs, laid out as named
row-major blocks (A, then r; dD/dtheta, then dD/dv; ...) that the runtimes read by name
(docs/runtime.md). `optimize` runs one CSE pass over the whole routine and schedules each
temporary just before its first use, so the named intermediates keep their order and nothing is
computed twice.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace
from functools import cached_property

import sympy as sp

from ..core.recent import Recent


@dataclass(frozen=True)
class Argument:
    """An array argument of a routine: its name and the symbols of its entries, in order."""

    name: str
    symbols: tuple[sp.Symbol, ...]


@dataclass(frozen=True)
class Block:
    """A named rows x cols row-major block of a routine's outputs (or of an argument), starting
    at `offset`."""

    name: str
    rows: int
    cols: int
    offset: int

    @property
    def size(self) -> int:
        return self.rows * self.cols

    @property
    def end(self) -> int:
        return self.offset + self.size


def layout(*shapes: tuple[str, int, int]) -> tuple[Block, ...]:
    """Blocks (name, rows, cols) one after the other from offset 0."""
    blocks, offset = [], 0
    for name, rows, cols in shapes:
        blocks.append(Block(name, rows, cols, offset))
        offset += rows * cols
    return tuple(blocks)


@dataclass(frozen=True)
class Routine:
    """A straight-line program: arguments, assignments (symbol, expr) in order, outputs (the
    named `blocks` one after the other)."""

    name: str
    arguments: tuple[Argument, ...]
    assignments: tuple[tuple[sp.Symbol, sp.Expr], ...]
    outputs: tuple[sp.Expr, ...]
    doc: str = ""
    blocks: tuple[Block, ...] = ()

    def __post_init__(self) -> None:
        if self.blocks and self.blocks[-1].end != len(self.outputs):
            raise ValueError(f"routine {self.name}: its blocks do not cover its outputs")

    def block(self, name: str) -> Block:
        """The block `name` of the outputs."""
        for b in self.blocks:
            if b.name == name:
                return b
        raise KeyError(f"routine {self.name} has no block {name}")

    @cached_property
    def ops(self) -> int:
        """Operation count (sympy count_ops) of the assignments and outputs."""
        return int(
            sum(sp.count_ops(e) for _, e in self.assignments)
            + sum(sp.count_ops(e) for e in self.outputs)
        )


#: The last routines optimised, by content (a Routine compares by its fields, its expressions
#: structurally): plans of one file with other options (levels, points, fixed inputs, a
#: variant) share most of their routines, and CSE is the slowest step of a derivation.
_OPTIMIZED: Recent[tuple[Routine, str], Routine] = Recent(128)


def optimize(routine: Routine, prefix: str = "_tmp") -> Routine:
    """One CSE pass over the routine; temporaries are scheduled just before their first use.
    The same routine optimised again is the routine found before (the pass is deterministic)."""
    return _OPTIMIZED.get_or_make((routine, prefix), lambda: _optimize(routine, prefix))


def _optimize(routine: Routine, prefix: str) -> Routine:
    named = [s for s, _ in routine.assignments]
    exprs = [e for _, e in routine.assignments] + list(routine.outputs)
    symbols = sp.numbered_symbols(prefix, real=True)
    replacements, reduced = sp.cse(exprs, symbols=symbols, order="canonical")
    temps = dict(replacements)
    done: set[sp.Symbol] = set()
    lines: list[tuple[sp.Symbol, sp.Expr]] = []

    def need(expr: sp.Expr) -> None:
        for symbol in sorted(expr.free_symbols & set(temps), key=_index):
            if symbol not in done:
                need(temps[symbol])
                done.add(symbol)
                lines.append((symbol, temps[symbol]))

    for symbol, expr in zip(named, reduced[: len(named)]):
        need(expr)
        lines.append((symbol, expr))
    outputs = tuple(reduced[len(named) :])
    for expr in outputs:
        need(expr)
    return replace(routine, assignments=tuple(lines), outputs=outputs)


def _index(symbol: sp.Symbol) -> tuple[int, str]:
    digits = "".join(ch for ch in symbol.name if ch.isdigit())
    return (int(digits) if digits else 0, symbol.name)


def flatten(rows: Sequence[Sequence[sp.Expr]]) -> tuple[sp.Expr, ...]:
    """Row-major flattening of a matrix given as rows."""
    return tuple(e for row in rows for e in row)


def hoist(routine: Routine, varying: str, prefix: str = "_fix") -> tuple[Routine, Routine]:
    """`routine` split for a loop that calls it again and again with only the argument named
    `varying` changed (a Newton iteration's delta): `<name>_pre`, what depends on the other
    arguments alone, once, and `<name>`, reading those values from the argument `pre` instead
    of its first argument (the same arguments otherwise, the same outputs). Every assignment
    and every largest subexpression without the varying symbols moves into `<name>_pre`, so
    the loop computes no trigonometry of the fixed angles twice (docs/generated-code.md)."""
    moving = set(next(a for a in routine.arguments if a.name == varying).symbols)
    fixed_lines: list[tuple[sp.Symbol, sp.Expr]] = []
    lines: list[tuple[sp.Symbol, sp.Expr]] = []
    lifted: dict[sp.Expr, sp.Symbol] = {}
    names = sp.numbered_symbols(prefix, real=True)

    def lift(expr: sp.Expr) -> sp.Expr:
        if not expr.args:
            return expr
        if isinstance(expr, sp.Expr) and not expr.free_symbols & moving:
            # (a condition of a Piecewise stays where it is: only numbers move)
            if expr not in lifted:
                lifted[expr] = next(names)
            return lifted[expr]
        return expr.func(*(lift(a) for a in expr.args))

    for symbol, expr in routine.assignments:
        if expr.free_symbols & moving:
            moving.add(symbol)
            lines.append((symbol, lift(expr)))
        else:
            fixed_lines.append((symbol, expr))
    outputs = tuple(lift(sp.sympify(e)) for e in routine.outputs)
    # what the loop reads of the fixed side: the lifted subexpressions, then fixed names
    read: set[sp.Symbol] = set()
    for e in [e for _, e in lines] + list(outputs):
        read |= e.free_symbols
    carried = list(lifted.values()) + sorted(
        (s for s in read - moving - set(lifted.values())), key=_index
    )
    values = {s: e for e, s in lifted.items()}
    pre_args = tuple(a for a in routine.arguments if a.name != varying)
    pre = Routine(
        routine.name + "_pre",
        pre_args,
        tuple(fixed_lines),
        tuple(values.get(s, s) for s in carried),
        f"{routine.doc}: its terms without {varying}, once per solve",
        layout(("pre", len(carried), 1)),
    )
    first = routine.arguments[0]
    if first.name == varying:
        raise ValueError(f"routine {routine.name}: its first argument is the varying one")
    loop = replace(
        routine,
        # the other fixed arguments stay in the signature, read through `pre` alone
        arguments=(Argument("pre", tuple(carried)),)
        + tuple(a if a.name == varying else Argument(a.name, ()) for a in routine.arguments[1:]),
        assignments=tuple(lines),
        outputs=outputs,
    )
    return pre, loop
