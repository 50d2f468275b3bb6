"""The Gauss–Seidel solver (``contact.solver = "gauss_seidel"``): sequential impulses over the
pairs, then the position projection. The pairs are taken in one of two layouts
(``contact.layout``): by blocks of grid columns, the blocks of one colour swept in parallel (the
kernels: :mod:`.colour`), or by contact colours, the pairs of one colour swept in parallel
(:mod:`.contact_colour`, coloured by :mod:`.edge_colouring`); one contact's update is the same in
both (:mod:`.sequential`)."""

from __future__ import annotations

from typing import Any

import numpy as np
import taichi as ti

from ti_golf.physics.model import Model
from ti_golf.physics.state import State
from ti_golf.physics.types import BlockOrder
from ti_golf.runtime import plain_compile
from ti_golf.scene.schema import Scene
from ti_golf.solvers import block_steps, collide, colour, contact_colour, edge_colouring, grid, sort, stale
from ti_golf.solvers.phases import Phase
from ti_golf.solvers.record import SolverRecord
from ti_golf.solvers.solver import CollisionSolver


class GaussSeidelSolver(CollisionSolver, kind="gauss_seidel"):
    """A :class:`.solver.CollisionSolver` whose sweeps are coloured Gauss–Seidel sweeps. A
    parallel one keeps the balls grouped by block of grid columns (``col_ids``, ``col_colour``,
    bucket starts ``col_start``; :meth:`_order_columns`), made again at every build."""

    gauss_seidel = True

    SAVED_ARRAYS = (*CollisionSolver.SAVED_ARRAYS, "col_ids", "col_colour", "col_start", "col_chunk")

    def __init__(
        self, model: Model, capacity: int = 1, serial: bool | None = None, reorder: bool | None = None
    ) -> None:
        super().__init__(model, capacity, serial, reorder)
        # the pairs' colours when the sweeps take them (contact_colour), else None: by grid columns
        self.colours: contact_colour.ContactColours | None = None
        if self._pairs_laid_out(model) and not self.serial:
            self.colours = contact_colour.ContactColours(band=2.0 * self.r_ref * edge_colouring.BAND_DIAMETERS)
        elif self.sweeps_by_blocks(model.scene, self.relists):  # the balls by grid column (colour.column_order)
            self.col_ids, self.col_colour = ti.ndarray(ti.i32, model.n), ti.ndarray(ti.i32, model.n)
            if self.serial:  # the balls colour after colour (block_steps.colour_walk), made at each launch
                self.col_walk = ti.ndarray(ti.i32, model.n)
        # the columns' bucket starts and their scan's scratch, made at the first build (_order_columns)
        self.col_start: ti.Ndarray | None = None
        self.col_chunk: ti.Ndarray | None = None

    def record(self) -> SolverRecord:
        """The solver's record (:meth:`.solver.CollisionSolver.record`), with the pairs' colours of
        the contacts layout (``colours.*``): a run loaded again sweeps its pairs in the same order."""
        record = super().record()
        if self.colours is not None:
            values, arrays = self.colours.saved()
            record.values.update({f"colours.{k}": v for k, v in values.items()})
            for name, a in arrays.items():
                record.arrays[f"colours.{name}"], record.elements[f"colours.{name}"] = a, []
        return record

    def restore(self, record: SolverRecord, state: State) -> None:
        super().restore(record, state)
        if self.colours is not None and "colours.builds" in record.values:
            values = {k.split(".", 1)[1]: v for k, v in record.values.items() if k.startswith("colours.")}
            arrays = {k.split(".", 1)[1]: a for k, a in record.arrays.items() if k.startswith("colours.")}
            self.colours.restore(values, arrays)
        elif self.colours is not None:  # (a record without them: the colours are made again)
            self.rebuild_due = True

    def _pairs_laid_out(self, model: Model) -> bool:
        return contact_colour.resolve_layout(model.scene.contact.layout) == "contacts"

    @classmethod
    def sweeps_by_blocks(cls, scene: Scene, relists: bool) -> bool:
        return not relists and contact_colour.resolve_layout(scene.contact.layout) != "contacts"

    def build(self, state: State) -> None:
        super().build(state)
        if self.colours is not None:
            self.colours.build(self._packs.lists(self))
        elif not self.relists:
            self._order_columns(state)

    def _carry_pair_order(self, stashed: Any) -> None:
        if self.colours is not None:  # the pairs listed before keep their colours
            stash = (stashed, self.stash_first, self.reorder, self.sorted_ids) if stashed is not None else None
            self.colours.carry(self._packs.lists(self), self._model.n, self.pair_capacity, self._model.gravity, stash)

    def _friction_rows(self) -> int:
        return self.pair_capacity  # (each pair's friction impulse, carried from step to step)

    def _all_still(self, state: State) -> bool:
        return colour.moving_balls(state.status) == 0

    def _order_columns(self, state: State) -> None:
        """Group the balls by block of grid columns for the sweeps (``colour.column_order``): the
        blocks of the box around the balls numbered one after another when there are no more of
        them than there are balls, else hashed; and count the balls with pairs that the colours
        leave to ``colour.far_pairs`` (``far_owners``)."""
        bounds = grid.cell_bounds(state.x, 0.5 / self.cell, self.bounds, sort.fold_in_array())  # in 2 x 2 columns
        lo, hi = [int(b) for b in bounds[:3]], [int(b) for b in bounds[3:]]
        ext_x, ext_z = hi[0] - lo[0] + 3, hi[2] - lo[2] + 3
        n = self._model.n
        dense = ext_x * ext_z <= max(n, 16)
        columns = ext_x * ext_z if dense else n
        buckets = 1 << max(4, int(np.ceil(np.log2(columns))))
        if self.col_start is None or self.col_start.shape[0] != buckets + 1:
            self.col_start = ti.ndarray(ti.i32, buckets + 1)
            self.col_chunk = ti.ndarray(ti.i32, sort.scan_chunks(buckets))
        if dense:
            origin, stride = (lo[0] - 1, 0, lo[2] - 1), (1, 0, ext_x)
        else:
            origin, stride = (0, 0, 0), (grid.SCATTERED_HASH[0], 0, grid.SCATTERED_HASH[2])
        far_owners = colour.column_order(
            self.x_at_build,
            1.0 / self.cell,
            buckets - 1,
            ti.Vector(origin, dt=ti.i32),
            ti.Vector(stride, dt=ti.i32),
            rank=self.rank,
            start=self.col_start,
            chunk_start=self.col_chunk,
            ids=self.col_ids,
            colour=self.col_colour,
            tasks=sort.bucket_tasks(buckets),
            lists=self._packs.lists(self),
        )
        self.far_owners = int(far_owners)

    def _block_order(self) -> tuple:
        """What the sweeps by blocks read besides the step's arguments: whether some balls own far
        pairs (``colour.far_pairs``), the grid's inverse cell size [1/m], the threads' share of
        the blocks (``sort.bucket_tasks``) and the blocks (``BlockOrder``)."""
        assert self.col_start is not None, "the lists are built before a step"
        tasks = sort.bucket_tasks(self.col_start.shape[0] - 1)
        blocks = self._packs.get(BlockOrder, start=self.col_start, ids=self.col_ids, colour=self.col_colour)
        return int(self.far_owners > 0), 1.0 / self.cell, tasks, blocks

    def _serial_steps(self, iterations: int, arguments: tuple) -> int:
        """The parallel step's launches in one thread, many steps in one launch
        (``block_steps.gauss_seidel_steps``): the same steps, bit for bit."""
        g, _grid, apart_ids, _stored_sorted = self.last_grid()
        any_far, inv_cell, _tasks, blocks = self._block_order()
        return int(
            block_steps.gauss_seidel_steps(
                *arguments,
                g,
                self.start,
                self.sorted_ids,
                apart_ids,
                iterations,
                any_far,
                inv_cell,
                int(self.skip_still),
                blocks,
                self.col_walk,
            )
        )

    def _sweep(self, iterations: int, arguments: tuple) -> tuple[bool, bool | None]:
        """One parallel step: the free flight and warm start, ``iterations`` coloured sweeps and
        the restitution pass (``colour.step_phases``), the last sweep, which only finishes the
        step, then ``colour.PROJECTIONS`` passes of the position projection. Returns whether the
        lists must be rebuilt and whether some ball is awake and in play, from one readback
        (:meth:`_after_step`)."""
        collide.launch(arguments, serial=collide.PARALLEL, warm=True, sweeps=0, last=False)
        scalars, _, _, _, kinds, model, lists, state, _, scratch = arguments
        if self.colours is not None:  # the contacts layout (contact_colour)
            contact_colour.gauss_seidel_step(self.colours, iterations, arguments)
            collide.launch(arguments, serial=collide.PARALLEL, warm=False, sweeps=0, last=True)
            contact_colour.project(self.colours, arguments)
            return self._after_step(arguments)
        any_far, inv_cell, tasks, blocks = self._block_order()
        for phase in colour.step_phases(iterations):
            with plain_compile():  # see runtime.plain_compile
                colour.gauss_seidel_sweep(
                    phase,
                    any_far,
                    inv_cell,
                    tasks,
                    kinds,
                    scalars,
                    model=model,
                    lists=lists,
                    state=state,
                    scratch=scratch,
                    blocks=blocks,
                )
            if any_far:
                colour.far_pairs(phase, inv_cell, kinds, scalars, model, lists, state, scratch)
        collide.launch(arguments, serial=collide.PARALLEL, warm=False, sweeps=0, last=True)
        for _ in range(colour.PROJECTIONS):
            if any_far:
                colour.far_pairs(Phase.PROJECT, inv_cell, kinds, scalars, model, lists, state, scratch)
            colour.project_sweep(
                any_far, inv_cell, tasks, scalars, model, lists=lists, state=state, scratch=scratch, blocks=blocks
            )
        return self._after_step(arguments)

    def _after_step(self, arguments: tuple) -> tuple[bool, bool]:
        """Whether the lists must be rebuilt after a parallel step, and whether some ball is awake
        and in play (``stale.lists_stale``, one readback)."""
        scalars, _, _, _, kinds, model, lists, state, _, scratch = arguments
        answer = int(stale.lists_stale(scalars, *self.last_grid(), kinds, model, lists, state, scratch))
        return bool(answer & stale.LISTS_STALE), bool(answer & stale.BALLS_AWAKE)
