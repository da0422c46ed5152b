"""Stiffness, loads and the physical levels (docs/physics.md).

- `stiffness`: EI, EA and κGA of every plate from its E, thickness, width and nu, and its beam;
- `plate_relation`, `reduced`: the `loaded` level, Newton on the reduced equilibrium (the
  compliant angles and the chord plates' loads, each plate by its closed-form relation);
- `arith`, `beams`, `equilibrium`: the `equilibrium` level, every plate a geometrically exact beam
  (Reissner's, or the elastica), solved numerically (float64 continuation, mpmath polish), and
  the loads' first buckling factor (`equilibrium.buckling_factor`);
- `result`: the plate end loads both levels report.

Their evaluation for one configuration (the `sympy` backend) is symkin.studies.physical's.
"""
