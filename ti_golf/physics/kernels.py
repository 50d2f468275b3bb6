"""Kernels: one thread per ball (or per lane group of balls), inputs first, outputs last.

These balls do not meet each other (flights, roll-outs, scenes with ``world.collisions = false``
or a single ball; the collision solvers of :mod:`ti_golf.solvers` step the rest), so each thread
integrates its balls through many steps without leaving the kernel (a "fused" step loop):
per-step launch overhead is paid once per call.
"""

import taichi as ti

from ti_golf.physics.aero import ROWS, SPIN, V, W, X, coefficients, column, row
from ti_golf.physics.contact import plane_impulse, plane_position, rest_update
from ti_golf.physics.integrate import (
    IN_FLIGHT,
    LANDED,
    NOT_TRACKED,
    apex_in_step,
    landing_in_step,
    step_free,
    track_flight,
)
from ti_golf.physics.terrain import outside, surface, surface_contact, terrain_position
from ti_golf.physics.types import (
    AirParams,
    BallState,
    FlightRecord,
    ModelArrays,
    float_array,
    int_array,
    kernel,
    of_ball,
    scalars_of,
    vec,
    vec3,
    vec3_array,
    vec3_table,
    vec3f_array,
    vec4f_table,
    zero3,
)
from ti_golf.scene.schema import AT_REST, OUT_OF_BOUNDS


@ti.func
def lane_state(x, v, w):
    """A (10, 1) lane state matrix holding one ball's x, v, ω and |ω|."""
    return ti.Matrix([[x[0]], [x[1]], [x[2]], [v[0]], [v[1]], [v[2]], [w[0]], [w[1]], [w[2]], [w.norm()]])


@kernel
def fly_to_landing(  # noqa: C901 (the fused flight kernel: steps, apex, landing and samples in one loop)
    # Model:
    air: AirParams,
    gravity: vec3,
    h: float,
    kinds: ti.template(),
    lanes: ti.template(),
    t_max: float,
    record_every: ti.i32,
    radius: float_array,
    mass: float_array,
    # Launch (read only):
    order: int_array,
    x0: vec3_array,
    v0: vec3_array,
    w0: vec3_array,
    # Flight record out:
    landed: int_array,
    apex: float_array,
    t_land: float_array,
    land_x: vec3_array,
    land_v: vec3_array,
    land_w: vec3_array,
    traj: vec3_table,
):
    """Integrate balls from their launch state until they land at their launch height (sweeps).

    Balls go in groups of ``lanes`` that step together (SIMD) until all of them have landed or
    ``t_max`` [s] has passed. Slot s of the launch order flies ball ``order[s]``; ``order`` should
    put balls of similar flight time next to each other, and its length is a multiple of ``lanes``
    (pad by repeating an id: each ball's results are written once, by its first slot).
    ``traj`` (N, S): positions every ``record_every`` steps while ``record_every > 0``; after
    landing a trajectory repeats its landing point. ``land_w``: ω at landing [rad/s], linear in
    time inside the landing step (error O(h²·d²ω/dt²), far below the spin decay per step).
    """
    n_samples = traj.shape[1]
    for group in range(order.shape[0] // lanes):
        ids = ti.Vector([order[group * lanes + l] for l in ti.static(range(lanes))])
        S = ti.Matrix.zero(float, ROWS, lanes)
        rad = ti.Vector.zero(float, lanes)
        mas = ti.Vector.zero(float, lanes)
        for l in ti.static(range(lanes)):
            for c in ti.static(range(3)):
                S[X + c, l] = x0[ids[l]][c]
                S[V + c, l] = v0[ids[l]][c]
                S[W + c, l] = w0[ids[l]][c]
            S[SPIN, l] = w0[ids[l]].norm()
            rad[l] = of_ball(radius, ids[l])
            mas[l] = of_ball(mass, ids[l])
        coef = coefficients(air, kinds, rad, mas)
        level = row(S, 1)
        state = ti.Vector([IN_FLIGHT] * lanes, dt=ti.i32)
        top = row(S, 1)
        tl = ti.Vector.zero(float, lanes)
        LX = ti.Matrix.zero(float, 3, lanes)
        LV = ti.Matrix.zero(float, 3, lanes)
        LW = ti.Matrix.zero(float, 3, lanes)
        if record_every > 0 and n_samples > 0:
            for l in ti.static(range(lanes)):
                traj[ids[l], 0] = column(S, X, l)
        k = 0
        flying = 1
        while flying != 0 and k * h < t_max:
            S1 = step_free(S, h, kinds, coef, air, gravity)
            # Lane-wise checks every step; the scalar per-ball work runs only at an apex or a landing.
            in_flight = state == IN_FLIGHT
            y, y1, vy, vy1 = row(S, 1), row(S1, 1), row(S, 4), row(S1, 4)
            top = ti.select(in_flight, ti.max(top, y1), top)
            peak = in_flight & (vy > 0.0) & (vy1 <= 0.0)
            cross = in_flight & (y >= level) & (y1 < level)
            if (peak | cross).any():
                for l in ti.static(range(lanes)):
                    if peak[l]:
                        top[l] = ti.max(top[l], apex_in_step(y[l], y1[l], vy[l], vy1[l], h))
                    if cross[l]:
                        t1, p, u = landing_in_step(
                            column(S, X, l), column(S, V, l), column(S1, X, l), column(S1, V, l), h, k * h, level[l]
                        )
                        state[l], tl[l] = LANDED, t1
                        f = t1 / h - k  # the landing's fraction of the step
                        for c in ti.static(range(3)):
                            LX[c, l], LV[c, l] = p[c], u[c]
                            LW[c, l] = S[W + c, l] + f * (S1[W + c, l] - S[W + c, l])
                flying = ti.cast((state == IN_FLIGHT).any(), ti.i32)
            S = S1
            k += 1
            if record_every > 0 and k % record_every == 0 and k // record_every < n_samples:
                for l in ti.static(range(lanes)):
                    traj[ids[l], k // record_every] = column(S, X, l) if state[l] == IN_FLIGHT else column(LX, 0, l)
        if record_every > 0:
            for j in range(k // record_every + 1, n_samples):
                for l in ti.static(range(lanes)):
                    traj[ids[l], j] = column(S, X, l) if state[l] == IN_FLIGHT else column(LX, 0, l)
        for l in ti.static(range(lanes)):
            first = True
            for m in ti.static(range(l)):
                if ids[m] == ids[l]:
                    first = False
            if first:
                i = ids[l]
                landed[i], apex[i], t_land[i] = state[l], top[l], tl[l]
                land_x[i], land_v[i], land_w[i] = column(LX, 0, l), column(LV, 0, l), column(LW, 0, l)


@kernel
def advance(
    # Model:
    scalars: float_array,
    t0: ti.f64,
    dt: ti.f64,
    steps: ti.i32,
    kinds: ti.template(),
    model: ModelArrays,
    # State in/out:
    state: BallState,
    flight: FlightRecord,
):
    """Advance every active ball by ``steps`` steps of ``params.h`` [s] from ``t0`` [s], the time of
    step k being ``t0`` plus ``dt`` [s] added k times in f64 (as :meth:`.state.State.advance_clock`
    adds it, so that a run's times do not depend on how its steps are split into launches); balls do not meet
    each other, only the planes and the terrain (one thread per ball runs all the steps). The air,
    contact, terrain and step parameters come in one array, ``scalars`` (:func:`.types.scalars_of`).

    A ball that stays touching with speed and R|ω| below ``v_rest`` for ``t_rest`` is put at rest
    (velocities zeroed, no longer integrated). With a terrain (``terrain.on``; ``heights`` is its
    grid, else any 2×2 array), a ball that leaves the grid's (x, z) extent or falls below
    ``terrain.kill`` is put out of bounds (velocities zeroed). Balls at rest or out of bounds are
    not touched.
    """
    air, contact, terrain, params = scalars_of(scalars)
    h = params.h
    v_inelastic = contact.v_bounce + 2.0 * params.gravity.norm() * h
    tracking = flight.landed.shape[0] == state.x.shape[0]  # else no ball is tracked: one-entry flight records, not read
    for i in range(state.x.shape[0]):
        st = state.status[i]
        if st != AT_REST and st != OUT_OF_BOUNDS:
            r = of_ball(model.radius, i)
            coef = coefficients(air, kinds, ti.Vector([r]), ti.Vector([of_ball(model.mass, i)]))
            xi, vi, wi = state.x[i], state.v[i], state.w[i]
            rt = state.rest_time[i]
            fl, top, tl, lx, lv, level = NOT_TRACKED, 0.0, 0.0, zero3(), zero3(), 0.0
            if tracking:
                fl, top, tl, lx, lv, level = (
                    flight.landed[i],
                    flight.apex[i],
                    flight.t_land[i],
                    flight.land_x[i],
                    flight.land_v[i],
                    model.launch_height[i],
                )
            t_step = t0  # (f64: the time at the start of each step)
            for _k in range(steps):
                S1 = step_free(lane_state(xi, vi, wi), h, kinds, coef, air, params.gravity)
                x_free, v_free, w1 = column(S1, X, 0), column(S1, V, 0), column(S1, W, 0)
                fl, top, tl, lx, lv = track_flight(
                    xi, vi, x_free, v_free, h, ti.cast(t_step, float), level, fl, top, tl, lx, lv
                )
                v1 = v_free
                touching = 0
                pushed = v_free - vi - h * params.gravity  # (what the air added this step [m/s])
                for p in range(model.plane_p.shape[0]):
                    v_in = v_inelastic + 2.0 * ti.max(-pushed.dot(model.plane_n[p]), 0.0)
                    v1, w1, t = plane_impulse(
                        xi, v1, w1, r, model.plane_p[p], model.plane_n[p], contact, v_in, h, kinds
                    )
                    touching |= t
                pt, nt = zero3(), vec(0.0, 1.0, 0.0)
                if ti.static(kinds.terrain):  # the terrain: the plane of the patch under the free-flight end point
                    pt, nt = surface(model.heights, terrain, x_free)
                    ct = surface_contact(
                        contact, model.surface_table, model.terrain_cells, model.heights, terrain, x_free
                    )
                    v_in = v_inelastic + 2.0 * ti.max(-pushed.dot(nt), 0.0)
                    v1, w1, t = plane_impulse(xi, v1, w1, r, pt, nt, ct, v_in, h, kinds)
                    touching |= t
                x1 = x_free + h * (v1 - v_free)
                for p in range(model.plane_p.shape[0]):
                    x1, v1 = plane_position(
                        xi,
                        x_free,
                        x1,
                        v_free,
                        v1,
                        r,
                        model.plane_p[p],
                        model.plane_n[p],
                        contact.k_p,
                        h,
                        params.gravity,
                    )
                if ti.static(kinds.terrain):
                    x1, v1 = plane_position(xi, x_free, x1, v_free, v1, r, pt, nt, contact.k_p, h, params.gravity)
                    x1 = terrain_position(xi, x1, pt, nt, r, model.heights, terrain)
                xi, vi, wi = x1, v1, w1
                t_step += dt
                st, rt = rest_update(touching, vi, wi, r, rt, h, params.v_rest, params.t_rest, kinds.friction)
                if ti.static(kinds.terrain):
                    if outside(model.heights, terrain, xi):
                        st = OUT_OF_BOUNDS
                        vi = zero3()
                        wi = zero3()
                        break
                if st == AT_REST:
                    vi = zero3()
                    wi = zero3()
                    break
            state.x[i], state.v[i], state.w[i] = xi, vi, wi
            state.status[i], state.rest_time[i] = st, rt
            if tracking:
                flight.landed[i], flight.apex[i], flight.t_land[i], flight.land_x[i], flight.land_v[i] = (
                    fl,
                    top,
                    tl,
                    lx,
                    lv,
                )


@kernel
def first_nonfinite(x: vec3_array, v: vec3_array, w: vec3_array, out: int_array):
    """``out[0]`` = smallest id of a ball whose x, v or ω holds NaN or ±inf, or N when all are finite.

    (An integer atomic min: the answer does not depend on thread order. ``isnan``/``isinf`` survive
    fast-math, unlike ``s != s``.)
    """
    out[0] = x.shape[0]
    for i in range(x.shape[0]):
        s = x[i].sum() + v[i].sum() + w[i].sum()
        if ti.math.isnan(s) or ti.math.isinf(s):
            ti.atomic_min(out[0], i)


@kernel
def zero_f32_vectors(a: vec3f_array):
    """Set every vector of an f32 array to zero.

    ``Ndarray.fill`` would compile a kernel that holds its value in the run's float type: in an f64
    run Taichi warns "Assign may lose precision" while it compiles it.
    """
    for i in range(a.shape[0]):
        a[i] = ti.Vector([0.0, 0.0, 0.0], dt=ti.f32)


@kernel
def zero_f32_table(a: vec4f_table):
    """Set every entry of a table of f32 4-vectors to zero (see :func:`zero_f32_vectors`)."""
    for i, j in ti.ndrange(a.shape[0], a.shape[1]):
        a[i, j] = ti.Vector([0.0, 0.0, 0.0, 0.0], dt=ti.f32)


@kernel
def copy_ints(source: int_array, target: int_array):
    """``target[i] = source[i]`` for every entry of ``source`` (``target`` at least as long): as
    ``Ndarray.copy_from``, whose own kernel's loop stays parallel in
    :func:`ti_golf.one_thread.in_one_thread`."""
    for i in range(source.shape[0]):
        target[i] = source[i]


@kernel
def int_at(a: int_array, i: ti.i32) -> ti.i32:
    """Entry i of an int array (a fifth of the time of ``a.to_numpy()[i]`` for a small array on the
    CI class: no copy, no loop)."""
    return a[i]
