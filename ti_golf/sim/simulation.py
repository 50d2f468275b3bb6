"""The :class:`Simulation` facade: build from a scene, step, inspect, modify, continue.

Like the report's WoP object: set initial conditions, simulate, read ``x``/``v``/``w``, change
them and simulate again.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np
import taichi as ti

from ti_golf.errors import SimulationError
from ti_golf.physics import kernels
from ti_golf.physics.model import Model
from ti_golf.physics.packs import Packs
from ti_golf.physics.state import State
from ti_golf.runtime import ensure_init, np_float
from ti_golf.scene.balls import build_balls
from ti_golf.scene.document import check_values, with_changes
from ti_golf.scene.loader import load_scene
from ti_golf.scene.schema import AT_REST, FLYING, OUT_OF_BOUNDS, STATUS_NAMES, Scene
from ti_golf.scene.terrain import Terrain
from ti_golf.signals import whole_steps
from ti_golf.sim.changes import (
    _UNSET,
    MOVES_T0_BALLS,
    as_changes,
    at_t0,
    refuse_after_t0,
    refuse_for_given_balls,
    refuse_unread,
    wakes,
)
from ti_golf.sim.flight_record import launch_again
from ti_golf.sim.given import (
    STEPS_PER_CALL,
    as_vectors,
    check_memory,
    copied,
    flags,
    given_balls,
    per_ball,
    steps_to_run,
    whole_number,
)
from ti_golf.sim.results import Flight, Overlap, Recording
from ti_golf.sim.step_check import check_changed_step, check_step


class RunProgress(Protocol):
    """What :meth:`Simulation.run` calls between chunks: ``progress(t_done, t_total)`` [s], and for a
    run with ``until`` also ``finished=(k, n, what)``: k of the n balls are ``what`` (at rest or out
    of bounds, landed). A callable of two arguments alone fails on a run with ``until``."""

    def __call__(self, done: float, total: float, /, finished: tuple[int, int, str] | None = None) -> None:
        """Say that ``done`` of ``total`` simulated seconds are done (and ``finished``: see the class)."""


def _per_ball(name: str, doc: str) -> Any:
    """The property of :class:`Simulation`'s per-ball vectors ``name`` (x, v or w)."""
    return property(lambda self: self._vectors(name), lambda self, a: self._assign(name, a), doc=doc)


@dataclass(frozen=True)
class InitialBalls:
    """The balls at t0 as given to :class:`Simulation`: ``x``, ``v``, ``w`` (N, 3) or ``None``
    (``x`` ``None``: the scene's balls), ``radius`` and ``mass`` (a scalar, (N,), or ``None``: the
    scene's ball), ``track`` (a bool or (N,)). Copies, so that later edits of the arrays passed
    in do not change them."""

    x: np.ndarray | None
    v: np.ndarray | None
    w: np.ndarray | None
    radius: float | np.ndarray | None
    mass: float | np.ndarray | None
    track: bool | np.ndarray

    @classmethod
    def copy_of(cls, x: Any, v: Any, w: Any, radius: Any, mass: Any, track: Any) -> "InitialBalls":
        """The balls as given, each array copied (``None`` kept), so that later changes leave them."""
        return cls(copied(x), copied(v), copied(w), copied(radius), copied(mass), copied(track))


class Simulation:
    """Many balls under the scene's air, gravity and ground, advanced by data-parallel kernels.

    Args:
        scene: a validated :class:`~ti_golf.scene.schema.Scene`, or a scene file's path or a
            bundled scene's name (loaded with :func:`~ti_golf.scene.loader.load_scene`).
        x: initial positions [m], (N, 3). Default: the balls the scene makes (its ``[launch]``,
            ``[[balls]]`` and ``[[blocks]]``), with their velocities and spins.
        v: initial velocities [m/s], (N, 3), with ``x`` only (default: at rest).
        w: initial spins (angular velocities) [rad/s], (N, 3), with ``x`` only (default: none).
        radius: per-ball radius [m], a scalar or (N,). Default: the scene's ball.
        mass: per-ball mass [kg], a scalar or (N,). Default: the scene's ball.
        track: which balls get landing detection (carry, apex ...), a bool or (N,), with ``x``
            only; default all. When no ball is tracked (a pile), no flight record is kept at all.
        keep_initial: keep a copy of the balls given (``x``, ``v``, ``w``, ``radius``, ``mass``) for
            :meth:`reset`; ``False`` saves their memory (24 bytes per ball and array in f64) for a
            big pile that is never reset, and :meth:`reset` is then refused.

    Between runs, read and assign ``x``, ``v`` and ``w`` (or :meth:`set_ball` for some balls),
    change scene keys with :meth:`set`, go back to t0 with :meth:`reset`, and :meth:`save` the run
    to continue it later with :meth:`load`.
    """

    def __init__(
        self,
        scene: Scene | str | os.PathLike[str],
        x: np.ndarray | None = None,
        v: np.ndarray | None = None,
        w: np.ndarray | None = None,
        radius: float | np.ndarray | None = None,
        mass: float | np.ndarray | None = None,
        track: bool | np.ndarray = True,
        *,
        keep_initial: bool = True,
    ) -> None:
        ensure_init()
        if isinstance(scene, (str, os.PathLike)):
            scene = load_scene(scene)
        if not isinstance(scene, Scene):
            raise TypeError(f"scene must be a Scene, a scene file's path or a bundled scene's name (got {scene!r:.60})")
        check_values(scene, "scene")  # (one changed in Python, by dataclasses.replace)
        if x is None:
            extra = [name for name, a in (("v", v), ("w", w)) if a is not None] + (
                ["track"] if track is not True else []
            )
            if extra:
                raise ValueError(f"{', '.join(extra)} given without x: the scene's balls come with their own")
        x, v, w = given_balls(scene, x, v, w, radius)
        given = x is not None or radius is not None or mass is not None
        self.initial = InitialBalls.copy_of(x, v, w, radius, mass, track) if given and keep_initial else None
        """The balls at t0 as given to the constructor (:meth:`reset` goes back to them), or ``None``
        when they are the scene's (and :meth:`reset` builds them again) or were not kept."""
        self.initial_kept = keep_initial or not given
        """Whether :meth:`reset` can go back to t0 (``False``: balls given with ``keep_initial=False``)."""
        self._set_up(scene, x, v, w, radius, mass, track)

    def _set_up(
        self,
        scene: Scene,
        x: np.ndarray | None,
        v: np.ndarray | None,
        w: np.ndarray | None,
        radius: float | np.ndarray | None,
        mass: float | np.ndarray | None,
        track: bool | np.ndarray,
        solver_flags: dict[str, bool] | None = None,
    ) -> None:
        """Build the model, the state at t0 and the collision solver (made with ``solver_flags``,
        ``serial`` and ``reorder``, when given) for ``scene`` and these balls (``x`` ``None``: the
        scene's)."""
        self.scene = scene
        if x is None:
            check_memory(scene)
            balls = build_balls(scene)
            x, v, w = balls.x, balls.v, balls.w
            radius = balls.radius if radius is None else radius
            mass = balls.mass if mass is None else mass
            track = balls.track
        x = as_vectors(x, "x")
        n = len(x)
        v = None if v is None else as_vectors(v, "v", n)  # None: at rest (no numpy zeros of a big pile)
        w = None if w is None else as_vectors(w, "w", n)
        radius = per_ball(scene.ball.radius if radius is None else radius, n, "radius")
        mass = per_ball(scene.ball.mass if mass is None else mass, n, "mass")
        check_step(scene, radius, mass, v, w)
        track = flags(track, n, "track")
        tracking = bool(np.any(track))  # else no flight record is kept (a pile: 96 bytes per ball less in f64)
        self.solver: CollisionSolver | None = None  # (the old one's arrays go before the new ones are made)
        """The CollisionSolver when balls can collide (several balls and ``world.collisions``)."""
        self.model = Model(scene, radius, mass, launch_height=x[:, 1] if tracking else np.zeros(1))
        self.state = State(n, tracking)
        self.state.reset(x, v, w, track)
        self.launch_x = x.copy() if tracking else None
        """Launch points [m], shape (N, 3): carry is measured from here; ``None`` when no ball is tracked."""
        self.launch_t = np.full(n, self.state.t) if tracking else None
        """Launch times [s], shape (N,): hang times are measured from here; ``None`` when no ball is tracked."""
        self._check_buf: Any = None  # a Taichi i32 array of 1, made on the first check
        self._packs = Packs()
        if n > 1 and scene.world.collisions:
            from ti_golf.solvers import CollisionSolver  # (imported when balls collide: a flight alone needs none)

            self.solver = CollisionSolver(self.model, **(solver_flags or {}))

    @classmethod
    def from_scene(
        cls, path: str | os.PathLike[str], overrides: Mapping[str, Any] | Iterable[str] | None = None, **kwargs: Any
    ) -> "Simulation":
        """Load a TOML scene (a path or a bundled scene's name) with ``overrides`` (as
        :func:`~ti_golf.scene.loader.load_scene` takes them) and build a simulation of it;
        ``kwargs`` go to :class:`Simulation` (``x``, ``v``, ``radius`` …, ``keep_initial``)."""
        return cls(load_scene(path, overrides), **kwargs)

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> "Simulation":
        """A simulation continued from a run saved by :meth:`save`: its scene (with every change
        made by :meth:`set`), the state at the time it was saved and the collision solver's lists
        and carried impulses, so that running on gives, bit for bit, what the saved simulation
        would have given (on the same backend and precision). :meth:`reset` goes back to the
        run's t0. Raises :class:`ConfigError` naming the file when it cannot be continued (a
        file written before runs could be resumed, another precision)."""
        from ti_golf.sim.saved_run import read_run, restore_run  # (imported when a run is read or saved)

        saved = read_run(path)
        sim = cls.__new__(cls)
        initial = saved.initial()
        sim.initial = None if initial is None else InitialBalls(**initial)
        sim.initial_kept = saved.initial_kept
        x, radius, mass, track = saved.balls()
        sim._set_up(saved.scene, x, None, None, radius, mass, track, solver_flags=saved.solver_flags)
        restore_run(saved, sim.state, sim.model, sim.solver)
        if saved.tracking and "launch_t" in saved.data:  # (runs saved before relaunches: all at t0)
            sim.launch_t = saved.data["launch_t"].astype(np.float64)
        return sim

    # -- changing the scene between runs ----------------------------------------------------------
    def set(self, changes: Mapping[str, Any] | Iterable[str] | str, value: Any = _UNSET) -> None:
        """Change scene keys between runs: ``set("air.C_D", 0.25)``, ``set({"contact.e": 0.5,
        "world.dt": 5e-4})`` or ``set(["air.wind=[-5,0,0]"])`` (``--set`` texts).

        Each value is checked as the scene loader checks ``--set`` (the same errors and ranges; a
        key left unread by the scene's settings is refused), and so is a key that no simulation
        reads (``sweep.*``, ``game.*``, ``world.t_max``, ``description``). The air, contact,
        gravity, time step, integrator, sleeping, ground, collision and solver keys apply from the
        next step on, from the current state: a new ``contact.skin`` or ``world.dt`` rebuilds the
        neighbour lists (touching pairs keep their carried impulses), a new ``contact.solver`` or
        ``world.collisions`` makes a new collision solver (no carried impulses, as at t0), and the
        balls at rest wake unless the key cannot move them (``ti_golf.sim.changes.STILL_AT_REST``).
        The keys that set up the balls or the ground
        (``launch.*``, ``ball.*``, ``terrain.*``) apply at t0 only: there the simulation is set up
        again, as ``Simulation`` of the changed scene would be (``world.ground_height`` too, which
        places a launched ball), and later in a run they are refused: use :meth:`reset` with them.
        The changes stay through :meth:`reset`, :meth:`save` and :meth:`load`.

        Raises:
            ConfigError: naming ``--set``, the key and what is allowed; nothing is changed then.
        """
        changed = as_changes(changes, value)
        scene = self._changed_scene(changed)
        if self.state.steps > 0:
            for key in changed:
                refuse_after_t0(key, self.t)
        if self.state.steps == 0 and any(at_t0(k) or k in MOVES_T0_BALLS for k in changed):
            self._set_up(scene, *self._initial_balls(), solver_flags=self._solver_flags())
        else:
            self._take_parameters(scene)
            if any(wakes(k) for k in changed):
                self._wake()

    def reset(self, changes: Mapping[str, Any] | Iterable[str] | str | None = None) -> None:
        """Go back to t0: the balls as they started (built again from the scene, or as given to
        the constructor), t = 0, no steps, every ball flying, the flight records and the collision
        solver's lists and carried impulses as at the start; bit for bit the state of a new
        ``Simulation`` of the current scene (the same solver options included). Parameters
        changed by :meth:`set` stay. ``changes`` (as :meth:`set` takes them, any key that a
        simulation reads) are made first."""
        scene = self.scene if not changes else self._changed_scene(as_changes(changes, _UNSET))
        self._set_up(scene, *self._initial_balls(), solver_flags=self._solver_flags())

    def _changed_scene(self, changes: dict[str, Any]) -> Scene:
        """The scene with ``changes``, refusing keys that would have no effect."""
        scene = with_changes(self.scene, changes)
        for key in changes:
            refuse_unread(key)
            refuse_for_given_balls(key, self.initial, self.initial_kept)
        return scene

    def _take_parameters(self, scene: Scene) -> None:
        """Continue with ``scene``'s parameters (the balls and the terrain unchanged)."""
        check_changed_step(self.scene, scene, self.model.radius_np, self.model.mass_np, lambda: (self.v, self.w))
        old = self.scene
        self.scene = scene
        self.model.set_parameters(scene)
        if self.n == 1 or not scene.world.collisions:
            self.solver = None
        elif self.solver is None or scene.contact.solver != old.contact.solver:
            from ti_golf.solvers import CollisionSolver

            flags = self._solver_flags()
            self.solver = None
            self.solver = CollisionSolver(self.model, **(flags or {}))
        else:
            self.solver.retune(self.model)

    def _initial_balls(self) -> tuple[Any, Any, Any, Any, Any, Any]:
        """``_set_up``'s balls at t0: x, v, w, radius, mass, track (``x`` ``None``: the scene's)."""
        if not self.initial_kept:
            raise ValueError("the balls at t0 were not kept (Simulation(..., keep_initial=False)): nothing to reset to")
        i = self.initial
        if i is None:
            return None, None, None, None, None, True
        return i.x, i.v, i.w, i.radius, i.mass, i.track

    def _solver_flags(self) -> dict[str, bool] | None:
        """The collision solver's ``serial`` and ``reorder`` options, to make another like it."""
        return None if self.solver is None else {"serial": self.solver.serial, "reorder": self.solver.reorder}

    # -- inspection -------------------------------------------------------------------------------
    @property
    def n(self) -> int:
        """Number of balls."""
        return self.state.n

    @property
    def t(self) -> float:
        """Simulated time [s]."""
        return self.state.t

    @property
    def step_count(self) -> int:
        """Time steps taken since t0."""
        return self.state.steps

    @property
    def dt(self) -> float:
        """Time step h [s]."""
        return self.model.dt

    def _vectors(self, name: str) -> np.ndarray:  # (a copy, by ball id)
        return self.state.read(name).astype(np.float64)

    def _assign(self, name: str, value: np.ndarray) -> None:
        """Overwrite x, v or w; the balls at rest whose value changed are awake again."""
        arr = as_vectors(value, name, self.n, bounded=True).astype(np_float())
        self._wake(np.any(arr != self.state.read(name), axis=1))
        self.state.write(name, arr)
        if name == "x" and self.solver is not None:
            self.solver.invalidate()  # moved balls may now touch balls missing from their lists
        if name != "w":  # (tracked balls: a new flight from here, flight_record)
            launch_again(
                self.state, self.model, self.launch_x, self.launch_t, self.t, self._vectors("x"), np.arange(self.n)
            )

    x = _per_ball("x", "Ball centres [m], a copy, shape (N, 3); assign to move balls (wakes those at rest).")
    v = _per_ball("v", "Velocities [m/s], a copy, shape (N, 3); assign to change them (wakes resting balls).")
    w = _per_ball("w", "Angular velocities ω [rad/s], a copy, shape (N, 3); assign to change them (wakes them).")

    @property
    def status(self) -> np.ndarray:
        """Per-ball status codes (ti_golf.scene.schema: FLYING, ROLLING, AT_REST, OUT_OF_BOUNDS), shape (N,)."""
        return self.state.read("status")

    def ball(self, i: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Ball ``i``'s centre [m], velocity [m/s] and angular velocity ω [rad/s], copies of shape
        (3,) each: ``sim.x[i]``, ``sim.v[i]`` and ``sim.w[i]``, reading that ball's entries (and,
        for balls stored in the grid's order, where it is stored) rather than three whole arrays:
        a view of one ball among 100,000 reads it in 0.6 ms every frame, against 15 ms."""
        negative = isinstance(i, (int, np.integer)) and not isinstance(i, bool) and i < 0
        if negative or not 0 <= whole_number(i, "ball") < self.n:  # (not a whole number: ValueError)
            raise IndexError(f"ball {i!r} is not one of the {self.n} balls (ids 0 … {self.n - 1})")
        p, state = self.state.index_of(int(i)), self.state
        x, v, w = (np.asarray(a[p], dtype=np.float64) for a in (state.x, state.v, state.w))
        return x, v, w

    @property
    def terrain(self) -> Terrain | None:
        """The scene's height field (:class:`ti_golf.scene.terrain.Terrain`: heights, origin, spacing,
        ``height(x, z)``, ``normal(x, z)``), or ``None``."""
        return self.model.terrain

    def counts(self) -> dict[str, int]:
        """How many balls are in each status: ``{"flying": …, "rolling": …, "at_rest": …,
        "out_of_bounds": …}``."""
        s = self.state.status.to_numpy()  # (in storage order: a count is the same in any)
        return {name: int(np.count_nonzero(s == code)) for code, name in STATUS_NAMES.items()}

    def deepest_overlap(self) -> Overlap | None:
        """The pair of balls that overlap the most now, or ``None`` when no two balls overlap (or
        the balls do not collide: one ball, or ``world.collisions`` off). Balls out of bounds are
        left out (frozen, nothing pushes them apart). Every pair close enough to touch is in the
        neighbour lists, so only listed pairs are measured, with the pairs of the balls that moved far
        since the lists were built (see ``pairs_that_may_overlap`` of the solver)."""
        if self.solver is None:
            return None
        i, j = self.solver.pairs_that_may_overlap(self.state).T
        status = self.status
        keep = (status[i] != OUT_OF_BOUNDS) & (status[j] != OUT_OF_BOUNDS)
        i, j = i[keep], j[keep]
        x, r = self.x, self.model.radius_np
        depth = r[i] + r[j] - np.linalg.norm(x[i] - x[j], axis=1)
        if depth.size == 0 or depth.max() <= 0.0:
            return None
        fraction = depth / np.minimum(r[i], r[j])
        k = int(np.argmax(fraction))
        return Overlap(float(depth[k]), float(fraction[k]), int(i[k]), int(j[k]))

    def flight(self) -> Flight:
        """Landing outcomes of the tracked balls: a ball in flight has its apex so far and NaN for the
        rest; a ball not tracked has NaN for all."""
        a = self.state.numpy()
        launch_x = self.launch_x if self.launch_x is not None else np.full((self.n, 3), np.nan)
        hang = a["t_land"] - (self.launch_t if self.launch_t is not None else 0.0)
        return Flight.from_arrays(launch_x, a["landed"], a["apex"], hang, a["land_x"], a["land_v"])

    def _wake(self, which: np.ndarray | None = None) -> None:
        """Set the balls at rest among ``which`` (a mask (N,); ``None``: all) flying, rest timers at 0."""
        status, rest = self.status, self.state.read("rest_time")
        woken = (status == AT_REST) & (True if which is None else which)
        if woken.any():
            status[woken], rest[woken] = FLYING, 0.0
            self.state.write("status", status)
            self.state.write("rest_time", rest)
            self._statuses_edited()

    def _statuses_edited(self) -> None:
        """Tell the collision solver that balls' statuses or rest timers changed between steps."""
        if self.solver is not None:
            self.solver.forget_quiet()

    def set_ball(
        self,
        i: int | Iterable[int],
        x: Any = None,
        v: Any = None,
        w: Any = None,
    ) -> None:
        """Edit the balls ``i`` (a ball id, or several) between runs: their centre ``x`` [m],
        velocity ``v`` [m/s] and spin ``w`` [rad/s], each (3,) (the same for every ball ``i``) or
        (len(i), 3); ``None`` leaves it. The edited balls are flying again (awake, back in play if
        they were out of bounds: a ball still outside is out again after the next step); the others
        keep their status. Moved balls get their neighbour lists rebuilt before the next step, and
        tracked balls moved or struck start a new flight record from where they are
        (:meth:`flight`: carry, apex and hang time measured from there and then).

        Raises:
            ValueError: a ball id outside 0 … N − 1, a value of another shape, or NaN or infinite.
        """
        ids = np.atleast_1d(np.asarray(i))
        if ids.ndim != 1 or ids.size == 0 or ids.dtype.kind not in "iu" or ids.min() < 0 or ids.max() >= self.n:
            raise ValueError(f"ball ids must be integers in 0 … {self.n - 1} (got {i!r})")
        for name, value in (("x", x), ("v", v), ("w", w)):
            if value is None:
                continue
            arr = as_vectors(value, label := f"{name} of balls {ids.tolist()}", bounded=True)  # (3,) or (K, 3)
            arr = as_vectors(np.broadcast_to(arr, (ids.size, 3)) if len(arr) == 1 else arr, label, ids.size)
            values = self._vectors(name)
            values[ids] = arr
            self.state.write(name, values.astype(np_float()))
        status, rest = self.status, self.state.read("rest_time")
        status[ids], rest[ids] = FLYING, 0.0
        self.state.write("status", status)
        self.state.write("rest_time", rest)
        self._statuses_edited()
        if x is not None and self.solver is not None:
            self.solver.invalidate()
        if x is not None or v is not None:  # (tracked balls: a new flight from here, flight_record)
            launch_again(self.state, self.model, self.launch_x, self.launch_t, self.t, self._vectors("x"), ids)

    # -- stepping ---------------------------------------------------------------------------------
    def step(self, n: int = 1) -> None:
        """Advance ``n`` time steps (a whole number >= 0); raises SimulationError naming the balls
        that went non-finite."""
        n = whole_number(n, "n")
        if n == 0:
            return
        m, s = self.model, self.state
        if self.solver is not None:
            self.solver.advance(m, s, int(n))
            self.check_finite()
            return
        with whole_steps() as came:  # each launch, then t and the step count, or none of them
            while n > 0 and not came:  # (launches of at most STEPS_PER_CALL: Ctrl-C stops between them)
                k = min(n, STEPS_PER_CALL)
                kernels.advance(
                    self._packs.step_scalars(m),
                    s.t,
                    m.dt,
                    k,
                    m.kinds,
                    self._packs.model(m),
                    self._packs.state(s),
                    self._packs.flight(s),
                )
                s.advance_clock(m.dt, k)
                n -= k
        self.check_finite()

    def check_finite(self) -> None:
        """Raise :class:`SimulationError` naming the first ball whose state is NaN or infinite."""
        if self._check_buf is None:
            self._check_buf = ti.ndarray(ti.i32, 1)
        kernels.first_nonfinite(self.state.x, self.state.v, self.state.w, self._check_buf)
        if int(self._check_buf.to_numpy()[0]) < self.n:
            finite = np.isfinite(self.x).all(axis=1) & np.isfinite(self.v).all(axis=1) & np.isfinite(self.w).all(axis=1)
            bad = int(np.argmin(finite))  # the lowest ball id (balls may be stored in another order)
            raise SimulationError(
                f"ball {bad} went non-finite at t = {self.t:.6g} s (x, v or ω is NaN or infinite); "
                "try a smaller world.dt or check the scene's parameters",
                [bad],
            )

    def run(
        self,
        t: float | None = None,
        steps: int | None = None,
        until: str | None = None,
        record_every: int = 0,
        progress: RunProgress | None = None,
        every: int = 0,
        on_every: Callable[["Simulation"], None] | None = None,
        recording: Recording | None = None,
    ) -> Recording:
        """Advance by ``t`` seconds (rounded up to whole steps of ``dt``) or ``steps`` steps, not
        both (default: the scene's ``world.t_end``).

        ``until="rest"`` stops early once every ball is at rest or out of bounds; ``until="landed"``
        once every tracked ball has landed, at the first check that finds it (every
        ``UNTIL_CHECK_S`` of simulated time, whatever the run records). ``record_every=K`` samples
        x and ω every K steps. ``progress(t_done, t_total)`` is called at each check and at the
        end, and with ``until`` also given
        ``finished=(k, n, what)``: k of the n balls are finished (``what``: "at rest or out of
        bounds", "landed"), since such a run ends when all are, often long before ``t_total``.
        ``on_every(sim)`` is called every ``every`` steps (e.g. to render a frame). The samples go
        into ``recording`` when given (a caller's, which keeps what was sampled if the run is
        interrupted), else into a new :class:`Recording`; either is returned.
        """
        if until not in (None, "rest", "landed"):
            raise ValueError(f"until must be None, 'rest' or 'landed' (got {until!r})")
        if until == "landed" and self.launch_x is None:  # (the run would stop at its first check)
            raise ValueError(f"until='landed' has no effect: {NOTHING_TRACKED}")
        steps = steps_to_run(t, steps, self.dt, self.scene.world.t_end, self.scene)
        record_every, every = whole_number(record_every, "record_every"), whole_number(every, "every")
        if every and on_every is None or on_every is not None and not every:
            raise ValueError("every and on_every go together: on_every(sim) is called every `every` steps")
        rec = Recording() if recording is None else recording
        if record_every:
            rec.t.append(self.t)
            rec.x.append(self.x)
            rec.w.append(self.w)
        check = max(1, min(steps, int(round(UNTIL_CHECK_S / self.dt)) or 1))  # (until and progress)
        done = 0
        while done < steps:
            # a launch runs to the next step that records, calls on_every or checks: the steps at
            # which a run with `until` may stop do not depend on what it records
            k = min(steps, *((done // c + 1) * c for c in (record_every, every, check) if c)) - done
            k = min(k, STEPS_PER_CALL)  # (a tiny step: Ctrl-C is heard between calls)
            self.step(k)
            done += k
            if record_every and done % record_every == 0:
                rec.t.append(self.t)
                rec.x.append(self.x)
                rec.w.append(self.w)
            if every and on_every is not None and done % every == 0:
                on_every(self)
            if done % check and done < steps:
                continue
            left = self.unfinished(until).size if until is not None else 0
            if progress is not None and until is not None:
                progress(done * self.dt, steps * self.dt, finished=(self.n - left, self.n, UNTIL_DONE[until]))
            elif progress is not None:
                progress(done * self.dt, steps * self.dt)
            if until is not None and left == 0:
                break
        return rec

    def unfinished(self, until: str) -> np.ndarray:
        """Ids of the balls a run with ``until`` waits for, shape (K,): with ``"rest"`` those
        neither at rest nor out of bounds, with ``"landed"`` the tracked balls still in flight."""
        if until == "rest":
            s = self.status
            return np.flatnonzero((s != AT_REST) & (s != OUT_OF_BOUNDS))
        if until != "landed":
            raise ValueError(f"until must be 'rest' or 'landed' (got {until!r})")
        return np.flatnonzero(self.state.read("landed") == 0)

    def save(self, path: str | os.PathLike[str], recording: Recording | None = None, partial: bool = False) -> None:
        """Write the run to an ``.npz``, whole or not at all (a temporary file renamed into place;
        ``.npz`` is added to a name without a suffix, and another suffix is refused): ``x``, ``v``,
        ``w`` (N, 3), ``t``, ``status``, ``radius``, ``mass`` by ball id; with a terrain
        ``terrain_heights`` (nx, nz), ``terrain_origin`` (3,) and ``terrain_spacing`` (dx, dz); the recording, if given
        (``traj_t``, ``traj_x``, ``traj_w``); ``partial`` (a bool), whether the run was stopped
        before the time it was asked to reach; and all that :meth:`load` needs to continue the
        run bit for bit (the scene, the step count, the flight records, the sleeping timers, the
        collision solver's lists and carried impulses, the balls at t0; see the docs' lab page)."""
        from ti_golf.sim.saved_run import write_run

        write_run(self, path, recording, partial)


UNTIL_CHECK_S = 0.05
"""Simulated seconds between a run's checks of ``until`` (and its progress reports): the steps at
which a run may stop, whatever it records or renders."""

UNTIL_DONE = {"rest": "at rest or out of bounds", "landed": "landed"}
"""What a ball is once a run with ``until`` no longer waits for it."""

NOTHING_TRACKED = (
    "no ball is tracked for its landing (a scene's [launch] ball shot above the ground, or the balls given "
    "with track=True, are); wait for rest instead"
)
"""Why a run of balls none of which is tracked cannot wait for them to land."""
