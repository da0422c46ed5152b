"""Code generation (docs/generated-code.md): an Analysis becomes a :class:`~.plan.Plan`, and
the plan is the backends' only input.

- :mod:`.plan`: the routines (one CSE pass each, :mod:`.routines`) with numbers as doubles
  (:mod:`.literals`) and the neutral data every template reads;
- :mod:`.derivation`: the statement of the derivation a report prints;
- :mod:`.backends`: one folder per language (printer, kernels' source, backend; the templates
  live in the top-level ``templates/<lang>/``): ``c``, ``numpy`` (the LaTeX report, which
  reads a plan and evaluations, is :mod:`symkin.report`);
- :mod:`.toolchain`: compiling and calling generated C, importing generated numpy modules;
- :mod:`.templating`: the Jinja2 environment every emitter shares.
"""
