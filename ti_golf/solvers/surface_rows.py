"""The collision solver's rows of surface impulses: the resting impulse (and, for the
Gauss–Seidel sweeps, the friction impulse) of each ball on each plane and the terrain, kept only
for the balls within reach of one (see :mod:`ti_golf.solvers.surfaces`)."""

from __future__ import annotations

from typing import Any

import taichi as ti

from ti_golf.physics.kernels import copy_ints, zero_f32_table
from ti_golf.physics.model import Model, scene_planes
from ti_golf.physics.state import State
from ti_golf.physics.types import vec4f
from ti_golf.scene.schema import Scene
from ti_golf.solvers import surfaces

ROW_ROOM = 4
"""Tables of rows that the balls near a surface outgrow are made for the rows listed plus
1/ROW_ROOM of them (and at least ``MIN_ROWS``), so that a pour filling a bin does not allocate at
every rebuild; a table more than twice as long as the rows listed is made anew, shorter."""
MIN_ROWS = 64


def surface_columns(model: Model) -> int:
    """Columns of a row of surface impulses: one per plane, and one for the terrain."""
    return max(1, len(model.plane_p) + (model.terrain is not None))


def scene_surface_columns(scene: Scene) -> int:
    """:func:`surface_columns` of a model of ``scene``, from the scene alone (no model made)."""
    return max(1, len(scene_planes(scene)) + (scene.terrain is not None))


def surface_table(rows: int, columns: int) -> ti.Ndarray:
    """A new zeroed table of ``rows`` rows of (λ, F) for ``columns`` surfaces (f32)."""
    table = ti.ndarray(vec4f, (max(1, rows), columns))
    zero_f32_table(table)  # (not table.fill: see zero_f32_table)
    return table


def every_ball_a_row(start: ti.Ndarray, model: Model) -> ti.Ndarray:
    """Give every ball a row (the serial steps: see ``surfaces.every_ball_a_row``), its start in
    ``start``; returns the new zeroed table of the rows."""
    surfaces.every_ball_a_row(start)
    return surface_table(model.n, surface_columns(model))


def list_surface_rows(solver: Any, state: State, carry: bool, v_max: float) -> tuple[int, tuple]:
    """Give a row of surface impulses to each ball of ``solver`` (a :class:`.solver.CollisionSolver`)
    that may touch a plane or the terrain before the next rebuild (``surfaces.list_surfaces``, with
    the lists' skin and step and the fastest ball's speed ``v_max`` [m/s]) or holds a resting
    impulse: the rows' starts in ``solver.surface_start``. Keeps the old rows' starts in
    ``solver.stash_first`` (free once the pairs were carried over) when ``carry`` (the same
    surfaces; after a reorder, ``solver.sorted_ids`` maps each ball to its old index, as for the
    pairs). Returns (the rows listed, the old rows as ``surfaces.carry_surfaces`` reads them)."""
    model = solver.model
    carry = carry and solver.surface_impulse.shape[1] == surface_columns(model)
    if carry:
        copy_ints(solver.surface_start, solver.stash_first)
    old = (int(carry), solver.stash_first, solver.surface_impulse, int(solver.reorder), solver.sorted_ids)
    rows = surfaces.list_surfaces(
        model.terrain is not None,
        model.terrain_params,
        solver.packs.model(model),
        state.x,
        max(solver.skin, 2.0 * model.dt * v_max),
        *old,
        solver.surface_start,
        solver.pair_chunk,
    )
    return int(rows), old


def table_fits(table: ti.Ndarray | None, rows: int, columns: int) -> bool:
    """Whether ``table`` can hold ``rows`` rows of ``columns`` surfaces without being more than
    twice as long as they need (and ``MIN_ROWS``)."""
    return table is not None and table.shape[1] == columns and rows <= table.shape[0] <= max(2 * rows, MIN_ROWS)


def table_for(rows: int, columns: int) -> ti.Ndarray:
    """A new table for ``rows`` rows of ``columns`` surfaces, with room to grow (``ROW_ROOM``)."""
    return surface_table(max(MIN_ROWS, rows + rows // ROW_ROOM), columns)
