"""The one place that calls ``ti.init``: backend choice, precision and fallbacks.

Backend: ``--arch`` / :func:`init` argument, else the environment variable ``TI_GOLF_ARCH``,
else ``cpu``. Precision: ``--precision`` / argument, else ``TI_GOLF_PRECISION``, else ``f64``
(the accuracy targets of the sweep are met in f64; f32 is faster on some GPUs).
"""

from __future__ import annotations

import atexit
import contextlib
import ctypes
import gc
import io
import os
import sys
import weakref
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import NoReturn

import numpy as np
import taichi as ti

from ti_golf import front_end, kernel_cache
from ti_golf.errors import ConfigError

ARCHES = ("cpu", "cuda", "vulkan", "gpu")
PRECISIONS = ("f32", "f64")


@dataclass(frozen=True)
class RuntimeInfo:
    """What :func:`init` settled on: requested and actual backend, the float type, and whether
    :func:`plain_compile` applies on CUDA too (the default; see :data:`CUDA_PASSES_ENV`)."""

    requested_arch: str
    arch: str
    precision: str
    plain_on_cuda: bool = True


_info: RuntimeInfo | None = None

announce_first_compile = False
"""Set by the CLI: :func:`init` then says on stderr when Taichi's kernel cache is still empty, so
a new user knows why the first commands on a machine pause (compiling, up to a minute in all)."""


CUDA_PASSES_ENV = "TI_GOLF_CUDA_PASSES"
"""Set to ``1`` to compile the kernels that :func:`plain_compile` wraps with Taichi's advanced IR
passes on CUDA (empty or ``0``: without them, the default), so that ``make gpu-check`` can time
both ways on one GPU."""


ON_THE_CPU = "running on the CPU"
"""The end of the note said when the backend asked for is not found (tools that start ti-golf
read it)."""


def _plain_on_cuda() -> bool:
    """Whether :func:`plain_compile` applies on CUDA: unless :data:`CUDA_PASSES_ENV` is ``1``."""
    text = os.environ.get(CUDA_PASSES_ENV, "")
    if text not in ("", "0", "1"):
        raise ConfigError(CUDA_PASSES_ENV, None, f"must be 1, 0 or empty, not {text!r}")
    return text != "1"


def resolve(arch: str | None, precision: str | None) -> tuple[str, str]:
    """The backend and precision that :func:`init` would start from the arguments given (``None``:
    ``$TI_GOLF_ARCH`` / ``$TI_GOLF_PRECISION``, else ``cpu`` / ``f64``), each checked: a
    :class:`ConfigError` naming the argument or the variable otherwise."""
    arch_from = "arch" if arch else "TI_GOLF_ARCH"
    prec_from = "precision" if precision else "TI_GOLF_PRECISION"
    arch = (arch or os.environ.get("TI_GOLF_ARCH") or "cpu").lower()
    precision = (precision or os.environ.get("TI_GOLF_PRECISION") or "f64").lower()
    if arch not in ARCHES:
        raise ConfigError(arch_from, None, f"unknown backend {arch!r}; allowed: {', '.join(ARCHES)}")
    if precision not in PRECISIONS:
        raise ConfigError(prec_from, None, f"unknown precision {precision!r}; allowed: f32, f64")
    _plain_on_cuda()  # (a wrong value is refused before anything runs)
    return arch, precision


def init_options(
    arch: str, precision: str, debug: bool = False, profile: bool = False, cpu_threads: int | None = None
) -> dict:
    """The keyword arguments of ``ti.init`` for a backend (one of :data:`ARCHES`) and precision;
    ``profile`` turns on Taichi's kernel profiler, which times every kernel launch (and waits
    for each to finish: see :mod:`ti_golf.bench.kernel_times`); ``cpu_threads`` caps the threads
    of the CPU backend's pool (``None``: one per core), so that several processes on one machine
    (the workers of a study) do not oversubscribe its cores.

    On CUDA (and ``gpu``, which picks CUDA where it can) matrices are scalarised
    (``force_scalarize_matrix``): without it, Taichi 1.7.4's CUDA code for the flight's lane
    matrices stops the first kernel that integrates a flight with
    ``CUDA_ERROR_MISALIGNED_ADDRESS``; scalarised, the same kernels give the CPU's results (see
    docs/solvers.md, "Few balls and backends")."""
    options = dict(
        arch=getattr(ti, arch),
        default_fp=ti.f64 if precision == "f64" else ti.f32,
        default_ip=ti.i32,
        debug=debug,
        offline_cache=True,
        fast_math=False,
        force_scalarize_matrix=arch in ("cuda", "gpu"),
        kernel_profiler=profile,
    )
    if cpu_threads is not None:
        options["cpu_max_num_threads"] = max(1, int(cpu_threads))
    return options


def init(
    arch: str | None = None,
    precision: str | None = None,
    *,
    debug: bool = False,
    profile: bool = False,
    cpu_threads: int | None = None,
) -> RuntimeInfo:
    """Initialise Taichi once per process.

    Args:
        arch: the backend, one of :data:`ARCHES` (``cpu``, ``cuda``, ``vulkan``, ``gpu``: the first GPU
            backend Taichi finds); default ``$TI_GOLF_ARCH`` or ``cpu``. One Taichi does not find runs
            on the CPU, with a one-line note.
        precision: ``f64`` or ``f32`` (:data:`PRECISIONS`); default ``$TI_GOLF_PRECISION`` or ``f64``.
        debug: Taichi's debug mode (bounds-checked arrays; slow).
        profile: Taichi's kernel profiler (every launch timed, and waited for).
        cpu_threads: the CPU backend's threads, default one per core; a second call does not
            change them.

    Returns:
        The :class:`RuntimeInfo`: the backend asked for and the one running, and the precision.

    A second call with the same (or no) request returns the existing runtime; a second call that
    asks for a different backend or precision raises RuntimeError, because Taichi cannot switch
    in-process (run another process instead). A value outside the allowed ones is a
    :class:`~ti_golf.errors.ConfigError` naming ``--arch`` or the environment variable.
    """
    global _info
    want_arch, want_prec = resolve(arch, precision)
    if _info is not None:
        if (
            (arch and want_arch != _info.requested_arch)
            or (precision and want_prec != _info.precision)
            or (debug and not ti.lang.impl.current_cfg().debug)
            or (profile and not ti.lang.impl.current_cfg().kernel_profiler)
        ):
            raise RuntimeError(
                f"ti_golf is already initialised with arch={_info.requested_arch}, precision={_info.precision}"
                f"{'' if ti.lang.impl.current_cfg().debug else ', debug off'}"
                f"{'' if ti.lang.impl.current_cfg().kernel_profiler else ', kernel profiler off'}; "
                "start a new process to change them "
                "(importing ti_golf.solvers.solver or ti_golf.physics initialises with the defaults: call init first)"
            )
        return _info
    front_end.install()  # the same kernels, with less of Taichi's front end repeated per call site
    start_arch = want_arch
    if want_arch != "cpu" and not backend_found(want_arch):
        start_arch = "cpu"
        wanted = "GPU" if want_arch == "gpu" else want_arch
        print(f"ti-golf: Taichi finds no {wanted} backend on this machine; {ON_THE_CPU}", file=sys.stderr)
    banner = io.StringIO()
    with contextlib.redirect_stdout(banner):  # Taichi prints "Starting on arch=..." on stdout
        ti.init(**init_options(start_arch, want_prec, debug, profile, cpu_threads))
    for line in banner.getvalue().splitlines():  # keep stdout clean for JSON; pass on anything unusual
        if not line.startswith("[Taichi] Starting on arch"):
            print(line, file=sys.stderr)
    free_every_ndarray()
    actual = ti.lang.impl.current_cfg().arch
    _info = RuntimeInfo(
        requested_arch=want_arch, arch=str(actual).split(".")[-1], precision=want_prec, plain_on_cuda=_plain_on_cuda()
    )
    first_run = not kernels_cached()
    kernel_cache.open_cache()  # (the cache's metadata read in this process's turn: see kernel_cache)
    atexit.register(reset_runtime)  # (run before the interpreter's teardown, after later handlers)
    if announce_first_compile and first_run:
        print(
            "ti-golf: first run on this machine: Taichi compiles the kernels as they are first used "
            f"(up to a minute in all) and keeps them in {ti.lang.impl.current_cfg().offline_cache_file_path}",
            file=sys.stderr,
        )
    return _info


def backend_found(arch: str) -> bool:
    """Whether Taichi finds the backend ``arch`` (one of :data:`ARCHES`; ``gpu``: any GPU backend)
    on this machine, asked with Taichi's log quiet: its own probe, in ``ti.init``, prints a raw
    warning for each library it misses and then falls back to the CPU with another."""
    from taichi._logging import set_logging_level
    from taichi.lang.misc import is_arch_supported

    wanted = ti.gpu if arch == "gpu" else [getattr(ti, arch)]
    set_logging_level("error")
    try:
        return any(is_arch_supported(a) for a in wanted)
    finally:
        set_logging_level("info")  # (ti.init sets it again from its own settings)


def free_every_ndarray() -> None:
    """Make Taichi free the memory of vector and matrix ndarrays when Python drops them, as it
    does for scalar ones.

    In Taichi 1.7.4 only ``ScalarNdarray`` has a ``__del__`` that hands its memory back
    (``Program.delete_ndarray``); a dropped ``VectorNdarray`` or ``MatrixNdarray`` keeps its
    memory until the runtime ends (taichi-dev/taichi issue 8763, fixed upstream by moving the
    method to the ``Ndarray`` base class, as this does). Every widening of the collision solver's
    pair tables, every ``Simulation.reset`` and every saved run loaded would otherwise leave the
    old vector arrays in the process. An array that a kernel was compiled with also sits in a
    reference cycle (the compiler's context keeps the arguments), freed when Python's cycle
    collector next runs: :func:`free_dropped_arrays` runs it."""
    from taichi.lang._ndarray import Ndarray, ScalarNdarray

    if "__del__" not in Ndarray.__dict__:
        Ndarray.__del__ = ScalarNdarray.__del__


def watch(*arrays: object) -> list[weakref.ref]:
    """Weak references to ``arrays`` (``None`` left out) that are about to be dropped, for
    :func:`free_dropped_arrays`."""
    return [weakref.ref(a) for a in arrays if a is not None]


def free_dropped_arrays(watched: list[weakref.ref] | None = None) -> None:
    """Free the Taichi arrays that Python dropped since the last call, before larger ones are
    allocated, so that the old and the new are never in memory together: an array that a kernel
    was compiled with sits in a reference cycle (see :func:`free_every_ndarray`) that only the
    cycle collector breaks. A full collection costs tens of milliseconds in a process that has
    built many kernels, so with ``watched`` (:func:`watch`, taken before the arrays were dropped)
    it runs only when one of them outlived its last reference, that is, sits in such a cycle;
    without, it always runs (for cycles of arrays nobody watched)."""
    if watched is None or any(ref() is not None for ref in watched):
        gc.collect()


def exit_process(code: int) -> NoReturn:
    """End the process with exit status ``code`` after Python's own exit work (the ``atexit``
    handlers, such as the one that closes the GGUI window while the runtime still stands; then
    Taichi's runtime reset, which writes the kernels compiled in this process to the offline
    cache; the streams flushed), but without the C++ static destructors that follow it, which
    with Taichi 1.7.4 on the CPU crash now and then after the last line of output (see the docs'
    performance page, "Design measurements")."""
    try:
        atexit._run_exitfuncs()
        reset_runtime()
    finally:
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(code)


def reset_runtime() -> None:
    """End Taichi's runtime, which writes the kernels compiled in this process to the offline
    cache, in this process's turn at the cache (:func:`ti_golf.kernel_cache.taking_turns`), where
    other processes that share it wait; a later :func:`ensure_init` starts a new one. Registered
    by :func:`init` to run at exit (before the interpreter's own teardown)."""
    global _info
    if _info is None:
        return
    with kernel_cache.taking_turns():
        ti.reset()
    _info = None


def available_memory() -> int | None:
    """Bytes of memory available to new allocations (Linux: MemAvailable), or ``None`` if unknown."""
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    try:
        return int(os.sysconf("SC_AVPHYS_PAGES")) * int(os.sysconf("SC_PAGE_SIZE"))
    except (AttributeError, OSError, ValueError):
        return None


def byte_size(nbytes: float) -> str:
    """A byte count for people: MiB below a GiB, else GiB."""
    return f"{nbytes / 2**20:.1f} MiB" if nbytes < 2**30 else f"{nbytes / 2**30:.1f} GiB"


def release_freed_memory() -> None:
    """Give the C heap's freed pages back to the OS (glibc's ``malloc_trim``; nothing elsewhere).

    Setting up a large simulation makes numpy copies of its balls (positions, velocities, radii
    given by id, converted to the float type), freed once Taichi holds them; glibc would keep
    much of that memory in the process for the rest of the run."""
    if not sys.platform.startswith("linux"):
        return
    with contextlib.suppress(OSError, AttributeError):  # not glibc (musl has no malloc_trim)
        ctypes.CDLL(None).malloc_trim(0)


def kernels_cached() -> bool:
    """Whether Taichi's offline kernel cache holds any compiled kernel (after :func:`init`)."""
    return any(Path(ti.lang.impl.current_cfg().offline_cache_file_path).glob("*.tic"))


def ensure_init() -> RuntimeInfo:
    """Initialise with the defaults (environment variables honoured) unless already done."""
    return _info if _info is not None else init()


def on_cpu() -> bool:
    """Whether the kernels run on a CPU backend (initialising with the defaults if need be)."""
    return ensure_init().arch in ("x64", "arm64")


def cpu_threads() -> int:
    """Threads of Taichi's CPU thread pool (``ti.init``'s ``cpu_max_num_threads``: the cores)."""
    ensure_init()
    return int(ti.lang.impl.current_cfg().cpu_max_num_threads)


def info() -> RuntimeInfo | None:
    """The current runtime, or ``None`` before :func:`init`."""
    return _info


def np_float() -> type[np.float64] | type[np.float32]:
    """The numpy float type matching the Taichi default float."""
    return np.float64 if ensure_init().precision == "f64" else np.float32


@contextlib.contextmanager
def plain_compile(vulkan: bool = False) -> Iterator[None]:
    """Kernels first launched inside are compiled without Taichi's advanced IR optimisation.

    For kernels whose bodies are long straight-line code: the lane-unrolled sweep kernel
    (``physics.kernels.fly_to_landing``, every lane of every RK4 stage spelled out), the
    collision step (``solvers.collide.collision_step``: the Jacobi sweeps unrolled, the warm
    start, the contact laws), the grid's listing (``solvers.grid.list_neighbours``), and the
    Gauss–Seidel sweeps in both layouts (their contact laws spelled out once per colour).
    Taichi's own IR passes grow much faster than linearly with such a body, while LLVM still
    optimises the code, so the kernels compile many times faster and run as fast, with the
    same results bit for bit (figures on the docs' performance page, "Design measurements").

    On the CPU, and with ``vulkan`` on Vulkan too: Taichi's SPIR-V code generator cannot compile
    the sweep kernel without the passes at all ("Not supported"), but compiles the collision step,
    the grid's listing and the contact colours' sweeps and colouring without them to the same
    results bit for bit (from an empty cache: a 70,000-ball pile's Jacobi step in 15 s instead
    of 87 s; 20 steps of a 5,000-ball pile with the contact colours in 23 s instead of 44 s).
    On CUDA too, unless ``TI_GOLF_CUDA_PASSES=1`` (:data:`CUDA_PASSES_ENV`): on an H200 the
    100,000-ball pour's kernels compile in 9 s instead of 21–30 s and run as fast, within what
    two machines differ by; there the results are not the same bit for bit as with the passes
    (the pour's figures part in the sixth digit at t = 0.25 s), while two runs with the passes on
    two machines gave the same figures to the last digit.
    """
    info = ensure_init()  # (read once at start: this wraps launches on the step's path)
    llvm = on_cpu() or (info.arch == "cuda" and info.plain_on_cuda)
    if not llvm and not (vulkan and info.arch == "vulkan"):
        yield
        return
    cfg = ti.lang.impl.current_cfg()
    before = cfg.advanced_optimization
    cfg.advanced_optimization = False
    try:
        yield
    finally:
        cfg.advanced_optimization = before
