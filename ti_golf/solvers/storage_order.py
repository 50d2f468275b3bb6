"""The balls stored in the hash grid's order (``CollisionSolver.reorder``), so that balls close in
space lie close in memory."""

from __future__ import annotations

import taichi as ti

from ti_golf.physics.model import Model
from ti_golf.physics.state import State
from ti_golf.solvers import sort


def store_in_grid_order(state: State, model: Model, grid: tuple, spares: list[ti.Ndarray]) -> list[ti.Ndarray]:
    """Gather every per-ball array of ``state`` and ``model`` into the grid's order (see
    ``CollisionSolver.reorder``): ball p of the new order is ball ``sorted_ids[p]`` of the old one,
    and the grid's bucket starts stay valid for :func:`~ti_golf.solvers.grid.list_neighbours`
    (``stored_sorted``). ``grid``: the arguments of :func:`.sort.storage_order` after the
    positions (the cells, the hash and the bucket tables, ``sorted_ids`` last). ``spares``: scratch
    arrays (a vec3, a float and an int array, the last also one of ``grid``'s tables) that take the
    gathered values; returns them with the old arrays in their places, as scratch. So no array is
    allocated but, on the first reorder, the state's ``ids``: the storage order stays in Taichi's
    memory, where each reorder gathers it as it gathers the balls, rather than being composed in
    numpy (at 8,192 balls that left 16 bytes per ball of freed heap in the process)."""
    sort.storage_order(state.x, *grid)
    order = grid[-1]
    spares = list(spares)
    per_ball = [(state, name) for name in state.per_ball()] + [(model, name) for name in model.per_ball()]
    for owner, name in per_ball:
        values = getattr(owner, name)
        k = next(k for k, a in enumerate(spares) if (a.dtype, a.element_shape) == (values.dtype, values.element_shape))
        sort.gather(values, order, spares[k])
        setattr(owner, name, spares[k])
        spares[k] = values
    if state.ids is None:  # the first reorder: the ids are this build's order (gathered above from then on)
        state.ids = ti.ndarray(ti.i32, state.n)
        state.ids.copy_from(order)
    return spares
