"""`symkin eval --backend numpy|c`: the generated evaluators, called for one configuration.

They print the same JSON as the sympy backend. When a generated evaluator reports that the
configuration cannot be assembled, the sympy derivation is asked why, so every backend fails with
the same exit code (3) and the same message naming the loop.
"""

from __future__ import annotations

from collections.abc import Mapping

import sympy as sp

from .analysis import Analysis, Evaluation, PointResult
from .errors import AssemblyError, InputError


def evaluate(analysis: Analysis, inputs: Mapping[str, object], level: str,
             params: Mapping[str, object] | None, backend: str) -> Evaluation:
    """One configuration through the generated `backend` ('numpy' or 'c')."""
    from .codegen.build import plan
    from .physics import LEVELS as PHYSICAL

    if backend == "sympy":
        return analysis.evaluate(inputs, level, params)
    if level in PHYSICAL:
        raise InputError(f"--level {level} is evaluated by the sympy backend only (the generated "
                         "numpy and C evaluators do not hold it yet)", entry="--backend",
                         hint="drop --backend or use --backend sympy")
    given = analysis._inputs(inputs)
    kin = analysis.kin
    names = [kin.hinges[a].name for a in kin.inputs]
    x = [float(sp.N(given[a], 20)) for a in kin.inputs]
    pvals = analysis.parameter_values(params)
    pfloat = [float(sp.N(pvals[s], 20)) for s in analysis.params]
    p = plan(analysis)
    source = analysis.mechanism.path
    hinges = [kin.hinges[a].name for a in sorted(kin.hinges)]
    if backend == "numpy":
        from .codegen import numpy_backend
        from .derive import import_numpy_module

        module = import_numpy_module(numpy_backend.emit(p, source), analysis.mechanism.name)
        res = module.evaluate(dict(zip(names, x)), level,
                              {q.name: v for q, v in zip(analysis.mechanism.parameters, pfloat)})
        if not bool(res["ok"]):
            _explain(analysis, inputs, level, params)
        points = {n: PointResult(*(tuple(float(v) for v in res["points"][n][key])
                                   for key in ("rigid", "compliant", "deviation")))
                  for n in p.points}
        rigid = {h: float(res["angles"]["rigid"][h]) for h in hinges}
        compliant = {h: float(res["angles"]["compliant"][h]) for h in hinges}
    elif backend == "c":
        from .codegen import c_backend, c_runtime

        header, code = c_backend.emit(p, source)
        name = analysis.mechanism.name
        lib = c_runtime.Library(c_runtime.build(name, header, code), name, len(x), len(pfloat),
                                len(p.points), len(hinges))
        status, out, angles = lib.evaluate(x, pfloat, {"paper": 0, "first_order": 1,
                                                       "exact": 2}[level])
        if status == 3:
            raise InputError("the C evaluator rejected the arguments", entry="--input")
        if status:
            _explain(analysis, inputs, level, params)
        points = {n: PointResult((out[6 * i], out[6 * i + 1]), (out[6 * i + 2], out[6 * i + 3]),
                                 (out[6 * i + 4], out[6 * i + 5])) for i, n in enumerate(p.points)}
        m = len(hinges)
        rigid = dict(zip(hinges, angles[:m]))
        compliant = dict(zip(hinges, angles[m:]))
    else:
        raise InputError(f"unknown backend '{backend}'", entry="--backend",
                         hint="backends: sympy, numpy, c")
    order = {kin.hinges[a].name: a for a in kin.hinges}
    return Evaluation(
        level=level, backend=backend, inputs=dict(zip(names, x)),
        angles_rigid={h: rigid[h] for h in sorted(rigid, key=order.get)},
        angles_compliant={h: compliant[h] for h in sorted(compliant, key=order.get)},
        points=points)


def _explain(analysis: Analysis, inputs, level, params) -> None:
    """Raise the sympy backend's error for a configuration a generated evaluator refused."""
    analysis.evaluate(inputs, level, params)
    raise AssemblyError(f"{analysis.mechanism.path}: the generated evaluator could not solve this "
                        "configuration (no convergence in float64), although the 40-digit "
                        "derivation can")

