"""``python -m ti_golf`` runs the command line."""

from ti_golf.cli import run

if __name__ == "__main__":  # not when a worker process started by spawning imports this module again
    run()
