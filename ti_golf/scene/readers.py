"""Which scene keys each application leaves unread, with who reads them instead.

A key without effect is an error: a key that the application it is given for does not read (a
``--set`` of a command, a key a study sets or varies for its tasks) is refused, naming what does
read it. The scene loader itself refuses the keys that no application reads in a scene (a
``read_when`` condition, a lattice's seed); what is here depends on the application. Each table
maps a dotted key, or a whole table, to the reason. Plain Python, no Taichi.
"""

from __future__ import annotations

from collections.abc import Mapping

from ti_golf.scene.schema import SCHEMA

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

_NOT_ROLLED = "read only when the balls bounce and roll out to rest: `sweep --to-rest`, a shot, a dispersion"

NOT_ROLLED_OUT: Unread = {
    "contact": _NOT_ROLLED,
    **{f"world.{name}": _NOT_ROLLED for name in ("ground", "v_rest", "t_rest")},
}
"""Keys that only the roll-out to rest reads: flights that stop at landing (a sweep without
``--to-rest``, ``dispersion --no-roll``, the tour table) do not read them. (A ``[terrain]`` stays
read: the launch ball rests on it.)"""

SWEEP_NOT_READ: Unread = {**NOT_ROLLED_OUT, **FLIGHTS_NOT_READ}
"""Keys that a sweep to landing (no ``--to-rest``; a study's sweep task) does not read."""

SHOTS_NOT_READ: Unread = {**FLIGHTS_NOT_READ, "sweep": NOT_READ["sweep"]}
"""Keys that a shot and a dispersion of shots rolled out to rest do not read."""

LANDING_NOT_READ: Unread = {**NOT_ROLLED_OUT, **SHOTS_NOT_READ}
"""Keys that shots flown to landing only (``dispersion --no-roll``) do not read."""

TOUR_NOT_READ: Unread = {
    **LANDING_NOT_READ,
    **{
        f"launch.{name}": "the tour table's rows give each ball's speed, launch angle and backspin, along +x"
        for name in ("speed", "angle_deg", "direction_deg", "spin")
    },
}
"""Keys that the tour table's flights do not read (the scene gives the air, the ball and where
they start)."""

FIT_NOT_READ: Unread = {
    **TOUR_NOT_READ,
    **{
        f"air.{name}": "the fit starts from the same coefficients whatever the scene holds"
        for name in ("C_D_crisis", "Re_crisis")
    },
}
"""Keys that ``ti-golf fit-aero`` does not read (it fits air.C_D_crisis and air.Re_crisis from
fixed starting values, and the second and third terms of air.C_D_S and air.C_L_S)."""

POUR_NOT_READ: Unread = {**NOT_READ, "world.t_end": "the pour runs for `bench pit --t`, or a study's task.t"}
"""Keys that the pit benchmark's pour does not read."""

TIMED_RUN_NOT_READ: Unread = {**NOT_READ, "world.t_end": "the run's own length (task.t or task.steps) replaces it"}
"""Keys that a run given its own length does not read."""

DRAWN = ("air.wind", "world.ground", "world.ground_height")
"""Keys of the tables that only act on the steps (:data:`STILL_NOT_READ`) that a picture draws:
the wind's arrow, the ground plane, and where the ground and a launched ball lie."""

_STILL = "a picture of the initial state simulates nothing: give --t, --steps or --until"

STILL_NOT_READ: Unread = {
    **{
        f"{table}.{name}": _STILL
        for table in ("air", "world", "contact")
        for name in SCHEMA[table]
        if f"{table}.{name}" not in DRAWN
    },
    **NOT_READ,
}
"""Keys that a picture of a scene's initial state (``ti-golf render`` without a time) does not
read: those that act only on the steps. The keys that set up the balls, the ground and the hole
are drawn."""

APPLICATIONS: Mapping[str, Unread] = {
    "run": NOT_READ,
    "sweep": SWEEP_NOT_READ,
    "shot": SHOTS_NOT_READ,
    "dispersion": SHOTS_NOT_READ,
    "tour": TOUR_NOT_READ,
    "pit": POUR_NOT_READ,
}
"""Each application (a study's ``task.kind``, a command) with the keys it does not read."""


def table_of(key: str) -> str:
    """The table of a dotted key (``"air"`` of ``"air.C_D"``, ``"blocks"`` of ``"blocks[0].number"``;
    a top-level key is its own table)."""
    return key.split(".", 1)[0].split("[", 1)[0]


def unread_reason(unread: Unread, key: str) -> str | None:
    """Why ``key`` is not read, by ``unread``'s key or its table; None when it is read."""
    return unread.get(key, unread.get(table_of(key)))
