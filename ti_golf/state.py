"""Per-step state of N balls in Taichi ndarrays, with numpy conversion.

Taichi ndarrays rather than fields: kernels compile once per precision whatever N is, and any
number of simulations can live side by side in one process (fields would recompile every kernel for
every new simulation and could not be freed one by one).
"""

from __future__ import annotations

import numpy as np
import taichi as ti

from .physics.integrate import IN_FLIGHT, NOT_TRACKED
from .physics.types import vec3
from .runtime import np_float


class State:
    """Everything that changes from step to step.

    Attributes (Taichi ndarrays, N = number of balls):
        x: ball centres [m], shape (N,), vec3.
        v: velocities [m/s], shape (N,), vec3.
        w: angular velocities ω [rad/s], shape (N,), vec3.
        status: ``FLYING``, ``ROLLING``, ``AT_REST`` or ``OUT_OF_BOUNDS`` (ti_golf.config), shape (N,), i32.
        rest_time: time spent slow while touching [s], shape (N,).
        landed: −1 not tracked, 0 in flight, 1 landed, shape (N,), i32.
        apex: highest centre height so far [m], shape (N,).
        t_land: landing time [s], shape (N,).
        land_x, land_v: landing point [m] and velocity [m/s], shape (N,), vec3.
        t: simulated time [s] (a Python float).
        order: the storage order: ``order[p]`` is the id of the ball stored at index p of every
            per-ball array (numpy int32 (N,)); ``None`` while the balls are stored in id order.
            A large pile is stored so that neighbours lie close in memory (see
            ``CollisionSolver.reorder``); :meth:`to_ids` and :meth:`from_ids` convert.
    """

    PER_BALL = ("x", "v", "w", "status", "rest_time", "landed", "apex", "t_land", "land_x", "land_v")
    """The per-ball arrays, all in storage order."""

    def __init__(self, n: int) -> None:
        self.n = int(n)
        self.x = ti.ndarray(vec3, self.n)
        self.v = ti.ndarray(vec3, self.n)
        self.w = ti.ndarray(vec3, self.n)
        self.status = ti.ndarray(ti.i32, self.n)
        self.rest_time = ti.ndarray(float, self.n)
        self.landed = ti.ndarray(ti.i32, self.n)
        self.apex = ti.ndarray(float, self.n)
        self.t_land = ti.ndarray(float, self.n)
        self.land_x = ti.ndarray(vec3, self.n)
        self.land_v = ti.ndarray(vec3, self.n)
        self.t = 0.0
        self.order: np.ndarray | None = None

    def to_ids(self, a: np.ndarray) -> np.ndarray:
        """Per-ball values in storage order (first axis N) rearranged by ball id."""
        if self.order is None:
            return a
        out = np.empty_like(a)
        out[self.order] = a
        return out

    def from_ids(self, a: np.ndarray) -> np.ndarray:
        """Per-ball values by ball id (first axis N) rearranged into storage order."""
        return a if self.order is None else a[self.order]

    def read(self, name: str) -> np.ndarray:
        """A copy of the per-ball array ``name`` (e.g. ``"x"``) as numpy, by ball id."""
        return self.to_ids(getattr(self, name).to_numpy())

    def write(self, name: str, a: np.ndarray) -> None:
        """Set the per-ball array ``name`` from numpy values given by ball id."""
        getattr(self, name).from_numpy(np.ascontiguousarray(self.from_ids(a)))

    def reset(self, x: np.ndarray, v: np.ndarray, w: np.ndarray, track: np.ndarray | bool = True) -> None:
        """Set positions, velocities and spins (each (N, 3)); start flight tracking where ``track``."""
        f = np_float()
        x = np.ascontiguousarray(x, dtype=f).reshape(self.n, 3)
        track = np.broadcast_to(np.asarray(track, dtype=bool), (self.n,))
        values = {
            "x": x, "v": np.asarray(v, dtype=f).reshape(self.n, 3), "w": np.asarray(w, dtype=f).reshape(self.n, 3),
            "status": np.zeros(self.n, np.int32), "rest_time": np.zeros(self.n, f),
            "landed": np.where(track, IN_FLIGHT, NOT_TRACKED).astype(np.int32), "apex": x[:, 1].copy(),
            "t_land": np.zeros(self.n, f), "land_x": x.copy(), "land_v": np.zeros((self.n, 3), f),
        }
        for name in self.PER_BALL:
            self.write(name, values[name])
        self.t = 0.0

    def numpy(self) -> dict[str, np.ndarray]:
        """Copies of all per-ball arrays as numpy by ball id (float64 for floats)."""
        out = {}
        for name in self.PER_BALL:
            a = self.read(name)
            out[name] = a.astype(np.float64) if a.dtype.kind == "f" else a
        return out
