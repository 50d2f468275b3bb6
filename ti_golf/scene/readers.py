"""Which scene keys each application leaves unread, with who reads them instead.

A key without effect is an error: a key that the application it is given for does not read (a
``--set`` of a command, a key a study sets or varies for its tasks) is refused, naming what does
read it. The scene loader itself refuses the keys that no application reads in a scene (a
``read_when`` condition, a lattice's seed); what is here depends on the application. Each table
maps a dotted key, or a whole table, to the reason. Plain Python, no Taichi.
"""

from __future__ import annotations

from collections.abc import Mapping

Unread = Mapping[str, str]
"""Dotted keys or whole tables (``"game"``), each with the reason it is not read."""

NOT_READ: Unread = {
    "description": "it is text for `ti-golf scenes`",
    "world.t_max": "sweeps read it (`ti-golf sweep`, ti_golf.sweep)",
    "sweep": "`ti-golf sweep` reads it",
    "game": "`ti-golf play` reads it",
}
"""Keys (or whole tables) that no simulation reads (``ti-golf run``, ``render``, ``lab``,
:class:`~ti_golf.sim.simulation.Simulation`), with who does."""

_SHOTS_APART = "each shot flies and rolls out alone, with no ball–ball collisions"

FLIGHTS_NOT_READ: Unread = {
    "description": NOT_READ["description"],
    "game": NOT_READ["game"],
    "hole": "`ti-golf run` and `ti-golf play` read it",
    "world.t_end": "a shot flies until it lands and rolls out until it rests, within world.t_max",
    "world.collisions": _SHOTS_APART,
    **{f"contact.{name}": _SHOTS_APART for name in ("solver", "layout", "iterations", "relax", "skin")},
}
"""Keys that the flights of a sweep, a shot, a dispersion and the tour table do not read: each
ball flies to landing and rolls out alone (:func:`ti_golf.golf.rollout.roll_out`)."""

SHOTS_NOT_READ: Unread = {**FLIGHTS_NOT_READ, "sweep": NOT_READ["sweep"]}
"""Keys that a shot and a dispersion of shots do not read."""

TOUR_NOT_READ: Unread = {
    **SHOTS_NOT_READ,
    **{
        f"launch.{name}": "the tour table's rows give each ball's speed, launch angle and backspin, along +x"
        for name in ("speed", "angle_deg", "direction_deg", "spin")
    },
}
"""Keys that the tour table's flights do not read (the scene gives the air, the ball and where
they start)."""

POUR_NOT_READ: Unread = {**NOT_READ, "world.t_end": "the pour runs for `bench pit --t`, or a study's task.t"}
"""Keys that the pit benchmark's pour does not read."""

TIMED_RUN_NOT_READ: Unread = {**NOT_READ, "world.t_end": "the run's own length (task.t or task.steps) replaces it"}
"""Keys that a run given its own length does not read."""

APPLICATIONS: Mapping[str, Unread] = {
    "run": NOT_READ,
    "sweep": FLIGHTS_NOT_READ,
    "shot": SHOTS_NOT_READ,
    "dispersion": SHOTS_NOT_READ,
    "tour": TOUR_NOT_READ,
    "pit": POUR_NOT_READ,
}
"""Each application (a study's ``task.kind``, a command) with the keys it does not read."""


def table_of(key: str) -> str:
    """The table of a dotted key (``"air"`` of ``"air.C_D"``; a top-level key is its own table)."""
    return key.split(".", 1)[0]


def unread_reason(unread: Unread, key: str) -> str | None:
    """Why ``key`` is not read, by ``unread``'s key or its table; None when it is read."""
    return unread.get(key, unread.get(table_of(key)))
