"""Generated families of mechanisms for the derivation benchmarks (TOML texts, docs/file-format.md).

- ``serial_chain(n)``: an open chain of n moving links on the ground, n hinges, every hinge an
  input, one point at the tip. No loops.
- ``ladder(k)``: k four-bar cells stacked into a ladder. Cell 1 is a four-bar on the ground
  (left upright, right upright, rung); every further cell is one RRR dyad — a new side link
  hinged to the previous rung and a new rung hinged to that side link and to the extended side
  link of the cell below — so each cell adds one loop, two links, three hinges and one dyad, and
  the mobility stays 1. The single input is the first ground hinge; one point sits on the top
  rung.
- ``fan(k)``: k copies of the paper's four-bar (examples/four_bar.toml) side by side on one
  frame, k inputs, k independent loops, a point C1 ... Ck on each coupler.

All plates are ``circular_arc`` of length l = 1e-3; links are about 0.05 m long. Coordinates are
written with at most 4 decimals, so the exact rationals symkin reads stay small.

Run ``python benchmarks/families.py`` to check that every member assembles (paper level, mpmath).
"""

from __future__ import annotations

import json
import math

LINK = 0.05  # typical link length, m
PLATE = "1e-3"  # plate length l, m


def _q(name: str) -> str:
    return json.dumps(name)


def _num(x: float) -> str:
    return repr(round(x, 4) + 0.0)


def _header(name: str) -> str:
    return (
        f'format = 1\nname = "{name}"\nground = "ground"\n\n[parameters]\nl = {PLATE}\n\n'
        '[defaults]\nmodel = "circular_arc"\nlength = "l"\n\n'
    )


def _links(names) -> str:
    return "".join(f"[[link]]\nname = {_q(n)}\n" for n in names)


def _hinge(
    name: str, p: str, m: str, x: float, y: float, angle: str = "0", input: bool = False
) -> str:
    return (
        f"\n[[hinge]]\nname = {_q(name)}\nlinks = [{_q(p)}, {_q(m)}]\n"
        f"at = [{_num(x)}, {_num(y)}]\nplate_angle = {_q(angle)}\n"
        + ("input = true\n" if input else "")
    )


def _point(name: str, link: str, x: float, y: float) -> str:
    return f"\n[[point]]\nname = {_q(name)}\nlink = {_q(link)}\nat = [{_num(x)}, {_num(y)}]\n"


def serial_chain(n: int) -> str:
    """n moving links in series (n hinges, all inputs), a point at the tip.

    The chain winds along a gentle arc (each link turned 10 degrees from the previous), so it
    stays in a few metres even for n = 64; the plates point along the link before them.
    """
    if n < 1:
        raise ValueError("n >= 1")
    names = ["ground"] + [f"s{i}" for i in range(1, n + 1)]
    text = _header(f"serial_{n}") + _links(names)
    x = y = 0.0
    heading = math.pi / 2
    for i in range(1, n + 1):
        text += _hinge(f"u{i}", names[i - 1], names[i], x, y, f"{round(heading, 4)}", input=True)
        x += LINK * math.cos(heading)
        y += LINK * math.sin(heading)
        heading -= math.radians(10)
    text += _point("tip", names[n], x, y)
    return text


def ladder(k: int) -> str:
    """k stacked four-bar cells (k loops, 2k+2 links, 3k+1 hinges, one input).

    Cell j (j >= 2) is bounded by the rung r{j-1} below, the new side link t{j} (on the side
    opposite the previous side link), the new rung r{j} and the previous side link t{j-1}
    extended upward. Sides alternate; the cells are slightly trapezoidal (no parallelograms).
    """
    if k < 1:
        raise ValueError("k >= 1")
    w, h = LINK, LINK
    names = ["ground", "t0", "t1", "r1"]
    for j in range(2, k + 1):
        names += [f"t{j}", f"r{j}"]
    text = _header(f"ladder_{k}") + _links(names)
    # cell 1: left upright t0 (input), right upright t1, rung r1.
    text += _hinge("g0", "ground", "t0", 0.0, 0.0, "pi/2", input=True)
    text += _hinge("g1", "ground", "t1", w, 0.0, "pi/2")
    top = {"t0": (0.004, h), "t1": (w, h)}  # upper hinge of each side link on its rung
    text += _hinge("a1", "t0", "r1", *top["t0"], "0")
    text += _hinge("b1", "r1", "t1", *top["t1"], "0")
    # side links: the newest one ("prev") and which side it is on (x coordinate of the rail).
    prev, prev_x = "t1", w
    for j in range(2, k + 1):
        new_x = 0.0 if prev_x > w / 2 else w
        inward = 0.006 if new_x == 0.0 else -0.006
        tilt = 0.003 if j % 2 else -0.002
        y0, y1 = (j - 1) * h, j * h
        # the new side link t{j} hinged to the rung below, a little inward from its end
        text += _hinge(f"c{j}", f"r{j - 1}", f"t{j}", new_x + inward, y0, "pi/2")
        # the new rung r{j}: on t{j} at the top and on the previous side link, extended
        text += _hinge(f"d{j}", f"t{j}", f"r{j}", new_x + inward + tilt, y1, "0")
        text += _hinge(f"e{j}", f"r{j}", prev, prev_x, y1, "0")
        prev, prev_x = f"t{j}", new_x
    text += _point("top", f"r{k}", w / 2, k * h + 0.01)
    return text


def fan(k: int) -> str:
    """k four-bars on one frame (k loops, 3k+1 links, 4k hinges, k inputs), 0.12 m apart.

    Cell j is the paper's crank-rocker (examples/four_bar.toml) shifted by 0.12 (j - 1) in x:
    crank a{j} (input at its ground hinge A0_{j}), coupler c{j} with the point C{j}, rocker
    r{j}.
    """
    if k < 1:
        raise ValueError("k >= 1")
    names = ["ground"]
    for j in range(1, k + 1):
        names += [f"a{j}", f"c{j}", f"r{j}"]
    text = _header(f"fan_{k}") + _links(names)
    for j in range(1, k + 1):
        x = 0.12 * (j - 1)
        text += _hinge(f"A0_{j}", "ground", f"a{j}", x, 0.0, "pi/2", input=True)
        text += _hinge(f"A_{j}", f"a{j}", f"c{j}", x + 0.015, 0.026, "pi/3")
        text += _hinge(f"B0_{j}", "ground", f"r{j}", x + 0.1, 0.0, "pi/2")
        text += _hinge(f"B_{j}", f"c{j}", f"r{j}", x + 0.085, 0.068, "0")
    for j in range(1, k + 1):
        text += _point(f"C{j}", f"c{j}", 0.12 * (j - 1) + 0.06, 0.09)
    return text


SERIAL_SIZES = (2, 4, 8, 16, 32, 64)
LADDER_SIZES = (1, 2, 4, 8, 16, 32)


def family(kind: str, size: int) -> str:
    return {"serial": serial_chain, "ladder": ladder, "fan": fan}[kind](size)


def check(sizes_serial=SERIAL_SIZES, sizes_ladder=LADDER_SIZES, angle: float = 0.05) -> None:
    """Every member loads, has the stated counts and assembles at a small input (paper level)."""
    import symkin

    for kind, sizes in (("serial", sizes_serial), ("ladder", sizes_ladder)):
        for n in sizes:
            mech = symkin.loads(family(kind, n), f"{kind}_{n}.toml")
            s = symkin.structure(mech)
            an = symkin.analyze(mech)
            inputs = dict.fromkeys(mech.inputs, angle)
            ev = symkin.evaluate(an, inputs, "paper", dps=20)
            dev = next(iter(ev.points.values())).deviation
            print(
                f"{kind:6} {n:3}: links {s.n + 1:3}, hinges {s.m:3}, loops {s.m - s.n:2}, "
                f"inputs {len(mech.inputs):2}, dyads {len(an.rigid.dyads):2}, "
                f"closed form {an.rigid.closed_form}, paper deviation {dev}",
                flush=True,
            )


if __name__ == "__main__":
    check()
