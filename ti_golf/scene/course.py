"""The scene's course tables of the golf game: ``[hole]``, the cup and its flagstick, and
``[game]``, the rules of ``ti-golf play`` (see :mod:`ti_golf.game.rules`). Plain Python, no Taichi
(see :mod:`ti_golf.scene.schema`, which collects them with the other tables)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

from ti_golf.scene.checks import DURATION, NON_NEGATIVE, POSITIVE, REACH, SPEED_LIMIT, Each, Interval, raise_config
from ti_golf.scene.keys import REQUIRED, key

if TYPE_CHECKING:  # (the schema collects these tables: it imports this module)
    from ti_golf.scene.schema import Scene


@dataclass(frozen=True)
class HoleConfig:
    """The ``[hole]`` table: a cup at ``position`` (x, z, in metres) on the course, and its flagstick."""

    position: tuple[float, float] = key(
        "vec2",
        REQUIRED,
        "m",
        "the cup's centre [x, z] (required); it sits on the terrain, else on the ground or the first "
        "upward-facing plane",
        Each(Interval(-REACH, REACH), 2),
    )
    radius: float = key("float", 0.054, "m", "cup radius (regulation: 108 mm across)", POSITIVE)
    flag_height: float = key(
        "float", 2.13, "m", "flagstick height above the cup (2.13 m = 7 ft is usual; 0: none)", NON_NEGATIVE
    )


@dataclass(frozen=True)
class GameConfig:
    """The ``[game]`` table of ``ti-golf play`` (see :mod:`ti_golf.game.rules`)."""

    start: tuple[float, float] | None = key(
        "vec2",
        None,
        "m",
        "where the ball lies for the first stroke of `ti-golf play`, [x, z] on the terrain (default: a "
        "random point of the course, from --seed)",
        read_when=("[hole]", (True,)),
    )
    wind_max: float = key(
        "float",
        0.0,
        "m/s",
        "each stroke's wind blows level from a random direction at a random speed up to this (0: the "
        "scene's air.wind throughout)",
        Interval(0.0, SPEED_LIMIT),
        read_when=("[hole]", (True,)),
    )
    max_strokes: int = key(
        "int",
        20,
        "-",
        "the round ends unfinished after this many strokes",
        Interval(1, 1000),
        read_when=("[hole]", (True,)),
    )
    shot_time: float = key(
        "float",
        60.0,
        "s",
        "longest a stroke is simulated; a ball still moving then is played from where it is",
        DURATION,
        read_when=("[hole]", (True,)),
    )


def check_hole(scene: "Scene") -> None:
    """Refuse a ``[hole]`` with nothing to sit on: off the terrain's grid, or, without a terrain,
    in a scene with neither a ground plane nor an upward-facing plane (|n_y| > 0.7 of |n|, as the
    picture and the game take the ground); the cup and its flag floated in the air."""
    if scene.hole is None:
        return
    x, z = scene.hole.position
    if scene.terrain is not None:
        (x0, _, z0), (sx, sz) = scene.terrain.origin, scene.terrain.size
        if not (x0 <= x <= x0 + sx and z0 <= z <= z0 + sz):
            raise_config(
                *scene.where("hole.position"),
                f"must lie on the terrain (x in [{x0:g}, {x0 + sx:g}] m, z in [{z0:g}, {z0 + sz:g}] m; got [{x:g}, {z:g}])",
            )
    elif not scene.world.ground and not any(p.normal[1] > 0.7 * math.hypot(*p.normal) for p in scene.planes):
        raise_config(
            *scene.where("hole.position"),
            "has nothing to sit on: the cup needs a [terrain], the ground (world.ground) or an upward-facing plane",
        )
