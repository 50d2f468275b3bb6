"""Where a process's start goes: each Taichi kernel's front end and its compilation, timed.

Taichi prepares a kernel the first time it is launched with a new set of template arguments (an
instance), in two steps:

1. the **front end** (``Kernel.materialize``): Python parses the kernel's source and transforms its
   AST, inlining every ``ti.func`` it calls, into Taichi's IR. It runs in every new process, for
   every instance, even when the compiled kernel then comes from the offline cache, because the
   cache's key is a hash of that IR;
2. the **compilation** (``Program.compile_kernel``, at the first launch): the IR optimised and
   compiled by LLVM, or, when the offline cache holds the kernel, loaded from it;
3. the rest of that **first launch**: on the CPU, the machine code for the compiled module, then
   the kernel's first run. The cache keeps the module as LLVM IR text, already through LLVM's O3
   passes; every process parses it and has LLVM's JIT select instructions and allocate registers
   for it again, a cost that grows with the IR's length (loops the O3 passes unrolled or
   vectorised, and each ``ti.func`` inlined at every call site, count as often as they appear).

:class:`KernelLog` wraps both (for as long as it is installed) and keeps, per kernel, the instances
prepared (by the names Taichi gives them) and the seconds of each step. Which instances came from
the cache Taichi says only in its debug log ("Create kernel 'NAME' from cache"):
:func:`cache_hits` reads them from a log. ``ti-golf bench startup --kernels SCENE`` prints the
table; the CLI reads the log to say what it is doing while a start takes long.
"""

from __future__ import annotations

import re
import struct
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from taichi.lang import impl
from taichi.lang.kernel_impl import Kernel

CACHE_LINE = re.compile(r"(?:Create kernel '([^']+)' from cache|Cache kernel '([^']+)') \(key='(\w+)'\)")
"""Taichi's debug-log lines (``TI_LOG_LEVEL=debug``) for an instance loaded from the offline cache
or compiled into it (the file is written when the process ends): its name, and its key there."""


def cache_hits(log: str) -> set[str]:
    """The names of the kernel instances that Taichi's debug ``log`` says it loaded from the cache."""
    return {loaded for loaded, _, _ in CACHE_LINE.findall(log) if loaded}


def cache_keys(log: str) -> dict[str, str]:
    """Each kernel instance's key in the offline cache, by the instance's name, from Taichi's debug
    ``log`` (loaded or compiled): its module lies in the cache folder as ``KEY.tic``."""
    return {loaded or cached: key for loaded, cached, key in CACHE_LINE.findall(log)}


CACHE_FILE_MAGIC = b"TIC\0"
"""The first bytes of a file of Taichi 1.7's offline cache: then a version, the lengths of the
metadata and of the module's source (two little-endian 64-bit integers), the metadata (JSON), the
source (on the CPU and CUDA, LLVM IR text) and a checksum."""


def cached_module_lines(path: Path) -> int | None:
    """Lines of the compiled module that the offline-cache file ``path`` holds: its length, which
    the machine code made from it at every first launch grows with (LLVM IR text on the CPU);
    ``None`` when the file is missing or not of the form :data:`CACHE_FILE_MAGIC` describes."""
    try:
        data = path.read_bytes()
    except OSError:
        return None
    if len(data) < 24 or not data.startswith(CACHE_FILE_MAGIC):
        return None
    metadata, source = struct.unpack_from("<QQ", data, 8)
    if 24 + metadata + source > len(data):
        return None
    return data.count(b"\n", 24 + metadata, 24 + metadata + source)


@dataclass
class KernelTimes:
    """The preparation of one kernel (all its instances) in this process.

    Attributes:
        name: the kernel's module and name (``ti_golf.physics.kernels.advance``).
        instances: instances prepared (one per set of template arguments).
        front_end_s: seconds in Taichi's front end (parse and AST transform).
        compile_s: seconds compiling, or loading from the cache.
        first_launch_s: seconds of the first launches of its instances, less their compilation:
            the machine code made from the compiled module and the first run of the kernel.
        instance_names: the instances' names as Taichi's log writes them (``advance_c12_0``).
    """

    name: str
    instances: int = 0
    front_end_s: float = 0.0
    compile_s: float = 0.0
    first_launch_s: float = 0.0
    instance_names: list[str] = field(default_factory=list)


class KernelLog:
    """Times each kernel's front end and compilation while :meth:`installed` (see the module).

    ``busy`` says what Taichi is doing now (``("front end", "compile" or "first launch", kernel
    name, since)``, ``None`` between kernels), for a status line read from another thread: a
    first launch runs the kernel once it is compiled, so a long one is the kernel's work."""

    def __init__(self) -> None:
        self.kernels: dict[str, KernelTimes] = {}
        self.busy: tuple[str, str, float] | None = None
        self._seen: set[int] = set()
        self._lock = threading.Lock()

    def _times(self, kernel: Kernel) -> KernelTimes:
        name = f"{kernel.func.__module__}.{kernel.func.__name__}"
        with self._lock:
            return self.kernels.setdefault(name, KernelTimes(name))

    @contextmanager
    def _step(self, what: str, kernel: Kernel) -> Iterator[KernelTimes]:
        entry = self._times(kernel)
        self.busy = (what, entry.name, time.perf_counter())
        try:
            yield entry
        finally:
            self.busy = None

    def totals(self) -> tuple[int, float, float, float]:
        """(instances prepared, front-end seconds, compile-or-load seconds, first-launch seconds)."""
        with self._lock:
            rows = list(self.kernels.values())
        return (
            sum(k.instances for k in rows),
            sum(k.front_end_s for k in rows),
            sum(k.compile_s for k in rows),
            sum(k.first_launch_s for k in rows),
        )

    def table(self) -> list[KernelTimes]:
        """The kernels, the longest front end first."""
        with self._lock:
            return sorted(self.kernels.values(), key=lambda k: (-k.front_end_s, k.name))

    @contextmanager
    def installed(self) -> Iterator[KernelLog]:
        """Time every kernel prepared inside the block (Taichi's ``Kernel`` patched, put back after)."""
        materialize, launch = Kernel.materialize, Kernel.launch_kernel
        log = self

        def timed_materialize(kernel: Kernel, key: Any = None, args: Any = None, arg_features: Any = None) -> None:
            whole = (kernel.func, 0, kernel.autodiff_mode) if key is None else key
            if whole in kernel.compiled_kernels:  # (every launch asks: already prepared)
                return materialize(kernel, key, args, arg_features)
            kernel.runtime.materialize()  # (the runtime's own start, once per process: not the kernel's)
            with log._step("front end", kernel) as entry:
                start = time.perf_counter()
                materialize(kernel, key, args, arg_features)
                entry.front_end_s += time.perf_counter() - start
                entry.instances += 1
                entry.instance_names.append(f"{kernel.func.__name__}_c{kernel.kernel_counter}_{whole[1]}")

        def timed_launch(kernel: Kernel, t_kernel: Any, *args: Any) -> Any:
            if id(t_kernel) in log._seen:
                return launch(kernel, t_kernel, *args)
            log._seen.add(id(t_kernel))
            runtime = impl.get_runtime()
            program = runtime.prog
            with log._step("compile", kernel) as entry:
                runtime.prog = _TimedProgram(program, entry, log)
                start, compiled_before = time.perf_counter(), entry.compile_s
                try:
                    return launch(kernel, t_kernel, *args)
                finally:
                    runtime.prog = program
                    entry.first_launch_s += time.perf_counter() - start - (entry.compile_s - compiled_before)

        Kernel.materialize, Kernel.launch_kernel = timed_materialize, timed_launch
        try:
            yield self
        finally:
            Kernel.materialize, Kernel.launch_kernel = materialize, launch


class _TimedProgram:
    """Taichi's program, with ``compile_kernel`` timed into a :class:`KernelTimes` (the rest passed
    on); once it has compiled, ``log.busy`` says the kernel's first launch goes on."""

    def __init__(self, program: Any, entry: KernelTimes, log: KernelLog) -> None:
        self._program = program
        self._entry = entry
        self._log = log

    def compile_kernel(self, *args: Any) -> Any:
        start = time.perf_counter()
        compiled = self._program.compile_kernel(*args)
        end = time.perf_counter()
        self._entry.compile_s += end - start
        self._log.busy = ("first launch", self._entry.name, end)
        return compiled

    def __getattr__(self, name: str) -> Callable[..., Any]:
        return getattr(self._program, name)
