"""The command line (docs/cli.md): a thin shell over the Python API (`commands`) and its plain-text
and JSON output (`output`)."""

from .commands import main

__all__ = ["main"]
