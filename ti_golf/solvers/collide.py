"""One step of colliding balls in a single kernel (report Appendix B, every touching pair at once).

Every pair of neighbours (a, b) is *owned* by one of them, say a (the ball behind the other along
their main axis, see :func:`.grid.owns`): it sits in a's upper neighbour list with its
accumulated resting impulse ``lam`` and, during a sweep, the impulse ``P`` on a (−P acts on b).
Ball b finds the pair through its lower list, which holds the slot of the pair in a's upper list.
So each pair impulse is evaluated once per sweep, the two balls of a pair apply exactly
opposite impulses (momentum is conserved to round-off), and every ball *gathers* its impulses in
id order: no float atomics, results do not depend on thread order.

The kernel's top-level loops run one after another, each over all balls in parallel:

1. free flight and warm start (with the Gauss–Seidel sweeps, first a ball asleep that a moving
   ball touches wakes: :func:`.pairs.touched_by_moving`): every awake ball flies under gravity
   and air forces (the integrator) to a predicted position, and flight records (apex, landing)
   are updated; then
   last step's *resting* impulses are applied again (ball pairs along their normals, planes and
   terrain with their friction), so a stack starts the step supported instead of re-learning its
   support every step. The ball pairs' part reads only start-of-step positions and ``lam``, which
   this loop does not write, so it needs no loop of its own; the same reads give each owned
   pair's normal and gap, stored for the sweeps (positions do not change during them), and each
   ball's calm time for sleeping, by islands or, with Gauss–Seidel, by regions
   (:func:`.pairs.island_calm`; a *quiet* ball, at rest among balls at rest, is then skipped by
   the sweeps) and its clearance from the planes and the terrain (the sweeps
   skip them for a ball that cannot reach one within the step);
2. ``iterations`` Jacobi sweeps, each a pair loop (impulses from the velocities of the previous
   sweep, with the normals and gaps that the first loop stored) and a ball loop (gather, then the
   planes and the terrain: the plane of the patch under the ball, see :mod:`ti_golf.physics.terrain`, applied
   in turn); between the two, in a sweep where pairs met as impacts, each ball finds its first
   impact, so that a ball takes one impact per sweep (:func:`matched`);
3. finish (fused with the last sweep's ball loop): positions from the final velocities (split at
   a plane's time of impact), position projection of overlaps (B.18), status, rest detection and
   out-of-bounds (off the terrain), and whether the neighbour lists must be rebuilt before the
   next step.

:func:`collision_step` launches these loops in parallel, one step per launch (with many
sweeps, a few launches: see ``solver.sweep_launches``); for a few balls, its ``serial``
variant runs the same loops (:func:`step_balls`) one ball after another, many steps per launch,
and rebuilds the lists itself by testing every pair: the same step, bit for bit, without the
launch overhead that dominates a step of a few balls.

Loop 1 reads almost every array of the step, and Taichi 1.7.4's Vulkan backend crashes the
process on a loop that reads more than 33 arrays (each loop of a kernel is counted apart; the
loop crashed so with the lists' lengths beside the pair tables' starts): an array more that it
needs must come with one less, or go to a loop of its own.
"""

import taichi as ti

from ti_golf.physics.aero import V, W, X, coefficients, column
from ti_golf.physics.contact import (
    GAUSS_SEIDEL,
    plane_position,
    rest_update,
)
from ti_golf.physics.integrate import IN_FLIGHT, step_free, track_flight
from ti_golf.physics.kernels import lane_state
from ti_golf.physics.terrain import (
    outside,
    same_cell,
    surface,
    terrain_position,
)
from ti_golf.physics.types import (
    BallState,
    FlightRecord,
    ModelArrays,
    NeighbourLists,
    StepScratch,
    float_array,
    kernel,
    of_ball,
    scalars_of,
    zero3,
)
from ti_golf.scene.schema import AT_REST, FLYING, OUT_OF_BOUNDS, ROLLING
from ti_golf.solvers.colour import (
    ASLEEP_OVERLAP,
    inelastic_speed,
    region_hop,
    serial_projection,
    serial_sweeps,
    stands_firm,
)
from ti_golf.solvers.links import moved_past, relist_all_pairs, slot_bits
from ti_golf.solvers.pairs import (
    QUIET,
    gather,
    impact_keys,
    owned_pairs,
    touched_by_moving,
    touching_by_gaps,
    warm_start,
)
from ti_golf.solvers.surfaces import beyond_reach, rounded_down, surface_clearance, surface_impulses


@kernel
def collision_step(
    # Model:
    scalars: float_array,
    t0: ti.f64,
    dt: ti.f64,
    steps: ti.i32,
    kinds: ti.template(),
    model: ModelArrays,
    # Neighbour lists and carried impulses in/out:
    lists: NeighbourLists,
    # State in/out:
    state: BallState,
    flight: FlightRecord,
    # Scratch:
    scratch: StepScratch,
    # The part of a step this launch takes:
    serial: ti.template(),
    warm: ti.template(),
    sweeps: ti.template(),
    last: ti.template(),
) -> ti.i32:
    """Advance all balls by ``steps`` steps of ``params.h`` [s]: the free flight and warm
    start (with ``warm``), ``sweeps`` Jacobi sweeps, then (with ``last``) the last sweep, which
    finishes the step. A whole step of ``iterations`` sweeps is ``(True, iterations − 1, True)``.

    Arguments: the air, contact and terrain parameters and the step's scalars ``params``
    (:data:`~ti_golf.physics.types.StepParams`) in one array, ``scalars`` (see
    :func:`~ti_golf.physics.types.scalars_of`); the time at the start of the launch ``t0`` [s];
    the time step ``dt`` [s] in f64; the steps to take, ``steps``; the scene's ``kinds`` of code (:class:`~ti_golf.physics.kinds.Kinds`); the model's arrays
    ``model``; the neighbour lists with the impulses they carry, ``lists``; the balls' ``state``
    and ``flight`` records; the step's ``scratch`` (:mod:`ti_golf.physics.types` documents each
    array's shape and units); and which part of a step this launch takes.

    In parallel (``serial`` False) the kernel takes exactly one step, or the part of one that
    ``warm``, ``sweeps`` and ``last`` name, so that a step of many sweeps can be split into
    launches (see ``solver.sweep_launches``; ``steps``, ``dt``, ``params.skin``, ``v_cut`` and
    ``r_cut`` are not read). It returns 1 (also left in ``scratch.flag[0]``) when some ball may
    come within reach of a ball missing from its neighbour lists next step: rebuild the lists
    (read it after the ``last`` part; the ``warm`` part clears it). The new positions are left in
    ``scratch.x_free`` (swap it with ``state.x``).

    With ``serial`` the balls are stepped one after another, ``steps`` steps in one launch:
    for scenes so small that launches and rebuilding the lists through the grid's kernels cost far
    more than the step itself. Each step is the parallel one on the same data, the time [s]
    advanced by ``dt`` from ``t0`` in f64, as the caller advances it between
    parallel steps; the neighbour lists are rebuilt in the kernel by testing every pair
    (:func:`~ti_golf.solvers.links.relist_all_pairs`, with the skin [m]; the balls faster than
    ``v_cut`` [m/s] or bigger than ``r_cut`` [m] own no pair with the others, as in the grid's
    lists: see :func:`~ti_golf.solvers.grid.owns`) whenever ``scratch.flag[0]`` asks for it at the
    start of a step, so the tables must be n − 1 wide; new positions are copied to ``state.x``
    after every step. Returns how many times the lists were rebuilt.

    With a terrain (``terrain.on``; ``model.heights`` its grid, else any 2×2 array;
    ``lists.surface_impulse`` then has a column more than there are planes) a ball that leaves the grid's
    extent or falls below ``terrain.kill`` is put out of bounds (velocities zeroed)."""
    air, contact, terrain, params = scalars_of(scalars)
    h = params.h
    result = 0
    if ti.static(not serial):
        if ti.static(warm):
            scratch.flag[0] = 0
        step_balls(
            serial,
            warm,
            sweeps,
            last,
            air,
            contact,
            terrain,
            params,
            ti.cast(t0, float),
            kinds,
            model,
            lists,
            state,
            flight,
            scratch,
        )
        result = scratch.flag[0]
    else:
        t = t0
        ti.loop_config(serialize=True)
        for _ in range(steps):
            if scratch.flag[0] != 0:
                relist_all_pairs(
                    state.x,
                    model.radius,
                    params.skin,
                    state.v,
                    h,
                    params.v_cut,
                    params.r_cut,
                    lists.upper,
                    lists.first,
                    lists.lower,
                    lists.lower_first,
                    lists.x_at_build,
                    lists.lam,
                    scratch.J,
                    lists.friction,
                    contact.solver == GAUSS_SEIDEL,
                    scratch.impact,
                )
                result += 1
                scratch.flag[0] = 0
            step_balls(
                serial,
                warm,
                sweeps,
                last,
                air,
                contact,
                terrain,
                params,
                ti.cast(t, float),
                kinds,
                model,
                lists,
                state,
                flight,
                scratch,
            )
            if ti.static(kinds.gauss_seidel):
                serial_projection(params, contact.k_p, model, lists, state, scratch)
            for i in range(state.x.shape[0]):
                state.x[i] = scratch.x_free[i]
            t += dt
    return result


def launch(arguments: tuple, *, serial: bool, warm: bool, sweeps: int, last: bool) -> int:
    """:func:`collision_step` with its flags by name: ``arguments``, the ten before them
    (``CollisionSolver._arguments``), then ``serial``, ``warm``, ``sweeps`` and ``last``.
    Returns what it returns."""
    return collision_step(*arguments, serial, warm, sweeps, last)


@ti.func
def step_balls(
    serial: ti.template(),
    warm: ti.template(),
    sweeps: ti.template(),
    last: ti.template(),
    air: ti.template(),
    contact: ti.template(),
    terrain: ti.template(),
    params: ti.template(),
    t0,
    kinds: ti.template(),
    model: ti.template(),
    lists: ti.template(),
    state: ti.template(),
    flight: ti.template(),
    scratch: ti.template(),
):
    """One step of all balls, the body of :func:`collision_step` (see there) in parallel and serially,
    or the part of it that ``warm``, ``sweeps`` and ``last`` name."""
    v_inelastic = inelastic_speed(contact, params)
    bits = slot_bits(lists.upper.shape[1])  # lower-list slots: owner · 2^bits + column (once, not per ball)
    if ti.static(warm):
        start_step(air, contact, terrain, params, t0, kinds, v_inelastic, bits, model, lists, state, flight, scratch)
    # 2. Jacobi sweeps; the last sweep's ball loop also finishes the step (3.)
    if ti.static(serial):  # every loop is serial here: the sweeps before the last need not be unrolled
        if ti.static(kinds.gauss_seidel):  # all the step's sweeps: the last one only finishes it
            serial_sweeps(sweeps + 1, contact, terrain, params, model, lists, state, scratch)
        else:
            for _ in range(sweeps):
                sweep(False, contact, terrain, params, v_inelastic, bits, model, lists, state, scratch)
    else:  # unrolled, so that each sweep's loops stay top-level loops (parallel)
        for _ in ti.static(range(sweeps)):
            sweep(False, contact, terrain, params, v_inelastic, bits, model, lists, state, scratch)
    if ti.static(last):
        sweep(True, contact, terrain, params, v_inelastic, bits, model, lists, state, scratch)


@ti.func
def start_step(
    air: ti.template(),
    contact: ti.template(),
    terrain: ti.template(),
    params: ti.template(),
    t0,
    kinds: ti.template(),
    v_inelastic,
    bits,
    model: ti.template(),
    lists: ti.template(),
    state: ti.template(),
    flight: ti.template(),
    scratch: ti.template(),
):
    """1. Free flight of every ball to ``x_free``, ``v_free``, then the warm start: last step's
    resting impulses (ball pairs, planes and terrain) applied again, so a stack starts the step
    supported (see the module's docstring)."""
    h = params.h
    tracking = flight.landed.shape[0] == state.x.shape[0]
    for i in range(state.x.shape[0]):  # a ball asleep in a Gauss–Seidel pile wakes when a moving ball touches it
        if stands_firm(contact, state.status[i]):
            if touched_by_moving(i, state.status, state.rest_time, lists, bits):
                state.status[i] = ROLLING
    for i in range(state.x.shape[0]):
        xi = state.x[i]
        x1, v1, w1 = xi, zero3(), zero3()
        if state.status[i] != AT_REST and state.status[i] != OUT_OF_BOUNDS:
            coef = coefficients(air, kinds, ti.Vector([of_ball(model.radius, i)]), ti.Vector([of_ball(model.mass, i)]))
            S1 = step_free(lane_state(xi, state.v[i], state.w[i]), h, kinds, coef, air, params.gravity)
            x1, v1, w1 = column(S1, X, 0), column(S1, V, 0), column(S1, W, 0)
            if tracking:  # else the flight records hold one entry each, not read (see State.tracking)
                if flight.landed[i] == IN_FLIGHT:  # a landed ball's record is final: neither read nor written
                    flight.landed[i], flight.apex[i], flight.t_land[i], flight.land_x[i], flight.land_v[i] = (
                        track_flight(
                            xi,
                            state.v[i],
                            x1,
                            v1,
                            h,
                            t0,
                            model.launch_height[i],
                            flight.landed[i],
                            flight.apex[i],
                            flight.t_land[i],
                            flight.land_x[i],
                            flight.land_v[i],
                        )
                    )
        scratch.x_free[i], scratch.v_free[i] = x1, v1
        scratch.clear[i] = rounded_down(surface_clearance(i, x1, terrain, model, lists, state))
        dv, dw, scratch.calm[i] = warm_start(
            i,
            state.x,
            model.radius,
            model.mass,
            state.status,
            state.rest_time,
            lists.upper,
            lists.first,
            lists.lower,
            lists.lower_first,
            bits,
            lists.lam,
            scratch.J,
            lists.friction,
            contact.mu,
            contact.solver == GAUSS_SEIDEL,
            region_hop(contact, params),
        )
        if state.status[i] != OUT_OF_BOUNDS and scratch.calm[i] != QUIET and not stands_firm(contact, state.status[i]):
            v1 += dv
            w1 += dw
            v1, w1 = surface_impulses(i, True, v1, w1, contact, terrain, h, v_inelastic, model, lists, state, scratch)
        state.v[i], state.w[i] = v1, w1


@ti.func
def sweep(
    last: ti.template(),
    contact: ti.template(),
    terrain: ti.template(),
    params: ti.template(),
    v_inelastic,
    bits,
    model: ti.template(),
    lists: ti.template(),
    state: ti.template(),
    scratch: ti.template(),
):
    """One Jacobi sweep: the pairs' impulses from the velocities of the previous sweep, then each
    ball gathers them and meets its planes; the ``last`` sweep's ball loop also finishes the step.
    Between the two, when the pairs marked impacts (``flag[1]``), every ball finds its first
    impact (:func:`impact_keys`, :func:`matched`).
    A quiet ball gets no impulse (its pairs are skipped) and stays where it is; the last pair pass
    still visits its pairs, for the projections its awake neighbours gather."""
    h = params.h
    scratch.flag[1] = 0
    for i in range(state.x.shape[0]):
        if contact.solver != GAUSS_SEIDEL:  # (its sweeps are done and leave each pair's gap in J: all it needs)
            if ti.static(last) or scratch.calm[i] != QUIET:
                owned_pairs(
                    i,
                    last,
                    contact,
                    h,
                    v_inelastic,
                    state.x,
                    model.radius,
                    model.mass,
                    state.status,
                    lists.upper,
                    lists.first,
                    lists.lam,
                    scratch.J,
                    state.v,
                    state.w,
                    scratch.flag,
                )
    for i in range(state.x.shape[0]):
        if scratch.flag[1] != 0:  # (a loop inside the test would not run in parallel)
            impact_keys(i, lists.first, lists.lower, lists.lower_first, bits, scratch.J, scratch.impact)
    pressed = 0.01  # the overlap [share of a radius] that keeps a ball awake
    if contact.solver == GAUSS_SEIDEL:
        pressed = ASLEEP_OVERLAP
    for i in range(state.x.shape[0]):
        if scratch.calm[i] == QUIET:
            if ti.static(last):
                scratch.x_free[i] = state.x[i]
        elif state.status[i] != OUT_OF_BOUNDS:
            dv, dw, dx, touching = zero3(), zero3(), zero3(), 0
            if contact.solver == GAUSS_SEIDEL:  # (only its last launch comes here)
                touching = touching_by_gaps(
                    i,
                    of_ball(model.radius, i),
                    lists.first,
                    lists.lower,
                    lists.lower_first,
                    bits,
                    scratch.J,
                    contact.k_p,
                    pressed,
                )
            else:
                dv, dw, dx, touching = gather(
                    i,
                    last,
                    state.x,
                    model.radius,
                    model.mass,
                    lists.upper,
                    lists.first,
                    lists.lower,
                    lists.lower_first,
                    bits,
                    scratch.J,
                    scratch.impact,
                    scratch.flag[1],
                    contact.k_p,
                    pressed,
                )
            v_new, w_new = state.v[i] + dv, state.w[i] + dw
            if contact.solver != GAUSS_SEIDEL:  # (its sweeps are done)
                v_new, w_new = surface_impulses(
                    i, False, v_new, w_new, contact, terrain, h, v_inelastic, model, lists, state, scratch
                )
            if ti.static(not last):
                state.v[i], state.w[i] = v_new, w_new
            else:
                finish(i, v_new, w_new, dx, touching, contact, terrain, params, model, lists, state, scratch)


@ti.func
def finish(
    i,
    v_final,
    w_final,
    dx,
    touching,
    contact: ti.template(),
    terrain: ti.template(),
    params: ti.template(),
    model: ti.template(),
    lists: ti.template(),
    state: ti.template(),
    scratch: ti.template(),
):
    """End of the step for ball i (not out of bounds) with its final velocities, the position
    projection ``dx`` of its ball overlaps and whether it ``touching`` a ball: new position in
    ``x_free`` (split at a plane's time of impact, overlaps projected out), status, rest timer,
    out-of-bounds; with the Jacobi sweeps, sets ``flag[0]`` when the neighbour lists must be rebuilt
    before the next step (:func:`.links.moved_past`; the Gauss–Seidel steps test after their
    projection, :func:`.stale.flag_stale_lists`)."""
    h = params.h
    st = state.status[i]
    xi, ri = state.x[i], of_ball(model.radius, i)
    x1 = scratch.x_free[i] + h * (v_final - scratch.v_free[i])
    # no plane or terrain patch within reach of the flight or the end point (see surface_clearance)
    moved = ti.max((scratch.x_free[i] - xi).norm_sqr(), (x1 - xi).norm_sqr())
    far = False
    if terrain.on == 0:
        far = beyond_reach(scratch.clear[i], ri, moved)
    else:
        far = beyond_reach(scratch.clear[i], ri, 4.0 * moved) and same_cell(model.heights, terrain, xi, x1)
    n_planes = model.plane_p.shape[0]
    if far:
        n_planes = 0
    for p in range(n_planes):
        x1 = plane_position(
            xi,
            scratch.x_free[i],
            x1,
            scratch.v_free[i],
            v_final,
            ri,
            model.plane_p[p],
            model.plane_n[p],
            contact.k_p,
            h,
        )
        if (x1 - model.plane_p[p]).dot(model.plane_n[p]) - ri < 0.01 * ri:
            touching = ti.max(touching, 1)
    if terrain.on != 0 and not far:
        pt, nt = surface(model.heights, terrain, scratch.x_free[i])
        x1 = plane_position(xi, scratch.x_free[i], x1, scratch.v_free[i], v_final, ri, pt, nt, contact.k_p, h)
        x1 = terrain_position(xi, x1, pt, nt, ri, model.heights, terrain)
        if (x1 - pt).dot(nt) - ri < 0.01 * ri:
            touching = ti.max(touching, 1)
    if contact.solver != GAUSS_SEIDEL:  # (Gauss–Seidel projects after the step: colour.project_sweep)
        x1 += dx  # position projection k_p·m_red·Δx·n̂ of the ball overlaps (B.18)
    if st == AT_REST and (v_final.norm() > 0.0 or w_final.norm() > 0.0):
        st = FLYING  # woken by an impulse
    if st != AT_REST:
        # island-like sleeping: the timer counts on from the least timer of the balls touching
        # this one at the start of the step (``calm``), so the balls of a calm group reach t_rest
        # together and fall asleep in the same step, and a ball pressed by a moving one stays
        # awake (asleep, it would feel no gravity and the balls above it would keep rocking)
        st, state.rest_time[i] = rest_update(
            touching, v_final, w_final, ri, scratch.calm[i], h, params.v_rest, params.t_rest, contact.friction
        )
        if st == AT_REST:
            v_final, w_final = zero3(), zero3()
            x1 = xi
    if terrain.on != 0 and outside(model.heights, terrain, x1):
        st = OUT_OF_BOUNDS
        v_final, w_final = zero3(), zero3()
    state.status[i] = st
    scratch.x_free[i] = x1
    state.v[i], state.w[i] = v_final, w_final
    if contact.solver != GAUSS_SEIDEL:  # (the Gauss–Seidel steps test the pairs after the projection: see stale)
        if moved_past(x1, lists.x_at_build[i], 2.0 * h * v_final.norm(), params.half_skin):
            scratch.flag[0] = 1
