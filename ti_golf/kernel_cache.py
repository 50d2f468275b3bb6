"""Taichi's offline kernel cache shared by processes that run at once: their turns at its metadata.

Taichi 1.7 guards the cache's metadata with a lock file that a process creates, tries five times
50 ms apart, and gives up on with a raw warning ("Lock .../ticache.lock failed. Please run 'ti
cache clean' ..."). It takes that lock twice: when the process first compiles a kernel (it then
reads which kernels the cache holds; without them it compiles every kernel again, seconds where a
load takes milliseconds) and when its runtime ends (it then writes every kernel it compiled or
loaded, and with them the metadata). Two ``ti-golf`` commands at once, the workers of a study on
one machine, or the two workers of the test suite meet there now and then, and one process's
writes can last longer than another's 0.2 s of tries.

:func:`taking_turns` is a lock of the operating system's (``flock``) on a file in the cache
folder, which a process holds while Taichi takes its own: the others wait for their turn, as
long as the turn lasts, instead of giving up. :func:`ti_golf.runtime.init` holds it while the
first kernel of the process compiles (:func:`open_cache`), and the end of the runtime
(:func:`ti_golf.runtime.reset_runtime`) while Taichi writes the cache.
"""

from __future__ import annotations

import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import IO

import taichi as ti

try:  # (POSIX; elsewhere each process takes Taichi's own lock alone, as before)
    import fcntl
except ImportError:  # pragma: no cover - Windows
    fcntl = None  # type: ignore[assignment]

LOCK_NAME = "ti_golf.lock"
"""The file of :func:`taking_turns`' lock, in the cache folder (beside Taichi's ``ticache.lock``)."""

WAIT_S = 60.0
"""Longest wait [s] for the turn; past it the process goes on as Taichi alone would (a process
that stopped while holding the lock frees it as it ends, so only a hung one is waited out)."""


def cache_folder() -> Path:
    """The folder of Taichi's offline kernel cache, as ``ti.init`` settled it (from
    ``TI_OFFLINE_CACHE_FILE_PATH``, else Taichi's default)."""
    return Path(ti.lang.impl.current_cfg().offline_cache_file_path)


@contextmanager
def taking_turns(folder: Path | None = None, wait_s: float = WAIT_S) -> Iterator[bool]:
    """Hold the turn at the cache in ``folder`` (default :func:`cache_folder`) for the block,
    waiting up to ``wait_s`` seconds for another process to end its own; yields whether the turn
    was taken (False where the lock cannot be had: no ``flock``, a folder that cannot be written,
    or the wait over)."""
    handle = _lock_file(folder or cache_folder())
    taken = False
    try:
        if handle is not None:
            deadline = time.monotonic() + wait_s
            while True:
                try:
                    fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
                    taken = True
                    break
                except BlockingIOError:
                    if time.monotonic() >= deadline:
                        break
                    time.sleep(0.01)
        yield taken
    finally:
        if handle is not None:
            handle.close()  # (closing the file frees the lock)


def _lock_file(folder: Path) -> IO[str] | None:
    """The lock's file in ``folder``, opened (the folder made if need be), or None."""
    if fcntl is None:
        return None
    try:
        folder.mkdir(parents=True, exist_ok=True)
        return open(folder / LOCK_NAME, "a")  # noqa: SIM115 - held open as long as the lock
    except OSError:
        return None


@ti.kernel
def _first_kernel():
    """Nothing: a kernel to load or compile, so that Taichi reads its cache's metadata now."""
    pass


def open_cache() -> None:
    """Have Taichi read which kernels its cache holds, in this process's turn (Taichi does so when
    it first compiles or loads a kernel: a trivial one, a few milliseconds). Call after
    ``ti.init``."""
    with taking_turns():
        _first_kernel()
