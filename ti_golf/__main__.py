"""``python -m ti_golf`` runs the command line."""

from ti_golf.cli import run

run()
