"""The scene keys a study's tasks read: a key that the study sets or varies for every task, and
that its ``task.kind`` does not read, is refused when the study is loaded (a key without effect
is an error; :mod:`ti_golf.scene.readers` says which keys each application leaves unread).
Plain Python, no Taichi."""

from __future__ import annotations

from collections.abc import Iterable, Sequence

from ti_golf.errors import OVERRIDES
from ti_golf.scene.balls import flies_alone_problem, tracks_landing
from ti_golf.scene.checks import raise_config
from ti_golf.scene.readers import APPLICATIONS, TIMED_RUN_NOT_READ, Unread, unread_reason
from ti_golf.scene.schema import Scene

VARIED_IN = {"grid": "grid", "points": "points", "random": "random.uniform"}
"""Each way of choosing the points, with the table an error names a varied key in (a point of
``[[points]]`` by its index)."""


def not_read_by(kind: str, timed: bool) -> Unread:
    """The keys that a task of ``kind`` does not read (a run ``timed``, given task.t or
    task.steps: its own length replaces the scene's world.t_end)."""
    return TIMED_RUN_NOT_READ if kind == "run" and timed else APPLICATIONS[kind]


def refuse_unread(
    kind: str,
    timed: bool,
    points: Sequence[Iterable[str]],
    how: str | None,
    file_keys: Iterable[str],
    cli_keys: Iterable[str],
    source: str,
) -> None:
    """A ConfigError for the first key that a task of ``kind`` (``timed``: given its own length)
    does not read (:func:`not_read_by`): of the command line's ``--set`` (``cli_keys``), of the
    study file's ``set`` (``file_keys``), or varied by one of the ``points`` (their keys, chosen
    ``how``: grid, points or random; None: no point varies a key). It names ``--set``, or the
    file and its key."""
    unread = not_read_by(kind, timed)
    why = f"is not read by a task of task.kind = {kind!r}"
    for where, keys in ((OVERRIDES, cli_keys), (source, file_keys)):
        for key in keys:
            reason = unread_reason(unread, key)
            if reason is not None:
                raise_config(where, key if where == OVERRIDES else f"set: {key}", f"{why} ({reason})")
    table = VARIED_IN.get(how or "")
    for i, point in enumerate(points if table is not None else ()):
        for key in point:
            reason = unread_reason(unread, key)
            if reason is not None:
                where = f"points[{i}].{key}" if how == "points" else f"{table}.{key}"
                raise_config(source, where, f"{why}: varying it changes nothing ({reason})")


def scene_problem(kind: str, until: str, scene: Scene) -> tuple[str, str] | None:
    """(key, reason) for what a task of ``kind`` (a run stopped ``until``) needs of its ``scene``
    and does not find, or None: a sweep, a shot and a dispersion fly the scene's ``[launch]``; the
    flights fly each launch alone, so ``[[balls]]`` and ``[[blocks]]`` would have no effect; a run
    until landed needs a ball tracked for its landing."""
    if kind in ("sweep", "shot", "dispersion") and scene.launch is None:
        return "scene", f"task.kind = {kind!r} flies the scene's [launch]: {scene.name!r} has none"
    alone = None if kind in ("run", "pit") else flies_alone_problem(scene)
    if alone is not None:
        return "scene", f"task.kind = {kind!r}: {scene.name}'s {alone[0]} {alone[1]}"
    if kind == "run" and until == "landed" and not tracks_landing(scene):
        return "task.until", (
            f"'landed' has no effect on {scene.name!r}: no ball of it is tracked for its landing (a [launch] "
            "ball shot above the ground is); give task.until = 'rest'"
        )
    return None
