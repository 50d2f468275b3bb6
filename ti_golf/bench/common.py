"""Helpers of the benchmarks: best-of timing, JSON output, the process's resident memory."""

from __future__ import annotations

import json
import os
import time
from collections.abc import Callable
from typing import Any


def _best_time(fn: Callable[[], Any], repeats: int) -> float:
    best = float("inf")
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


def faster(q: float, digits: int = 1) -> str:
    """A speed ratio ``q`` (this one's speed over another's) in words: ``"2.5x faster"``, or
    ``"1.7x slower"`` below 1."""
    return f"{q:,.{digits}f}x faster" if q >= 1.0 else f"{1.0 / q:,.{digits}f}x slower"


def to_json(result: dict[str, Any]) -> str:
    """One line of JSON (floats rounded to 6 significant digits, in dicts, lists and tuples at any
    depth: the pit's ``timeline``, the start-up's ``commands``)."""

    def clean(o: Any) -> Any:
        if isinstance(o, float):
            return float(f"{o:.6g}")
        if isinstance(o, dict):
            return {k: clean(v) for k, v in o.items()}
        if isinstance(o, (list, tuple)):
            return [clean(v) for v in o]
        return o

    return json.dumps(clean(result))


def _rss_bytes() -> int:
    """Current resident set size [bytes] (Linux /proc; peak RSS elsewhere)."""
    try:
        with open("/proc/self/statm") as fh:
            return int(fh.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")
    except OSError:  # pragma: no cover
        return _peak_rss_bytes()


def _restart_peak_rss() -> bool:
    """Restart the OS's count of this process's peak resident set size from the current one
    (Linux ≥ 4.0: ``/proc/self/clear_refs``); whether it could. Elsewhere the peak stays the
    process's lifetime peak."""
    try:
        with open("/proc/self/clear_refs", "w") as fh:
            fh.write("5")
        return True
    except OSError:  # pragma: no cover
        return False


def _peak_rss_bytes() -> int:
    """Peak resident set size [bytes] of this process since its start or the last
    :func:`_restart_peak_rss` (Linux: ``VmHWM``; ``ru_maxrss`` elsewhere, which also keeps the
    peaks of threads that have exited)."""
    try:
        with open("/proc/self/status") as fh:
            for line in fh:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1]) * 1024  # kB
    except OSError:  # pragma: no cover
        pass
    import resource  # pragma: no cover  (POSIX only; reached where /proc is missing)

    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024  # pragma: no cover
