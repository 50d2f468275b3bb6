"""Static data of a simulation: parameters from the scene and per-ball properties."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import taichi as ti

from ti_golf.physics.aero import air_params
from ti_golf.physics.kinds import kinds_of
from ti_golf.physics.types import ContactParams, TerrainParams, vec3
from ti_golf.runtime import np_float
from ti_golf.scene.schema import Scene, Surface, Vec3
from ti_golf.scene.terrain import build_terrain


class Model:
    """What does not change while stepping.

    Attributes:
        scene: the validated scene.
        n: number of balls.
        radius: ball radii [m], Taichi ndarray of shape (N,), or (1,) when all balls have the same
            radius, as in most scenes (kernels read it with ``physics.types.of_ball``): 8 bytes
            per ball less in f64.
        mass: ball masses [kg], shape (N,), or (1,) when all balls have the same mass.
        radius_np, mass_np: the same as read-only float64 numpy arrays (N,), by ball id.
        launch_height: height whose downward crossing counts as landing [m], shape (N,), or (1,)
            when no ball's flight is tracked (``State.tracking``: the kernels then do not read it).
        The Taichi arrays of :meth:`per_ball` follow the state's storage order (``State.order``): a
        collision solver may store the balls in another order than their ids.
        air, contact: kernel-argument structs (AirParams, ContactParams).
        gravity: g [m/s²], vec3.
        kinds: the scene's choices of code, the kernels' compile-time argument
            (:class:`~ti_golf.physics.kinds.Kinds`: integrator, air model, wind profile, terrain,
            contact solver, friction model, turf impacts).
        plane_p, plane_n: points on and unit normals of the impenetrable planes (the ground
            included), numpy (P, 3); passed to kernels directly.
        terrain: the scene's height field (:class:`ti_golf.scene.terrain.Terrain`, numpy) or ``None``.
        terrain_params: kernel-argument struct (TerrainParams); ``on`` = 0 without a terrain.
        terrain_cells: surface type of every terrain cell, Taichi ndarray (nx − 1, nz − 1) int.
        surface_table: e, μ, μ_roll and turf (0 or 1) of every surface type, numpy (S, 4) (one row from [contact]
            when the scene has no [[surfaces]]).
        terrain_h: the terrain's heights (nx, nz) [m] as a Taichi ndarray (a 2×2 zero grid
            without a terrain: kernels always take one).
    """

    PER_BALL = ("radius", "mass", "launch_height")
    """The per-ball Taichi arrays."""

    def per_ball(self) -> list[str]:
        """The names of the Taichi arrays that hold an entry per ball (``radius`` and ``mass`` only
        while they vary, ``launch_height`` only while some ball is tracked)."""
        return [name for name in self.PER_BALL if getattr(self, name).shape[0] == self.n]

    def __init__(self, scene: Scene, radius: np.ndarray, mass: np.ndarray, launch_height: np.ndarray) -> None:
        f = np_float()
        self.scene = scene
        self.n = int(len(radius))
        self.radius = _shared_or_per_ball(radius)
        self.mass = _shared_or_per_ball(mass)
        self.launch_height = ti.ndarray(float, len(launch_height))
        self.launch_height.from_numpy(np.asarray(launch_height, dtype=f))
        self.radius_np = _compact(radius)
        self.mass_np = _compact(mass)
        self.terrain = None
        heights: np.ndarray = np.zeros((2, 2))
        origin: Sequence[float] | np.ndarray = (0.0, 0.0, 0.0)
        spacing: Sequence[float] | np.ndarray = (1.0, 1.0)
        kill = 0.0
        if scene.terrain is not None:
            self.terrain = build_terrain(scene.terrain, scene.path)
            heights, origin, spacing, kill = (
                self.terrain.heights,
                self.terrain.origin,
                self.terrain.spacing,
                scene.terrain.kill,
            )
        self.terrain_params = TerrainParams(
            on=int(self.terrain is not None),
            origin=vec3(*origin),
            dx=float(spacing[0]),
            dz=float(spacing[1]),
            kill=float(kill),
        )
        self.terrain_h = ti.ndarray(float, heights.shape)
        self.terrain_h.from_numpy(np.ascontiguousarray(heights, dtype=f))
        cells = np.zeros((1, 1), np.int32)
        if self.terrain is not None:
            # a terrain without surface types is all of the first (as build_terrain makes it without levels)
            t_cells = self.terrain.cells
            cells = t_cells if t_cells is not None else np.zeros_like(self.terrain.heights[:-1, :-1], np.int32)
        self.terrain_cells = ti.ndarray(ti.i32, cells.shape)
        self.terrain_cells.from_numpy(np.ascontiguousarray(cells, dtype=np.int32))
        self.set_parameters(scene)

    def set_parameters(self, scene: Scene) -> None:
        """Take the physical parameters of ``scene``: air, contact, gravity, the integrator, the time
        step, the planes and the surface table. The balls and the terrain stay as they are (the
        caller makes sure that ``scene`` has the same ``[terrain]``)."""
        f = np_float()
        self.scene = scene
        a, c, w = scene.air, scene.contact, scene.world
        self.air = air_params(a, w.ground_height)
        self.contact = ContactParams(
            e=c.e,
            mu=c.mu,
            k_p=c.k_p,
            mu_roll=c.mu_roll,
            relax=c.relax,
            v_bounce=c.v_bounce,
            turf=int(c.turf),
        )
        self.gravity = vec3(*w.gravity)
        self.kinds = kinds_of(scene)
        self.dt = w.dt
        planes = scene_planes(scene)
        self.plane_p = np.array([p for p, _ in planes], dtype=f).reshape(-1, 3)
        self.plane_n = np.array([n for _, n in planes], dtype=f).reshape(-1, 3)
        surfaces = scene.surfaces or (Surface(),)
        self.surface_table = np.array(
            [
                [
                    c.e if sf.e is None else sf.e,
                    c.mu if sf.mu is None else sf.mu,
                    c.mu_roll if sf.mu_roll is None else sf.mu_roll,
                    float(c.turf if sf.turf is None else sf.turf),
                ]
                for sf in surfaces
            ],
            dtype=f,
        )


def _shared_or_per_ball(values: np.ndarray) -> ti.Ndarray:
    """A Taichi array of per-ball ``values`` (N,) in the float type, or of one entry when all are
    equal (see ``physics.types.of_ball``)."""
    a = np.asarray(values, dtype=np_float()).reshape(-1)
    if a.size > 1 and np.all(a == a[0]):
        a = a[:1]
    out = ti.ndarray(float, a.size)
    out.from_numpy(a)
    return out


def _compact(values: np.ndarray) -> np.ndarray:
    """A read-only float64 copy of per-ball ``values`` (N,); when all are equal, as in most scenes, a
    broadcast view of one number, which takes no memory per ball (8 bytes per ball and array less
    for a million balls of one kind)."""
    a = np.asarray(values, dtype=np.float64).reshape(-1)
    if a.size > 1 and np.all(a == a[0]):
        return np.broadcast_to(a[:1], a.shape)  # a broadcast view is read-only
    a = a.copy()
    a.flags.writeable = False
    return a


def scene_planes(scene: Scene) -> list[tuple[Vec3, Vec3]]:
    """The impenetrable planes of ``scene`` as (a point on it [m], its unit normal): its
    ``[[planes]]``, then the ground when ``world.ground``."""
    planes: list[tuple[Vec3, Vec3]] = [(pl.point, pl.normal) for pl in scene.planes]
    if scene.world.ground:
        planes.append(((0.0, scene.world.ground_height, 0.0), (0.0, 1.0, 0.0)))
    return planes
