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
    """

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

    def reset(self, x: np.ndarray, v: np.ndarray, w: np.ndarray, track: np.ndarray | bool = True) -> None:
        """Set positions, velocities and spins (each (N, 3)); start flight tracking where ``track``."""
        f = np_float()
        x = np.ascontiguousarray(x, dtype=f).reshape(self.n, 3)
        self.x.from_numpy(x)
        self.v.from_numpy(np.ascontiguousarray(v, dtype=f).reshape(self.n, 3))
        self.w.from_numpy(np.ascontiguousarray(w, dtype=f).reshape(self.n, 3))
        self.status.from_numpy(np.zeros(self.n, np.int32))
        self.rest_time.from_numpy(np.zeros(self.n, f))
        track = np.broadcast_to(np.asarray(track, dtype=bool), (self.n,))
        self.landed.from_numpy(np.where(track, IN_FLIGHT, NOT_TRACKED).astype(np.int32))
        self.apex.from_numpy(x[:, 1].copy())
        self.t_land.from_numpy(np.zeros(self.n, f))
        self.land_x.from_numpy(x.copy())
        self.land_v.from_numpy(np.zeros((self.n, 3), f))
        self.t = 0.0

    def numpy(self) -> dict[str, np.ndarray]:
        """Copies of all per-ball arrays as numpy (float64 for floats)."""
        out = {}
        for name in ("x", "v", "w", "status", "rest_time", "landed", "apex", "t_land", "land_x", "land_v"):
            a = getattr(self, name).to_numpy()
            out[name] = a.astype(np.float64) if a.dtype.kind == "f" else a
        return out
