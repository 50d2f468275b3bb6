"""Which scene keys a :class:`~ti_golf.sim.simulation.Simulation` can change, and when.

A change between runs is one of:

* *live*: the air, the contact, gravity, the time step, the integrator, sleeping, the ground
  plane, collisions and the solver: the next step uses the new value, from the current state;
* *at t0*: the keys that set up the balls or the ground (``launch.*``, ``ball.*``,
  ``terrain.*``, and the keys of the ``[[balls]]``, ``[[blocks]]``, ``[[planes]]`` and
  ``[[surfaces]]`` tables, ``blocks[0].number``): they apply when the simulation is at t0 (it is
  set up again, as a new simulation of the changed scene would be), and are refused later in a run;
* *not read*: keys that no simulation reads (``description``, ``world.t_max``, ``sweep.*``,
  ``game.*``): refused, as the scene loader refuses a key that would have no effect.

Plain Python, no Taichi.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from typing import Any

from ti_golf.errors import OVERRIDES, ConfigError
from ti_golf.scene.overrides import parse_override
from ti_golf.scene.readers import NOT_READ, table_of, unread_reason

AT_T0 = ("launch", "ball", "terrain", "balls", "blocks", "planes", "surfaces")
"""Tables (and ``[[...]]`` arrays, whose keys are ``blocks[0].number``) whose keys set up the balls
or the ground at t0."""

MOVES_T0_BALLS = ("world.ground_height",)
"""Live keys that also place the balls at t0 (a launched ball rests on the ground): at t0 they set
the simulation up again, as the keys of :data:`AT_T0` do."""


STILL_AT_REST = frozenset(
    {
        "world.dt",
        "world.integrator",
        "world.t_end",
        "world.v_rest",
        "world.t_rest",
        "contact.e",
        "contact.v_bounce",
        "contact.k_p",
        "contact.solver",
        "contact.layout",
        "contact.iterations",
        "contact.relax",
        "contact.skin",
    }
)
"""Live keys whose change cannot set a ball at rest moving: how the steps are taken, how impacts
bounce, when a ball counts as at rest. A change of any other key (the air and its wind, gravity,
the ground, collisions, friction) wakes the balls at rest, which rest again if nothing moves them."""


def wakes(key: str) -> bool:
    """Whether a change of the live ``key`` wakes the balls at rest (:data:`STILL_AT_REST`)."""
    return key not in STILL_AT_REST


def as_changes(changes: Mapping[str, Any] | Iterable[str] | str, value: Any) -> dict[str, Any]:
    """``set``'s arguments as ``{dotted key: value}``: a key and a value, a mapping, or
    ``KEY=VALUE`` texts (one, or several) as ``--set`` takes them."""
    if isinstance(changes, str):
        if value is not _UNSET:
            return {changes: value}
        return dict([parse_override(changes)])
    if value is not _UNSET:
        raise TypeError(f"set(key, value) takes a key, a dotted text such as 'air.C_D' (got {changes!r:.60})")
    if isinstance(changes, Mapping):
        return dict(changes)
    if not isinstance(changes, (list, tuple)) or not all(isinstance(text, str) for text in changes):
        raise TypeError(
            f"changes must be a key and a value, a mapping of keys to values or KEY=VALUE texts (got {changes!r:.60})"
        )
    return dict(parse_override(text) for text in changes)


class _Unset:
    def __repr__(self) -> str:
        return "<unset>"


_UNSET: Any = _Unset()
"""``set``'s value when none is given (``None`` is a value)."""


def at_t0(key: str) -> bool:
    """Whether ``key`` sets up the balls or the ground at t0."""
    return table_of(key) in AT_T0


def refuse_unread(key: str) -> None:
    """Raise :class:`ConfigError` for a key that no simulation reads."""
    reader = unread_reason(NOT_READ, key)
    if reader is not None:
        raise ConfigError(OVERRIDES, key, f"has no effect on a simulation ({reader})")


def refuse_after_t0(key: str, t: float) -> None:
    """Raise :class:`ConfigError` for a key of :data:`AT_T0` changed at time ``t`` [s] after t0."""
    if at_t0(key):
        raise ConfigError(
            OVERRIDES,
            key,
            f"sets up the balls or the ground at t0, and this run is at t = {t:.6g} s: start again from t0 "
            "with it (Simulation.reset(changes) in Python; ti-golf run SCENE --set KEY=VALUE)",
        )


def refuse_for_given_balls(key: str, initial: Any, kept: bool) -> None:
    """Raise :class:`ConfigError` for a ball key that balls given as arrays do not read: the
    launch's when the positions were given, the radius and the mass when they were (``initial``:
    the balls at t0 as given, ``None`` for the scene's; not ``kept``: what was given is not known,
    so none of them is taken)."""
    if kept and initial is None:
        return
    x_given, radius_given, mass_given = (
        (True,) * 3
        if initial is None
        else (initial.x is not None, initial.radius is not None, initial.mass is not None)
    )
    given = (
        (table_of(key) in ("launch", "balls", "blocks") and x_given)
        or (key == "ball.radius" and radius_given)
        or (key == "ball.mass" and mass_given)
    )
    if given:
        raise ConfigError(
            OVERRIDES,
            key,
            "has no effect: this simulation's balls were given as arrays (edit them with x, v, w or set_ball)",
        )
