"""One step of colliding balls in a single kernel (report Appendix B, every touching pair at once).

Every pair of neighbours (a, b) is *owned* by one of them, say a (the ball behind the other along
their main axis, see :func:`.grid.owns`): it sits in a's upper neighbour list with its
accumulated resting impulse ``lam`` and, during a sweep, the impulse ``P`` on a (−P acts on b).
Ball b finds the pair through its lower list, which holds the slot of the pair in a's upper list.
So each pair impulse is evaluated once per sweep, the two balls of a pair apply exactly
opposite impulses (momentum is conserved to round-off), and every ball *gathers* its impulses in
id order: no float atomics, results do not depend on thread order.

The kernel's top-level loops run one after another, each over all balls in parallel:

1. free flight and warm start (:func:`start_step`; with the Gauss–Seidel sweeps, first a ball
   asleep that a moving ball touches wakes: :func:`.pairs.touched_by_moving`): every awake ball
   flies under gravity and air forces (the integrator) to a predicted position, and flight
   records (apex, landing) are updated (:func:`fly`); then last step's *resting* impulses are
   applied again (ball pairs along their normals, :func:`.pairs.warm_start`, planes and terrain
   with their friction), so a stack starts the step supported instead of re-learning its
   support every step. The ball pairs' part reads only start-of-step positions and ``lam``, which
   this loop does not write, so it needs no loop of its own; the same reads give each owned
   pair's normal and gap, stored for the sweeps (positions do not change during them), and each
   ball's calm time for sleeping, by islands or, with Gauss–Seidel, by regions
   (:func:`.pairs.island_calm`; a *quiet* ball, at rest among balls at rest, is then skipped by
   the sweeps, and with Gauss–Seidel a ball still quiet from the step before is skipped by this
   loop too: :func:`.pairs.still_quiet`) and its clearance from the planes and the terrain (the sweeps skip them for a
   ball that cannot reach one within the step);
2. ``iterations`` Jacobi sweeps (:func:`sweep`), each a pair loop (:func:`.pairs.owned_pairs`:
   impulses from the velocities of the previous sweep, with the normals and gaps that the first
   loop stored) and a ball loop (:func:`ball_sweep`: gather, then the planes and the terrain:
   the plane of the patch under the ball, see :mod:`ti_golf.physics.terrain`, applied in turn);
   between the two, in a sweep where pairs met as impacts, each ball finds its first impact, so
   that a ball takes one impact per sweep (:func:`.pairs.matched`). The Gauss–Seidel sweeps are
   launched between the first part and the last instead (:mod:`.colour`, :mod:`.contact_colour`);
3. finish (:func:`finish`, fused with the last sweep's ball loop): positions from the final
   velocities (split at a plane's time of impact: :func:`end_position`), position projection of
   overlaps (B.18), status, rest detection and out-of-bounds (off the terrain), and whether the
   neighbour lists must be rebuilt before the next step.

:func:`collision_step` launches these loops in parallel, one step per launch (with many
sweeps, a few launches: see :func:`.jacobi.sweep_launches`); for a few balls, its ``serial``
variant runs the same loops (:func:`step_balls`) one ball after another, many steps per launch
(:func:`serial_steps`): the same step, bit for bit, without the launch overhead that dominates
a step of a few hundred balls. It rebuilds the lists itself by testing every pair, or stops for
the caller to build them through the grid. The functions take
the step's parameters and arrays as one argument, a :class:`.step.Step`.

Loop 1 reads almost every array of the step, and Taichi 1.7.4's Vulkan backend crashes the
process on a loop that reads more than 33 arrays (each loop of a kernel is counted apart; the
loop crashed so with the lists' lengths beside the pair tables' starts): an array more that it
needs must come with one less, or go to a loop of its own.
"""

import taichi as ti

from ti_golf.physics.aero import V, W, X, coefficients, column
from ti_golf.physics.contact import (
    PRESSED_OVERLAP,
    TOUCHING_GAP,
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
from ti_golf.runtime import plain_compile
from ti_golf.scene.schema import AT_REST, FLYING, OUT_OF_BOUNDS, ROLLING
from ti_golf.solvers.colour import ASLEEP_OVERLAP, region_hop, serial_projection, serial_sweeps
from ti_golf.solvers.links import moved_past, relist_all_pairs, slot_bits
from ti_golf.solvers.pairs import (
    QUIET,
    gather,
    impact_keys,
    owned_pairs,
    still_quiet,
    stir_neighbours,
    touched_by_moving,
    touching_by_gaps,
    warm_start,
)
from ti_golf.solvers.sequential import inelastic_speed, stands_firm
from ti_golf.solvers.step import Step
from ti_golf.solvers.surfaces import beyond_reach, rounded_down, surface_clearance, surface_impulses

PARALLEL, SERIAL_RELISTS, SERIAL_STOPS = 0, 1, 2
"""How :func:`collision_step` steps (its ``serial``): one step in parallel; serially, many steps
in one launch, the lists rebuilt in the kernel by testing every pair; or serially until the lists
must be rebuilt (see :func:`serial_steps`)."""


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
    launches (see :func:`.jacobi.sweep_launches`; ``steps``, ``dt``, ``params.skin``, ``v_cut`` and
    ``r_cut`` are not read). It returns 1 (also left in ``scratch.flag[0]``) when some ball may
    come within reach of a ball missing from its neighbour lists next step: rebuild the lists
    (read it after the ``last`` part; the ``warm`` part clears it). The new positions are left in
    ``scratch.x_free`` (swap it with ``state.x``).

    Serially (``serial`` :data:`SERIAL_RELISTS` or :data:`SERIAL_STOPS`) the balls are stepped one
    after another, up to ``steps`` whole steps in one launch: for piles so small that a parallel
    step is mostly launches. Each step is the parallel one on the same data, the time [s]
    advanced by ``dt`` from ``t0`` in f64, as the caller advances it between parallel steps, and
    new positions are copied to ``state.x`` after every step. When ``scratch.flag[0]`` asks for new
    lists at the start of a step, :data:`SERIAL_RELISTS` rebuilds them in the kernel by testing
    every pair (:func:`~ti_golf.solvers.links.relist_all_pairs`, with the skin [m]; the balls
    faster than ``v_cut`` [m/s] or bigger than ``r_cut`` [m] own no pair with the others, as in
    the grid's lists: see :func:`~ti_golf.solvers.grid.owns`), so the tables must be n − 1 wide,
    and returns how many times it did; :data:`SERIAL_STOPS` stops there and returns the steps it
    took (:func:`serial_steps`).

    With a terrain (``terrain.on``; ``model.heights`` its grid, else any 2×2 array;
    ``lists.surface_impulse`` then has a column more than there are planes) a ball that leaves the grid's
    extent or falls below ``terrain.kill`` is put out of bounds (velocities zeroed)."""
    air, contact, terrain, params = scalars_of(scalars)
    s = ti.static(Step(contact, terrain, params, model, lists, state, scratch, kinds=kinds, air=air, flight=flight))
    result = 0
    if ti.static(serial == PARALLEL):
        if ti.static(warm):
            scratch.flag[0] = 0
        step_balls(ti.cast(t0, float), kinds, s, serial=False, warm=warm, sweeps=sweeps, last=last)
        result = scratch.flag[0]
    else:
        result = serial_steps(t0, dt, steps, kinds, s, relist=serial == SERIAL_RELISTS, sweeps=sweeps)
    return result


@ti.func
def serial_steps(t0, dt, steps, kinds: ti.template(), s: ti.template(), relist: ti.template(), sweeps: ti.template()):
    """The serial :func:`collision_step`: up to ``steps`` whole steps of ``sweeps`` + 1 sweeps,
    every ball one after another (see there), from the time ``t0`` [s] in steps of ``dt`` [s]
    (f64) (``s``: the :class:`.step.Step`). When ``scratch.flag[0]`` asks for new lists at the
    start of a step, with ``relist`` they are rebuilt in the kernel by testing every pair
    (:func:`~ti_golf.solvers.links.relist_all_pairs`), and it returns how many times they were;
    without, the launch stops there, and it returns the steps it took, for the caller to build
    them through the grid (``CollisionSolver.build``) and launch again. A launch of no steps
    with ``relist`` only rebuilds the lists when asked to (``CollisionSolver.relist``)."""
    result = 0
    t = t0
    ti.loop_config(serialize=True)
    for k in range(ti.max(steps, 1)):  # (no steps: a turn for the lists alone)
        if s.scratch.flag[0] != 0:
            if ti.static(not relist):
                break
            relist_all_pairs(s.params, kinds.gauss_seidel, s.contact.mu, s.model, s.lists, s.state, s.scratch)
            for i in range(s.state.x.shape[0]):  # new neighbours: no ball is still quiet (pairs.still_quiet)
                s.scratch.calm[i] = 0.0
            result += 1
            s.scratch.flag[0] = 0
        if k < steps:
            step_balls(ti.cast(t, float), kinds, s, serial=True, warm=True, sweeps=sweeps, last=True)
            if ti.static(kinds.gauss_seidel):
                serial_projection(s)
            for i in range(s.state.x.shape[0]):
                s.state.x[i] = s.scratch.x_free[i]
            t += dt
            if ti.static(not relist):
                result += 1
    return result


def launch(arguments: tuple, *, serial: int, warm: bool, sweeps: int, last: bool) -> int:
    """:func:`collision_step` with its flags by name: ``arguments``, the ten before them
    (``CollisionSolver._arguments``), then ``serial`` (:data:`PARALLEL`, :data:`SERIAL_RELISTS`
    or :data:`SERIAL_STOPS`), ``warm``, ``sweeps`` and ``last`` (a serial launch takes whole
    steps: ``warm`` and ``last`` true). Returns what it returns."""
    with plain_compile(vulkan=True):  # (see runtime.plain_compile)
        return collision_step(*arguments, serial, warm, sweeps, last)


@ti.func
def step_balls(
    t0,
    kinds: ti.template(),
    s: ti.template(),
    serial: ti.template(),
    warm: ti.template(),
    sweeps: ti.template(),
    last: ti.template(),
):
    """One step of all balls from the time ``t0`` [s] (``s``: the :class:`.step.Step`), the body of
    :func:`collision_step` (see there) in parallel and serially, or the part of it that ``warm``,
    ``sweeps`` and ``last`` name."""
    v_inelastic = inelastic_speed(s.contact, s.params)
    bits = slot_bits(s.lists.upper.shape[1])  # lower-list slots: owner · 2^bits + column (once, not per ball)
    if ti.static(warm):
        start_step(t0, kinds, v_inelastic, bits, s)
    # 2. Jacobi sweeps; the last sweep's ball loop also finishes the step (3.)
    if ti.static(serial):  # every loop is serial here: the sweeps before the last need not be unrolled
        if ti.static(kinds.gauss_seidel):  # all the step's sweeps: the last one only finishes it
            serial_sweeps(sweeps + 1, s)
        else:
            for _ in range(sweeps):
                sweep(v_inelastic, bits, s, last=False)
    else:  # unrolled, so that each sweep's loops stay top-level loops (parallel)
        for _ in ti.static(range(sweeps)):
            sweep(v_inelastic, bits, s, last=False)
    if ti.static(last):
        sweep(v_inelastic, bits, s, last=True)


@ti.func
def start_step(t0, kinds: ti.template(), v_inelastic, bits, s: ti.template()):
    """1. Free flight of every ball to ``x_free``, ``v_free`` (:func:`fly`), then the warm start:
    last step's resting impulses (ball pairs, planes and terrain) applied again, so a stack starts
    the step supported (see the module's docstring)."""
    lists, state, scratch = ti.static((s.lists, s.state, s.scratch))
    if ti.static(s.kinds.gauss_seidel):  # a ball asleep in a Gauss–Seidel pile wakes when a moving ball touches it
        for i in range(state.x.shape[0]):
            if stands_firm(s.kinds, state.status[i]):
                if not still_quiet(i, s):  # (a ball still quiet has no neighbour that moved)
                    if touched_by_moving(i, state.status, state.rest_time, lists, bits):
                        state.status[i] = ROLLING
                        stir_neighbours(i, bits, lists, scratch.calm)
    for i in range(state.x.shape[0]):
        if not still_quiet(i, s):  # (a ball still quiet keeps its calm time; the sweeps skip it)
            warm_ball(i, t0, kinds, v_inelastic, bits, s)


@ti.func
def warm_ball(i, t0, kinds: ti.template(), v_inelastic, bits, s: ti.template()):
    """Ball i's part of :func:`start_step`'s second loop: its free flight, surface clearance,
    calm time and warm start."""
    model, lists, state, scratch = ti.static((s.model, s.lists, s.state, s.scratch))
    x1, v1, w1 = fly(i, t0, kinds, s)
    scratch.x_free[i], scratch.v_free[i] = x1, v1
    scratch.clear[i] = rounded_down(surface_clearance(i, x1, s.kinds.terrain, s.terrain, model, lists, state))
    dv, dw, scratch.calm[i] = warm_start(i, bits, region_hop(s.kinds, s.params), s)
    if state.status[i] != OUT_OF_BOUNDS and scratch.calm[i] != QUIET and not stands_firm(s.kinds, state.status[i]):
        v1 += dv
        w1 += dw
        v1, w1 = surface_impulses(i, warm=True, vi=v1, wi=w1, h=s.params.h, v_inelastic=v_inelastic, s=s)
    state.v[i], state.w[i] = v1, w1


@ti.func
def fly(i, t0, kinds: ti.template(), s: ti.template()):
    """Ball i's free flight over the step from the time ``t0`` [s] under gravity and the air
    (the integrator), and its flight record (apex, landing) updated: its (x, v, ω) at the end of
    the flight; a ball asleep or out of bounds stays where it is, (x, 0, 0)."""
    air, model, state, flight = ti.static((s.air, s.model, s.state, s.flight))
    h = s.params.h
    xi = state.x[i]
    x1, v1, w1 = xi, zero3(), zero3()
    if state.status[i] != AT_REST and state.status[i] != OUT_OF_BOUNDS:
        coef = coefficients(air, kinds, ti.Vector([of_ball(model.radius, i)]), ti.Vector([of_ball(model.mass, i)]))
        S1 = step_free(lane_state(xi, state.v[i], state.w[i]), h, kinds, coef, air, s.params.gravity)
        x1, v1, w1 = column(S1, X, 0), column(S1, V, 0), column(S1, W, 0)
        tracking = flight.landed.shape[0] == state.x.shape[0]
        if tracking:  # else the flight records hold one entry each, not read (see State.tracking)
            if flight.landed[i] == IN_FLIGHT:  # a landed ball's record is final: neither read nor written
                flight.landed[i], flight.apex[i], flight.t_land[i], flight.land_x[i], flight.land_v[i] = track_flight(
                    xi,
                    state.v[i],
                    x1,
                    v1,
                    h,
                    t0,
                    level=model.launch_height[i],
                    landed=flight.landed[i],
                    apex=flight.apex[i],
                    t_land=flight.t_land[i],
                    land_x=flight.land_x[i],
                    land_v=flight.land_v[i],
                )
    return x1, v1, w1


@ti.func
def sweep(v_inelastic, bits, s: ti.template(), last: ti.template()):
    """One Jacobi sweep: the pairs' impulses from the velocities of the previous sweep, then each
    ball gathers them and meets its planes; the ``last`` sweep's ball loop also finishes the step
    (:func:`ball_sweep`). Between the two, when the pairs marked impacts (``flag[1]``), every ball
    finds its first impact (:func:`impact_keys`, :func:`matched`).
    A quiet ball gets no impulse (its pairs are skipped) and stays where it is; the last pair pass
    still visits its pairs, for the projections its awake neighbours gather. With the
    Gauss–Seidel sweeps (``s.kinds.gauss_seidel``) only the ball loop is built: their sweeps are
    done, and leave each pair's gap in J, all that the ball loop reads of the pairs."""
    state, scratch = ti.static((s.state, s.scratch))
    if ti.static(not s.kinds.gauss_seidel):
        scratch.flag[1] = 0
        for i in range(state.x.shape[0]):
            if ti.static(last) or scratch.calm[i] != QUIET:
                owned_pairs(i, last, s.params.h, v_inelastic, s)
        for i in range(state.x.shape[0]):
            if scratch.flag[1] != 0:  # (a loop inside the test would not run in parallel)
                impact_keys(i, bits, s.lists, scratch)
    pressed = PRESSED_OVERLAP  # the overlap [share of a radius] that keeps a ball awake
    if ti.static(s.kinds.gauss_seidel):
        pressed = ASLEEP_OVERLAP
    for i in range(state.x.shape[0]):
        if scratch.calm[i] == QUIET:
            if ti.static(last):
                scratch.x_free[i] = state.x[i]
        elif state.status[i] != OUT_OF_BOUNDS:
            ball_sweep(i, last, pressed, v_inelastic, bits, s)


@ti.func
def ball_sweep(i, last: ti.template(), pressed, v_inelastic, bits, s: ti.template()):
    """The ball loop of a :func:`sweep` for ball i (awake and in play): with the Jacobi sweeps, it
    gathers its pairs' impulses (:func:`gather`) and meets its planes and the terrain; with the
    Gauss–Seidel sweeps (only the last launch of a step comes here) it finds whether it touches a
    ball (:func:`touching_by_gaps`; ``pressed``: the overlap, a share of its radius, that keeps
    it awake). The ``last`` sweep then finishes the step (:func:`finish`)."""
    contact, state = ti.static((s.contact, s.state))
    dv, dw, dx, touching = zero3(), zero3(), zero3(), 0
    if ti.static(s.kinds.gauss_seidel):  # (only its last launch comes here)
        touching = touching_by_gaps(i, of_ball(s.model.radius, i), bits, contact.k_p, pressed, s.lists, s.scratch)
    else:
        dv, dw, dx, touching = gather(i, last, bits, contact.k_p, pressed, s)
    v_new, w_new = state.v[i] + dv, state.w[i] + dw
    if ti.static(not s.kinds.gauss_seidel):  # (its sweeps are done)
        v_new, w_new = surface_impulses(i, warm=False, vi=v_new, wi=w_new, h=s.params.h, v_inelastic=v_inelastic, s=s)
    if ti.static(not last):
        state.v[i], state.w[i] = v_new, w_new
    else:
        finish(i, v_new, w_new, dx, touching, s)


@ti.func
def finish(i, v_final, w_final, dx, touching, s: ti.template()):
    """End of the step for ball i (not out of bounds) with its final velocities, the position
    projection ``dx`` of its ball overlaps and whether it ``touching`` a ball: new position in
    ``x_free`` (split at a plane's time of impact, overlaps projected out: :func:`end_position`),
    status, rest timer, out-of-bounds; with the Jacobi sweeps, sets ``flag[0]`` when the neighbour
    lists must be rebuilt before the next step (:func:`.links.moved_past`; the Gauss–Seidel steps
    test after their projection, :func:`.stale.flag_stale_lists`)."""
    contact, terrain, params, model, state, scratch = ti.static(
        (s.contact, s.terrain, s.params, s.model, s.state, s.scratch)
    )
    h = params.h
    st = state.status[i]
    xi, ri = state.x[i], of_ball(model.radius, i)
    x1, v_final, touching = end_position(i, v_final, touching, s)
    if ti.static(not s.kinds.gauss_seidel):  # (Gauss–Seidel projects after the step: colour.project_sweep)
        x1 += dx  # position projection k_p·m_red·Δx·n̂ of the ball overlaps (B.18)
    if st == AT_REST and (v_final.norm() > 0.0 or w_final.norm() > 0.0):
        st = FLYING  # woken by an impulse
    if st != AT_REST:
        # island-like sleeping: the timer counts on from the least timer of the balls touching
        # this one at the start of the step (``calm``), so the balls of a calm group reach t_rest
        # together and fall asleep in the same step, and a ball pressed by a moving one stays
        # awake (asleep, it would feel no gravity and the balls above it would keep rocking)
        st, state.rest_time[i] = rest_update(
            touching, v_final, w_final, ri, scratch.calm[i], h, params.v_rest, params.t_rest, friction=s.kinds.friction
        )
        if st == AT_REST:
            v_final, w_final = zero3(), zero3()
            x1 = xi
    if ti.static(s.kinds.terrain):
        if outside(model.heights, terrain, x1):
            st = OUT_OF_BOUNDS
            v_final, w_final = zero3(), zero3()
    state.status[i] = st
    scratch.x_free[i] = x1
    state.v[i], state.w[i] = v_final, w_final
    if ti.static(not s.kinds.gauss_seidel):  # (the Gauss–Seidel steps test the pairs after the projection: see stale)
        if moved_past(x1, s.lists.x_at_build[i], 2.0 * h * v_final.norm(), params.half_skin):
            scratch.flag[0] = 1


@ti.func
def end_position(i, v_final, touching, s: ti.template()):
    """Ball i's position at the end of the step from its final velocity, split at the time of
    impact of each plane and of the terrain's patch that it reaches within the step (none beyond
    reach: :func:`.surfaces.surface_clearance`), as is the velocity of a bounce
    (:func:`~ti_golf.physics.contact.plane_position`): (the position [m], the velocity [m/s],
    ``touching`` raised to 1 when it ends within 1 % of its radius of one)."""
    contact, terrain, model, state, scratch = ti.static((s.contact, s.terrain, s.model, s.state, s.scratch))
    h, g = s.params.h, s.params.gravity
    xi, ri = state.x[i], of_ball(model.radius, i)
    x_free, v_free = scratch.x_free[i], scratch.v_free[i]
    x1 = x_free + h * (v_final - v_free)
    # no plane or terrain patch within reach of the flight or the end point (see surface_clearance)
    moved = ti.max((x_free - xi).norm_sqr(), (x1 - xi).norm_sqr())
    far = False
    if ti.static(not s.kinds.terrain):
        far = beyond_reach(scratch.clear[i], ri, moved)
    else:
        far = beyond_reach(scratch.clear[i], ri, 4.0 * moved) and same_cell(model.heights, terrain, xi, x1)
    n_planes = model.plane_p.shape[0]
    if far:
        n_planes = 0
    for p in range(n_planes):
        x1, v_final = plane_position(
            xi, x_free, x1, v_free, v_final, ri, model.plane_p[p], model.plane_n[p], contact.k_p, h, g
        )
        if (x1 - model.plane_p[p]).dot(model.plane_n[p]) - ri < TOUCHING_GAP * ri:
            touching = ti.max(touching, 1)
    if ti.static(s.kinds.terrain):
        if not far:
            pt, nt = surface(model.heights, terrain, x_free)
            x1, v_final = plane_position(xi, x_free, x1, v_free, v_final, ri, pt, nt, contact.k_p, h, g)
            x1 = terrain_position(xi, x1, pt, nt, ri, model.heights, terrain)
            if (x1 - pt).dot(nt) - ri < TOUCHING_GAP * ri:
                touching = ti.max(touching, 1)
    return x1, v_final, touching
