"""A collision solver's state saved with a run and given back to a new solver (:mod:`.saved_run`):
the neighbour lists, the carried impulses and the numbers they were built with, so that a run
loaded again continues bit for bit."""

from __future__ import annotations

from typing import Any

import numpy as np
import taichi as ti

from ti_golf.physics.types import pair_columns
from ti_golf.sim.packs import Packs
from ti_golf.sim.solver import CollisionSolver
from ti_golf.sim.state import State

NOT_SAVED = ("_model", "_packs", "_ids", "serial", "reorder", "loop_cap", "gauss_seidel", "_last_grid")
"""Attributes of a :class:`CollisionSolver` that its constructor sets from its arguments, the
model and the backend, and what it caches of the others (``_last_grid``)."""


def solver_arrays(solver: CollisionSolver) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
    """What the next steps read of ``solver``, to continue bit for bit after :func:`restore_solver`:
    the neighbour lists, each pair's and each ball's carried impulses, the Gauss–Seidel column
    order and the numbers they were built with. Returns (arrays by attribute name, in storage
    order; a JSON-ready description: the scalars, each array's element shape, the scratch
    arrays' shapes and types, and which attributes hold the same array)."""
    arrays: dict[str, np.ndarray] = {}
    meta: dict[str, Any] = {"values": {}, "elements": {}, "scratch": {}, "same": {}}
    seen: dict[int, str] = {}
    for name, value in vars(solver).items():
        if name in NOT_SAVED:
            continue
        if isinstance(value, ti.Ndarray):
            if id(value) in seen:
                meta["same"][name] = seen[id(value)]
                continue
            seen[id(value)] = name
            element = list(getattr(value, "element_shape", ()))
            if name in solver.SCRATCH:
                meta["scratch"][name] = [list(value.shape), element, str(value.to_numpy().dtype)]
            else:
                arrays[name] = value.to_numpy()
                meta["elements"][name] = element
        elif name == "_hash":
            meta["values"][name] = None if value is None else [[int(c) for c in v.to_list()] for v in value]
        elif value is None or isinstance(value, (bool, int, float, tuple)):
            meta["values"][name] = [int(c) for c in value] if isinstance(value, tuple) else value
        else:
            raise TypeError(f"CollisionSolver.{name} ({type(value).__name__}) cannot be saved")
    return arrays, meta


def restore_solver(solver: CollisionSolver, state: State, arrays: dict[str, np.ndarray], meta: dict[str, Any]) -> None:
    """Give ``solver`` back what :func:`solver_arrays` returned, for ``state`` restored to the same moment (its
    storage order included): the next step is then the one that the saved solver would have made."""
    if "n_upper" in arrays:
        arrays, meta = _pairs_ball_after_ball(solver, arrays, meta)
    if "surface_start" not in arrays:
        arrays, meta = _surface_rows(state, arrays, meta)
    if "n_lower" in arrays:
        arrays, meta = _lower_links(arrays, meta)
    if arrays["lam"].dtype != np.float32:  # saved before the pairs' resting impulses were kept in f32 (2026-11-27)
        arrays = {**arrays, "lam": arrays["lam"].astype(np.float32)}
    shape, element, dtype = meta["scratch"].get("impulse", [[0], [], ""])
    if element:  # saved before the sweep's table had a row per pair (until 2026-11-26: a 5-vector per pair)
        meta = {
            **meta,
            "scratch": {**meta["scratch"], "impulse": [[shape[0], pair_columns(solver.gauss_seidel)], [], dtype]},
        }
    for name, value in meta["values"].items():
        if name == "_hash":
            value = None if value is None else tuple(ti.Vector(v, dt=ti.i32) for v in value)
        elif isinstance(getattr(solver, name, None), tuple):
            value = tuple(value)
        setattr(solver, name, value)
    for name, a in arrays.items():
        setattr(solver, name, _ndarray(a.shape[: a.ndim - len(meta["elements"][name])], meta["elements"][name], a))
    for name, (shape, element, dtype) in meta["scratch"].items():
        if name not in solver.SCRATCH:  # (a table an earlier version kept)
            continue
        setattr(solver, name, _ndarray(tuple(shape), element, np.zeros(0, dtype)))
    for name, other in meta["same"].items():
        setattr(solver, name, getattr(solver, other))
    if solver.gauss_seidel and "start" not in arrays:  # saved before its steps read the last build's grid
        solver._rebuild = True  # (stale.lists_stale): build it again
    solver._ids = state.ids
    solver._packs = Packs()


_TAICHI_TYPES = {"float64": ti.f64, "float32": ti.f32, "int32": ti.i32}


def _ndarray(shape: tuple[int, ...], element: list[int], values: np.ndarray) -> ti.Ndarray:
    """A Taichi array of ``shape`` whose elements are scalars (``element`` empty) or vectors of
    ``element[0]`` entries of ``values``' type, holding ``values`` unless they are empty."""
    dtype = _TAICHI_TYPES[str(values.dtype)]
    out = ti.ndarray(ti.types.vector(element[0], dtype) if element else dtype, shape)
    if values.size:
        out.from_numpy(np.ascontiguousarray(values))
    return out


def _pairs_ball_after_ball(
    solver: CollisionSolver, arrays: dict[str, np.ndarray], meta: dict[str, Any]
) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
    """The arrays and description of a solver saved before its pair tables were laid out ball
    after ball (until 2026-11-26: a row per ball as wide as the longest list, and each list's
    length in ``n_upper``), laid out as the solver keeps them now (``first``): the same pairs
    with the same impulses, so that a run saved then continues as it would have."""
    arrays, meta = dict(arrays), {key: dict(value) if isinstance(value, dict) else value for key, value in meta.items()}
    n_upper = arrays.pop("n_upper")
    meta["elements"].pop("n_upper", None)
    width = arrays["lam"].shape[1]
    listed = np.arange(width)[None, :] < n_upper[:, None]
    pairs = int(n_upper.sum())
    capacity = len(n_upper) * width if solver.serial else max(1, pairs)  # (see CollisionSolver.build)

    def ball_after_ball(table: np.ndarray) -> np.ndarray:
        out = np.zeros((capacity, *table.shape[2:]), table.dtype)
        out[:pairs] = table[listed]
        return out

    arrays["first"] = np.concatenate([[0], np.cumsum(n_upper)]).astype(np.int32)
    meta["elements"]["first"] = []
    arrays["lam"] = ball_after_ball(arrays["lam"])
    friction = arrays["friction"]
    arrays["friction"] = (
        ball_after_ball(friction) if friction.shape[:2] == listed.shape else friction.reshape(-1, 3)[:1]
    )
    meta["values"]["pair_capacity"] = capacity
    shape, element, dtype = meta["scratch"]["impulse"]
    meta["scratch"]["impulse"] = [[capacity], element, dtype]
    return arrays, meta


def _lower_links(arrays: dict[str, np.ndarray], meta: dict[str, Any]) -> tuple[dict, dict]:
    """The arrays and description of a solver saved before its lower lists lay ball after ball
    (until 2026-11-27: a table as wide as the longest lower list, stored by column, each list's
    length in ``n_lower``, and the tables' two widths in ``capacity``), as the solver keeps them
    now: made again from the upper lists, as ``links.link_lower`` makes them (each ball's links
    to the pairs others own with it, in the order of the owners' ids)."""
    arrays, meta = dict(arrays), {key: dict(value) if isinstance(value, dict) else value for key, value in meta.items()}
    del arrays["n_lower"], arrays["lower"]
    upper, first = arrays["upper"], arrays["first"].astype(np.int64)
    n, count = len(first) - 1, np.diff(first)
    owner = np.repeat(np.arange(n), count)
    column = np.arange(int(first[-1])) - first[owner]
    other = upper[owner, column]
    bits = max(0, int(upper.shape[1] - 1).bit_length())  # (CollisionSolver.slot_bits)
    slot = (owner << bits) | column
    lower = np.zeros(int(meta["values"]["pair_capacity"]), np.int32)
    lower[: len(slot)] = slot[np.lexsort((slot, other))]
    arrays["lower"] = lower
    arrays["lower_first"] = np.concatenate([[0], np.cumsum(np.bincount(other, minlength=n))]).astype(np.int32)
    meta["elements"].pop("n_lower", None)
    meta["elements"]["lower"] = meta["elements"]["lower_first"] = []
    meta["values"]["capacity"] = int(upper.shape[1])
    return arrays, meta


def _surface_rows(state: State, arrays: dict[str, np.ndarray], meta: dict[str, Any]) -> tuple[dict, dict]:
    """The arrays and description of a solver saved before the surface impulses were kept in rows
    for the balls near a surface (until 2026-11-26: λ in ``lam_plane`` and the friction impulses
    in ``friction_plane``, a row per ball, or one placeholder under Jacobi), as the solver keeps
    them now: every ball its own row of (λ, F), which the next rebuild carries into the rows of
    the balls near a surface."""
    arrays, meta = dict(arrays), {key: dict(value) if isinstance(value, dict) else value for key, value in meta.items()}
    lam, friction = arrays.pop("lam_plane"), arrays.pop("friction_plane")
    impulse = np.zeros((*lam.shape, 4), np.float32)
    impulse[..., 0] = lam
    if friction.shape[:2] == lam.shape:  # (Gauss–Seidel)
        impulse[..., 1:] = friction
    arrays["surface_impulse"] = impulse
    arrays["surface_start"] = np.arange(state.n + 1, dtype=np.int32)
    for name in ("lam_plane", "friction_plane"):
        meta["elements"].pop(name, None)
    meta["elements"].update(surface_impulse=[4], surface_start=[])
    return arrays, meta
