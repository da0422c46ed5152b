"""Running CalculiX's `ccx` on a deck and reading the deviations back (docs/fea.md).

ccx runs in a private temporary folder; what it leaves there (.frd, .sta, .cvg, spooles.out) is
thrown away except the printed results, which are parsed from its .dat file.
"""

from __future__ import annotations

import math
import os
import re
import resource
import shutil
import subprocess
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from ._symkin import AssemblyError, InputError
from .deck import Deck

#: The Debian/Ubuntu package that installs ccx.
PACKAGE = "calculix-ccx"
#: Lines of ccx's output that say why it stopped.
ERROR = re.compile(r"^\s*\*ERROR.*$", re.MULTILINE)
INCREMENT = re.compile(r"^\s*increment\s+(\d+)\s+attempt\s+(\d+)")
TOTAL_TIME = re.compile(r"^\s*actual total time=\s*(\S+)")
BLOCK = re.compile(r"displacements \(vx,vy,vz\) for set (\S+) and time\s+(\S+)")


def executable() -> str:
    """The path of `ccx`; without it, bad input (exit 2) naming the package to install."""
    found = shutil.which("ccx")
    if found is None:
        raise InputError(
            "CalculiX's solver 'ccx' is not on PATH",
            entry="--run",
            hint=f"install it (Debian/Ubuntu: apt install {PACKAGE}), or drop --run "
            "to write the deck only",
        )
    return found


class Failed(AssemblyError):
    """ccx stopped short of the end of the step (exit 3); `log` is its output."""

    def __init__(self, message: str, log: str) -> None:
        super().__init__(message)
        self.log = log


@dataclass(frozen=True)
class Run:
    """What a ccx run gave: the displacements of the printed nodes at the step's end, the
    wall-clock time and ccx's own output."""

    displacements: dict[int, tuple[float, float, float]]
    seconds: float
    cpu_seconds: float  # ccx's own processor time (user + system): what the machine
    # load does not change
    log: str
    results: bytes  # the .frd file (displacements and stresses at the step's end)
    printed: str  # the .dat file


def run(
    deck: Deck, name: str, progress: Callable[[str], None] | None = None, threads: int | None = None
) -> Run:
    """Run ccx on `deck` (job `name`) in a temporary folder; a run that stops short of the end
    of the step (no convergence) raises Failed, an AssemblyError (exit 3), quoting ccx's
    message."""
    ccx = executable()
    env = dict(os.environ)
    if threads is not None:
        env["OMP_NUM_THREADS"] = str(threads)
    env.setdefault("OMP_NUM_THREADS", "1")
    with tempfile.TemporaryDirectory(prefix="symkin-fea-") as tmp:
        folder = Path(tmp)
        (folder / f"{name}.inp").write_text(deck.text, encoding="ascii")
        start = time.perf_counter()
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        lines: list[str] = []
        increment, attempt = 0, 0
        factor, reached = 0.0, 0.0  # the increment's load factor, the last converged
        with subprocess.Popen(
            [ccx, "-i", name],
            cwd=folder,
            env=env,
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            stdin=subprocess.DEVNULL,
            text=True,
            errors="replace",
        ) as proc:
            assert proc.stdout is not None
            for line in proc.stdout:
                lines.append(line)
                m = INCREMENT.match(line)
                if m:
                    increment, attempt = int(m.group(1)), int(m.group(2))
                    continue
                if line.strip() == "convergence":
                    reached = factor
                    continue
                m = TOTAL_TIME.match(line)
                if m:
                    factor = float(m.group(1))
                if m and progress is not None:
                    retry = f" (attempt {attempt})" if attempt > 1 else ""
                    progress(
                        f"ccx: increment {increment}{retry}, load factor "
                        f"{float(m.group(1)):.3g}, {time.perf_counter() - start:.1f} s"
                    )
            code = proc.wait()
        seconds = time.perf_counter() - start
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
        log = "".join(lines)
        dat = folder / f"{name}.dat"
        text = dat.read_text(errors="replace") if dat.exists() else ""
        frd = folder / f"{name}.frd"
        results = frd.read_bytes() if frd.exists() else b""
    errors = ERROR.findall(log) + ERROR.findall(text)
    blocks = parse(text)
    if code != 0 or errors or not blocks or not math.isclose(blocks[-1][0], 1.0, rel_tol=1e-6):
        where = f"; it reached load factor {reached:.4g} of 1" if reached else ""
        quote = (
            " / ".join(dict.fromkeys(e.strip() for e in errors))
            or (log.strip().splitlines() or ["(no output)"])[-1].strip()
        )
        raise Failed(f"ccx did not finish the step (exit code {code}{where}): {quote}", log)
    return Run(blocks[-1][1], seconds, cpu, log, results, text)


def parse(text: str) -> list[tuple[float, dict[int, tuple[float, float, float]]]]:
    """The displacement blocks of a .dat file's static step: (time, {node: (u1, u2, u3)}), in
    order."""
    out: list[tuple[float, dict[int, tuple[float, float, float]]]] = []
    current: dict[int, tuple[float, float, float]] | None = None
    for line in text.splitlines():
        if "E I G E N V A L U E" in line:  # a frequency step's modes follow the static step
            break
        m = BLOCK.search(line)
        if m:
            current = {}
            out.append((float(m.group(2)), current))
            continue
        parts = line.split()
        if current is not None and len(parts) == 4 and parts[0].isdigit():
            current[int(parts[0])] = (float(parts[1]), float(parts[2]), float(parts[3]))
        elif parts and current is not None and not parts[0].isdigit():
            current = None
    return out
