"""One folder per language: its printer, the source of symkin's special functions in that
language and the backend that renders a plan with the templates of ``templates/<lang>/``."""
