"""``ti-golf``: the parser of every command and the entry point; ``main(argv) -> exit code``.

Bad input exits with code 2 and one line naming the file, the key and what is allowed; a
simulation that goes non-finite exits with code 3.
"""

from __future__ import annotations

import argparse
import importlib
import os
import signal
import sys
import threading
from collections.abc import Callable, Sequence
from types import ModuleType
from typing import Any

from ti_golf.cli._common import API_OPTIONS, Parser, StartupStatus, options_named
from ti_golf.errors import ConfigError, SimulationError, TiGolfError

COMMANDS: dict[str, tuple[str, str]] = {
    "scenes": ("scenes", "cmd_scenes"),
    "keys": ("scenes", "cmd_keys"),
    "schema": ("schema", "cmd_schema"),
    "sweep": ("sweep", "cmd_sweep"),
    "shot": ("shot", "cmd_shot"),
    "dispersion": ("dispersion", "cmd_dispersion"),
    "run": ("run", "cmd_run"),
    "table": ("table", "cmd_table"),
    "tour": ("tour", "cmd_tour"),
    "fit-aero": ("tour", "cmd_fit_aero"),
    "figure": ("figure", "cmd_figure"),
    "bench": ("bench", "cmd_bench"),
    "render": ("render", "cmd_render"),
    "play": ("play", "cmd_play"),
    "lab": ("lab", "cmd_lab"),
    "study": ("study", "cmd_study"),
}
"""Each subcommand's module in ``ti_golf.cli`` and the function there that runs it (parsed
arguments -> exit code), in the order ``ti-golf --help`` lists them."""

NO_RUNTIME = ("scenes", "keys", "schema", "study")
"""Commands that start no Taichi runtime: they simulate nothing, or (a study) leave it to their
worker processes, each of which starts its own."""


def _module(command: str) -> ModuleType:
    return importlib.import_module(f"ti_golf.cli.{COMMANDS[command][0]}")


def _command(command: str) -> Callable[[argparse.Namespace], int]:
    return getattr(_module(command), COMMANDS[command][1])


class _Version(argparse.Action):
    """``--version``: the package's version, read only when asked for (see ``ti_golf.__version__``)."""

    def __call__(self, parser: argparse.ArgumentParser, *args: Any) -> None:
        from ti_golf import __version__

        print(f"ti-golf {__version__}")
        parser.exit()


def build_parser(argv: Sequence[str] | None = None) -> Parser:
    """The argument parser of ``ti-golf``: with ``argv`` that names a command, that command's parser
    alone (only its module is imported: ``ti-golf keys`` imports neither Taichi nor the plotting
    libraries); else every command's."""
    p = Parser(prog="ti-golf", description="Golf-ball physics on Taichi: flights, sweeps, collisions.")
    p.add_argument("--version", action=_Version, nargs=0, help="show the version and exit")
    sub = p.add_subparsers(dest="command", required=True, parser_class=Parser)
    named = argv[0] if argv and argv[0] in COMMANDS else None
    modules = [COMMANDS[named][0]] if named else list(dict.fromkeys(m for m, _ in COMMANDS.values()))
    for name in modules:
        importlib.import_module(f"ti_golf.cli.{name}").add_parser(sub)
    return p


def run_cli() -> None:
    """The ``ti-golf`` command and ``python -m ti_golf``: :func:`main`, whose code the process then
    exits with (see ``runtime.exit_process``: Taichi's runtime can crash the normal exit)."""
    try:
        code = main(status=True)
    except BrokenPipeError:  # the reader of stdout left (``ti-golf keys | head``): end quietly
        code = _reader_gone()
    try:
        sys.stdout.flush()  # (what is still buffered, while the exit can still be chosen)
    except BrokenPipeError:
        code = _reader_gone()
    if "ti_golf.runtime" in sys.modules:  # Taichi was started (a command that simulates)
        for held in (signal.SIGINT, signal.SIGTERM):  # the command is over: its exit work (the kernels
            signal.signal(held, signal.SIG_IGN)  # written to the cache) is not cut off by a late Ctrl-C
        sys.modules["ti_golf.runtime"].exit_process(code)
    sys.exit(code)


def _reader_gone() -> int:
    """Exit code of a command whose standard output was closed by its reader (``ti-golf keys |
    head``): output goes nowhere from now on, so that no error follows, and the code is the one
    a shell gives a command stopped by SIGPIPE (128 + 13), which shells and ``head`` pass over."""
    os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
    return 128 + signal.SIGPIPE


def _interrupt(signum: int, frame: object) -> None:
    """SIGTERM handler: stop as Ctrl-C does (``KeyboardInterrupt``), so outputs are kept."""
    raise KeyboardInterrupt


def _run_command(args: argparse.Namespace, status: bool) -> int:
    """Run the parsed command, Taichi started first unless the command needs none (with
    ``status``, the start's waits said on standard error: :class:`StartupStatus`)."""
    if args.command not in NO_RUNTIME and not getattr(args, "no_runtime", False):  # notice before output
        from ti_golf import runtime

        runtime.announce_first_compile = True
        runtime.init(
            getattr(args, "arch", None), getattr(args, "precision", None), profile=getattr(args, "profile", False)
        )
        if status:
            from ti_golf.kernel_log import KernelLog

            with KernelLog().installed() as log, StartupStatus(log):
                return _command(args.command)(args)
    return _command(args.command)(args)


def main(argv: Sequence[str] | None = None, status: bool = False) -> int:
    """Entry point of ``ti-golf`` and ``python -m ti_golf``; returns the exit code. With ``status``
    (the console command) a start that waits on Taichi's kernels says what it is doing
    (:class:`~ti_golf.cli._common.StartupStatus`)."""
    argv = sys.argv[1:] if argv is None else list(argv)
    try:
        args = build_parser(argv).parse_command_line(argv)
    except ConfigError as exc:  # (a switch read as the command's modules are imported: TI_GOLF_PLAIN_FRONT_END)
        print(f"ti-golf: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:  # (a Ctrl-C while the command's modules are imported, before it started)
        print("ti-golf: interrupted", file=sys.stderr)
        return 130
    on_main_thread = threading.current_thread() is threading.main_thread()
    if on_main_thread:  # a kill stops as Ctrl-C does, keeping what was done (signals reach the main thread only)
        previous = signal.signal(signal.SIGTERM, _interrupt)
    try:
        with options_named(API_OPTIONS):  # (the package's errors name its Python arguments)
            return _run_command(args, status)
    except BrokenPipeError:  # (an OSError) the reader of standard output left: see run_cli
        raise
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
        said: BaseException = exc  # (a Ctrl-C again while the first one's outputs were written: its words)
        while not said.args and isinstance(said.__context__, KeyboardInterrupt):
            said = said.__context__
        print(f"ti-golf: interrupted{f' {said}' if said.args else ''}", file=sys.stderr)
        return 130
    finally:
        if on_main_thread:
            signal.signal(signal.SIGTERM, previous)
