"""The collision solvers' shared base (:class:`CollisionSolver`): the hash-grid neighbour lists,
the pair and surface tables with their carried impulses, the storage order, and the build of the
lists (:meth:`CollisionSolver.build`). It steps as :class:`.stepping.Stepping` does (serially or
in parallel, the lists built again when a step asks), and a saved run keeps it as
:class:`.record.Recorded` says. A step is free flight, the contact sweeps and the end-of-step
position update, in that fixed order (see :mod:`.collide`); the sweeps are each kind's own:
:class:`.jacobi.JacobiSolver` and :class:`.gauss_seidel.GaussSeidelSolver`, which
``CollisionSolver(model)`` picks by ``contact.solver``."""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np
import taichi as ti

from ti_golf.errors import SimulationError
from ti_golf.physics.kernels import copy_ints, zero_f32_vectors
from ti_golf.physics.model import Model
from ti_golf.physics.packs import Packs
from ti_golf.physics.state import State
from ti_golf.physics.types import GridParams, GridScratch, KeptLists, pair_columns, pair_table_type, vec3, vec3f
from ti_golf.runtime import (
    available_memory,
    byte_size,
    ensure_init,
    free_dropped_arrays,
    on_cpu,
    plain_compile,
    release_freed_memory,
    watch,
)
from ti_golf.scene.schema import Scene
from ti_golf.solvers import apart, grid, links, sort, stale, surfaces
from ti_golf.solvers.limits import check_loop_cap, farthest_reaching
from ti_golf.solvers.links import table_bytes
from ti_golf.solvers.record import Recorded, SolverRecord
from ti_golf.solvers.stepping import Stepping, relists_in_kernel, steps_serially
from ti_golf.solvers.storage_order import store_in_grid_order
from ti_golf.solvers.surface_rows import (
    every_ball_a_row,
    list_surface_rows,
    surface_columns,
    surface_table,
    table_fits,
    table_for,
)

REORDER_MIN_BALLS = 8192
"""From this many balls on, the parallel step stores the balls in grid order (see
:attr:`CollisionSolver.reorder`): smaller piles stay in the CPU's caches whatever their order."""


PAIR_ROOM = 16
"""Pair tables that the lists outgrow are made for the pairs listed plus 1/PAIR_ROOM of them (see
``CollisionSolver._fit_pair_tables``): room for the lists to grow a little before the tables are
allocated again, while a pour lands."""


COLLECT_EVERY = 64
"""Rebuilds of the lists between two full collections of Python's garbage, in piles of
``REORDER_MIN_BALLS`` or more: Taichi's kernel launches leave reference cycles that only a full
collection frees, and while a pour lands the lists are rebuilt at every step (what they hold and
what a collection costs: the docs' performance page, "Design measurements")."""


class CollisionSolver(Recorded, Stepping):
    """Buffers and neighbour lists for stepping N colliding balls: the driver both kinds of
    sweeps share. ``CollisionSolver(model, ...)`` makes the kind that ``contact.solver`` names
    (:attr:`KINDS`); each kind steps with its own sweeps (:meth:`.stepping.Stepping._sweep`), the
    steps as :class:`.stepping.Stepping` takes them, and a saved run keeps what
    :class:`.record.Recorded` names.

    Attributes:
        r_max: the largest radius [m] of the balls.
        cell: grid cell size [m] at the last build: the largest diameter plus the skin, or plus
            2h·v_max when the fastest pair could close more than the skin in a step (see
            ``grid.cell_size``: pairs are listed by their closing speed too); both of the balls
            not listed apart when some are (``n_apart``).
        skin: neighbour-list skin [m] (``contact.skin`` × ``r_ref``).
        r_cut, r_ref: balls bigger than ``r_cut`` [m] are listed apart, and ``r_ref`` [m] is the
            largest radius of the others (``apart.size_cut``: infinite, and the largest radius,
            unless a few balls are more than twice the size of the rest).
        n_apart: how many balls, much faster or bigger than the rest, the last build set apart
            (``apart.APART_MAX``): they own none of their pairs with the others, and on CPU
            backends they are listed apart.
        loop_cap: on Taichi's Vulkan backend, the loop iterations after which a thread stops (see
            ``grid.LOOP_CAP``): a build that needs more stops the run; ``None`` elsewhere.
        capacity: width of the neighbour table, the upper lists' (it grows when a list overflows).
        pair_capacity: entries of the pair tables (resting and friction impulses, the sweep's
            entries): the pairs listed, laid out ball after ball (``first``), plus room to grow.
        rebuilds: how many times the neighbour lists were built (for benchmarks and tests).
        drift, amendable: each ball's skin used before the last build since its list was made
            (f32, [m]), and whether the next build may keep the lists of the balls that did not
            move (:meth:`_may_amend`; see ``grid.list_neighbours``).
        edited: whether balls were moved or the model retuned between steps since the lists were
            last built (``invalidate``): the lists may then miss pairs that overlap now
            (:meth:`pairs_that_may_overlap`); a fresh or restored solver counts as edited.
        skip_still: whether a parallel step in which no ball is awake and in play is skipped, the
            time advanced alone (default: with the Gauss–Seidel sweeps, under which such a step
            changes nothing, see ``colour.moving_balls``): a pile asleep then costs one pass over
            the balls' status a step, not the step's dozen kernel launches.
        still_steps: how many steps were so skipped (for benchmarks and tests).
        far_owners: how many balls own pairs that the Gauss–Seidel colours leave to
            ``colour.far_pairs`` (0 with the Jacobi sweeps).
        serial: whether steps run serially, many per launch (default: :func:`.stepping.steps_serially`; CPU
            backends only); else one parallel launch per step. Both give the same lists, and
            bit-identical steps with the Jacobi sweeps, and with the Gauss–Seidel sweeps when the
            lists are not rebuilt in the kernel (``relists``).
        relists: whether the serial launches rebuild the lists themselves by testing every pair
            (up to ``RELIST_MAX_BALLS`` balls); else they are built with the hash grid, between
            launches when serial. Either gives the same lists.
        reorder: whether every list build also stores the balls in the grid's order, so that
            balls close in space lie close in memory (default: from ``REORDER_MIN_BALLS`` balls
            on, parallel steps only). A pile whose ids are in no spatial order (balls passed in
            any order, balls that have mixed) otherwise fetches every neighbour from a cache line
            of its own. Each per-ball array of the state and the model is gathered into the new order
            (``State.order`` records it; :class:`~ti_golf.sim.simulation.Simulation` reads and writes by
            ball id), and the pairs keep their accumulated impulses. The physics is the same, but
            sums over a ball's neighbours run in another order: results differ from a run
            without reordering by round-off, and two runs of a scene still agree bit for bit.
    """

    KINDS: ClassVar[dict[str, type[CollisionSolver]]] = {}
    """The kinds of solver by their ``contact.solver`` name (each subclass adds itself)."""

    gauss_seidel: ClassVar[bool] = False
    """Whether the sweeps are Gauss–Seidel's: the kernels' flag for the pairs' friction impulses."""

    def __init_subclass__(cls, kind: str = "", **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        if kind:
            CollisionSolver.KINDS[kind] = cls

    def __new__(cls, model: Model, *args: Any, **kwargs: Any) -> CollisionSolver:
        if cls is CollisionSolver:  # the kind the scene names
            cls = CollisionSolver.KINDS[model.scene.contact.solver]
        return super().__new__(cls)

    def __init__(
        self, model: Model, capacity: int = 1, serial: bool | None = None, reorder: bool | None = None
    ) -> None:
        self._model = model
        self._packs = Packs()
        n = model.n
        self.r_max = float(model.radius_np.max())
        self.r_cut, self.r_ref = apart.size_cut(model.radius_np)
        self.skin = model.scene.contact.skin * self.r_ref
        self.v_cut = apart.fast_speed(self.r_ref, self.skin, model.dt)  # faster balls are listed apart
        self.h = model.dt  # the time step the lists are built for [s]
        self.cell = grid.cell_size(self.r_max, self.skin, model.dt, 0.0)[0]
        self.mask = (1 << max(4, int(np.ceil(np.log2(2 * n))))) - 1
        if serial is None:  # (a layout of the sweeps by pairs, or the grid's storage order, when asked for, is
            # what the steps take, however few the balls)
            serial = steps_serially(n) and not self._pairs_laid_out(model) and not reorder
        self.serial = bool(serial)
        if self.serial and not on_cpu():
            raise ValueError("serial stepping runs on the CPU backend only (on a GPU it would run on one thread)")
        self.reorder = (n >= REORDER_MIN_BALLS and not self.serial) if reorder is None else bool(reorder)
        if self.reorder and self.serial:
            raise ValueError("serial stepping keeps the balls in id order (reorder=False)")
        self.relists = relists_in_kernel(n, self.serial)
        if self.relists:  # a table wide enough for every other ball: the kernel's lists cannot overflow
            capacity = max(capacity, n - 1, 1)
        self.capacity = capacity
        self.rebuilds = 0
        self.still_steps = 0
        self.rank = ti.ndarray(ti.i32, n)
        self.sorted_ids = ti.ndarray(ti.i32, n)
        self.start = ti.ndarray(ti.i32, self.mask + 2)
        self.chunk_start = ti.ndarray(ti.i32, sort.scan_chunks(self.mask + 1))
        self.x_at_build = ti.ndarray(vec3f, n)  # f32: only tested against the skin (links.distance_from_build)
        self.drift = ti.ndarray(ti.f32, n)  # the skin used before the last build since each list was made [m]
        self.drift.fill(0.0)
        self.x_free = ti.ndarray(vec3.get(), n)
        self.v_free = ti.ndarray(vec3.get(), n)
        self.calm = ti.ndarray(float, n)  # least rest timer of each ball and the balls it touches [s]
        self.clear = ti.ndarray(ti.f32, n)  # least gap of each ball to the planes [m] (collide.surface_clearance)
        self.upper = self.impulse = None
        # ball i's upper list's length, first[i + 1] − first[i], and its pairs' entries in the pair tables
        # from first[i] on (links.pair_starts); and the layout of the stashed pairs during a rebuild
        self.first, self.stash_first = ti.ndarray(ti.i32, n + 1), ti.ndarray(ti.i32, n + 1)
        self.first.fill(0)
        self.pair_chunk = ti.ndarray(ti.i32, sort.scan_chunks(n))
        self.pair_capacity = 1
        self.lam = ti.ndarray(ti.f32, self.pair_capacity)
        # ball i's lower list: lower[lower_first[i] : lower_first[i + 1]], as long as the pair tables (links.link_lower)
        self.lower, self.lower_first = ti.ndarray(ti.i32, self.pair_capacity), ti.ndarray(ti.i32, n + 1)
        self.lower_first.fill(0)
        self.impact = ti.ndarray(ti.i32, n)  # each ball's first impact in a sweep (pairs.impact_keys)
        # resting impulses per unit mass [m/s] of the planes and (one column more) the terrain, in f32, and
        # (Gauss–Seidel) friction impulses, in a row per ball within reach of one (surfaces.list_surfaces),
        # and the tables a rebuild carries them into (surface_rows.list_surface_rows)
        self.surface_start = ti.ndarray(ti.i32, n + 1)
        self.surface_start.fill(0)
        self.surface_impulse, self.surface_impulse_back = surface_table(1, surface_columns(model)), None
        self.flag = ti.ndarray(ti.i32, 2)
        self.apart_ids = ti.ndarray(ti.i32, apart.APART_MAX + 1)  # the balls listed apart (apart.apart_balls), count
        # where the threads of the build's reductions meet: the cells' bounds and the squared speeds' bits
        self.bounds, self.top_speeds = ti.ndarray(ti.i32, 6), ti.ndarray(ti.i64, 2)
        self.n_apart = 0
        # the loop iterations after which a thread stops its loops without a word (grid.LOOP_CAP)
        self.loop_cap = grid.LOOP_CAP if ensure_init().arch == "vulkan" else None
        self.skip_still = self.gauss_seidel
        # each pair's friction impulse, carried from step to step and over rebuilds (Gauss–Seidel only: a
        # rebuild stashes it beside the resting impulse, links.stash)
        self.friction = ti.ndarray(vec3f, 1)
        if self.relists:
            self.surface_impulse = every_ball_a_row(self.surface_start, model)
        self.far_owners = 0
        self.amendable = False
        self._no_stash = ti.ndarray(ti.f32, (1, 3))  # (the stash of a build that keeps no list: see _kept_lists)
        self._valid = False
        self._rebuild = True
        self.edited = True
        self._ids: ti.Ndarray | None = None  # the state's storage order at the last build (see pairs)
        self._hash: tuple[Any, ...] | None = (
            None  # the grid hash's (origin, stride) at the last build (grid.hash_strides)
        )
        self._last_grid: tuple[Any, ...] | None = None  # (a cache of last_grid())
        self._grid_struct: tuple[Any, Any] | None = None  # (the GridParams last made, by their values)

    @property
    def model(self) -> Model:
        """The model the solver was made for (its balls' radii, the planes, the terrain)."""
        return self._model

    @property
    def packs(self) -> Packs:
        """The kernels' argument packs of the solver's arrays (see :class:`~ti_golf.physics.packs.Packs`)."""
        return self._packs

    @property
    def lists_valid(self) -> bool:
        """Whether the neighbour lists were built for the balls' positions (a saved run keeps it)."""
        return self._valid

    @lists_valid.setter
    def lists_valid(self, valid: bool) -> None:
        self._valid = valid

    @property
    def rebuild_due(self) -> bool:
        """Whether the lists are to be built again before the next parallel step (a saved run keeps it)."""
        return self._rebuild

    @rebuild_due.setter
    def rebuild_due(self, due: bool) -> None:
        self._rebuild = due

    def record(self) -> SolverRecord:
        """What the next steps read, to continue bit for bit after :meth:`restore`: the record of
        :class:`.record.Recorded`, and the grid hash (``hash``)."""
        record = super().record()
        record.values["hash"] = None if self._hash is None else [[int(c) for c in v.to_list()] for v in self._hash]
        return record

    def restore(self, record: SolverRecord, state: State) -> None:
        """Take back what :meth:`record` returned, for ``state`` restored to the same moment (its
        storage order included): the next step is then the one that the recorded solver would
        have made. What the record lacks keeps the value this solver was made with."""
        super().restore(record, state)
        if "hash" in record.values:
            hashed = record.values["hash"]
            self._hash = None if hashed is None else tuple(ti.Vector(v, dt=ti.i32) for v in hashed)
        if record.rebuild:
            self._rebuild = True
        self._ids = state.ids
        self._packs = Packs()
        self._last_grid = None
        self.forget_quiet()  # (the record's calm times may come from code that kept none: see forget_quiet)

    def build(self, state: State) -> None:
        """Sort balls into the hash grid and rebuild every neighbour list in place (or keep the
        lists of the balls that did not move, :meth:`_may_amend`), carrying each pair's
        accumulated impulse over (the neighbour tables widen to the longest list when one
        overflows; the pair tables grow with the pairs listed in all): the old lists stashed, the
        cells sized (:meth:`_size_cells`), the balls listed (:meth:`_list_balls`), then the pair
        tables fitted and linked (:meth:`_link_pairs`)."""
        n = state.n
        self._last_grid = None
        if n >= REORDER_MIN_BALLS:  # 0.2 ms, against the build's tens of milliseconds
            release_freed_memory()  # before the tables: numpy copies freed since (balls set up, storage order)
        stashed = None
        mu = float(self._model.scene.contact.mu)
        if self._valid:  # the sweep's table is scratch between steps: it keeps the old lists' λ, ids and friction
            stashed = self.impulse
            links.stash(self.upper, self.first, self.lam, stashed, self.gauss_seidel, state.x, self.friction, mu)
            copy_ints(self.first, self.stash_first)
        amend = stashed is not None and self._may_amend()
        fast, v_max = self._size_cells(state)
        amend = amend and self.n_apart == 0
        self._ids = state.ids
        longest = self._list_balls(state, fast, int(amend), self._kept_lists(state, stashed if amend else None))
        check_loop_cap(self.loop_cap, self.cell, self._model, state, int(longest[2]))
        if n << self.slot_bits > 2**31:  # the largest slot, (n − 1)·2^bits + 2^bits − 1, must fit an i32
            raise SimulationError(
                f"{n} balls with up to {self.capacity} neighbours each are more than the "
                f"neighbour lists can address (n × 2^{self.slot_bits} must not exceed 2^31)"
            )
        pairs = int(links.pair_starts(self.first, self.pair_chunk))
        if self.relists:  # the kernel rebuilds the lists in place: room for every list to grow to n − 1
            self._fit_pair_tables(state, n * self.capacity, 0)  # (and the stash, links.relist_all_pairs)
        else:
            self._fit_pair_tables(state, pairs, PAIR_ROOM)
        self._link_pairs(state, stashed, mu)
        self._carry_pair_order(stashed)  # (while the stash is kept)
        carried = stashed is not None
        stashed = None
        if not self.relists:  # (relisting in the kernel: a row for every ball, see surface_rows.every_ball_a_row)
            self._list_surface_rows(state, carried, v_max)
        self._fit_sweep_table()
        self.forget_quiet()
        self.amendable = True
        self.rebuilds += 1
        if n >= REORDER_MIN_BALLS and self.rebuilds % COLLECT_EVERY == 0:
            free_dropped_arrays()  # (the cycles that Taichi's launches leave: see COLLECT_EVERY)
        self._valid = True

    def make_room_to_relist(self, state: State) -> None:
        """Make the tables of a solver that ``relists`` in its kernel, empty, for the balls of
        ``state``, and ask the kernel for lists: its next launch lists every pair first
        (``links.relist_all_pairs``), as a build through the grid would, bit for bit."""
        self._last_grid = None
        self._ids = state.ids
        self._size_cells(state)  # (the grid a build would size, kept as a saved run keeps it: see record)
        self._new_neighbour_table(state)
        self.first.fill(0)  # (nothing to carry over)
        self._fit_pair_tables(state, state.n * self.capacity, 0)
        self._fit_sweep_table()
        self.flag.from_numpy(np.array([1, 0], dtype=np.int32))
        self._valid = True

    def _fit_sweep_table(self) -> None:
        """Make the sweeps' table (each pair's inverse distance, gap or projection, and, for Jacobi,
        its impulse in a sweep: ``pairs.owned_pairs``) as long as the pair tables, the old one
        freed first."""
        if self.impulse is None or self.impulse.shape[0] != self.lam.shape[0]:
            dropped = watch(self.impulse)
            self.impulse = None  # free the old table (the stash) before allocating
            free_dropped_arrays(dropped)
            shape = (self.lam.shape[0], pair_columns(self.gauss_seidel))
            self.impulse = ti.ndarray(pair_table_type(self.gauss_seidel), shape)

    def _new_neighbour_table(self, state: State) -> None:
        """Make the neighbour table ``capacity`` wide when it is not, the old one freed first."""
        if self.upper is None or self.upper.shape[1] != self.capacity:
            self._packs.clear()  # (their references would keep the narrower table in memory)
            dropped = watch(self.upper)
            self.upper = None
            free_dropped_arrays(dropped)
            self.upper = ti.ndarray(ti.i32, (state.n, self.capacity))

    def _size_cells(self, state: State) -> tuple[bool, float]:
        """Size the grid's cells and hash for a build (``grid.cell_size``, ``grid.hash_strides``),
        the balls much faster or bigger than the rest set apart first (``apart.apart_balls``), and
        with :attr:`reorder` store the balls in the grid's order. Returns (whether pairs are listed
        by their closing speed too, the fastest ball's speed [m/s])."""
        h = self._model.dt
        folded = sort.fold_in_array()
        set_apart = (self.v_cut, self.r_cut, self.apart_ids, self.top_speeds, folded)
        v_max, v_rest, n_apart = (float(s) for s in apart.apart_balls(state.v, self._model.radius, *set_apart))
        self.n_apart = int(n_apart) if n_apart <= apart.APART_MAX else 0  # a few own no pair with the others
        scan_apart = self.n_apart > 0 and on_cpu()  # and are listed apart (see apart.APART_MAX)
        # the cells hold every pair of the other balls; fast: their pairs are listed by closing speed too
        if scan_apart:
            self.cell, fast = grid.cell_size(self.r_ref, self.skin, h, v_rest)
        else:
            self.cell, fast = grid.cell_size(self.r_max, self.skin, h, v_max)
        bounds = grid.cell_bounds(state.x, 1.0 / self.cell, self.bounds, folded)
        strides = grid.hash_strides(bounds, self.mask + 1)
        if self._hash is None or [v.to_list() for v in self._hash] != [list(v) for v in strides]:
            self._hash = tuple(ti.Vector(v, dt=ti.i32) for v in strides)  # (kept while it holds: see _grid_params)
        if self.reorder:
            grid_order = (1.0 / self.cell, self.mask, *self._hash, self.rank, self.start, self.chunk_start)
            self.v_free, self.calm, self.rank = store_in_grid_order(
                state, self._model, (*grid_order, self.sorted_ids), [self.v_free, self.calm, self.rank]
            )
            if scan_apart:  # their new indices (from the arrays in the new order, not the old ones)
                apart.apart_balls(state.v, self._model.radius, *set_apart)
        return fast, v_max

    def _may_amend(self) -> bool:
        """Whether the next build may keep the lists of balls that did not move (``grid.list_neighbours``):
        Gauss–Seidel sweeps built through the grid, no ball set apart at the last build, no edit since."""
        return self.amendable and self.gauss_seidel and not self.relists and self.n_apart == 0

    def _kept_lists(self, state: State, stashed: Any) -> Any:
        """The :data:`~ti_golf.physics.types.KeptLists` of a build: with the old lists'
        ``stashed`` table, each ball marked to keep its list or not (``stale.mark_kept``); without
        (``None``: every ball listed anew), placeholders."""
        table = self._no_stash if stashed is None else stashed
        kept = self._packs.get(
            KeptLists, marks=self.x_free, new_index=self.impact, stashed=table, stash_first=self.stash_first
        )
        if stashed is not None:
            marks = (self.skin, self._model.dt, self.sorted_ids, self.reorder, kept)
            stale.mark_kept(state.x, state.v, self._packs.lists(self), *marks)
        return kept

    def _list_balls(self, state: State, fast: bool, amend: int, kept: Any) -> Any:
        """List every ball's neighbours (``grid.list_neighbours``; ``fast``: see
        :meth:`_size_cells`; ``amend``, ``kept``: the balls that keep their lists, see
        :meth:`_kept_lists`), the neighbour table widened to the longest list and the balls listed
        again while one overflows it. Returns what ``grid.list_neighbours`` returns."""
        while True:
            self._new_neighbour_table(state)
            params, scratch = self._grid_params(fast), self._grid_scratch()
            with plain_compile(vulkan=True):  # (see runtime.plain_compile)
                longest = grid.list_neighbours(
                    params,
                    state.x,
                    state.v,
                    self._model.radius,
                    self.apart_ids,
                    amend,
                    kept,
                    scratch=scratch,
                    lists=self._packs.lists(self),  # (not kept: a wider table frees this one's first)
                    longest=self.flag,
                    stored_sorted=self.reorder,
                )
            if longest[0] <= self.capacity:
                return longest
            # widen to the longest list found (no power-of-two padding: memory follows the pile)
            wider = int(longest[0])
            self._check_table_memory(state, wider, self.pair_capacity)
            self.capacity = wider

    def _link_pairs(self, state: State, stashed: Any, mu: float) -> None:
        """Link the lower lists to the pairs (``links.link_lower``) and, from the old lists'
        ``stashed`` table (``None`` at a first build), carry each pair's accumulated impulses over
        (``links.link_and_carry``; after a reorder, ``sorted_ids`` still maps each ball to its index
        in the stashed lists); without a stash, every pair starts from zero."""
        if stashed is not None:
            links.link_and_carry(
                self.upper,
                self.first,
                self.lower,
                self.lower_first,
                self.impact,
                chunk=self.pair_chunk,
                stashed=stashed,
                stash_first=self.stash_first,
                lam=self.lam,
                moved=self.reorder,
                old_id=self.sorted_ids,
                with_friction=self.gauss_seidel,
                x=state.x,
                friction=self.friction,
                mu=mu,
            )
        else:
            links.link_lower(self.upper, self.first, self.lower, self.lower_first, self.impact, self.pair_chunk)
            self.lam.fill(0.0)
            if self.gauss_seidel:  # none yet
                zero_f32_vectors(self.friction)  # (not fill: see zero_f32_vectors)

    def _list_surface_rows(self, state: State, carry: bool, v_max: float) -> None:
        """Give a row of surface impulses to each ball that may touch a plane or the terrain before
        the next rebuild (:func:`.surface_rows.list_surface_rows`), in the second of two tables,
        then swap them: each ball that had a row keeps its impulses when ``carry``, the others
        start from zero."""
        rows, old = list_surface_rows(self, state, carry, v_max)
        columns = surface_columns(self._model)
        back = self.surface_impulse_back
        if not table_fits(back, rows, columns):
            self._packs.clear()  # (their references would keep the old table in memory)
            dropped = watch(back)
            self.surface_impulse_back = back = None
            free_dropped_arrays(dropped)
            back = table_for(rows, columns)
        surfaces.carry_surfaces(*old, self.surface_start, back)
        self.surface_impulse, self.surface_impulse_back = back, self.surface_impulse

    def _grid_params(self, fast: bool) -> Any:
        """The :data:`~ti_golf.physics.types.GridParams` of the grid as the last build made it (its
        cells, hash, skin, step and the balls set apart), ``fast`` when pairs are listed by their
        closing speed too (``grid.cell_size``)."""
        assert self._hash is not None, "the lists are built before the grid is read"
        scalars = (self.cell, self.mask, self.skin, self._model.dt, int(fast), self.v_cut, self.r_cut, self.n_apart)
        key = (scalars, *(tuple(v.to_list()) for v in self._hash))
        if self._grid_struct is not None and self._grid_struct[0] == key:
            return self._grid_struct[1]  # (kept: a struct costs more to make than a build's launch)
        params = GridParams(
            inv_cell=1.0 / self.cell,
            mask=self.mask,
            origin=self._hash[0],
            stride=self._hash[1],
            skin=self.skin,
            h=self._model.dt,
            fast=int(fast),
            v_cut=self.v_cut,
            r_cut=self.r_cut,
            n_apart=self.n_apart,
            scan_apart=int(self.n_apart > 0 and on_cpu()),
        )
        self._grid_struct = (key, params)
        return params

    def _grid_scratch(self) -> Any:
        """The grid's :data:`~ti_golf.physics.types.GridScratch`: its buckets' starts and the balls
        sorted by bucket, which the last build left and the steps read until the next."""
        return self._packs.get(
            GridScratch, rank=self.rank, start=self.start, chunk_start=self.chunk_start, sorted_ids=self.sorted_ids
        )

    def last_grid(self) -> tuple:
        """The grid of the last build as ``stale.lists_stale`` reads it, after the step it builds
        the lists for: its :data:`~ti_golf.physics.types.GridParams` and
        :data:`~ti_golf.physics.types.GridScratch`, the balls it set apart and whether the balls
        are stored in its order (``stored_sorted`` of ``grid.list_neighbours``). Made from what the
        build kept, and so also for a solver restored from a saved run."""
        if self._last_grid is None:
            self._last_grid = (self._grid_params(False), self._grid_scratch(), self.apart_ids, self.reorder)
        return self._last_grid

    def _fit_pair_tables(self, state: State, pairs: int, room: int) -> None:
        """Make room for ``pairs`` pairs in the tables of the pairs' resting impulses, lower-list links
        and (Gauss–Seidel) friction impulses: when they hold fewer, new tables, the old ones freed first (their values
        are in the stash): for ``pairs`` at the first build, and when they outgrew tables built
        before, for ``pairs`` plus 1/``room`` of them (none with ``room`` 0)."""
        grow = pairs > self.pair_capacity
        if grow:
            capacity = max(1, pairs + (pairs // room if room and self.rebuilds > 0 else 0))
            self._check_table_memory(state, self.capacity, capacity)
            self.pair_capacity = capacity
        rows = self._friction_rows()
        new_friction = self.friction is None or self.friction.shape[0] != rows  # (the first build, or grown)
        if grow or new_friction:
            self._packs.clear()  # (their references would keep the old tables in memory)
            dropped = watch(*((self.lam, self.lower) if grow else ()), *((self.friction,) if new_friction else ()))
            if grow:
                self.lam = self.lower = None
            if new_friction:
                self.friction = None
            free_dropped_arrays(dropped)
            if grow:
                self.lam = ti.ndarray(ti.f32, self.pair_capacity)
                self.lower = ti.ndarray(ti.i32, self.pair_capacity)
            if new_friction:
                self.friction = ti.ndarray(vec3f, rows)

    def _check_table_memory(self, state: State, width: int, pairs: int) -> None:
        """Raise :class:`SimulationError` before a neighbour table ``width`` wide and pair tables of
        ``pairs`` entries take more than half the memory available (:func:`available_memory`),
        naming the ball that reaches farthest within a step (r + h·|v|): the neighbour table is as
        wide as the longest list, so many balls shot fast into a pile (3,100 balls within the reach
        of one ball at 1,000 m/s in a pile of 20,000, in one 1 ms step) would make the tables take
        gigabytes, and then swap or be killed, losing the run."""
        need = table_bytes(state.n, width, pairs, self.gauss_seidel)
        avail = available_memory()
        if avail is None or need <= 0.5 * avail:
            return
        ball, farthest = farthest_reaching(self._model, state)
        raise SimulationError(
            f"the neighbour lists would take {byte_size(need)}, more than half the {byte_size(avail)} of memory "
            f"available: {pairs:,} pairs within reach of one step, and a ball with {width:,}, the neighbour table "
            f"as wide as the longest list. {farthest}; lower world.dt, or that ball's speed or radius",
            [ball],
        )

    @property
    def slot_bits(self) -> int:
        """Low bits of a lower-list entry that hold the pair's column in its owner's upper list (the
        owner's id is in the bits above; see ``links.slot_bits``)."""
        return max(0, int(self.capacity - 1).bit_length())

    def pairs(self) -> np.ndarray:
        """The listed neighbour pairs (i, j), i < j, by ball id, each once, sorted: int array (n_pairs, 2)."""
        upper, count = self.upper.to_numpy(), np.diff(self.first.to_numpy())
        listed = np.arange(upper.shape[1])[None, :] < count[:, None]
        i = np.broadcast_to(np.arange(len(count))[:, None], upper.shape)
        pairs = np.stack([i[listed], upper[listed]], axis=1)
        if self._ids is not None:  # storage indices to ball ids
            pairs = self._ids.to_numpy()[pairs]
        pairs = np.sort(pairs, axis=1)  # (owner, other) to (lower id, higher id)
        return pairs[np.lexsort((pairs[:, 1], pairs[:, 0]))]

    def _pairs_laid_out(self, model: Model) -> bool:
        """Whether the sweeps take the pairs in a layout of their own (not ball by ball), which the
        serial steps would not follow: the Gauss–Seidel sweeps by contact colours."""
        return False

    @classmethod
    def sweeps_by_blocks(cls, scene: Scene, relists: bool) -> bool:
        """Whether a solver of this kind for ``scene``, relisting in the serial kernel (``relists``:
        `.stepping.relists_in_kernel`) or not, sweeps the balls by blocks of grid columns (the
        Gauss–Seidel sweeps' column layout), whose order its record keeps (``col_ids``,
        ``col_colour``, ``col_start``, ``col_chunk``)."""
        return False

    def _carry_pair_order(self, stashed: Any) -> None:
        """Carry over a rebuild what orders the pairs in the sweeps, from the old lists' ``stashed``
        table (``None`` at a first build): nothing, unless the sweeps order the pairs themselves."""

    def _friction_rows(self) -> int:
        """Rows of the pairs' friction impulses: one placeholder, unless the sweeps carry them."""
        return 1
