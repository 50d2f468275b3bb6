"""Gauss–Seidel sweeps over the ball pairs, coloured by grid columns (``contact.solver =
"gauss_seidel"``).

A Jacobi sweep (:mod:`.collide`) computes every pair's impulse from the velocities of the sweep
before, so a support found at the bottom of a pile climbs one layer per sweep, and a ball pressed
by many neighbours gets all their corrections at once. A Gauss–Seidel sweep applies each pair's
impulse at once, so the next pair already sees it: down a column of balls handled bottom-up, the
floor's support reaches the top in one sweep.

To run in parallel and still give the same result on every thread order, the balls are grouped by
the vertical *column* of grid cells (x, z) they were in when the neighbour lists were built
(:func:`column_order`), sorted bottom-up inside a column, and the columns are given one of nine
colours by their coordinates modulo 3. A listed pair's balls were at most one cell apart along x
and z at the build (the cells are wider than any listed pair reaches, see :mod:`.grid`), so a
column's pairs touch only balls of that column and the eight around it, and two columns of one
colour are three columns apart: the columns of a colour are swept in parallel, one thread per
column, without two threads ever writing one ball. The nine colours follow one another
(:func:`colour_sweep`, one launch each). The few pairs whose balls were farther apart (a ball
set apart as much bigger or faster than the rest, see :mod:`.apart`) are swept after the colours,
one after another (:func:`far_pairs`).

Each pair's impulse is the report's impulse (:func:`ti_golf.physics.contact.pair_impulse`), with its accumulated
resting impulse carried from step to step as in the Jacobi sweeps; each ball meets its planes and
the terrain right after its pairs.
"""

import taichi as ti

from ti_golf.physics.contact import (
    GAUSS_SEIDEL,
    clamp_friction,
    inverse_inertia,
    kinetic_change,
    pivot_impulse,
    spin_jolt,
)
from ti_golf.physics.types import (
    GAP,
    INV,
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
    zero3,
)
from ti_golf.scene.schema import AT_REST, OUT_OF_BOUNDS
from ti_golf.solvers.links import listed
from ti_golf.solvers.pairs import QUIET, pair_normal, skip_pair
from ti_golf.solvers.phases import Phase
from ti_golf.solvers.sequential import pair_step
from ti_golf.solvers.sort import bucket_in_turn, cell_of, counting_sort, sort_bucket, spread_turns, task_stride
from ti_golf.solvers.stale import flag_stale_lists
from ti_golf.solvers.surfaces import surface_impulses

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
    moving = 0
    for i in range(status.shape[0]):
        if status[i] != AT_REST and status[i] != OUT_OF_BOUNDS:
            moving += 1  # (an integer sum: the same on every thread order)
    return moving


@ti.func
def region_hop(contact: ti.template(), params: ti.template()):
    """What each contact nearer a moving ball takes off how long a ball counts as calm [s]
    (``pairs.island_calm``): t_rest / ``REGION_HOPS`` with the Gauss–Seidel sweeps, else 0 (the
    Jacobi sweeps put islands to sleep)."""
    hop = 0.0
    if contact.solver == GAUSS_SEIDEL:
        hop = params.t_rest / REGION_HOPS
    return hop


@ti.func
def stands_firm(contact: ti.template(), status_i):
    """Whether a ball with status ``status_i`` stands firm in a step: with the Gauss–Seidel sweeps, a
    ball asleep takes no impulse and does not move, and the awake balls touching it meet it as they
    meet a wall, until a moving ball touches it (:func:`.pairs.touched_by_moving`)."""
    return contact.solver == GAUSS_SEIDEL and status_i == AT_REST


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
def in_this_pass(col, j, far_only: ti.template(), any_far, inv_cell, lists: ti.template()):
    """Whether a pair of a ball in grid column ``col`` with ball j is taken by the colours
    (``far_only`` False) or by :func:`far_pairs` (True): with ``any_far``, the pairs whose balls
    were not in columns beside each other at the build are :func:`far_pairs`' alone."""
    far = False
    if any_far != 0:
        far = not adjacent(col, column_of(lists.x_at_build[j], inv_cell))
    return far == far_only


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
    counting_sort(x_at_build, inv_block, mask, origin, stride, rank, start, chunk_start, ids)
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
    scalars: float_array,
    model: ModelArrays,
    lists: NeighbourLists,
    state: BallState,
    scratch: StepScratch,
    blocks: BlockOrder,
):
    """One Gauss–Seidel sweep of ``phase`` (:func:`pair_step`), colour after colour: the balls of
    every block of a colour, each block bottom-up in one thread (see the module's docstring;
    ``blocks`` from :func:`column_order`), meet the pairs they own (but, when ``any_far``, those
    whose other ball was not beside them at the build), then their planes and the terrain, with the
    parameters in ``scalars`` (:func:`ti_golf.physics.types.scalars_of`)."""
    _, contact, terrain, params = scalars_of(scalars)
    buckets = blocks.start.shape[0] - 1
    for c in ti.static(range(COLOURS)):  # a top-level loop per colour: the colours in turn
        for t in range(tasks * ti.static(task_stride())):  # (the blocks spread over the threads: see spread_turns)
            turn0, turns = spread_turns(t, tasks, buckets)
            for k in range(turns):
                b = bucket_in_turn(turn0 + k * tasks, buckets)
                for s in range(blocks.start[b], blocks.start[b + 1]):
                    if blocks.colour[s] == c:
                        sweep_ball(
                            blocks.ids[s],
                            phase,
                            False,
                            any_far,
                            inv_cell,
                            contact,
                            terrain,
                            params,
                            model,
                            lists,
                            state,
                            scratch,
                        )


@kernel
def far_pairs(
    phase: ti.i32,
    inv_cell: float,
    scalars: float_array,
    model: ModelArrays,
    lists: NeighbourLists,
    state: BallState,
    scratch: StepScratch,
):
    """The pairs the colours left out (their balls were farther apart than beside each other at the
    build), one ball after another in storage order."""
    _, contact, terrain, params = scalars_of(scalars)
    ti.loop_config(serialize=True)
    for i in range(state.x.shape[0]):
        if phase == Phase.PROJECT:
            project_ball(i, True, 1, inv_cell, contact.k_p, model, lists, state, scratch)
        else:
            sweep_ball(
                i,
                phase,
                True,
                1,
                inv_cell,
                contact,
                terrain,
                params,
                model,
                lists,
                state,
                scratch,
            )


@ti.func
def serial_sweeps(
    sweeps: ti.template(),
    contact: ti.template(),
    terrain: ti.template(),
    params: ti.template(),
    model: ti.template(),
    lists: ti.template(),
    state: ti.template(),
    scratch: ti.template(),
):
    """A step's ``sweeps`` Gauss–Seidel sweeps (:func:`step_phases`) and the restitution pass,
    every ball in storage order, in the calling (serial) loop's thread."""
    serial_sweep(Phase.FIRST, contact, terrain, params, model, lists, state, scratch)
    for _ in range(sweeps - 2):
        serial_sweep(Phase.SOLVE, contact, terrain, params, model, lists, state, scratch)
    if sweeps > 1:
        serial_sweep(Phase.SHOCK, contact, terrain, params, model, lists, state, scratch)
    serial_sweep(Phase.BOUNCE, contact, terrain, params, model, lists, state, scratch)


@ti.func
def serial_sweep(
    phase,
    contact: ti.template(),
    terrain: ti.template(),
    params: ti.template(),
    model: ti.template(),
    lists: ti.template(),
    state: ti.template(),
    scratch: ti.template(),
):
    """A Gauss–Seidel sweep of every ball in storage order, in the calling (serial) loop's thread."""
    for i in range(state.x.shape[0]):
        sweep_ball(i, phase, False, 0, 1.0, contact, terrain, params, model, lists, state, scratch)


def step_phases(iterations: int) -> list[int]:
    """The phases of a step's ``iterations`` sweeps and its restitution pass: ``FIRST``, then
    ``SOLVE``, the last sweep ``SHOCK`` (with two or more), then ``BOUNCE``."""
    sweeps = [Phase.FIRST] + [Phase.SOLVE] * max(iterations - 2, 0) + [Phase.SHOCK] * (iterations > 1)
    return sweeps + [Phase.BOUNCE]


@ti.func
def upward(params: ti.template()):
    """The unit vector against gravity (zero without gravity)."""
    g = params.gravity.norm()
    up = ti.Vector([0.0, 0.0, 0.0], dt=float)
    if g > 0.0:
        up = -params.gravity / g
    return up


@ti.func
def inelastic_speed(contact: ti.template(), params: ti.template()):
    """Approach speed [m/s] below which a contact is inelastic: v_bounce + 2|g|h."""
    return contact.v_bounce + 2.0 * params.gravity.norm() * params.h


@ti.func
def sweep_ball(
    i,
    phase,
    far_only: ti.template(),
    any_far,
    inv_cell,
    contact: ti.template(),
    terrain: ti.template(),
    params: ti.template(),
    model: ti.template(),
    lists: ti.template(),
    state: ti.template(),
    scratch: ti.template(),
):
    """Ball i's Gauss–Seidel step: each pair it owns (:func:`pair_step`, from the current velocities
    of both balls, applied to both at once, with the normal and gap the warm start stored in
    ``scratch.J``), then (unless ``far_only``) its planes and the terrain, with the step's scalars
    ``params`` (h, and gravity for the inelastic speed and the shock sweep's "up"). When ``any_far``, a pair whose other ball was not in a column beside i's at the
    build is taken only with ``far_only`` (:func:`far_pairs`), and the others only without. A quiet
    ball (at rest among balls at rest) is skipped, and gets nothing from its neighbours' pairs, as
    in a Jacobi sweep. The first sweep marks in ``scratch.impact[i]`` whether one of ball i's pairs
    approached faster than the inelastic speed; the restitution pass (``BOUNCE``), which changes
    no other pair, visits only the pairs of the balls so marked."""
    if state.status[i] != OUT_OF_BOUNDS and scratch.calm[i] != QUIET:
        h, v_inelastic, up = params.h, inelastic_speed(contact, params), upward(params)
        xi, vi, wi = state.x[i], state.v[i], state.w[i]
        ri, inv_mi = of_ball(model.radius, i), 1.0 / of_ball(model.mass, i)
        firm = stands_firm(contact, state.status[i])
        if firm:
            inv_mi = 0.0
        col = column_of(lists.x_at_build[i], inv_cell)
        owned = listed(lists.first, i)
        if phase == Phase.BOUNCE and scratch.impact[i] == 0:
            owned = 0  # none of its pairs approached fast enough to bounce: the pass changes none
        approached = 0
        p0 = lists.first[i]
        for k in range(owned):
            j, p = lists.upper[i, k], p0 + k
            if in_this_pass(col, j, far_only, any_far, inv_cell, lists):
                vi, wi, hit = sweep_pair(
                    i, j, p, phase, xi, vi, wi, ri, inv_mi, h, v_inelastic, up, contact, model, lists, state, scratch
                )
                approached = ti.max(approached, hit)
        if phase == Phase.FIRST:  # the restitution pass visits the pairs of the balls marked here
            if ti.static(far_only):
                scratch.impact[i] = ti.max(scratch.impact[i], approached)  # (after the colours)
            else:
                scratch.impact[i] = approached
        if not far_only and not firm:
            vi, wi = surface_impulses(
                i, False, vi, wi, contact, terrain, h, v_inelastic, model, lists, state, scratch, phase
            )
        state.v[i], state.w[i] = vi, wi


@ti.func
def sweep_pair(  # noqa: C901 (a ti.func: a pair's update in both layouts' sweeps)
    i,
    j,
    p,
    phase,
    xi,
    vi,
    wi,
    ri,
    inv_mi,
    h,
    v_inelastic,
    up,
    contact: ti.template(),
    model: ti.template(),
    lists: ti.template(),
    state: ti.template(),
    scratch: ti.template(),
):
    """One Gauss–Seidel update of pair p, ball i (at ``xi`` [m], moving at ``vi``, ``wi``, radius
    ``ri``, inverse mass ``inv_mi``: 0 when it stands firm) with ball j (:func:`pair_step`, from the
    current velocities of both balls, applied to both at once, with the normal and gap the warm
    start stored in ``scratch.J``): ball j's velocity and spin are written, ball i's returned, as
    (v_i, ω_i, approached), ``approached`` 1 when the pair approached faster than the inelastic
    speed ``v_inelastic`` before the step's contacts (read in ``FIRST`` and ``BOUNCE``). Both
    layouts of the sweeps (:func:`sweep_ball`, :mod:`.contact_colour`) make this update."""
    approached = 0
    if state.status[j] == OUT_OF_BOUNDS:
        lists.lam[p] = ti.f32(0.0)  # a frozen ball no longer supports anything
    elif not skip_pair(state.status, i, j):
        n = pair_normal(xi, state.x[j], scratch.J[p, INV])
        if n.norm_sqr() > 0.0:
            rj, inv_mj = of_ball(model.radius, j), 1.0 / of_ball(model.mass, j)
            if stands_firm(contact, state.status[j]):
                inv_mj = 0.0
            F = ti.cast(lists.friction[p], float)
            lam = ti.cast(lists.lam[p], float)
            if phase == Phase.FIRST:  # what the warm start applied (pairs.carried_friction)
                F = clamp_friction(F, n, contact.mu * lam)
            inv_a, inv_b = inv_mi, inv_mj
            if phase == Phase.SHOCK and up.norm_sqr() > 0.0:  # the lower ball stands firm
                if n.dot(up) > 0.0:
                    inv_b = 0.0
                else:
                    inv_a = 0.0
            if inv_a + inv_b > 0.0:  # (not both standing firm: a ball asleep, and the shock sweep)
                v_n0 = 0.0  # the approach before the contacts: read where it is used
                if phase == Phase.FIRST or phase == Phase.BOUNCE:
                    v_n0 = (scratch.v_free[i] - scratch.v_free[j]).dot(n)
                    if v_n0 < -v_inelastic:
                        approached = 1
                vj, wj = state.v[j], state.w[j]
                shocked = inv_a + inv_b != inv_mi + inv_mj  # (the lower ball made to stand firm)
                P, lam_new, F_new = zero3(), lam, F
                for attempt in range(2):
                    P, lam_new, F_new = pair_step(
                        phase,
                        n,
                        scratch.J[p, GAP],
                        v_n0,
                        vi,
                        wi,
                        ri,
                        inv_a,
                        vj,
                        wj,
                        rj,
                        inv_b,
                        lam,
                        F,
                        contact.e,
                        contact.mu,
                        v_inelastic,
                        h,
                    )
                    if attempt == 1 or not shocked or P.norm_sqr() == 0.0:
                        break
                    if kinetic_change(vi, wi, ri, inv_a, P, n) + kinetic_change(vj, wj, rj, inv_b, -P, -n) <= 0.0:
                        break
                    inv_a, inv_b = inv_mi, inv_mj  # the lower ball standing firm would add energy
                lists.lam[p] = ti.cast(lam_new, ti.f32)
                F = F_new
                lists.friction[p] = ti.cast(F, ti.f32)
                if P.norm_sqr() > 0.0:  # (a pair apart or at rest changes nothing: ball j left unread)
                    vi += P * inv_a
                    wi += spin_jolt(P, n, ri, inv_a)
                    if scratch.calm[j] != QUIET:
                        state.v[j] -= P * inv_b
                        state.w[j] += spin_jolt(-P, -n, rj, inv_b)
                if phase == Phase.SHOCK and lam_new > 0.0:  # once a step, with the pair's support
                    inv_Ia, inv_Ib = inverse_inertia(ri, inv_mi), inverse_inertia(rj, inv_mj)
                    if scratch.calm[j] == QUIET:
                        inv_Ib = 0.0
                    L = pivot_impulse(
                        (wi - state.w[j]).dot(n), inv_Ia, inv_Ib, contact.mu_roll * lam_new * ti.min(ri, rj)
                    )
                    if L != 0.0:
                        wi += L * inv_Ia * n
                        state.w[j] -= L * inv_Ib * n
    return vi, wi, approached


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
    _air, contact, _terrain, _params = scalars_of(scalars)
    buckets = blocks.start.shape[0] - 1
    for c in ti.static(range(COLOURS)):
        for t in range(tasks * ti.static(task_stride())):  # (the blocks spread over the threads: see spread_turns)
            turn0, turns = spread_turns(t, tasks, buckets)
            for k in range(turns):
                b = bucket_in_turn(turn0 + k * tasks, buckets)
                for s in range(blocks.start[b], blocks.start[b + 1]):
                    if blocks.colour[s] == c:
                        project_ball(blocks.ids[s], False, any_far, inv_cell, contact.k_p, model, lists, state, scratch)


@ti.func
def serial_projection(
    params: ti.template(), k_p, model: ti.template(), lists: ti.template(), state: ti.template(), scratch: ti.template()
):
    """The position projection of :func:`project_sweep`, ``PROJECTIONS`` passes of every ball in
    storage order, then whether the lists must be rebuilt (:func:`.stale.flag_stale_lists`, every
    ball tested), in the calling (serial) loop's thread."""
    for _ in range(PROJECTIONS):
        for i in range(state.x.shape[0]):
            project_ball(i, False, 0, 1.0, k_p, model, lists, state, scratch)
    flag_stale_lists(True, params, model.radius, lists, state, scratch, 0, 0, 0, False)


@ti.func
def project_ball(
    i,
    far_only: ti.template(),
    any_far,
    inv_cell,
    k_p,
    model: ti.template(),
    lists: ti.template(),
    state: ti.template(),
    scratch: ti.template(),
):
    """Ball i's position projection at the end of a Gauss–Seidel step, on the new positions
    ``scratch.x_free`` [m]: each pair it owns that overlaps by Δx moves apart by k_p·Δx, ball i by
    k_p·m_red·Δx along the normal and the other ball the rest (B.18); a ball at rest does not move
    (the other ball takes the whole projection). Then (unless ``far_only``) what overlaps a plane
    moves out by k_p of the overlap. Pairs are split between the colours and :func:`far_pairs` as
    in :func:`sweep_ball`. Moves only positions: the velocities, and so the energy, are untouched."""
    if state.status[i] != OUT_OF_BOUNDS and scratch.calm[i] != QUIET:
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
def project_pair(j, xi, ri, inv_mi, k_p, model: ti.template(), state: ti.template(), scratch: ti.template()):
    """The position projection (B.18) of a pair of a ball at ``xi`` [m] (radius ``ri``, inverse
    mass ``inv_mi``: 0 at rest) with ball j, on the step's new positions: when they overlap by Δx,
    they move apart by k_p·Δx, ball j's share written to ``scratch.x_free[j]`` (none when it is out
    of bounds, at rest or quiet), the ball's returned. Both layouts of the sweeps
    (:func:`project_ball`, :mod:`.contact_colour`) make this update."""
    if state.status[j] != OUT_OF_BOUNDS:
        inv_mj = 0.0
        if state.status[j] != AT_REST and scratch.calm[j] != QUIET:
            inv_mj = 1.0 / of_ball(model.mass, j)
        d = xi - scratch.x_free[j]
        dist = d.norm()
        overlap = ri + of_ball(model.radius, j) - dist
        if overlap > 0.0 and dist > 0.0 and inv_mi + inv_mj > 0.0:
            q = (k_p * overlap / (inv_mi + inv_mj)) * (d / dist)
            xi += q * inv_mi
            scratch.x_free[j] -= q * inv_mj
    return xi


@ti.func
def project_planes(xi, ri, k_p, model: ti.template()):
    """A ball at ``xi`` [m] of radius ``ri`` moved out of each plane it overlaps by k_p of the
    overlap (B.18, m_red = 1): its new position."""
    for p in range(model.plane_n.shape[0]):
        gap = (xi - model.plane_p[p]).dot(model.plane_n[p]) - ri
        if gap < 0.0:
            xi -= k_p * gap * model.plane_n[p]
    return xi
