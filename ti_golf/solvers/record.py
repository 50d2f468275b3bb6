"""A collision solver's state saved with a run (:mod:`ti_golf.sim.saved_run`) and given back to a
new solver: the neighbour lists, the carried impulses and the numbers they were built with, so
that a run loaded again continues bit for bit (what a solver keeps: :class:`Recorded`).

The record is versioned (:data:`VERSION`). In a saved run it is the ``solver`` entry of the run's
description, ``{"version", "values", "elements", "scratch"}`` (the numbers by name; each kept
array's element shape; each scratch array's shape, element shape and type), beside the arrays
``solver.NAME``. Version 1, without ``version``, is what the solver's attributes were, saved
whole (``_r_max``, ``_valid``, ``_rebuild``, ``_hash`` among its numbers); earlier layouts of its
tables are laid out anew as they are read (:func:`from_file`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np
import taichi as ti

from ti_golf.physics.types import pair_columns

VERSION = 2
"""The version of the record that :func:`to_file` writes."""

READS = (1, 2)
"""The versions that :func:`from_file` reads."""


@dataclass
class SolverRecord:
    """What the next steps read of a solver (:meth:`.solver.CollisionSolver.record`): the numbers,
    the arrays kept whole (in storage order) and the scratch arrays' shapes."""

    values: dict[str, Any]
    """Numbers by name (:attr:`Recorded.SAVED_VALUES`), and ``hash``: the grid hash's (origin,
    stride) as two lists of ints, or ``None``."""
    arrays: dict[str, np.ndarray]
    """The arrays kept whole, by name (:attr:`Recorded.SAVED_ARRAYS`)."""
    elements: dict[str, list[int]]
    """Each array's element shape ([] for scalars, [3] for 3-vectors)."""
    scratch: dict[str, list[Any]] = field(default_factory=dict)
    """Each scratch array's [shape, element shape, numpy type]."""
    rebuild: bool = False
    """Whether the lists must be built again before the next step (a record too old to hold what
    the steps read of the last build)."""

    def ndarray(self, name: str) -> ti.Ndarray:
        """A Taichi array holding the kept array ``name``."""
        a, element = self.arrays[name], self.elements[name]
        return _ndarray(a.shape[: a.ndim - len(element)], element, a)

    def scratch_array(self, name: str) -> ti.Ndarray:
        """A Taichi array of the shape and type of the scratch array ``name`` (not filled)."""
        shape, element, dtype = self.scratch[name]
        return _ndarray(tuple(shape), element, np.zeros(0, dtype))


class Recorded:
    """What a saved run keeps of a collision solver (:class:`.solver.CollisionSolver`), by the
    names of the solver's public attributes: the numbers of ``SAVED_VALUES``, the arrays of
    ``SAVED_ARRAYS`` kept whole, and the shapes and types of the ``SCRATCH`` arrays.
    :meth:`record` reads them, :meth:`restore` sets them again; a solver adds what else its steps
    read (the grid hash) in its own."""

    SAVED_VALUES: ClassVar[dict[str, str]] = {
        "r_max": "r_max",
        "r_cut": "r_cut",
        "r_ref": "r_ref",
        "skin": "skin",
        "v_cut": "v_cut",
        "h": "h",
        "cell": "cell",
        "mask": "mask",
        "capacity": "capacity",
        "rebuilds": "rebuilds",
        "still_steps": "still_steps",
        "pair_capacity": "pair_capacity",
        "n_apart": "n_apart",
        "skip_still": "skip_still",
        "far_owners": "far_owners",
        "valid": "lists_valid",
        "rebuild": "rebuild_due",
        "amendable": "amendable",
    }
    """The numbers a saved run keeps (:meth:`record`), by their name in the record: the
    attributes that hold them. (The grid hash, a pair of vectors, is kept as ``hash``.)"""

    SAVED_ARRAYS: ClassVar[tuple[str, ...]] = (
        "sorted_ids",
        "start",
        "x_at_build",
        "drift",
        "upper",
        "first",
        "lam",
        "lower",
        "lower_first",
        "surface_start",
        "surface_impulse",
        "flag",
        "apart_ids",
        "friction",
    )
    """The arrays a saved run keeps whole (:meth:`record`): the lists, the carried impulses and the
    grid of the last build."""

    SCRATCH: ClassVar[tuple[str, ...]] = (
        "x_free",
        "v_free",
        "calm",
        "clear",
        "rank",
        "chunk_start",
        "impulse",
        "impact",
        "stash_first",
        "pair_chunk",
        "surface_impulse_back",
    )
    """Arrays that each step or list build writes before it reads them: a saved run keeps only
    their shapes and types."""

    def record(self) -> SolverRecord:
        """The numbers of ``SAVED_VALUES``, the arrays of ``SAVED_ARRAYS`` (those made) and the
        shapes and types of the ``SCRATCH`` arrays."""
        values: dict[str, Any] = {name: getattr(self, attr) for name, attr in self.SAVED_VALUES.items()}
        arrays, elements, scratch = {}, {}, {}
        for name in self.SAVED_ARRAYS:
            a = getattr(self, name, None)  # (a serial Gauss–Seidel solver has no column order)
            if a is not None:
                arrays[name] = a.to_numpy()
                elements[name] = list(getattr(a, "element_shape", ()))
        for name in self.SCRATCH:
            a = getattr(self, name)
            if a is not None:
                scratch[name] = [list(a.shape), list(getattr(a, "element_shape", ())), str(a.to_numpy().dtype)]
        return SolverRecord(values, arrays, elements, scratch)

    def restore(self, record: SolverRecord, state: Any) -> None:
        """Take back what :meth:`record` returned (for ``state`` restored to the same moment): what
        the record lacks keeps the value the solver was made with."""
        for name, attribute in self.SAVED_VALUES.items():
            if name in record.values:
                setattr(self, attribute, record.values[name])
        for name in self.SAVED_ARRAYS:
            if name in record.arrays:
                setattr(self, name, record.ndarray(name))
        for name in self.SCRATCH:
            if name in record.scratch:
                setattr(self, name, record.scratch_array(name))


def to_file(record: SolverRecord) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
    """The arrays (by name, without the ``solver.`` prefix) and the JSON-ready description that a
    saved run holds of ``record``."""
    meta = {"version": VERSION, "values": record.values, "elements": record.elements, "scratch": record.scratch}
    return dict(record.arrays), meta


def unreadable(meta: dict[str, Any]) -> str | None:
    """Why a saved solver described by ``meta`` cannot be read (a version this code does not know),
    or ``None``."""
    version = meta.get("version", 1)
    if version in READS:
        return None
    return f"holds a collision solver saved in record version {version!r}; this ti-golf reads versions {READS[0]} to {READS[-1]}"


def from_file(
    arrays: dict[str, np.ndarray], meta: dict[str, Any], n: int, serial: bool, gauss_seidel: bool
) -> SolverRecord:
    """The record that :func:`to_file` wrote (any version of :data:`READS`; see
    :func:`unreadable`) for ``n`` balls, given back to a solver that steps ``serial`` or not with
    the ``gauss_seidel`` sweeps or not: older layouts of the tables laid out as the solver keeps
    them now, the same pairs with the same impulses."""
    if "n_upper" in arrays:
        arrays, meta = _pairs_ball_after_ball(serial, arrays, meta)
    if "surface_start" not in arrays:
        arrays, meta = _surface_rows(n, arrays, meta)
    if "n_lower" in arrays:
        arrays, meta = _lower_links(arrays, meta)
    if arrays["lam"].dtype != np.float32:  # saved before the pairs' resting impulses were kept in f32 (2026-11-27)
        arrays = {**arrays, "lam": arrays["lam"].astype(np.float32)}
    scratch = dict(meta["scratch"])
    shape, element, dtype = scratch.get("impulse", [[0], [], ""])
    if element:  # saved before the sweep's table had a row per pair (until 2026-11-26: a 5-vector per pair)
        scratch["impulse"] = [[shape[0], pair_columns(gauss_seidel)], [], dtype]
    if gauss_seidel and "impulse" in scratch and scratch["impulse"][2] != "float32":  # saved before 2026-11-30
        scratch["impulse"] = [[shape[0], pair_columns(gauss_seidel)], [], "float32"]  # (its values: a step's)
    values = dict(meta["values"])
    elements = dict(meta["elements"])
    if "drift" not in arrays:  # saved before a build kept the lists of balls that had not moved (2026-11-30)
        arrays = {**arrays, "drift": np.zeros(n, np.float32)}  # (every list was made at the last build)
        elements["drift"] = []
    if meta.get("version", 1) == 1:  # the attributes' names, and arrays that were one another
        values = {name.lstrip("_"): value for name, value in values.items()}
        for name, other in meta.get("same", {}).items():
            arrays = {**arrays, name: arrays[other]}
            elements[name] = elements[other]
    rebuild = gauss_seidel and "start" not in arrays  # saved before its steps read the last build's grid
    return SolverRecord(values, arrays, elements, scratch, rebuild)


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
    serial: bool, arrays: dict[str, np.ndarray], meta: dict[str, Any]
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
    capacity = len(n_upper) * width if serial else max(1, pairs)  # (see CollisionSolver.build)

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


def _surface_rows(n: int, arrays: dict[str, np.ndarray], meta: dict[str, Any]) -> tuple[dict, dict]:
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
    arrays["surface_start"] = np.arange(n + 1, dtype=np.int32)
    for name in ("lam_plane", "friction_plane"):
        meta["elements"].pop(name, None)
    meta["elements"].update(surface_impulse=[4], surface_start=[])
    return arrays, meta
