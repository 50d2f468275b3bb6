"""The Dask client of a study: a local cluster bound to the loopback address, or a scheduler joined.

Dask's distributed scheduler (``pip install 'ti-golf[cluster]'``) places the tasks, honours
per-task resources (a GPU) and runs a task again elsewhere when its worker dies. Locally, one
worker process per core, each with one thread, every process listening on 127.0.0.1 only, and no
dashboard. ``address`` (or :data:`ADDRESS_ENV`) joins a running scheduler instead: its address
(``tcp://10.0.0.5:8786``) or the JSON file ``dask scheduler --scheduler-file`` wrote.
"""

from __future__ import annotations

import contextlib
import json
import logging
import os
import shutil
import subprocess
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from ti_golf.errors import ConfigError
from ti_golf.signals import ctrl_c_held

ADDRESS_ENV = "TI_GOLF_SCHEDULER"
"""The environment variable naming a scheduler to join when ``--address`` is not given."""

INSTALL_HINT = "pip install 'ti-golf[cluster]'"

LOOPBACK = "127.0.0.1"


def require_dask() -> None:
    """A one-line error (exit code 2) saying how to install Dask and pyarrow when they are missing."""
    missing = []
    for module in ("distributed", "pyarrow"):
        try:
            __import__(module)
        except ImportError:
            missing.append({"distributed": "dask[distributed]"}.get(module, module))
    if missing:
        raise ConfigError(
            "ti-golf study",
            None,
            f"needs {' and '.join(missing)}, which are not installed: {INSTALL_HINT} (or pip install "
            f"{' '.join(repr(m) for m in missing)})",
        )


def cores() -> int:
    """The cores this process may run on."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)


def local_gpus() -> int:
    """How many NVIDIA GPUs ``nvidia-smi -L`` lists here (0 without it)."""
    smi = shutil.which("nvidia-smi")
    if smi is None:
        return 0
    try:
        out = subprocess.run([smi, "-L"], capture_output=True, text=True, timeout=20, check=False).stdout
    except (OSError, subprocess.SubprocessError):
        return 0
    return sum(1 for line in out.splitlines() if line.startswith("GPU "))


WORKERS_PER_CORE = 4
"""The most local workers a core: each worker is a process with its own Taichi, one task at a
time, so more than one a core only queues tasks (a bound, so that a mistyped count does not try
to start a hundred thousand processes)."""


def check_workers(workers: Any) -> int:
    """``workers``, the local worker processes asked for: a whole number in [1, WORKERS_PER_CORE ×
    cores], or a ConfigError naming ``workers`` (``run_study``'s argument; ``--workers`` on the command line)."""
    most = WORKERS_PER_CORE * cores()
    if isinstance(workers, bool) or not isinstance(workers, int) or not 1 <= workers <= most:
        raise ConfigError(
            "workers",
            None,
            f"must be a whole number in [1, {most}], {WORKERS_PER_CORE} a core here (got {workers!r})",
        )
    return workers


@contextlib.contextmanager
def study_client(
    address: str | None = None,
    workers: int | None = None,
    gpus: int | None = None,
    need_gpu: bool = False,
    task_threads: int | None = None,
) -> Iterator[Any]:
    """A ``distributed.Client``: joined to ``address`` (or :data:`ADDRESS_ENV`), else of a local
    cluster of ``workers`` processes (default: one per core) and ``gpus`` more with the resource
    ``GPU = 1`` (default: one per GPU here when ``need_gpu``), each task's Taichi given
    ``task_threads`` CPU threads (default: the cores shared among the workers). Closed (the local
    cluster stopped) when the block ends."""
    require_dask()
    from distributed import Client

    address = address or os.environ.get(ADDRESS_ENV) or None
    logging.getLogger("distributed").setLevel(logging.ERROR)
    if address:
        for name, value in (("workers", workers), ("gpus", gpus)):
            if value is not None:
                raise ConfigError(name, None, "starts a local cluster: give it or a scheduler's address, not both")
        given = "address" if os.environ.get(ADDRESS_ENV) != address else ADDRESS_ENV
        if Path(address).suffix == ".json":
            if not Path(address).is_file():
                raise ConfigError(given, None, f"scheduler file {address!r} not found")
            try:
                if not isinstance(json.loads(Path(address).read_text(encoding="utf-8"))["address"], str):
                    raise TypeError("an address is a text")  # (5 failed inside Dask's client: a traceback)
            except (OSError, ValueError, KeyError, TypeError):
                raise ConfigError(
                    given, None, f"scheduler file {address!r} holds no scheduler's address (JSON with an 'address')"
                ) from None
        try:
            if Path(address).suffix == ".json":
                client = Client(scheduler_file=address, timeout="30s")
            else:
                client = Client(address, timeout="30s")
        except (OSError, ValueError, KeyError) as exc:  # (a malformed address or file, or no scheduler there)
            what = "scheduler file" if Path(address).suffix == ".json" else "address"
            raise ConfigError(
                given, None, f"no Dask scheduler reached through the {what} {address!r} ({type(exc).__name__}: {exc})"
            ) from None
        try:
            if need_gpu and not any(
                w.get("resources", {}).get("GPU") for w in client.scheduler_info()["workers"].values()
            ):
                raise ConfigError(
                    "address",
                    None,
                    f"the study's tasks ask for a GPU (task.gpu = true) and no worker of {address} has one: start "
                    "workers with `dask worker ... --resources GPU=1`",
                )
            yield client
        finally:
            client.close()
        return
    n = cores() if workers is None else check_workers(workers)
    if gpus is None:
        gpus = local_gpus() if need_gpu else 0
    if need_gpu and gpus < 1:
        raise ConfigError(
            "task.gpu",
            None,
            "the study's tasks ask for a GPU and this machine has none (nvidia-smi lists none): join a cluster with "
            "GPU workers (--address)",
        )
    cluster = _local_cluster(n, gpus, task_threads)
    try:
        client = Client(cluster)
        try:
            yield client
        finally:
            client.close()
    finally:
        cluster.close()


WORKER_LOGS = logging.CRITICAL
"""The least level of the local workers' own log that reaches the terminal: their errors (a
scheduler that closed under a heartbeat while the study stops, with its traceback) say nothing
the study does not say itself; a task's failure comes back as its row's error."""


def _local_cluster(n: int, gpus: int, task_threads: int | None = None) -> Any:
    """``n`` single-threaded CPU workers (Taichi given ``cores / n`` threads each) and ``gpus``
    GPU workers, every process listening on 127.0.0.1, no dashboard."""
    threads = task_threads or max(1, cores() // max(n, 1))
    options = {
        "host": LOOPBACK,
        "dashboard_address": None,
        "worker_dashboard_address": None,
        "protocol": "tcp://",
        "silence_logs": WORKER_LOGS,
    }
    cluster = None
    try:
        # Ctrl-C blocked while the workers start, which inherit it so: a terminal's Ctrl-C reaches
        # every process of its group, and this one alone stops the study and the cluster (the
        # workers printed their own KeyboardInterrupt); one that comes meanwhile is raised once
        # the cluster is up (it was ignored, and the study ran to its end)
        with ctrl_c_held(block=True):
            cluster = _start_local_cluster(n, gpus, threads, options)
    except KeyboardInterrupt:  # (one held while it started: the cluster is closed, not left running)
        if cluster is not None:
            cluster.close()
        raise
    return cluster


def _start_local_cluster(n: int, gpus: int, threads: int, options: dict[str, Any]) -> Any:
    from distributed import LocalCluster, Nanny

    from ti_golf.study.worker import THREADS_ENV

    cluster = LocalCluster(
        n_workers=n,
        threads_per_worker=1,
        processes=True,
        env={THREADS_ENV: str(threads)},
        # the scheduler's HTTP server (health and metrics; no dashboard) on a free loopback port, so
        # that a second study on the machine neither collides with the first nor warns
        scheduler_kwargs={"dashboard": False, "dashboard_address": f"{LOOPBACK}:0"},
        **options,
    )
    for i in range(gpus):
        cluster.worker_spec[f"gpu-{i}"] = {
            "cls": Nanny,
            "options": {
                "host": LOOPBACK,
                "nthreads": 1,
                "resources": {"GPU": 1},
                "dashboard_address": None,
                "silence_logs": WORKER_LOGS,
                "env": {THREADS_ENV: str(threads), "CUDA_VISIBLE_DEVICES": str(i)},
            },
        }
    if gpus:
        cluster.sync(cluster._correct_state)
        cluster.wait_for_workers(n + gpus)
    return cluster
