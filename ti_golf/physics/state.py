"""Per-step state of N balls in Taichi ndarrays, with numpy conversion.

Taichi ndarrays rather than fields: kernels compile once per precision whatever N is, and any
number of simulations can live side by side in one process (fields would recompile every kernel for
every new simulation and could not be freed one by one).
"""

from __future__ import annotations

import numpy as np
import taichi as ti

from ti_golf.physics.integrate import IN_FLIGHT, NOT_TRACKED
from ti_golf.physics.types import vec3
from ti_golf.runtime import np_float


class State:
    """Everything that changes from step to step.

    Attributes (Taichi ndarrays, N = number of balls):
        x: ball centres [m], shape (N,), vec3.
        v: velocities [m/s], shape (N,), vec3.
        w: angular velocities ω [rad/s], shape (N,), vec3.
        status: ``FLYING``, ``ROLLING``, ``AT_REST`` or ``OUT_OF_BOUNDS`` (ti_golf.scene.schema), shape (N,), i32.
        rest_time: time spent slow while touching [s], shape (N,).
        landed: −1 not tracked, 0 in flight, 1 landed, shape (N,), i32.
        apex: highest centre height so far [m], shape (N,).
        t_land: landing time [s], shape (N,).
        land_x, land_v: landing point [m] and velocity [m/s], shape (N,), vec3.
        tracking: whether any ball's flight is recorded. Without, the ``FLIGHT`` arrays hold one
            entry each, which the kernels do not read (72 bytes per ball less in f64 for a pile,
            with the model's launch heights), and :meth:`read` gives the record of untracked balls.
        t: simulated time [s] (a Python float).
        steps: time steps taken since t0.
        ids: the storage order: ``ids[p]`` is the id of the ball stored at index p of every
            per-ball array, shape (N,), i32; ``None`` while the balls are stored in id order. A large
            pile is stored so that neighbours lie close in memory (see ``CollisionSolver.reorder``),
            and ``ids`` is gathered with the other per-ball arrays (:meth:`per_ball`); :attr:`order`
            reads it, :meth:`to_ids` and :meth:`from_ids` convert.
    """

    FLIGHT = ("landed", "apex", "t_land", "land_x", "land_v")
    """The flight record's arrays (one entry each while no ball is tracked)."""
    PER_BALL = ("x", "v", "w", "status", "rest_time") + FLIGHT
    """The per-ball arrays, all in storage order."""

    def __init__(self, n: int, tracking: bool = True) -> None:
        self.n = int(n)
        self.tracking = bool(tracking)
        self.x = ti.ndarray(vec3.get(), self.n)
        self.v = ti.ndarray(vec3.get(), self.n)
        self.w = ti.ndarray(vec3.get(), self.n)
        self.status = ti.ndarray(ti.i32, self.n)
        self.rest_time = ti.ndarray(float, self.n)
        m = self.n if self.tracking else 1
        self.landed = ti.ndarray(ti.i32, m)
        self.apex = ti.ndarray(float, m)
        self.t_land = ti.ndarray(float, m)
        self.land_x = ti.ndarray(vec3.get(), m)
        self.land_v = ti.ndarray(vec3.get(), m)
        self.t = 0.0
        self.steps = 0
        self.ids: ti.Ndarray | None = None

    @property
    def order(self) -> np.ndarray | None:
        """A copy of :attr:`ids` (numpy int32 (N,)), ``None`` while the balls are stored in id order."""
        return None if self.ids is None else self.ids.to_numpy()

    def to_ids(self, a: np.ndarray) -> np.ndarray:
        """Per-ball values in storage order (first axis N) rearranged by ball id."""
        order = self.order
        if order is None:
            return a
        out = np.empty_like(a)
        _rows(out)[order] = _rows(a)
        return out

    def from_ids(self, a: np.ndarray) -> np.ndarray:
        """Per-ball values by ball id (first axis N) rearranged into storage order."""
        order = self.order
        return a if order is None else _rows(a)[order].view(a.dtype).reshape(a.shape)

    def index_of(self, i: int) -> int:
        """Where ball ``i`` is stored: its index in the per-ball arrays."""
        order = self.order
        return int(i) if order is None else int(np.flatnonzero(order == i)[0])

    def per_ball(self) -> list[str]:
        """The names of the arrays that hold an entry per ball and follow the storage order (the
        flight record's only while tracking, ``ids`` once the balls are stored out of id order)."""
        names = [name for name in self.PER_BALL if self.tracking or name not in self.FLIGHT]
        return names + (["ids"] if self.ids is not None else [])

    def read(self, name: str) -> np.ndarray:
        """A copy of the per-ball array ``name`` (e.g. ``"x"``) as numpy, by ball id. While no ball
        is tracked, the flight record reads as that of balls not tracked (``landed`` −1, NaN)."""
        a = getattr(self, name).to_numpy()
        if name in self.FLIGHT and not self.tracking:
            return np.full((self.n,) + a.shape[1:], NOT_TRACKED if name == "landed" else np.nan, a.dtype)
        return self.to_ids(a)

    def write(self, name: str, a: np.ndarray) -> None:
        """Set the per-ball array ``name`` from numpy values given by ball id."""
        getattr(self, name).from_numpy(np.ascontiguousarray(self.from_ids(a)))

    def reset(self, x: np.ndarray, v: np.ndarray | None, w: np.ndarray | None, track: np.ndarray | bool = True) -> None:
        """Set positions, velocities and spins (each (N, 3); ``None``: zero); start flight tracking
        where ``track`` (ignored while not ``tracking``). One array at a time, so that few numpy
        copies of a large pile live at once."""
        f, n = np_float(), self.n
        x = np.ascontiguousarray(x, dtype=f).reshape(n, 3)
        self.write("x", x)
        for name, values in (("v", v), ("w", w)):
            if values is None:
                getattr(self, name).fill(0.0)
            else:
                self.write(name, np.asarray(values, dtype=f).reshape(n, 3))
        self.status.fill(0)  # zeros: the same in every storage order, and no numpy copies
        self.rest_time.fill(0.0)
        if self.tracking:
            track = np.broadcast_to(np.asarray(track, dtype=bool), (n,))
            self.write("landed", np.where(track, IN_FLIGHT, NOT_TRACKED).astype(np.int32))
            self.write("apex", x[:, 1].copy())
            self.t_land.fill(0.0)
            self.write("land_x", x)
            self.land_v.fill(0.0)
        else:
            self.landed.from_numpy(np.full(1, NOT_TRACKED, np.int32))
        self.t = 0.0
        self.steps = 0

    def advance_clock(self, dt: float, steps: int) -> None:
        """Count ``steps`` steps of ``dt`` [s] on the clock: ``dt`` added to :attr:`t` once a step,
        as the kernels add it to the time of each step, so that the time after a run's steps is the
        same however they were split into launches (or skipped, as a pile asleep skips them)."""
        for _ in range(int(steps)):
            self.t += dt
        self.steps += int(steps)

    def numpy(self) -> dict[str, np.ndarray]:
        """Copies of all per-ball arrays as numpy by ball id (float64 for floats)."""
        out = {}
        for name in self.PER_BALL:
            a = self.read(name)
            out[name] = a.astype(np.float64) if a.dtype.kind == "f" else a
        return out


def _rows(a: np.ndarray) -> np.ndarray:
    """The rows of ``a`` (first axis N, C-contiguous) as N opaque items of a row's bytes each: numpy
    moves them by index about twice as fast as rows of several numbers (100,000 vectors in 0.9 ms
    against 1.8 ms)."""
    a = np.ascontiguousarray(a)
    row = a.reshape(len(a), -1)
    return row.view(np.dtype((np.void, row.shape[1] * row.itemsize)))[:, 0]
