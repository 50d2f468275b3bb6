"""``ti-golf bench study``: what Dask costs and gains a study on this machine.

Eight equal tasks (runs of ``lab_turbulent``'s one ball for ``steps`` time steps, each its own
task id) are run three ways, each task's Taichi on one CPU thread, each process warmed up first by
one such task (Taichi started, the kernels loaded): one after another in one Python process without
Dask (the baseline: the sum of the tasks' times), on a local cluster of one worker, and on one of
two workers (from the first task's submission to the last row; a cluster's start-up, measured
apart, is not in it). Reported: the speed-up of two workers over one, and the overhead per task of
Dask over the baseline, in seconds and as a share of a task's time.
"""

from __future__ import annotations

import json
import subprocess
import sys
import time
from collections.abc import Callable
from typing import Any

from ti_golf.study.cluster import cores, study_client
from ti_golf.study.worker import THREADS_ENV

BENCH_SCENE = "lab_turbulent"


def bench_tasks(n: int, steps: int) -> list[dict[str, Any]]:
    """``n`` equal tasks: the scene run for ``steps`` steps (ids differ so Dask runs each)."""
    task = {
        "kind": "run",
        "t": None,
        "steps": steps,
        "until": "",
        "save": False,
        "balls": None,
        "gpu": False,
        "precision": "f64",
    }
    return [
        {
            "id": f"bench-{i}",
            "point": {},
            "seed": None,
            "scene": BENCH_SCENE,
            "changes": [],
            "task": dict(task),
            "figures": ["carry", "wall_time"],
        }
        for i in range(n)
    ]


def _on_cluster(tasks: list[dict[str, Any]], workers: int) -> tuple[float, float, list[dict[str, Any]]]:
    """(start-up s, wall s of the tasks, rows) on a fresh local cluster of ``workers``."""
    from distributed import wait

    from ti_golf.study.worker import run_task

    t0 = time.perf_counter()
    with study_client(workers=workers, task_threads=1) as client:
        client.wait_for_workers(workers)
        started = time.perf_counter() - t0
        warm = [
            client.submit(run_task, {**tasks[0], "id": f"warm-{i}"}, None, workers=[w], pure=False)
            for i, w in enumerate(client.scheduler_info()["workers"])
        ]
        wait(warm)
        t1 = time.perf_counter()
        futures = [client.submit(run_task, t, None, key=f"ti-golf-{t['id']}-{workers}", pure=False) for t in tasks]
        wait(futures)
        wall = time.perf_counter() - t1
        rows = client.gather(futures)
    return started, wall, rows


def _without_dask(tasks: list[dict[str, Any]]) -> tuple[float, list[dict[str, Any]]]:
    """(s, rows) of the tasks one after another in one process (after a warm-up task): the sum of
    their times."""
    import os

    done = subprocess.run(
        [sys.executable, "-m", "ti_golf.study.worker"],
        input=json.dumps({"tasks": [{**tasks[0], "id": "warm"}, *tasks], "run_dir": None}),
        capture_output=True,
        text=True,
        env=dict(os.environ, **{THREADS_ENV: "1"}),
        check=True,
    )
    rows = [json.loads(line) for line in done.stdout.splitlines() if line.startswith("{")][1:]
    return sum(r["wall_s"] for r in rows), rows


def bench_study(n: int = 8, steps: int = 120_000, log: Callable[[str], None] = print) -> dict[str, Any]:
    """Run the benchmark (see the module's docstring); returns the figures as a dict."""
    tasks = bench_tasks(n, steps)
    log(f"study: {n} tasks of {steps} steps of {BENCH_SCENE}, without Dask, then on 1 and 2 workers ...")
    base_s, base_rows = _without_dask(tasks)
    start1, one_s, rows1 = _on_cluster(tasks, 1)
    start2, two_s, rows2 = _on_cluster(tasks, 2)
    failed = [r for r in base_rows + rows1 + rows2 if r["status"] != "ok"]
    if failed:
        raise RuntimeError(f"a benchmark task failed: {failed[0]['error']}")
    same = all(a["carry_m"] == b["carry_m"] or a["carry_m"] != a["carry_m"] for a, b in zip(base_rows, rows1 + rows2))
    task_s = base_s / n
    overhead = (one_s - base_s) / n
    result: dict[str, Any] = {
        "benchmark": "study",
        "tasks": n,
        "steps": steps,
        "scene": BENCH_SCENE,
        "cores": cores(),
        "task_s": task_s,
        "one_worker_s": one_s,
        "two_workers_s": two_s,
        "speedup": one_s / two_s,
        "cluster_start_s": {"one_worker": start1, "two_workers": start2},
        "overhead_per_task_s": overhead,
        "overhead_fraction": overhead / task_s,
        "task_s_on_workers": {
            "one_worker": sum(r["wall_s"] for r in rows1) / n,
            "two_workers": sum(r["wall_s"] for r in rows2) / n,
        },
        "rows_equal": same,
        "baselines": {"without_dask_s": base_s},
    }
    log(
        f"without Dask {base_s:.1f} s ({task_s:.2f} s a task); 1 worker {one_s:.1f} s, 2 workers {two_s:.1f} s: "
        f"speed-up {result['speedup']:.2f}x; Dask's overhead {overhead:+.3f} s a task "
        f"({100 * result['overhead_fraction']:+.1f} %); clusters started in {start1:.1f} s and {start2:.1f} s"
    )
    return result
