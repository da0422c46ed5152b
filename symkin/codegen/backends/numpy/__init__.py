"""numpy backend: printer, kernels' source, backend (templates/numpy)."""
