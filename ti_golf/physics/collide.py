"""Kernels of a step with ball–ball collisions (report Appendix B, every touching pair at once).

A step, with h the time step:

1. ``free_step``: every awake ball flies freely (forces, integrator) to a predicted position;
   flight records (apex, landing) are updated; balls that moved too far flag a list rebuild;
2. ``contact_pass`` × ``contact.iterations``: Jacobi sweeps. Each ball gathers the impulses of
   all its touching neighbours, computed from the velocities of the previous sweep, then those of
   the planes. Every pair impulse is evaluated with the lower id as body a, so the two balls of a
   pair see exactly opposite impulses (momentum is conserved to round-off) and no float atomics
   are needed (results do not depend on thread order);
3. ``finish_step``: positions from the final velocities (split at a plane's time of impact),
   position projection of overlaps (B.18), status and rest detection.
"""

import taichi as ti

from ..config import AT_REST, FLYING, OUT_OF_BOUNDS, ROLLING
from .aero import V, W, X, coefficients, column
from .contact import pair_impulse, plane_impulse, plane_position, spin_jolt
from .grid import int_table
from .integrate import step_free, track_flight
from .kernels import lane_state
from .types import AirParams, ContactParams, float_array, int_array, vec3, vec3_array


@ti.kernel
def free_step(
    # Model:
    air: AirParams,
    gravity: vec3,
    h: float,
    integrator: ti.template(),
    t0: float,
    half_skin: float,
    radius: float_array,
    mass: float_array,
    launch_height: float_array,
    status: int_array,
    x: vec3_array,
    x_at_build: vec3_array,
    # State in → free-flight out:
    v: vec3_array,
    w: vec3_array,
    x_free: vec3_array,
    # Flight record in/out:
    landed: int_array,
    apex: float_array,
    t_land: float_array,
    land_x: vec3_array,
    land_v: vec3_array,
    rebuild: int_array,
):
    """Free flight of every awake ball over one step; ``rebuild[0]`` = 1 when a neighbour list may miss a contact."""
    for i in range(x.shape[0]):
        xi = x[i]
        x1, v1, w1 = xi, vec3(0.0), vec3(0.0)
        if status[i] != AT_REST and status[i] != OUT_OF_BOUNDS:
            coef = coefficients(air, ti.Vector([radius[i]]), ti.Vector([mass[i]]))
            S1 = step_free(lane_state(xi, v[i], w[i]), h, integrator, coef, air, gravity)
            x1, v1, w1 = column(S1, X, 0), column(S1, V, 0), column(S1, W, 0)
            landed[i], apex[i], t_land[i], land_x[i], land_v[i] = track_flight(
                xi, v[i], x1, v1, h, t0, launch_height[i], landed[i], apex[i], t_land[i], land_x[i], land_v[i])
        x_free[i], v[i], w[i] = x1, v1, w1
        if (xi - x_at_build[i]).norm() + h * v1.norm() > half_skin:
            rebuild[0] = 1


@ti.kernel
def contact_pass(
    # Model:
    contact: ContactParams,
    h: float,
    v_inelastic: float,
    radius: float_array,
    mass: float_array,
    plane_p: vec3_array,
    plane_n: vec3_array,
    status: int_array,
    x: vec3_array,
    neighbours: int_table,
    n_neighbours: int_array,
    # Velocities of the previous sweep in, of this sweep out:
    v_in: vec3_array,
    w_in: vec3_array,
    v_out: vec3_array,
    w_out: vec3_array,
):
    """One Jacobi sweep of ball–ball and ball–plane impulses (gathered per ball)."""
    for i in range(x.shape[0]):
        vi, wi = v_in[i], w_in[i]
        if status[i] != OUT_OF_BOUNDS:
            dv, dw = vec3(0.0), vec3(0.0)
            for k in range(n_neighbours[i]):
                j = neighbours[i, k]
                if status[j] != OUT_OF_BOUNDS and (status[i] != AT_REST or status[j] != AT_REST):
                    a, b = ti.min(i, j), ti.max(i, j)  # evaluate every pair as (lower id, higher id)
                    d = x[a] - x[b]
                    dist = d.norm()
                    if dist > 0.0:
                        n = d / dist
                        inv_ma, inv_mb = 1.0 / mass[a], 1.0 / mass[b]
                        P, touching = pair_impulse(n, dist - radius[a] - radius[b], v_in[a], w_in[a], radius[a],
                                                   inv_ma, v_in[b], w_in[b], radius[b], inv_mb, contact.e, contact.mu,
                                                   v_inelastic, h)
                        if i == a:
                            dv += P * inv_ma
                            dw += spin_jolt(P, n, radius[a], inv_ma)
                        else:
                            dv -= P * inv_mb
                            dw += spin_jolt(-P, -n, radius[b], inv_mb)
            vi += dv
            wi += dw
            for p in range(plane_p.shape[0]):
                vi, wi, _ = plane_impulse(x[i], vi, wi, radius[i], plane_p[p], plane_n[p], contact, v_inelastic, h)
        v_out[i], w_out[i] = vi, wi


@ti.kernel
def finish_step(
    # Model:
    contact: ContactParams,
    h: float,
    v_rest: float,
    t_rest: float,
    radius: float_array,
    mass: float_array,
    plane_p: vec3_array,
    plane_n: vec3_array,
    neighbours: int_table,
    n_neighbours: int_array,
    x: vec3_array,
    x_free: vec3_array,
    v_free: vec3_array,
    v_final: vec3_array,
    w_final: vec3_array,
    # out:
    x_new: vec3_array,
    v: vec3_array,
    w: vec3_array,
    status: int_array,
    rest_time: float_array,
):
    """Positions, projections, status and rest detection at the end of the step.

    ``v`` may be the same array as ``v_free`` (it is read before it is written, per ball).
    """
    for i in range(x.shape[0]):
        st = status[i]
        if st != OUT_OF_BOUNDS:
            xi, ri = x[i], radius[i]
            vf, wf = v_final[i], w_final[i]
            x1 = x_free[i] + h * (vf - v_free[i])
            touching = 0
            for p in range(plane_p.shape[0]):
                x1 = plane_position(xi, x_free[i], x1, v_free[i], vf, ri, plane_p[p], plane_n[p], contact.k_p, h)
                if (x1 - plane_p[p]).dot(plane_n[p]) - ri < 0.01 * ri:
                    touching = 1
            for k in range(n_neighbours[i]):  # position projection k_p·m_red·Δx·n̂ (B.18)
                j = neighbours[i, k]
                d = xi - x[j]
                dist = d.norm()
                overlap = ri + radius[j] - dist
                if overlap > -0.01 * ri:
                    touching = 1
                if overlap > 0.0 and dist > 0.0:
                    x1 += contact.k_p * mass[j] / (mass[i] + mass[j]) * overlap * (d / dist)
            if st == AT_REST and (vf.norm() > 0.0 or wf.norm() > 0.0):
                st = FLYING  # woken by an impulse
            if st != AT_REST:
                rt = rest_time[i]
                if touching != 0 and vf.norm() < v_rest and ri * wf.norm() < v_rest:
                    rt += h
                else:
                    rt = 0.0
                st = ROLLING if touching != 0 else FLYING
                if rt >= t_rest and touching != 0:
                    st = AT_REST
                    vf, wf = vec3(0.0), vec3(0.0)
                    x1 = xi
                rest_time[i] = rt
            x_new[i] = x1
            v[i], w[i] = vf, wf
            status[i] = st
        else:
            x_new[i] = x[i]
