"""A ball's contacts with the planes and the terrain in a collision step (report Appendix B).

Each ball meets the planes, then the plane of the terrain patch under its free-flight end point,
in turn (:func:`surface_impulses`); a resting impulse on each is kept from step to step. A ball
whose clearance (:func:`surface_clearance`) shows it cannot reach any of them within the step
skips them, which changes no result.
"""

import taichi as ti

from ti_golf.physics.contact import (
    CENTRE_FRICTION,
    FIRST,
    GAUSS_SEIDEL,
    centre_friction,
    clamp_friction,
    plane_jolt,
    spin_jolt,
    surface_impulse,
    surface_step,
    warm_impulse,
)
from ti_golf.physics.terrain import (
    surface,
    surface_contact,
    terrain_clearance,
)
from ti_golf.physics.types import (
    is_f64,
    of_ball,
    zero3,
)

FAR = 1e30  # the surface clearance of a ball when there are no planes and no terrain (see surface_clearance)
NEAR = -1.0  # the surface clearance of a ball resting on a plane or the terrain: it always visits them


@ti.func
def surface_clearance(
    i, x_free_i, terrain: ti.template(), model: ti.template(), lists: ti.template(), state: ti.template()
):
    """The least surface gap [m] of ball i to the planes at the start of the step and, with a
    terrain, a lower bound on its gap to the terrain less its free-flight displacement (see
    :func:`terrain.terrain_clearance`; the free-flight end point ``x_free_i``); ``FAR`` with
    neither, ``NEAR`` when the ball keeps a resting impulse on one of them. A plane's gap at any
    point y is at least the plane clearance less |y − x_i| (the normals are unit vectors), a
    terrain patch's at least the terrain clearance less twice that (the patch is taken under a
    moved point too). This lets the sweeps and :func:`finish` skip the planes and the terrain of a
    ball that cannot reach any of them (most balls of a pile) without changing any result."""
    c = FAR
    for p in range(model.plane_n.shape[0]):
        c = ti.min(c, (state.x[i] - model.plane_p[p]).dot(model.plane_n[p]) - of_ball(model.radius, i))
        if lists.lam_plane[i, p] > 0.0:
            c = NEAR
    if terrain.on != 0:
        if lists.lam_plane[i, model.plane_n.shape[0]] > 0.0:
            c = NEAR
        elif c != NEAR:
            c = ti.min(c, terrain_clearance(model.heights, terrain, state.x[i], x_free_i, of_ball(model.radius, i)))
    return c


@ti.func
def rounded_down(c):
    """``c`` [m] as an f32 no larger than ``c``, for the ``clear`` array (f32 whatever the
    precision: 4 bytes per ball less in f64): a clearance may only err on the near side, where
    it makes the ball visit planes that it cannot reach (no impulse, no change). In f64 the value
    is first lowered by 2^-23·|c|, twice what rounding to f32 can add."""
    low = c
    if ti.static(is_f64()):
        low = c - ti.abs(c) * 2.0**-23
    return ti.cast(low, ti.f32)


@ti.func
def beyond_reach(clear, r, reach_sqr):
    """Whether a ball of radius ``r`` with surface clearance ``clear`` (:func:`surface_clearance`)
    stays more than 2 % of a radius from every plane and the terrain while its gaps shrink by at
    most sqrt(``reach_sqr``) [m]: it can neither touch one nor count as touching one (below 1 %),
    with room for round-off."""
    c = clear - 0.02 * r
    return c > 0.0 and c * c > reach_sqr


@ti.func
def surface_impulses(
    i,
    warm: ti.template(),
    vi,
    wi,
    contact: ti.template(),
    terrain: ti.template(),
    h,
    v_inelastic,
    model: ti.template(),
    lists: ti.template(),
    state: ti.template(),
    scratch: ti.template(),
    phase=-1,
):
    """Ball i's contacts with the planes, then the terrain (the plane of the patch under its
    free-flight end point; its resting impulse is kept in the column after the planes' in
    ``lam_plane``, in f32: 4 bytes instead of 8 for every ball and plane, though most balls touch
    none; only the ball reads and writes its own λ, so nothing can disagree about it, and the next
    sweep or step corrects what the rounding left, 2^-24 of the impulse), applied in turn to
    (vi, wi): the warm start (``warm``) or a sweep, Jacobi (``phase`` −1, :func:`.contact.surface_impulse`)
    or Gauss–Seidel (``phase``: that of :func:`.contact.surface_step`). A sweep skips
    them when the ball is too far from all of them (``clear[i]``, see :func:`surface_clearance`)
    to touch one within the step at its speed, and marks the ball ``NEAR`` once it rests on one
    (that resting impulse must be visited in later sweeps, to be given back). Returns (v, ω)."""
    r = of_ball(model.radius, i)
    far = False
    if ti.static(not warm):
        far = beyond_reach(scratch.clear[i], r, h * h * vi.norm_sqr())
    n_planes = model.plane_n.shape[0]
    if far:
        n_planes = 0
    for p in range(n_planes):
        n = model.plane_n[p]
        gap = (state.x[i] - model.plane_p[p]).dot(n) - r
        vi, wi = surface_contact_step(i, p, warm, n, gap, vi, wi, r, contact, h, v_inelastic, lists, scratch, phase)
    if terrain.on != 0 and not far:
        q = model.plane_n.shape[0]
        if ti.static(not warm) or lists.lam_plane[i, q] > 0.0:
            pt, n = surface(model.heights, terrain, scratch.x_free[i])
            ct = surface_contact(
                contact, model.surface_table, model.terrain_cells, model.heights, terrain, scratch.x_free[i]
            )
            gap = (state.x[i] - pt).dot(n) - r
            vi, wi = surface_contact_step(i, q, warm, n, gap, vi, wi, r, ct, h, v_inelastic, lists, scratch, phase)
    return vi, wi


@ti.func
def surface_contact_step(
    i,
    column,
    warm: ti.template(),
    n,
    gap,
    vi,
    wi,
    r,
    contact,
    h,
    v_inelastic,
    lists: ti.template(),
    scratch: ti.template(),
    phase,
):
    """Ball i's contact with one surface of normal ``n`` and surface gap ``gap`` [m], whose resting
    impulse (and, for the Gauss–Seidel sweeps, friction impulse) per unit mass is kept in
    ``column`` of ``lists.lam_plane`` (and ``lists.friction_plane``): see :func:`surface_impulses`.
    Returns (v, ω)."""
    lam0 = ti.cast(lists.lam_plane[i, column], float)  # f32 in the table (see surface_impulses)
    if ti.static(warm):
        if lam0 > 0.0:
            if contact.solver == GAUSS_SEIDEL:  # the normal and friction impulses carried from the last step
                P = lam0 * n + clamp_friction(ti.cast(lists.friction_plane[i, column], float), n, contact.mu * lam0)
                vi += P
                if contact.friction != CENTRE_FRICTION:
                    wi += spin_jolt(P, n, r, 1.0)
            else:
                P = zero3()
                if contact.friction == CENTRE_FRICTION:
                    P = lam0 * n + centre_friction(n, vi, 1.0, contact.mu * lam0)
                else:
                    P = warm_impulse(n, vi, wi, r, zero3(), zero3(), 0.0, 1.0, lam0, contact.mu)
                vi, wi = plane_jolt(P, lam0, vi, wi, r, n, contact.mu_roll, contact.friction)
    elif gap + h * ti.min(vi.dot(n), 0.0) < 0.0 or lam0 > 0.0:  # else no impulse (pair_impulse)
        lam_p = 0.0
        if phase >= 0:
            F = ti.cast(lists.friction_plane[i, column], float)
            if phase == FIRST:  # what the warm start applied
                F = clamp_friction(F, n, contact.mu * lam0)
            vi, wi, lam_p, F = surface_step(
                phase, n, gap, scratch.v_free[i], vi, wi, r, lam0, F, contact, v_inelastic, h
            )
            lists.friction_plane[i, column] = ti.cast(F, ti.f32)
        else:
            P, lam_p, _, n_eff = surface_impulse(n, gap, vi, wi, r, lam0, contact, v_inelastic, h)
            if P.dot(n) != 0.0:
                vi, wi = plane_jolt(P, lam_p - lam0, vi, wi, r, n_eff, contact.mu_roll, contact.friction)
        lists.lam_plane[i, column] = ti.cast(lam_p, ti.f32)
        if lam_p > 0.0:
            scratch.clear[i] = ti.cast(NEAR, ti.f32)
    return vi, wi
