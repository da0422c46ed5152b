"""A single notch hinge as a plane-strain CalculiX continuum (docs/fea.md, "One notch").

A notch's thickness T(x) varies along its span by a factor of 10–100 (a circular notch of
radius R and thinnest thickness t is t at its centre and 2R + t at its ends), so a mesh of
columns equally spaced along the span either wastes elements in the thick ends or leaves the
neck coarse. Here the element columns are spaced in proportion to the local thickness: the
corners sit at equal steps of s(x) = ∫ dx/T, so every element has about the same aspect ratio
and the neck gets as many elements per thickness as the ends.

:func:`fea.profile_columns.columns` gives those positions for any T(x) (the mechanism's deck uses
them too, for a plate whose profile is not uniform); :func:`single_notch` writes the deck of one
notch in the plane of its axis — P's end face clamped, M's end face a rigid section (linear
`*EQUATION`s on a reference node at its centre and a rotation node), one step under a transverse
force on the reference node and one under a pure moment on the rotation node, small deflections
(no NLGEOM) — and :func:`solve` runs ccx on it and reads back the compliances at the centre of M's
end section, the displacement of the notch's centre and the stress at the neck's faces.

The deck is written in millimetres, newtons and megapascals: ccx 2.20 rejects the small elements
of a thin neck in metres ("nonpositive jacobian"), its tolerances being absolute.
"""

from __future__ import annotations

import math
import os
import re
import subprocess
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

from .ccx import ERROR, Failed, executable
from .profile_columns import Depth, column_count, columns

#: Element type: quadratic brick, reduced integration, one layer through the width with u_z = 0
#: on every node (plane strain without the MPCs ccx adds to CPE8 elements; docs/fea.md).
ELEMENT = "C3D20R"


def across_positions(count: int, grading: float = 0.0) -> list[float]:
    """The 2 count + 1 node positions over [0, 1] across the thickness: corners at
    η − g·sin(2πη)/(2π) (smaller towards both faces for g in (0, 1)), midside nodes halfway."""
    corners = [
        k / count - grading * math.sin(2 * math.pi * k / count) / (2 * math.pi)
        for k in range(count + 1)
    ]
    corners[0], corners[-1] = 0.0, 1.0
    out: list[float] = []
    for k in range(count):
        out += [corners[k], (corners[k] + corners[k + 1]) / 2]
    return out + [1.0]


@dataclass(frozen=True)
class NotchMesh:
    """Elements `across` the thickness everywhere, columns about `aspect` thicknesses/across
    long, corners graded towards the faces by `grading` (0: uniform)."""

    across: int
    aspect: float = 1.0
    grading: float = 0.0

    def __str__(self) -> str:
        return f"{self.across} across, aspect {self.aspect:g}, grading {self.grading:g}"


@dataclass(frozen=True)
class NotchDeck:
    """A single notch's deck and the nodes its results are read at."""

    text: str
    nodes: int
    elements: int
    reference: int  # centre of M's end section: u_1, u_2
    rotation: int  # M's end section's rotation: u_1
    centre: int  # the notch's centre (x = span/2, y = 0) on the face z = 0
    neck: tuple[int, int]  # the lower and upper face at x = span/2, z = 0
    force: float  # the transverse force of step 1 (N)
    moment: float  # the moment of step 2 (N mm)


def _number(v: float) -> str:
    return f"{v:.12g}"


def single_notch(
    depth: Depth,
    span: float,
    width: float,
    E: float,
    nu: float,
    mesh: NotchMesh,
    force: float = 1.0,
    moment: float = 1.0,
) -> NotchDeck:
    """The deck of one notch (millimetres, N, MPa): thickness `depth(x)` for x in [0, span]
    along the axis x, centred on y = 0, `width` b along z; P's end face (x = 0) clamped, M's end
    face (x = span) rigid, tied to a reference node at its centre (span, 0) and a rotation node by
    u_1 = U_1 − y·φ, u_2 = U_2; step 1 a `force` along y on the reference node, step 2 (the force
    removed) a `moment` about z on the rotation node. Linear (small deflections): the compliances
    are displacement / load."""
    nt = mesh.across
    count = column_count(depth, span, nt, mesh.aspect)
    along = columns(depth, span, count)
    across = across_positions(nt, mesh.grading)
    ni, nj = len(along), len(across)
    ids: dict[tuple[int, int, int], int] = {}
    node_lines = ["*NODE, NSET=NALL"]
    coords: dict[int, tuple[float, float, float]] = {}
    for i in range(ni):
        x = along[i]
        t = depth(x)
        for j in range(nj):
            y = t * (across[j] - 0.5)
            for kz in range(3):
                if (i % 2 and j % 2) or (kz == 1 and (i % 2 or j % 2)):
                    continue
                n = len(ids) + 1
                ids[i, j, kz] = n
                coords[n] = (x, y, width * kz / 2)
                node_lines.append(f"{n}, {_number(x)}, {_number(y)}, {_number(width * kz / 2)}")
    nodes = len(ids)
    ref, rot = nodes + 1, nodes + 2
    node_lines += [f"{ref}, {_number(span)}, 0, 0", f"{rot}, {_number(span)}, 0, 0"]
    element_lines = [f"*ELEMENT, TYPE={ELEMENT}, ELSET=EALL"]
    elements = 0
    for ei in range(count):
        for ej in range(nt):
            i, j = 2 * ei, 2 * ej
            corners = [(i, j), (i + 2, j), (i + 2, j + 2), (i, j + 2)]
            mids = [(i + 1, j), (i + 2, j + 1), (i + 1, j + 2), (i, j + 1)]
            order = (
                [ids[a, b, 0] for a, b in corners]
                + [ids[a, b, 2] for a, b in corners]
                + [ids[a, b, 0] for a, b in mids]
                + [ids[a, b, 2] for a, b in mids]
                + [ids[a, b, 1] for a, b in corners]
            )
            elements += 1
            line = [elements, *order]
            element_lines.append(", ".join(map(str, line[:16])) + ",")
            element_lines.append(", ".join(map(str, line[16:])))
    clamp = [n for (i, _, _), n in ids.items() if i == 0]
    end = [n for (i, _, _), n in ids.items() if i == ni - 1]
    # the notch's centre: the column nearest x = span/2 (exactly there when the count is even;
    # the profiles are symmetric, so columns() puts a corner or a midside node there)
    mid_i = min(range(ni), key=lambda i: abs(along[i] - span / 2))
    mid_j = nj // 2
    centre = ids.get((mid_i, mid_j, 0))
    if centre is None:  # (odd, odd) positions are not nodes: the centre of an element face
        raise ValueError("the notch's centre is not a node: use an even element count across")
    neck = (ids[mid_i, 0, 0], ids[mid_i, nj - 1, 0])

    def nset(name: str, members: list[int]) -> list[str]:
        out = [f"*NSET, NSET={name}"]
        out += [", ".join(map(str, members[k : k + 8])) for k in range(0, len(members), 8)]
        return out

    equations = ["*EQUATION"]
    for n in end:
        y = coords[n][1]
        equations += ["3", f"{n}, 1, 1., {ref}, 1, -1., {rot}, 1, {_number(y)}"]
        equations += ["2", f"{n}, 2, 1., {ref}, 2, -1."]
    lines = [
        "** one notch hinge in plane strain (symkin.fea.notch_mesh): units mm, N, MPa",
        f"** span {_number(span)} mm, width {_number(width)} mm, E {_number(E)} MPa, nu "
        f"{_number(nu)}; mesh {mesh}: {count} columns x {nt} elements",
        *node_lines,
        *element_lines,
        *nset("CLAMP", clamp),
        *nset("READ", [ref, rot, centre]),
        *nset("NECK", list(neck)),
        "*MATERIAL, NAME=STEEL",
        "*ELASTIC",
        f"{_number(E)}, {_number(nu)}",
        "*SOLID SECTION, ELSET=EALL, MATERIAL=STEEL",
        *equations,
        "*BOUNDARY",
        "CLAMP, 1, 3, 0.",
        "NALL, 3, 3, 0.",
        f"{rot}, 2, 3, 0.",
        "*STEP",
        "*STATIC",
        "*CLOAD",
        f"{ref}, 2, {_number(force)}",
        "*NODE PRINT, NSET=READ",
        "U",
        "*EL FILE, NSET=NECK",
        "S",
        "*END STEP",
        "*STEP",
        "*STATIC",
        "*CLOAD, OP=NEW",
        f"{rot}, 1, {_number(moment)}",
        "*NODE PRINT, NSET=READ",
        "U",
        "*EL FILE, NSET=NECK",
        "S",
        "*END STEP",
    ]
    return NotchDeck(
        "\n".join(lines) + "\n",
        nodes,
        elements,
        ref,
        rot,
        centre,
        neck,
        force,
        moment,
    )


@dataclass(frozen=True)
class NotchResult:
    """One notch's answers at the centre of M's end section (mm, N, N mm, MPa): the compliances
    C_yF, C_θF (rotation per force), C_θM, C_yM (deflection per moment); under the moment, the
    displacement of the notch's centre (x, y) and the axial stress at the neck's faces."""

    y_F: float
    theta_F: float
    theta_M: float
    y_M: float
    centre_M: tuple[float, float]
    neck_stress_M: tuple[float, float]
    nodes: int
    elements: int
    seconds: float


BLOCK = re.compile(r"^\s*(\w+) \(.*\) for set (\S+) and time\s+(\S+)")


def blocks(text: str) -> list[tuple[str, str, dict[int, tuple[float, ...]]]]:
    """The printed blocks of a .dat file in order: (quantity, set, {node: values})."""
    out: list[tuple[str, str, dict[int, tuple[float, ...]]]] = []
    current: dict[int, tuple[float, ...]] | None = None
    for line in text.splitlines():
        m = BLOCK.match(line)
        if m:
            current = {}
            out.append((m.group(1), m.group(2), current))
            continue
        parts = line.split()
        if current is not None and len(parts) >= 2 and parts[0].isdigit():
            current[int(parts[0])] = tuple(float(p) for p in parts[1:])
        elif parts and current is not None:
            current = None
    return out


def frd_stresses(text: str) -> list[dict[int, tuple[float, ...]]]:
    """The nodal stress blocks of a .frd file in order: {node: (sxx, syy, szz, sxy, syz, szx)}
    (ccx's extrapolation of the integration points, averaged over the elements at the node)."""
    out: list[dict[int, tuple[float, ...]]] = []
    current: dict[int, tuple[float, ...]] | None = None
    for line in text.splitlines():
        if line.startswith(" -4  "):
            current = {} if line.split()[1] == "STRESS" else None
            if current is not None:
                out.append(current)
        elif line.startswith(" -1") and current is not None:
            # fixed columns: the node in 10 characters after " -1", then values 12 wide
            node = int(line[3:13])
            current[node] = tuple(float(line[13 + 12 * k : 25 + 12 * k]) for k in range(6))
        elif line.startswith(" -3"):
            current = None
    return out


def solve(deck: NotchDeck, name: str = "notch") -> NotchResult:
    """Run ccx (one thread) on a single notch's deck and read its compliances; ccx stopping
    with an error raises ccx.Failed (its output in `log`)."""
    with tempfile.TemporaryDirectory(prefix="symkin-notch-") as tmp:
        folder = Path(tmp)
        (folder / f"{name}.inp").write_text(deck.text, encoding="ascii")
        start = time.perf_counter()
        proc = subprocess.run(
            [executable(), "-i", name],
            cwd=folder,
            env={**os.environ, "OMP_NUM_THREADS": "1"},
            capture_output=True,
            text=True,
            errors="replace",
            check=False,
        )
        seconds = time.perf_counter() - start
        dat = folder / f"{name}.dat"
        text = dat.read_text(errors="replace") if dat.exists() else ""
        frd = folder / f"{name}.frd"
        stresses = frd_stresses(frd.read_text(errors="replace")) if frd.exists() else []
    errors = ERROR.findall(proc.stdout) + ERROR.findall(text)
    found = blocks(text)
    if proc.returncode != 0 or errors or len(found) != 2 or len(stresses) != 2:
        quote = " / ".join(e.strip() for e in errors) or proc.stdout.strip()[-300:]
        raise Failed(f"ccx failed on the notch deck (exit {proc.returncode}): {quote}", proc.stdout)
    (_, _, u_f), (_, _, u_m) = found
    s_m = stresses[1]
    lo, hi = deck.neck
    return NotchResult(
        y_F=u_f[deck.reference][1] / deck.force,
        theta_F=u_f[deck.rotation][0] / deck.force,
        theta_M=u_m[deck.rotation][0] / deck.moment,
        y_M=u_m[deck.reference][1] / deck.moment,
        centre_M=(u_m[deck.centre][0], u_m[deck.centre][1]),
        neck_stress_M=(s_m[lo][0], s_m[hi][0]),
        nodes=deck.nodes,
        elements=deck.elements,
        seconds=seconds,
    )
