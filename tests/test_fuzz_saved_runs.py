"""Fuzzed saved runs: every edited, damaged or cut-short run file either loads into a simulation
whose state is finite and steps, or is refused in one line naming the file.

Property-based (hypothesis), as ``test_fuzz.py`` does it for scene files: each case starts from
one of two small real runs (made once per module: the default collision solver, serial, with
tracked balls; and the Jacobi sweeps in parallel, storing the balls in grid order), then drops
entries, pokes NaN, infinite, negative, huge or out-of-range numbers into arrays, replaces arrays
with others of any shape and type, sets fields of the ``run`` description (the scene, the
solver's numbers and shapes) to any JSON value, and cuts, flips or extends the file's bytes. A
case must load, or raise ``ConfigError`` with one line starting with the file's path; any other
exception is a defect. A run that loads must step: it may stop there with ``SimulationError``
only as a scene of the same finite numbers would (1e300 m/s goes non-finite in a step), never
with NaN in the state it loaded. Derandomised and bounded, as ``test_fuzz.py``.
"""

from __future__ import annotations

import contextlib
import math
import tempfile
from pathlib import Path

import numpy as np
import pytest
from conftest import read_saved_run, write_saved_run
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

import ti_golf as tg
from ti_golf.errors import ConfigError, SimulationError
from ti_golf.solvers import CollisionSolver

FUZZ = settings(
    max_examples=300, derandomize=True, deadline=None, database=None, suppress_health_check=list(HealthCheck)
)

R = 0.02
SPECIAL = [math.nan, math.inf, -math.inf, -1, 0, -0.0, 1e-300, 1e300, -1e300, 3, 4, 5, 7, 2**31 - 1, -(2**31), 10**6]
"""Numbers poked into arrays: non-finite, negative, zero, tiny, huge, and past every index."""
DTYPES = ["float64", "float32", ">f8", "int32", "int64", ">i4", "bool", "complex128", "<U3", "S2"]

json_values = st.recursive(
    st.one_of(
        st.none(),
        st.booleans(),
        st.integers(min_value=-(2**40), max_value=2**40),
        st.floats(allow_nan=True, allow_infinity=True),
        st.text(max_size=6),
        st.sampled_from([0, 1, 2, 3, 15, 63, 64, [], [0], [3], [[4], [3], "float64"]]),
    ),
    lambda inner: st.one_of(st.lists(inner, max_size=3), st.dictionaries(st.text(max_size=4), inner, max_size=2)),
    max_leaves=6,
)


def _pile(solver: str, **kwargs) -> tg.Simulation:
    """Three balls touching on the ground and one flying and spinning over them, no air."""
    scene = tg.load_scene(None, data={"air": {"rho": 0.0}, "world": {"dt": 0.001}, "contact": {"solver": solver}})
    x = [[0.0, R, 0.0], [2 * R, R, 0.0], [4 * R, R, 0.0], [0.0, 0.3, 0.2]]
    v = [[0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [1.0, 1.0, -1.0]]
    w = [[0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 50.0]]
    return tg.Simulation(scene, x=x, v=v, w=w, **kwargs)


@pytest.fixture(scope="module")
def bases(tmp_path_factory) -> list[Path]:
    """Two runs saved after 15 steps: the default solver (serial) with two balls tracked, and the
    Jacobi sweeps in parallel storing the balls in grid order (``order``)."""
    folder = tmp_path_factory.mktemp("bases")
    tracked = _pile("gauss_seidel", track=[True, False, False, True])
    jacobi = _pile("jacobi", track=False)
    jacobi.solver = CollisionSolver(jacobi.model, serial=False, reorder=True)
    paths = []
    for name, sim in (("tracked", tracked), ("jacobi", jacobi)):
        sim.run(steps=15)
        paths.append(folder / f"{name}.npz")
        sim.save(paths[-1])
    return paths


def _paths(meta: dict, depth: int = 3) -> list[tuple[str, ...]]:
    """Every key of the ``run`` description as a path of keys, tables to ``depth``."""
    out = []
    for key, value in meta.items():
        out.append((key,))
        if isinstance(value, dict) and depth > 1:
            out += [(key, *p) for p in _paths(value, depth - 1)]
    return out


def _set_path(meta: dict, path: tuple[str, ...], value) -> None:
    table = meta
    for key in path[:-1]:
        table = table[key]
    table[path[-1]] = value


def _scrambled(a: np.ndarray, seed: int) -> np.ndarray:
    """``a``'s shape and type, with numbers drawn anew: whole numbers from −5 to twice the
    largest, or floats of any sign, a few of them NaN or huge."""
    rng = np.random.default_rng(seed)
    if a.dtype.kind in "iu":
        hi = max(5, 2 * int(np.abs(a).max(initial=0)))
        return rng.integers(-5, hi, a.shape).astype(a.dtype)
    if a.dtype.kind == "f":
        out = rng.normal(0, 10.0 ** rng.integers(-3, 6), a.shape)
        out[rng.random(a.shape) < 0.05] = np.nan
        return out.astype(a.dtype)
    return a


def _edit_arrays(draw, data: dict, meta: dict) -> None:
    """One edit of the arrays or the description, drawn."""
    kind = draw(st.sampled_from(["drop", "poke", "replace", "scramble", "meta", "meta"]))
    name = draw(st.sampled_from(sorted(data)))
    a = data[name]
    if kind == "drop":
        del data[name]
    elif kind == "poke" and a.size and a.dtype.kind in "fiub":
        a = a.copy()
        flat = a.reshape(-1)
        value = draw(st.sampled_from(SPECIAL))
        with np.errstate(all="ignore"):
            try:
                flat[draw(st.integers(0, a.size - 1))] = value
            except (OverflowError, ValueError):  # (NaN into whole numbers: the largest instead)
                flat[0] = np.iinfo(a.dtype).max if a.dtype.kind in "iu" else value
        data[name] = a
    elif kind == "replace":
        dtype = draw(st.sampled_from(DTYPES))
        shape = draw(st.one_of(st.just(a.shape), hnp.array_shapes(min_dims=0, max_dims=3, min_side=0, max_side=6)))
        data[name] = draw(hnp.arrays(np.dtype(dtype), shape))
    elif kind == "scramble":
        data[name] = _scrambled(a, draw(st.integers(0, 2**16)))
    elif kind == "meta":
        _set_path(meta, draw(st.sampled_from(_paths(meta))), draw(json_values))


def _damage_bytes(draw, content: bytes) -> bytes:
    """The file's bytes cut short, with bytes flipped, or with bytes added, drawn."""
    kind = draw(st.sampled_from(["cut", "flip", "append"]))
    at = draw(st.integers(0, max(0, len(content) - 1)))
    if kind == "cut":
        return content[:at]
    if kind == "flip":
        mask = draw(st.integers(1, 255))
        return content[:at] + bytes([content[at] ^ mask]) + content[at + 1 :]
    return content + draw(st.binary(min_size=1, max_size=64))


def loads_or_refuses(path: Path) -> None:
    """The property: the run loads into a finite state that steps, or ConfigError names the file
    in one line."""
    try:
        sim = tg.Simulation.load(path)
    except ConfigError as exc:
        text = str(exc)
        assert "\n" not in text and text.startswith(f"{path}: "), text
        return
    for name in ("x", "v", "w", "rest_time"):
        assert np.all(np.isfinite(sim.state.read(name))), name
    assert math.isfinite(sim.t) and sim.t >= 0
    assert np.all(sim.model.radius_np > 0) and np.all(sim.model.mass_np > 0)
    with contextlib.suppress(SimulationError):  # (finite numbers too big for a step, as in a scene file)
        sim.run(steps=2)


@FUZZ
@given(data=st.data())
def test_fuzzed_saved_runs_load_or_are_refused(bases, data):
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "fuzz.npz"
        arrays, meta = read_saved_run(data.draw(st.sampled_from(bases)))
        for _ in range(data.draw(st.integers(0, 3))):
            _edit_arrays(data.draw, arrays, meta)
        write_saved_run(path, arrays, meta)
        if data.draw(st.integers(0, 3)) == 0:
            path.write_bytes(_damage_bytes(data.draw, path.read_bytes()))
        loads_or_refuses(path)


def test_the_fuzz_bases_load_and_step(bases):
    for path in bases:
        loads_or_refuses(path)
