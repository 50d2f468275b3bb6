"""``python -m ti_golf`` runs the command line."""

from .cli import run

run()
