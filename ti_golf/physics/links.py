"""Links between the neighbour lists, and the impulses they carry across rebuilds.

Each pair is listed once, in its owner's upper list (:mod:`ti_golf.physics.grid`); the other ball
finds it through a *slot* in its lower list: the owner's index times 2^bits plus the column
(:func:`slot_bits`, :func:`owner_slot`). When the lists are rebuilt, each pair's accumulated
resting impulse is stashed by (owner, neighbour) and carried into the new lists
(:func:`stash`, :func:`link_and_carry`). :func:`relist_all_pairs` rebuilds the lists of a small
scene inside a serial kernel by testing every pair.
"""

import taichi as ti

from ti_golf.physics.apart import APART_MAX, is_apart
from ti_golf.physics.grid import owns, pair_reach
from ti_golf.physics.types import (
    float_grid,
    int_array,
    int_table,
    is_f64,
    kernel,
    of_ball,
    pair_table,
    vec3f_table,
)

ID_EXACT_F32 = 2**24
"""Balls an f32 run can hold: :func:`stash_ball` keeps the neighbours' ids in the float type, exact
below 2^24 in f32 (below 2^53 in f64)."""


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


@kernel
def link_lower(upper: int_table, n_upper: int_array, lower: int_table, n_lower: int_array):
    """Replace each lower neighbour j of every ball by the slot of the pair in j's upper list
    (see :func:`link_ball`)."""
    bits = slot_bits(upper.shape[1])
    for i in range(lower.shape[1]):
        link_ball(i, bits, upper, n_upper, lower, n_lower)


@ti.func
def link_ball(i, bits, upper: ti.template(), n_upper: ti.template(), lower: ti.template(), n_lower: ti.template()):
    """Replace each lower neighbour j of ball i by the slot of the pair in j's upper list,
    ``j · 2^bits + k`` with ``upper[j, k] = i`` (see :func:`slot_bits`): the ball that owns a
    pair stores its impulse there, and the other ball gathers it from there."""
    for m in range(n_lower[i]):
        j = lower[m, i]
        slot = -1
        for k in range(n_upper[j]):
            if upper[j, k] == i:
                slot = (j << bits) | k
        lower[m, i] = slot


@kernel
def stash(
    upper: int_table,
    n_upper: int_array,
    lam: float_grid,
    scratch: pair_table,
    with_friction: ti.template(),
    friction: vec3f_table,
):
    """Keep every pair's (accumulated impulse, neighbour id, friction impulse) in ``scratch`` (see
    :func:`stash_ball`)."""
    for i in range(scratch.shape[0]):
        stash_ball(i, upper, n_upper, lam, scratch, with_friction, friction)


@ti.func
def stash_ball(
    i,
    upper: ti.template(),
    n_upper: ti.template(),
    lam: ti.template(),
    scratch: ti.template(),
    with_friction: ti.template(),
    friction: ti.template(),
):
    """Keep the (accumulated impulse, neighbour id, friction impulse) of every pair that ball i owns
    in row i of ``scratch`` (a table of upper's shape that is free between steps: the pair
    impulses) so the lists and the friction table can be rebuilt in place; the friction impulse
    (of the Gauss–Seidel sweeps) only ``with_friction``, else zero. The id is exact in f32 as well
    below 2^24 (``ID_EXACT_F32``). Unused slots get the id −1."""
    for k in range(scratch.shape[1]):
        j = -1
        F = ti.Vector([0.0, 0.0, 0.0], dt=ti.f32)
        if k < n_upper[i]:
            j = upper[i, k]
            if ti.static(with_friction):
                F = friction[i, k]
        scratch[i, k] = ti.Vector([lam[i, k], j, F[0], F[1], F[2]], dt=float)


@kernel
def link_and_carry(
    upper: int_table,
    n_upper: int_array,
    lower: int_table,
    n_lower: int_array,
    stashed: pair_table,
    lam: float_grid,
    moved: ti.template(),
    old_id: int_array,
    with_friction: ti.template(),
    friction: vec3f_table,
):
    """:func:`link_lower`, and each pair's accumulated impulse carried from the stashed old lists (see
    :func:`stash` and :func:`carry_ball`) to the new ones, in one launch (neither writes what the
    other reads). With ``moved`` the balls were stored in a new order since the stash: ball i was
    ball ``old_id[i]`` of the stashed lists. With ``with_friction`` the pairs' stashed friction
    impulses (of the Gauss–Seidel sweeps) are carried into ``friction`` too."""
    bits = slot_bits(upper.shape[1])
    for i in range(lower.shape[1]):
        link_ball(i, bits, upper, n_upper, lower, n_lower)
        carry_ball(i, stashed, upper, n_upper, lam, old_id, moved, with_friction, friction)


@ti.func
def carry_ball(
    i,
    stashed: ti.template(),
    upper: ti.template(),
    n_upper: ti.template(),
    lam: ti.template(),
    old_id: ti.template(),
    moved: ti.template(),
    with_friction: ti.template(),
    friction: ti.template(),
):
    """Carry the accumulated impulse of each pair ball i owns in the new lists from the stashed old
    ones (see :func:`stash_ball`), and with ``with_friction`` its friction impulse into
    ``friction``; new pairs start at zero. The pair of balls a and b (their old ids: ``old_id``
    of i and j when ``moved``) is looked up in the row of its old owner, which is a's, or b's
    when the pair changed hands (a pair's owner is the ball behind the other along
    their main axis, see :func:`owns`, and that axis can change as the balls move)."""
    for k in range(n_upper[i]):
        a, b = i, upper[i, k]
        if ti.static(moved):
            a, b = old_id[a], old_id[b]
        found, value, slot = stashed_impulse(stashed, a, b)
        F = ti.Vector([0.0, 0.0, 0.0], dt=ti.f32)
        if found:
            if ti.static(with_friction):
                F = stashed_friction(stashed, a, slot)
        else:
            found, value, slot = stashed_impulse(stashed, b, a)
            if ti.static(with_friction):
                if found:
                    F = -stashed_friction(stashed, b, slot)  # (the friction on the other ball of the pair)
        lam[i, k] = value
        if ti.static(with_friction):
            friction[i, k] = F


@ti.func
def stashed_impulse(stashed: ti.template(), a, b):
    """(whether, with which accumulated impulse, and in which slot) the stashed row of ball a holds
    its pair with ball b: a search of a row sorted by id, stopping at the first id past b."""
    found, value, slot = 0, 0.0, 0
    for k in range(stashed.shape[1]):
        j = stashed_id(stashed, a, k)
        if j < 0 or j > b:
            break
        if j == b:
            found, value, slot = 1, stashed[a, k][0], k
    return found, value, slot


@ti.func
def stashed_id(stashed: ti.template(), i, k):
    """The neighbour id kept by :func:`stash_ball` in slot (i, k) (−1: unused)."""
    return ti.cast(stashed[i, k][1], ti.i32)


@ti.func
def stashed_friction(stashed: ti.template(), i, k):
    """The friction impulse [N·s] kept by :func:`stash_ball` in slot (i, k) (exact: it was f32)."""
    s = stashed[i, k]
    return ti.Vector([s[2], s[3], s[4]], dt=ti.f32)


@ti.func
def relist_all_pairs(
    x: ti.template(),
    radius: ti.template(),
    skin,
    v: ti.template(),
    h,
    v_cut,
    r_cut,
    upper: ti.template(),
    n_upper: ti.template(),
    lower: ti.template(),
    n_lower: ti.template(),
    x_at_build: ti.template(),
    lam: ti.template(),
    scratch: ti.template(),
    friction: ti.template(),
    clear_friction,
):
    """Rebuild the neighbour lists of a few balls in place without a grid, by testing every pair:
    the lists, slots and carried-over impulses that ``list_neighbours`` and ``link_and_carry``
    give on a CPU backend (with the same owners: the balls faster than ``v_cut`` or bigger than
    ``r_cut`` are listed apart unless there are more than ``APART_MAX``), in O(n²) work. The
    tables must be n − 1 wide (no list can overflow). Meant for a serial loop (the ``serial``
    variant of ``collide.collision_step``); ``scratch`` as in :func:`stash_ball`. With
    ``clear_friction`` the pairs' friction impulses (of the Gauss–Seidel sweeps) are set to zero:
    they are not carried over in place."""
    n_apart = 0
    for i in range(x.shape[0]):
        stash_ball(i, upper, n_upper, lam, scratch, False, friction)
        if is_apart(v, radius, i, v_cut, r_cut, 1):  # as apart_balls counts them
            n_apart += 1
    if n_apart > APART_MAX:
        n_apart = 0
    for i in range(x.shape[0]):
        xi, ri = x[i], of_ball(radius, i)
        apart_i = is_apart(v, radius, i, v_cut, r_cut, n_apart)
        n_up, n_low = 0, 0
        for j in range(x.shape[0]):  # in id order: the lists come out sorted
            reach = ri + of_ball(radius, j) + pair_reach(skin, h, v[i], v[j])
            if j != i and (x[j] - xi).norm_sqr() < reach * reach:  # the test of list_ball
                if owns(xi, x[j], i, j, apart_i, is_apart(v, radius, j, v_cut, r_cut, n_apart)):
                    upper[i, n_up] = j
                    n_up += 1
                else:
                    lower[n_low, i] = j
                    n_low += 1
        n_upper[i], n_lower[i] = n_up, n_low
        x_at_build[i] = ti.cast(xi, ti.f32)
    bits = slot_bits(upper.shape[1])
    for i in range(x.shape[0]):
        link_ball(i, bits, upper, n_upper, lower, n_lower)
    for i in range(x.shape[0]):
        carry_ball(i, scratch, upper, n_upper, lam, n_upper, False, False, friction)  # ids unchanged
        if clear_friction:  # (not carried: the pairs' friction impulses start again from zero)
            for k in range(n_upper[i]):
                friction[i, k] = ti.Vector([0.0, 0.0, 0.0], dt=ti.f32)


@ti.func
def moved_past(x1, x_build, reach, half_skin):
    """Whether a ball now at ``x1`` [m], which may move ``reach`` [m] more before the next step's
    test, can be farther than ``half_skin`` [m] from where it was when the lists were built.

    The position at the build, ``x_build``, is kept in f32 (12 bytes per ball less in f64): it
    only serves this test. Rounding moved it by at most 2^-24·|x| (round to nearest), so the test
    adds twice that, |x_build|·2^-23 (in f64; nothing in f32, where nothing was rounded): a ball
    never moves past half the skin unseen, and the lists are rebuilt a little early, by 2 % of
    half the skin of a golf ball (1.07 mm) for a ball 170 m from the origin, by 11 % at 1 km."""
    xb = ti.cast(x_build, float)
    margin = 0.0
    if ti.static(is_f64()):
        margin = xb.norm() * 2.0**-23
    return (x1 - xb).norm() + margin + reach > half_skin
