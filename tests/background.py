"""Slow subprocesses that tests need, run in the background while the other tests run.

Most of the suite's time goes to compiling kernels, one process at a time on one core. A few
tests run a whole process of their own, which compiles its own kernels for up to two minutes:
the Vulkan pile, the bounds-checked (debug) kernels, the collide benches, the f32 sweep, a
terrain run through the CLI; and three of the narrow pit's pours (tests/pile_pours.py) take as
long on one core. Their processes do not depend on the tests before them, so they can start as
soon as the session does and run one after another beside the main process, on the CI machine's
second core; the test then only waits for its run's result and checks it. Measured on the 2-core
CI machine from an empty kernel cache (2026-11-23): six of those runs took 387 of the suite's
922 seconds (the boulder bench 8.5: it loaded the kernels another had compiled), and the suite
572 seconds with seven in the background and their tests last (the terrain run, 45 s in the main
process then, went to the background after that).

A module declares such a run with :func:`declare` (a key and a function that writes what the run
needs into its own directory and returns its command), and a test that uses it carries the marker
``@pytest.mark.background(key)``; the session fixture ``background_runs`` (conftest) starts the
runs of the selected tests in the order the tests will run, and ``background_runs.result(key)``
waits for one. Those tests run last (conftest), so that every other test overlaps their runs. A run no selected test marked (a test run alone with ``-k``, say) runs when asked for.

The runs keep their compiled kernels in an offline cache of their own (``<Taichi's cache
path>-background``): Taichi locks its cache while a process reads or writes it and, when a lock
is not freed within 0.2 s, warns on stderr and compiles without it, which tests that read a
process's stderr would see.
"""

from __future__ import annotations

import os
import subprocess
import sys
import threading
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

Command = tuple[list[str], dict[str, str]]
"""A run's command line and the environment variables it adds to the session's."""

_DECLARED: dict[str, tuple[Callable[[Path], Command], float]] = {}


def declare(key: str, make: Callable[[Path], Command], timeout: float = 900) -> None:
    """Declare the run ``key``: ``make(workdir)`` writes what it needs into ``workdir`` (its own,
    empty) and returns its command; it is killed after ``timeout`` seconds."""
    if key in _DECLARED:
        raise ValueError(f"background run {key!r} declared twice")
    _DECLARED[key] = (make, float(timeout))


def python(*args: str) -> list[str]:
    """The command line of this Python running ``args``."""
    return [sys.executable, *args]


@dataclass
class _Run:
    workdir: Path
    done: threading.Event = field(default_factory=threading.Event)
    proc: subprocess.CompletedProcess | None = None
    error: BaseException | None = None


class BackgroundRuns:
    """The declared runs of one test session, run one after another on a thread of their own."""

    def __init__(self, root: Path, cache: str) -> None:
        self._root = root
        self._env = {**os.environ, "TI_OFFLINE_CACHE_FILE_PATH": cache}
        self._runs: dict[str, _Run] = {}
        self._queue: list[str] = []
        self._lock = threading.Lock()
        self._children: set[subprocess.Popen] = set()
        self._stopped = False
        self._thread = threading.Thread(target=self._work, name="background-runs", daemon=True)

    def start(self, keys: list[str]) -> None:
        """Start the runs ``keys`` (declared, each once, in this order) in the background."""
        for key in keys:
            if key not in _DECLARED:
                raise KeyError(f"background run {key!r} was never declared (tests/background.declare)")
            if key not in self._runs:
                self._runs[key] = _Run(self._root / key)
                self._queue.append(key)
        self._thread.start()

    def result(self, key: str) -> tuple[subprocess.CompletedProcess, Path]:
        """The finished run ``key`` and its directory: waits for it, or runs it now if it was not
        started in the background."""
        with self._lock:
            run = self._runs.get(key)
            now = run is None
            if now:
                run = self._runs[key] = _Run(self._root / key)
        if now:
            self._execute(key, run)
        run.done.wait()
        if run.error is not None:
            raise run.error
        if run.proc is None:
            raise RuntimeError(f"background run {key!r} did not finish (stopped, or its thread failed: see the log)")
        return run.proc, run.workdir

    def succeeded(self, key: str, unavailable: str) -> tuple[subprocess.CompletedProcess, Path]:
        """:meth:`result` of a run that exits with 77 when this machine cannot do what it tries (the
        test is then skipped, saying ``unavailable``) and must otherwise exit with 0."""
        import pytest

        done, workdir = self.result(key)
        if done.returncode == 77:
            pytest.skip(unavailable)
        assert done.returncode == 0, done.stderr[-2000:]
        return done, workdir

    def stop(self) -> None:
        """Kill the run in progress and start no other (the session ends)."""
        with self._lock:
            self._stopped = True
            self._queue.clear()
            children = list(self._children)
        for child in children:
            if child.poll() is None:
                child.kill()

    def _work(self) -> None:
        try:
            while True:
                with self._lock:
                    if self._stopped or not self._queue:
                        return
                    key = self._queue.pop(0)
                self._execute(key, self._runs[key])
        finally:  # stopped, or failed: no test waits for a run that will not come
            with self._lock:
                left = [self._runs[key] for key in self._queue]
                self._queue.clear()
            for run in left:
                run.done.set()

    def _execute(self, key: str, run: _Run) -> None:
        try:
            make, timeout = _DECLARED[key]
            run.workdir.mkdir(parents=True, exist_ok=True)
            argv, env = make(run.workdir)
            child = subprocess.Popen(
                argv,
                stdout=subprocess.PIPE,
                stderr=subprocess.PIPE,
                text=True,
                env={**self._env, **env},
                cwd=Path(__file__).resolve().parent.parent,
            )
            with self._lock:
                self._children.add(child)
                if self._stopped:  # the session ended while it started
                    child.kill()
            try:
                out, err = child.communicate(timeout=timeout)
            except subprocess.TimeoutExpired:
                child.kill()
                out, err = child.communicate()
                raise subprocess.TimeoutExpired(argv, timeout, out, err) from None
            finally:
                with self._lock:
                    self._children.discard(child)
            run.proc = subprocess.CompletedProcess(argv, child.returncode, out, err)
        except (OSError, subprocess.SubprocessError) as error:  # handed to the test that asks for it
            run.error = error
        finally:
            run.done.set()
