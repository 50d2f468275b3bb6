"""The orders the collision solver keeps the balls in: their storage in the hash grid's order
(``CollisionSolver.reorder``), so that balls close in space lie close in memory, and the
Gauss–Seidel sweeps' blocks of grid columns (:func:`order_columns`)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import taichi as ti

from ti_golf.physics import colour, grid, sort
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
    if state.ids is None:  # the first reorder: the ids are this build's order (gathered above from then on)
        state.ids = ti.ndarray(ti.i32, state.n)
        state.ids.copy_from(order)


def order_columns(solver: CollisionSolver, state: State) -> None:
    """Group the balls of ``solver`` by block of grid columns for the Gauss–Seidel sweeps
    (``colour.column_order``): the blocks of the box around the balls numbered one after
    another when there are no more of them than there are balls, else hashed; and count the
    balls with pairs that the colours leave to ``colour.far_pairs``."""
    bounds = grid.cell_bounds(state.x, 0.5 / solver.cell)  # in blocks of 2 x 2 columns
    lo, hi = [int(b) for b in bounds[:3]], [int(b) for b in bounds[3:]]
    ext_x, ext_z = hi[0] - lo[0] + 3, hi[2] - lo[2] + 3
    n = solver._model.n
    dense = ext_x * ext_z <= max(n, 16)
    columns = ext_x * ext_z if dense else n
    buckets = 1 << max(4, int(np.ceil(np.log2(columns))))
    if solver.col_start is None or solver.col_start.shape[0] != buckets + 1:
        solver.col_start = ti.ndarray(ti.i32, buckets + 1)
        solver.col_chunk = ti.ndarray(ti.i32, sort.scan_chunks(buckets))
    if dense:
        origin, stride = (lo[0] - 1, 0, lo[2] - 1), (1, 0, ext_x)
    else:
        origin, stride = (0, 0, 0), (grid.SCATTERED_HASH[0], 0, grid.SCATTERED_HASH[2])
    inv_cell = 1.0 / solver.cell
    far_owners = colour.column_order(
        solver.x_at_build,
        inv_cell,
        buckets - 1,
        ti.Vector(origin, dt=ti.i32),
        ti.Vector(stride, dt=ti.i32),
        solver.rank,
        solver.col_start,
        solver.col_chunk,
        solver.col_ids,
        solver.col_colour,
        sort.bucket_tasks(buckets),
        solver._packs.lists(solver),
    )
    solver.far_owners = int(far_owners)
