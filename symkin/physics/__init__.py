"""Stiffness, loads and the physical levels (docs/physics.md).

- `stiffness`: EI and EA of every plate from its E, thickness, width and nu;
- `beamcolumn`, `statics`: the `loaded` level's derivation (pin-linkage statics, the plates'
  beam-column compliance added to their circular arcs), emitted like the kinematic levels;
- `arith`, `elastica`, `equilibrium`: the `equilibrium` level, every plate an elastica, solved
  numerically (float64 continuation, mpmath polish);
- `result`: the plate end loads both levels report.

Their evaluation for one configuration is symkin.studies.evaluation's (the `sympy` backend).
"""
