"""Shots as golfers meet them: launch-monitor launches flown to landing, then rolled out to rest.

Two phases, each the fastest the engine has for it:

1. the flight to landing (at launch height) in SIMD lanes (:func:`ti_golf.golf.sweep.fly`, the
   scene's integrator, step ``world.dt`` or a chosen flight step);
2. from the landing state (x, v, ω), bounce and roll on the scene's ground, turf included, with
   ball–ball collisions off (:func:`ti_golf.golf.rollout.roll_out`, step ``world.dt``).
"""

from __future__ import annotations

import os
from dataclasses import replace

import numpy as np

from ti_golf.golf.sweep import fly_then_roll_out
from ti_golf.scene.balls import launch_position
from ti_golf.scene.launch_monitor import LAUNCH_LIMITS, MonitorLaunch, target_direction
from ti_golf.scene.loader import load_scene
from ti_golf.scene.schema import Scene
from ti_golf.signals import KeptInterrupt
from ti_golf.sim.results import Shots
from ti_golf.sim.simulation import RunProgress


def fly_shots(
    scene: Scene,
    x0: np.ndarray,
    v0: np.ndarray,
    w0: np.ndarray,
    to_rest: bool = True,
    flight_dt: float | None = None,
    progress: RunProgress | None = None,
) -> Shots:
    """Fly balls from (x0, v0, ω0) (each (N, 3), SI) to landing and, with ``to_rest``, roll them
    out to rest on the scene's ground. A ball that never rises above its launch height (launched
    level or downward, without the lift to climb) is down through it at once: its carry, apex and
    hang time are 0, its landing angle, speed and spin NaN, and all it travels is roll.

    ``flight_dt`` [s] replaces ``world.dt`` for the flight only (the roll-out keeps ``world.dt``,
    which the contacts need); ``progress(t_done, t_total)`` follows the roll-out.

    The flights are one kernel launch: an interrupt waits for it. Interrupted then, or during the
    roll-out, it raises :class:`KeptInterrupt` holding the Shots computed: the flights, and the
    rests reached (none when the flights were interrupted).
    """
    x0 = np.asarray(x0, dtype=float)
    if flight_dt is not None and not FLIGHT_DT_RANGE[0] <= flight_dt <= FLIGHT_DT_RANGE[1]:
        lo, hi = FLIGHT_DT_RANGE
        raise ValueError(f"flight_dt must be in [{lo:g}, {hi:g}] s (got {flight_dt!r})")
    flown = scene if flight_dt is None else replace(scene, world=replace(scene.world, dt=float(flight_dt)))
    step_name = "world.dt" if flight_dt is None else "flight_dt"
    _, shots, stopped = fly_then_roll_out(scene, x0, v0, w0, to_rest, progress, flown, step_name)
    if stopped is not None:
        raise KeptInterrupt(_down_at_once(shots)) from None
    return _down_at_once(shots)


def _down_at_once(out: Shots) -> Shots:
    """``out`` with no landing angle, speed or spin for a ball that never rose above its launch
    height: it is "down" at once, with no landing to describe."""
    rose = ~(out.apex <= 0.0)
    if not rose.all():
        nan = np.where(rose, 1.0, np.nan)
        out = replace(
            out, land_angle=out.land_angle * nan, land_speed=out.land_speed * nan, land_spin=out.land_spin * nan
        )
    return out


FLIGHT_DT_RANGE = (1e-5, 0.05)
"""The flight steps [s] a shot's flight may take (``flight_dt``): down to 10 µs, up to 50 ms."""

LAUNCH_UNITS = {"speed": "m/s", "vla_deg": "deg", "hla_deg": "deg", "spin": "rad/s", "axis_deg": "deg"}
"""The unit of each launch-monitor value, as :class:`MonitorLaunch` holds it."""


def check_launches(launch: MonitorLaunch) -> None:
    """Every launch of ``launch`` (floats, or arrays of one shape) finite and within
    :data:`~ti_golf.scene.launch_monitor.LAUNCH_LIMITS`, or a ValueError naming the field, the
    allowed range and the first value outside it."""
    shapes = {np.shape(getattr(launch, name)) for name in LAUNCH_LIMITS} - {()}
    if len(shapes) > 1:
        raise ValueError(f"the launch's arrays must share one shape (got {sorted(shapes)})")
    for name, (lo, hi) in LAUNCH_LIMITS.items():
        a = np.atleast_1d(np.asarray(getattr(launch, name), dtype=float))
        bad = ~(np.isfinite(a) & (a >= lo) & (a <= hi))
        if np.any(bad):
            raise ValueError(f"launch {name} must be in [{lo:g}, {hi:g}] {LAUNCH_UNITS[name]} (got {a[bad][0]:g})")


def shots(
    scene: Scene | str | os.PathLike[str],
    launch: MonitorLaunch,
    to_rest: bool = True,
    flight_dt: float | None = None,
    progress: RunProgress | None = None,
) -> Shots:
    """Fly launch-monitor launches (floats, or arrays of shape (N,)) from the scene's launch point
    (the ball on the ground at the origin unless ``launch.position`` says otherwise), the target
    line along the scene's launch azimuth; see :func:`fly_shots`. ``scene`` is a Scene, a TOML
    path or a bundled scene name.

    Example:
        >>> from ti_golf.scene.launch_monitor import MonitorLaunch, MPH, RPM   # doctest: +SKIP
        >>> fade = MonitorLaunch(123 * MPH, 16.1, 0.0, 7124 * RPM, 5.0)         # doctest: +SKIP
        >>> s = shots(load_scene("tour_shot"), fade); s.carry, s.offline        # doctest: +SKIP
    """
    check_launches(launch)
    if not isinstance(scene, Scene):
        scene = load_scene(scene)
    v0, w0 = launch.vectors(target_direction(scene))
    x0 = np.tile(np.asarray(launch_position(scene), float), (len(v0), 1))
    return fly_shots(scene, x0, v0, w0, to_rest=to_rest, flight_dt=flight_dt, progress=progress)
