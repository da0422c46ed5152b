"""symkin benchmarks: one command, every number of issue 5 in one run.

    python benchmarks/run.py [--quick] [--no-readme] [--budget SECONDS]

Measures, on this machine:

1. Per point, exact level, for each example: symkin's generated C (timed inside C), symkin's
   numpy module (vectorized over 10^4 points), `sympy.lambdify` of the same closed form with the
   same Newton loop in Python, `scipy.optimize.root` on the compliant loop equations, and
   SymForce-generated C++ for the same routines driven by the same algorithm (where SymForce
   installs). Every alternative is first checked to give the same deviation as the C evaluator.
2. Throughput: the numpy module on 10^6 points against the C evaluator called 10^6 times in a
   C loop.
3. Derivation (`symkin.derive.generate`, every available emitter, all levels) time and peak memory
   on the examples and on generated families (benchmarks/families.py), each in a fresh process,
   with growth exponents fitted by least squares on log-log.

Writes benchmarks/results.json (raw numbers) and rewrites only the README block between
`<!-- benchmarks:start -->` and `<!-- benchmarks:end -->` (read-modify-write at the very end).
"""

from __future__ import annotations

import argparse
import ctypes
import datetime
import importlib
import importlib.util
import json
import math
import os
import platform
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
BENCH = ROOT / "benchmarks"
sys.path.insert(0, str(BENCH))

import families  # noqa: E402
from symkin.levels import LEVELS, get as level  # noqa: E402
from symkin.solver import SOLVER  # noqa: E402

EXACT = level("exact").code

EXAMPLES = {
    # example -> input ranges (radians) sampled uniformly; all inside the assembly range
    "four_bar": {"A0": (-1.0, 1.0)},
    "stephenson_six_bar": {"O_A": (-0.5, 0.5)},
    "nine_bar_platform": {"O": (-0.1, 0.1), "A": (-0.1, 0.1), "B": (-0.1, 0.1),
                          "K": (-0.1, 0.1)},
}
# Compile flags for every timed C / C++ build: the same optimisation level symkin's runtime uses.
C_FLAGS = ["-std=c99", "-pedantic", "-Wall", "-Wextra", "-O2", "-fPIC"]
CXX_FLAGS = ["-std=c++14", "-O2", "-DNDEBUG", "-fPIC", "-w"]
EIGEN = "/usr/include/eigen3"
TOL = {"numpy": 1e-12, "lambdify": 1e-9, "lambdify_cse": 1e-9, "lambdify_cse_no_polish": 1e-9,
       "symforce": 1e-9, "scipy": 1e-5}
START, END = "<!-- benchmarks:start -->", "<!-- benchmarks:end -->"


#: The generated evaluators' iteration policy, which the lambdify and SymForce drivers below
#: follow step for step: symkin's solver settings in float64.
POLICY = {"polish": SOLVER.float64.polish, "stop": SOLVER.float64.converged,
          "stall": SOLVER.float64.stalled, "stall_ratio": SOLVER.stall_ratio,
          "iterations": SOLVER.exact_iterations}


def log(message: str) -> None:
    print(f"[{time.strftime('%H:%M:%S')}] {message}", file=sys.stderr, flush=True)


def best_time(fn, repeat: int = 3, min_time: float = 0.2) -> tuple[float, int]:
    """Best-of-`repeat` time of one call of fn, with calls batched to last at least min_time."""
    t0 = time.perf_counter()
    fn()
    once = time.perf_counter() - t0
    calls = max(1, int(min_time / max(once, 1e-9)))
    best = math.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        for _ in range(calls):
            fn()
        best = min(best, (time.perf_counter() - t0) / calls)
    return best, calls


def relerr(a, b) -> float:
    a, b = np.asarray(a, float), np.asarray(b, float)
    return float(np.linalg.norm(a - b) / max(np.linalg.norm(b), 1e-300))


# ------------------------------------------------------------------------------------------------
# machine
# ------------------------------------------------------------------------------------------------
def first_line(cmd: list[str]) -> str:
    try:
        return subprocess.run(cmd, capture_output=True, text=True).stdout.splitlines()[0]
    except (OSError, IndexError):
        return "unavailable"


def machine() -> dict:
    cpu = "unknown"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    import scipy
    import sympy

    info = {"cpu": cpu, "cores": os.cpu_count(), "system": f"{platform.system()} "
            f"{platform.release()} {platform.machine()}", "python": platform.python_version(),
            "numpy": np.__version__, "sympy": sympy.__version__, "scipy": scipy.__version__,
            "cc": first_line([os.environ.get("CC", "cc"), "--version"]),
            "cxx": first_line(["c++", "--version"]), "c_flags": " ".join(C_FLAGS),
            "mem_total_gb": None}
    try:
        kb = int(next(l for l in Path("/proc/meminfo").read_text().splitlines()
                      if l.startswith("MemTotal")).split()[1])
        info["mem_total_gb"] = round(kb / 2 ** 20, 1)
    except (OSError, StopIteration, ValueError):
        pass
    return info


# ------------------------------------------------------------------------------------------------
# SymForce availability (pip install tried once, by this script, if it is not importable)
# ------------------------------------------------------------------------------------------------
def symforce_status() -> dict:
    def probe() -> str | None:
        r = subprocess.run([sys.executable, "-c", "import symforce; print(symforce.__version__)"],
                           capture_output=True, text=True)
        return r.stdout.strip() if r.returncode == 0 else None

    version = probe()
    note = ""
    if version is None:
        log("SymForce not importable: trying `pip install symforce` once")
        r = subprocess.run([sys.executable, "-m", "pip", "install", "-q", "symforce"],
                           capture_output=True, text=True)
        version = probe()
        if version is None:
            tail = (r.stderr or r.stdout).strip().splitlines()[-1:] or ["(no output)"]
            note = f"pip install symforce failed: {tail[0][:200]}"
    if version is not None and not Path(EIGEN, "Eigen", "Core").exists():
        note = (f"SymForce {version} installed, but its C++ needs Eigen headers "
                f"({EIGEN}; apt-get install libeigen3-dev)")
        return {"available": False, "version": version, "note": note}
    if version is not None and shutil.which("c++") is None:
        return {"available": False, "version": version, "note": "no C++ compiler"}
    return {"available": version is not None, "version": version, "note": note}


# ------------------------------------------------------------------------------------------------
# symkin's C: compiled with a timing harness in a separate translation unit (no inlining)
# ------------------------------------------------------------------------------------------------
HARNESS_C = r"""
#define _POSIX_C_SOURCE 199309L
#include <stddef.h>
#include <time.h>
#include "{name}.h"

/* Calls {name}_evaluate on n_points input vectors, reps times; returns the elapsed seconds
   (CLOCK_MONOTONIC, measured here in C) and the number of non-zero statuses. */
double bench_loop(const double *inputs, int n_points, const double *params, int level, int reps,
                  double *out, int *failures)
{{
    struct timespec t0, t1;
    int r, i, fails = 0;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    for (r = 0; r < reps; ++r) {{
        for (i = 0; i < n_points; ++i) {{
            if ({name}_evaluate(inputs + (size_t)i * {NAME}_N_INPUTS, params, level,
                                out + (size_t)i * 6 * {NAME}_N_POINTS) != 0) {{
                ++fails;
            }}
        }}
    }}
    clock_gettime(CLOCK_MONOTONIC, &t1);
    *failures = fails;
    return (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec);
}}
"""


def compile_c(workdir: Path, name: str, header: str, code: str) -> Path:
    cc = os.environ.get("CC", "cc")
    (workdir / f"{name}.h").write_text(header)
    (workdir / f"{name}.c").write_text(code)
    (workdir / "harness.c").write_text(HARNESS_C.format(name=name, NAME=name.upper()))
    for src in (f"{name}.c", "harness.c"):
        subprocess.run([cc, *C_FLAGS, "-c", src, "-o", src + ".o"], cwd=workdir, check=True,
                       capture_output=True, text=True)
    lib = workdir / f"lib{name}_bench.so"
    subprocess.run([cc, "-shared", f"{name}.c.o", "harness.c.o", "-o", str(lib), "-lm"],
                   cwd=workdir, check=True, capture_output=True, text=True)
    return lib


class CBench:
    def __init__(self, lib: Path, name: str, n_inputs: int, n_points: int):
        self.lib = ctypes.CDLL(str(lib))
        d = ctypes.POINTER(ctypes.c_double)
        self.loop = self.lib.bench_loop
        self.loop.restype = ctypes.c_double
        self.loop.argtypes = [d, ctypes.c_int, d, ctypes.c_int, ctypes.c_int, d,
                              ctypes.POINTER(ctypes.c_int)]
        self.n_inputs, self.n_points = n_inputs, n_points

    def run(self, x: np.ndarray, level: int = EXACT, reps: int = 1) -> tuple[float, np.ndarray, int]:
        """(seconds for reps x len(x) calls, measured in C; out (N, n_points, 6); failures)."""
        x = np.ascontiguousarray(x, dtype=float).reshape(-1, self.n_inputs)
        out = np.zeros((len(x), self.n_points, 6))
        fails = ctypes.c_int(0)
        d = ctypes.POINTER(ctypes.c_double)
        secs = self.loop(x.ctypes.data_as(d), len(x), None, level, reps, out.ctypes.data_as(d),
                         ctypes.byref(fails))
        return secs, out, fails.value

    def per_point(self, x: np.ndarray, level: int = EXACT, min_time: float = 0.3,
                  repeat: int = 3) -> float:
        secs, _, _ = self.run(x, level, 1)
        reps = max(1, int(min_time / max(secs, 1e-9)))
        return min(self.run(x, level, reps)[0] for _ in range(repeat)) / (reps * len(x))


# ------------------------------------------------------------------------------------------------
# The alternatives
# ------------------------------------------------------------------------------------------------
def substituted(routine) -> list:
    """The routine's outputs with its named assignments substituted (one closed-form expression
    per output)."""
    import sympy as sp

    env: dict = {}
    for symbol, expr in routine.assignments:
        env[symbol] = sp.sympify(expr).xreplace(env)
    return [sp.sympify(o).xreplace(env) for o in routine.outputs]


class Pipeline:
    """What the generated evaluators do, with the routines given as Python callables:
    closed-form rigid angles, [rigid polish], first-order δ, Newton on δ, point positions."""

    def __init__(self, plan, fns: dict, polish: int = POLICY["polish"]):
        self.fns = fns
        self.m = len(plan.hinges)
        self.k = len(plan.unknown_index)
        self.nd = plan.n_dyads
        self.input_index = list(plan.input_index)
        self.unknown_index = list(plan.unknown_index)
        self.needs_loops = plan.needs_loops
        self.polish = polish
        self.params = [p.value for p in plan.parameters]

    def __call__(self, x) -> list[float]:
        k, p = self.k, self.params
        theta = [0.0] * self.m
        for j, i in enumerate(self.input_index):
            theta[i] = float(x[j])
        if k:
            sol = self.fns["rigid"](*x, *p)
            if any(r < 0 for r in sol[k:k + self.nd]):
                raise ArithmeticError("cannot assemble")
            for j, i in enumerate(self.unknown_index):
                theta[i] = math.remainder(sol[j], 2 * math.pi)
            for _ in range(self.polish):         # the C template's Newton polish steps
                res = self.fns["rigid_res"](*theta, *p)
                res = [math.remainder(r, 2 * math.pi) if n % 3 == 0 else r
                       for n, r in enumerate(res)]
                lin = self.fns["linear"](*theta, *p)
                step = np.linalg.solve(np.array(lin[:k * k], dtype=float).reshape(k, k),
                                       np.array(res, dtype=float))
                for j, i in enumerate(self.unknown_index):
                    theta[i] -= float(step[j])
        delta = [0.0] * k
        if self.needs_loops:
            lin = self.fns["linear"](*theta, *p)
            a = np.array(lin[:k * k], dtype=float).reshape(k, k)
            delta = list(np.linalg.solve(a, -np.array(lin[k * k:], dtype=float)))
            previous = math.inf
            for _ in range(POLICY["iterations"]):
                nw = self.fns["newton"](*theta, *delta, *p)
                step = np.linalg.solve(np.array(nw[k:], dtype=float).reshape(k, k),
                                       np.array(nw[:k], dtype=float))
                delta = [d - s for d, s in zip(delta, step)]
                size = max(abs(d) for d in delta)
                change = float(np.max(np.abs(step)))
                if (change <= POLICY["stop"] * size or size == 0.0
                        or (change >= POLICY["stall_ratio"] * previous
                            and change <= POLICY["stall"] * size)):
                    break
                previous = change
            else:
                raise ArithmeticError("no convergence")
        rigid = self.fns["rigid_points"](*theta, *p)
        return list(self.fns["dev_exact"](*theta, *delta, *p)), rigid


def lambdify_alternative(plan, cse: bool, polish: int = POLICY["polish"]):
    """`sympy.lambdify` (modules: symkin's float64 kernels, then `math`; one scalar call per point;
    `cse` as given) of the same closed-form expressions: the rigid dyad assignments substituted
    into the angle, reach and margin outputs, the loop Jacobian A and r, the exact closure F and
    dF/dδ, the deviation; driven by the same Newton loop in Python (numpy.linalg.solve for the
    small systems)."""
    import sympy as sp
    from symkin import special
    from symkin.codegen.backends.c import kernels as c_kernels
    from symkin.codegen.backends.numpy import kernels as np_kernels

    # conjugate: substituting the dyad assignments turns Abs(x)**2 into x*conjugate(x), which
    # `math` lacks; for real floats it is the identity.
    modules = [dict(np_kernels.float64_namespace(), conjugate=lambda z: z.conjugate()), "math"]
    fns = {}
    for key in ("rigid", "rigid_res", "linear", "newton", "rigid_points", "dev_exact"):
        r = plan.routines.get(key)
        if r is None:
            continue
        args = [s for a in r.arguments for s in a.symbols]
        outs = substituted(r)
        fns[key] = sp.lambdify(args, outs, modules=modules, cse=cse)
    return Pipeline(plan, fns, polish=polish)


def scipy_alternative(an):
    """`scipy.optimize.root` (hybr, xtol 1e-12) on the loop equations a user would write: per
    chord the angular closure Σ Φ q = 0 and the positional closure Σ Rot(φ_i) V_i (+ Φ Δz when
    compliant) = 0, lambdified with numpy, unknowns the non-input hinge angles. The rigid pose is
    solved from the as-fabricated pose (θ = 0), the compliant pose from the rigid one; the
    deviation is the compliant position (rigid position formula + Σ Δz over the path, at the
    compliant angles) minus the rigid position."""
    import sympy as sp
    from scipy.optimize import root
    from symkin import special
    from symkin.codegen.backends.c import kernels as c_kernels
    from symkin.codegen.backends.numpy import kernels as np_kernels

    kin = an.kin
    modules = [np_kernels.numpy_namespace(), "numpy"]
    params = list(an.params)
    thetas = list(an.thetas)
    rows_r, rows_c = [], []
    for c in kin.chords:
        rows_r.append(kin.angular_closure(c))
        rows_r.extend(kin.positional_closure(c, rigid=True))
        rows_c.append(kin.angular_closure(c))
        rows_c.extend(kin.positional_closure(c))
    f_rigid = sp.lambdify(thetas + params, rows_r, modules=modules)
    f_comp = sp.lambdify(thetas + params, rows_c, modules=modules)
    point = an.points[0]
    link = an.link[point.link]
    rig = list(kin.rigid_position(link, point.at))
    comp = [a + b for a, b in zip(rig, kin.path_deviation(link))]
    f_pos_r = sp.lambdify(thetas + params, rig, modules=modules)
    f_pos_c = sp.lambdify(thetas + params, comp, modules=modules)
    pvals = [float(p.value) for p in an.mechanism.parameters]
    inputs = [a - 1 for a in kin.inputs]
    unknown = [a - 1 for a in kin.unknowns]
    m = len(thetas)

    def full(x, u):
        th = np.zeros(m)
        th[inputs] = x
        th[unknown] = u
        return th

    def solve(x):
        x = np.asarray(x, float)
        th0 = np.zeros(len(unknown))
        if unknown:
            sr = root(lambda u: np.asarray(f_rigid(*full(x, u), *pvals), float), th0,
                      method="hybr", options={"xtol": 1e-12})
            sc = root(lambda u: np.asarray(f_comp(*full(x, u), *pvals), float), sr.x,
                      method="hybr", options={"xtol": 1e-12})
            if not (sr.success and sc.success):
                raise ArithmeticError(f"root: {sr.message} / {sc.message}")
            ur, uc = sr.x, sc.x
        else:
            ur = uc = th0
        pr = np.asarray(f_pos_r(*full(x, ur), *pvals), float)
        pc = np.asarray(f_pos_c(*full(x, uc), *pvals), float)
        return list(pc - pr)

    return solve


# ------------------------------------------------------------------------------------------------
# SymForce: the same routines generated as C++ by SymForce, the same algorithm in a C++ driver
# ------------------------------------------------------------------------------------------------
SF_DRIVER = r"""
#include <time.h>
#include <cmath>
#include <cstddef>
#include "kernels.h"
{includes}

namespace {{
const int M = {m}, K = {k}, NIN = {nin}, NP = {np_}, NPAR = {npar}, ND = {nd};
const int in_idx[NIN > 0 ? NIN : 1] = {{ {in_idx} }};
const int unk_idx[K > 0 ? K : 1] = {{ {unk_idx} }};
const double two_pi = 6.283185307179586476925286766559006;
const int POLISH = {polish}, ITERATIONS = {iterations};
const double STOP = {stop!r}, STALL = {stall!r}, STALL_RATIO = {stall_ratio!r};
typedef Eigen::Matrix<double, NIN, 1> InVec;
typedef Eigen::Matrix<double, NPAR, 1> ParVec;
typedef Eigen::Matrix<double, M, 1> ThVec;
typedef Eigen::Matrix<double, (K > 0 ? K : 1), 1> DeVec;

/* symkin's Gaussian elimination with partial pivoting, verbatim. */
int solve(int n, double *a, double *b)
{{
    int i, j, c, p;
    for (c = 0; c < n; ++c) {{
        double best = std::fabs(a[c * n + c]);
        p = c;
        for (i = c + 1; i < n; ++i) {{
            if (std::fabs(a[i * n + c]) > best) {{ best = std::fabs(a[i * n + c]); p = i; }}
        }}
        if (!(best > 0.0) || !std::isfinite(best)) return 1;
        if (p != c) {{
            double t;
            for (j = 0; j < n; ++j) {{ t = a[c * n + j]; a[c * n + j] = a[p * n + j]; a[p * n + j] = t; }}
            t = b[c]; b[c] = b[p]; b[p] = t;
        }}
        for (i = c + 1; i < n; ++i) {{
            const double f = a[i * n + c] / a[c * n + c];
            for (j = c; j < n; ++j) a[i * n + j] -= f * a[c * n + j];
            b[i] -= f * b[c];
        }}
    }}
    for (i = n - 1; i >= 0; --i) {{
        double s = b[i];
        for (j = i + 1; j < n; ++j) s -= a[i * n + j] * b[j];
        b[i] = s / a[i * n + i];
    }}
    return 0;
}}

int evaluate(const double *inputs, const double *params, double *out)
{{
    InVec x;
    ParVec p;
    ThVec theta = ThVec::Zero();
    DeVec delta = DeVec::Zero();
    int i;
    for (i = 0; i < NIN; ++i) x(i) = inputs[i];
    for (i = 0; i < NPAR; ++i) p(i) = params[i];
    for (i = 0; i < NIN; ++i) theta(in_idx[i]) = inputs[i];
{body}
    {{
        const auto rig = sk::RigidPoints<double>(theta, p);
        const auto dev = sk::DevExact<double>(theta, delta, p);
        for (i = 0; i < NP; ++i) {{
            out[6 * i + 0] = rig(2 * i); out[6 * i + 1] = rig(2 * i + 1);
            out[6 * i + 2] = rig(2 * i) + dev(2 * i); out[6 * i + 3] = rig(2 * i + 1) + dev(2 * i + 1);
            out[6 * i + 4] = dev(2 * i); out[6 * i + 5] = dev(2 * i + 1);
        }}
    }}
    return 0;
}}
}}  // namespace

extern "C" double sf_bench_loop(const double *inputs, int n_points, const double *params,
                                int reps, double *out, int *failures)
{{
    struct timespec t0, t1;
    int r, i, fails = 0;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    for (r = 0; r < reps; ++r) {{
        for (i = 0; i < n_points; ++i) {{
            if (evaluate(inputs + (std::size_t)i * NIN, params, out + (std::size_t)i * 6 * NP) != 0) ++fails;
        }}
    }}
    clock_gettime(CLOCK_MONOTONIC, &t1);
    *failures = fails;
    return (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec);
}}
"""

SF_RIGID = r"""
    {
        const auto sol = sk::Rigid<double>(x, p);
        for (i = 0; i < ND; ++i) if (!(sol(K + i) >= 0.0)) return 1;
        for (i = 0; i < K; ++i) theta(unk_idx[i]) = std::remainder(sol(i), two_pi);
        for (int it = 0; it < POLISH; ++it) {      /* the same polish steps as symkin's C */
            const auto rr = sk::RigidRes<double>(theta, p);
            const auto ll = sk::Linear<double>(theta, p);
            double lin[K * K > 0 ? K * K : 1], res[K > 0 ? K : 1];
            for (i = 0; i < K * K; ++i) lin[i] = ll(i);
            for (i = 0; i < K; ++i) res[i] = (i % 3 == 0) ? std::remainder(rr(i), two_pi) : rr(i);
            if (solve(K, lin, res)) return 1;
            for (i = 0; i < K; ++i) theta(unk_idx[i]) -= res[i];
        }
    }
"""

SF_LOOPS = r"""
    {
        const auto ll = sk::Linear<double>(theta, p);
        double lin[K * K > 0 ? K * K : 1], d[K > 0 ? K : 1];
        for (i = 0; i < K * K; ++i) lin[i] = ll(i);
        for (i = 0; i < K; ++i) d[i] = -ll(K * K + i);
        if (solve(K, lin, d)) return 1;
        for (i = 0; i < K; ++i) delta(i) = d[i];
        double previous = HUGE_VAL;
        int it, converged = 0;
        for (it = 0; it < ITERATIONS && !converged; ++it) {
            const auto nw = sk::Newton<double>(theta, delta, p);
            double jac[K * K > 0 ? K * K : 1], f[K > 0 ? K : 1];
            double size = 0.0, change = 0.0;
            for (i = 0; i < K; ++i) f[i] = nw(i);
            for (i = 0; i < K * K; ++i) jac[i] = nw(K + i);
            if (solve(K, jac, f)) return 1;
            for (i = 0; i < K; ++i) {
                delta(i) -= f[i];
                if (std::fabs(delta(i)) > size) size = std::fabs(delta(i));
                if (std::fabs(f[i]) > change) change = std::fabs(f[i]);
            }
            converged = change <= STOP * size || size == 0.0
                        || (change >= STALL_RATIO * previous && change <= STALL * size);
            previous = change;
        }
        if (!converged) return 2;
    }
"""


def symforce_build(plan, workdir: Path) -> tuple[Path, float]:
    """Generate the routines with SymForce (sympy symbolic API, its own CSE; the rigid dyad
    assignments substituted; symkin's stable kernels called through override_methods) and compile
    them with the driver. Returns (library, generation seconds)."""
    import sympy as sp
    import symforce

    if not getattr(symforce, "_symkin_bench_setup", False):
        symforce.set_symbolic_api("sympy")
        symforce.set_log_level("warning")
        symforce.set_epsilon_to_symbol()
        symforce._symkin_bench_setup = True
    import symforce.symbolic as sf
    from symforce.codegen import Codegen, CppConfig
    from symforce.values import Values
    from symkin import special
    from symkin.codegen.backends.c import kernels as c_kernels
    from symkin.codegen.backends.numpy import kernels as np_kernels

    t0 = time.perf_counter()
    needed = ["rigid_points", "dev_exact"]
    if plan.unknown_index:
        needed += ["rigid", "rigid_res", "linear"]
    if plan.needs_loops:
        needed += ["newton"]
    raw = {k: plan.routines[k] for k in needed}
    outputs = {k: substituted(r) for k, r in raw.items()}
    kernels = special.used_names(*[e for outs in outputs.values() for e in outs])
    overrides = {sp.conjugate: ""}        # real scalars: conjugate(x) is printed as (x)
    for e in (e for outs in outputs.values() for e in outs):
        for f in sp.sympify(e).atoms(sp.Function):
            if type(f).__name__ in kernels:
                overrides[type(f)] = f"symkin_{type(f).__name__}"
    (workdir / "kernels.h").write_text("#pragma once\n#include <math.h>\n"
                                       + c_kernels.support(kernels) + "\n")
    includes = []
    for key, r in raw.items():
        inputs = Values()
        for a in r.arguments:
            inputs[a.name] = sf.Matrix(list(a.symbols)) if a.symbols else sf.Matrix([0])
        cfg = CppConfig(override_methods=overrides, extra_imports=["kernels.h"])
        cg = Codegen(inputs, Values(out=sf.Matrix(outputs[key])), cfg, name=key,
                     return_key="out")
        cg.generate_function(output_dir=str(workdir), namespace="sk",
                             skip_directory_nesting=True)
        includes.append(f'#include "{key}.h"')
    gen_seconds = time.perf_counter() - t0
    body = (SF_RIGID if plan.unknown_index else "") + (SF_LOOPS if plan.needs_loops else "")
    src = SF_DRIVER.format(
        includes="\n".join(includes), m=len(plan.hinges), k=len(plan.unknown_index),
        nin=len(plan.inputs), np_=len(plan.points), npar=len(plan.parameters),
        nd=plan.n_dyads, in_idx=", ".join(map(str, plan.input_index)) or "0",
        unk_idx=", ".join(map(str, plan.unknown_index)) or "0", body=body,
        **POLICY)
    (workdir / "sf_driver.cc").write_text(src)
    lib = workdir / "libsf_bench.so"
    proc = subprocess.run(["c++", *CXX_FLAGS, f"-I{EIGEN}", "-I.", "-shared", "sf_driver.cc",
                           "-o", str(lib), "-lm"], cwd=workdir, capture_output=True, text=True)
    if proc.returncode != 0:
        raise RuntimeError("SymForce C++ did not compile:\n" + proc.stderr[-3000:])
    return lib, gen_seconds


class SFBench:
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
        secs = self.loop(x.ctypes.data_as(d), len(x), self.params.ctypes.data_as(d), reps,
                         out.ctypes.data_as(d), ctypes.byref(fails))
        return secs, out, fails.value

    def per_point(self, x, min_time=0.3, repeat=3):
        secs, _, _ = self.run(x, 1)
        reps = max(1, int(min_time / max(secs, 1e-9)))
        return min(self.run(x, reps)[0] for _ in range(repeat)) / (reps * len(x))


# ------------------------------------------------------------------------------------------------
# 1 + 2: evaluators
# ------------------------------------------------------------------------------------------------
def bench_example(example: str, quick: bool, sf: dict, workroot: Path) -> dict:
    import symkin
    from symkin.codegen.backends.c import backend as c_backend
    from symkin.codegen.backends.numpy import backend as numpy_backend
    from symkin.codegen.plan import plan as make_plan
    from symkin.codegen.runtime import import_numpy_module

    log(f"evaluators: {example}")
    mech = symkin.load(ROOT / "examples" / f"{example}.toml")
    an = symkin.analyze(mech)
    ranges = EXAMPLES[example]
    names = list(mech.inputs)
    rng = np.random.default_rng(1)

    def sample(n):
        return np.column_stack([rng.uniform(*ranges[k], n) for k in names])

    p = make_plan(an)
    source = f"{example}.toml"
    header, code = c_backend.emit(p, source)
    work = workroot / example
    work.mkdir(parents=True, exist_ok=True)
    cb = CBench(compile_c(work, mech.name, header, code), mech.name, len(names), len(p.points))
    npmod = import_numpy_module(numpy_backend.emit(p, source), mech.name)
    res: dict = {"inputs": {k: list(v) for k, v in ranges.items()}, "point": p.points[0],
                 "k_unknowns": len(an.deltas), "needs_loops": p.needs_loops,
                 "closed_form": p.closed_form, "checks": {}, "per_point_s": {}, "notes": {}}

    # the C evaluator, checked against the mpmath reference (40 digits)
    check_x = sample(5)
    _, c_out, fails = cb.run(check_x, EXACT)
    assert fails == 0, f"{example}: C evaluator failed on the check points"
    c_dev = c_out[:, 0, 4:6]
    errs = []
    for i in range(2):
        ref = symkin.evaluate(an, dict(zip(names, map(float, check_x[i]))), "exact")
        errs.append(relerr(c_dev[i], ref.points[p.points[0]].deviation))
    res["checks"]["c_vs_mpmath"] = max(errs)

    n_c = 10 ** 4
    xs = sample(n_c)
    _, _, fails = cb.run(xs, EXACT)
    assert fails == 0, f"{example}: C evaluator failed on {fails} of the sample points"
    for level in LEVELS:
        res["per_point_s"][f"c_{level.name}"] = cb.per_point(xs, level.code, 0.1 if quick else 0.3)
    t_c = res["per_point_s"]["c"] = res["per_point_s"]["c_exact"]

    # numpy module, vectorized over 10^4 points
    np_in = {k: xs[:, j] for j, k in enumerate(names)}
    out = npmod.evaluate({k: v[:5] for k, v in
                          {k: check_x[:, j] for j, k in enumerate(names)}.items()}, "exact")
    res["checks"]["numpy"] = max(relerr(out["points"][p.points[0]]["deviation"][:, i], c_dev[i])
                                 for i in range(5))
    t_np, _ = best_time(lambda: npmod.evaluate(np_in, "exact"), 3, 0.0)
    res["per_point_s"]["numpy_vectorized_1e4"] = t_np / n_c

    # lambdify of the same closed form: plain (substituted, no CSE) and with cse=True
    if p.closed_form:
        raw = make_plan(an, cse=False)
        res["closed_form_ops"] = {"symkin_rigid_after_cse": p.routines["rigid"].ops
                                  if "rigid" in p.routines else 0}
        if "rigid" in raw.routines:
            import sympy as sp
            res["closed_form_ops"]["rigid_substituted"] = int(sum(
                sp.count_ops(e) for e in substituted(raw.routines["rigid"])))
        variants = (("lambdify", False, POLICY["polish"]), ("lambdify_cse", True, POLICY["polish"]),
                    ("lambdify_cse_no_polish", True, 0))
        for key, cse, polish in variants:
            t0 = time.perf_counter()
            lam = lambdify_alternative(raw, cse, polish)
            res.setdefault("setup_s", {})[key] = time.perf_counter() - t0
            res["checks"][key] = max(relerr(lam(check_x[i])[0], c_dev[i]) for i in range(5))
            n_l = 20 if key == "lambdify" else 100
            t, _ = best_time(lambda: [lam(x) for x in xs[:n_l]], 3, 0.2 if quick else 0.5)
            res["per_point_s"][key] = t / n_l
    else:
        res["notes"]["lambdify"] = res["notes"]["lambdify_cse"] = \
            "no closed form (not all groups are dyads)"

    # scipy.optimize.root on the loop equations
    sci = scipy_alternative(an)
    res["checks"]["scipy"] = max(relerr(sci(check_x[i]), c_dev[i]) for i in range(5))
    t, _ = best_time(lambda: [sci(x) for x in xs[:20]], 3, 0.3 if quick else 1.0)
    res["per_point_s"]["scipy_root"] = t / 20

    # SymForce
    if sf.get("available") and p.closed_form:
        try:
            sfw = work / "symforce"
            sfw.mkdir(exist_ok=True)
            lib, gen = symforce_build(make_plan(an, cse=False), sfw)
            sb = SFBench(lib, len(names), len(p.points),
                         [float(q.value) for q in mech.parameters])
            _, sf_out, sf_fail = sb.run(check_x)
            assert sf_fail == 0, "SymForce evaluator failed on the check points"
            res["checks"]["symforce"] = max(relerr(sf_out[i, 0, 4:6], c_dev[i]) for i in range(5))
            res["per_point_s"]["symforce"] = sb.per_point(xs, 0.1 if quick else 0.3)
            res["symforce_codegen_s"] = gen
        except Exception as exc:  # report, do not abort the whole run
            res["notes"]["symforce"] = f"failed: {type(exc).__name__}: {str(exc)[:300]}"
    elif not sf.get("available"):
        res["notes"]["symforce"] = sf.get("note") or "SymForce not available"

    res["verified"] = {k: v <= TOL.get(k, 1e-12) for k, v in res["checks"].items()}
    res["verified"]["c_vs_mpmath"] = res["checks"]["c_vs_mpmath"] <= 1e-12
    res["ratios"] = {k: v / t_c for k, v in res["per_point_s"].items()
                     if k != "c" and not k.startswith("c_")}

    # throughput: numpy on 10^6 points vs the C loop over the same 10^6 points
    n_big = 10 ** 5 if quick else 10 ** 6
    big = sample(n_big)
    c_secs = min(cb.run(big, EXACT)[0] for _ in range(2))
    big_in = {k: big[:, j] for j, k in enumerate(names)}
    t0 = time.perf_counter()
    out = npmod.evaluate(big_in, "exact")
    np_secs = time.perf_counter() - t0
    res["throughput"] = {"points": n_big, "c_loop_s": c_secs, "numpy_s": np_secs,
                         "ratio_numpy_over_c": np_secs / c_secs,
                         "numpy_ok_fraction": float(np.mean(out["ok"]))}
    del out
    return res


# ------------------------------------------------------------------------------------------------
# 3: derivation, one fresh process per case
# ------------------------------------------------------------------------------------------------
def emitters() -> list[str]:
    from symkin.derive import EMITTERS

    return list(EMITTERS)


def peak_rss_mb() -> float:
    """Peak resident set of this process (VmHWM; ru_maxrss would carry the parent's peak over
    fork + exec on Linux)."""
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("VmHWM:"):
                return int(line.split()[1]) / 1024
    except (OSError, ValueError, IndexError):
        pass
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def derive_child(kind: str, arg: str) -> None:
    """Runs in a fresh process: prints one JSON line with the derivation's time and memory."""
    t_start = time.perf_counter()
    import symkin
    from symkin.derive import generate

    import symkin.codegen.plan  # noqa: F401 - the emitters' imports are start-up, not derivation
    for module in ("numpy.backend", "c.backend", "latex.report"):
        importlib.import_module(f"symkin.codegen.backends.{module}")
    rss0 = peak_rss_mb()
    t_import = time.perf_counter() - t_start
    if kind == "example":
        mech = symkin.load(ROOT / "examples" / f"{arg}.toml")
    else:
        mech = symkin.loads(families.family(kind, int(arg)), f"{kind}_{arg}.toml")
    s = symkin.structure(mech)
    paths = [len(s.tree_path(i)) for i in range(1, s.n + 1)]
    emit = emitters()
    marks = []
    t0 = time.perf_counter()
    files = generate(mech, emit=emit,
                     progress=lambda msg: marks.append((time.perf_counter() - t0, msg)))
    total = time.perf_counter() - t0
    rss1 = peak_rss_mb()
    phases, prev = {}, (0.0, "start")
    for t, msg in marks + [(total, "end")]:
        if prev[1] != "start":
            phases[prev[1]] = t - prev[0]
        prev = (t, msg)
    print(json.dumps({
        "links": s.n + 1, "hinges": s.m, "loops": s.m - s.n, "inputs": len(mech.inputs),
        "mean_path": sum(paths) / len(paths), "size": s.m * sum(paths) / len(paths),
        "emit": emit, "derive_s": total, "import_s": t_import, "phases_s": phases,
        "without_latex_s": total - sum(v for k, v in phases.items() if "LaTeX" in k),
        "maxrss_mb": rss1, "baseline_rss_mb": rss0,
        "output_kb": sum(len(v) for v in files.values()) / 1024}))


def structure_stats(kind: str, arg) -> dict:
    import symkin

    if kind == "example":
        mech = symkin.load(ROOT / "examples" / f"{arg}.toml")
    else:
        mech = symkin.loads(families.family(kind, int(arg)), f"{kind}_{arg}.toml")
    s = symkin.structure(mech)
    paths = [len(s.tree_path(i)) for i in range(1, s.n + 1)]
    return {"links": s.n + 1, "hinges": s.m, "loops": s.m - s.n, "inputs": len(mech.inputs),
            "mean_path": sum(paths) / len(paths), "size": s.m * sum(paths) / len(paths)}


def derive_case(kind: str, arg, budget: float) -> dict:
    cmd = [sys.executable, str(Path(__file__).resolve()), "--derive-child", kind, str(arg)]
    t0 = time.perf_counter()
    try:
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=budget, cwd=ROOT)
    except subprocess.TimeoutExpired:
        log(f"derive {kind} {arg}: over budget ({budget:.0f} s)")
        return {"kind": kind, "case": str(arg), "over_budget": True, "budget_s": budget,
                **structure_stats(kind, arg)}
    wall = time.perf_counter() - t0
    if proc.returncode != 0:
        return {"kind": kind, "case": str(arg), "error": proc.stderr.strip()[-500:]}
    out = json.loads(proc.stdout.strip().splitlines()[-1])
    out.update(kind=kind, case=str(arg), process_wall_s=wall, over_budget=False)
    log(f"derive {kind} {arg}: {out['derive_s']:.2f} s, peak RSS {out['maxrss_mb']:.0f} MB")
    return out


def cli_derive(example: str) -> dict:
    """Wall time of the whole `symkin derive` command (start-up and writing included)."""
    with tempfile.TemporaryDirectory() as tmp:
        cmd = [sys.executable, "-m", "symkin", "derive", str(ROOT / "examples" / f"{example}.toml"),
               "-o", tmp, "--quiet", "--emit", ",".join(emitters())]
        t0 = time.perf_counter()
        proc = subprocess.run(cmd, capture_output=True, text=True, cwd=ROOT)
        return {"wall_s": time.perf_counter() - t0, "exit": proc.returncode,
                "stderr": proc.stderr.strip()[-300:]}


def fit(xs, ys) -> float | None:
    pts = [(math.log(x), math.log(y)) for x, y in zip(xs, ys) if x > 0 and y > 0]
    if len(pts) < 2:
        return None
    a = np.array(pts)
    return float(np.polyfit(a[:, 0], a[:, 1], 1)[0])


def exponents(cases: list[dict]) -> dict:
    ok = [c for c in cases if not c.get("over_budget") and "derive_s" in c]
    out = {}
    for label, key in (("size", "size"), ("hinges", "hinges")):
        xs = [c[key] for c in ok]
        ys = [c["derive_s"] for c in ok]
        core = [c["without_latex_s"] for c in ok]
        out[f"time_vs_{label}_last_step"] = fit(xs[-2:], ys[-2:]) if len(ok) >= 2 else None
        out[f"core_vs_{label}_largest3"] = fit(xs[-3:], core[-3:]) if len(ok) >= 3 else None
        out[f"time_vs_{label}"] = fit(xs, ys)
        out[f"time_vs_{label}_largest3"] = fit(xs[-3:], ys[-3:]) if len(ok) >= 3 else None
        mem = [max(c["maxrss_mb"] - c["baseline_rss_mb"], 1e-3) for c in ok]
        out[f"memory_vs_{label}_largest3"] = fit(xs[-3:], mem[-3:]) if len(ok) >= 3 else None
    return out


# ------------------------------------------------------------------------------------------------
# report
# ------------------------------------------------------------------------------------------------
def fmt_ratio(x: float | None) -> str:
    if x is None:
        return "—"
    if x >= 100:
        return f"{x:,.0f}×"
    if x >= 10:
        return f"{x:.0f}×"
    return f"{x:.2g}×" if x < 1 else f"{x:.1f}×"


def fmt_exp(x):
    return "—" if x is None else f"{x:.2f}"


def render(results: dict) -> str:
    m = results["machine"]
    ev = results["evaluators"]
    ex = list(ev)
    sf = results["symforce"]
    lines = []
    quick = " (`--quick`: smaller sizes)" if results["quick"] else ""
    lines.append(
        f"Measured {results['date']} by `python benchmarks/run.py`{quick} in "
        f"{results['total_s'] / 60:.1f} min (symkin at commit {results['symkin_commit']}"
        f"{' with uncommitted changes' if results.get('symkin_dirty') else ''}) on: {m['cpu']}, {m['cores']} cores, "
        f"{m['mem_total_gb']} GB, {m['system']}; Python {m['python']}, numpy {m['numpy']}, "
        f"sympy {m['sympy']}, scipy {m['scipy']}, SymForce "
        f"{sf['version'] or 'not installed'}; {m['cc']} (`{m['c_flags']}`). "
        "Raw numbers (absolute times too): `benchmarks/results.json`.")
    lines.append("")
    lines.append("Per point, exact level: time of each alternative ÷ time of symkin's generated C "
                 "(C timed inside C over 10^4 points; higher = symkin faster).")
    lines.append("")
    lines.append("| alternative ÷ symkin C | " + " | ".join(ex) + " | target |")
    lines.append("| --- | " + " | ".join("---:" for _ in ex) + " | --- |")
    rows = [("scipy.optimize.root on the loop equations", "scipy_root", "≥ 1000×"),
            ("sympy.lambdify of the closed form, dyads substituted", "lambdify", "≥ 50×"),
            ("the same with lambdify(cse=True)", "lambdify_cse", "≥ 50×"),
            ("symkin numpy, per point (10^4 vectorized)", "numpy_vectorized_1e4", ""),
            ("SymForce-generated C++, same algorithm", "symforce", "")]
    check_of = {"scipy_root": "scipy", "lambdify": "lambdify", "lambdify_cse": "lambdify_cse",
                "numpy_vectorized_1e4": "numpy", "symforce": "symforce"}
    notes = []
    for label, key, target in rows:
        cells = []
        for e in ex:
            r = ev[e]
            if key in r["ratios"]:
                ok = r["verified"].get(check_of[key], False)
                cells.append(fmt_ratio(r["ratios"][key]) + ("" if ok else " (unverified)"))
            else:
                cells.append("n/a")
                note = r["notes"].get(check_of[key])
                if note and f"{key}: {note}" not in notes:
                    notes.append(f"{key}: {note}")
        lines.append(f"| {label} | " + " | ".join(cells) + f" | {target} |")
    lines.append("| symkin C at the paper level ÷ at the exact level | " + " | ".join(
        fmt_ratio(ev[e]["per_point_s"]["c_paper"] / ev[e]["per_point_s"]["c_exact"])
        for e in ex) + " | |")
    for n in notes:
        lines.append(f"\n(n/a — {n})")
    lines.append("")
    lines.append("Throughput, exact level: symkin numpy on "
                 f"{ev[ex[0]]['throughput']['points']:.0e} points in one call ÷ the C evaluator "
                 "called on the same points in a C loop (target ≤ 3×).".replace("1e+06", "10^6")
                 .replace("1e+05", "10^5"))
    lines.append("")
    lines.append("| | " + " | ".join(ex) + " |")
    lines.append("| --- | " + " | ".join("---:" for _ in ex) + " |")
    lines.append("| numpy ÷ C loop | " + " | ".join(
        fmt_ratio(ev[e]["throughput"]["ratio_numpy_over_c"]) for e in ex) + " |")
    lines.append("")
    if not sf["available"]:
        lines.append(f"SymForce: {sf['note'] or 'not available'}.")
        lines.append("")
    dv = results["derivation"]
    lines.append("Derivation (`symkin.derive.generate`, all levels, emitters "
                 f"{', '.join(dv['emitters'])}; each case in a fresh process; time excludes "
                 "start-up and imports; memory = peak RSS (VmHWM) above the RSS after importing symkin "
                 "and its emitter modules, so it includes what they import lazily, e.g. "
                 "matplotlib for the figures; budget "
                 f"{dv['budget_s']:.0f} s per case):")
    lines.append("")
    lines.append("| case | links / hinges / loops | hinges × mean path | time | of which LaTeX "
                 "| peak memory |")
    lines.append("| --- | --- | ---: | ---: | ---: | ---: |")
    for c in dv["examples"] + dv["serial"] + dv["ladder"]:
        label = c["case"] if c["kind"] == "example" else f"{c['kind']} {c['case']}"
        if c.get("over_budget"):
            lines.append(f"| {label} | {c['links']} / {c['hinges']} / {c['loops']} | "
                         f"{c['size']:.0f} | over budget (> {c['budget_s']:.0f} s)"
                         + (", not run" if c.get("skipped") else "") + " | | |")
            continue
        if "error" in c:
            lines.append(f"| {label} | | | error | | |")
            continue
        extra = ""
        if c["kind"] == "example" and "cli" in c:
            extra = f" (CLI {c['cli']['wall_s']:.1f} s)"
        lines.append(f"| {label} | {c['links']} / {c['hinges']} / {c['loops']} | "
                     f"{c['size']:.0f} | {c['derive_s']:.2f} s{extra} | "
                     f"{c['derive_s'] - c['without_latex_s']:.2f} s | "
                     f"{c['maxrss_mb'] - c['baseline_rss_mb']:.0f} MB |")
    lines.append("")
    lines.append("Growth exponent b of derivation time ∝ x^b (least squares on log-log over the "
                 "three largest measured sizes; in brackets over all measured sizes, pulled down "
                 "by the ~1.5 s constant of the small cases):")
    lines.append("")
    lines.append("| family | time vs x = hinges × mean path | same, two largest only | "
                 "time vs x = hinges | time without LaTeX vs hinges × mean path | "
                 "peak memory vs hinges |")
    lines.append("| --- | ---: | ---: | ---: | ---: | ---: |")
    for fam in ("serial", "ladder"):
        e = dv["exponents"][fam]
        lines.append(f"| {fam} | {fmt_exp(e['time_vs_size_largest3'])} "
                     f"({fmt_exp(e['time_vs_size'])}) | {fmt_exp(e['time_vs_size_last_step'])} | "
                     f"{fmt_exp(e['time_vs_hinges_largest3'])} "
                     f"({fmt_exp(e['time_vs_hinges'])}) | "
                     f"{fmt_exp(e['core_vs_size_largest3'])} | "
                     f"{fmt_exp(e['memory_vs_hinges_largest3'])} |")
    lines.append("")
    lines.append("Targets:")
    lines.append("")
    for t in results["targets"]:
        lines.append(f"- {'met' if t['met'] else 'MISSED'}: {t['text']} — measured {t['measured']}")
    lines.append("")
    lines.append(
        "What is timed: *symkin C* — the generated `<name>_evaluate` (level 2), compiled with "
        "the flags above in its own translation unit, called from a C loop that reads "
        "`clock_gettime(CLOCK_MONOTONIC)` (no ctypes overhead). *numpy* — the generated module's "
        "`evaluate` on arrays. *lambdify* — `sympy.lambdify` (symkin's float64 kernels + `math`, "
        "scalar calls; plain, and with `cse=True`) of symkin's routines before CSE with the "
        "dyad assignments substituted into one expression per output, driven in Python by the "
        "same steps as the C (closed-form rigid angles, its Newton polish step(s), first-order δ, "
        "Newton on δ, `numpy.linalg.solve` for the small systems, rigid position and "
        "deviation); results.json also has `lambdify_cse_no_polish`. *scipy* — "
        "`scipy.optimize.root` (hybr, xtol 1e-12, finite-difference Jacobian) on the per-chord "
        "angular and positional loop closures lambdified with numpy, rigid pose from the "
        "as-fabricated pose, compliant pose from the rigid one, deviation = compliant − rigid "
        "point position. *SymForce* — the same routines generated by SymForce's C++ codegen "
        "(its own CSE, Eigen types, symkin's kernels via `override_methods`), driven by a C++ "
        "copy of symkin's algorithm (the same polish step(s), first-order start and Newton "
        "stopping rule, from symkin.solver), timed like the C. Each alternative's deviation is first checked "
        "against the C evaluator on 5 points (relative tolerance: numpy 1e-12, lambdify and "
        "SymForce 1e-9, scipy 1e-5), and the C against symkin's 40-digit mpmath evaluation.")
    return "\n".join(lines)


def targets(results: dict) -> list[dict]:
    ev = results["evaluators"]
    out = []
    sci = {e: r["ratios"].get("scipy_root") for e, r in ev.items()}
    out.append({"text": "exact-level C ≥ 1000× faster per point than scipy.optimize.root",
                "met": all(v is not None and v >= 1000 for v in sci.values()),
                "measured": ", ".join(f"{e} {fmt_ratio(v)}" for e, v in sci.items())})
    lam = {e: min(r["ratios"]["lambdify"], r["ratios"]["lambdify_cse"]) for e, r in ev.items()
           if r["ratios"].get("lambdify") is not None}
    out.append({"text": "≥ 50× faster than lambdify where a closed form exists (the faster of "
                "plain and cse=True)",
                "met": bool(lam) and all(v >= 50 for v in lam.values()),
                "measured": ", ".join(f"{e} {fmt_ratio(v)}" for e, v in lam.items())})
    th = {e: r["throughput"]["ratio_numpy_over_c"] for e, r in ev.items()}
    out.append({"text": f"numpy on {ev[next(iter(ev))]['throughput']['points']:.0e} points "
                "within 3× of the C loop".replace("1e+06", "10^6").replace("1e+05", "10^5"),
                "met": all(v <= 3 for v in th.values()),
                "measured": ", ".join(f"{e} {fmt_ratio(v)}" for e, v in th.items())})
    dv = results["derivation"]
    nine = next((c for c in dv["examples"] if c["case"] == "nine_bar_platform"), None)
    if nine and "derive_s" in nine:
        cli = nine.get("cli", {}).get("wall_s")
        out.append({"text": "`symkin derive` of the nine-bar, all levels and backends, < 5 s",
                    "met": nine["derive_s"] < 5 and (cli is None or cli < 5),
                    "measured": f"{nine['derive_s']:.2f} s in process, "
                                f"{cli:.2f} s for the whole command (emitters "
                                f"{', '.join(nine['emit'])})"})
    s64 = next((c for c in dv["serial"] if c["case"] == "64"), None)
    if s64 is not None:
        met = not s64.get("over_budget") and s64.get("derive_s", 1e9) < 30
        out.append({"text": "64-link serial chain < 30 s", "met": met,
                    "measured": (f"{s64['derive_s']:.2f} s" if "derive_s" in s64
                                 else "over budget")})
    for fam in ("serial", "ladder"):
        e = dv["exponents"][fam]["time_vs_size_largest3"]
        step = dv["exponents"][fam]["time_vs_size_last_step"]
        over = [c for c in dv[fam] if c.get("over_budget")]
        done = [c for c in dv[fam] if "derive_s" in c]
        text = (f"exponent {fmt_exp(e)} over the three largest measured, {fmt_exp(step)} "
                f"between the two largest")
        bound = None
        if over and done:
            # the first over-budget member bounds the exponent from below
            last, first_over = done[-1], over[0]
            bound = (math.log(first_over["budget_s"] / last["derive_s"])
                     / math.log(first_over["size"] / last["size"]))
            dv["exponents"][fam]["lower_bound_from_budget"] = bound
            text += (f"; {fam} {', '.join(c['case'] for c in over)} over budget (linear "
                     f"growth from {fam} {last['case']} would take "
                     f"{last['derive_s'] * first_over['size'] / last['size']:.0f} s, so the "
                     "budget only bounds the exponent from below, by "
                     f"{bound:.2f}: not shown)")
        out.append({"text": f"{fam}: derivation time about linear in hinges × path length "
                    "(exponent ≤ 1.2, every size measured)",
                    "met": (e is not None and e <= 1.2 and step is not None and step <= 1.2
                            and not over),
                    "measured": text})
    return out


def write_readme(block: str) -> bool:
    path = ROOT / "README.md"
    text = path.read_text()
    if START not in text or END not in text:
        log("README has no benchmark markers: not written")
        return False
    head, rest = text.split(START, 1)
    _, tail = rest.split(END, 1)
    path.write_text(head + START + "\n" + block + "\n" + END + tail)
    return True


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="smaller sizes, shorter timings")
    ap.add_argument("--no-readme", action="store_true", help="do not rewrite README.md")
    ap.add_argument("--budget", type=float, default=120.0,
                    help="seconds allowed per derivation case (default 120)")
    ap.add_argument("--derive-child", nargs=2, metavar=("KIND", "ARG"), help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.derive_child:
        derive_child(*args.derive_child)
        return
    t_start = time.perf_counter()
    results: dict = {"quick": args.quick, "date": datetime.date.today().isoformat(),
                     "machine": machine(), "solver": POLICY,
                     "symkin_commit": first_line(["git", "-C", str(ROOT), "rev-parse",
                                                  "--short", "HEAD"]),
                     "symkin_dirty": bool(subprocess.run(
                         ["git", "-C", str(ROOT), "status", "--porcelain", "symkin", "templates"],
                         capture_output=True, text=True).stdout.strip())}
    log("machine: " + json.dumps(results["machine"]))
    results["symforce"] = symforce_status()
    log(f"SymForce: {results['symforce']}")

    with tempfile.TemporaryDirectory(prefix="symkin-bench-") as tmp:
        results["evaluators"] = {e: bench_example(e, args.quick, results["symforce"], Path(tmp))
                                 for e in EXAMPLES}

    dv: dict = {"budget_s": args.budget, "emitters": emitters()}
    dv["examples"] = []
    for e in EXAMPLES:
        case = derive_case("example", e, args.budget)
        case["cli"] = cli_derive(e)
        dv["examples"].append(case)
    serial = families.SERIAL_SIZES if not args.quick else (2, 4, 8, 16)
    ladder = families.LADDER_SIZES if not args.quick else (1, 2, 4)
    for kind, sizes in (("serial", serial), ("ladder", ladder)):
        dv[kind] = []
        over = False
        for n in sizes:
            if over:       # a larger member of a family already over budget: skip, say so
                dv[kind].append({"kind": kind, "case": str(n), "over_budget": True,
                                 "budget_s": args.budget, "skipped": True,
                                 **structure_stats(kind, n)})
                continue
            case = derive_case(kind, n, args.budget)
            over = bool(case.get("over_budget"))
            dv[kind].append(case)
    dv["exponents"] = {k: exponents(dv[k]) for k in ("serial", "ladder")}
    results["derivation"] = dv
    results["total_s"] = time.perf_counter() - t_start
    results["targets"] = targets(results)
    out = BENCH / ("results-quick.json" if args.quick else "results.json")
    out.write_text(json.dumps(results, indent=1, default=str) + "\n")
    block = render(results)
    print(block)
    if not args.no_readme:
        write_readme(block)          # read-modify-write of the marked block only, at the end
    log(f"done in {results['total_s'] / 60:.1f} min; raw numbers in {out.relative_to(ROOT)}")


if __name__ == "__main__":
    main()
