"""Whether the neighbour lists must be rebuilt after a Gauss–Seidel step, pair by pair.

A build lists every pair whose surface gap is below the skin or h·|v_a − v_b|, the reach of its
closing speed (:func:`.grid.pair_reach`). A pair left out may touch in the next step when its gap
now is below 2h·|v_a − v_b|, what it closes in the step ahead at up to twice its relative speed
(:func:`unlisted_within_reach`): the build's rule, kept between builds, and like it blind to a
motion the two balls share. The Jacobi steps rebuild as soon as one ball has used half the skin
(:func:`.links.moved_past`: its distance from the build plus 2h·|v|, the skin it has *used*,
:func:`skin_used`), which bounds every pair. The Gauss–Seidel steps test the pairs themselves
(:func:`flag_stale_lists`). A pair out of the lists was more than the skin apart at the build, and
its gap now, less 2h·|v_a − v_b|, is at least that gap less u_a + u_b: only a pair with a ball
past half the skin can be stale. Such a ball is tested against the balls within u_a + u_b of it
at the build, in the 125 grid cells around its cell then, and the lists are rebuilt only when a
pair within reach is missing from them. The cells are at least 2·r + skin wide, so those 125 hold
every such ball for a ball that used up to about r + skin, not the skin alone
(:func:`searched_reach`): only a ball that used more forces a rebuild by itself, or one that may
touch a plane or the terrain that the build found out of its reach (:func:`surface_unforeseen`).
A ball whose list a build kept (``grid.list_kept``) owes, besides the skin it used since, its
``drift``: the skin it used before that build since its list was made (:func:`skin_owed`); a pair
out of the lists has a gap of at least the skin less what its two balls owe, so a ball is searched
once what it owes and 2h·|v| pass half the skin (the search itself reaches as far as the balls
moved since the build: the grid is the build's).
So one ball rolling over a settled pile, whose neighbours have not moved, uses the whole skin
before it forces a rebuild, not half of it; a ball that bounces over a settling pile at a few
metres a second forces one when it comes near a ball the lists miss or has moved about a radius
since the build, not at every step; and balls falling together, a cell apart, force none until
one has moved about a radius.

Rebuilt earlier or later, the lists hold every pair that can touch in the step; the steps between
differ only in which pairs are listed but still apart, which change nothing (see
:func:`.sequential.pair_step`), and in the order of the balls that the build stores.
"""

import taichi as ti

from ti_golf.physics.types import (
    BallState,
    GridParams,
    GridScratch,
    KeptLists,
    ModelArrays,
    NeighbourLists,
    StepScratch,
    float_array,
    int_array,
    kernel,
    of_ball,
    scalars_of,
    vec3_array,
)
from ti_golf.scene.schema import AT_REST, OUT_OF_BOUNDS
from ti_golf.solvers.links import distance_from_build, listed
from ti_golf.solvers.sort import bucket_of, cell_of
from ti_golf.solvers.step import Step
from ti_golf.solvers.surface_reach import near_a_surface, surface_row

LISTS_STALE = 1
"""Bit of :func:`lists_stale`'s answer: the lists must be rebuilt before the next step."""

BALLS_AWAKE = 2
"""Bit of :func:`lists_stale`'s answer: some ball is awake and in play after the step
(:func:`in_play`), so that the next step is not to be skipped (``colour.moving_balls``, asked of
the balls without a readback of its own)."""

REACH_CELLS = 2
"""Cells on each side of a ball's cell (at the build) in which :func:`stale_near` looks for the
balls it may have come within reach of: every ball whose centre was within two cell sides of it."""

SEARCHED = 0.99
"""The share of a grid cell, less the ball's radius, that a ball may use of the skin before the lists
are rebuilt without a search (:func:`searched_reach`); the 1 % spares the f32 positions of the build
their rounding at a cell's edge."""


@ti.func
def skin_used(x1, x_build, v, h):
    """How much of the skin [m] a ball now at ``x1`` [m] with velocity ``v`` [m/s] has used: its
    distance from ``x_build`` (its position at the build, f32, with the rounding margin of
    :func:`.links.distance_from_build`), plus 2h·|v| for the step ahead (``h`` [s])."""
    return distance_from_build(x1, x_build) + 2.0 * h * v.norm()


@ti.func
def skin_owed(x1, x_build, drift):
    """How much of the skin [m] a ball now at ``x1`` [m] owes: its distance from ``x_build``, its
    position at the last build (:func:`.links.distance_from_build`), plus its ``drift`` [m], the
    skin it used before that build since its list was made (0 unless the build kept its list)."""
    return distance_from_build(x1, x_build) + drift


@kernel
def mark_kept(
    x: vec3_array,
    v: vec3_array,
    lists: NeighbourLists,
    skin: float,
    h: float,
    sorted_ids: int_array,
    reordered: ti.template(),
    kept: KeptLists,
):
    """Before a build that keeps the lists of the balls that did not move (``amend`` of
    ``grid.list_neighbours``): each ball's skin owed (:func:`skin_owed`) into ``kept.marks[p][0]``,
    and 1 into ``kept.marks[p][1]`` when its list is made again: when what it owes and 2h·|v| for
    the step ahead (``h`` [s]) pass half the ``skin`` [m], as a ball is searched for pairs the
    lists miss (:func:`flag_stale_lists`); and each ball's new index by its old one into
    ``kept.new_index``. ``x``, ``v``: the balls' positions [m] and velocities [m/s] in the build's
    order; ``lists``: the old lists, in the old order; with ``reordered``, ball p of the build's
    order was ball ``sorted_ids[p]``."""
    for p in range(x.shape[0]):
        o = p
        if ti.static(reordered):
            o = sorted_ids[p]
        owed = skin_owed(x[p], lists.x_at_build[o], ti.cast(lists.drift[o], float))
        anew = 0.0
        if owed + 2.0 * h * v[p].norm() > 0.5 * skin:
            anew = 1.0
        kept.marks[p] = ti.Vector([owed, anew, 0.0])
        kept.new_index[o] = p


@ti.func
def pair_listed(i, j, lists: ti.template()):
    """Whether the lists hold the pair of balls i and j (in either ball's upper list)."""
    found = False
    for k in range(listed(lists.first, i)):
        if lists.upper[i, k] == j:
            found = True
            break  # (an early exit: also keeps LLVM from vectorising a loop of a few pairs)
    if not found:
        for k in range(listed(lists.first, j)):
            if lists.upper[j, k] == i:
                found = True
                break
    return found


@ti.func
def unlisted_within_reach(i, j, h, radius: ti.template(), lists: ti.template(), x1: ti.template(), v: ti.template()):
    """Whether balls i and j (j ≠ i) form a pair the lists miss that may touch in the next step
    (``h`` [s]): their surface gap now below 2h·|v_i − v_j| (``x1``, ``v``: the balls' new
    positions [m] and velocities [m/s])."""
    stale = False
    if j != i:
        gap = (x1[i] - x1[j]).norm() - of_ball(radius, i) - of_ball(radius, j)
        if gap < 2.0 * h * (v[i] - v[j]).norm():
            if not pair_listed(i, j, lists):
                stale = True
    return stale


@ti.func
def set_apart(i, apart_ids: ti.template(), n_apart):
    """Whether ball i is one of the ``n_apart`` balls the last build set apart (``apart_ids``)."""
    found = False
    for f in range(n_apart):
        if apart_ids[f] == i:
            found = True
            break
    return found


@ti.func
def stale_by_every_ball(i, h, radius: ti.template(), lists: ti.template(), x1: ti.template(), v: ti.template()):
    """Whether ball i has come within reach of a ball the lists miss, every ball tested."""
    stale = False
    for j in range(x1.shape[0]):
        if unlisted_within_reach(i, j, h, radius, lists, x1, v):
            stale = True
            break
    return stale


@ti.func
def stale_near(
    i,
    g: ti.template(),
    start: ti.template(),
    sorted_ids: ti.template(),
    apart_ids: ti.template(),
    stored_sorted: ti.template(),
    radius: ti.template(),
    lists: ti.template(),
    x1: ti.template(),
    v: ti.template(),
):
    """:func:`stale_by_every_ball`, with the grid of the last build (``g``: its
    :data:`ti_golf.physics.types.GridParams`; ``start``, ``sorted_ids``: its buckets, see
    :func:`.grid.list_neighbours` for ``stored_sorted``): the balls of the ``REACH_CELLS`` cells
    around ball i's at the build, and the balls listed apart (every ball, for a ball listed apart),
    as the build tested them. The candidates come in runs (:func:`candidate_run`), all tested by
    one call site of :func:`unlisted_within_reach`, which Taichi's front end inlines once."""
    every = g.scan_apart != 0 and set_apart(i, apart_ids, g.n_apart)
    c = cell_of(ti.cast(lists.x_at_build[i], float), g.inv_cell)
    runs = 1 if every else 2 * COLUMNS + 1
    stale = False
    for q in range(runs):
        lo, hi = candidate_run(q, every, c, g, start, x1.shape[0])
        apart_run = q == 2 * COLUMNS  # the balls listed apart
        for k in range(lo, hi):
            j = k  # every ball, or the grid's k-th
            if apart_run:
                j = apart_ids[k]
            elif not every:
                if ti.static(not stored_sorted):
                    j = sorted_ids[k]
            if unlisted_within_reach(i, j, g.h, radius, lists, x1, v):
                stale = True
                break
        if stale:
            break
    return stale


SPAN = 2 * REACH_CELLS + 1
"""Cells along each axis of the box around a ball's cell that :func:`stale_near` searches."""

COLUMNS = SPAN * SPAN
"""The columns of cells, each ``SPAN`` cells tall, around a ball's cell that :func:`stale_near` searches."""


@ti.func
def candidate_run(q, every, c, g: ti.template(), start: ti.template(), n):
    """Run q of :func:`stale_near`'s candidates, as a range [lo, hi): with ``every`` (a ball
    listed apart) the n balls; else run 2·m + part, for m < ``COLUMNS``, the part (the second where
    it wraps around the table's end) of the buckets of column m of cells around cell ``c`` (from
    the grid ``g`` and its bucket starts ``start``), and run 2·``COLUMNS`` the balls listed apart
    (``apart_ids``' first ``g.n_apart`` with ``g.scan_apart``)."""
    lo, hi = 0, n
    if not every:
        if q == 2 * COLUMNS:
            hi = g.n_apart * g.scan_apart
        else:
            m, part = q // 2, q % 2
            row = c + ti.Vector([m % SPAN - REACH_CELLS, -REACH_CELLS, m // SPAN - REACH_CELLS])
            b = bucket_of(row, g.mask, g.origin, g.stride)
            lo, hi = start[b], start[ti.min(b + SPAN, g.mask + 1)]
            if part == 1:  # the run wraps around the table's end
                lo, hi = start[0], start[ti.max(b + SPAN - (g.mask + 1), 0)]
    return lo, hi


@ti.func
def searched_reach(i, serial: ti.template(), g: ti.template(), radius: ti.template(), params: ti.template()):
    """The most skin [m] ball i may use before the lists are rebuilt without a search
    (:func:`flag_stale_lists`), for the pairs the lists miss, among every ball (``serial``): the
    skin; among the ``REACH_CELLS`` cells around it (the grid ``g``, of cell side w): w·``SEARCHED``
    less its radius r_i, and at least the skin (a ball set apart for its size, wider than a cell,
    searches every ball). A pair the lists miss touches only when r_a + r_b + u_a + u_b exceeds the
    distance of its centres at the build; with each ball's u below that reach, the distance is under
    2·w·``SEARCHED``, so the other ball lies in the cells searched."""
    reach = params.skin
    if ti.static(not serial):
        reach = ti.max(params.skin, SEARCHED / g.inv_cell - of_ball(radius, i))
    return reach


@ti.func
def surface_unforeseen(i, x1, ahead, s: ti.template()):
    """Whether ball i, now at ``x1`` [m] and past the skin since the build, may touch in the next
    step, moving no farther than ``ahead`` [m] (2h·|v|, as :func:`skin_used` counts the step
    ahead), a plane or the terrain that the build found out of its reach, so that it keeps no row
    of surface impulses for it (:func:`.surfaces.list_surfaces`, which gives rows to the balls
    within the skin of a surface): the lists are then rebuilt before that step (``s``: the step's
    :class:`.step.Step`). Asked at every step of such a ball, from where it is, not from where it
    was at the build: a ball falling past a wall does not force a rebuild for the wall."""
    unforeseen = False
    if surface_row(s.lists.surface_start, i) < 0:
        unforeseen = near_a_surface(i, x1, ahead, ti.static(s.kinds.terrain), s.terrain, s.model)
    return unforeseen


@ti.func
def flag_stale_lists(
    s: ti.template(),
    serial: ti.template(),
    g: ti.template(),
    grid: ti.template(),
    apart_ids: ti.template(),
    stored_sorted: ti.template(),
):
    """Set ``scratch.flag[0]`` when the lists must be rebuilt before the next step of balls now at
    ``scratch.x_free`` [m] with velocities ``state.v`` [m/s] (``s``: the step's
    :class:`.step.Step`, of which the radii, lists, state, scratch and the step's scalars, h and
    the skin, are read): a ball has used more than the reach of a search (:func:`searched_reach`)
    or may touch a surface it keeps no row for (:func:`surface_unforeseen`), or a pair out of the
    lists is within reach of a ball that owes more than half the skin, counting 2h·|v| for the
    step ahead (:func:`skin_owed`; see the module's docstring), looked for only when no ball has forced a rebuild by itself, with the
    grid of the last build (``g``, ``grid``: its :data:`ti_golf.physics.types.GridParams` and
    :data:`ti_golf.physics.types.GridScratch`, or what holds its ``start`` and ``sorted_ids``;
    ``apart_ids``, ``stored_sorted``: see :func:`stale_near`) or, ``serial``, among every ball (the
    four are not read, and the reach of a search is the skin)."""
    params, radius, lists, state, scratch = ti.static((s.params, s.model.radius, s.lists, s.state, s.scratch))
    for i in range(scratch.x_free.shape[0]):
        used = skin_used(scratch.x_free[i], lists.x_at_build[i], state.v[i], params.h)
        if used > searched_reach(i, serial, g, radius, params):
            scratch.flag[0] = 1
        elif used > params.skin:  # (only without ``serial``: see searched_reach)
            if surface_unforeseen(i, scratch.x_free[i], 2.0 * params.h * state.v[i].norm(), s):
                scratch.flag[0] = 1
    for i in range(scratch.x_free.shape[0]):  # (a second loop: no ball searched when one used its reach)
        if scratch.flag[0] == 0:  # (once the lists must be rebuilt, no other ball need be tested)
            used = skin_used(scratch.x_free[i], lists.x_at_build[i], state.v[i], params.h)
            owed = used + lists.drift[i]  # (see skin_owed)
            if owed > params.half_skin and used <= searched_reach(i, serial, g, radius, params):
                stale = False
                if ti.static(serial):
                    stale = stale_by_every_ball(i, params.h, radius, lists, scratch.x_free, state.v)
                else:
                    stale = stale_near(
                        i,
                        g,
                        grid.start,
                        grid.sorted_ids,
                        apart_ids=apart_ids,
                        stored_sorted=stored_sorted,
                        radius=radius,
                        lists=lists,
                        x1=scratch.x_free,
                        v=state.v,
                    )
                if stale:
                    scratch.flag[0] = 1


@kernel
def lists_stale(
    scalars: float_array,
    g: GridParams,
    grid: GridScratch,
    apart_ids: int_array,
    stored_sorted: ti.template(),
    kinds: ti.template(),
    model: ModelArrays,
    lists: NeighbourLists,
    state: BallState,
    scratch: StepScratch,
) -> ti.i32:
    """What the host needs after a parallel Gauss–Seidel step (its projection done), in one
    readback: ``LISTS_STALE`` when the lists must be rebuilt (:func:`flag_stale_lists` with the
    grid of the last build, ``g``, ``grid``, ``apart_ids`` and ``stored_sorted`` as
    :func:`.grid.list_neighbours` had them, and the step's scalars,
    :func:`ti_golf.physics.types.scalars_of`), plus ``BALLS_AWAKE`` when some ball is awake and
    in play."""
    _air, contact, terrain, params = scalars_of(scalars)
    s = ti.static(Step(contact, terrain, params, model, lists, state, scratch, kinds=kinds))
    flag_stale_lists(s, serial=False, g=g, grid=grid, apart_ids=apart_ids, stored_sorted=stored_sorted)
    return LISTS_STALE * ti.min(scratch.flag[0], 1) + BALLS_AWAKE * ti.min(balls_in_play(state.status), 1)


@ti.func
def balls_in_play(status: ti.template()):
    """How many balls of ``status`` are awake and in play (:func:`in_play`): a loop of its own at
    a kernel's top level, else in the calling thread. An integer sum: the same on every thread
    order."""
    moving = 0
    for i in range(status.shape[0]):
        moving += in_play(status[i])
    return moving


@ti.func
def in_play(status):
    """1 for a ball of ``status`` awake and in play (neither ``AT_REST`` nor ``OUT_OF_BOUNDS``), else 0."""
    return ti.cast(status != AT_REST and status != OUT_OF_BOUNDS, ti.i32)
