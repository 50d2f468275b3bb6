"""Kernels: one thread per ball, inputs first, outputs last.

Balls do not interact yet, so each thread integrates its own ball through many steps without
leaving the kernel (a "fused" step loop): per-step launch overhead is paid once per call.
"""


import taichi as ti

from ..config import AT_REST, FLYING, OUT_OF_BOUNDS, ROLLING
from .aero import ball_coefficients
from .contact import plane_contact
from .integrate import IN_FLIGHT, step_free, track_flight
from .types import AirParams, ContactParams, float_array, int_array, vec3, vec3_array, vec3_table


@ti.kernel
def fly_to_landing(
    # Model:
    air: AirParams,
    gravity: vec3,
    h: float,
    integrator: ti.template(),
    t_max: float,
    record_every: ti.i32,
    radius: float_array,
    mass: float_array,
    # State in/out (each ball advances until it lands or reaches t_max):
    x: vec3_array,
    v: vec3_array,
    w: vec3_array,
    # Flight record out:
    landed: int_array,
    apex: float_array,
    t_land: float_array,
    land_x: vec3_array,
    land_v: vec3_array,
    traj: vec3_table,
):
    """Integrate every ball from t = 0 to its landing at its launch height (sweeps).

    ``traj`` (N, S): positions every ``record_every`` steps while ``record_every > 0``; the
    remaining samples of a landed ball repeat its landing point.
    """
    for i in range(x.shape[0]):
        coef = ball_coefficients(air, radius[i], mass[i])
        xi, vi, wi = x[i], v[i], w[i]
        level = xi[1]
        state = IN_FLIGHT
        top, tl, lx, lv = xi[1], 0.0, xi, vi
        n_samples = traj.shape[1]
        if record_every > 0 and n_samples > 0:
            traj[i, 0] = xi
        k = 0
        while state == IN_FLIGHT and k * h < t_max:
            x1, v1, w1 = step_free(xi, vi, wi, h, integrator, coef, air, gravity)
            state, top, tl, lx, lv = track_flight(xi, vi, x1, v1, h, k * h, level, state, top, tl, lx, lv)
            xi, vi, wi = x1, v1, w1
            k += 1
            if record_every > 0 and k % record_every == 0:
                j = k // record_every
                if j < n_samples:
                    traj[i, j] = lx if state != IN_FLIGHT else xi
        if record_every > 0:
            j0 = k // record_every + 1
            for j in range(j0, n_samples):
                traj[i, j] = lx if state != IN_FLIGHT else xi
        x[i], v[i], w[i] = xi, vi, wi
        landed[i], apex[i], t_land[i], land_x[i], land_v[i] = state, top, tl, lx, lv


@ti.kernel
def advance(
    # Model:
    air: AirParams,
    contact: ContactParams,
    gravity: vec3,
    h: float,
    integrator: ti.template(),
    n_steps: ti.i32,
    t0: float,
    ground: ti.i32,
    ground_p: vec3,
    ground_n: vec3,
    v_rest: float,
    t_rest: float,
    radius: float_array,
    mass: float_array,
    launch_height: float_array,
    # State in/out:
    x: vec3_array,
    v: vec3_array,
    w: vec3_array,
    status: int_array,
    rest_time: float_array,
    # Flight record in/out:
    landed: int_array,
    apex: float_array,
    t_land: float_array,
    land_x: vec3_array,
    land_v: vec3_array,
):
    """Advance every active ball by ``n_steps`` steps of ``h`` [s] from time ``t0``, with ground contact.

    A ball that stays touching with speed and R|ω| below ``v_rest`` for ``t_rest`` is put at rest
    (velocities zeroed, no longer integrated). Balls at rest or out of bounds are not touched.
    """
    v_inelastic = contact.v_bounce + 2.0 * gravity.norm() * h
    for i in range(x.shape[0]):
        st = status[i]
        if st != AT_REST and st != OUT_OF_BOUNDS:
            r = radius[i]
            coef = ball_coefficients(air, r, mass[i])
            xi, vi, wi = x[i], v[i], w[i]
            rt = rest_time[i]
            fl, top, tl, lx, lv = landed[i], apex[i], t_land[i], land_x[i], land_v[i]
            for k in range(n_steps):
                x1, v1, w1 = step_free(xi, vi, wi, h, integrator, coef, air, gravity)
                fl, top, tl, lx, lv = track_flight(xi, vi, x1, v1, h, t0 + k * h, launch_height[i], fl, top, tl, lx, lv)
                touching = 0
                if ground != 0:
                    x1, v1, w1, touching = plane_contact(xi, x1, v1, w1, r, ground_p, ground_n, contact, v_inelastic, h)
                xi, vi, wi = x1, v1, w1
                if touching != 0 and vi.norm() < v_rest and r * wi.norm() < v_rest:
                    rt += h
                else:
                    rt = 0.0
                st = ROLLING if touching != 0 else FLYING
                if rt >= t_rest and touching != 0:
                    st = AT_REST
                    vi = vec3(0.0)
                    wi = vec3(0.0)
                    break
            x[i], v[i], w[i] = xi, vi, wi
            status[i], rest_time[i] = st, rt
            landed[i], apex[i], t_land[i], land_x[i], land_v[i] = fl, top, tl, lx, lv


@ti.kernel
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
