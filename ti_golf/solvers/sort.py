"""The hash grid's counting sort (ball ids grouped by bucket), and storing the balls in that order
so that neighbours lie close in memory."""

import taichi as ti

from ti_golf.physics.types import (
    int_array,
    ivec3,
    kernel,
    vec3_array,
)
from ti_golf.runtime import cpu_threads, ensure_init, on_cpu


@ti.func
def cell_of(x, inv_cell):
    """Integer cell coordinates of a point [m]."""
    return ti.cast(ti.floor(x * inv_cell), ti.i32)


CPU_TASK_ITEMS = 512
"""Iterations in one task of a parallel loop on Taichi's CPU backend (1.7.4) whose bounds are
known only at run time: the backend's adaptive block size, which neither
``ti.loop_config(block_dim=...)`` nor ``ti.init(cpu_block_dim_adaptive=False)`` changes
(measured). A loop of up to 512 iterations therefore runs on one thread, however much each
iteration does: a loop over a few hundred blocks of a pile must be spread (:func:`spread_turns`)."""

FOLD = 16
"""Balls a thread of a reduction over the balls (``grid.cell_bounds``, ``apart.apart_balls``) folds
before it meets the other threads in the reduction's array with atomics: thread t takes balls
t, t + T, t + 2T, ... (T the threads, so neighbouring threads read neighbouring balls)."""


def fold_in_array() -> bool:
    """Whether the reductions over the balls (``grid.cell_bounds``, ``apart.apart_balls``) fold
    ``FOLD`` balls a thread and meet in an array: on CUDA. Elsewhere the threads meet in the
    kernel's own variables, which Taichi's CPU backend folds in a copy per thread first, and
    which Taichi 1.7.4's Vulkan backend compiles (it refuses the folded loop: "Not supported")."""
    return ensure_init().arch == "cuda"


@ti.func
def fold_threads(n):
    """Threads of a reduction over ``n`` balls, each folding up to ``FOLD`` of them (see ``FOLD``)."""
    return (n + FOLD - 1) // FOLD


TASKS_PER_THREAD = 8
"""Tasks per CPU thread of a loop over buckets spread by :func:`spread_turns`: the threads take
tasks as they finish the last, so a thread that drew the busier buckets takes fewer tasks."""


def task_stride() -> int:
    """Iterations of a spread loop per task (:func:`spread_turns`): ``CPU_TASK_ITEMS`` on the CPU,
    1 elsewhere (where a loop's iterations spread over the threads one by one)."""
    return CPU_TASK_ITEMS if on_cpu() else 1


def bucket_tasks(buckets: int) -> int:
    """Tasks of a loop over ``buckets`` buckets spread by :func:`spread_turns`: ``TASKS_PER_THREAD``
    per CPU thread (at most one per bucket), or one per bucket elsewhere."""
    return min(buckets, TASKS_PER_THREAD * cpu_threads()) if on_cpu() else buckets


@ti.func
def spread_turns(t, tasks, buckets):
    """(first, count): the turns (see :func:`bucket_in_turn`) that iteration t of a parallel loop
    over ``tasks`` × :func:`task_stride` iterations takes: ``count`` turns, first, first + tasks,
    first + 2·tasks, ..., when t begins a task (a multiple of the stride), else none. Every turn
    of ``buckets`` is taken once, by one task: on the CPU each task falls in a block of iterations
    of its own (``CPU_TASK_ITEMS``), which the thread pool hands to whichever thread is free, so
    the buckets of a loop of a few hundred spread over the threads."""
    stride = ti.static(task_stride())
    first, count = 0, 0
    if t % stride == 0:
        first = t // stride
        count = (buckets - first + tasks - 1) // tasks
    return first, count


@ti.func
def bucket_of(c, mask, origin, stride):
    """Hash of integer cell coordinates into [0, mask]: (c − origin)·stride, wrapping around, with
    stride 1 along y, so a column of cells fills consecutive buckets (their starts share a cache
    line; see ``list_ball``). See :func:`hash_strides` for ``origin`` and ``stride``."""
    d = c - origin
    h = (
        ti.cast(d[0], ti.u32) * ti.cast(stride[0], ti.u32)
        + ti.cast(d[1], ti.u32) * ti.cast(stride[1], ti.u32)
        + ti.cast(d[2], ti.u32) * ti.cast(stride[2], ti.u32)
    )
    return ti.cast(h & ti.cast(mask, ti.u32), ti.i32)


@ti.func
def bucket_in_turn(k, buckets):
    """The bucket that iteration k of a parallel loop over ``buckets`` buckets (a power of two)
    takes: k times an odd constant (Knuth's 2654435761), modulo ``buckets``, a one-to-one shuffle.

    Taichi's CPU backend hands a parallel loop to its threads in contiguous runs of iterations
    (``CPU_TASK_ITEMS``; a spread loop's tasks, :func:`spread_turns`, take every ``tasks``-th
    turn). Shuffled, each run takes buckets from all over the table, so the threads share the
    balls evenly even where the buckets in use are only the first part of it (a dense hash fills
    ext_x·ext_z blocks of a power of two) or the balls crowd one part of the bin; and k's lowest
    bit stays the bucket's, so the blocks of one colour (by the parities of their column) are
    not gathered into one run as reversing k's bits would gather them."""
    return ti.cast((ti.cast(k, ti.u32) * ti.u32(2654435761)) & ti.cast(buckets - 1, ti.u32), ti.i32)


@ti.func
def counting_sort(
    x: ti.template(),
    inv_cell,
    mask,
    origin,
    stride,
    rank: ti.template(),
    start: ti.template(),
    chunk_start: ti.template(),
    sorted_ids: ti.template(),
):
    """The grid's counting sort (see :func:`list_neighbours`): ``sorted_ids[start[b] : start[b + 1]]``
    are the balls of bucket b, in the order their threads took ranks (an integer atomic add)."""
    for b in range(start.shape[0]):
        start[b] = 0
    for i in range(x.shape[0]):
        b = bucket_of(cell_of(x[i], inv_cell), mask, origin, stride)
        rank[i] = ti.atomic_add(start[b + 1], 1)  # bucket b's count, until the scan turns it into a start
    bucket_starts(start, chunk_start)
    for i in range(x.shape[0]):
        sorted_ids[start[bucket_of(cell_of(x[i], inv_cell), mask, origin, stride)] + rank[i]] = i


@kernel
def storage_order(
    x: vec3_array,
    inv_cell: float,
    mask: ti.i32,
    origin: ivec3,
    stride: ivec3,
    rank: int_array,
    start: int_array,
    chunk_start: int_array,
    sorted_ids: int_array,
):
    """The order in which to store the balls so that neighbours lie close in memory: ``sorted_ids``
    lists the ball ids bucket by bucket (the grid's counting sort), and within a bucket by
    position, y then z then x (then id), so the order does not depend on thread scheduling. The
    balls of each column of cells (:func:`hash_strides`), and of the columns a ball's neighbours
    lie in, end up in runs of consecutive indices."""
    counting_sort(
        x, inv_cell, mask, origin, stride, rank=rank, start=start, chunk_start=chunk_start, sorted_ids=sorted_ids
    )
    sort_buckets(x, start, sorted_ids)


@ti.func
def sort_buckets(x: ti.template(), start: ti.template(), sorted_ids: ti.template()):
    """Sort the ball ids of every bucket of a counting sort by position, y then z then x (then
    id): :func:`stored_after`."""
    for turn in range(start.shape[0] - 1):
        sort_bucket(bucket_in_turn(turn, start.shape[0] - 1), x, start, sorted_ids)


SHELL_MIN = 24
"""Buckets of more balls than this are Shell-sorted (:func:`sort_bucket`)."""


@ti.func
def sort_bucket(b, x: ti.template(), start: ti.template(), sorted_ids: ti.template()):
    """Sort the ball ids of bucket b (:func:`sort_buckets`) by :func:`stored_after`. A grid cell
    holds a few balls: one insertion sort. A bucket of more than ``SHELL_MIN`` balls, as a block of
    grid columns holds hundreds (``colour.column_order``) in no order, is first sorted by the ids
    g apart for the gaps g = …, 40, 13, 4 (Knuth's, (3^k − 1)/2, the largest below a third of its
    balls first: a Shell sort), so that the last insertion sort moves each id a few places, not
    past a quarter of the others. ``stored_after`` is a strict total order (ties broken by id), so
    either way the order is the same. One loop over the gaps, the last 1, so that the kernel holds
    one copy of the insertion pass (its machine code is made at every start)."""
    lo, hi = start[b], start[b + 1]
    gap = 1
    if hi - lo > SHELL_MIN:
        while gap < (hi - lo) // 3:
            gap = 3 * gap + 1
    while gap >= 1:
        insertion_pass(lo, hi, gap, x, sorted_ids)
        gap //= 3


@ti.func
def insertion_pass(lo, hi, gap, x: ti.template(), sorted_ids: ti.template()):
    """Sort each chain of ids ``gap`` apart in ``sorted_ids[lo:hi]`` by :func:`stored_after`: an
    insertion sort of each."""
    for k in range(lo + gap, hi):
        j = sorted_ids[k]
        m = k
        while m >= lo + gap:  # not `m >= lo + gap and ...`: Taichi evaluates both sides of an `and`
            if not stored_after(x, sorted_ids[m - gap], j):  # (sorted_ids[m − gap] below lo would be read)
                break
            sorted_ids[m] = sorted_ids[m - gap]
            m -= gap
        sorted_ids[m] = j


@ti.func
def stored_after(x: ti.template(), a, b):
    """Whether ball a goes after ball b in a bucket of :func:`storage_order`: by y, z, x, then id."""
    after = a > b
    for axis in ti.static((0, 2, 1)):  # the least significant first: each later axis overrides
        if x[a][axis] != x[b][axis]:
            after = x[a][axis] > x[b][axis]
    return after


@kernel
def gather(src: ti.types.ndarray(), order: int_array, dst: ti.types.ndarray()):
    """dst[p] = src[order[p]]: per-ball data into a new storage order (any element type)."""
    for p in range(dst.shape[0]):
        dst[p] = src[order[p]]


SCAN_CHUNKS = 4096
"""Most chunks the buckets' scan (:func:`bucket_starts`) splits the buckets into: the length of its
one serial loop, far below the 65,535 iterations after which Taichi's Vulkan backend silently
stops a serial loop."""


def scan_chunks(buckets: int) -> int:
    """Length of the ``chunk_start`` scratch of :func:`list_neighbours` for ``buckets`` buckets:
    chunks of at least 64 buckets, at most ``SCAN_CHUNKS`` of them, plus one entry."""
    return max(1, min(SCAN_CHUNKS, buckets // 64)) + 1


@ti.func
def bucket_starts(start: ti.template(), chunk_start: ti.template()):
    """The buckets' starts from their counts, in place: given start[0] = 0 and bucket b's count
    c_b in start[b + 1], start[b + 1] becomes c_0 + … + c_b (an exclusive scan of the counts; one
    array instead of two, 8 bytes per ball less), in three loops: the sums of chunks of buckets,
    in parallel; a serial scan of those sums into ``chunk_start`` (as many entries as there are
    chunks, plus one); each chunk's running sum from its start, in parallel. No loop runs long on
    one thread: a single-thread scan of all buckets (2^21 of them for a million balls) would crawl
    on a GPU, and Taichi's Vulkan backend stops a serial loop after 65,535 iterations without a
    word, which left most balls of a large pile without neighbours (``PrefixSumExecutor`` does not
    run on CPU). Integer sums: the same result on every backend and thread count."""
    n_chunks = chunk_start.shape[0] - 1
    buckets = start.shape[0] - 1
    size = (buckets + n_chunks - 1) // n_chunks
    for c in range(n_chunks):
        total = 0
        for b in range(c * size, ti.min((c + 1) * size, buckets)):
            total += start[b + 1]
        chunk_start[c + 1] = total
        if c == 0:
            chunk_start[0] = 0
            start[0] = 0
    ti.loop_config(serialize=True)
    for c in range(n_chunks):
        chunk_start[c + 1] += chunk_start[c]
    for c in range(n_chunks):
        running = chunk_start[c]
        for b in range(c * size, ti.min((c + 1) * size, buckets)):
            running += start[b + 1]
            start[b + 1] = running
