"""Uniform hash grid and neighbour lists.

Cells are cubes of side ``cell`` (the largest diameter plus the skin), hashed into a table of
``mask + 1`` buckets (a power of two), so the world is unbounded: far-apart balls simply land in
other buckets. Building the grid is a counting sort of ball ids by bucket:

1. ``count_buckets``: each ball's bucket and its rank inside it (an integer atomic add);
2. ``exclusive_scan``: bucket starts (a serial scan: ``PrefixSumExecutor`` does not run on CPU);
3. ``scatter``: ball ids sorted by bucket.

``build_neighbours`` then lists, for every ball, the balls within r_a + r_b + skin in its own and
the 26 adjacent cells, sorted by id (so sums over neighbours do not depend on thread order).
A neighbour list stays valid until some ball has moved, or could move within a step, more than
half the skin since the build.
"""

import taichi as ti

from .types import float_array, int_array, real, vec3_array

int_table = ti.types.ndarray(dtype=ti.i32, ndim=2)
ivec3_array = ti.types.ndarray(dtype=ti.types.vector(3, ti.i32), ndim=1)
real_table = ti.types.ndarray(dtype=real, ndim=2)


@ti.func
def cell_of(x, inv_cell):
    """Integer cell coordinates of a point [m]."""
    return ti.cast(ti.floor(x * inv_cell), ti.i32)


@ti.func
def bucket_of(c, mask):
    """Hash of integer cell coordinates into [0, mask]."""
    h = (ti.cast(c[0], ti.u32) * ti.u32(73856093)) ^ (ti.cast(c[1], ti.u32) * ti.u32(19349663)) ^ (
        ti.cast(c[2], ti.u32) * ti.u32(83492791))
    return ti.cast(h & ti.cast(mask, ti.u32), ti.i32)


@ti.kernel
def clear(a: int_array):
    """Set every entry of an int array to zero."""
    for i in range(a.shape[0]):
        a[i] = 0


@ti.kernel
def clear2(a: real_table):
    """Set every entry of a float table to zero."""
    for i, k in a:
        a[i, k] = 0.0


@ti.kernel
def count_buckets(x: vec3_array, inv_cell: float, mask: ti.i32, cell: ivec3_array, bucket: int_array,
                  rank: int_array, count: int_array):
    """Cell and bucket of every ball and its rank among the balls of that bucket."""
    for i in range(x.shape[0]):
        c = cell_of(x[i], inv_cell)
        b = bucket_of(c, mask)
        cell[i] = c
        bucket[i] = b
        rank[i] = ti.atomic_add(count[b], 1)


@ti.kernel
def exclusive_scan(count: int_array, start: int_array):
    """start[b] = count[0] + … + count[b − 1]; start has one more entry than count."""
    ti.loop_config(serialize=True)
    for b in range(count.shape[0]):
        start[b + 1] = start[b] + count[b]


@ti.kernel
def scatter(bucket: int_array, rank: int_array, start: int_array, sorted_ids: int_array):
    """Ball ids grouped by bucket: sorted_ids[start[b] : start[b + 1]] are the balls of bucket b."""
    for i in range(bucket.shape[0]):
        sorted_ids[start[bucket[i]] + rank[i]] = i


@ti.kernel
def build_neighbours(
    x: vec3_array,
    radius: float_array,
    cell: ivec3_array,
    mask: ti.i32,
    skin: float,
    start: int_array,
    sorted_ids: int_array,
    # out:
    neighbours: int_table,
    n_neighbours: int_array,
    x_at_build: vec3_array,
    longest: int_array,
):
    """Neighbour lists (ascending ids) of balls closer than r_a + r_b + skin; ``longest[0]`` gets
    the longest list found (it may exceed the table's width: the caller then rebuilds wider)."""
    capacity = neighbours.shape[1]
    for idx in range(x.shape[0]):
        i = sorted_ids[idx]  # in bucket order: consecutive threads probe the same 27 buckets (cache hits)
        xi = x[i]
        ri = radius[i]
        c = cell[i]
        n = 0
        for d in ti.static(ti.grouped(ti.ndrange((-1, 2), (-1, 2), (-1, 2)))):
            cc = c + d
            b = bucket_of(cc, mask)
            for k in range(start[b], start[b + 1]):
                j = sorted_ids[k]
                if j != i and (cell[j] == cc).all():  # not a ball of another cell in the same bucket
                    reach = ri + radius[j] + skin
                    if (x[j] - xi).norm_sqr() < reach * reach:
                        if n < capacity:  # insertion keeps the list sorted by id
                            m = n
                            while m > 0 and neighbours[i, m - 1] > j:
                                neighbours[i, m] = neighbours[i, m - 1]
                                m -= 1
                            neighbours[i, m] = j
                        n += 1
        n_neighbours[i] = ti.min(n, capacity)
        x_at_build[i] = xi
        ti.atomic_max(longest[0], n)


@ti.kernel
def carry_over(
    old_neighbours: int_table,
    old_count: int_array,
    old_lam: real_table,
    neighbours: int_table,
    n_neighbours: int_array,
    lam: real_table,
):
    """Carry each pair's accumulated impulse from the old to the new neighbour lists (both sorted
    by id: a merge per ball); new pairs start at zero."""
    for i in range(n_neighbours.shape[0]):
        k_old = 0
        for k in range(n_neighbours[i]):
            j = neighbours[i, k]
            while k_old < old_count[i] and old_neighbours[i, k_old] < j:
                k_old += 1
            value = 0.0
            if k_old < old_count[i] and old_neighbours[i, k_old] == j:
                value = old_lam[i, k_old]
            lam[i, k] = value
