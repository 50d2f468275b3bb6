"""Bounce and roll balls to rest from their landing states, all at once, without ball–ball contact."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace

import numpy as np

from ti_golf.errors import ConfigError
from ti_golf.scene.schema import AT_REST, Scene
from ti_golf.sim.simulation import Simulation


def has_ground(scene: Scene) -> bool:
    """Whether a ball can come to rest in the scene: a ground plane, a terrain or planes."""
    return bool(scene.world.ground or scene.terrain is not None or scene.planes)


def roll_out(
    scene: Scene,
    x: np.ndarray,
    v: np.ndarray,
    w: np.ndarray,
    progress: Callable[[float, float], None] | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Run balls from (x, v, ω) (each (N, 3), SI) on the scene's ground until every ball is at rest,
    out of bounds, or ``world.t_max`` has passed.

    The balls are independent shots, not a pile: ball–ball collisions are off
    (``world.collisions = false``: the ``advance`` kernel, one thread per ball), so shots that
    land on the same spot do not meet. Contacts, turf and rest detection are the scene's.

    Returns:
        (x, at_rest): final centres [m], shape (N, 3), and whether each ball came to rest, (N,).
    """
    if not has_ground(scene):
        raise ConfigError(
            scene.path or scene.name, "world.ground", "rolling shots out to rest needs a ground, a terrain or planes"
        )
    if len(x) == 0:
        return np.zeros((0, 3)), np.zeros(0, bool)
    apart = replace(scene, world=replace(scene.world, collisions=False))
    sim = Simulation(apart, x=x, v=v, w=w, track=False)
    sim.run(t=scene.world.t_max, until="rest", progress=progress)
    return sim.x, sim.status == AT_REST
