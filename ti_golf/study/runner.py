"""Running a study: its tasks submitted to Dask, each row kept as it comes back, the table written.

>>> from ti_golf.study import run_study                                    # doctest: +SKIP
>>> result = run_study("bag_weather", out="bag", workers=2)                # doctest: +SKIP
>>> result.failed, result.table["carry_m[PGA Driver]"][:3]                 # doctest: +SKIP
"""

from __future__ import annotations

import contextlib
import os
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ti_golf.errors import ConfigError
from ti_golf.files import write_problem
from ti_golf.study.cluster import check_workers, study_client
from ti_golf.study.results import RUNS, Manifest, table_rows, write_table
from ti_golf.study.spec import StudySpec, TaskSpec, load_study

TABLE_EVERY_S = 30.0
"""While a study runs, its table is rewritten at most this often (the manifest at every row)."""
FINISHED_ROW_S = 5.0
"""After a Ctrl-C, the longest the row of a task that had finished is waited for [s]."""


@dataclass
class StudyResult:
    """What a study ran: its folder, the rows of the table (columns -> values), how many tasks
    ran now, were skipped as finished before, and failed; ``interrupted`` when stopped early."""

    spec: StudySpec
    folder: Path
    columns: list[str] = field(default_factory=list)
    rows: list[dict[str, Any]] = field(default_factory=list)
    ran: int = 0
    skipped: int = 0
    failed: int = 0
    interrupted: bool = False

    @property
    def table(self) -> dict[str, list[Any]]:
        """The table by column."""
        return {c: [row.get(c) for row in self.rows] for c in self.columns}


def default_folder(spec: StudySpec) -> Path:
    """Where a study's results go unless ``--out`` says: ``NAME_study`` in the current folder."""
    return Path(f"{spec.name}_study")


def run_study(
    study: str | os.PathLike[str] | StudySpec,
    out: str | os.PathLike[str] | None = None,
    workers: int | None = None,
    address: str | None = None,
    overrides: Sequence[str] = (),
    gpus: int | None = None,
    log: Callable[[str], None] = print,
) -> StudyResult:
    """Run the tasks of ``study`` (a study file, a bundled study's name, or a loaded spec) not
    finished in its folder ``out``, on a local Dask cluster of ``workers`` processes or on the
    scheduler at ``address``; returns the table. Ctrl-C (``KeyboardInterrupt``) stops it after
    writing the finished rows, and is raised again. Local workers are new processes that import
    the calling script again: a script calls this under ``if __name__ == "__main__":``."""
    if workers is not None:
        check_workers(workers)  # (before the study's folder is made)
    spec = study if isinstance(study, StudySpec) else load_study(study, overrides)
    if out is not None and not str(out).strip():  # (Path("") is the current folder)
        raise ConfigError("out", None, "needs a folder name (got an empty path)")
    folder = Path(out) if out is not None else default_folder(spec)
    if folder.exists() and not folder.is_dir():
        raise ConfigError("out", None, f"{str(folder)!r} is a file, not a folder")
    parent = folder.resolve().parent  # (the study's folder is made, as run --frames makes its own: not its parents)
    if not folder.exists() and not parent.is_dir():
        raise ConfigError("out", None, f"cannot make {str(folder)!r}: folder {str(parent)!r} does not exist")
    problem = write_problem(folder if folder.is_dir() else parent)  # (before the cluster starts)
    if problem is not None:
        raise ConfigError("out", None, f"cannot write into {str(folder)!r}: {problem}")
    manifest = Manifest(folder)
    if (folder / RUNS).exists() and not (folder / RUNS).is_dir():
        raise ConfigError(str(folder / RUNS), None, "is not a folder: a study folder keeps its tasks' saved runs there")
    todo = [t for t in spec.tasks if not manifest.finished(t.id, t.figures)]
    result = StudyResult(spec, folder, skipped=len(spec.tasks) - len(todo))
    if result.skipped:
        log(f"{spec.name}: {result.skipped} of {len(spec.tasks)} tasks finished before (in {folder}), skipped")
    foreign = len(set(manifest.rows) - {t.id for t in spec.tasks})
    if foreign:  # (another study's, or this one's before an edit: kept, and left out of the table)
        log(
            f"note: {folder} also holds {foreign} task row{'s' if foreign != 1 else ''} that {spec.name} does not "
            "have (another study's, or this one's before it was changed); the results table lists this study's only"
        )
    try:
        if todo:
            with study_client(address, workers, gpus, need_gpu=spec.gpu) as client:
                folder.mkdir(exist_ok=True)  # (once the cluster is up: not for a bad address)
                (folder / RUNS).mkdir(exist_ok=True)
                _run(spec, todo, client, folder, manifest, result, log)
    except KeyboardInterrupt:
        result.interrupted = True
        if not folder.is_dir():  # (while the cluster started: nothing was made)
            raise KeyboardInterrupt("before any task ran") from None
        raise KeyboardInterrupt(
            f"after {result.ran} of {len(todo)} tasks; the finished rows are in {folder}: run the study again to "
            "finish it"
        ) from None
    finally:
        result.columns, result.rows = table_rows(spec.tasks, manifest, spec.keys)
        if folder.is_dir():
            write_table(folder, result.columns, result.rows)
        result.failed = sum(1 for row in result.rows if row["status"] != "ok")
    return result


def _run(
    spec: StudySpec,
    todo: list[TaskSpec],
    client: Any,
    folder: Path,
    manifest: Manifest,
    result: StudyResult,
    log: Callable[[str], None],
) -> None:
    from distributed import as_completed

    from ti_golf.study.worker import run_task

    workers = client.scheduler_info()["workers"]
    log(f"{spec.name}: {len(todo)} tasks on {len(workers)} worker(s) of {client.scheduler.address}")
    run_dir = str((folder / RUNS).resolve())
    resources = {"GPU": 1} if spec.gpu else None
    futures = {
        client.submit(run_task, t.as_dict(), run_dir, key=f"ti-golf-{t.id}", pure=False, resources=resources): t
        for t in todo
    }
    last_table = time.monotonic()
    recorded: set[Any] = set()

    def record(future: Any, row: dict[str, Any]) -> None:
        task = futures[future]
        row["run_path"] = os.path.relpath(row["run_path"], folder) if row.get("run_path") else ""
        manifest.add(row)
        recorded.add(future)
        result.ran += 1
        what = ", ".join(f"{k} = {v}" for k, v in task.point.items()) or "the base scene"
        seed = "" if task.seed is None else f", seed {task.seed}"
        outcome = "ok" if row["status"] == "ok" else f"FAILED: {row['error']}"
        wall = f" in {row['wall_s']:.1f} s" if row.get("wall_s") is not None else ""
        where = f" on {row['host']}" if row.get("host") else ""
        log(f"[{result.ran}/{len(todo)}] {what}{seed}: {outcome}{wall}{where}")

    try:
        for future in as_completed(futures):
            try:
                row = future.result()
            except Exception as exc:  # the task's worker died too often (KilledWorker), or the scheduler left
                task = futures[future]
                row = {"id": task.id, "status": "failed", "error": f"{type(exc).__name__}: {exc}", "wall_s": None}
            record(future, row)
            if time.monotonic() - last_table > TABLE_EVERY_S:
                write_table(folder, *table_rows(spec.tasks, manifest, spec.keys))
                last_table = time.monotonic()
    finally:
        # a Ctrl-C while waiting: the tasks that finished meanwhile are kept too (their rows were
        # waiting to be read), each read in at most a few seconds; the others are cancelled
        for future in futures:
            if future not in recorded and future.status == "finished":
                with contextlib.suppress(Exception):  # (what cannot be read now runs again next time)
                    record(future, future.result(timeout=FINISHED_ROW_S))
        unfinished = [f for f in futures if not f.done()]
        if unfinished:
            client.cancel(unfinished)
