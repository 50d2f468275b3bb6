"""How a collision solver steps its balls (:class:`Stepping`): serially, many steps in one launch
of ``collide.collision_step`` (which rebuilds the lists itself, or stops for a build through the
grid), or a parallel launch a step with its kind's sweeps
(:meth:`Stepping._sweep`), and when it builds its neighbour lists again: before the first step,
when a step or the caller asks for it (balls moved, the model retuned)."""

from __future__ import annotations

from typing import Any

import numpy as np

from ti_golf.one_thread import in_one_thread
from ti_golf.physics.kernels import int_at
from ti_golf.physics.model import Model
from ti_golf.physics.packs import Packs
from ti_golf.physics.state import State
from ti_golf.runtime import on_cpu, plain_compile
from ti_golf.signals import whole_steps
from ti_golf.solvers import apart, collide, grid
from ti_golf.solvers.surface_rows import every_ball_a_row, surface_columns

SERIAL_MAX_BALLS = 4096
"""Up to this many balls (on the CPU), steps run one ball after another, many in one kernel launch
(``serial`` in ``collide.collision_step``): for so few balls a parallel step is mostly launch and
thread-pool overhead (see the docs' performance page, "Design measurements")."""

MOVED_PAIRS_MAX = 200_000
"""Most pairs of balls that moved far with every other ball that :meth:`Stepping.pairs_that_may_overlap`
takes (measured in numpy at a fraction of a microsecond each) before it builds the lists instead."""

RELIST_MAX_BALLS = 512
"""Up to this many balls, the serial launch also rebuilds the lists itself, by testing every pair
in tables n − 1 wide (time and memory that grow as n²); beyond, it stops when the lists must be
rebuilt, and they are built through the grid between launches (:attr:`Stepping.relists`)."""


def relists_in_kernel(n: int, serial: bool) -> bool:
    """Whether a solver of ``n`` balls that steps ``serial`` or not rebuilds its lists in the
    serial kernel (``RELIST_MAX_BALLS``) and sweeps its balls in storage order."""
    return serial and n <= RELIST_MAX_BALLS


def steps_serially(n: int) -> bool:
    """Whether a collision solver steps ``n`` balls serially by default: few balls, on the CPU (a
    GPU would run the serial loop on one slow thread)."""
    return n <= SERIAL_MAX_BALLS and on_cpu()


class Stepping:
    """The steps of a collision solver (:class:`.solver.CollisionSolver`, which builds the lists
    and holds the arrays named below) and the schedule of its list builds."""

    _model: Model
    serial: bool
    relists: bool
    capacity: int
    rebuilds: int
    still_steps: int
    skip_still: bool
    lists_valid: bool
    rebuild_due: bool
    edited: bool
    amendable: bool
    drift: Any
    r_ref: float
    skin: float
    h: float
    v_cut: float
    r_cut: float
    flag: Any
    calm: Any
    upper: Any
    x_at_build: Any
    x_free: Any
    surface_start: Any
    surface_impulse: Any
    surface_impulse_back: Any

    @property
    def packs(self) -> Packs:
        """The kernels' argument packs of the solver's arrays (the solver's own)."""
        raise NotImplementedError

    def build(self, state: State) -> None:
        """Build the neighbour lists for the balls of ``state`` (the solver's own)."""
        raise NotImplementedError

    def make_room_to_relist(self, state: State) -> None:
        """Make the tables for the balls of ``state`` and ask the relisting kernel for lists (the
        solver's own)."""
        raise NotImplementedError

    @property
    def lists_due(self) -> bool:
        """Whether the lists are to be built before the next step: none built yet, balls moved between
        steps (:meth:`invalidate`), or the last step asked for it (the serial kernel's flag, or
        ``rebuild_due``)."""
        return not self.lists_valid or (int_at(self.flag, 0) != 0 if self.serial else self.rebuild_due)

    def ensure_lists(self, state: State) -> None:
        """Build the neighbour lists for the current positions unless they still hold every pair in
        reach: before the first step, after balls were moved (:meth:`invalidate`), or when the last
        step asked for a rebuild. The next step then starts from these lists, as it would have
        built them itself (same lists, same step)."""
        if not self.lists_due:
            return
        if self.relists:
            self.capacity = max(self.capacity, state.n - 1, 1)
        if self.relists and (not self.lists_valid or self.upper.shape[1] >= self.capacity):
            self.relist(state)
        else:  # (through the grid; also to carry lists into wider tables)
            with in_one_thread(self.serial):  # (a serial solver's balls are few: see one_thread)
                self.build(state)
                grid.clear(self.flag)  # build() left the longest lists there
        self.rebuild_due = self.edited = False

    def relist(self, state: State) -> None:
        """Rebuild the lists of a solver that ``relists`` in its kernel, in a launch of no steps
        (the tables made first when none were built: :meth:`make_room_to_relist`): the lists of a
        build through the grid, bit for bit, without launching the grid's kernels."""
        if not self.lists_valid:
            with in_one_thread():  # (see one_thread)
                self.make_room_to_relist(state)
        else:
            self.flag.from_numpy(np.array([1, 0], dtype=np.int32))  # the kernel's request
        self._launch_relisting(self._model, state, 0)

    def _launch_relisting(self, model: Model, state: State, steps: int) -> None:
        """One serial launch of ``steps`` steps that rebuilds the lists itself (``relists``)."""
        with plain_compile():  # see runtime.plain_compile
            self.rebuilds += collide.launch(
                self._arguments(model, state, steps),
                serial=collide.SERIAL_RELISTS,
                warm=True,
                sweeps=model.scene.contact.iterations - 1,
                last=True,
            )

    def pairs(self) -> np.ndarray:
        """The listed pairs by ball id (the solver's own)."""
        raise NotImplementedError

    def pairs_that_may_overlap(self, state: State) -> np.ndarray:
        """Every pair of balls that may overlap now, by ball id (i < j; int array of shape (pairs, 2)):
        the listed pairs (:meth:`pairs`), then, without a build, the pairs a build could add that may
        overlap: each ball that moved far since the build with every other ball (a pair may so come
        twice). A pair the build left out had a surface gap of at least the skin, less its balls'
        ``drift`` (counted in their shifts below); since, the gap shrank
        by at most |Δx_a − Δx_b| ≤ |Δx_a − c| + |Δx_b − c| for any c, the balls' displacements Δx
        taken here relative to their median c (balls that fall together close no gap). So only a pair
        whose two shifts sum to more than the skin can be missing: a pair of a ball whose shift and the
        largest other shift do. The lists are built first (:meth:`ensure_lists`) when they do not
        stand for the balls (never built, balls moved or the model retuned between steps:
        :meth:`invalidate`), or when those pairs would be more than ``MOVED_PAIRS_MAX``."""
        moved = self._moved_far(state) if self.lists_due else np.zeros(0, np.int64)
        if moved is None or moved.size * state.n > MOVED_PAIRS_MAX:
            self.ensure_lists(state)
            moved = np.zeros(0, np.int64)
        pairs = self.pairs()
        if moved.size:
            ids = state.order  # (storage index to ball id; None: the same)
            far = moved if ids is None else ids[moved]
            others = np.arange(state.n)
            lo, hi = np.minimum(far[:, None], others).ravel(), np.maximum(far[:, None], others).ravel()
            pairs = np.concatenate([pairs, np.stack([lo, hi], axis=1)[lo != hi]])
        return pairs

    def _moved_far(self, state: State) -> np.ndarray | None:
        """The storage indices of the balls that may have closed a gap the last build left out (see
        :meth:`pairs_that_may_overlap`), or None when the lists do not stand for the balls."""
        if not self.lists_valid or self.edited or state.n < 2:
            return None
        x_build = self.x_at_build.to_numpy()  # (f32)
        moved = np.subtract(state.x.to_numpy(), x_build, dtype=np.float64)
        moved -= np.median(moved, axis=0)
        # as links.distance_from_build: the f32 position's rounding, at most |x|·2^-24, counted twice
        shift = np.linalg.norm(moved, axis=1) + np.linalg.norm(x_build, axis=1) * 2.0**-23
        shift += self.drift.to_numpy()  # (the skin used before the build: see stale.skin_owed)
        first, second = np.partition(shift, -2)[-2:][::-1]
        largest_other = np.where(shift == first, second, first)
        return np.flatnonzero(shift + largest_other > self.skin)

    def retune(self, model: Model) -> None:
        """Take the model's parameters as changed between steps (``Model.set_parameters``): a new
        skin (``contact.skin``) or time step changes which pairs the lists must hold, so they are
        rebuilt before the next step (each pair that stays listed keeps its impulse); a new number of
        planes (``world.ground``) starts every ball's plane impulses again from zero, and the lists are
        rebuilt (they list the balls within reach of a plane). The kind of solver (``contact.solver``)
        is fixed: a change of it needs a new solver."""
        skin = model.scene.contact.skin * self.r_ref
        if (skin, model.dt) != (self.skin, self.h):
            self.skin, self.h = skin, model.dt
            self.v_cut = apart.fast_speed(self.r_ref, self.skin, model.dt)
            self.invalidate()
        if self.surface_impulse.shape[1] != surface_columns(model):
            if self.relists:
                self.surface_impulse, self.surface_impulse_back = every_ball_a_row(self.surface_start, model), None
            else:
                self.invalidate()  # (the build makes the tables for the new planes)

    def invalidate(self) -> None:
        """Rebuild the neighbour lists before the next step (balls were moved between steps), each
        pair that stays listed keeping its accumulated impulse."""
        self.rebuild_due = self.edited = True
        self.amendable = False  # (the next build lists every ball anew: the skin or the balls may have changed)
        self.flag.from_numpy(np.array([1, 0], dtype=np.int32))  # the serial kernel's request

    def forget_quiet(self) -> None:
        """Forget which balls were quiet at the last step (``calm``, see ``pairs.still_quiet``), so
        that the next step asks each ball asleep of its neighbours: after a build of the lists (new
        neighbours; a reorder also leaves other balls' values in ``calm``; the serial kernel forgets
        them itself when it relists, as after :meth:`invalidate`), after a restore, and whenever the
        balls' statuses or rest timers are edited between steps (``Simulation.set_ball``, waking balls).
        Always safe: a ball asked comes out quiet or not as the step would have found it."""
        self.calm.fill(0.0)

    def advance(self, model: Model, state: State, steps: int) -> None:
        """Advance all balls by ``steps`` steps of ``model.dt``: serially, many in one launch, or one
        parallel launch per step (see ``serial``); Ctrl-C and SIGTERM wait for whole steps
        (:func:`~ti_golf.signals.whole_steps`)."""
        with whole_steps() as came:  # (the handlers set once, not at every step)
            if self.serial:
                if self.relists:
                    self._advance_serially(model, state, int(steps))
                else:
                    self._advance_serially_between_builds(model, state, int(steps), came)
                self.rebuild_due = bool(int_at(self.flag, 0))  # (the serial kernels' request, for a saved run)
            else:
                awake: bool | None = None  # whether a ball is awake and in play: asked of the balls at first
                for k in range(int(steps)):
                    taken, awake = self._step_in_parallel(model, state, awake)
                    if not taken:  # skipped: so would every step after it be
                        self._skip_still_steps(model, state, int(steps) - k - 1)
                        break
                    if came:  # Ctrl-C or SIGTERM: stop after this whole step
                        break
        if steps > 0:  # every kind of step builds the lists first when balls were edited (invalidate)
            self.edited = False

    def _advance_serially(self, model: Model, state: State, steps: int) -> None:
        """``steps`` steps in one serial launch that rebuilds the lists itself (``relists``)."""
        width = max(1, state.n - 1)
        if not self.lists_valid or self.upper.shape[1] < width:  # first step, or lists built narrower since
            self.capacity = width
            with in_one_thread():  # (see one_thread)
                if not self.lists_valid:  # the launch lists the balls (nothing to carry over)
                    self.make_room_to_relist(state)
                else:  # (lists to carry over into wider tables)
                    self.build(state)
                    grid.clear(self.flag)  # build() left the longest lists there; from now on the kernel rebuilds
        self._launch_relisting(model, state, steps)
        state.advance_clock(model.dt, steps)

    def _advance_serially_between_builds(self, model: Model, state: State, steps: int, came: list[int]) -> None:
        """``steps`` steps in serial launches, each until a step asks for new lists, which are built
        through the grid between them (:meth:`ensure_lists`), or until no ball is awake and in
        play, when the steps left are skipped as the parallel steps skip them (``skip_still``);
        Ctrl-C or SIGTERM (``came``) stops at the end of a launch."""
        while steps > 0:
            self.ensure_lists(state)
            with in_one_thread():  # (see one_thread)
                still = self.skip_still and self._all_still(state)
            if still:  # as the parallel steps are skipped
                self._skip_still_steps(model, state, steps)
                return
            with plain_compile():  # see runtime.plain_compile
                taken = self._serial_steps(model.scene.contact.iterations, self._arguments(model, state, steps))
            state.advance_clock(model.dt, taken)
            steps -= taken
            if came:
                break

    def _step_in_parallel(self, model: Model, state: State, awake: bool | None) -> tuple[bool, bool | None]:
        """One parallel step, the lists built first when due; or, with ``skip_still`` and no ball
        awake and in play, the time advanced alone (the step would change nothing). ``awake``:
        whether some ball is, as the step before reported it (``None``: not known, so the balls
        are asked). Returns whether the step was taken, and whether some ball is awake after it
        (``None`` when the kind of sweeps does not say)."""
        if not self.lists_valid or self.rebuild_due:
            self.build(state)
        elif self.skip_still and (not awake if awake is not None else self._all_still(state)):
            self._skip_still_steps(model, state, 1)
            return False, False
        rebuild, awake = self._sweep(model.scene.contact.iterations, self._arguments(model, state, 1))
        state.x, self.x_free = self.x_free, state.x  # the kernel left the new positions in x_free
        state.advance_clock(model.dt, 1)
        self.rebuild_due = rebuild
        return True, awake

    def _skip_still_steps(self, model: Model, state: State, steps: int) -> None:
        """Skip ``steps`` steps in which no ball is awake and in play (``skip_still``): none would
        change anything, so neither would the next, and only the time advances (counted in
        ``still_steps``)."""
        self.still_steps += steps
        state.advance_clock(model.dt, steps)

    def _all_still(self, state: State) -> bool:
        """Whether no ball is awake and in play, so that a step would change nothing (only the
        kinds whose sweeps leave such a step unchanged say so)."""
        return False

    def _sweep(self, iterations: int, arguments: tuple) -> tuple[bool, bool | None]:
        """One parallel step's launches, from the free flight to the new positions in ``x_free``,
        with ``iterations`` sweeps; ``arguments``: :meth:`_arguments`. Returns whether the lists
        must be rebuilt before the next step, and whether some ball is awake and in play after
        it (``None`` from a kind that does not say: :meth:`_all_still` is then asked)."""
        raise NotImplementedError

    def _serial_steps(self, iterations: int, arguments: tuple) -> int:
        """Serial steps with ``iterations`` sweeps each, in one launch, until one asks for new lists
        (``arguments``: :meth:`_arguments`, with the steps to take at most). Returns the steps
        taken. These: ``collide.collision_step``'s, the same step as its parallel launch (the
        Gauss–Seidel kind's own also stop when no ball is awake and in play, with ``skip_still``)."""
        return collide.launch(arguments, serial=collide.SERIAL_STOPS, warm=True, sweeps=iterations - 1, last=True)

    def _arguments(self, m: Model, s: State, steps: int) -> tuple:
        """The arguments of ``collide.collision_step`` before ``serial``: the array of the air,
        contact, terrain and step parameters, the launch's start time [s], the time step [s] and
        the steps to take, the kinds (:class:`~ti_golf.physics.kinds.Kinds`), the model, the lists, the state, the flight record and
        the scratch."""
        packs = self.packs
        return (
            packs.step_scalars(m, self.skin, self.v_cut, self.r_cut),
            s.t,
            m.dt,
            steps,
            m.kinds,
            packs.model(m),
            packs.lists(self),
            packs.state(s),
            packs.flight(s),
            packs.scratch(self),
        )
