"""A study's folder: the manifest of finished tasks, and the results table (Parquet and CSV).

The manifest (``manifest.jsonl``) gets one line per finished task as soon as its row comes back,
flushed to the disk, so that a study stopped at any point (Ctrl-C, SIGTERM, a lost machine) keeps
every row it finished; running the study again skips the tasks whose rows say ``ok`` and runs the
others (failed or never run). The table (``results.parquet`` and ``results.csv``) has one row per
finished task of the study in the study's order, and is written whole or not at all
(:func:`ti_golf.files.atomic_path`): the task's id, the varied keys, the seed, the figures, the
status and error, the wall time, the host and worker that ran it, and the path of its saved run
(relative to the folder).
"""

from __future__ import annotations

import csv
import json
import math
import os
import zipfile
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any

from ti_golf.errors import ConfigError
from ti_golf.files import atomic_path
from ti_golf.study.figures import FIGURES

MANIFEST = "manifest.jsonl"
TABLE_PARQUET = "results.parquet"
TABLE_CSV = "results.csv"
RUNS = "runs"

BOOKKEEPING = ("status", "error", "wall_s", "host", "worker", "run_path")
"""The columns after the figures."""


class Manifest:
    """The rows finished so far in a study folder, by task id (the last row of a task wins).

    The file is read as input: a row cut short (the machine went down while writing it) is
    skipped, so its task runs again; a file that is not UTF-8 text, or a line that is not a task's
    row as :meth:`add` writes it, is a :class:`~ti_golf.errors.ConfigError` naming the file and
    the line."""

    def __init__(self, folder: str | os.PathLike[str]) -> None:
        self.path = Path(folder) / MANIFEST
        self.rows: dict[str, dict[str, Any]] = {}
        self._cut = False
        if self.path.exists() and not self.path.is_file():  # (found only once the tasks had run)
            raise ConfigError(
                str(self.path), None, "is not a file: a study folder's manifest is its file of finished rows"
            )
        if not self.path.is_file():
            return
        try:
            text = self.path.read_bytes().decode("utf-8")
        except UnicodeDecodeError as exc:
            raise ConfigError(str(self.path), None, f"is not UTF-8 text (byte {exc.start}); {_REDO}") from None
        self._cut = bool(text) and not text.endswith("\n")  # (the next row starts a line of its own)
        for number, line in enumerate(text.splitlines(), 1):
            line = line.strip()
            if not line:
                continue
            try:
                row = json.loads(line)
            except json.JSONDecodeError as exc:
                if line.startswith('{"id": '):  # a row cut short when the machine went down: that task runs again
                    continue
                raise ConfigError(
                    f"{self.path}:{number}", None, f"is not a task's row (not JSON: {exc.msg}); {_REDO}"
                ) from None
            problem = _row_problem(row)
            if problem:
                raise ConfigError(f"{self.path}:{number}", None, f"{problem}; {_REDO}")
            self.rows[row["id"]] = row

    def finished(self, task_id: str, figures: Sequence[str] = ()) -> bool:
        """Whether the task has a row that says ``ok``, holds each of its ``figures`` (names of
        :data:`~ti_golf.study.figures.FIGURES`; a row without one runs again), and whose saved run,
        if it made one, is still in the folder whole (a zip archive whose directory can be read;
        else the task runs again)."""
        row = self.rows.get(task_id, {})
        if row.get("status") != "ok":
            return False
        if not all(any(_of_figure(name, FIGURES[f].column) for name in row) for f in figures):
            return False
        return not row.get("run_path") or zipfile.is_zipfile(self.path.parent / row["run_path"])

    def add(self, row: Mapping[str, Any]) -> None:
        """Keep a finished task's row: in memory and, at once, at the end of the manifest file."""
        self.rows[row["id"]] = dict(row)
        with open(self.path, "a", encoding="utf-8") as fh:
            fh.write(("\n" if self._cut else "") + json.dumps(row, default=_plain) + "\n")
            self._cut = False
            fh.flush()
            os.fsync(fh.fileno())


_REDO = "remove the line (or the file) to run its tasks again"


def _row_problem(row: Any) -> str | None:
    """Why ``row`` (a manifest line's JSON) is not a finished task's row, or ``None``: an object
    with a string ``id``, a ``status`` of ``ok`` or ``failed``, the bookkeeping as text or numbers
    (``wall_s``), and every other entry, a figure, a number or null."""
    if not isinstance(row, dict) or not isinstance(row.get("id"), str):
        return "is not a task's row (an object with a string 'id')"
    if row.get("status") not in ("ok", "failed"):
        return f"task {row['id']}: 'status' must be 'ok' or 'failed' (got {row.get('status')!r})"
    for name, value in row.items():
        if name not in ("id", *BOOKKEEPING) and not any(_of_figure(name, f.column) for f in FIGURES.values()):
            return f"task {row['id']}: {name!r} is neither a figure nor the task's bookkeeping"
        if name == "wall_s" or name not in ("id", *BOOKKEEPING):
            if value is not None and (isinstance(value, bool) or not isinstance(value, (int, float))):
                return f"task {row['id']}: {name!r} must be a number (got {value!r})"
        elif name != "id" and value is not None and not isinstance(value, str):
            return f"task {row['id']}: {name!r} must be text (got {value!r})"
    return None


def _of_figure(name: str, column: str) -> bool:
    """Whether a row's entry ``name`` is a figure's ``column``, or one of its columns per club
    (``carry_m[PGA Driver]``)."""
    return name == column or name.startswith(column + "[") and name.endswith("]")


def _plain(value: Any) -> Any:
    return value.tolist() if hasattr(value, "tolist") else str(value)


def table_rows(tasks: Iterable[Any], manifest: Manifest, keys: Sequence[str]) -> tuple[list[str], list[dict[str, Any]]]:
    """The columns and the rows of the results table: the finished ``tasks`` (TaskSpec) in order."""
    rows = []
    figure_columns: list[str] = []
    for t in tasks:
        done = manifest.rows.get(t.id)
        if done is None:
            continue
        row: dict[str, Any] = {"task_id": t.id}
        for k in keys:
            value = t.point.get(k)
            row[k] = json.dumps(value) if isinstance(value, (list, tuple)) else value
        row["seed"] = t.seed
        for name, value in done.items():
            if name in ("id", *BOOKKEEPING):
                continue
            if name not in figure_columns:
                figure_columns.append(name)
            row[name] = value
        for name in BOOKKEEPING:  # (a row without them: empty text, and no time: a number column)
            row[name] = done.get(name, None if name == "wall_s" else "")
        rows.append(row)
    columns = ["task_id", *keys, "seed", *figure_columns, *BOOKKEEPING]
    return columns, rows


def write_table(folder: str | os.PathLike[str], columns: Sequence[str], rows: Sequence[Mapping[str, Any]]) -> None:
    """Write the table as ``results.parquet`` (pyarrow) and ``results.csv``, each whole or not at all.

    The figures are 64-bit floats in both (the CSV's written with every digit, so that it reads
    back to the same bits); a figure a row lacks is null in Parquet and empty in the CSV."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    folder = Path(folder)
    arrays = {}
    for name in columns:
        values = [row.get(name) for row in rows]
        present = [v for v in values if v is not None]
        numbers = bool(present) and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in present)
        if numbers and name != "seed" and any(isinstance(v, float) for v in present):
            values = [None if v is None else float(v) for v in values]
        arrays[name] = pa.array(values)
    table = pa.table(arrays) if columns else pa.table({})
    with atomic_path(folder / TABLE_PARQUET) as tmp:
        pq.write_table(table, tmp)
    with atomic_path(folder / TABLE_CSV) as tmp, open(tmp, "w", newline="", encoding="utf-8") as fh:
        writer = csv.writer(fh, lineterminator="\n")
        writer.writerow(columns)
        for row in rows:
            writer.writerow([_cell(row.get(name)) for name in columns])


def _cell(value: Any) -> str:
    if value is None:
        return ""
    if isinstance(value, float):
        return repr(value) if math.isfinite(value) else str(value)
    return str(value)


def read_table(folder: str | os.PathLike[str]) -> dict[str, list[Any]]:
    """The results table of a study folder as columns (from the Parquet file)."""
    import pyarrow.parquet as pq

    return pq.read_table(Path(folder) / TABLE_PARQUET).to_pydict()
