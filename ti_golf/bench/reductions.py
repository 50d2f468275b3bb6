"""``ti-golf bench reductions``: the two reductions of a neighbour-list build over the balls
(``grid.cell_bounds``, ``apart.apart_balls``), each both ways its threads can meet: in the kernel's
own variables, or folded ``sort.FOLD`` balls a thread and met in an array (``sort.fold_in_array``
picks the second on CUDA only). The baseline, timed in the same run, is a loop over the same balls
that writes a cell per ball and reduces nothing. Each call's result is read back (so the device
has finished it) and checked against numpy's over every ball. Two probes beside them reduce into
one integer variable of the kernel's own, as other kernels of a step do (``stale.balls_in_play``'s
``+=``, ``grid.list_neighbours``' greatest loop count): an i32 sum and an i32 maximum, each a ball's
cell height, to tell whether the cost of the kernels' own variables on CUDA is in their number, in
the vectors, or in the float maxima."""

import functools
import time
from collections.abc import Callable
from typing import Any

import numpy as np
import taichi as ti

from ti_golf.physics.types import int_array, kernel, vec3, vec3_array
from ti_golf.runtime import ensure_init
from ti_golf.solvers import apart, grid
from ti_golf.solvers.sort import cell_of, fold_in_array

CELL = 0.045
"""The cell side [m] of the bounds (a golf ball's diameter and the skin)."""


@kernel
def one_cell_a_ball(x: vec3_array, inv_cell: float, out: int_array) -> ti.i32:
    """The baseline: ball i's cell height into ``out[i]``, no reduction; returns the first (a
    readback, as the reductions' results are)."""
    for i in range(x.shape[0]):
        out[i] = cell_of(x[i], inv_cell)[1]
    return out[0]


@kernel
def i32_sum(x: vec3_array, inv_cell: float) -> ti.i32:
    """The probe of a sum: the balls' cell heights added into one i32 of the kernel's own."""
    total = 0
    for i in range(x.shape[0]):
        total += cell_of(x[i], inv_cell)[1]
    return total


@kernel
def i32_max(x: vec3_array, inv_cell: float) -> ti.i32:
    """The probe of a maximum: the balls' greatest cell height in one i32 of the kernel's own."""
    most = -(2**30)
    for i in range(x.shape[0]):
        ti.atomic_max(most, cell_of(x[i], inv_cell)[1])
    return most


def _per_call_s(call: Callable[[], Any], repeats: int) -> tuple[float, Any]:
    """Seconds a call (its result read back), the mean of ``repeats`` after two warm-up calls (the
    first compiles), and the last call's result."""
    for _ in range(2):
        result = call()
    t0 = time.perf_counter()
    for _ in range(repeats):
        result = call()
    return (time.perf_counter() - t0) / repeats, result


def bench_reductions(n: int = 100_000, repeats: int = 50, log: Callable[[str], None] = print) -> dict[str, Any]:
    """Milliseconds a call of the build's two reductions over ``n`` balls at random places and
    speeds, both ways (see the module's docstring), against a loop that reduces nothing; whether
    each agrees with numpy."""
    info = ensure_init()
    rng = np.random.default_rng(1)
    places, speeds = rng.uniform((-1.0, 0.0, -1.0), (1.0, 3.0, 1.0), (n, 3)), rng.normal(0.0, 2.0, (n, 3))
    x, v = ti.ndarray(vec3.get(), n), ti.ndarray(vec3.get(), n)
    x.from_numpy(places)
    v.from_numpy(speeds)
    radius = ti.ndarray(float, 1)
    radius.from_numpy(np.array([0.02135]))
    ids, bounds, top = ti.ndarray(ti.i32, apart.APART_MAX + 1), ti.ndarray(ti.i32, 6), ti.ndarray(ti.i64, 2)
    cells = np.floor(places / CELL).astype(np.int64)
    want_bounds = np.concatenate([cells.min(axis=0), cells.max(axis=0)])
    want_speed = float(np.linalg.norm(speeds, axis=1).max())
    out = ti.ndarray(ti.i32, n)
    rtol = 1e-14 if info.precision == "f64" else 1e-6  # (the norms' rounding, numpy's against the kernel's)

    def bounds_of(folded: bool) -> np.ndarray:
        return np.asarray(grid.cell_bounds(x, 1.0 / CELL, bounds, folded).to_numpy())

    def speeds_of(folded: bool) -> np.ndarray:
        return np.asarray(apart.apart_balls(v, radius, 1e9, 1e9, ids, top, folded).to_numpy())

    baseline_s, _ = _per_call_s(lambda: one_cell_a_ball(x, 1.0 / CELL, out), repeats)
    ways: dict[str, Any] = {}
    for folded in (False, True):
        if folded and info.arch == "vulkan":  # (its code generator refuses the folded loop: see fold_in_array)
            continue
        bounds_s, got_bounds = _per_call_s(functools.partial(bounds_of, folded), repeats)
        speeds_s, got_speeds = _per_call_s(functools.partial(speeds_of, folded), repeats)
        ways["in_array" if folded else "own_variables"] = {
            "cell_bounds_ms": bounds_s * 1e3,
            "apart_balls_ms": speeds_s * 1e3,
            "agree_with_numpy": bool(
                np.array_equal(got_bounds, want_bounds) and np.isclose(got_speeds[0], want_speed, rtol=rtol, atol=0.0)
            ),
        }
    sum_s, got_sum = _per_call_s(lambda: i32_sum(x, 1.0 / CELL), repeats)
    max_s, got_max = _per_call_s(lambda: i32_max(x, 1.0 / CELL), repeats)
    probes = {
        "i32_sum_ms": sum_s * 1e3,
        "i32_max_ms": max_s * 1e3,
        "agree_with_numpy": bool(got_sum == int(cells[:, 1].sum()) and got_max == int(cells[:, 1].max())),
    }
    chosen = "in_array" if fold_in_array() else "own_variables"
    result = {
        "benchmark": "reductions",
        "n": n,
        "arch": info.arch,
        "precision": info.precision,
        "repeats": repeats,
        **ways,
        "chosen": chosen,
        "probes": probes,
        "baselines": {"one_cell_a_ball_ms": baseline_s * 1e3},
    }
    for way, figures in ways.items():
        log(
            f"{way}{' (the default here)' if way == chosen else ''}: cell_bounds {figures['cell_bounds_ms']:.3f} ms, "
            f"apart_balls {figures['apart_balls_ms']:.3f} ms a call over {n:,} balls"
            f"{'' if figures['agree_with_numpy'] else ' (NOT numpy results)'}"
        )
    log(
        f"probes, one i32 of the kernel's own: a sum {probes['i32_sum_ms']:.3f} ms, a maximum "
        f"{probes['i32_max_ms']:.3f} ms{'' if probes['agree_with_numpy'] else ' (NOT numpy results)'}"
    )
    log(f"baseline one_cell_a_ball: {baseline_s * 1e3:.3f} ms a call ({info.arch})")
    return result
