"""Where a rebuild of the neighbour lists keeps the old lists' pairs (the *stash*, see
``links.stash``): each pair's row in the sweep's table, free between steps, holds its resting
impulse, its neighbour's id and, with the Gauss–Seidel sweeps, its friction impulse in 32 bits,
laid out as the old pair tables were (``stash_first``). The new lists read it back by pair
(:func:`stashed_row`): to carry the impulses over, and to keep the lists of the balls that did
not move (``grid.list_neighbours``)."""

import taichi as ti

from ti_golf.physics.types import FRIC, ID, is_f64


@ti.func
def put_id(scratch: ti.template(), p, j, with_friction: ti.template()):
    """Write the ball id j (or −1, a list's end) into column ``ID`` of row p of ``scratch``: in
    the f32 tables (the Gauss–Seidel sweeps', and every table in f32: ``types.pair_table_type``)
    its 32 bits, never read as a number, so that any i32 id is kept; in an f64 table its value
    (exact below 2^53)."""
    if ti.static(with_friction or not is_f64()):
        scratch[p, ID] = ti.bit_cast(ti.cast(j, ti.i32), ti.f32)
    else:
        scratch[p, ID] = ti.cast(j, float)


@ti.func
def stashed_id_bits(scratch: ti.template(), p, with_friction: ti.template()):
    """(neighbour id, friction bits) of the stashed pair in row p of ``scratch`` (see
    :func:`put_stashed`; the bits are 0 without ``with_friction``)."""
    j, bits = 0, 0
    if ti.static(with_friction or not is_f64()):
        j = ti.bit_cast(scratch[p, ID], ti.i32)
    else:
        j = ti.cast(scratch[p, ID], ti.i32)
    if ti.static(with_friction):
        bits = ti.bit_cast(scratch[p, FRIC], ti.i32)
    return j, bits


@ti.func
def stashed_row(stashed: ti.template(), stash_first: ti.template(), width, a, b, with_friction: ti.template()):
    """(the row, or −1, and the friction bits) of ball a's stashed pair with ball b (see
    :func:`stashed_impulse`): with ``width`` 0 the row is the pair's index in the old lists."""
    row, word = -1, 0
    lo, hi = a * width, a * width + width
    if width == 0:
        lo, hi = stash_first[a], stash_first[a + 1]
    for p in range(lo, hi):
        j, bits = stashed_id_bits(stashed, p, with_friction)  # (−1: the list's end)
        if j < 0 or j > b:
            break
        if j == b:
            row, word = p, bits
    return row, word
