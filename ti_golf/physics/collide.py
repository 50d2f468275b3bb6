"""One step of colliding balls in a single kernel (report Appendix B, every touching pair at once).

The kernel's top-level loops run one after another, each over all balls in parallel:

1. free flight: every awake ball flies under gravity and air forces (the integrator) to a
   predicted position; flight records (apex, landing) are updated;
2. warm start: last step's *resting* contact impulses (and their friction) are applied again, so
   a stack starts the step supported instead of re-learning its support every step;
3. ``iterations`` Jacobi sweeps: each ball gathers the impulses of its touching neighbours,
   computed from the velocities of the previous sweep, then those of the planes and of the
   terrain (the plane of the patch under the ball, see :mod:`.terrain`). Every pair
   impulse is evaluated with the lower id as body a, so the two balls of a pair apply exactly
   opposite impulses (momentum is conserved to round-off) without float atomics, and results do
   not depend on thread order;
4. finish: positions from the final velocities (split at a plane's time of impact), position
   projection of overlaps (B.18), status, rest detection and out-of-bounds (off the terrain), and
   whether the neighbour lists must be rebuilt before the next step.
"""

import taichi as ti

from ..config import AT_REST, FLYING, OUT_OF_BOUNDS
from .aero import V, W, X, coefficients, column
from .contact import pair_impulse, plane_jolt, plane_position, rest_update, spin_jolt, warm_impulse
from .grid import int_table, real_table
from .integrate import step_free, track_flight
from .kernels import lane_state
from .terrain import outside, surface, surface_contact, terrain_position
from .types import (AirParams, ContactParams, TerrainParams, float_array, float_grid, int_array, int_grid, vec3,
                    vec3_array)


@ti.func
def pair_geometry(x: ti.template(), radius: ti.template(), a, b):
    """Unit normal from ball b to ball a, their surface gap [m], and whether the normal is defined."""
    d = x[a] - x[b]
    dist = d.norm()
    n = vec3(0.0, 1.0, 0.0)
    ok = dist > 0.0
    if ok:
        n = d / dist
    return n, dist - radius[a] - radius[b], ok


@ti.func
def gather(dv, dw, P, n, i_is_a, r_a, r_b, inv_ma, inv_mb):
    """Add the pair impulse P (on a; −P on b) to the velocity and spin jolts of ball i."""
    if i_is_a:
        dv += P * inv_ma
        dw += spin_jolt(P, n, r_a, inv_ma)
    else:
        dv -= P * inv_mb
        dw += spin_jolt(-P, -n, r_b, inv_mb)
    return dv, dw


@ti.func
def sweep_ball(i, contact: ti.template(), h, v_inelastic, radius: ti.template(), mass: ti.template(),
               plane_p: ti.template(), plane_n: ti.template(), terrain, heights: ti.template(),
               terrain_cells: ti.template(), surface_table: ti.template(),
               status: ti.template(), x: ti.template(), x_free: ti.template(),
               neighbours: ti.template(), n_neighbours: ti.template(), lam: ti.template(),
               lam_plane: ti.template(), v_in: ti.template(), w_in: ti.template(), v_out: ti.template(),
               w_out: ti.template()):
    """One Jacobi sweep for ball i: gather its pair impulses, then its plane impulses, then the
    terrain's (the plane of the patch under its free-flight end point; its resting impulse is kept
    in the column after the planes' in ``lam_plane``)."""
    vi, wi = v_in[i], w_in[i]
    if status[i] != OUT_OF_BOUNDS:
        dv, dw = vec3(0.0), vec3(0.0)
        for k in range(n_neighbours[i]):
            j = neighbours[i, k]
            if status[j] != OUT_OF_BOUNDS and (status[i] != AT_REST or status[j] != AT_REST):
                a, b = ti.min(i, j), ti.max(i, j)  # evaluate every pair as (lower id, higher id)
                n, gap, ok = pair_geometry(x, radius, a, b)
                if ok:
                    inv_ma, inv_mb = 1.0 / mass[a], 1.0 / mass[b]
                    P, lam_ab, _ = pair_impulse(n, gap, v_in[a], w_in[a], radius[a], inv_ma, v_in[b], w_in[b],
                                                radius[b], inv_mb, lam[i, k], contact.e, contact.mu, v_inelastic, h,
                                                contact.relax)
                    lam[i, k] = lam_ab  # both balls of the pair store the same value
                    dv, dw = gather(dv, dw, P, n, i == a, radius[a], radius[b], inv_ma, inv_mb)
            elif status[j] == OUT_OF_BOUNDS:
                lam[i, k] = 0.0  # a frozen ball no longer supports anything (no warm start from it)
        vi += dv
        wi += dw
        for p in range(plane_p.shape[0]):
            n = plane_n[p]
            gap = (x[i] - plane_p[p]).dot(n) - radius[i]
            P, lam_p, _ = pair_impulse(n, gap, vi, wi, radius[i], 1.0, vec3(0.0), vec3(0.0), 0.0, 0.0,
                                       lam_plane[i, p], contact.e, contact.mu, v_inelastic, h)
            if P.dot(n) != 0.0:
                vi, wi = plane_jolt(P, lam_p - lam_plane[i, p], vi, wi, radius[i], n, contact.mu_roll)
            lam_plane[i, p] = lam_p
        if terrain.on != 0:
            q = plane_p.shape[0]
            pt, n = surface(heights, terrain, x_free[i])
            ct = surface_contact(contact, surface_table, terrain_cells, heights, terrain, x_free[i])
            gap = (x[i] - pt).dot(n) - radius[i]
            P, lam_p, _ = pair_impulse(n, gap, vi, wi, radius[i], 1.0, vec3(0.0), vec3(0.0), 0.0, 0.0,
                                       lam_plane[i, q], ct.e, ct.mu, v_inelastic, h)
            if P.dot(n) != 0.0:
                vi, wi = plane_jolt(P, lam_p - lam_plane[i, q], vi, wi, radius[i], n, ct.mu_roll)
            lam_plane[i, q] = lam_p
    v_out[i], w_out[i] = vi, wi


@ti.kernel
def collision_step(
    # Model:
    air: AirParams,
    contact: ContactParams,
    gravity: vec3,
    h: float,
    integrator: ti.template(),
    iterations: ti.template(),
    t0: float,
    half_skin: float,
    v_rest: float,
    t_rest: float,
    radius: float_array,
    mass: float_array,
    launch_height: float_array,
    plane_p: vec3_array,
    plane_n: vec3_array,
    terrain: TerrainParams,
    heights: float_grid,
    terrain_cells: int_grid,
    surface_table: float_grid,
    # Neighbour lists (built by grid.build_neighbours) and their accumulated resting impulses:
    neighbours: int_table,
    n_neighbours: int_array,
    x_at_build: vec3_array,
    lam: real_table,
    lam_plane: real_table,
    # State in/out:
    x: vec3_array,
    v: vec3_array,
    w: vec3_array,
    status: int_array,
    rest_time: float_array,
    # Scratch:
    x_free: vec3_array,
    v_a: vec3_array,
    w_a: vec3_array,
    v_b: vec3_array,
    w_b: vec3_array,
    # Flight record in/out:
    landed: int_array,
    apex: float_array,
    t_land: float_array,
    land_x: vec3_array,
    land_v: vec3_array,
    flag: int_array,
):
    """Advance all balls by one step of ``h`` [s]. On return ``flag[0]`` is 1 when some ball may
    come within reach of a ball missing from its neighbour list next step (rebuild the lists).
    New positions are left in ``x_free`` (swap it with ``x``). With a terrain (``terrain.on``;
    ``heights`` its grid, else any 2×2 array; ``lam_plane`` then has a column more than there are
    planes) a ball that leaves the grid's extent or falls below ``terrain.kill`` is put out of
    bounds (velocities zeroed)."""
    v_inelastic = contact.v_bounce + 2.0 * gravity.norm() * h
    # 1. free flight (v, w become the free-flight velocities)
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
    # 2. warm start with last step's resting impulses
    for i in range(x.shape[0]):
        vi, wi = v[i], w[i]
        if status[i] != OUT_OF_BOUNDS:
            dv, dw = vec3(0.0), vec3(0.0)
            for k in range(n_neighbours[i]):
                if lam[i, k] > 0.0 and status[neighbours[i, k]] != OUT_OF_BOUNDS:
                    j = neighbours[i, k]
                    a, b = ti.min(i, j), ti.max(i, j)
                    n, _, ok = pair_geometry(x, radius, a, b)
                    if ok:
                        inv_ma, inv_mb = 1.0 / mass[a], 1.0 / mass[b]
                        P = warm_impulse(n, v[a], w[a], radius[a], v[b], w[b], radius[b], inv_ma + inv_mb,
                                         lam[i, k], contact.mu)
                        dv, dw = gather(dv, dw, P, n, i == a, radius[a], radius[b], inv_ma, inv_mb)
            vi += dv
            wi += dw
            for p in range(plane_n.shape[0]):
                if lam_plane[i, p] > 0.0:
                    n = plane_n[p]
                    P = warm_impulse(n, vi, wi, radius[i], vec3(0.0), vec3(0.0), 0.0, 1.0, lam_plane[i, p], contact.mu)
                    vi, wi = plane_jolt(P, lam_plane[i, p], vi, wi, radius[i], n, contact.mu_roll)
            if terrain.on != 0:
                q = plane_n.shape[0]
                if lam_plane[i, q] > 0.0:
                    _, n = surface(heights, terrain, x_free[i])
                    ct = surface_contact(contact, surface_table, terrain_cells, heights, terrain, x_free[i])
                    P = warm_impulse(n, vi, wi, radius[i], vec3(0.0), vec3(0.0), 0.0, 1.0, lam_plane[i, q], ct.mu)
                    vi, wi = plane_jolt(P, lam_plane[i, q], vi, wi, radius[i], n, ct.mu_roll)
        v_b[i], w_b[i] = vi, wi
    # 3. Jacobi sweeps, ping-pong between the (v_a, w_a) and (v_b, w_b) buffers
    for k in ti.static(range(iterations)):
        if ti.static(k % 2 == 0):
            for i in range(x.shape[0]):
                sweep_ball(i, contact, h, v_inelastic, radius, mass, plane_p, plane_n, terrain, heights, terrain_cells,
                           surface_table, status, x,
                           x_free, neighbours, n_neighbours, lam, lam_plane, v_b, w_b, v_a, w_a)
        else:
            for i in range(x.shape[0]):
                sweep_ball(i, contact, h, v_inelastic, radius, mass, plane_p, plane_n, terrain, heights, terrain_cells,
                           surface_table, status, x,
                           x_free, neighbours, n_neighbours, lam, lam_plane, v_a, w_a, v_b, w_b)
    # 4. positions, projections, status, rest; then whether the lists stay valid
    for i in range(x.shape[0]):
        st = status[i]
        v_final, w_final = v_a[i], w_a[i]
        if ti.static(iterations % 2 == 0):
            v_final, w_final = v_b[i], w_b[i]
        x1 = x[i]
        if st != OUT_OF_BOUNDS:
            xi, ri = x[i], radius[i]
            x1 = x_free[i] + h * (v_final - v[i])
            touching = 0
            for p in range(plane_p.shape[0]):
                x1 = plane_position(xi, x_free[i], x1, v[i], v_final, ri, plane_p[p], plane_n[p], contact.k_p, h)
                if (x1 - plane_p[p]).dot(plane_n[p]) - ri < 0.01 * ri:
                    touching = 1
            if terrain.on != 0:
                pt, nt = surface(heights, terrain, x_free[i])
                x1 = plane_position(xi, x_free[i], x1, v[i], v_final, ri, pt, nt, contact.k_p, h)
                x1 = terrain_position(xi, x1, pt, nt, ri, heights, terrain)
                if (x1 - pt).dot(nt) - ri < 0.01 * ri:
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
            if st == AT_REST and (v_final.norm() > 0.0 or w_final.norm() > 0.0):
                st = FLYING  # woken by an impulse
            if st != AT_REST:
                st, rest_time[i] = rest_update(touching, v_final, w_final, ri, rest_time[i], h, v_rest, t_rest)
                if st == AT_REST:
                    v_final, w_final = vec3(0.0), vec3(0.0)
                    x1 = xi
            if terrain.on != 0 and outside(heights, terrain, x1):
                st = OUT_OF_BOUNDS
                v_final, w_final = vec3(0.0), vec3(0.0)
            status[i] = st
        x_free[i] = x1
        v[i], w[i] = v_final, w_final
        if (x1 - x_at_build[i]).norm() + 2.0 * h * v_final.norm() > half_skin:
            flag[0] = 1
