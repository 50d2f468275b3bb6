"""A study task's identity: the hash that a study run again, or grown, finds its finished tasks by."""

from __future__ import annotations

import functools
import hashlib
import json
import os
from collections.abc import Mapping, Sequence
from typing import Any


def task_id(scene_doc: Mapping[str, Any], seed: int | None, task: Mapping[str, Any], figures: Sequence[str]) -> str:
    """A task's identity: a hash of its scene (every key read, and the data of the heights file it
    names: the same path with other heights is another scene), seed, task settings and figures, so
    that a study run again, or grown by more points, finds the tasks it has already finished."""
    heights = scene_doc.get("terrain", {}).get("file")
    data = _file_digest(*_file_stamp(heights)) if heights else None
    text = json.dumps(
        {"scene": scene_doc, "heights": data, "seed": seed, "task": task, "figures": list(figures)},
        sort_keys=True,
        default=str,
    )
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def _file_stamp(path: str) -> tuple[str, int, int]:
    """``path`` with its size and modification time [ns]: what :func:`_file_digest` is cached by."""
    stat = os.stat(path)
    return path, stat.st_size, stat.st_mtime_ns


@functools.lru_cache(maxsize=8)
def _file_digest(path: str, size: int, mtime_ns: int) -> str:
    """The SHA-256 of a file's bytes, read once for all the tasks of a study that name it."""
    digest = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()
