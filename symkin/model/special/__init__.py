"""symkin's special functions: the cancellation-free kernels of the hinge models and the
tip-force elastica (docs/numerics.md).

- :mod:`.kernels`: sinr_n, cosr_n, arck, sympy functions with exact series, stable derivatives,
  mpmath values at any precision and a language-neutral float algorithm;
- :mod:`.axial`: the beam-column kernels of the axial load index p (rational in p and
  T(p) = tanh(sqrt(p)/2)/(sqrt(p)/2)), exact series at p = 0, derivatives in the family;
- :mod:`.elastica`: the Bisshopp-Drucker cantilever in Carlson's symmetric integrals;
- :mod:`.registry`: every function by name, its mpmath implementation and the helpers its float
  algorithm calls.

The float algorithms are written out beside each backend (:mod:`symkin.codegen.backends`), and
each backend's printer names the functions in its language.
"""

from __future__ import annotations

import sympy as sp

from . import axial
from .axial import AxialKernel
from .elastica_force import (
    ELASTICA_FUNCTIONS,
    ELASTICA_LIMIT,
    ElasticaFunction,
    elastica_dx,
    elastica_dx_d1,
    elastica_dy,
    elastica_dy_d1,
    elastica_load,
    elastica_x,
    elastica_y,
)
from .kernels import StableKernel, arck, cosr, sinr
from .registry import DomainError, is_special, mpmath_namespace, used_names, with_dependencies

__all__ = [
    "ELASTICA_FUNCTIONS",
    "ELASTICA_LIMIT",
    "AxialKernel",
    "DomainError",
    "ElasticaFunction",
    "StableKernel",
    "arck",
    "axial",
    "cosr",
    "elastica_dx",
    "elastica_dx_d1",
    "elastica_dy",
    "elastica_dy_d1",
    "elastica_load",
    "elastica_x",
    "elastica_y",
    "expand_special",
    "is_special",
    "mpmath_namespace",
    "sinr",
    "used_names",
    "with_dependencies",
]


def expand_special(expr: sp.Expr) -> sp.Expr:
    """`expr` with every symkin special function written out (kernels: elementary; elastica:
    Legendre elliptic integrals)."""
    return expr.rewrite("elementary")
