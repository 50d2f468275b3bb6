"""What a build of the neighbour lists refuses, and the ball it names when it does: a thread's loops
past what Taichi's Vulkan backend runs (:func:`check_loop_cap`), or tables past the memory at hand
(``CollisionSolver._check_table_memory``), both widened by the ball that reaches farthest
(:func:`farthest_reaching`)."""

from __future__ import annotations

import numpy as np

from ti_golf.errors import SimulationError
from ti_golf.physics.model import Model
from ti_golf.physics.state import State


def check_loop_cap(loop_cap: int | None, cell: float, model: Model, state: State, loops: int) -> None:
    """Raise :class:`SimulationError` when a build ran a thread's loops past ``loop_cap`` (see
    ``grid.LOOP_CAP``; ``None``: no cap; ``loops``: the bound ``grid.list_neighbours`` returns;
    ``cell``: the grid's cell size [m]): on Taichi's Vulkan backend that thread stopped without a
    word, and pairs are missing from the lists."""
    if loop_cap is None or loops <= loop_cap:
        return
    ball, farthest = farthest_reaching(model, state)
    raise SimulationError(
        f"listing the neighbours of a ball took up to {loops:,} loop iterations in one thread, and Taichi's "
        f"Vulkan backend stops a thread's loops after {loop_cap:,} without a word: pairs would be "
        f"missed. The cells are {cell:.4g} m wide for the largest ball and the fastest pair. "
        f"{farthest}; run on the CPU or CUDA backend (--arch), or lower that ball's radius or speed",
        [ball],
    )


def farthest_reaching(model: Model, state: State) -> tuple[int, str]:
    """(id, a sentence naming it) of the ball that reaches farthest within a step (r + h·|v|): the
    one that widens the lists, and on a GPU the cells."""
    h = model.dt
    speed = np.linalg.norm(state.v.to_numpy(), axis=1)
    radius = np.broadcast_to(model.radius.to_numpy(), speed.shape)  # one entry when all are alike
    k = int(np.argmax(radius + h * speed))
    order = state.order
    ball = int(order[k]) if order is not None else k
    return ball, (
        f"Ball {ball} reaches farthest (radius {radius[k]:.4g} m, speed {speed[k]:.4g} m/s: "
        f"{h * speed[k]:.4g} m per step of {h:g} s)"
    )
