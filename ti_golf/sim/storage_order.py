"""Storing the balls in the hash grid's order (``CollisionSolver.reorder``), so that balls close in
space lie close in memory."""

from __future__ import annotations

from typing import TYPE_CHECKING

import taichi as ti

from ti_golf.physics import sort
from ti_golf.sim.state import State

if TYPE_CHECKING:
    from ti_golf.sim.solver import CollisionSolver


def store_in_grid_order(solver: CollisionSolver, state: State) -> None:
    """Gather every per-ball array of ``state`` and the model into the grid's order (see
    ``CollisionSolver.reorder``): ball p of the new order is ball ``sorted_ids[p]`` of the old one, and the
    grid's bucket starts stay valid for :func:`~ti_golf.physics.grid.list_neighbours` (``stored_sorted``).
    Scratch arrays of the same type take the gathered values and the old arrays become scratch,
    so no array is allocated but, on the first reorder, the state's ``ids``: the storage order
    stays in Taichi's memory, where each reorder gathers it as it gathers the balls, rather than
    being composed in numpy (at 8,192 balls that left 16 bytes per ball of freed heap in the
    process)."""
    sort.storage_order(
        state.x,
        1.0 / solver.cell,
        solver.mask,
        *solver._hash,
        solver.rank,
        solver.start,
        solver.chunk_start,
        solver.sorted_ids,
    )
    order = solver.sorted_ids
    spares = [solver.v_free, solver.calm, solver.rank]  # scratch between steps: a vec3, a float and an int array
    model = solver._model
    per_ball = [(state, name) for name in state.per_ball()] + [(model, name) for name in model.per_ball()]
    for owner, name in per_ball:
        values = getattr(owner, name)
        k = next(k for k, a in enumerate(spares) if (a.dtype, a.element_shape) == (values.dtype, values.element_shape))
        sort.gather(values, order, spares[k])
        setattr(owner, name, spares[k])
        spares[k] = values
    solver.v_free, solver.calm, solver.rank = spares
    for column in range(solver.lam_plane.shape[1]):
        sort.gather_column(solver.lam_plane, column, order, solver.clear)  # (f32 scratch between steps)
        if solver.gauss_seidel:  # (the positions at the last build: vec3f scratch until this one ends)
            sort.gather_column(solver.friction_plane, column, order, solver.x_at_build)
    if state.ids is None:  # the first reorder: the ids are this build's order (gathered above from then on)
        state.ids = ti.ndarray(ti.i32, state.n)
        state.ids.copy_from(order)
