"""What a Dask worker runs for a task: the process's one Taichi runtime, then the task, as a row.

A worker process initialises Taichi once, with the backend and precision of its first task and
its CPU threads capped at the cores the worker has (``TI_GOLF_TASK_THREADS``, set by the local
cluster, else the worker's thread count). The tasks of one worker run one at a time. A task that
needs another backend or precision than the process already has runs in a fresh Python process
(``python -m ti_golf.study.worker``, the task as JSON on its standard input). An error in a task
is kept in its row (``status = "failed"``, ``error``); the study goes on.
"""

from __future__ import annotations

import json
import os
import socket
import subprocess
import sys
import threading
import time
import traceback
from typing import Any

from ti_golf.errors import TiGolfError, env_count, one_line

THREADS_ENV = "TI_GOLF_TASK_THREADS"
"""The CPU threads of each task's Taichi runtime (the local cluster sets it: its cores / workers)."""

_one_at_a_time = threading.Lock()


def task_arch(task: dict[str, Any]) -> tuple[str, str]:
    """The backend and precision a task runs on: CUDA when it asks for a GPU, else the CPU."""
    return ("cuda" if task["task"]["gpu"] else "cpu"), task["task"]["precision"]


def _threads() -> int:
    given = env_count(THREADS_ENV)
    if given is not None:
        return given
    try:
        from distributed import get_worker

        return max(1, int(get_worker().state.nthreads))
    except (ImportError, ValueError, AttributeError):
        return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)


def _where() -> str:
    try:
        from distributed import get_worker

        return str(get_worker().address)
    except (ImportError, ValueError):
        return f"pid {os.getpid()}"


def run_task(task: dict[str, Any], run_dir: str | None) -> dict[str, Any]:
    """Run a task (:meth:`~ti_golf.study.spec.TaskSpec.as_dict`) in this process, or in a fresh
    one when this one's runtime is of another backend or precision; returns its row: the figures,
    ``status`` (``ok`` or ``failed``), ``error``, ``wall_s``, ``host``, ``worker`` and ``run_path``."""
    with _one_at_a_time:
        t0 = time.perf_counter()
        row: dict[str, Any] = {"id": task["id"], "host": socket.gethostname(), "worker": _where()}
        try:
            from ti_golf import runtime

            arch, precision = task_arch(task)
            info = runtime.info()
            if info is None:
                runtime.init(arch, precision, cpu_threads=_threads())
                info = runtime.info()
            assert info is not None
            if info.requested_arch != arch or info.precision != precision:
                result = _in_fresh_process(task, run_dir)
            else:
                from ti_golf.study.tasks import execute

                result = execute(task, run_dir)
            row.update(result)
            row.setdefault("status", "ok")
            row.setdefault("error", "")
        except TiGolfError as exc:
            row.update(status="failed", error=one_line(str(exc)))
        except Exception as exc:  # any failure of one task is its row's, not the study's
            last = traceback.extract_tb(exc.__traceback__)[-1:]
            at = f" (at {os.path.basename(last[0].filename)}:{last[0].lineno})" if last else ""
            row.update(status="failed", error=one_line(f"{type(exc).__name__}: {exc}{at}"))
        row["wall_s"] = time.perf_counter() - t0
        return row


def _in_fresh_process(task: dict[str, Any], run_dir: str | None) -> dict[str, Any]:
    """The task run by ``python -m ti_golf.study.worker`` (its own Taichi runtime)."""
    env = dict(os.environ, **{THREADS_ENV: str(_threads())})
    done = subprocess.run(
        [sys.executable, "-m", "ti_golf.study.worker"],
        input=json.dumps({"task": task, "run_dir": run_dir}),
        capture_output=True,
        text=True,
        env=env,
        check=False,
    )
    lines = done.stdout.strip().splitlines()
    if done.returncode != 0 or not lines:
        tail = one_line(done.stderr.strip().splitlines()[-1]) if done.stderr.strip() else ""
        return {"status": "failed", "error": f"the task's own process ended with code {done.returncode}: {tail}"}
    row = json.loads(lines[-1])
    row.pop("wall_s", None)
    row.pop("worker", None)
    return row


def main() -> None:
    """``python -m ti_golf.study.worker``: a task (``{"task": ..., "run_dir": ...}``) or several
    (``"tasks"``, run one after another, as the benchmark's baseline without Dask) from standard
    input; a row per task on standard output, one JSON line each."""
    from ti_golf import runtime

    request = json.loads(sys.stdin.read())
    for task in request.get("tasks", [request.get("task")]):
        print(json.dumps(run_task(task, request["run_dir"])), flush=True)
    runtime.exit_process(0)


if __name__ == "__main__":
    main()
