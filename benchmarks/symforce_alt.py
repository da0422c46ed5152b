"""The alternative SymForce: the same routines generated as C++ by SymForce (its own CSE, Eigen
types, symkin's kernels through override_methods), driven by benchmarks/symforce_driver.cc, a C++
copy of the generated evaluators' algorithm configured by a generated sk_config.h."""

from __future__ import annotations

import ctypes
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
from common import BENCH, CXX_FLAGS, EIGEN, POLICY, log
from lambdify_alt import substituted


def symforce_status(install: bool = True) -> dict:
    """Whether SymForce, its Eigen headers and a C++ compiler are there; with `install`, a
    missing SymForce is pip-installed once."""

    def probe() -> str | None:
        r = subprocess.run(
            [sys.executable, "-c", "import symforce; print(symforce.__version__)"],
            capture_output=True,
            text=True,
        )
        return r.stdout.strip() if r.returncode == 0 else None

    version = probe()
    note = ""
    if version is None and not install:
        note = "SymForce is not installed"
    elif version is None:
        log("SymForce not importable: trying `pip install symforce` once")
        r = subprocess.run(
            [sys.executable, "-m", "pip", "install", "-q", "symforce"],
            capture_output=True,
            text=True,
        )
        version = probe()
        if version is None:
            tail = (r.stderr or r.stdout).strip().splitlines()[-1:] or ["(no output)"]
            note = f"pip install symforce failed: {tail[0][:200]}"
    if version is not None and not Path(EIGEN, "Eigen", "Core").exists():
        note = (
            f"SymForce {version} installed, but its C++ needs Eigen headers "
            f"({EIGEN}; apt-get install libeigen3-dev)"
        )
        return {"available": False, "version": version, "note": note}
    if version is not None and shutil.which("c++") is None:
        return {"available": False, "version": version, "note": "no C++ compiler"}
    return {"available": version is not None, "version": version, "note": note}


def symforce_build(plan, workdir: Path) -> tuple[Path, float]:
    """Generate the routines with SymForce (sympy symbolic API, its own CSE; the rigid dyad
    assignments substituted; symkin's stable kernels called through override_methods) and compile
    them with the driver. Returns (library, generation seconds)."""
    import symforce
    import sympy as sp

    if not getattr(symforce, "_symkin_bench_setup", False):
        symforce.set_symbolic_api("sympy")
        symforce.set_log_level("warning")
        symforce.set_epsilon_to_symbol()
        symforce._symkin_bench_setup = True
    import symforce.symbolic as sf
    from symforce.codegen import Codegen, CppConfig
    from symforce.values import Values

    from symkin.codegen.backends.c import kernels as c_kernels
    from symkin.model import special

    t0 = time.perf_counter()
    needed = ["rigid_points", "dev_exact"]
    if plan.unknown_index:
        needed += ["rigid", "rigid_res", "linear"]
    if plan.needs_loops:
        needed += ["newton"]
    raw = {k: plan.routines[k] for k in needed}
    outputs = {k: substituted(r) for k, r in raw.items()}
    kernels = special.used_names(*[e for outs in outputs.values() for e in outs])
    overrides = {sp.conjugate: ""}  # real scalars: conjugate(x) is printed as (x)
    for e in (e for outs in outputs.values() for e in outs):
        for f in sp.sympify(e).atoms(sp.Function):
            if type(f).__name__ in kernels:
                overrides[type(f)] = f"symkin_{type(f).__name__}"
    (workdir / "kernels.h").write_text(
        "#pragma once\n#include <math.h>\n" + c_kernels.support(kernels) + "\n"
    )
    for key, r in raw.items():
        inputs = Values()
        for a in r.arguments:
            inputs[a.name] = sf.Matrix(list(a.symbols)) if a.symbols else sf.Matrix([0])
        cfg = CppConfig(override_methods=overrides, extra_imports=["kernels.h"])
        cg = Codegen(inputs, Values(out=sf.Matrix(outputs[key])), cfg, name=key, return_key="out")
        cg.generate_function(output_dir=str(workdir), namespace="sk", skip_directory_nesting=True)
    gen_seconds = time.perf_counter() - t0
    config = {
        "SK_M": len(plan.hinges),
        "SK_K": len(plan.unknown_index),
        "SK_NIN": len(plan.inputs),
        "SK_NP": len(plan.points),
        "SK_NPAR": len(plan.parameters),
        "SK_ND": plan.n_dyads,
        "SK_HAS_UNKNOWNS": int(bool(plan.unknown_index)),
        "SK_NEEDS_LOOPS": int(plan.needs_loops),
        "SK_INPUT_INDEX": ", ".join(map(str, plan.input_index)) or "0",
        "SK_UNKNOWN_INDEX": ", ".join(map(str, plan.unknown_index)) or "0",
        "SK_POLISH": POLICY["polish"],
        "SK_ITERATIONS": POLICY["iterations"],
        "SK_STOP": repr(POLICY["stop"]),
        "SK_STALL": repr(POLICY["stall"]),
        "SK_STALL_RATIO": repr(POLICY["stall_ratio"]),
    }
    (workdir / "sk_config.h").write_text(
        "#pragma once\n"
        + "".join(f"#define {k} {v}\n" for k, v in config.items())
        + "".join(f'#include "{key}.h"\n' for key in raw)
    )
    shutil.copy(BENCH / "symforce_driver.cc", workdir / "symforce_driver.cc")
    lib = workdir / "libsf_bench.so"
    proc = subprocess.run(
        [
            "c++",
            *CXX_FLAGS,
            f"-I{EIGEN}",
            "-I.",
            "-shared",
            "symforce_driver.cc",
            "-o",
            str(lib),
            "-lm",
        ],
        cwd=workdir,
        capture_output=True,
        text=True,
    )
    if proc.returncode != 0:
        raise RuntimeError("SymForce C++ did not compile:\n" + proc.stderr[-3000:])
    return lib, gen_seconds


class SFBench:
    """The compiled SymForce driver: `run` evaluates points, `per_point` times them in C++."""

    def __init__(self, lib: Path, n_inputs: int, n_points: int, params: list[float]):
        self.lib = ctypes.CDLL(str(lib))
        d = ctypes.POINTER(ctypes.c_double)
        self.loop = self.lib.sf_bench_loop
        self.loop.restype = ctypes.c_double
        self.loop.argtypes = [d, ctypes.c_int, d, ctypes.c_int, d, ctypes.POINTER(ctypes.c_int)]
        self.n_inputs, self.n_points = n_inputs, n_points
        self.params = np.asarray(params, float)

    def run(self, x, reps=1):
        x = np.ascontiguousarray(x, dtype=float).reshape(-1, self.n_inputs)
        out = np.zeros((len(x), self.n_points, 6))
        fails = ctypes.c_int(0)
        d = ctypes.POINTER(ctypes.c_double)
        secs = self.loop(
            x.ctypes.data_as(d),
            len(x),
            self.params.ctypes.data_as(d),
            reps,
            out.ctypes.data_as(d),
            ctypes.byref(fails),
        )
        return secs, out, fails.value

    def per_point(self, x, min_time=0.3, repeat=3):
        secs, _, _ = self.run(x, 1)
        reps = max(1, int(min_time / max(secs, 1e-9)))
        return min(self.run(x, reps)[0] for _ in range(repeat)) / (reps * len(x))
