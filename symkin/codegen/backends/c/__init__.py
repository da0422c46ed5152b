"""C99 backend: printer, kernels' source, backend (templates/c)."""
