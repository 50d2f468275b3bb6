"""A step with ball–ball collisions: free flight, hash-grid neighbour lists, Jacobi contact
sweeps and the end-of-step position update, in that fixed order (see physics/collide.py)."""

from __future__ import annotations

import numpy as np
import taichi as ti

from .model import Model
from .physics import collide, grid
from .physics.types import vec3
from .state import State


class CollisionSolver:
    """Buffers and neighbour lists for stepping N colliding balls.

    Attributes:
        cell: grid cell size [m]: the largest diameter plus the skin.
        skin: neighbour-list skin [m] (``contact.skin`` × largest radius).
        capacity: width of the neighbour table (grows when a list overflows).
        rebuilds: how many times the neighbour lists were built (for benchmarks and tests).
    """

    def __init__(self, model: Model, capacity: int = 16) -> None:
        self._model = model
        n = model.n
        r_max = float(model.radius_np.max())
        self.skin = model.scene.contact.skin * r_max
        self.cell = 2.0 * r_max + self.skin
        self.mask = (1 << max(4, int(np.ceil(np.log2(2 * n))))) - 1
        self.capacity = capacity
        self.rebuilds = 0
        self.bucket = ti.ndarray(ti.i32, n)
        self.rank = ti.ndarray(ti.i32, n)
        self.sorted_ids = ti.ndarray(ti.i32, n)
        self.count = ti.ndarray(ti.i32, self.mask + 1)
        self.start = ti.ndarray(ti.i32, self.mask + 2)
        self.neighbours = ti.ndarray(ti.i32, (n, capacity))
        self.n_neighbours = ti.ndarray(ti.i32, n)
        self.x_at_build = ti.ndarray(vec3, n)
        self.x_free = ti.ndarray(vec3, n)
        self.v_a, self.w_a = ti.ndarray(vec3, n), ti.ndarray(vec3, n)
        self.v_b, self.w_b = ti.ndarray(vec3, n), ti.ndarray(vec3, n)
        self.flag = ti.ndarray(ti.i32, 1)
        self._valid = False

    def build(self, state: State) -> None:
        """Sort balls into the hash grid and rebuild every neighbour list (widening the table if needed)."""
        grid.clear(self.count)
        grid.count_buckets(state.x, 1.0 / self.cell, self.mask, self.bucket, self.rank, self.count)
        grid.exclusive_scan(self.count, self.start)
        grid.scatter(self.bucket, self.rank, self.start, self.sorted_ids)
        while True:
            grid.clear(self.flag)
            grid.build_neighbours(state.x, self._model.radius, 1.0 / self.cell, self.mask, self.skin, self.start,
                                  self.sorted_ids, self.neighbours, self.n_neighbours, self.x_at_build, self.flag)
            longest = int(self.flag.to_numpy()[0])
            if longest <= self.capacity:
                break
            self.capacity = int(2 ** np.ceil(np.log2(longest)))
            self.neighbours = ti.ndarray(ti.i32, (state.n, self.capacity))
        self.rebuilds += 1
        self._valid = True

    def step(self, model: Model, state: State) -> None:
        """Advance all balls by one step of ``model.dt``."""
        if not self._valid:
            self.build(state)
        m, s, c = model, state, model.scene.contact
        h = m.dt
        grid.clear(self.flag)
        collide.free_step(m.air, m.gravity, h, m.integrator, s.t, 0.5 * self.skin, m.radius, m.mass, m.launch_height,
                          s.status, s.x, self.x_at_build, s.v, s.w, self.x_free, s.landed, s.apex, s.t_land,
                          s.land_x, s.land_v, self.flag)
        if int(self.flag.to_numpy()[0]):
            self.build(state)
        v_in, w_in = s.v, s.w  # the free-flight velocities
        buffers = [(self.v_a, self.w_a), (self.v_b, self.w_b)]
        for k in range(c.iterations):
            v_out, w_out = buffers[k % 2]
            collide.contact_pass(m.contact, h, m.v_inelastic, m.radius, m.mass, m.plane_p, m.plane_n, s.status, s.x,
                                 self.neighbours, self.n_neighbours, v_in, w_in, v_out, w_out)
            v_in, w_in = v_out, w_out
        # finish_step reads x_free[i] and v[i] of ball i before writing x_new[i] and v[i], so it may
        # write the new positions over x_free; other balls' old positions are read from state.x.
        collide.finish_step(m.contact, h, m.scene.world.v_rest, m.scene.world.t_rest, m.radius, m.mass, m.plane_p,
                            m.plane_n, self.neighbours, self.n_neighbours, s.x, self.x_free, s.v, v_in, w_in,
                            self.x_free, s.v, s.w, s.status, s.rest_time)
        s.x, self.x_free = self.x_free, s.x
        s.t += h
