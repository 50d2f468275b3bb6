"""Checks of a collision solver's record read back from a saved run (:mod:`.record`), before a
solver takes it: the description's numbers and shapes, and each array's type, shape and the
indices it holds, against the run's number of balls and the record's own sizes (``capacity``,
``pair_capacity``, ``mask``). The kernels read these arrays without bounds checks, so a record
that fails one is refused (:class:`RecordError`, naming the entry of the saved run at fault)
rather than stepped.

What the next step rewrites before reading it is not checked for its values: the lists' indices
and carried impulses when the record says the lists were never built (``valid`` false).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ti_golf.physics.types import pair_columns
from ti_golf.runtime import np_float
from ti_golf.solvers import record
from ti_golf.solvers.apart import APART_MAX
from ti_golf.solvers.contact_colour import COLOURS, ContactColours
from ti_golf.solvers.edge_colouring import UNCOLOURED
from ti_golf.solvers.gauss_seidel import GaussSeidelSolver
from ti_golf.solvers.record import SolverRecord
from ti_golf.solvers.solver import CollisionSolver
from ti_golf.solvers.sort import scan_chunks
from ti_golf.solvers.surface_rows import MIN_ROWS, ROW_ROOM

RUN = "run"
"""The saved run's entry that holds the record's description (its ``solver`` table)."""

INT32_MAX = 2**31 - 1


class RecordError(ValueError):
    """A record that a solver cannot take: ``entry``, the saved run's entry at fault (``solver.NAME``
    or ``run``), and ``reason``, what is wrong and what is allowed."""

    def __init__(self, entry: str, reason: str) -> None:
        self.entry = entry
        self.reason = reason
        super().__init__(f"entry '{entry}': {reason}")


@dataclass(frozen=True)
class Sizes:
    """What a record's arrays are measured against: the run's balls and surfaces, the kind of
    solver that takes it, and the record's own sizes."""

    n: int
    """Balls of the run."""
    columns: int
    """Surfaces a row of surface impulses holds (``surface_rows.surface_columns``)."""
    gauss_seidel: bool
    """Whether the solver sweeps Gauss–Seidel's way (its friction impulses a row per pair)."""
    capacity: int
    """Width of the neighbour table."""
    pair_capacity: int
    """Entries of the pair tables."""
    mask: int
    """The grid hash's mask (its buckets less one)."""

    @property
    def surface_rows(self) -> int:
        """The most rows a table of surface impulses has (``surface_rows.table_for`` for every ball)."""
        return max(MIN_ROWS, self.n + self.n // ROW_ROOM)


@dataclass(frozen=True)
class Taker:
    """The solver that takes a record: its balls and surfaces, and how it steps."""

    n: int
    """Balls of the run."""
    columns: int
    """Surfaces a row of surface impulses holds (``surface_rows.scene_surface_columns``)."""
    serial: bool
    """Whether it steps serially."""
    gauss_seidel: bool
    """Whether it sweeps Gauss–Seidel's way."""
    blocks: bool
    """Whether it sweeps by blocks of grid columns (``col_ids``, ``col_colour``, ``col_start``)."""


def read_record(arrays: dict[str, np.ndarray], meta: Any, taker: Taker) -> SolverRecord:
    """The record of a saved run's ``solver.NAME`` arrays (``arrays``, without the prefix) and
    description ``meta`` (:func:`.record.from_file`) for the solver ``taker``, checked; or
    :class:`RecordError`."""
    check_description(meta)
    lam = arrays.get("lam")
    if not isinstance(lam, np.ndarray) or lam.dtype.kind != "f":
        what = "missing" if lam is None else f"dtype {lam.dtype}" if isinstance(lam, np.ndarray) else "not an array"
        raise RecordError("solver.lam", f"{what}; expects the pairs' resting impulses, floating-point numbers")
    if "surface_start" not in arrays and "lam_plane" not in arrays:
        raise RecordError("solver.surface_start", "missing; the collision solver's record holds it")
    try:
        converted = record.from_file(arrays, meta, taker.n, taker.serial, taker.gauss_seidel)
    except (KeyError, IndexError, ValueError, TypeError, AttributeError) as exc:  # an older layout, laid out anew
        raise RecordError(
            _legacy_entry(arrays), f"an older layout of the lists that cannot be laid out anew ({exc!r})"
        ) from None
    check_record(converted, taker)
    return converted


def _legacy_entry(arrays: dict[str, np.ndarray]) -> str:
    """The entry that marks the older layout :func:`.record.from_file` lays out anew."""
    if "n_upper" in arrays:
        return "solver.n_upper"
    if "surface_start" not in arrays:
        return "solver.lam_plane"
    return "solver.n_lower" if "n_lower" in arrays else RUN


def check_description(meta: Any) -> None:
    """The record's description: a table of ``values``, ``elements`` (each a list of whole
    numbers) and ``scratch`` (each [shape, element shape, type])."""
    if not isinstance(meta, dict):
        raise RecordError(RUN, f"'solver' is {_short(meta)}; expects a table (the collision solver's record) or null")
    for key in ("values", "elements", "scratch"):
        if not isinstance(meta.get(key), dict):
            raise RecordError(RUN, f"'solver.{key}' is {_short(meta.get(key))}; expects a table")
    for name, element in meta["elements"].items():
        if not (isinstance(element, list) and all(_is_whole(e) and 0 < e <= 16 for e in element)):
            raise RecordError(RUN, f"'solver.elements.{name}' is {_short(element)}; expects [] or [k], 0 < k <= 16")
    for name, entry in meta["scratch"].items():
        ok = isinstance(entry, list) and len(entry) == 3 and all(isinstance(p, list) for p in entry[:2])
        if not ok or not all(_is_whole(s) and s >= 0 for s in entry[0] + entry[1]) or not isinstance(entry[2], str):
            raise RecordError(RUN, f"'solver.scratch.{name}' is {_short(entry)}; expects [shape, element shape, type]")
    for key in ("serial", "reorder"):
        if not isinstance(meta.get(key), bool):
            raise RecordError(RUN, f"'solver.{key}' is {_short(meta.get(key))}; expects true or false")
    if meta["serial"] and meta["reorder"]:
        raise RecordError(
            RUN, "'solver.serial' and 'solver.reorder' are both true; a serial solver keeps the balls in id order"
        )


def check_record(rec: SolverRecord, taker: Taker) -> None:
    """A record in the layout a solver keeps now (:func:`.record.from_file`'s), for the solver
    ``taker``: its numbers, its scratch arrays' shapes, its arrays' types and shapes, and (once
    the lists were built) the indices and impulses they hold."""
    sizes = _sizes(rec.values, taker.n, taker.columns, taker.gauss_seidel)
    valid = _check_values(rec.values, sizes)
    colours = _colour_values(rec.values)
    _check_scratch(rec.scratch, sizes, valid)
    stepping = valid and not rec.values.get("rebuild", True)  # (the next step reads the lists as they are)
    _check_shapes(rec, sizes, stepping and taker.blocks, colours)
    _check_surfaces(rec.arrays)
    if valid:
        _check_lists(rec.arrays, sizes, int(rec.values.get("n_apart", 0)))
        if "col_ids" in rec.arrays:
            _check_columns(rec.arrays, sizes.n)
        if colours:
            _check_colours(rec, sizes)


# -- the numbers ----------------------------------------------------------------------------------
def _sizes(values: dict[str, Any], n: int, columns: int, gauss_seidel: bool) -> Sizes:
    """The record's sizes, each checked: ``capacity`` (1 to n − 1: a list holds each other ball
    once at most), ``pair_capacity`` and ``mask`` (a power of two, at least 16, less one)."""
    capacity = _value(values, "capacity", 1, max(1, n - 1), required=True)
    pair_capacity = _value(values, "pair_capacity", 1, INT32_MAX, required=True)
    mask = _value(values, "mask", 15, INT32_MAX - 1, required=True)
    if (mask + 1) & mask:
        raise RecordError(RUN, f"solver value 'mask' is {mask}; expects a power of two less one")
    return Sizes(n, columns, gauss_seidel, capacity, pair_capacity, mask)


_POSITIVE_FINITE = ("r_max", "r_ref", "h", "cell")
"""Numbers finite and > 0: radii [m], the time step [s], the cell size [m]."""
_POSITIVE = ("r_cut", "v_cut")
"""Numbers > 0, infinite allowed: the radius [m] and speed [m/s] above which a ball is set apart."""
_COUNTS = ("rebuilds", "still_steps", "far_owners")
"""Whole numbers >= 0."""
_FLAGS = ("skip_still", "valid", "rebuild", "amendable")
"""True or false."""


def _check_values(values: dict[str, Any], sizes: Sizes) -> bool:
    """The numbers the solver takes (those the record lacks keep the solver's own); returns
    ``valid``, whether the lists were built."""
    for name in _POSITIVE_FINITE + _POSITIVE:
        if name in values:
            v = values[name]
            finite = name in _POSITIVE_FINITE
            if not _is_number(v) or not v > 0 or (finite and not math.isfinite(v)):
                raise RecordError(
                    RUN, f"solver value {name!r} is {_short(v)}; expects a {'finite ' if finite else ''}number > 0"
                )
    if "skin" in values and not (_is_number(values["skin"]) and 0 <= values["skin"] < math.inf):
        raise RecordError(RUN, f"solver value 'skin' is {_short(values['skin'])}; expects a finite number >= 0")
    for name in _COUNTS:
        _value(values, name, 0, None)
    _value(values, "n_apart", 0, APART_MAX)
    for name in _FLAGS:
        if name in values and not isinstance(values[name], bool):
            raise RecordError(RUN, f"solver value {name!r} is {_short(values[name])}; expects true or false")
    hashed = values.get("hash")
    if hashed is not None and not (
        isinstance(hashed, list)
        and len(hashed) == 2
        and all(
            isinstance(v, list) and len(v) == 3 and all(_is_whole(c) and abs(c) <= INT32_MAX for c in v) for v in hashed
        )
    ):
        raise RecordError(
            RUN, f"solver value 'hash' is {_short(hashed)}; expects null or [[3 whole numbers], [3 whole numbers]]"
        )
    valid = bool(values.get("valid", False))
    if valid and hashed is None:
        raise RecordError(
            RUN, "solver value 'hash' is missing or null; a record of lists that were built gives the grid's hash"
        )
    return valid


def _value(values: dict[str, Any], name: str, lo: int, hi: int | None, required: bool = False) -> int:
    """The whole number ``values[name]`` in [lo, hi] (``hi`` None: no bound), or ``lo`` when the
    record lacks it and it is not ``required``."""
    if name not in values:
        if required:
            raise RecordError(RUN, f"solver value {name!r} is missing; expects a whole number")
        return lo
    v = values[name]
    if not _is_whole(v) or v < lo or (hi is not None and v > hi):
        allowed = f">= {lo}" if hi is None else f"in [{lo}, {hi}]"
        raise RecordError(RUN, f"solver value {name!r} is {_short(v)}; expects a whole number {allowed}")
    return int(v)


# -- shapes and types -----------------------------------------------------------------------------
def _expected_scratch(sizes: Sizes) -> dict[str, tuple[tuple[int, ...], list[int], str]]:
    """The shape, element shape and type of each scratch array of a solver of ``sizes`` (the
    surface impulses' second table: rows of its own, see :func:`_check_scratch`)."""
    n, f = sizes.n, np.dtype(np_float()).name
    table = "float32" if sizes.gauss_seidel else f  # (types.pair_table_type)
    return {
        "x_free": ((n,), [3], f),
        "v_free": ((n,), [3], f),
        "calm": ((n,), [], f),
        "clear": ((n,), [], "float32"),
        "rank": ((n,), [], "int32"),
        "chunk_start": ((scan_chunks(sizes.mask + 1),), [], "int32"),
        "impulse": ((sizes.pair_capacity, pair_columns(sizes.gauss_seidel)), [], table),
        "impact": ((n,), [], "int32"),
        "stash_first": ((n + 1,), [], "int32"),
        "pair_chunk": ((scan_chunks(n),), [], "int32"),
    }


def _check_scratch(scratch: dict[str, list[Any]], sizes: Sizes, valid: bool) -> None:
    """Each scratch array the record gives a shape: the shape and type a solver of ``sizes`` makes
    it in (a step writes it before reading it, so too small a table would be written past its end);
    the sweep's table (``impulse``, which a solver makes at its first build) given once the
    lists were built."""
    if valid and "impulse" not in scratch:
        raise RecordError(RUN, "solver scratch 'impulse' is missing; a record of lists that were built gives its shape")
    expected = _expected_scratch(sizes)
    for name, (shape, element, dtype) in scratch.items():
        if name == "surface_impulse_back":
            ok = len(shape) == 2 and 1 <= shape[0] <= sizes.surface_rows and shape[1] == sizes.columns
            want = f"[rows, {sizes.columns}], [4], float32 with 1 <= rows <= {sizes.surface_rows}"
            if ok and list(element) == [4] and dtype == "float32":
                continue
        elif name in expected:
            shape0, element0, dtype0 = expected[name]
            if tuple(shape) == shape0 and list(element) == element0 and dtype == dtype0:
                continue
            want = f"{list(shape0)}, {element0}, {dtype0}"
        else:
            continue  # (no solver reads it)
        raise RecordError(
            RUN, f"solver scratch {name!r} is {[shape, element, dtype]}; expects {want} for {sizes.n} balls"
        )


def _expected_shapes(rec: SolverRecord, sizes: Sizes) -> dict[str, tuple[str, tuple[int, ...], str]]:
    """The type, shape and what fixes it of each kept array (the surface impulses: rows of their
    own; the Gauss–Seidel columns and colours: see :func:`_check_shapes`)."""
    n, cap, pairs = sizes.n, sizes.capacity, sizes.pair_capacity
    balls = f"the run has {n} balls"
    shapes = {
        "sorted_ids": ("int32", (n,), balls),
        "start": ("int32", (sizes.mask + 2,), f"the record's mask is {sizes.mask}"),
        "x_at_build": ("float32", (n, 3), balls),
        "drift": ("float32", (n,), balls),
        "upper": ("int32", (n, cap), f"{balls} and the record's capacity is {cap}"),
        "first": ("int32", (n + 1,), balls),
        "lam": ("float32", (pairs,), f"the record's pair_capacity is {pairs}"),
        "lower": ("int32", (pairs,), f"the record's pair_capacity is {pairs}"),
        "lower_first": ("int32", (n + 1,), balls),
        "surface_start": ("int32", (n + 1,), balls),
        "flag": ("int32", (2,), "a solver keeps 2 flags"),
        "apart_ids": ("int32", (APART_MAX + 1,), f"a solver sets {APART_MAX} balls apart at most"),
        "friction": (
            ("float32", (pairs, 3), f"the record's pair_capacity is {pairs}")
            if sizes.gauss_seidel or _rows(rec.arrays.get("friction")) == pairs  # (Jacobi: the next build drops them)
            else ("float32", (1, 3), "the Jacobi sweeps keep no friction impulses")
        ),
        "col_ids": ("int32", (n,), balls),
        "col_colour": ("int32", (n,), balls),
    }
    start = rec.arrays.get("col_start")
    if isinstance(start, np.ndarray) and start.ndim == 1:
        buckets = max(16, 1 << max(0, int(start.shape[0]) - 2).bit_length())
        shapes["col_start"] = ("int32", (buckets + 1,), "the columns' buckets are a power of two, at least 16")
        shapes["col_chunk"] = ("int32", (scan_chunks(buckets),), f"the columns have {buckets} buckets")
    return shapes


def _rows(a: Any) -> int | None:
    """The rows of the array ``a`` (its first axis), or ``None`` for no array or one number."""
    return int(a.shape[0]) if isinstance(a, np.ndarray) and a.ndim > 0 else None


REQUIRED = tuple(name for name in CollisionSolver.SAVED_ARRAYS if name != "upper")
"""The arrays every record holds (a solver makes them; ``upper`` at its first build)."""
BLOCKS = tuple(name for name in GaussSeidelSolver.SAVED_ARRAYS if name not in CollisionSolver.SAVED_ARRAYS)
"""The arrays of a solver that sweeps by blocks of grid columns, once its lists were built."""


def _check_shapes(rec: SolverRecord, sizes: Sizes, blocks: bool, colours: bool) -> None:
    """Each array present (``upper`` once the lists were built, with ``blocks`` those of the
    blocks of columns, and with ``colours``, the record's colours' numbers, all their tables or
    none), with the type, shape and element shape a solver of ``sizes`` makes it in (the
    ``elements`` of the description agreeing)."""
    arrays = rec.arrays
    built = ("upper",) if rec.values.get("valid") else ()
    for name in REQUIRED + built:
        if name not in arrays:
            raise RecordError(f"solver.{name}", "missing; the collision solver's record holds it")
    for name in BLOCKS if blocks else ():
        if name not in arrays:
            raise RecordError(
                f"solver.{name}",
                "missing; the next step sweeps the balls by blocks of grid columns, whose order it holds (a run "
                "saved with the contacts layout, or on a GPU, continues on the backend and layout it was saved with)",
            )
    if "col_start" in arrays and "col_chunk" not in arrays:
        raise RecordError("solver.col_chunk", "missing; the record holds the columns' buckets (solver.col_start)")
    if colours and any(name.startswith("colours.") for name in arrays):
        missing = [name for name in ContactColours.TABLES if f"colours.{name}" not in arrays]
        if missing:
            raise RecordError(f"solver.colours.{missing[0]}", "missing; the record holds the other colour tables")
        if rec.values["colours.room"] < 1:
            raise RecordError(RUN, "solver value 'colours.room' is 0; expects at least 1 with the colour tables")
    shapes = _expected_shapes(rec, sizes)
    for name, a in arrays.items():
        if name == "surface_impulse":
            rows = a.shape[0] if isinstance(a, np.ndarray) and a.ndim == 3 else 0
            table = (min(max(rows, 1), sizes.surface_rows), sizes.columns, 4)
            why = f"the scene has {sizes.columns} surface column(s), and 1 to {sizes.surface_rows} rows"
            _check_array(name, a, "float32", table, why, rec.elements.get(name))
        elif name in shapes:
            dtype, shape, why = shapes[name]
            _check_array(name, a, dtype, shape, why, rec.elements.get(name))
        elif colours and name.startswith("colours.") and name.split(".", 1)[1] in ContactColours.TABLES:
            why = f"the record's colours.room is {rec.values['colours.room']}"
            _check_array(name, a, "int32", _colour_shape(name, rec.values), why, rec.elements.get(name))


def _check_array(name: str, a: Any, dtype: str, shape: tuple[int, ...], why: str, element: list[int] | None) -> None:
    """``a`` a numpy array of ``dtype`` and ``shape``, whose description's element shape is its
    last axes (none for one number an entry)."""
    entry = f"solver.{name}"
    if not isinstance(a, np.ndarray):
        raise RecordError(entry, "is not an array")
    if a.dtype != np.dtype(dtype):  # (native byte order: Taichi takes no other)
        raise RecordError(entry, f"dtype {a.dtype}; expects {dtype}")
    if a.shape != shape:
        raise RecordError(entry, f"shape {a.shape} but {why} (expects {shape})")
    want = [3] if name in ("x_at_build", "friction") else [4] if name == "surface_impulse" else []
    if element != want:
        raise RecordError(RUN, f"'solver.elements.{name}' is {_short(element)}; expects {want}")


def _colour_shape(name: str, values: dict[str, Any]) -> tuple[int, ...]:
    """The shape of the colours' table ``colours.NAME`` (``contact_colour.ColourTables``)."""
    table = name.split(".", 1)[1]
    if table == "count":
        return (1,)
    if table == "start":
        return (COLOURS + 2,)
    if table == "fill":
        return (COLOURS + 1,)
    return (int(values["colours.room"]),)


# -- the lists' contents --------------------------------------------------------------------------
def _check_lists(arrays: dict[str, np.ndarray], sizes: Sizes, n_apart: int) -> None:
    """The lists of the last build: ball ids within the run, each list's pairs within the pair
    tables, each lower-list link to a pair its owner lists, finite impulses and positions."""
    n = sizes.n
    _within("sorted_ids", arrays["sorted_ids"], 0, n - 1)
    _offsets("start", arrays["start"], n, "the run's balls")
    _finite("x_at_build", arrays["x_at_build"])
    _finite("drift", arrays["drift"])
    if np.any(arrays["drift"] < 0.0):
        raise RecordError("solver.drift", f"holds {float(arrays['drift'].min()):.4g}; expects distances >= 0")
    first = _offsets("first", arrays["first"], sizes.pair_capacity, "the record's pair_capacity", starts=True)
    count = np.diff(first)
    if count.size and count.max() > sizes.capacity:
        ball = int(np.argmax(count))
        raise RecordError(
            "solver.first",
            f"lists {int(count[ball])} pairs for ball {ball}; expects at most capacity, {sizes.capacity}",
        )
    upper = arrays["upper"]
    listed = np.arange(upper.shape[1])[None, :] < count[:, None]
    _within("upper", upper[listed], 0, n - 1)
    lower_first = _offsets(
        "lower_first", arrays["lower_first"], sizes.pair_capacity, "the record's pair_capacity", starts=True
    )
    bits = max(0, int(sizes.capacity - 1).bit_length())
    slots = arrays["lower"][: int(lower_first[-1])].astype(np.int64)
    _within("lower", slots, 0, (n << bits) - 1)
    owner, column = slots >> bits, slots & ((1 << bits) - 1)
    if np.any(column >= count[owner]):
        k = int(np.argmax(column >= count[owner]))
        raise RecordError(
            "solver.lower",
            f"links to column {int(column[k])} of ball {int(owner[k])}'s list, which holds {int(count[owner[k]])}",
        )
    for name in ("lam", "friction"):
        _finite(name, arrays[name])
    _within("apart_ids", arrays["apart_ids"][:n_apart], 0, n - 1)


def _check_surfaces(arrays: dict[str, np.ndarray]) -> None:
    """Each ball's row of surface impulses within their table, and the impulses finite (read at
    every step of a serial solver, lists built or not)."""
    impulse = arrays.get("surface_impulse")
    rows = impulse.shape[0] if impulse is not None else 0
    _offsets("surface_start", arrays["surface_start"], rows, "the rows of solver.surface_impulse", starts=True)
    if impulse is not None:
        _finite("surface_impulse", impulse)


def _check_columns(arrays: dict[str, np.ndarray], n: int) -> None:
    """The Gauss–Seidel sweeps' blocks of columns (``colour.column_order``): each ball once, its
    block's colour 0 to 3, the buckets' starts within the balls."""
    ids = arrays["col_ids"]
    if not np.array_equal(np.sort(ids), np.arange(n)):
        raise RecordError("solver.col_ids", f"expects each ball id from 0 to {n - 1} once")
    _within("col_colour", arrays["col_colour"], 0, 3)
    if "col_start" in arrays:
        _offsets("col_start", arrays["col_start"], n, "the run's balls")


def _colour_values(values: dict[str, Any]) -> bool:
    """The contact colours' numbers (``contact_colour.ContactColours.saved``), all or none;
    returns whether the record holds them."""
    if not any(name.startswith("colours.") for name in values):
        return False
    for name in ("builds", "rounds", "rounds_max", "n", "used", "room"):
        _value(values, f"colours.{name}", 0, INT32_MAX, required=True)
    return True


def _check_colours(rec: SolverRecord, sizes: Sizes) -> None:
    """The contact colours' tables, when the record holds them, of lists that were built: each
    listed pair's owner and colour, and the pairs laid out colour by colour within the pair
    tables."""
    if "colours.owner" not in rec.arrays:
        return
    a = {name: rec.arrays[f"colours.{name}"] for name in ContactColours.TABLES}
    room = int(rec.values["colours.room"])
    pairs = int(rec.arrays["first"][-1])
    if room < pairs:
        raise RecordError(RUN, f"solver value 'colours.room' is {room}; expects at least the {pairs} pairs listed")
    _within("colours.owner", a["owner"][:pairs], 0, sizes.n - 1)
    for name in ("colour", "colour_b", "propose", "propose_b"):
        _within(f"colours.{name}", a[name][:pairs], UNCOLOURED, COLOURS)
    laid = _offsets("colours.start", a["start"], min(room, sizes.pair_capacity), "the pair tables", starts=True)
    _within("colours.pairs", a["pairs"][: int(laid[-1])], 0, pairs - 1)
    _within("colours.count", a["count"], 0, room)
    _within("colours.fresh", a["fresh"][: int(a["count"][0])], 0, max(0, pairs - 1))


def _within(name: str, a: np.ndarray, lo: int, hi: int) -> None:
    """Every entry of ``a`` (a part of ``solver.NAME``) in [lo, hi]."""
    bad = (a < lo) | (a > hi)
    if np.any(bad):
        value = a.ravel()[int(np.argmax(bad.ravel()))]
        raise RecordError(f"solver.{name}", f"holds {value}; expects entries in [{lo}, {hi}]")


def _offsets(name: str, a: np.ndarray, last: int, of: str, starts: bool = False) -> np.ndarray:
    """``a``, the starts of consecutive runs: never decreasing, within [0, last] (``of`` names what
    bounds it), from 0 when ``starts``."""
    offsets = a.astype(np.int64)
    if offsets.size and ((starts and offsets[0] != 0) or offsets.min() < 0 or offsets.max() > last):
        raise RecordError(
            f"solver.{name}", f"runs from {offsets[0]} to {offsets.max()}; expects starts from 0 to {last} ({of})"
        )
    if np.any(np.diff(offsets) < 0):
        k = int(np.argmax(np.diff(offsets) < 0))
        raise RecordError(f"solver.{name}", f"decreases at entry {k + 1}; expects starts that never decrease")
    return offsets


def _finite(name: str, a: np.ndarray) -> None:
    """No NaN or infinity in ``solver.NAME``."""
    if not np.all(np.isfinite(a)):
        raise RecordError(f"solver.{name}", "holds NaN or infinite values; expects finite numbers")


def _is_whole(v: Any) -> bool:
    """Whether ``v`` is a whole number of JSON (not true or false)."""
    return isinstance(v, int) and not isinstance(v, bool)


def _is_number(v: Any) -> bool:
    """Whether ``v`` is a number of JSON (not true or false)."""
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def _short(v: Any) -> str:
    """``v`` as JSON writes it, cut to 60 characters."""
    text = repr(v)
    return text if len(text) <= 60 else text[:57] + "..."
