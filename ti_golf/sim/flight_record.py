"""A tracked ball's flight record started again: a ball moved or struck between steps is launched
anew from where it is, at the time it is (its carry, apex and hang time are measured from there)."""

from __future__ import annotations

import numpy as np

from ti_golf.physics.integrate import IN_FLIGHT, NOT_TRACKED
from ti_golf.physics.model import Model
from ti_golf.physics.state import State


def launch_again(
    state: State,
    model: Model,
    launch_x: np.ndarray | None,
    launch_t: np.ndarray | None,
    t: float,
    x: np.ndarray,
    ids: np.ndarray,
) -> None:
    """Launch the tracked balls among ``ids`` again from their centres ``x`` [m] (all balls', (N, 3),
    by id) at the time ``t`` [s]: their launch points ``launch_x`` (N, 3) and times ``launch_t``
    (N,) are set in place, the height whose downward crossing is their landing
    (``model.launch_height``, in storage order) becomes their height, and their records are in
    flight again with the apex where they are. At t0 this moves the launch itself. Nothing
    without tracked balls (``launch_x`` ``None``)."""
    if launch_x is None or launch_t is None:
        return
    landed = state.read("landed")
    ids = ids[landed[ids] != NOT_TRACKED]
    if ids.size == 0:
        return
    start = x[ids]
    launch_x[ids], launch_t[ids] = start, t
    landed[ids] = IN_FLIGHT
    state.write("landed", landed)
    for name, value in (("apex", start[:, 1]), ("t_land", 0.0), ("land_x", 0.0), ("land_v", 0.0)):
        record = state.read(name)
        record[ids] = value
        state.write(name, record)
    level = model.launch_height.to_numpy()
    order = state.order  # (storage index to ball id; None: the same)
    level[ids if order is None else np.argsort(order)[ids]] = start[:, 1]
    model.launch_height.from_numpy(level)
