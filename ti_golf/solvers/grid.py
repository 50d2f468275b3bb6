"""Uniform hash grid and neighbour lists.

Cells are cubes of side ``cell`` (the largest diameter plus the skin, or more while balls move
fast: see below), hashed into a table of ``mask + 1`` buckets (a power of two), so the world is
unbounded: far-apart balls simply land in other buckets. ``list_neighbours`` builds the grid, a counting sort of ball ids by bucket, and
then lists, for every ball, the balls within r_a + r_b + skin in its own and the 26 adjacent
cells, sorted by id (so sums over neighbours do not depend on thread order), in two halves: the
*upper* list (the pairs the ball owns, each evaluated once per sweep: see :func:`owns`) and the
*lower* list (the pairs its neighbours own), which ``links.link_lower`` (or ``link_and_carry``,
which also carries each pair's accumulated impulse over from the old lists) makes from the upper
lists: the slots where the owners store the pairs' impulses, so each ball gathers its impulses
without float atomics.
A neighbour list stays valid until some ball has moved, or could move within a step, more than
half the skin since the build (with the Gauss–Seidel sweeps, until a pair it misses may touch or
it has moved about a radius, see :mod:`.stale`). A build also lists the pairs that can meet within the step that
follows it: a pair is listed when its surface gap is below the larger of the skin and
h·|v_a − v_b| (:func:`pair_reach`), and the cells are widened for the fastest pair
(:func:`cell_size`). Otherwise a ball that moves farther than the skin in a step, as fast balls do
(6 m/s is 3 mm per 0.5 ms step, against a skin of 2 mm for golf balls), would meet a ball
missing from its lists only in the next step, after flying into it. A few balls much faster or
bigger than the rest (at most ``APART_MAX``: moving more than a diameter in two steps, see
:func:`.apart.fast_speed`, or more than twice the size of the rest, see :func:`.apart.size_cut`) are set
apart: they own none of their pairs with the others (:func:`owns`), and on CPU backends they are
listed apart, each tested against every ball (:func:`list_ball`), so that the cells stay small
for the rest.

A build may also keep the lists of the balls that did not move (``amend``, with the Gauss–Seidel
sweeps): while a pour lands, its lists are rebuilt at nearly every step for the few balls that
land, and most of the pile has not moved. Each ball then *owes* the skin it used since its list
was made: its distance from where it was then, and before the last build its ``drift``. A ball
that owes less than half the skin, less 2h·|v| for the step ahead, keeps its list
(:func:`list_kept`): the pairs of its old list still within reach. The others are listed anew
(:func:`list_ball`); a pair of theirs with a ball that keeps its list stays in that list if it
held it, else goes by :func:`owns`, and when that gives it to the other ball, that ball is listed
anew after them (:func:`.kept.amended_owner`). So every pair within reach with a ball listed anew is listed, once, the
lists as narrow as :func:`owns` makes them; and a pair of two balls that kept
their lists and were not listed had, at the build before, a gap of at least the skin less what
the two owed then: ``stale.flag_stale_lists`` counts the drift as skin used, and searches for
such pairs as it searches for the others.
"""

import taichi as ti

from ti_golf.errors import SimulationError
from ti_golf.physics.types import (
    GridParams,
    GridScratch,
    KeptLists,
    NeighbourLists,
    float_array,
    int_array,
    ivec3,
    kernel,
    of_ball,
    vec3_array,
)
from ti_golf.solvers.apart import is_apart
from ti_golf.solvers.kept import Keep, amended_owner, keeps_list, old_index, promoted, rounded_up
from ti_golf.solvers.sort import FOLD, bucket_of, cell_of, counting_sort, fold_in_array, fold_threads
from ti_golf.solvers.stash import stashed_id_bits

SCATTERED_HASH = (19349663, 1, 83492791)

"""Strides of the cell coordinates (x, y, z) in the hash of a grid whose balls are too spread out
for a dense one (see :func:`hash_strides`)."""


def cell_size(r_max: float, skin: float, h: float, v_max: float) -> tuple[float, bool]:
    """Side [m] of the grid's cells for balls of radii up to ``r_max`` [m] whose speeds are at most
    ``v_max`` [m/s], with time step ``h`` [s], so that no listed pair (:func:`pair_reach`) reaches
    beyond the 26 cells around a ball's own; and whether some pair may close more than the skin
    [m] in a step, so that :func:`pair_reach` must read the velocities (else it is the skin for
    every pair). h·|v_a − v_b| ≤ 2h·v_max; the factor 1 + 1e-6 covers the rounding of either side."""
    closing = 2.0 * h * v_max * (1.0 + 1e-6)
    return 2.0 * r_max + max(skin, closing), closing > skin


@ti.func
def pair_reach(skin, h, v_a, v_b):
    """The surface gap [m] below which a pair is listed: the skin, or h·|v_a − v_b| when larger, so
    that a build lists every pair the speculative contact test (gap + h·v_n < 0, see
    :func:`ti_golf.physics.contact.pair_impulse`) can take up in the step after it at the velocities of the build
    (|v_n| ≤ |v_a − v_b|). Symmetric in a and b.

    Twice that reach, a margin for what the sweeps add to the velocities, listed so many pairs
    that are still apart in a pour that the Jacobi sweeps' simultaneous bounces (e > 0) fed on
    themselves: with e = 0.3 the narrow ball pit of the tests blew up (10 to 2,000 m/s within
    three steps). The steps between builds keep that margin from the skin (a ball may move half
    of it, less 2h·|v|, before the lists are rebuilt)."""
    return ti.max(skin, h * (v_a - v_b).norm())


LOOP_CAP = 65_535

"""Loop iterations after which a thread of Taichi's Vulkan backend stops all its loops, nested or
not, without a word (measured with Taichi 1.7.4 and lavapipe: 70,001 iterations ran 65,535 flat
and 65,505 nested in blocks). Listing a ball's neighbours loops over every ball of its 27 cells,
so a build whose largest bound (:func:`list_neighbours`) exceeds it on that backend has lost
pairs, and ``CollisionSolver.build`` stops the run instead."""


@kernel
def cell_bounds(x: vec3_array, inv_cell: float, bounds: int_array, folded: ti.template()) -> ti.types.vector(6, ti.i32):
    """The least (first three) and greatest (last three) cell coordinates of the balls (integer
    atomics: the same on every thread order). With ``folded`` (``sort.fold_in_array``: on CUDA),
    each thread folds ``sort.FOLD`` balls, then meets the others in ``bounds`` (6,): on CUDA,
    atomics on a kernel's own variables cost about 5 ms over 100,000 balls, however few (measured
    on an H200); else the threads meet in the kernel's own variables."""
    lo, hi = ti.Vector([2147483647] * 3), ti.Vector([-2147483647] * 3)
    if ti.static(not folded):
        for i in range(x.shape[0]):
            c = cell_of(x[i], inv_cell)
            ti.atomic_min(lo, c)
            ti.atomic_max(hi, c)
    else:
        for k in range(3):
            bounds[k], bounds[k + 3] = lo[k], hi[k]
        threads = fold_threads(x.shape[0])
        for t in range(threads):
            least, most = ti.Vector([2147483647] * 3), ti.Vector([-2147483647] * 3)
            for f in range(FOLD):
                i = t + f * threads
                if i < x.shape[0]:
                    c = cell_of(x[i], inv_cell)
                    least, most = ti.min(least, c), ti.max(most, c)
            for a in ti.static(range(3)):
                ti.atomic_min(bounds[a], least[a])
                ti.atomic_max(bounds[a + 3], most[a])
        for a in ti.static(range(3)):
            lo[a], hi[a] = bounds[a], bounds[a + 3]
    return ti.Vector([lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]])


CELL_REACH = 2**30
"""Grid cell coordinates of the balls must lie within ±CELL_REACH: their i32 arithmetic (a
ball's cell and those around it, the hash) never overflows. Beyond the range of i32, the cast of
a position to a cell gives no cell at all."""


def hash_strides(bounds, buckets: int) -> tuple[tuple[int, int, int], tuple[int, int, int]]:
    """(origin, stride) of the grid's hash for balls in the cells ``bounds`` (:func:`cell_bounds`).

    When the box of cells around the balls, one cell wider on every side (the cells a ball's
    neighbours are looked for in), has no more cells than there are ``buckets``, the hash numbers
    that box's cells one after another, y fastest, then x, then z: no two cells share a bucket,
    and the grid's order (:func:`storage_order`) is the box's columns of cells in turn, bottom-up,
    so that a ball's neighbours above and below it and in the column beside it lie close in
    memory too, and the Gauss–Seidel sweeps, which take the balls column by column
    (``colour.column_order``), read memory in runs. Else (balls spread far apart) the cells are
    hashed with ``SCATTERED_HASH``, still linear in y."""
    lo, hi = [int(b) for b in bounds[:3]], [int(b) for b in bounds[3:]]
    if min(lo) <= -CELL_REACH or max(hi) >= CELL_REACH:
        raise SimulationError(
            f"a ball lies more than {CELL_REACH:,} grid cells from the origin, beyond what the grid's 32-bit "
            "cell coordinates hold: the balls are too small for how far they are spread (the cells are "
            "the largest ball's diameter and the skin wide)"
        )
    ext = [h - lo_ + 3 for lo_, h in zip(lo, hi)]
    if ext[0] * ext[1] * ext[2] <= buckets:
        return (lo[0] - 1, lo[1] - 1, lo[2] - 1), (ext[1], 1, ext[0] * ext[1])
    return (0, 0, 0), SCATTERED_HASH


@kernel
def clear(a: int_array):
    """Set every entry of an int array to zero."""
    for i in range(a.shape[0]):
        a[i] = 0


@kernel
def list_neighbours(
    # In:
    g: GridParams,
    x: vec3_array,
    v: vec3_array,
    radius: float_array,
    apart_ids: int_array,
    amend: ti.i32,
    kept: KeptLists,
    # Scratch:
    scratch: GridScratch,
    # Out:
    lists: NeighbourLists,
    longest: int_array,
    stored_sorted: ti.template(),
) -> ivec3:
    """Sort the balls into the hash grid, then list every ball's neighbours closer than
    r_a + r_b + :func:`pair_reach` (with ``fast`` 0, the skin: see :func:`cell_size`; ``h`` is
    the time step [s], ``v`` the velocities), each list sorted by id (the ``n_apart`` balls faster
    than ``v_cut`` or bigger than ``r_cut`` whose indices are in ``apart_ids``, see
    :func:`apart_balls`, own none of their pairs with the others, and with ``scan_apart`` they
    are listed apart: see :func:`list_ball`): row i of ``upper`` holds the neighbours whose pairs
    ball i owns (:func:`owns`), and ``first[i + 1]`` their number (``links.pair_starts`` turns
    the numbers into the lists' starts in the pair tables); the pairs the others own are only
    counted (``links.link_lower`` lists them from the upper lists). The sort and
    the lists are built in one launch. The counting sort: each ball's rank among the balls of its
    bucket (an integer atomic add, counting in ``start``), the buckets' starts
    (:func:`bucket_starts`; ``start`` has one entry more than there are buckets, ``chunk_start`` is
    its scratch), then the ball ids grouped by bucket (each ball's bucket hashed again, rather
    than kept: 4 bytes per ball less): ``sorted_ids[start[b] : start[b + 1]]`` are
    the balls of bucket b. Returns the longest upper and lower lists found, also left in
    ``longest[0:2]`` (the upper may exceed the table's width: the caller then rebuilds wider), and a
    bound on the most loop iterations a ball's thread ran (see ``LOOP_CAP``).

    With ``amend`` 1 the balls that ``kept.marks`` marks keep their old lists (see the module's
    docstring and :func:`list_kept`; no ball is set apart), and each ball's ``drift`` is what it owes
    of the skin (``kept.marks``), 0 for a ball listed anew.

    With ``stored_sorted`` the balls are stored in bucket order already (:func:`storage_order`,
    then every per-ball array gathered into that order): ball p is the p-th of the sort, ``start``
    still holds the buckets' starts, and the sort is skipped (``sorted_ids`` is not read)."""
    longest[0], longest[1] = 0, 0
    most_up, most_low, most_loops = 0, 0, 0  # (the CPU's: see fold_in_array)
    if ti.static(not stored_sorted):
        counting_sort(
            x,
            g.inv_cell,
            g.mask,
            g.origin,
            g.stride,
            rank=scratch.rank,
            start=scratch.start,
            chunk_start=scratch.chunk_start,
            sorted_ids=scratch.sorted_ids,
        )
    keep = ti.static(Keep(amend, kept, scratch.sorted_ids, stored_sorted))
    for idx in range(x.shape[0]):
        i = idx  # in bucket order: consecutive threads probe the same 27 buckets (cache hits)
        if ti.static(not stored_sorted):
            i = scratch.sorted_ids[idx]
        n_up, n_low, loops = 0, 0, 0
        owed = 0.0  # (the skin it owes: see stale.skin_owed)
        if keeps_list(i, keep):
            n_up = list_kept(i, x, v, radius, g, keep, lists.upper)
            owed = kept.marks[i][0]
        else:
            n_up, n_low, loops = list_ball(i, x, v, radius, apart_ids, g, scratch, lists.upper, keep)
        lists.first[i + 1] = ti.min(n_up, lists.upper.shape[1])  # its length, until links.pair_starts
        lists.x_at_build[i] = ti.cast(x[i], ti.f32)
        lists.drift[i] = rounded_up(owed)
        count_longest(longest, most_up, most_low, n_up, n_low)
        ti.atomic_max(most_loops, loops)
    for idx in range(x.shape[0] * keep.amend):  # the balls promoted in the first pass (amended_owner)
        i = idx
        if ti.static(not stored_sorted):
            i = scratch.sorted_ids[idx]
        if promoted(i, keep):
            n_up, n_low, loops = list_ball(i, x, v, radius, apart_ids, g, scratch, lists.upper, keep)
            lists.first[i + 1] = ti.min(n_up, lists.upper.shape[1])
            lists.drift[i] = ti.cast(0.0, ti.f32)
            count_longest(longest, most_up, most_low, n_up, n_low)
            ti.atomic_max(most_loops, loops)
    if ti.static(not fold_in_array()):
        longest[0], longest[1] = most_up, most_low
    return ti.Vector([longest[0], longest[1], most_loops])


@ti.func
def count_longest(longest: ti.template(), most_up: ti.template(), most_low: ti.template(), n_up, n_low):
    """A ball's upper and lower lists (``n_up``, ``n_low`` pairs) counted into the longest of a
    build (:func:`list_neighbours`): on CUDA into ``longest[0:2]``, where atomics on an array cost
    next to nothing; elsewhere into the kernel's own ``most_up`` and ``most_low`` (passed by
    reference), which Taichi's CPU backend folds in a copy per thread, where two threads' atomics
    on one place of an array take turns with it (:func:`~ti_golf.solvers.sort.fold_in_array`)."""
    if ti.static(fold_in_array()):
        ti.atomic_max(longest[0], n_up)
        ti.atomic_max(longest[1], n_low)
    else:
        ti.atomic_max(most_up, n_up)
        ti.atomic_max(most_low, n_low)


@ti.func
def list_ball(
    i,
    x: ti.template(),
    v: ti.template(),
    radius: ti.template(),
    apart_ids: ti.template(),
    g: ti.template(),
    scratch: ti.template(),
    upper: ti.template(),
    keep: ti.template(),
):
    """The neighbours whose pairs ball i owns into its row of ``upper`` in id order (as many as
    fit; ``g``, ``scratch``: see :func:`list_neighbours`; ``keep``: :class:`.kept.Keep`). Returns how many
    neighbours it has (whose pairs it owns, whose pairs the others own) and a bound on the
    iterations of the thread's loops (see ``LOOP_CAP``).

    The balls in its own and the 26 adjacent cells (:func:`list_nearby`), but, with
    ``scan_apart``, for the balls listed apart (:func:`is_apart`): those are tested by every
    ball, and a ball listed apart tests every ball. So one ball shot into a pile does not widen
    the cells of all (a 70 m/s ball with a 1 ms step would make them 4.5 diameters wide: 90 times
    as many balls tested), nor does one boulder (see :func:`size_cut`), and both balls of every
    pair still test it, with the same :func:`pair_reach`. Without ``scan_apart`` (a GPU, see
    ``APART_MAX``) the cells are sized for all balls, and the balls apart still own none of their
    pairs with the others."""
    xi = x[i]
    ri = of_ball(radius, i)
    n_up, n_low = 0, 0
    apart_i = is_apart(v, radius, i, g.v_cut, g.r_cut, g.n_apart)
    tested = 0  # candidates tested, for the bound on the thread's loop iterations (see LOOP_CAP)
    if apart_i and g.scan_apart != 0:
        tested = x.shape[0]
        for j in range(x.shape[0]):
            if j != i:
                apart_j = is_apart(v, radius, j, g.v_cut, g.r_cut, g.n_apart)
                n_up, n_low = list_pair(
                    i,
                    j,
                    xi,
                    x[j],
                    ri + of_ball(radius, j),
                    g.skin,
                    v,
                    g.h,
                    fast=1,
                    apart_i=True,
                    apart_j=apart_j,
                    upper=upper,
                    n_up=n_up,
                    n_low=n_low,
                    keep=keep,
                )
    else:
        n_up, n_low, tested = list_nearby(i, apart_i, x, v, radius, g, scratch, upper, keep)
        for f in range(g.n_apart * g.scan_apart):
            j = apart_ids[f]
            n_up, n_low = list_pair(
                i,
                j,
                xi,
                x[j],
                ri + of_ball(radius, j),
                g.skin,
                v,
                g.h,
                fast=1,
                apart_i=False,
                apart_j=True,
                upper=upper,
                n_up=n_up,
                n_low=n_low,
                keep=keep,
            )
        tested += 18 + g.n_apart * g.scan_apart
    # the insertions' shifts: at most n(n − 1)/2 for a list of n (and the lower list's in links.link_lower_lists)
    return n_up, n_low, tested + (n_up * n_up + n_low * n_low) // 2


@ti.func
def list_nearby(
    i,
    apart_i,
    x: ti.template(),
    v: ti.template(),
    radius: ti.template(),
    g: ti.template(),
    scratch: ti.template(),
    upper: ti.template(),
    keep: ti.template(),
):
    """:func:`list_ball` of ball i among the balls of its own and the 26 adjacent cells (but those
    listed apart, with ``scan_apart``): the column of three cells along y at each of the 3 × 3
    (x, z) cells around it, whose buckets are consecutive (one range, or two where they wrap).
    Returns (n_up, n_low, the candidates tested)."""
    xi = x[i]
    ri = of_ball(radius, i)
    n_up, n_low, tested = 0, 0, 0
    c = cell_of(xi, g.inv_cell)  # recomputed, not stored: 12 bytes per ball less
    # no pair the cells list is farther apart than a cell's side (see cell_size): the square of
    # that side, with room for the rounding of 1/inv_cell and of the pair's reach
    cell_sqr = (1.0 + 1e-4) / (g.inv_cell * g.inv_cell)
    for m in range(9):  # (a loop, not unrolled: one copy of the listing in the kernel)
        # the column of three cells c + (dx, −1…1, dz): consecutive buckets, one range unless it wraps
        row = c + ti.Vector([m // 3 - 1, -1, m % 3 - 1])
        b = bucket_of(row, g.mask, g.origin, g.stride)
        for part in range(2):
            lo, hi = scratch.start[b], scratch.start[ti.min(b + 3, g.mask + 1)]
            if part == 1:
                lo, hi = scratch.start[0], scratch.start[ti.max(b + 3 - (g.mask + 1), 0)]
            tested += hi - lo
            for k in range(lo, hi):
                j = k
                if ti.static(not keep.stored_sorted):
                    j = scratch.sorted_ids[k]
                xj = x[j]
                # most candidates are out of reach: test that first, the cell and the rest only
                # for the few within it (a third off the build of a dense pile)
                if (xj - xi).norm_sqr() < cell_sqr:
                    cj = cell_of(xj, g.inv_cell)
                    apart_j = is_apart(v, radius, j, g.v_cut, g.r_cut, g.n_apart)
                    # a ball of the column (not of another cell sharing its buckets), not one listed apart
                    if (
                        j != i
                        and cj[0] == row[0]
                        and cj[2] == row[2]
                        and ti.abs(cj[1] - c[1]) <= 1
                        and not (apart_j and g.scan_apart != 0)
                    ):
                        n_up, n_low = list_pair(
                            i,
                            j,
                            xi,
                            xj,
                            ri + of_ball(radius, j),
                            g.skin,
                            v,
                            g.h,
                            fast=g.fast,
                            apart_i=apart_i,
                            apart_j=apart_j,
                            upper=upper,
                            n_up=n_up,
                            n_low=n_low,
                            keep=keep,
                        )
    return n_up, n_low, tested


@ti.func
def list_pair(
    i,
    j,
    xi,
    xj,
    r_sum,
    skin,
    v: ti.template(),
    h,
    fast,
    apart_i,
    apart_j,
    upper: ti.template(),
    n_up,
    n_low,
    keep: ti.template(),
):
    """Ball j into ball i's ``upper`` row when ball i owns their pair (:func:`owns`; ``apart_i``,
    ``apart_j``: whether they are listed apart; but a pair that a ball keeping its list keeps is
    that ball's, see :func:`kept_by_other`), or counted in ``n_low`` when j owns it, when they are
    :func:`within_reach`. Returns the new counts (n_up, n_low); an entry beyond the row's width is
    counted, not stored."""
    if within_reach(i, j, xi, xj, r_sum, skin, v, h, fast):
        mine = owns(xi, xj, i, j, apart_i, apart_j)
        if keep.amend != 0:
            mine = amended_owner(i, j, mine, keep)
        if mine:
            insert_sorted(upper, i, n_up, upper.shape[1], j)
            n_up += 1
        else:
            n_low += 1
    return n_up, n_low


@ti.func
def within_reach(i, j, xi, xj, r_sum, skin, v: ti.template(), h, fast):
    """Whether balls i and j, at ``xi`` and ``xj`` [m], are to be listed: their surface gap below
    :func:`pair_reach` (the skin when ``fast`` is 0; ``r_sum``: r_i + r_j [m]). Symmetric in i
    and j, bit for bit."""
    gap_reach = skin
    if fast != 0:  # (else pair_reach is the skin for every pair: v not read)
        gap_reach = pair_reach(skin, h, v[i], v[j])
    reach = r_sum + gap_reach
    return (xj - xi).norm_sqr() < reach * reach


@ti.func
def list_kept(
    i,
    x: ti.template(),
    v: ti.template(),
    radius: ti.template(),
    g: ti.template(),
    keep: ti.template(),
    upper: ti.template(),
):
    """Ball i's old list, kept (see the module's docstring): the pairs of its old list (the
    stash, ``keep.kept``) still :func:`within_reach`, into its row of ``upper`` by their balls'
    new indices, in order. Returns how many (an entry beyond the row's width is counted, not
    stored)."""
    o = old_index(i, keep)
    xi, ri = x[i], of_ball(radius, i)
    n_up = 0
    for e in range(keep.kept.stash_first[o], keep.kept.stash_first[o + 1]):
        j, _bits = stashed_id_bits(keep.kept.stashed, e, True)
        if ti.static(keep.stored_sorted):
            j = keep.kept.new_index[j]
        if within_reach(i, j, xi, x[j], ri + of_ball(radius, j), g.skin, v, g.h, g.fast):
            insert_sorted(upper, i, n_up, upper.shape[1], j)
            n_up += 1
    return n_up


@ti.func
def owns(xi, xj, i, j, apart_i, apart_j):
    """Whether ball i (at ``xi``) owns its pair with ball j (at ``xj``): whether j lies ahead of i
    along the axis on which the two centres differ most (the lower id when they coincide). Of
    the two balls of a pair exactly one owns it (x_j − x_i is exactly −(x_i − x_j) in floating
    point, so both find the same axis and opposite signs). Each ball of a cubic lattice owns
    exactly its three pairs in +x, +y and +z however the lattice is jostled, and a random pile's
    longest list, the width of the neighbour table, is shorter than with ownership by storage order
    (7-8 pairs against 10 in a 20,000-ball pour): an order along a grid flips for every pair
    that straddles a cell boundary.

    But a ball listed apart (``apart_j``; see :func:`is_apart`) never owns a pair with a ball
    that is not (``apart_i`` false): a boulder sunk into a pile touches hundreds of balls, and
    owned by them its pairs are taken one by each of their threads rather than all by the
    boulder's, while the upper table, as wide as the longest upper list for every ball, stays
    narrow; the boulder's lower list is long instead (4 bytes a link, see ``links.link_lower``)."""
    owner = False
    if apart_i != apart_j:
        owner = apart_j
    else:
        d = xj - xi
        ahead = d[0]  # the component of largest magnitude (the first of equals)
        if ti.abs(d[1]) > ti.abs(ahead):
            ahead = d[1]
        if ti.abs(d[2]) > ti.abs(ahead):
            ahead = d[2]
        owner = ahead > 0.0 or (ahead == 0.0 and j > i)
    return owner


@ti.func
def insert_sorted(table: ti.template(), i, n, capacity, j):
    """Insert id j into row i of ``table`` holding n ids in ascending order (dropped when full)."""
    if n < capacity:
        m = n
        while m > 0:  # the test apart: Taichi evaluates both sides of an `and` (no table[i, -1])
            if table[i, m - 1] <= j:
                break
            table[i, m] = table[i, m - 1]
            m -= 1
        table[i, m] = j
