"""Bounce and roll balls to rest from their landing states, all at once, without ball–ball contact."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ti_golf.errors import ConfigError
from ti_golf.scene.launch_monitor import target_direction
from ti_golf.scene.schema import AT_REST, Scene
from ti_golf.signals import KeptInterrupt
from ti_golf.sim.results import Flight, Shots
from ti_golf.sim.simulation import RunProgress, Simulation


def has_ground(scene: Scene) -> bool:
    """Whether a ball can come to rest in the scene: a ground plane, a terrain or planes."""
    return bool(scene.world.ground or scene.terrain is not None or scene.planes)


def roll_out(
    scene: Scene,
    x: np.ndarray,
    v: np.ndarray,
    w: np.ndarray,
    progress: RunProgress | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Run balls from (x, v, ω) (each (N, 3), SI) on the scene's ground until every ball is at rest,
    out of bounds, or ``world.t_max`` has passed.

    The balls are independent shots, not a pile: ball–ball collisions are off
    (``world.collisions = false``: the ``advance`` kernel, one thread per ball), so shots that
    land on the same spot do not meet. Contacts, turf and rest detection are the scene's.

    Returns:
        (x, at_rest): final centres [m], shape (N, 3), and whether each ball came to rest, (N,).
        An interrupt stops the run between launches and raises :class:`KeptInterrupt` holding
        them as they were then.
    """
    if not has_ground(scene):
        raise ConfigError(*scene.where("world.ground"), "rolling shots out to rest needs a ground, a terrain or planes")
    if len(x) == 0:
        return np.zeros((0, 3)), np.zeros(0, bool)
    apart = replace(scene, world=replace(scene.world, collisions=False))
    sim = Simulation(apart, x=x, v=v, w=w, track=False)
    try:
        sim.run(t=scene.world.t_max, until="rest", progress=progress)
    except KeyboardInterrupt:
        raise KeptInterrupt((sim.x, sim.status == AT_REST)) from None
    return sim.x, sim.status == AT_REST


def shots_from_landing(
    scene: Scene,
    x0: np.ndarray,
    raw: dict[str, np.ndarray],
    to_rest: bool,
    progress: RunProgress | None = None,
) -> Shots:
    """The :class:`Shots` of balls launched from ``x0`` (N, 3) whose flight to landing is ``raw``
    (:func:`ti_golf.golf.sweep.fly`'s record), rolled out to rest with ``to_rest``; the target line
    is the scene's launch azimuth. An interrupt during the roll-out raises :class:`KeptInterrupt`
    holding the Shots with the rests reached by then (the balls still rolling not at rest)."""
    flight = Flight.from_arrays(x0, raw["landed"], raw["apex"], raw["t_land"], raw["land_x"], raw["land_v"])
    direction = target_direction(scene)
    if not to_rest:
        return Shots.from_flight(flight, x0, raw["land_w"].astype(np.float64), direction)
    idx = np.flatnonzero(flight.landed)
    rest_x, at_rest = np.full((len(x0), 3), np.nan), np.zeros(len(x0), bool)
    x, v, w = (raw[k][idx].astype(np.float64) for k in ("land_x", "land_v", "land_w"))
    stopped = None
    try:
        rest_x[idx], at_rest[idx] = roll_out(scene, x, v, w, progress=progress)
    except KeptInterrupt as stop:
        (rest_x[idx], at_rest[idx]), stopped = stop.kept, stop
    shots = Shots.from_flight(flight, x0, raw["land_w"].astype(np.float64), direction, rest_x, at_rest)
    if stopped is not None:
        raise KeptInterrupt(shots) from None
    return shots
