"""The LaTeX report of a mechanism (docs/cli.md, `derive`): it reads a plan's derivation and the
evaluations of its generated numpy module and of the `equilibrium` level; it is not an evaluator
backend. text (escaping, numbers, the printer, line breaking), figures, sections (the derivation
restated), sweeps (the figures' and the sensitivity table's numbers), equilibrium (what the
`equilibrium` level reports), document (`emit`, with the templates of templates/latex)."""
