"""Dependency pruning: the part of a mechanism that moves the requested points (docs/pruning.md).

Links welded by input hinges form bodies (their relative angle is given). Each unknown body has
three pose variables, each hinge between two bodies two closure equations; the file's mobility
check makes the system square. A maximum matching of equations to variables orders it block
triangular (the Dulmage–Mendelsohn decomposition: the Assur groups, in the order a rigid solve
assembles them), so the bodies a point's body depends on are those reachable from it through the
equations matched to its variables. Those bodies, the ground and the hinges among them are a
mechanism of their own whose loops close without the rest: the kinematic levels of a point are
the same in it, and nothing else need be derived, generated or solved.

The physical levels (docs/physics.md) also carry forces: a plate's stiffness or a load anywhere
on a link that is hinged, directly or through other moving links, to a kept link changes the
kept plates' forces. Only the frame stops them, so for those levels every moving link connected
to a kept one other than through the ground is kept as well.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass

from ..core.levels import LOADED, loaded_by_default
from ..model.mechanism import Mechanism
from .structure import Structure, build


@dataclass(frozen=True)
class Pruning:
    """What a pruned derivation keeps of the file's mechanism, and why."""

    points: tuple[str, ...]  # the requested points
    physical: bool  # force paths were followed too (physical levels)
    kept_links: tuple[str, ...]  # in file order, the ground first
    dropped_links: tuple[str, ...]
    dropped_hinges: tuple[str, ...]
    dropped_inputs: tuple[str, ...]
    kept_loops: int  # independent loops (m - n) kept and dropped
    dropped_loops: int

    @property
    def pruned(self) -> bool:
        return bool(self.dropped_links or self.dropped_hinges)

    def notes(self) -> list[str]:
        """Lines for the generated headers and the report (empty when nothing was dropped)."""
        if not self.pruned:
            return []
        why = (
            "their loops neither move the points nor, through their plates and loads, "
            "change the forces on the links that do"
            if self.physical
            else "their loops do not move the points"
        )
        lines = [
            f"Pruned for the points {', '.join(self.points)}: kept {self.kept_loops} of "
            f"{self.kept_loops + self.dropped_loops} loop(s) and the links "
            f"{', '.join(self.kept_links)}; dropped the links "
            f"{', '.join(self.dropped_links) or '(none)'} and the hinges "
            f"{', '.join(self.dropped_hinges)} ({why})."
        ]
        if self.dropped_inputs:
            one = len(self.dropped_inputs) == 1
            lines.append(
                f"  The input{'' if one else 's'} {', '.join(self.dropped_inputs)} "
                f"move{'s' if one else ''} none of the points and "
                f"{'is' if one else 'are'} not an argument of this evaluator."
            )
        return lines


def for_levels(
    mech: Mechanism, points: Sequence[str], levels: Sequence[str] | None
) -> tuple[Mechanism, Pruning]:
    """:func:`prune` for a derivation of `levels` (None: every generated level the file's data
    allows): force paths are followed when it holds a physical level, the file's direct paths
    kept when it holds `paper`."""
    physical = loaded_by_default(mech) if levels is None else any(lv in LOADED for lv in levels)
    return prune(mech, points, physical, paths=levels is None or "paper" in levels)


def needed_links(
    mech: Mechanism,
    points: Sequence[str],
    physical: bool = False,
    paths: bool = True,
    structure: Structure | None = None,
) -> set[str]:
    """The links the requested points' positions depend on (the ground included); with
    `physical`, also every link their forces reach other than through the ground; with `paths`
    (the `paper` level is derived), also the links on the points' direct paths of the file's
    skeleton tree, over which (4.8) sums, and what places them (`structure`: the file's, when
    already built)."""
    mech.check_points(points)
    body = _bodies(mech)
    depends = _dependencies(mech, body)
    if depends is None:  # structurally singular: keep everything
        return {lk.name for lk in mech.links}
    carriers = {mech.point(p).link for p in points}
    if paths:
        s = structure or build(mech)
        carriers |= {
            s.links[s.i_minus[a - 1]]
            for p in points
            for a in s.tree_path(s.links.index(mech.point(p).link))
        }
    todo = [body[link] for link in carriers]
    bodies: set[str] = {body[mech.ground]}
    while todo:
        b = todo.pop()
        if b not in bodies:
            bodies.add(b)
            todo.extend(depends[b])
    kept = _welded_links(mech, body, bodies, carriers)
    if physical:
        kept |= _force_reach(mech, kept)
    return kept


def prune(
    mech: Mechanism, points: Sequence[str], physical: bool = False, paths: bool = True
) -> tuple[Mechanism, Pruning]:
    """The mechanism of the links `points` depend on (see :func:`needed_links`): its hinges are
    those between kept links, its points the requested ones, its loads those on kept links. Its
    skeleton tree keeps every edge of the file's tree among the kept links (so the points'
    direct paths, and the `paper` level, are the file's); a kept link whose tree edge was
    dropped hangs on the first kept hinge, in file order, that reaches it."""
    full = build(mech)
    kept = needed_links(mech, points, physical, paths, full)
    links = tuple(lk for lk in mech.links if lk.name in kept)
    hinges = tuple(h for h in mech.hinges if set(h.links) <= kept)
    hinge_names = {h.name for h in hinges}
    if len(hinges) == len(mech.hinges) and len(links) == len(mech.links):
        sub = dataclasses.replace(mech, points=tuple(p for p in mech.points if p.name in points))
    else:
        tree = [name for name in full.hinges[: full.n] if name in hinge_names]
        root = {lk.name: lk.name for lk in links}
        chosen = []
        for name in tree + [h.name for h in hinges]:
            a, b = (_find(root, x) for x in mech.hinge(name).links)
            if a != b:
                root[a] = b
                chosen.append(name)
        chain: list[str] = []
        for name in mech.basic_chain or ():
            if name not in kept:
                break
            chain.append(name)
        sub = dataclasses.replace(
            mech,
            links=links,
            hinges=hinges,
            points=tuple(p for p in mech.points if p.name in points),
            loads=tuple(ld for ld in mech.loads if ld.link in kept),
            chords=tuple(h.name for h in hinges if h.name not in chosen),
            basic_chain=None if mech.basic_chain is None else tuple(chain),
        )
    order = [p.name for p in mech.points if p.name in points]
    ground_first = (mech.ground,) + tuple(lk.name for lk in links if lk.name != mech.ground)
    return sub, Pruning(
        points=tuple(order),
        physical=physical,
        kept_links=ground_first,
        dropped_links=tuple(lk.name for lk in mech.links if lk.name not in kept),
        dropped_hinges=tuple(h.name for h in mech.hinges if h.name not in hinge_names),
        dropped_inputs=tuple(n for n in mech.inputs if n not in hinge_names),
        kept_loops=sub.loop_count,
        dropped_loops=mech.loop_count - sub.loop_count,
    )


def _bodies(mech: Mechanism) -> dict[str, str]:
    """Link -> its body (the first of its links in file order): links welded by input hinges."""
    root = {lk.name: lk.name for lk in mech.links}
    order = {lk.name: k for k, lk in enumerate(mech.links)}
    for h in mech.hinges:
        if h.input:
            a, b = sorted((_find(root, h.links[0]), _find(root, h.links[1])), key=order.get)
            root[b] = a
    return {lk.name: _find(root, lk.name) for lk in mech.links}


def _find(root: dict[str, str], x: str) -> str:
    """The representative of `x` in the union-find forest `root` (paths halved on the way)."""
    while root[x] != x:
        root[x] = root[root[x]]
        x = root[x]
    return x


def _dependencies(mech: Mechanism, body: dict[str, str]) -> dict[str, set[str]] | None:
    """Body -> the bodies its pose is solved from (through the equations matched to its three
    pose variables), or None when no matching covers every variable."""
    ground = body[mech.ground]
    variables = [
        (b, k)
        for b in dict.fromkeys(body[lk.name] for lk in mech.links)
        if b != ground
        for k in range(3)
    ]
    equations = []  # the two closure equations of every hinge
    for h in mech.hinges:
        if h.input:
            continue
        touched = [b for b in dict.fromkeys(body[x] for x in h.links) if b != ground]
        cols = [(b, k) for b in touched for k in range(3)]
        equations += [cols, cols]
    if len(equations) != len(variables):
        return None
    matched: dict[tuple[str, int], int] = {}  # variable -> equation

    def augment(e: int, seen: set) -> bool:
        for v in equations[e]:
            if v in seen:
                continue
            seen.add(v)
            if v not in matched or augment(matched[v], seen):
                matched[v] = e
                return True
        return False

    for e in range(len(equations)):
        if not augment(e, set()):
            return None
    depends: dict[str, set[str]] = {b: set() for b, _ in variables}
    for (b, _), e in matched.items():
        depends[b].update(c for c, _ in equations[e] if c != b)
    return depends


def _welded_links(
    mech: Mechanism, body: dict[str, str], bodies: set[str], carriers: set[str]
) -> set[str]:
    """The links of `bodies` that are needed: those carrying a point, hinged (not by an input) to
    a link of another kept body, or the ground, and the input hinges' chains joining them within
    their body (a crank welded to the ground that nothing kept is hinged to is left out)."""
    links = {lk.name for lk in mech.links if body[lk.name] in bodies}
    terminal = (carriers & links) | {mech.ground}
    welds = [h.links for h in mech.hinges if h.input and set(h.links) <= links]
    for h in mech.hinges:
        if not h.input and set(h.links) <= links and body[h.links[0]] != body[h.links[1]]:
            terminal.update(h.links)
    # the smallest part of each body's weld forest joining its terminals: strip other leaves
    changed = True
    while changed:
        changed = False
        for link in sorted(links - terminal):
            if sum(link in w and not (set(w) - links) for w in welds) <= 1:
                links.discard(link)
                changed = True
    return links


def _force_reach(mech: Mechanism, kept: set[str]) -> set[str]:
    """Every link connected to a kept moving link by hinges between moving links."""
    seen = {name for name in kept if name != mech.ground}
    todo = list(seen)
    while todo:
        link = todo.pop()
        for h in mech.hinges:
            if link in h.links:
                other = h.links[1] if h.links[0] == link else h.links[0]
                if other != mech.ground and other not in seen:
                    seen.add(other)
                    todo.append(other)
    return seen
