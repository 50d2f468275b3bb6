"""``ti-golf``: the parser of every command and the entry point; ``main(argv) -> exit code``.

Bad input exits with code 2 and one line naming the file, the key and what is allowed; a
simulation that goes non-finite exits with code 3.
"""

from __future__ import annotations

import argparse
import os
import signal
import sys
import threading
from collections.abc import Callable, Sequence

import ti_golf
from ti_golf import runtime
from ti_golf.cli import (
    bench,
    dispersion,
    figure,
    lab,
    play,
    render,
    run,
    scenes,
    schema,
    shot,
    study,
    sweep,
    table,
    tour,
)
from ti_golf.cli._common import Parser
from ti_golf.errors import ConfigError, SimulationError, TiGolfError

COMMANDS: dict[str, Callable[[argparse.Namespace], int]] = {
    "scenes": scenes.cmd_scenes,
    "keys": scenes.cmd_keys,
    "schema": schema.cmd_schema,
    "sweep": sweep.cmd_sweep,
    "shot": shot.cmd_shot,
    "dispersion": dispersion.cmd_dispersion,
    "run": run.cmd_run,
    "table": table.cmd_table,
    "figure": figure.cmd_figure,
    "tour": tour.cmd_tour,
    "fit-aero": tour.cmd_fit_aero,
    "bench": bench.cmd_bench,
    "render": render.cmd_render,
    "play": play.cmd_play,
    "lab": lab.cmd_lab,
    "study": study.cmd_study,
}
"""Each subcommand's function: parsed arguments -> exit code."""

NO_RUNTIME = ("scenes", "keys", "schema", "study")
"""Commands that start no Taichi runtime: they simulate nothing, or (a study) leave it to their
worker processes, each of which starts its own."""


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of ``ti-golf``."""
    p = Parser(prog="ti-golf", description="Golf-ball physics on Taichi: flights, sweeps, collisions.")
    p.add_argument("--version", action="version", version=f"ti-golf {ti_golf.__version__}")
    sub = p.add_subparsers(dest="command", required=True, parser_class=Parser)
    for module in (scenes, schema, sweep, shot, dispersion, run, table, tour, figure, bench, render, play, lab, study):
        module.add_parser(sub)
    return p


def run_cli() -> None:
    """The ``ti-golf`` command and ``python -m ti_golf``: :func:`main`, whose code the process then
    exits with (see ``runtime.exit_process``: Taichi's runtime can crash the normal exit)."""
    try:
        code = main()
    except BrokenPipeError:  # the reader of stdout left (``ti-golf scenes | head``): no traceback
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        code = 1
    runtime.exit_process(code)


def _interrupt(signum: int, frame: object) -> None:
    """SIGTERM handler: stop as Ctrl-C does (``KeyboardInterrupt``), so outputs are kept."""
    raise KeyboardInterrupt


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of ``ti-golf`` and ``python -m ti_golf``; returns the exit code."""
    args = build_parser().parse_args(argv)
    on_main_thread = threading.current_thread() is threading.main_thread()
    if on_main_thread:  # a kill stops as Ctrl-C does, keeping what was done (signals reach the main thread only)
        previous = signal.signal(signal.SIGTERM, _interrupt)
    runtime.announce_first_compile = True
    try:
        if args.command not in NO_RUNTIME:  # before any output: a first run's notice comes first
            runtime.init(
                getattr(args, "arch", None), getattr(args, "precision", None), profile=getattr(args, "profile", False)
            )
        return COMMANDS[args.command](args)
    except ConfigError as exc:
        print(f"ti-golf: error: {exc}", file=sys.stderr)
        return 2
    except SimulationError as exc:
        print(f"ti-golf: simulation stopped: {exc}", file=sys.stderr)
        return 3
    except TiGolfError as exc:  # pragma: no cover - future error kinds
        print(f"ti-golf: error: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:  # a file that went away or a full disk while reading or writing: no traceback
        where = f"{exc.filename}: " if exc.filename else ""
        print(f"ti-golf: error: {where}{exc.strerror or exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt as exc:
        print(f"ti-golf: interrupted{f' {exc}' if exc.args else ''}", file=sys.stderr)
        return 130
    finally:
        if on_main_thread:
            signal.signal(signal.SIGTERM, previous)
