"""Options, checks and progress shared by the ``ti-golf`` commands."""

from __future__ import annotations

import argparse
import contextlib
import difflib
import math
import os
import re
import sys
import threading
import time
from collections.abc import Iterator, Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ti_golf.errors import OVERRIDES, ConfigError
from ti_golf.files import PLOT_FORMATS, PLOT_FORMATS_HELP, plot_format, write_problem

if TYPE_CHECKING:
    import rich.progress

    from ti_golf.sim.simulation import Simulation


class Parser(argparse.ArgumentParser):
    """argparse that reports usage errors as one line with exit code 2 (its default code), and
    takes a value that starts with a negative number as a value: ``--angles -10,45`` and
    ``--angles -10:10:5`` as ``--angles -10``, where argparse took them for unknown options."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self._negative_number_matcher = re.compile(r"^-\.?\d")  # (no option of ti-golf starts with a digit)

    def error(self, message: str) -> None:  # type: ignore[override]
        self.print_usage(sys.stderr)
        self.exit(2, f"ti-golf: error: {message}\n")

    def parse_command_line(self, argv: list[str]) -> argparse.Namespace:
        """``parse_args``, but arguments that no parser took are reported by the (sub)command's
        parser they were given to, with its usage, and with the option it most likely meant:
        argparse's own reports them with the top-level usage alone."""
        args, extra = self.parse_known_args(argv)
        if extra:
            parser = self._command_parser(args)
            names = [o[2:] for action in parser._actions for o in action.option_strings if o.startswith("--")]
            guesses = [
                difflib.get_close_matches(a.split("=", 1)[0].lstrip("-"), names, n=1, cutoff=0.7)
                for a in extra
                if a.startswith("-")
            ]
            near = [f"'--{g[0]}'" for g in guesses if g]
            hint = f" (did you mean {', '.join(near)}?)" if near else ""
            parser.error(f"unrecognized arguments: {' '.join(extra)}{hint}")
        args.given = self._given(argv)
        return args

    def _given(self, argv: list[str]) -> frozenset[str]:
        """The ``dest`` of each option that ``argv`` gives, whatever its value (an option given at
        its default value is given all the same): ``argv`` parsed again with every default of
        every (sub)command's parser suppressed, so that only what was given is set."""
        parsers = self._parsers()
        actions = [(action, action.default) for parser in parsers for action in parser._actions]
        set_defaults = [(parser, parser._defaults) for parser in parsers]
        try:
            for action, _ in actions:
                action.default = argparse.SUPPRESS
            for parser in parsers:
                parser._defaults = {}
            given, _ = self.parse_known_args(argv)
        finally:
            for action, default in actions:
                action.default = default
            for parser, defaults in set_defaults:
                parser._defaults = defaults
        return frozenset(vars(given))

    def _parsers(self) -> list[argparse.ArgumentParser]:
        """This parser and every (sub)command's parser below it."""
        parsers: list[argparse.ArgumentParser] = [self]
        for action in self._actions:
            if isinstance(action, argparse._SubParsersAction):
                for sub in dict.fromkeys(action.choices.values()):
                    parsers += sub._parsers() if isinstance(sub, Parser) else [sub]
        return parsers

    def _command_parser(self, args: argparse.Namespace) -> argparse.ArgumentParser:
        """The innermost parser of the (sub)commands ``args`` names."""
        parser: argparse.ArgumentParser = self
        while True:
            sub = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
            name = getattr(args, sub[0].dest, None) if sub else None
            if name is None:
                return parser
            parser = sub[0].choices[name]


def seed_value(text: str) -> int:
    """A ``--seed``: a whole number, 0 or more; argparse turns the error into a usage line (exit code 2)."""
    try:
        seed = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a whole number, 0 or more (got {text!r})") from None
    if seed < 0:
        raise argparse.ArgumentTypeError(f"must be a whole number, 0 or more (got {seed})")
    return seed


def runtime_options(p: argparse.ArgumentParser, window: bool = False) -> None:
    """``--arch`` and ``--precision``: the Taichi backend and float type of a command that simulates
    (``window``: a command that draws in a GGUI window, which GGUI draws with the CPU and CUDA
    backends alone: ``render.GGUI_ARCHES``)."""
    from ti_golf.runtime import ARCHES, PRECISIONS  # (imports Taichi: not for the commands without these options)

    if window:
        p.add_argument(
            "--arch",
            choices=("cpu", "cuda"),
            default=None,
            help="Taichi backend: cpu or cuda, those GGUI draws with (default: $TI_GOLF_ARCH or cpu)",
        )
    else:
        p.add_argument("--arch", choices=ARCHES, default=None, help="Taichi backend (default: $TI_GOLF_ARCH or cpu)")
    p.add_argument(
        "--precision", choices=PRECISIONS, default=None, help="float precision (default: $TI_GOLF_PRECISION or f64)"
    )


def scene_options(
    p: argparse.ArgumentParser,
    default: str | None = None,
    scene_help: str = "scene file, or the name of a bundled scene (see `ti-golf scenes`)",
    example: str = "air.wind=[-5,0,0]",
) -> None:
    """The positional scene (optional when it has a ``default``) and ``--set KEY=VALUE`` overrides."""
    if default is None:
        p.add_argument("scene", help=scene_help)
    else:
        with_default = scene_help if "default" in scene_help or not default else f"{scene_help} (default {default})"
        p.add_argument("scene", nargs="?", default=default, help=with_default)
    set_option(
        p,
        f"override a scene key with a TOML value, e.g. --set {example}; KEY= (no value) clears it, back "
        "to its default (repeatable)",
    )


def resume_option(p: argparse.ArgumentParser, what: str) -> None:
    """``--resume RUN.npz``: a run saved with ``ti-golf run --out`` in place of the scene (see
    :func:`scene_or_saved_run`); ``what`` says what the command does with it."""
    p.add_argument("--resume", metavar="RUN.npz", help=f"a run saved with `ti-golf run --out` instead of SCENE: {what}")


def scene_or_saved_run(args: argparse.Namespace, command: str) -> Simulation:
    """The simulation of ``args.scene`` at t0, or with ``args.resume`` the saved run where it
    stopped (:meth:`Simulation.load`), each with ``--set``'s changes; ``command`` names the
    subcommand in the error when neither or both are given."""
    from ti_golf.sim.simulation import Simulation

    if not args.resume:
        if not args.scene:
            raise ConfigError(
                command, None, "needs a SCENE (a scene file or a bundled scene's name) or --resume RUN.npz"
            )
        refuse_unread_keys(args.overrides, command)
        return Simulation.from_scene(args.scene, args.overrides)
    if args.scene:
        raise ConfigError("--resume", None, f"takes the scene from {args.resume}: leave out SCENE (got {args.scene!r})")
    sim = Simulation.load(args.resume)
    if args.overrides:
        sim.set(args.overrides)
    return sim


def refuse_unread_keys(overrides: list[str] | None, command: str, unread: Mapping[str, str] | None = None) -> None:
    """A ConfigError naming ``--set`` for a key that ``ti-golf command`` does not read (``unread``:
    keys or whole tables, each with who reads it, as in :mod:`ti_golf.scene.readers`; default:
    those no simulation reads, :data:`~ti_golf.scene.readers.NOT_READ`): a key without effect is
    an error."""
    from ti_golf.scene.readers import NOT_READ, unread_reason

    for text in overrides or ():
        key = set_key(text)
        reason = unread_reason(NOT_READ if unread is None else unread, key)
        if reason is not None:
            raise ConfigError("--set", key, f"has no effect on `ti-golf {command}` ({reason})")


def check_steps_span(steps: int | None, dt: float) -> None:
    """``--steps`` within :data:`~ti_golf.scene.checks.TIME_LIMIT` of simulated time at step ``dt``
    [s] (past it a step no longer moves the clock) and at most
    :data:`~ti_golf.sim.given.RUN_STEPS_MAX`, or a ConfigError saying how many steps that is."""
    from ti_golf.scene.checks import TIME_LIMIT
    from ti_golf.sim.given import RUN_STEPS_MAX

    if steps is not None and steps * dt > TIME_LIMIT:
        limit = f"{TIME_LIMIT / dt:.3g} steps of {dt:g} s ({TIME_LIMIT:g} s; got {steps})"
        raise ConfigError("--steps", None, f"must be at most {limit}")
    if steps is not None and steps > RUN_STEPS_MAX:
        raise ConfigError("--steps", None, f"must be at most {RUN_STEPS_MAX:.0e}, which would take days (got {steps})")


def set_key(text: str) -> str:
    """The KEY of a ``--set KEY=VALUE`` text, as the scene loader reads it."""
    return text.split("=", 1)[0].strip()


class _SetOnce(argparse.Action):
    """``--set KEY=VALUE`` appended to the list ``dest``; the same KEY twice is a
    :class:`ConfigError` (the first value would have no effect)."""

    def __call__(
        self, parser: argparse.ArgumentParser, namespace: argparse.Namespace, value: Any, option: Any = None
    ) -> None:
        given = list(getattr(namespace, self.dest, None) or [])  # (none: its default suppressed)
        key = set_key(str(value))
        if key and any(set_key(text) == key for text in given):
            raise ConfigError("--set", key, "is given twice: give it once")
        setattr(namespace, self.dest, [*given, value])


def set_option(p: argparse.ArgumentParser, help: str) -> None:
    """``--set KEY=VALUE`` (repeatable, each key once) into ``args.overrides``."""
    p.add_argument("--set", dest="overrides", action=_SetOnce, default=[], metavar="KEY=VALUE", help=help)


def check_writable(path: str | None, option: str, suffixes: tuple[str, ...] = ()) -> None:
    """Fail before a long computation rather than lose its result to an unwritable output path
    (``None``: the option was not given) or a path that names a folder (one that ends in a
    separator: ``shot.png/``, which Path would read as ``shot.png``), or write a format its name
    does not say: with ``suffixes`` (such as ``(".npz",)``), the file's name must end in one of them."""
    if path is None:
        return
    if not path.strip():
        raise ConfigError(option, None, "needs a file name (got an empty path)")
    if Path(path).is_dir() or Path(path).name in ("", ".", ".."):
        raise ConfigError(option, None, f"cannot write {path!r}: it is a folder; give a file name")
    if path.endswith(
        tuple(sep for sep in (os.sep, os.altsep, "/") if sep)
    ):  # (a folder's name, though none is there yet)
        raise ConfigError(option, None, f"cannot write {path!r}: it ends in a separator, as a folder; give a file name")
    parent = Path(path).resolve().parent
    if parent.exists() and not parent.is_dir():
        raise ConfigError(option, None, f"cannot write {path!r}: {str(parent)!r} is a file, not a folder")
    if not parent.is_dir():
        raise ConfigError(option, None, f"cannot write {path!r}: folder {str(parent)!r} does not exist")
    problem = write_problem(parent)
    if problem is not None:
        raise ConfigError(option, None, f"cannot write {path!r}: {problem}")
    if suffixes and Path(path).suffix.lower() not in suffixes:
        raise ConfigError(option, None, f"must end in {' or '.join(suffixes)} (got {path!r})")


def check_until(until: str | None, sim: "Simulation") -> None:
    """Refuse ``--until landed`` for a simulation none of whose balls is tracked for its landing:
    the run stopped at its first check, saying nothing."""
    if until == "landed" and sim.launch_x is None:
        raise ConfigError(
            "--until",
            None,
            f"landed has no effect on {sim.scene.name}: no ball of it is tracked for its landing (a [launch] ball "
            "shot above the ground is); give --until rest",
        )


API_OPTIONS = {
    OVERRIDES: "--set",
    "arch": "--arch",
    "precision": "--precision",
    "workers": "--workers",
    "address": "--address",
    "out": "--out",
}
"""Each Python argument that the package's errors may name, with the option that gives it on the
command line: ``ti-golf`` names the option instead (:func:`options_named`, around every command)."""


@contextlib.contextmanager
def options_named(options: dict[str, str]) -> Iterator[None]:
    """Name the command line's option in a :class:`ConfigError` that a Python function raised
    naming its argument: ``options`` maps each argument (``"angles_deg"``) to its option
    (``"--angles"``)."""
    try:
        yield
    except ConfigError as exc:
        if exc.source not in options:
            raise
        raise ConfigError(options[exc.source], exc.key, exc.reason) from None


def refuse_without(args: argparse.Namespace, options: dict[str, str], needs: str) -> None:
    """A key without effect is an error: each option of ``options`` (``dest`` → its flag) given
    while none of what it ``needs`` (words naming the options, which the caller found absent) is
    given."""
    refuse_given(args, options, f"without {needs}")


def refuse_given(args: argparse.Namespace, options: dict[str, str], why: str) -> None:
    """Each option of ``options`` (``dest`` → its flag) given on the command line, at any value
    (its default included: :meth:`Parser.parse_command_line` records what was given), is
    refused: it "has no effect ``why``"."""
    for dest, flag in options.items():
        if given(args, dest):
            raise ConfigError(flag, None, f"has no effect {why}")


def given(args: argparse.Namespace, dest: str) -> bool:
    """Whether the command line gave the option ``dest``, at any value (``args.given``, recorded
    by :meth:`Parser.parse_command_line`)."""
    return dest in args.given


def refuse_replaced(overrides: list[str] | None, replaced: dict[str, str]) -> None:
    """A ``--set`` of a key that the command replaces has no effect, so it is refused: ``replaced``
    maps each such key to what replaces it (an option given, or the command's own values)."""
    for text in overrides or ():
        key = set_key(text)
        if key in replaced:
            raise ConfigError("--set", key, f"has no effect with {replaced[key]}")


def check_plot(path: str | None, option: str = "--plot") -> None:
    """:func:`check_writable`, and the plot's format from its extension (:data:`PLOT_FORMATS_HELP`;
    none: PNG): a one-line error naming ``option`` and the allowed extensions for any other."""
    check_writable(path, option)
    if path is not None:
        plot_format(path, option)
        if not Path(path).suffix:  # (the plotting API adds .png, as matplotlib does: the CLI says what it writes)
            allowed = " or ".join(f".{f}" for f in PLOT_FORMATS)
            raise ConfigError(option, None, f"must end in {allowed} (got {path!r})")


def plot_help(what: str) -> str:
    """The help of a ``--plot`` option that writes ``what``."""
    return f"write {what}: {PLOT_FORMATS_HELP}"


SIZE_RANGE = (16, 8192)
"""Least and greatest width and height of a picture [pixels]."""


def parse_size(text: str) -> tuple[int, int]:
    """``WIDTHxHEIGHT`` [pixels] -> (width, height), each in :data:`SIZE_RANGE`; argparse turns the
    error into a usage line (exit code 2)."""
    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected WIDTHxHEIGHT, e.g. 1280x720 (got {text!r})") from None
    lo, hi = SIZE_RANGE
    if not (lo <= w <= hi and lo <= h <= hi):
        raise argparse.ArgumentTypeError(f"must be between {lo}x{lo} and {hi}x{hi} (got {w}x{h})")
    return w, h


def say_unfinished(sim: Simulation, args: argparse.Namespace) -> None:
    """For a run with ``--until`` that reached its time limit first: one line saying so, which
    limit, and which balls still move (or fly), by id."""
    from ti_golf.sim.simulation import UNTIL_DONE

    left = sim.unfinished(args.until)
    if not left.size:
        return
    if args.t is not None or args.steps is not None:
        limit = "--t" if args.t is not None else "--steps"
    else:
        since = " from where it resumed" if getattr(args, "resume", None) else ""
        limit = f"world.t_end = {sim.scene.world.t_end:g} s, the default length of a run{since}"
    ids = ", ".join(str(i) for i in left[:10]) + (f" and {left.size - 10:,} more" if left.size > 10 else "")
    moving = "still moving" if args.until == "rest" else "still in flight"
    print(
        f"stopped at the time limit ({limit}) before every ball was {UNTIL_DONE[args.until]}: "
        f"{left.size:,} {moving} (ball{'s' if left.size > 1 else ''} {ids}); a longer --t runs on"
    )


class Progress:
    """Progress of a run longer than a few seconds: a rich progress bar on a terminal, a plain line
    every few seconds otherwise (logs and CI read standard error).

    Called as ``progress(done, total)`` with simulated times [s] (``unit="s"``) or counts of
    ``unit`` (``"frames"``), and, for a run that stops early once every ball is finished (``--until``),
    ``finished=(k, n, what)``: k of n balls are ``what``. The fraction shown is then the larger of
    the time's and the balls', so that a run that ends long before its time limit is not shown
    stuck at a few per cent. :meth:`close` ends the bar.
    """

    def __init__(self, after_s: float = 3.0, every_s: float = 5.0, unit: str = "s") -> None:
        self.start = time.perf_counter()
        self.after_s, self.every_s = after_s, every_s
        self.unit = unit
        self.last = 0.0
        self.tty = sys.stderr.isatty()
        self._bar: rich.progress.Progress | None = None
        self._task: rich.progress.TaskID | None = None

    def __call__(self, done: float, total: float, finished: tuple[int, int, str] | None = None) -> None:
        now = time.perf_counter() - self.start
        if now < self.after_s:
            return
        frac = done / total if total else 1.0
        text = f"t = {done:.3g} of {total:.3g} s" if self.unit == "s" else f"{done:g} of {total:g} {self.unit}"
        if finished is not None:
            k, n, what = finished
            frac = max(frac, k / n if n else 1.0)
            text += f"; {k:,} of {n:,} balls {what}"
        if self.tty:
            if self._bar is None:
                import rich.console  # (on first use: some 25 ms of every command's start otherwise)
                import rich.progress

                self._bar = rich.progress.Progress(
                    rich.progress.BarColumn(),
                    rich.progress.TaskProgressColumn(),
                    rich.progress.TextColumn("{task.description}"),
                    rich.progress.TimeElapsedColumn(),
                    console=rich.console.Console(stderr=True),
                    transient=True,
                )
                self._task = self._bar.add_task(text, total=1.0)
                self._bar.start()
            assert self._task is not None
            self._bar.update(self._task, completed=frac, description=text)
        elif now - self.last >= self.every_s:
            self.last = now
            print(f"progress: {100 * frac:5.1f}% ({text}, {now:.0f} s elapsed)", file=sys.stderr)

    def close(self) -> None:
        if self._bar is not None:
            self._bar.stop()
            self._bar = None


class StartupStatus:
    """Says on standard error what Taichi is doing while a command waits for its kernels: from
    ``after_s`` seconds into the command, whenever a kernel has been in Taichi's front end or its
    compiler for half a second, a line naming it, the kernels ready so far and the seconds since
    the start (again every ``every_s`` seconds while it lasts). ``log`` is a
    :class:`ti_golf.kernel_log.KernelLog` (its ``busy`` and ``totals()``), read from a thread of
    its own."""

    STEPS = {
        "front end": "reading the kernel {name} (its front end runs in every new process, even for cached kernels)",
        "compile": "compiling the kernel {name} (or loading it from its cache)",
        "first launch": "making machine code for the kernel {name} and running it (its first launch)",
    }

    def __init__(self, log: Any, after_s: float = 1.0, every_s: float = 5.0, poll_s: float = 0.25) -> None:
        self.log = log
        self.after_s, self.every_s, self.poll_s = after_s, every_s, poll_s
        self.start = time.perf_counter()
        self._said = -math.inf
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._watch, name="ti-golf startup status", daemon=True)

    def __enter__(self) -> StartupStatus:
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._thread.join()

    def line(self) -> str | None:
        """The status line due now, or ``None``."""
        busy, now = self.log.busy, time.perf_counter()
        if busy is None or now - self.start < self.after_s or now - busy[2] < 0.5 or now - self._said < self.every_s:
            return None
        self._said = now
        what, name, _ = busy
        ready = self.log.totals()[0]
        return (
            f"ti-golf: Taichi is {self.STEPS[what].format(name=name.rsplit('.', 1)[-1])}; "
            f"{ready} kernel{'s' if ready != 1 else ''} ready, {now - self.start:.0f} s"
        )

    def _watch(self) -> None:
        while not self._stop.wait(self.poll_s):
            text = self.line()
            if text:
                print(text, file=sys.stderr, flush=True)
