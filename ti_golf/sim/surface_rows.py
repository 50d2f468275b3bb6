"""The collision solver's rows of surface impulses: the resting impulse (and, for the
Gauss–Seidel sweeps, the friction impulse) of each ball on each plane and the terrain, kept only
for the balls within reach of one (see :mod:`ti_golf.physics.surfaces`)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import taichi as ti

from ti_golf.physics import surfaces
from ti_golf.physics.kernels import zero_f32_table
from ti_golf.physics.types import vec4f
from ti_golf.runtime import free_dropped_arrays
from ti_golf.sim.model import Model
from ti_golf.sim.state import State

if TYPE_CHECKING:
    from ti_golf.sim.solver import CollisionSolver

ROW_ROOM = 4
"""Tables of rows that the balls near a surface outgrow are made for the rows listed plus
1/ROW_ROOM of them (and at least ``MIN_ROWS``), so that a pour filling a bin does not allocate at
every rebuild; a table more than twice as long as the rows listed is made anew, shorter."""
MIN_ROWS = 64


def surface_columns(model: Model) -> int:
    """Columns of a row of surface impulses: one per plane, and one for the terrain."""
    return max(1, len(model.plane_p) + (model.terrain is not None))


def surface_table(rows: int, columns: int) -> ti.Ndarray:
    """A new zeroed table of ``rows`` rows of (λ, F) for ``columns`` surfaces (f32)."""
    table = ti.ndarray(vec4f, (max(1, rows), columns))
    zero_f32_table(table)  # (not table.fill: see zero_f32_table)
    return table


def every_ball_a_row(solver: CollisionSolver, model: Model) -> None:
    """Give every ball a zeroed row (the serial steps: see ``surfaces.every_ball_a_row``)."""
    surfaces.every_ball_a_row(solver.surface_start)
    solver.surface_impulse = surface_table(model.n, surface_columns(model))
    solver.surface_impulse_back = None


def list_surface_rows(solver: CollisionSolver, state: State, carry: bool, v_max: float) -> None:
    """Give a row of surface impulses to each ball that may touch a plane or the terrain before the
    next rebuild (``surfaces.list_surfaces``, with the lists' skin and step and the fastest ball's
    speed ``v_max`` [m/s]) or holds a resting impulse, in the second of two tables, then swap
    them: each ball that had a row keeps its impulses when ``carry`` (the same surfaces; after a
    reorder, ``solver.sorted_ids`` maps each ball to its old index, as for the pairs), the others
    start from zero. Uses
    ``solver.stash_first`` (free once the pairs were carried over) to keep the old rows' starts."""
    model = solver._model
    columns = surface_columns(model)
    carry = carry and solver.surface_impulse.shape[1] == columns
    if carry:
        solver.stash_first.copy_from(solver.surface_start)
    old = (int(carry), solver.stash_first, solver.surface_impulse, int(solver.reorder), solver.sorted_ids)
    rows = int(
        surfaces.list_surfaces(
            model.terrain_params,
            solver._packs.model(model),
            state.x,
            max(solver.skin, 2.0 * model.dt * v_max),
            *old,
            solver.surface_start,
            solver.pair_chunk,
        )
    )
    back = solver.surface_impulse_back
    if back is None or back.shape[1] != columns or not rows <= back.shape[0] <= max(2 * rows, MIN_ROWS):
        solver._packs.clear()  # (their references would keep the old table in memory)
        solver.surface_impulse_back = back = None
        free_dropped_arrays()
        back = surface_table(max(MIN_ROWS, rows + rows // ROW_ROOM), columns)
    surfaces.carry_surfaces(*old, solver.surface_start, back)
    solver.surface_impulse, solver.surface_impulse_back = back, solver.surface_impulse
