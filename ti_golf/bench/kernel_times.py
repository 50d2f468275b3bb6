"""Where a benchmark's time goes, kernel by kernel, from Taichi's kernel profiler.

With the profiler on (``ti-golf bench pit --profile``, :func:`ti_golf.runtime.init` with
``profile``), Taichi times every parallel loop of every kernel launch, waiting for each to end
before the next starts. :class:`KernelTimes` sums those times by kernel (the Python function that
``ti.kernel`` compiled, all its loops together) and counts its launches; what the wall time holds
beyond the kernels' sum is the host's part: Python, the launches' argument set-up and the reads
of results. The profiler keeps a record per loop and launch, so the records are folded into the
sums and dropped every :data:`FOLD_EVERY` steps (a 100,000-ball pour would otherwise gather
tens of megabytes of them, counted as the pour's memory).
"""

from __future__ import annotations

import re
from collections import Counter
from typing import Any

import taichi as ti

FOLD_EVERY = 100
"""Steps after which the profiler's records are folded into the sums and dropped."""

_TASK_NAME = re.compile(r"^(?P<instance>(?P<kernel>.+)_c\d+_\d+)_kernel_\d+_[a-z_]+$")
"""Taichi 1.7.4's name of a kernel's offloaded loop: ``<kernel>_c<N>_<M>_kernel_<K>_<kind>``, where
``<kernel>_c<N>_<M>`` names one compiled instance of the kernel (one set of ``ti.template``
arguments) and ``kernel_<K>`` the loop."""


def profiling() -> bool:
    """Whether Taichi's kernel profiler is on in this process."""
    return bool(ti.lang.impl.current_cfg().kernel_profiler)


def kernel_of(loop: str) -> tuple[str, str]:
    """The kernel (Python function) and its compiled instance that a loop's profiler name
    (:data:`_TASK_NAME`) is of; the name itself for both when it has not that form."""
    m = _TASK_NAME.match(loop)
    return (m.group("kernel"), m.group("instance")) if m else (loop, loop)


class KernelTimes:
    """Seconds spent in each kernel and its launches, summed over the profiler's records."""

    def __init__(self) -> None:
        self.seconds: Counter[str] = Counter()
        self.launches: Counter[str] = Counter()
        self.drop()

    def fold(self) -> None:
        """Add the profiler's records since the last fold to the sums, and drop them. A kernel's
        launches are, summed over its compiled instances, those of the instance's loop launched
        most (each loop of an instance runs once per launch of it)."""
        profiler = ti.profiler.kernel_profiler.get_default_kernel_profiler()
        profiler._update_records()  # (Taichi 1.7.4 has no public call for the records themselves)
        by_loop: Counter[str] = Counter()
        for record in profiler._traced_records:
            self.seconds[kernel_of(record.name)[0]] += record.kernel_time * 1e-3  # (the profiler's times are in ms)
            by_loop[record.name] += 1
        most: Counter[tuple[str, str]] = Counter()  # by (kernel, instance)
        for loop, count in by_loop.items():
            key = kernel_of(loop)
            most[key] = max(most[key], count)
        for (kernel, _), count in most.items():
            self.launches[kernel] += count
        self.drop()

    def drop(self) -> None:
        """Drop the profiler's records since the last fold, unsummed (kernels run between the timed
        steps, such as those that measure the pile)."""
        ti.profiler.clear_kernel_profiler_info()

    def total_s(self) -> float:
        """The kernels' seconds, all together."""
        return float(sum(self.seconds.values()))

    def as_dict(self) -> dict[str, Any]:
        """``{kernel: {"s": seconds, "launches": n}}``, the dearest first."""
        return {k: {"s": s, "launches": self.launches[k]} for k, s in self.seconds.most_common()}
