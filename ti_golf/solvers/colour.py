"""Gauss–Seidel sweeps over the ball pairs, coloured by grid columns (``contact.solver =
"gauss_seidel"``).

A Jacobi sweep (:mod:`.collide`) computes every pair's impulse from the velocities of the sweep
before, so a support found at the bottom of a pile climbs one layer per sweep, and a ball pressed
by many neighbours gets all their corrections at once. A Gauss–Seidel sweep applies each pair's
impulse at once, so the next pair already sees it: down a column of balls handled bottom-up, the
floor's support reaches the top in one sweep.

To run in parallel and still give the same result on every thread order, the balls are grouped by
*block*: 2 × 2 vertical columns of grid cells (x, z), as they were when the neighbour lists were
built (:func:`column_order`), sorted bottom-up inside a block, and the blocks are given one of four
colours by the parities of their coordinates (:func:`colour_of`). A listed pair's balls were at
most one cell apart along x and z at the build (the cells are wider than any listed pair reaches,
see :mod:`.grid`), so a block's pairs touch only balls of that block and the eight around it, and
two blocks of one colour are a block apart: the blocks of a colour are swept in parallel, one
thread per block, without two threads ever writing one ball. The four colours follow one another in
one launch (:func:`gauss_seidel_sweep`: a top-level loop each, :func:`block_sweep`). The few pairs
whose balls were farther apart (a ball set apart as much bigger or faster than the rest, see
:mod:`.apart`) are swept after the colours, one after another (:func:`far_pairs`). The position
projection at the end of the step is laid out the same way (:func:`project_sweep`); a serial step
sweeps every ball in storage order (:func:`serial_sweeps`, :func:`serial_projection`).

Each pair's update is :func:`.sequential.sweep_pair` (the sequential impulses of
:func:`.sequential.pair_step`), with its accumulated resting and friction impulses carried from
step to step; each ball meets its planes and the terrain right after its pairs
(:func:`sweep_ball`).
"""

import taichi as ti

from ti_golf.physics.types import (
    BallState,
    BlockOrder,
    ModelArrays,
    NeighbourLists,
    StepScratch,
    float_array,
    int_array,
    ivec3,
    kernel,
    of_ball,
    scalars_of,
    vec3f_array,
)
from ti_golf.scene.schema import AT_REST, OUT_OF_BOUNDS
from ti_golf.solvers.links import listed
from ti_golf.solvers.pairs import QUIET
from ti_golf.solvers.phases import Phase
from ti_golf.solvers.sequential import (
    body,
    project_pair,
    project_planes,
    stands_firm,
    sweep_constants,
    sweep_pair,
)
from ti_golf.solvers.sort import bucket_in_turn, cell_of, counting_sort, sort_bucket, spread_turns, task_stride
from ti_golf.solvers.stale import balls_in_play, flag_stale_lists
from ti_golf.solvers.step import Step
from ti_golf.solvers.surfaces import beyond_reach, surface_impulses

PROJECTIONS = 3
"""Passes of the position projection (B.18, :func:`project_sweep`) at the end of a Gauss–Seidel
step. A pass moves each overlapping pair apart by k_p of its overlap; a ball wedged between
neighbours is pushed back in by the pairs handled after its own, so a pile needs more than one
pass to shed such overlaps (docs/solvers.md, "Gauss–Seidel sweeps")."""

COLOURS = 4
"""Colours of the blocks of 2 × 2 grid columns: the parities of the block's coordinates."""

REGION_HOPS = 8
"""Contacts between a ball and the nearest moving one beyond which the ball may fall asleep, with
the Gauss–Seidel sweeps (``pairs.island_calm``): each contact nearer the moving ball takes
``world.t_rest`` / ``REGION_HOPS`` off how long the ball counts as calm."""

ASLEEP_OVERLAP = 0.005
"""Deepest overlap, as a share of the radius, with which a ball may fall asleep with the
Gauss–Seidel sweeps (1 % with the Jacobi sweeps): a ball asleep is no longer projected out of its
overlaps with other balls asleep, so it falls asleep only with half the overlap a settled pile may
have."""


@kernel
def moving_balls(status: int_array) -> ti.i32:
    """How many balls are awake and in play: neither asleep (``AT_REST``) nor out of bounds. With
    the Gauss–Seidel sweeps, a step in which none is changes nothing (:func:`stands_firm`: a ball
    asleep takes no impulse and does not move, and only a moving ball wakes it)."""
    return balls_in_play(status)


@ti.func
def region_hop(kinds: ti.template(), params: ti.template()):
    """What each contact nearer a moving ball takes off how long a ball counts as calm [s]
    (``pairs.island_calm``): t_rest / ``REGION_HOPS`` with the Gauss–Seidel sweeps
    (``kinds.gauss_seidel``), else 0 (the Jacobi sweeps put islands to sleep)."""
    hop = 0.0
    if ti.static(kinds.gauss_seidel):
        hop = params.t_rest / REGION_HOPS
    return hop


@ti.func
def column_of(x, inv_cell):
    """Integer (x, z) coordinates of the grid column holding point ``x`` [m]."""
    c = cell_of(x, inv_cell)
    return ti.Vector([c[0], c[2]])


@ti.func
def block_of(x, inv_cell):
    """Integer (x, z) coordinates of the *block* holding point ``x`` [m]: a column two grid cells
    wide along x and z."""
    return column_of(x, 0.5 * inv_cell)


@ti.func
def colour_of(block):
    """The colour, 0 to 3, of a block (:func:`block_of`): its coordinates' parities."""
    return (block[0] % 2 + 2) % 2 + 2 * ((block[1] % 2 + 2) % 2)


@ti.func
def adjacent(col_a, col_b):
    """Whether two grid columns are the same or neighbours (8-connected)."""
    d = col_a - col_b
    return ti.abs(d[0]) <= 1 and ti.abs(d[1]) <= 1


@ti.func
def in_this_pass(col, j, far_only, any_far, inv_cell, lists: ti.template()):
    """Whether a pair of a ball in grid column ``col`` with ball j is taken by the colours
    (``far_only`` False) or by :func:`far_pairs` (True): with ``any_far``, the pairs whose balls
    were not in columns beside each other at the build are :func:`far_pairs`' alone."""
    far = False
    if any_far != 0:
        far = not adjacent(col, column_of(lists.x_at_build[j], inv_cell))
    return far == (far_only != 0)


@kernel
def column_order(
    x_at_build: vec3f_array,
    inv_cell: float,
    mask: ti.i32,
    origin: ivec3,
    stride: ivec3,
    rank: int_array,
    start: int_array,
    chunk_start: int_array,
    ids: int_array,
    colour: int_array,
    tasks: ti.i32,
    lists: NeighbourLists,
) -> ti.i32:
    """Group the balls by block for the sweeps: ``ids[start[b] : start[b + 1]]`` are the balls of
    hash bucket b (the blocks, cells of side 2/``inv_cell`` hashed with ``origin`` and ``stride``,
    whose y stride is 0), bottom-up (then by z, x and id, so the order does not depend on thread
    scheduling), and ``colour[s]`` is the colour of ball ``ids[s]``'s block. Positions are those of the lists' build, in f32, so that
    the columns are those the pair tests of the sweeps see. Returns how many balls own a pair whose
    other ball was not in their grid column or one beside it (:func:`far_pairs` takes those)."""
    inv_block = 0.5 * inv_cell
    counting_sort(
        x_at_build, inv_block, mask, origin, stride, rank=rank, start=start, chunk_start=chunk_start, sorted_ids=ids
    )
    buckets = start.shape[0] - 1
    for t in range(tasks * ti.static(task_stride())):  # (the blocks spread over the threads: see spread_turns)
        turn0, turns = spread_turns(t, tasks, buckets)
        for k in range(turns):
            sort_bucket(bucket_in_turn(turn0 + k * tasks, buckets), x_at_build, start, ids)
    for s in range(ids.shape[0]):
        colour[s] = colour_of(block_of(x_at_build[ids[s]], inv_cell))
    far_owners = 0  # the balls that own a pair with a ball not in their grid column or one beside it
    for i in range(x_at_build.shape[0]):
        col = column_of(x_at_build[i], inv_cell)
        far = 0
        for k in range(listed(lists.first, i)):
            if not adjacent(col, column_of(x_at_build[lists.upper[i, k]], inv_cell)):
                far = 1
        far_owners += far  # (an integer sum: the same on every thread order)
    return far_owners


@kernel
def gauss_seidel_sweep(
    phase: ti.i32,
    any_far: ti.i32,
    inv_cell: float,
    tasks: ti.i32,
    kinds: ti.template(),
    scalars: float_array,
    model: ModelArrays,
    lists: NeighbourLists,
    state: BallState,
    scratch: StepScratch,
    blocks: BlockOrder,
):
    """One Gauss–Seidel sweep of ``phase`` (:func:`.sequential.pair_step`), colour after colour: the
    balls of every block of a colour, each block bottom-up in one thread (see the module's
    docstring; ``blocks`` from :func:`column_order`), meet the pairs they own (but, when
    ``any_far``, those whose other ball was not beside them at the build), then their planes and
    the terrain (:func:`sweep_ball`), with the parameters in ``scalars``
    (:func:`ti_golf.physics.types.scalars_of`) and the scene's ``kinds`` of code."""
    air, contact, terrain, params = scalars_of(scalars)  # (the air: a surface's inelastic speed, surfaces.air_push)
    s = ti.static(Step(contact, terrain, params, model, lists, state, scratch, kinds=kinds, air=air))
    block_sweep(phase, project=False, any_far=any_far, inv_cell=inv_cell, tasks=tasks, blocks=blocks, s=s)


@kernel
def project_sweep(
    any_far: ti.i32,
    inv_cell: float,
    tasks: ti.i32,
    scalars: float_array,
    model: ModelArrays,
    lists: NeighbourLists,
    state: BallState,
    scratch: StepScratch,
    blocks: BlockOrder,
):
    """A pass of the position projection (B.18) of a Gauss–Seidel step, colour after colour as in
    :func:`gauss_seidel_sweep`, on the step's new positions ``scratch.x_free``
    (:func:`project_ball`); after the last, :func:`.stale.lists_stale` tells whether the lists
    must be rebuilt before the next step."""
    _air, contact, terrain, params = scalars_of(scalars)
    s = ti.static(Step(contact, terrain, params, model, lists, state, scratch))
    block_sweep(Phase.PROJECT, project=True, any_far=any_far, inv_cell=inv_cell, tasks=tasks, blocks=blocks, s=s)


@ti.func
def block_sweep(phase, project: ti.template(), any_far, inv_cell, tasks, blocks: ti.template(), s: ti.template()):
    """A sweep of ``phase`` (:func:`sweep_ball`) or, with ``project``, a pass of the position
    projection (:func:`project_ball`) over the balls block by block (``blocks``), colour after
    colour: a top-level loop per colour, the blocks of a colour spread over ``tasks`` threads (see
    :func:`.sort.spread_turns`), each block's balls bottom-up in its thread."""
    buckets = blocks.start.shape[0] - 1
    for c in ti.static(range(COLOURS)):  # a top-level loop per colour: the colours in turn
        for t in range(tasks * ti.static(task_stride())):  # (the blocks spread over the threads: see spread_turns)
            turn0, turns = spread_turns(t, tasks, buckets)
            for k in range(turns):
                b = bucket_in_turn(turn0 + k * tasks, buckets)
                for m in range(blocks.start[b], blocks.start[b + 1]):
                    if blocks.colour[m] == c:
                        ball_pass(blocks.ids[m], phase, project, any_far, inv_cell, s)


@ti.func
def ball_pass(i, phase, project: ti.template(), any_far, inv_cell, s: ti.template()):
    """Ball i's part of a sweep of ``phase`` by the colours (:func:`sweep_ball`) or, with
    ``project``, of a pass of the position projection (:func:`project_ball`)."""
    if ti.static(project):
        project_ball(i, far_only=False, any_far=any_far, inv_cell=inv_cell, s=s)
    else:
        sweep_ball(i, phase, far_only=False, any_far=any_far, inv_cell=inv_cell, s=s)


@kernel
def far_pairs(
    phase: ti.i32,
    inv_cell: float,
    kinds: ti.template(),
    scalars: float_array,
    model: ModelArrays,
    lists: NeighbourLists,
    state: BallState,
    scratch: StepScratch,
):
    """The pairs the colours left out (their balls were farther apart than beside each other at the
    build), one ball after another in storage order (``kinds``: the scene's kinds of code)."""
    air, contact, terrain, params = scalars_of(scalars)  # (the air: a surface's inelastic speed, surfaces.air_push)
    s = ti.static(Step(contact, terrain, params, model, lists, state, scratch, kinds=kinds, air=air))
    ti.loop_config(serialize=True)
    for i in range(state.x.shape[0]):
        if phase == Phase.PROJECT:
            project_ball(i, far_only=True, any_far=1, inv_cell=inv_cell, s=s)
        else:
            sweep_ball(i, phase, far_only=True, any_far=1, inv_cell=inv_cell, s=s)


@ti.func
def serial_sweeps(iterations: ti.template(), s: ti.template()):
    """A step's ``iterations`` Gauss–Seidel sweeps and the restitution pass (:func:`step_phases`),
    every ball in storage order, in the calling (serial) loop's thread (``s``: the step's
    :class:`.step.Step`; one call site of the ball's sweep, which each inlines whole)."""
    for k in range(iterations + 1):
        phase = phase_of_sweep(k, iterations)
        for i in range(s.state.x.shape[0]):
            sweep_ball(i, phase, far_only=False, any_far=0, inv_cell=1.0, s=s)


@ti.func
def phase_of_sweep(k, iterations: ti.template()):
    """The phase of sweep k (0 to ``iterations``) of a step, as :func:`step_phases` lists them:
    ``FIRST``, ``SOLVE`` …, ``SHOCK`` (with two sweeps or more), then the restitution pass,
    ``BOUNCE``."""
    phase = Phase.SOLVE
    if k == 0:
        phase = Phase.FIRST
    elif k == iterations:
        phase = Phase.BOUNCE
    elif k == iterations - 1:
        phase = Phase.SHOCK
    return phase


def step_phases(iterations: int) -> list[int]:
    """The phases of a step's ``iterations`` sweeps and its restitution pass: ``FIRST``, then
    ``SOLVE``, the last sweep ``SHOCK`` (with two or more), then ``BOUNCE``."""
    sweeps = [Phase.FIRST] + [Phase.SOLVE] * max(iterations - 2, 0) + [Phase.SHOCK] * (iterations > 1)
    return sweeps + [Phase.BOUNCE]


@ti.func
def sweep_ball(i, phase, far_only, any_far, inv_cell, s: ti.template()):
    """Ball i's Gauss–Seidel step (``s``: the step's :class:`.step.Step`): each pair it owns
    (:func:`.sequential.sweep_pair`, from the current velocities of both balls, applied to both at
    once, with the normal and gap the warm start stored in ``scratch.J``), then (unless
    ``far_only``) its planes and the terrain, with the step's scalars ``params`` (h, and gravity
    for the inelastic speed and the shock sweep's "up"). When ``any_far``, a pair whose other ball
    was not in a column beside i's at the build is taken only with ``far_only``
    (:func:`far_pairs`), and the others only without. A quiet ball (at rest among balls at rest) is
    skipped, and gets nothing from its neighbours' pairs, as in a Jacobi sweep. The first sweep
    marks in ``scratch.impact[i]`` whether one of ball i's pairs approached faster than the
    inelastic speed; the restitution pass (``BOUNCE``), which changes no other pair, visits only
    the pairs of the balls so marked."""
    contact, model, lists, state, scratch = ti.static((s.contact, s.model, s.lists, s.state, s.scratch))
    if state.status[i] != OUT_OF_BOUNDS and scratch.calm[i] != QUIET:
        if not alone_and_clear(i, project=False, s=s):  # (nested: see alone_and_clear)
            k = sweep_constants(contact, s.params)
            xi, vi, wi = state.x[i], state.v[i], state.w[i]
            ri, inv_mi = of_ball(model.radius, i), 1.0 / of_ball(model.mass, i)
            firm = stands_firm(s.kinds, state.status[i])
            if firm:
                inv_mi = 0.0
            col = column_of(lists.x_at_build[i], inv_cell)
            owned = listed(lists.first, i)
            if phase == Phase.BOUNCE and scratch.impact[i] == 0:
                owned = 0  # none of its pairs approached fast enough to bounce: the pass changes none
            approached = 0
            p0 = lists.first[i]
            for m in range(owned):
                j, p = lists.upper[i, m], p0 + m
                if in_this_pass(col, j, far_only, any_far, inv_cell, lists):
                    vi, wi, hit = sweep_pair(i, j, p, phase, xi, body(vi, wi, ri, inv_mi), k, s)
                    approached = ti.max(approached, hit)
            if phase == Phase.FIRST:  # the restitution pass visits the pairs of the balls marked here
                if far_only:
                    scratch.impact[i] = ti.max(scratch.impact[i], approached)  # (after the colours)
                else:
                    scratch.impact[i] = approached
            if not far_only and not firm:
                vi, wi = surface_impulses(
                    i, warm=False, vi=vi, wi=wi, h=k.h, v_inelastic=k.v_inelastic, s=s, phase=phase
                )
            state.v[i], state.w[i] = vi, wi


@ti.func
def serial_projection(s: ti.template()):
    """The position projection of :func:`project_sweep`, ``PROJECTIONS`` passes of every ball in
    storage order, then whether the lists must be rebuilt (:func:`.stale.flag_stale_lists`, every
    ball tested), in the calling (serial) loop's thread."""
    for _ in range(PROJECTIONS):
        for i in range(s.state.x.shape[0]):
            project_ball(i, far_only=False, any_far=0, inv_cell=1.0, s=s)
    flag_stale_lists(s, serial=True, g=0, grid=0, apart_ids=0, stored_sorted=False)


@ti.func
def project_ball(i, far_only, any_far, inv_cell, s: ti.template()):
    """Ball i's position projection at the end of a Gauss–Seidel step, on the new positions
    ``scratch.x_free`` [m]: each pair it owns that overlaps by Δx moves apart by k_p·Δx, ball i by
    k_p·m_red·Δx along the normal and the other ball the rest (B.18); a ball at rest does not move
    (the other ball takes the whole projection). Then (unless ``far_only``) what overlaps a plane
    moves out by k_p of the overlap. Pairs are split between the colours and :func:`far_pairs` as
    in :func:`sweep_ball`. Moves only positions: the velocities, and so the energy, are untouched."""
    model, lists, state, scratch = ti.static((s.model, s.lists, s.state, s.scratch))
    k_p = s.contact.k_p
    if state.status[i] != OUT_OF_BOUNDS and scratch.calm[i] != QUIET:
        if not alone_and_clear(i, project=True, s=s):  # (nested: see alone_and_clear)
            xi, ri = scratch.x_free[i], of_ball(model.radius, i)
            inv_mi = 0.0
            if state.status[i] != AT_REST:
                inv_mi = 1.0 / of_ball(model.mass, i)
            col = column_of(lists.x_at_build[i], inv_cell)
            for k in range(listed(lists.first, i)):
                j = lists.upper[i, k]
                if in_this_pass(col, j, far_only, any_far, inv_cell, lists):
                    xi = project_pair(j, xi, ri, inv_mi, k_p, model, state, scratch)
            if not far_only and inv_mi > 0.0:
                xi = project_planes(xi, ri, k_p, model)
            scratch.x_free[i] = xi


@ti.func
def alone_and_clear(i, project: ti.template(), s: ti.template()):
    """Whether a sweep or, with ``project``, a projection pass leaves ball i as it is, so that it
    need not be read (``s``: the step's :class:`.step.Step`): it has no pair in the lists, neither
    owned nor owned by another ball (``lists.lower_first``), so that only a surface could change
    it, and its surface clearance (``scratch.clear``) keeps it out of reach of every plane and the
    terrain (:func:`.surfaces.beyond_reach`) while its gaps shrink by h·|v| in a sweep (the test
    by which the sweep itself skips the surfaces), or by its move over the step in a projection.
    Most balls of a pour in flight are so: their sweeps would read their state and write it back
    unchanged. The tests are nested, so that a ball with pairs costs one comparison. A sweep
    skipping the ball leaves its impact mark (``scratch.impact``) as it was: the restitution pass
    reads it only for the ball's own pairs, and it has none."""
    alone = False
    if listed(s.lists.first, i) == 0:  # (nested: Taichi evaluates both sides of an `and`)
        if s.lists.lower_first[i + 1] == s.lists.lower_first[i]:
            reach_sqr = 0.0
            if ti.static(project):
                reach_sqr = (s.scratch.x_free[i] - s.state.x[i]).norm_sqr()
            else:
                reach_sqr = s.params.h * s.params.h * s.state.v[i].norm_sqr()
            alone = beyond_reach(s.scratch.clear[i], of_ball(s.model.radius, i), reach_sqr)
    return alone
