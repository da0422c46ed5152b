"""LaTeX report: text (escaping, printer, line breaking), figures, report (templates/latex)."""
