"""The grid's storage order (``physics.sort.storage_order``): the balls bucket by bucket, and within
a bucket by position, y then z then x, then id (``sort.stored_after``), whatever order the counting
sort's atomic ranks left them in and however many balls a bucket holds (``sort.sort_bucket``)."""

import numpy as np
import pytest
import taichi as ti

from ti_golf.physics.types import vec3
from ti_golf.runtime import ensure_init
from ti_golf.solvers import grid, sort


def stored(x: np.ndarray, cell: float) -> tuple[np.ndarray, np.ndarray]:
    """(the ids in storage order, the buckets' starts) of balls at ``x`` (n, 3) [m] in cells of side
    ``cell`` [m], by the solver's kernels."""
    ensure_init()
    n, buckets = len(x), 1 << 12
    xs = ti.ndarray(vec3.get(), n)
    xs.from_numpy(x)
    bounds = grid.cell_bounds(xs, 1.0 / cell, ti.ndarray(ti.i32, 6), sort.fold_in_array())
    origin, stride = (ti.Vector(v, dt=ti.i32) for v in grid.hash_strides(bounds, buckets))
    rank, ids = ti.ndarray(ti.i32, n), ti.ndarray(ti.i32, n)
    start, chunks = ti.ndarray(ti.i32, buckets + 1), ti.ndarray(ti.i32, sort.scan_chunks(buckets))
    sort.storage_order(xs, 1.0 / cell, buckets - 1, origin, stride, rank, start, chunks, ids)
    return ids.to_numpy(), start.to_numpy()


@pytest.mark.parametrize("cell", [0.05, 0.5], ids=["a_few_balls_a_bucket", "hundreds_a_bucket"])
def test_each_bucket_is_sorted_by_y_then_z_then_x_then_id(cell):
    rng = np.random.default_rng(11)
    x = rng.uniform(0.0, 1.0, (3000, 3))
    x[::7, 1] = x[1::7, 1][: len(x[::7])]  # equal heights: z decides
    x[::11, 1:] = 0.5  # equal heights and depths: x decides
    x[::13] = x[0]  # the same point: the id decides
    ids, start = stored(x, cell)
    assert np.array_equal(np.sort(ids), np.arange(len(x)))  # every ball once
    sizes = np.diff(start)
    assert sizes.max() > (200 if cell == 0.5 else 1)
    for b in np.nonzero(sizes > 1)[0]:
        bucket = ids[start[b] : start[b + 1]]
        # the expected order: numpy's lexsort, last key most significant
        expected = bucket[np.lexsort((bucket, x[bucket, 0], x[bucket, 2], x[bucket, 1]))]
        np.testing.assert_array_equal(bucket, expected)


@pytest.mark.parametrize("folded", [False, True], ids=["own_variables", "folded_in_array"])
@pytest.mark.parametrize("n", [1, 15, 17, 1000, 4099])
def test_reductions_take_every_ball_once(n, folded):
    """The least and greatest cells (``grid.cell_bounds``) and the speeds and balls set apart
    (``apart.apart_balls``), reduced on the device with atomics, are numpy's over every ball; the
    extremes sit at random balls, so a ball skipped shows. Both ways of meeting (``folded``: CUDA's,
    ``sort.fold_in_array``), on the CPU, and on CUDA (Vulkan compiles only the first)."""
    if folded and ensure_init().arch == "vulkan":
        pytest.skip("Taichi 1.7.4's Vulkan backend does not compile the folded loop (sort.fold_in_array)")
    from ti_golf.solvers import apart

    ensure_init()
    rng = np.random.default_rng(n)
    x, v = rng.uniform(-2.0, 2.0, (n, 3)), rng.normal(0.0, 3.0, (n, 3))
    radius = rng.uniform(0.01, 0.03, n)
    xs, vs, rs = ti.ndarray(vec3.get(), n), ti.ndarray(vec3.get(), n), ti.ndarray(float, n)
    xs.from_numpy(x), vs.from_numpy(v), rs.from_numpy(radius)
    cells = np.floor(x / 0.1).astype(int)
    bounds = grid.cell_bounds(xs, 1.0 / 0.1, ti.ndarray(ti.i32, 6), folded).to_numpy()
    np.testing.assert_array_equal(bounds, np.concatenate([cells.min(axis=0), cells.max(axis=0)]))

    ids = ti.ndarray(ti.i32, apart.APART_MAX + 1)
    speed = np.linalg.norm(v, axis=1)
    v_cut, r_cut = float(np.quantile(speed, 0.9)), 0.028
    apart_now = (speed**2 > v_cut**2) | (radius > r_cut)
    fastest, fastest_rest, count = apart.apart_balls(
        vs, rs, v_cut, r_cut, ids, ti.ndarray(ti.i64, 2), folded
    ).to_numpy()
    assert fastest == pytest.approx(speed.max(), rel=1e-15) and count == apart_now.sum()
    assert fastest_rest == pytest.approx(speed[~apart_now].max() if (~apart_now).any() else 0.0, rel=1e-15)
    listed = ids.to_numpy()[: min(int(count), apart.APART_MAX)]
    assert set(listed) <= set(np.flatnonzero(apart_now)) and len(set(listed)) == len(listed)
