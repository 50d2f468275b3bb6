"""Keys whose effect depends on other tables than their own: when a scene leaves them unread.

A key's ``read_when`` (:class:`~ti_golf.scene.keys.Key`) names one setting under which it is read.
The keys here are read under any of several, spread over tables: ``world.ground_height`` places
the ground plane, measures the log wind profile's heights and rests a launched ball on the ground;
``contact.turf`` shapes impacts on a ground. The loader refuses such a key, set in a scene that
leaves it unread, as it refuses a ``read_when`` key; the lab shows it unread; a scene written back
as a document leaves it out. Plain Python, no Taichi.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import Any

from ti_golf.scene.schema import Scene


def _ground_height_read(scene: Scene) -> bool:
    """``world.ground_height`` is read by the ground plane, a log wind profile, and a ``[launch]``
    ball that rests on the ground (no ``launch.position``, no terrain under it)."""
    launched_on_ground = scene.launch is not None and scene.launch.position is None and scene.terrain is None
    return scene.world.ground or scene.air.wind_profile == "log" or launched_on_ground


def _has_ground(scene: Scene) -> bool:
    """Whether the scene has something to land on: the ground plane, ``[[planes]]`` or a terrain."""
    return scene.world.ground or bool(scene.planes) or scene.terrain is not None


READ_ACROSS: dict[str, tuple[Callable[[Scene], bool], str]] = {
    "world.ground_height": (
        _ground_height_read,
        "the scene has the ground plane (world.ground = true), a log wind profile (air.wind_profile = "
        '"log") or a [launch] ball resting on the ground (no launch.position, no [terrain])',
    ),
    "contact.turf": (
        _has_ground,
        "the scene has a ground: world.ground = true, [[planes]] or a [terrain]",
    ),
}
"""Each such key (dotted): whether a scene reads it, and when that is, in words. Whether a key is
read never depends on its own value or another key of this table, so a scene with these keys left
out tells whether each would be read."""


def read_across(dotted: str, scene: Scene) -> bool:
    """Whether ``scene`` reads the key ``dotted`` (``"world.ground_height"``) as far as the other
    tables decide; ``True`` for a key not in :data:`READ_ACROSS`."""
    rule = READ_ACROSS.get(dotted)
    return rule is None or rule[0](scene)


def with_value(scene: Scene, dotted: str, value: Any) -> Scene:
    """``scene`` with its key ``dotted`` (``"contact.turf"``) set to ``value``, a value already
    checked: a key of :data:`READ_ACROSS` changes no other key's reading, so nothing else is."""
    table, name = dotted.split(".")
    return dataclasses.replace(scene, **{table: dataclasses.replace(getattr(scene, table), **{name: value})})


def unread_text(dotted: str) -> str:
    """The error's reason for a key of :data:`READ_ACROSS` that a scene leaves unread."""
    return f"is only read when {READ_ACROSS[dotted][1]}"
