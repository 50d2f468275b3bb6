"""The command line ``ti-golf``: one module per command, each with ``add_parser`` and ``cmd_*``.

:func:`main` parses and runs a command line and returns its exit code; :func:`run` is the
console script (it exits the process with that code).
"""

from ti_golf.cli.main import build_parser, main
from ti_golf.cli.main import run_cli as run

__all__ = ["build_parser", "main", "run"]
