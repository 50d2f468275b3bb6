"""Serial Gauss–Seidel steps by blocks of grid columns (:func:`gauss_seidel_steps`): the parallel
step of :meth:`.gauss_seidel.GaussSeidelSolver._sweep`, its launches run one after another in one
thread, many steps in one launch. A colour's blocks never share a ball (:mod:`.colour`), so taking
them one after another gives what the threads give: the same step, bit for bit, without the dozen
launches a step that cost a pile of a few thousand balls more than the step itself. The launch
stops where a step asks for new lists, which the caller builds through the grid."""

from typing import Any, NamedTuple

import taichi as ti

from ti_golf.physics.types import (
    BallState,
    BlockOrder,
    FlightRecord,
    GridParams,
    ModelArrays,
    NeighbourLists,
    StepScratch,
    float_array,
    int_array,
    kernel,
    scalars_of,
)
from ti_golf.solvers.collide import step_balls
from ti_golf.solvers.colour import COLOURS, PROJECTIONS, phase_of_sweep, project_ball, sweep_ball
from ti_golf.solvers.phases import Phase
from ti_golf.solvers.stale import flag_stale_lists, in_play
from ti_golf.solvers.step import Step


class BuildGrid(NamedTuple):
    """The grid of the last build as :func:`.stale.flag_stale_lists` reads it: its buckets' starts
    and the balls sorted by bucket (the members of :data:`~ti_golf.physics.types.GridScratch` it reads)."""

    start: Any
    sorted_ids: Any


@kernel
def gauss_seidel_steps(
    scalars: float_array,
    t0: ti.f64,
    dt: ti.f64,
    steps: ti.i32,
    kinds: ti.template(),
    model: ModelArrays,
    lists: NeighbourLists,
    state: BallState,
    flight: FlightRecord,
    scratch: StepScratch,
    g: GridParams,
    grid_start: int_array,
    grid_sorted_ids: int_array,
    apart_ids: int_array,
    iterations: ti.template(),
    any_far: ti.i32,
    inv_cell: float,
    skip_still: ti.i32,
    blocks: BlockOrder,
    walk: int_array,
) -> ti.i32:
    """Up to ``steps`` Gauss–Seidel steps of ``dt`` [s] (f64) from the time ``t0`` [s], each with
    ``iterations`` sweeps, as the parallel launches take them: the free flight and warm start,
    the sweeps and the restitution pass, the last sweep, which finishes the step, and the
    ``PROJECTIONS`` passes of the position projection (each pass: :func:`serial_pass`, with
    ``any_far``, ``blocks`` and ``inv_cell`` as :func:`.colour.gauss_seidel_sweep` has them), then
    the test of the lists with the grid of the last build (``g``, its buckets' starts and the
    balls by bucket, ``grid_start`` and ``grid_sorted_ids``, and ``apart_ids``: see
    :func:`.stale.flag_stale_lists`; arrays, not the :data:`~ti_golf.physics.types.GridScratch`
    pack: Taichi 1.7.4 mixes up the members of two packs that share a name, here ``start``,
    reading one pack's as missing). The first ten arguments are those of
    :func:`.collide.collision_step`. Stops before a step when ``scratch.flag[0]`` asks for
    new lists, or, with ``skip_still``, when no ball is awake and in play (the caller skips such
    steps: see ``CollisionSolver.skip_still``); returns the steps taken. ``walk`` (n entries) is
    its scratch: the balls colour after colour (:func:`colour_walk`)."""
    air, contact, terrain, params = scalars_of(scalars)
    s = ti.static(Step(contact, terrain, params, model, lists, state, scratch, kinds=kinds, air=air, flight=flight))
    taken = 0
    t = t0
    ti.loop_config(serialize=True)
    for step in range(steps):
        if (
            step == 0
        ):  # (inside the serial loop: a loop of its own would be a parallel one; the blocks hold for the launch)
            colour_walk(blocks, walk)
        if scratch.flag[0] != 0 or (skip_still != 0 and not any_in_play(state.status)):
            break
        step_balls(ti.cast(t, float), kinds, s, serial=False, warm=True, sweeps=0, last=False)
        for k in range(iterations + 2 + PROJECTIONS):  # (one call site each: each inlines its whole pass)
            if k == iterations + 1:  # the last sweep, which finishes the step
                step_balls(ti.cast(t, float), kinds, s, serial=False, warm=False, sweeps=0, last=True)
            else:
                phase = Phase.PROJECT
                if k <= iterations:
                    phase = phase_of_sweep(k, iterations)
                serial_pass(phase, any_far, walk, inv_cell, s)
        grid = ti.static(BuildGrid(grid_start, grid_sorted_ids))
        flag_stale_lists(s, serial=False, g=g, grid=grid, apart_ids=apart_ids, stored_sorted=False)
        for i in range(state.x.shape[0]):
            state.x[i] = scratch.x_free[i]
        t += dt
        taken += 1
    return taken


@ti.func
def any_in_play(status: ti.template()):
    """Whether some ball of ``status`` is awake and in play (:func:`.stale.in_play`), in the
    calling (serial) thread, which stops at the first."""
    found = False
    for i in range(status.shape[0]):
        if in_play(status[i]) != 0:
            found = True
            break
    return found


@ti.func
def colour_walk(blocks: ti.template(), walk: ti.template()):
    """The balls in the order the colours take them, into ``walk``: colour after colour, the
    blocks of a colour in their order and each block's balls bottom-up (``blocks``: see
    :func:`.colour.column_order`), in the calling (serial) thread."""
    n, taken = blocks.ids.shape[0], 0
    for q in range(COLOURS * n):
        c, m = q // n, q % n
        if blocks.colour[m] == c:
            walk[taken] = blocks.ids[m]
            taken += 1


@ti.func
def serial_pass(phase, any_far, walk: ti.template(), inv_cell, s: ti.template()):
    """A sweep of ``phase``, or a pass of the position projection (``Phase.PROJECT``), as the
    parallel launches take it, in the calling (serial) thread: the balls colour after colour
    (``walk``, :func:`colour_walk`; the blocks of a colour share no ball, so their order does not
    matter: :func:`.colour.block_sweep`) and, with ``any_far``, every ball's pairs that the
    colours left out (:func:`.colour.far_pairs`), after the colours in a sweep and before them
    in a projection pass."""
    n = s.state.x.shape[0]
    slots = n
    if any_far != 0:
        slots = 2 * n  # slots n to 2n − 1: every ball's far pairs, in storage order
    for q in range(slots):
        k = q
        if phase == Phase.PROJECT:  # (a projection pass takes the far pairs first)
            k = (q + n) % slots
        i, far_only = k - n, 1
        if k < n:
            i, far_only = walk[k], 0
        if phase == Phase.PROJECT:
            project_ball(i, far_only, any_far, inv_cell, s)
        else:
            sweep_ball(i, phase, far_only, any_far, inv_cell, s)
