"""Steps that Ctrl-C (SIGINT) or SIGTERM cannot cut in half.

A step updates the state in several places (the kernels' arrays, then the time and the step
count; a parallel step swaps the positions with the solver's scratch), and a signal arriving in
between would leave a state that no step produced: a run saved after it could not be continued
as the run that never stopped. :func:`whole_steps` holds the signals while steps run and delivers
them, to the handlers that were there, once the steps are done.
"""

from __future__ import annotations

import signal
import sys
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

HELD = (signal.SIGINT, signal.SIGTERM)
"""The signals held while steps run."""


class KeptInterrupt(KeyboardInterrupt):
    """Ctrl-C (or SIGTERM) that stopped work between whole steps or launches, holding what had
    been computed by then (``kept``), for the caller to keep."""

    def __init__(self, kept: Any) -> None:
        super().__init__()
        self.kept = kept  # (each layer's own result: what it raises is documented where it is raised)


def not_ignored(signals: tuple[int, ...]) -> list[int]:
    """Those of ``signals`` the process does not ignore: a signal ignored (``nohup``, ``trap ''
    INT``, a background job of a script) stays ignored by whoever holds signals, since a held one
    would stop the work early while the program went on as if it had all been done."""
    return [s for s in signals if signal.getsignal(s) is not signal.SIG_IGN]


@contextmanager
def whole_steps(note: str | None = None) -> Iterator[list[int]]:
    """Hold :data:`HELD` inside the block and raise each one that came, in order, when it ends
    (with the handlers restored: Ctrl-C then raises ``KeyboardInterrupt`` after the last whole
    step). The block gets the list of the signals held so far, to stop early between its steps
    when one came; a block that clears it drops them. ``note``: a line written to stderr when the
    first signal is held (what the program finishes before it stops). A signal the process ignores
    stays ignored. Outside the main thread, where Python runs no signal handler, it holds nothing."""
    came: list[int] = []
    if threading.current_thread() is not threading.main_thread():
        yield came
        return

    def hold(signum: int, frame: object) -> None:
        if note is not None and not came:
            print(f"ti-golf: {note}", file=sys.stderr, flush=True)
        came.append(signum)

    previous = {s: signal.signal(s, hold) for s in not_ignored(HELD)}
    try:
        yield came
    finally:
        for s, handler in previous.items():
            signal.signal(s, signal.SIG_DFL if handler is None else handler)  # None: set outside Python
        for signum in dict.fromkeys(came):
            signal.raise_signal(signum)


@contextmanager
def ctrl_c_held(block: bool = False) -> Iterator[None]:
    """Ctrl-C (SIGINT) held inside the block and raised as it ends: for work that a
    ``KeyboardInterrupt`` would leave broken, such as an import (a compiled extension interrupted
    while it initialises fails for good). With ``block`` it is also blocked on this thread, so
    that the threads and processes started meanwhile inherit it blocked and never see it (a
    terminal's Ctrl-C reaches every process of its group: the caller alone then handles it); it is
    recorded should another thread take it. Only on the main thread (where Python handles
    signals), and not where Ctrl-C is ignored."""
    previous = signal.getsignal(signal.SIGINT)
    if threading.current_thread() is not threading.main_thread() or previous is signal.SIG_IGN:
        yield
        return
    came: list[int] = []
    signal.signal(signal.SIGINT, lambda signum, frame: came.append(signum))
    mask = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT}) if block else None
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, signal.SIG_DFL if previous is None else previous)
        if mask is not None:
            signal.pthread_sigmask(signal.SIG_SETMASK, mask)  # (one pending is taken by the handler put back)
        if came:
            signal.raise_signal(signal.SIGINT)
