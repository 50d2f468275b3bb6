"""The kernels' argument packs of a model, a state and a solver, made once and reused.

A Taichi argument pack holds references to arrays; making one costs tens of microseconds, so
:class:`Packs` keeps each pack until one of its arrays is replaced (the solver swaps the state's
positions with its scratch every step, and reorders per-ball arrays when it sorts the balls).
It also keeps the array of the kernels' scalar parameters (:meth:`Packs.step_scalars`), filled
again only when they change.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import taichi as ti

from ti_golf.physics.types import (
    BallState,
    FlightRecord,
    ModelArrays,
    NeighbourLists,
    StepParams,
    StepScratch,
    scalar_values,
)
from ti_golf.runtime import np_float


class Packs:
    """Argument packs by their members' identity: ``packs.get(BallState, x=..., v=..., ...)``."""

    MAX_KEPT = 16
    """Packs kept before the least recently used are dropped."""

    PER_SHAPE = 2
    """Packs kept of one kind whose arrays have the same shapes: a solver alternates between two
    (it swaps the state's positions with its scratch every step). Past them, the least recently
    used takes the new arrays as its members: none is made. Taichi 1.7.4 keeps memory of every
    pack it ever made (the docs' performance page, "Design measurements"), and a reorder of the
    balls at each rebuild of the lists would otherwise make new ones."""

    def __init__(self) -> None:
        self._kept: dict[tuple[Any, ...], tuple[tuple[Any, ...], Any]] = {}  # least recently used first
        self._scalars: tuple[tuple[Any, ...], Any] | None = None  # (the structs, their array)
        self._step: tuple[tuple[Any, ...], Any] | None = None  # ((scene, skin, v_cut, r_cut), StepParams)

    def get(self, kind: Any, **members: Any) -> Any:
        """The pack of type ``kind`` holding ``members`` (made now, or taken over, if these arrays have
        none yet).

        A new pack drops the kept packs of its kind whose arrays have other shapes than these: arrays
        that were replaced by bigger ones (the solver's pair tables, widened), which the old packs
        would otherwise keep in memory beside the new ones."""
        key = (id(kind), *(id(a) for a in members.values()))
        kept = self._kept.pop(key, None)
        if kept is not None:
            self._kept[key] = kept
            return kept[1]
        shapes = (id(kind), *(getattr(a, "shape", None) for a in members.values()))
        alike = []
        for old, (old_shapes, _) in list(self._kept.items()):
            if old_shapes[0] == id(kind) and old_shapes != shapes:
                del self._kept[old]
            elif old_shapes == shapes:
                alike.append(old)
        if len(alike) >= self.PER_SHAPE:
            pack = self._kept.pop(alike[0])[1]
            for name, a in members.items():
                if pack[name] is not a:
                    pack[name] = a
        else:
            if len(self._kept) >= self.MAX_KEPT:
                self._kept.pop(next(iter(self._kept)))
            pack = kind(**members)
        self._kept[key] = (shapes, pack)
        return pack

    def scalars(self, air: Any, contact: Any, terrain: Any, params: Any) -> Any:
        """The array of scalars (:func:`~ti_golf.physics.types.scalars_of`) of these air, contact,
        terrain and step parameters (Python-scope structs), filled again only when one of them is
        another object than at the last call: a struct's members do not change once it is made."""
        structs = (air, contact, terrain, params)
        kept = self._scalars
        if kept is None or any(a is not b for a, b in zip(kept[0], structs, strict=True)):
            values = np.asarray(scalar_values(*structs), dtype=np_float())
            array = kept[1] if kept is not None else ti.ndarray(float, values.size)
            array.from_numpy(values)
            self._scalars = kept = (structs, array)
        return kept[1]

    def step_scalars(self, m: Any, skin: float = 0.0, v_cut: float = 0.0, r_cut: float = 0.0) -> Any:
        """:meth:`scalars` of a :class:`~ti_golf.physics.model.Model`'s air, contact and terrain and of
        a step's :data:`~ti_golf.physics.types.StepParams` with the neighbour lists' ``skin`` [m],
        ``v_cut`` [m/s] and ``r_cut`` [m] (0 without lists); the step's struct is made again only
        when the model takes another scene (``Model.set_parameters``) or these change."""
        kept = self._step
        if kept is None or kept[0][0] is not m.scene or kept[0][1:] != (skin, v_cut, r_cut):
            w = m.scene.world
            params = StepParams(
                gravity=m.gravity,
                h=m.dt,
                half_skin=0.5 * skin,
                skin=skin,
                v_rest=w.v_rest,
                t_rest=w.t_rest,
                v_cut=v_cut,
                r_cut=r_cut,
            )
            self._step = kept = ((m.scene, skin, v_cut, r_cut), params)
        return self.scalars(m.air, m.contact, m.terrain_params, kept[1])

    def clear(self) -> None:
        """Drop every kept pack, and with them their references to arrays about to be replaced."""
        self._kept.clear()

    def model(self, m: Any) -> Any:
        """:data:`~ti_golf.physics.types.ModelArrays` of a :class:`~ti_golf.physics.model.Model`."""
        return self.get(
            ModelArrays,
            radius=m.radius,
            mass=m.mass,
            launch_height=m.launch_height,
            plane_p=m.plane_p,
            plane_n=m.plane_n,
            heights=m.terrain_h,
            terrain_cells=m.terrain_cells,
            surface_table=m.surface_table,
        )

    def state(self, s: Any) -> Any:
        """:data:`~ti_golf.physics.types.BallState` of a :class:`~ti_golf.physics.state.State`."""
        return self.get(BallState, x=s.x, v=s.v, w=s.w, status=s.status, rest_time=s.rest_time)

    def flight(self, s: Any) -> Any:
        """:data:`~ti_golf.physics.types.FlightRecord` of a :class:`~ti_golf.physics.state.State`."""
        return self.get(FlightRecord, landed=s.landed, apex=s.apex, t_land=s.t_land, land_x=s.land_x, land_v=s.land_v)

    def lists(self, c: Any) -> Any:
        """:data:`~ti_golf.physics.types.NeighbourLists` of a collision solver."""
        return self.get(
            NeighbourLists,
            upper=c.upper,
            first=c.first,
            lower=c.lower,
            lower_first=c.lower_first,
            x_at_build=c.x_at_build,
            drift=c.drift,
            lam=c.lam,
            surface_start=c.surface_start,
            surface_impulse=c.surface_impulse,
            friction=c.friction,
        )

    def scratch(self, c: Any) -> Any:
        """:data:`~ti_golf.physics.types.StepScratch` of a collision solver."""
        return self.get(
            StepScratch,
            x_free=c.x_free,
            v_free=c.v_free,
            calm=c.calm,
            clear=c.clear,
            J=c.impulse,
            impact=c.impact,
            flag=c.flag,
        )
