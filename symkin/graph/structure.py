"""Graph structure of a mechanism (paper §2): regular labeling, skeleton tree, I, I+, Φ, Ψ = [T; 0].

Everything here is integer bookkeeping from graph traversal; no matrix is ever inverted.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..core.errors import InputError
from ..model.mechanism import Mechanism


def _frozen(rows: list[list[int]], shape: tuple[int, int]) -> np.ndarray:
    array = np.array(rows, dtype=np.int64).reshape(shape)
    array.setflags(write=False)
    return array


@dataclass(frozen=True, eq=False)
class Structure:
    """The labeled graph of a mechanism and its structure matrices (all integer, read-only).

    Labels follow the paper: links s_0..s_n (s_0 the ground), hinges u_1..u_m with the skeleton
    tree's hinges 1..n (hinge a joins link a to a smaller label) and the chords n+1..m.
    """

    mechanism: Mechanism
    links: tuple[str, ...]  # link names by label 0..n
    hinges: tuple[str, ...]  # hinge names by label 1..m (position a-1)
    i_plus: tuple[int, ...]  # i+(a): the smaller label, reference link of hinge a
    i_minus: tuple[int, ...]  # i-(a): the larger label
    parent: tuple[int, ...]  # parent[i-1] = label of link i's parent in the skeleton tree
    basic_chain: tuple[int, ...]  # labels 1..i* of the basic chain
    relabeled: bool  # False when the file's order already was a regular labeling
    incidence: np.ndarray  # I, (n+1) x m
    incidence_plus: np.ndarray  # I+, (n+1) x m
    loops: np.ndarray  # Φ, (m-n) x m
    paths: np.ndarray  # Ψ = [T; 0], m x n

    @property
    def n(self) -> int:
        return len(self.links) - 1

    @property
    def m(self) -> int:
        return len(self.hinges)

    @property
    def T(self) -> np.ndarray:
        """T = S̆⁻¹, the upper n rows of Ψ."""
        return self.paths[: self.n]

    @property
    def chords(self) -> tuple[str, ...]:
        return self.hinges[self.n :]

    def hinge_label(self, name: str) -> int:
        """Label a (1-based) of the named hinge."""
        return self.hinges.index(name) + 1

    def tree_path(self, label: int) -> tuple[int, ...]:
        """Hinge labels on the direct path [s_0, s_label], from the ground outward."""
        path = []
        while label != 0:
            path.append(label)
            label = self.parent[label - 1]
        return tuple(reversed(path))

    def loop_hinges(self, chord: int) -> tuple[int, ...]:
        """Hinge labels of the fundamental loop of `chord` (a label > n), in label order."""
        row = self.loops[chord - self.n - 1]
        return tuple(int(b) + 1 for b in np.flatnonzero(row))

    def loop_text(self, chord: int) -> str:
        """The fundamental loop of `chord` as a signed sum of hinge names, e.g. 'A0 + A - B0 +
        B'."""
        row = self.loops[chord - self.n - 1]
        terms = [("+ " if v > 0 else "- ") + self.hinges[b] for b, v in enumerate(row) if v]
        text = " ".join(terms)
        return text[2:] if text.startswith("+ ") else "-" + text[2:]

    def mapping(self) -> list[tuple[str, str, int]]:
        """(kind, name, label) for every link and hinge: the labeling, for reports."""
        return [("link", name, i) for i, name in enumerate(self.links)] + [
            ("hinge", name, a + 1) for a, name in enumerate(self.hinges)
        ]


def build(mech: Mechanism) -> Structure:
    """Label the mechanism regularly and compute I, I+, Φ and Ψ by traversal."""
    file_links = [lk.name for lk in mech.links]
    chords = set(mech.chords or ())
    candidates = [h for h in mech.hinges if h.name not in chords]
    label: dict[str, int] = {mech.ground: 0}
    tree_edge: list[str] = []  # tree_edge[i-1] = hinge joining link i to its parent
    parent: list[int] = []

    def joining(link: str, labeled_only: str | None = None) -> str | None:
        """Earliest candidate hinge joining `link` to a labeled link (or to `labeled_only`)."""
        for h in candidates:
            if link in h.links:
                other = h.links[1] if h.links[0] == link else h.links[0]
                if other in label and (labeled_only is None or other == labeled_only):
                    return h.name
        return None

    def attach(link: str, hinge_name: str) -> None:
        h = mech.hinge(hinge_name)
        other = h.links[1] if h.links[0] == link else h.links[0]
        label[link] = len(label)
        tree_edge.append(hinge_name)
        parent.append(label[other])

    previous = mech.ground
    for link in mech.basic_chain or ():
        if link == mech.ground and previous == mech.ground and not tree_edge:
            continue
        if link in label:
            raise InputError(
                f"link '{link}' appears twice on the basic chain or is the ground",
                file=mech.path,
                entry="basic_chain",
                hint="list the chain's links from the ground outward, once each",
            )
        hinge = joining(link, previous)
        if hinge is None:
            on_chord = [
                h.name for h in mech.hinges if h.name in chords and set(h.links) == {link, previous}
            ]
            if on_chord:
                raise InputError(
                    f"the chord '{on_chord[0]}' lies on the basic chain between "
                    f"'{previous}' and '{link}'",
                    file=mech.path,
                    entry="chords",
                    hint="a chord may never lie on the basic chain; choose another",
                )
            raise InputError(
                f"no hinge joins '{previous}' and '{link}'",
                file=mech.path,
                entry="basic_chain",
                hint="consecutive links of the basic chain must share a hinge",
            )
        attach(link, hinge)
        previous = link

    while len(label) < len(file_links):
        for link in file_links:  # the unlabeled link first in file order...
            if link not in label:
                hinge = joining(link)  # ...that a non-chord hinge reaches
                if hinge is not None:
                    attach(link, hinge)
                    break
        else:
            lost = [lk for lk in file_links if lk not in label]
            raise InputError(
                f"the chords leave link(s) {', '.join(lost)} outside the skeleton tree",
                file=mech.path,
                entry="chords",
                hint="name fewer chords: the other hinges must form a spanning tree",
            )

    links = tuple(sorted(label, key=label.get))
    tree = set(tree_edge)
    hinges = tuple(tree_edge) + tuple(h.name for h in mech.hinges if h.name not in tree)
    n, m = len(links) - 1, len(hinges)
    i_plus, i_minus = [], []
    for name in hinges:
        p, q = (label[x] for x in mech.hinge(name).links)
        i_plus.append(min(p, q))
        i_minus.append(max(p, q))

    incidence = [[0] * m for _ in range(n + 1)]
    incidence_plus = [[0] * m for _ in range(n + 1)]
    for a in range(m):
        incidence[i_plus[a]][a] = 1
        incidence[i_minus[a]][a] = -1
        incidence_plus[i_plus[a]][a] = 1

    # Ψ: hinge a on [s_0, s_i] is a tree edge pointing away from s_0 (i+ < i-), so ψ_ai = -1.
    paths = [[0] * n for _ in range(m)]
    for i in range(1, n + 1):
        k = i
        while k != 0:
            paths[k - 1][i - 1] = -1
            k = parent[k - 1]

    # Φ row of chord c: +1 on c; on the tree, the path i-(c) -> s_0 -> i+(c) walked in the
    # chord's sense, which is ψ(:, i-(c)) - ψ(:, i+(c)).
    def psi(a: int, i: int) -> int:
        return 0 if i == 0 else paths[a][i - 1]

    loops = []
    for c in range(n, m):
        row = [psi(b, i_minus[c]) - psi(b, i_plus[c]) for b in range(n)] + [0] * (m - n)
        row[c] = 1
        loops.append(row)

    chain = []
    while len(chain) < n and parent[len(chain)] == len(chain):
        chain.append(len(chain) + 1)

    relabeled = list(links) != file_links or list(hinges) != [h.name for h in mech.hinges]
    return Structure(
        mechanism=mech,
        links=links,
        hinges=hinges,
        i_plus=tuple(i_plus),
        i_minus=tuple(i_minus),
        parent=tuple(parent),
        basic_chain=tuple(chain),
        relabeled=relabeled,
        incidence=_frozen(incidence, (n + 1, m)),
        incidence_plus=_frozen(incidence_plus, (n + 1, m)),
        loops=_frozen(loops, (m - n, m)),
        paths=_frozen(paths, (m, n)),
    )
