"""Links between the neighbour lists, and the impulses they carry across rebuilds.

Each pair is listed once, in its owner's upper list (:mod:`ti_golf.solvers.grid`); the other ball
finds it through a *slot* in its lower list: the owner's index times 2^bits plus the column
(:func:`slot_bits`, :func:`owner_slot`). When the lists are rebuilt, each pair's accumulated
resting impulse is stashed by (owner, neighbour) and carried into the new lists
(:func:`stash`, :func:`link_and_carry`). :func:`relist_all_pairs` rebuilds the lists of a small
scene inside a serial kernel by testing every pair.
"""

import numpy as np
import taichi as ti

from ti_golf.physics.types import (
    FRIC,
    LAM,
    f32_array,
    int_array,
    int_table,
    is_f64,
    kernel,
    of_ball,
    pair_columns,
    pair_table,
    vec3_array,
    vec3f_array,
)
from ti_golf.runtime import np_float
from ti_golf.solvers.apart import APART_MAX, is_apart
from ti_golf.solvers.grid import owns, pair_reach
from ti_golf.solvers.sort import bucket_starts
from ti_golf.solvers.stash import put_id, stashed_row


def table_bytes(n: int, width: int, pairs: int, gauss_seidel: bool) -> int:
    """Bytes of the neighbour and pair tables of ``n`` balls with upper lists ``width`` wide and
    room for ``pairs`` pairs: per upper-list entry a neighbour (4 bytes); per pair its link in the
    other ball's lower list (4 bytes), its resting impulse (f32), its row of the sweep's table
    (:func:`ti_golf.physics.types.pair_columns` entries of :func:`~ti_golf.physics.types.pair_table_type`),
    and with the Gauss–Seidel sweeps its friction impulse (3 f32)."""
    f = 4 if gauss_seidel else np.dtype(np_float()).itemsize
    per_pair = 4 + 4 + pair_columns(gauss_seidel) * f + (12 if gauss_seidel else 0)
    return n * width * 4 + pairs * per_pair


@ti.func
def slot_bits(width):
    """Bits of a lower-list slot that hold the column k < ``width`` of the pair in its owner's
    upper list (the owner's id is in the bits above): decoding a slot is then a shift and a mask,
    not an integer division (which costs tens of cycles, several times per ball and sweep)."""
    bits = 0
    while (1 << bits) < width:
        bits += 1
    return bits


@ti.func
def owner_slot(slot, bits):
    """(owner j, column k) of a pair from its lower-list slot ``j · 2^bits + k``."""
    return slot >> bits, slot & ((1 << bits) - 1)


@ti.func
def listed(first: ti.template(), i):
    """How many pairs ball i owns: the length of its upper list, ``first[i + 1] − first[i]`` (see
    ``NeighbourLists.first``)."""
    return first[i + 1] - first[i]


@kernel
def link_lower(
    upper: int_table, first: int_array, lower: int_array, lower_first: int_array, count: int_array, chunk: int_array
):
    """Every ball's lower list from the upper lists (see :func:`link_lower_lists`)."""
    link_lower_lists(upper, first, lower, lower_first, count, chunk, serial=False)


@ti.func
def link_lower_lists(
    upper: ti.template(),
    first: ti.template(),
    lower: ti.template(),
    lower_first: ti.template(),
    count: ti.template(),
    chunk: ti.template(),
    serial: ti.template(),
):
    """Every ball's lower list from the upper lists: ball j's list, ``lower[lower_first[j] :
    lower_first[j + 1]]``, holds the slot ``i · 2^bits + k`` (:func:`slot_bits`) of each pair
    that another ball i owns with it, ``upper[i, k] = j``, in the order of the owners' ids: the
    ball that owns a pair stores its impulse there, and the other ball gathers it from there. The
    lists lie ball after ball, as the pair tables do (``lower`` holds as many entries as they
    do), rather than in a table as wide as the longest list: 4 bytes a pair, not 4 times the
    longest list a ball. Each ball's links are counted (in ``count``), their starts scanned
    (:func:`.sort.bucket_starts`, ``chunk``: its scratch), the slots written, each at the next
    free place of its ball's list, then each list sorted: the lists are the same whatever order
    the threads ran in. ``serial``: in a serial loop (the lists then come out sorted, and the
    scan runs serially too).

    The counts are integer atomic adds (:func:`next_link`), one a thread: a thread per slot of
    the upper lists, not a thread per ball looping over its list. On Taichi's Vulkan backend
    (1.7.4, mesa's lavapipe) a thread's loop of atomic adds lost some of them (3 % of a dense
    set's links), which left pairs out of the lower lists."""
    bits = slot_bits(upper.shape[1])
    n = first.shape[0] - 1
    for i in range(n):
        count[i] = 0
    for q in range(n << bits):  # slot q: the pair in column k of ball i's upper list, if listed
        i, k = q >> bits, q & ((1 << bits) - 1)
        if k < listed(first, i):
            next_link(count, upper[i, k], serial)
    for i in range(n):
        lower_first[i + 1] = count[i]
        count[i] = 0
    if ti.static(serial):
        lower_first[0] = 0
        for i in range(n):
            lower_first[i + 1] = lower_first[i + 1] + lower_first[i]
    else:
        bucket_starts(lower_first, chunk)
    for q in range(n << bits):
        i, k = q >> bits, q & ((1 << bits) - 1)
        if k < listed(first, i):
            j = upper[i, k]
            lower[lower_first[j] + next_link(count, j, serial)] = q
    for j in range(n):
        lo, hi = lower_first[j], lower_first[j + 1]
        for m in range(lo + 1, hi):  # an insertion sort: a few links a ball
            slot, q = lower[m], m
            while q > lo:  # the test apart: Taichi evaluates both sides of an `and` (no lower[−1])
                if lower[q - 1] <= slot:
                    break
                lower[q] = lower[q - 1]
                q -= 1
            lower[q] = slot


@ti.func
def next_link(count: ti.template(), j, serial: ti.template()):
    """``count[j]`` before adding one to it: an integer atomic add in a parallel loop, a plain one
    in a serial loop (``serial``)."""
    k = 0
    if ti.static(serial):
        k = count[j]
        count[j] = k + 1
    else:
        k = ti.atomic_add(count[j], 1)
    return k


@kernel
def pair_starts(first: int_array, chunk_start: int_array) -> ti.i32:
    """Lay the pair tables out ball after ball, each ball's pairs as many entries as its list
    holds: from the lists' lengths in ``first[1:]`` (as :func:`.grid.list_neighbours` leaves
    them), ``first[i]`` = the lengths of the lists before ball i's (``first[0]`` = 0, ``first[N]``
    the pairs in all), in place, by the grid's chunked scan (:func:`.sort.bucket_starts`;
    ``chunk_start``: its scratch, ``sort.scan_chunks(N)`` entries). Returns the pairs in all. The
    tables are then as long as the lists are in all, not N times the longest list (8 pairs while
    a pour lands, 3.5 on average)."""
    bucket_starts(first, chunk_start)
    return first[first.shape[0] - 1]


@kernel
def stash(
    upper: int_table,
    first: int_array,
    lam: f32_array,
    scratch: pair_table,
    with_friction: ti.template(),
    x: vec3_array,
    friction: vec3f_array,
    mu: float,
):
    """Keep every pair's (accumulated impulse, neighbour id) in ``scratch``, laid out as the pair
    tables, and ``with_friction`` its friction impulse (see :func:`stash_ball`)."""
    for i in range(first.shape[0] - 1):
        stash_ball(i, upper, first, lam, scratch, width=0, with_friction=with_friction, x=x, friction=friction, mu=mu)


@ti.func
def stash_ball(
    i,
    upper: ti.template(),
    first: ti.template(),
    lam: ti.template(),
    scratch: ti.template(),
    width,
    with_friction: ti.template(),
    x: ti.template(),
    friction: ti.template(),
    mu,
):
    """Keep the (accumulated impulse, neighbour id) of every pair that ball i owns in the columns
    ``LAM`` and ``ID`` of ``scratch`` (the sweep's table, free between steps) so that the lists
    and the pair tables can be rebuilt in place: in the pair tables' rows of ball i, or with
    ``width`` > 0 in rows i · width onwards, followed by the id −1 when the list is shorter (the
    serial rebuild, which overwrites ``first`` before it carries the impulses over). With
    ``with_friction`` (the Gauss–Seidel
    sweeps) each pair's friction impulse from ``friction`` is kept beside them, in
    32 bits (:func:`friction_bits`, from the positions ``x`` and friction coefficient ``mu``), so
    that a rebuild needs no second friction table to carry it into."""
    p0, count = first[i], listed(first, i)
    if width > 0:
        p0 = i * width
        if count < width:
            put_id(scratch, p0 + count, -1, with_friction)
    for k in range(count):
        j, p = upper[i, k], first[i] + k
        bits = 0
        if ti.static(with_friction):
            bits = friction_bits(friction[p], x[i] - x[j], mu * lam[p])
        put_stashed(scratch, p0 + k, lam[p], j, bits, with_friction)


@ti.func
def put_stashed(scratch: ti.template(), p, lam, j, bits, with_friction: ti.template()):
    """Write a stashed pair into row p of ``scratch``: its resting impulse ``lam`` into ``LAM``, its
    neighbour's id j into ``ID`` (:func:`put_id`) and, ``with_friction``, the 32 ``bits`` of its
    friction impulse into ``FRIC``."""
    scratch[p, LAM] = lam
    put_id(scratch, p, j, with_friction)
    if ti.static(with_friction):
        scratch[p, FRIC] = ti.bit_cast(bits, ti.f32)


FRICTION_STEPS = 32767
"""Steps of each tangent component of a stashed friction impulse from 0 to its bound μ·λ (a signed
16-bit integer each, :func:`friction_bits`)."""


@ti.func
def tangent_basis(n):
    """Two unit vectors that make a right-handed orthonormal basis with the unit vector n (Duff et
    al. 2017, "Building an orthonormal basis, revisited"): a function of n alone, so that the
    stash and the carry of a rebuild, which see the same positions, use the same basis."""
    s = 1.0 if n[2] >= 0.0 else -1.0
    a = -1.0 / (s + n[2])
    b = n[0] * n[1] * a
    t1 = ti.Vector([1.0 + s * n[0] * n[0] * a, s * b, -s * n[0]])
    t2 = ti.Vector([b, s + n[1] * n[1] * a, -n[1]])
    return t1, t2


@ti.func
def friction_bits(F, d, bound):
    """A pair's friction impulse F [N·s] (f32) in 32 bits, for a pair whose centres are ``d`` [m]
    apart (owner minus neighbour) and whose friction is at most ``bound`` = μ·λ [N·s]: its
    components along :func:`tangent_basis` of the normal d/|d|, as shares of ``bound`` in
    steps of 1/``FRICTION_STEPS`` (a signed 16-bit integer each, the first in the low bits).
    What the next step uses of F is kept whole but for those steps: the warm start and the first
    sweep take F in the tangent plane of the same normal and at most ``bound`` long
    (:func:`ti_golf.physics.contact.clamp_friction`), so the normal part and the part beyond ``bound`` are
    dropped here. 0 when ``bound`` or d is 0 (F is then not used)."""
    bits = 0
    dd = d.norm_sqr()
    if bound > 0.0 and dd > 0.0:
        t1, t2 = tangent_basis(d / ti.sqrt(dd))
        Fv = ti.cast(F, float)
        u, w = Fv.dot(t1) / bound, Fv.dot(t2) / bound
        size = ti.sqrt(u * u + w * w)
        if size > 1.0:
            u, w = u / size, w / size
        qu, qw = ti.cast(ti.round(u * FRICTION_STEPS), ti.i32), ti.cast(ti.round(w * FRICTION_STEPS), ti.i32)
        bits = (qu & 0xFFFF) | (qw << 16)
    return bits


@ti.func
def friction_from_bits(bits, d, bound):
    """The friction impulse [N·s] (f32) that :func:`friction_bits` kept in ``bits`` for the same
    ``d`` and ``bound``."""
    F = ti.Vector([0.0, 0.0, 0.0])
    dd = d.norm_sqr()
    if bound > 0.0 and dd > 0.0:
        t1, t2 = tangent_basis(d / ti.sqrt(dd))
        qu, qw = (bits << 16) >> 16, bits >> 16  # (arithmetic shifts: the signs come back)
        F = (bound / FRICTION_STEPS) * (ti.cast(qu, float) * t1 + ti.cast(qw, float) * t2)
    return ti.cast(F, ti.f32)


@kernel
def link_and_carry(
    upper: int_table,
    first: int_array,
    lower: int_array,
    lower_first: int_array,
    count: int_array,
    chunk: int_array,
    stashed: pair_table,
    stash_first: int_array,
    lam: f32_array,
    moved: ti.template(),
    old_id: int_array,
    with_friction: ti.template(),
    x: vec3_array,
    friction: vec3f_array,
    mu: float,
):
    """:func:`link_lower` (``count``, ``chunk``: its scratch), and each pair's accumulated impulse
    carried from the stashed old lists (see :func:`stash` and :func:`carry_ball`; ``stash_first``:
    their layout) to the new ones, in one launch (neither writes what the other reads). With
    ``moved`` the balls were stored in a new order since the stash: ball i was ball ``old_id[i]``
    of the stashed lists. With ``with_friction`` the pairs' friction impulses (of the
    Gauss–Seidel sweeps) are carried from the stash into ``friction`` too (``x``: the positions,
    ``mu``: the friction coefficient, as at the stash)."""
    link_lower_lists(upper, first, lower, lower_first, count, chunk, serial=False)
    for i in range(first.shape[0] - 1):
        carry_ball(
            i,
            stashed,
            stash_first,
            width=0,
            upper=upper,
            first=first,
            lam=lam,
            old_id=old_id,
            moved=moved,
            with_friction=with_friction,
            x=x,
            friction=friction,
            mu=mu,
        )


@ti.func
def carry_ball(
    i,
    stashed: ti.template(),
    stash_first: ti.template(),
    width,
    upper: ti.template(),
    first: ti.template(),
    lam: ti.template(),
    old_id: ti.template(),
    moved: ti.template(),
    with_friction: ti.template(),
    x: ti.template(),
    friction: ti.template(),
    mu,
):
    """Carry the accumulated impulse of each pair ball i owns in the new lists from the stashed old
    ones (see :func:`stash_ball`: laid out by ``stash_first``, or ``width`` a ball), and with
    ``with_friction`` its friction impulse into ``friction``; new pairs start at zero. The pair
    of balls a and b (their old ids: ``old_id`` of i and j when ``moved``) is looked up in the
    entries of its old owner, which is a's, or b's when the pair changed hands (a pair's owner
    is the ball behind the other along their main axis, see :func:`owns`, and that axis can
    change as the balls move)."""
    p = first[i]
    for k in range(listed(first, i)):
        j = upper[i, k]
        a, b = i, j
        if ti.static(moved):
            a, b = old_id[a], old_id[b]
        found, value, word = stashed_impulse(stashed, stash_first, width, a, b, with_friction)
        sign = 1.0
        if not found:
            found, value, word = stashed_impulse(stashed, stash_first, width, b, a, with_friction)
            sign = -1.0  # (stashed by b: the friction on b, with b's normal)
        lam[p + k] = ti.cast(value, ti.f32)
        if ti.static(with_friction):
            F = friction_from_bits(word, sign * (x[i] - x[j]), mu * value)
            friction[p + k] = ti.cast(sign, ti.f32) * F


@ti.func
def stashed_impulse(stashed: ti.template(), stash_first: ti.template(), width, a, b, with_friction: ti.template()):
    """(whether, with which accumulated impulse, and with which friction bits) the stashed pairs of
    ball a hold its pair with ball b (see :func:`stash_ball` for the layouts): a search of entries
    sorted by id, stopping at the first id past b."""
    found, value, word = 0, 0.0, 0
    row, bits = stashed_row(stashed, stash_first, width, a, b, with_friction)
    if row >= 0:
        found, value, word = 1, stashed[row, LAM], bits
    return found, value, word


@ti.func
def relist_all_pairs(
    params: ti.template(),
    with_friction: ti.template(),
    mu,
    model: ti.template(),
    lists: ti.template(),
    state: ti.template(),
    step_scratch: ti.template(),
):
    """Rebuild the neighbour lists of a few balls in place without a grid, by testing every pair:
    the lists, slots and carried-over impulses that ``list_neighbours`` and ``link_and_carry``
    give on a CPU backend (with the same owners: the balls faster than ``v_cut`` or bigger than
    ``r_cut`` are listed apart unless there are more than ``APART_MAX``), in O(n²) work, with the
    step's parameters ``params`` (the skin, h, ``v_cut`` and ``r_cut``), the model's radii and the
    balls' positions and velocities. The tables must be n − 1 wide (no list can overflow), and the
    step's table ``step_scratch.J`` hold n (n − 1) entries: the old impulses are stashed n − 1 a
    ball (:func:`stash_ball`), as ``first`` is rewritten. Meant for a serial loop (the ``serial``
    variant of ``collide.collision_step``; ``step_scratch.impact``: a scratch entry per ball, see
    :func:`link_lower_lists`). With ``with_friction`` the pairs' friction impulses (of the
    Gauss–Seidel sweeps, friction coefficient ``mu``) are carried over too, as ``link_and_carry``
    carries them: a build through the grid on the same positions gives the same lists and
    impulses, bit for bit."""
    x, radius, v = ti.static((state.x, model.radius, state.v))
    skin, h, v_cut, r_cut = ti.static((params.skin, params.h, params.v_cut, params.r_cut))
    upper, first, lower, lower_first = ti.static((lists.upper, lists.first, lists.lower, lists.lower_first))
    x_at_build, lam, friction = ti.static((lists.x_at_build, lists.lam, lists.friction))
    scratch, count = ti.static((step_scratch.J, step_scratch.impact))
    width = upper.shape[1]
    n_apart = 0
    for i in range(x.shape[0]):
        stash_ball(
            i, upper, first, lam, scratch, width=width, with_friction=with_friction, x=x, friction=friction, mu=mu
        )
        if is_apart(v, radius, i, v_cut, r_cut, 1):  # as apart_balls counts them
            n_apart += 1
    if n_apart > APART_MAX:
        n_apart = 0
    first[0] = 0
    for i in range(x.shape[0]):
        xi, ri = x[i], of_ball(radius, i)
        apart_i = is_apart(v, radius, i, v_cut, r_cut, n_apart)
        n_up = 0
        for j in range(x.shape[0]):  # in id order: the lists come out sorted
            reach = ri + of_ball(radius, j) + pair_reach(skin, h, v[i], v[j])
            if j != i and (x[j] - xi).norm_sqr() < reach * reach:  # the test of list_ball
                if owns(xi, x[j], i, j, apart_i, is_apart(v, radius, j, v_cut, r_cut, n_apart)):
                    upper[i, n_up] = j
                    n_up += 1
        first[i + 1] = first[i] + n_up
        x_at_build[i] = ti.cast(xi, ti.f32)
    link_lower_lists(upper, first, lower, lower_first, count, count, serial=True)
    for i in range(x.shape[0]):
        carry_ball(
            i,
            stashed=scratch,
            stash_first=first,
            width=width,
            upper=upper,
            first=first,
            lam=lam,
            old_id=first,
            moved=False,
            with_friction=with_friction,
            x=x,
            friction=friction,
            mu=mu,
        )  # ids kept


@ti.func
def distance_from_build(x1, x_build):
    """How far [m] a ball now at ``x1`` [m] may be from where it was when the lists were built.

    The position at the build, ``x_build``, is kept in f32 (12 bytes per ball less in f64): it
    only serves the tests of whether the lists still hold. Rounding moved it by at most
    2^-24·|x| (round to nearest), so the distance adds twice that, |x_build|·2^-23 (in f64;
    nothing in f32, where nothing was rounded): a ball never moves past the skin unseen, and the
    lists are rebuilt a little early, by 2 % of half the skin of a golf ball (1.07 mm) for a ball
    170 m from the origin, by 11 % at 1 km."""
    xb = ti.cast(x_build, float)
    margin = 0.0
    if ti.static(is_f64()):
        margin = xb.norm() * 2.0**-23
    return (x1 - xb).norm() + margin


@ti.func
def moved_past(x1, x_build, reach, half_skin):
    """Whether a ball now at ``x1`` [m], which may move ``reach`` [m] more before the next step's
    test, can be farther than ``half_skin`` [m] from where it was when the lists were built
    (:func:`distance_from_build`)."""
    return distance_from_build(x1, x_build) + reach > half_skin
