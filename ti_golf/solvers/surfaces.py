"""A ball's contacts with the planes and the terrain in a collision step (report Appendix B).

Each ball meets the planes, then the plane of the terrain patch under its free-flight end point,
in turn (:func:`surface_impulses`); a resting impulse on each is kept from step to step. A ball
whose clearance (:func:`surface_clearance`) shows it cannot reach any of them within the step
skips them, which changes no result.

The impulses are kept in a row per ball that the neighbour lists' build finds within reach of a
plane or the terrain, as it lists the ball pairs (:func:`list_surfaces`, with the same skin): a
ball more than that from every surface cannot touch one before the lists are rebuilt, and keeps no
row. In a pile most balls touch no surface, and a row for every ball (the five planes of a bin:
80 bytes a ball with the friction impulses of the Gauss–Seidel sweeps) was the largest table of a
pile after the pair tables. Each rebuild carries the rows of the balls that keep one
(:func:`carry_surfaces`).
"""

import taichi as ti

from ti_golf.physics.aero import V, coefficients, column, rates
from ti_golf.physics.contact import (
    CENTRE_FRICTION,
    centre_friction,
    clamp_friction,
    plane_jolt,
    spin_jolt,
    surface_impulse,
    warm_impulse,
)
from ti_golf.physics.kernels import lane_state
from ti_golf.physics.terrain import (
    surface,
    surface_contact,
    terrain_clearance,
)
from ti_golf.physics.types import (
    ModelArrays,
    TerrainParams,
    int_array,
    is_f64,
    kernel,
    of_ball,
    vec3_array,
    vec4f,
    vec4f_table,
    zero3,
)
from ti_golf.solvers.phases import Phase
from ti_golf.solvers.sequential import surface_step
from ti_golf.solvers.sort import bucket_starts
from ti_golf.solvers.surface_reach import near_a_surface, surface_row

LAMBDA = 0
"""The component of a contact's (λ, F) in ``NeighbourLists.surface_impulse`` that holds λ."""
FAR = 1e30  # the surface clearance of a ball when there are no planes and no terrain (see surface_clearance)
NEAR = -1.0  # the surface clearance of a ball resting on a plane or the terrain: it always visits them


@ti.func
def surface_clearance(
    i,
    x_free_i,
    with_terrain: ti.template(),
    terrain: ti.template(),
    model: ti.template(),
    lists: ti.template(),
    state: ti.template(),
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
    row = surface_row(lists.surface_start, i)
    for p in range(model.plane_n.shape[0]):
        c = ti.min(c, (state.x[i] - model.plane_p[p]).dot(model.plane_n[p]) - of_ball(model.radius, i))
        if row >= 0 and lists.surface_impulse[row, p][LAMBDA] > 0.0:
            c = NEAR
    if ti.static(with_terrain):
        if row >= 0 and lists.surface_impulse[row, model.plane_n.shape[0]][LAMBDA] > 0.0:
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
def surface_impulses(i, warm: ti.template(), vi, wi, h, v_inelastic, s: ti.template(), phase=Phase.JACOBI):
    """Ball i's contacts (``s``: the step's :class:`.step.Step`) with the planes, then the terrain (the
    plane of the patch under its free-flight end point; its resting impulse is kept in the
    column after the planes' in the ball's row of ``surface_impulse``, in f32: only the ball
    reads and writes its own λ, so nothing can disagree about it, and the next sweep or step
    corrects what the rounding left, 2^-24 of the impulse; a ball without a row touches none:
    see :func:`list_surfaces`), applied in turn to (vi, wi): the warm start (``warm``) or a
    sweep, Jacobi (``Phase.JACOBI``, :func:`ti_golf.physics.contact.surface_impulse`) or
    Gauss–Seidel (``phase``: that of :func:`.sequential.surface_step`). A sweep skips them when
    the ball is too far from all of them (``clear[i]``, see :func:`surface_clearance`) to touch
    one within the step at its speed, and marks the ball ``NEAR`` once it rests on one (that
    resting impulse must be visited in later sweeps, to be given back). Returns (v, ω)."""
    contact, terrain, model, lists, state, scratch = ti.static(
        (s.contact, s.terrain, s.model, s.lists, s.state, s.scratch)
    )
    r = of_ball(model.radius, i)
    row = surface_row(lists.surface_start, i)
    far = False
    if ti.static(warm):
        far = row < 0  # (no resting impulse to apply)
    else:
        far = beyond_reach(scratch.clear[i], r, h * h * vi.norm_sqr())
    n_planes = model.plane_n.shape[0]
    if far:
        n_planes = 0
    for p in range(n_planes):
        n = model.plane_n[p]
        gap = (state.x[i] - model.plane_p[p]).dot(n) - r
        v_in = surface_inelastic_speed(i, n, vi, wi, v_inelastic, h, s, warm)
        vi, wi = surface_contact_step(
            i, row, p, n, gap, vi, wi, r, contact=contact, h=h, v_inelastic=v_in, s=s, warm=warm, phase=phase
        )
    if ti.static(s.kinds.gauss_seidel and not warm):
        if phase == Phase.BOUNCE and row >= 0 and n_planes > 1:
            vi, wi = joint_plane_bounce(i, row, vi, wi, r, h, v_inelastic, s)
    if ti.static(s.kinds.terrain):
        if not far:
            q = model.plane_n.shape[0]
            if ti.static(not warm) or lists.surface_impulse[row, q][LAMBDA] > 0.0:  # (warm: row ≥ 0)
                pt, n = surface(model.heights, terrain, scratch.x_free[i])
                ct = surface_contact(
                    contact, model.surface_table, model.terrain_cells, model.heights, terrain, scratch.x_free[i]
                )
                gap = (state.x[i] - pt).dot(n) - r
                v_in = surface_inelastic_speed(i, n, vi, wi, v_inelastic, h, s, warm)
                vi, wi = surface_contact_step(
                    i, row, q, n, gap, vi, wi, r, contact=ct, h=h, v_inelastic=v_in, s=s, warm=warm, phase=phase
                )
    return vi, wi


PLANE_ROUNDS = 16
"""The most rounds of :func:`joint_plane_bounce` over a ball's impact planes after the restitution
pass's first (4^-16 of the error left in a V of planes at ±30° or ±60°)."""
COUPLED = 1e-6
"""Planes whose unit normals' dot product is no larger than this in size are orthogonal (a bin's
floor and walls): met in turn, one's normal impulse leaves the other's normal velocity as it was,
so the restitution pass already leaves each at its rebound, and :func:`joint_plane_bounce` adds
no rounds."""
ROUNDS_TOLERANCE = 1e-9
"""A round of :func:`joint_plane_bounce` that changes the ball's velocity by less than this share
of it ends the rounds."""


@ti.func
def plane_impact(i, row, p, vi, wi, v_inelastic, h, s: ti.template()):
    """Whether ball i (its row ``row`` of surface impulses) meets plane p as an impact in the
    restitution pass (:func:`.sequential.pair_step`'s ``BOUNCE``): pressed (λ > 0), approaching it
    before the step's contacts faster than its inelastic speed (:func:`surface_inelastic_speed`),
    and not turf (whose frame follows the ball's velocity)."""
    contact, model, lists, scratch = ti.static((s.contact, s.model, s.lists, s.scratch))
    n = model.plane_n[p]
    hit = lists.surface_impulse[row, p][LAMBDA] > 0.0 and contact.e > 0.0
    if ti.static(s.kinds.turf):
        hit = hit and contact.turf == 0
    if hit:
        hit = scratch.v_free[i].dot(n) < -surface_inelastic_speed(i, n, vi, wi, v_inelastic, h, s, False)
    return hit


@ti.func
def joint_plane_bounce(i, row, vi, wi, r, h, v_inelastic, s: ti.template()):
    """Ball i's restitution against the planes it meets as impacts at once (:func:`plane_impact`),
    solved jointly: after the restitution pass has met each plane once (Newton's −e·v_n0, in turn),
    the impact planes are met again, up to ``PLANE_ROUNDS`` rounds, each again toward its own
    −e·v_n0 from the ball's velocity now (Gauss–Seidel over the ball's impact planes alone: planes
    do not move, so nothing else changes). Met once each, in turn, a later plane's rebound undid
    part of an earlier one: a ball dropped into a V of planes at ±30° (e = 1) left sideways with
    1.4 to 1.55 times its energy, at ±60° with a third of it. Jointly the ball leaves each plane at
    e times its approach, straight back out of a symmetric V, which is Poisson's restitution too
    when the sweeps stop it in both (λ_k = e times each compression), to the rounds' convergence
    (geometric: 4^-rounds at ±30° and ±60°). A ball meeting one plane, or planes whose normals are
    orthogonal (``COUPLED``: a bin's floor and walls), or resting on them, is left as the single
    pass made it. Unlike Poisson's e·λ, a plane's rebound never gives back the load that the balls
    around it pressed into the plane within the step (in the narrow pit's pour, bouncing planes by
    Poisson gave back 18 times the energy of Newton's rebound at contacts whose λ was more than
    twice the ball's own approach)."""
    contact, model, state = ti.static((s.contact, s.model, s.state))
    hits = 0
    for p in range(model.plane_n.shape[0]):
        if plane_impact(i, row, p, vi, wi, v_inelastic, h, s):
            hits += 1
    coupled = False
    if hits > 1:  # (rare: a ball meeting two planes at once)
        for p in range(model.plane_n.shape[0]):
            for q in range(p + 1, model.plane_n.shape[0]):
                if ti.abs(model.plane_n[p].dot(model.plane_n[q])) > COUPLED:
                    if plane_impact(i, row, p, vi, wi, v_inelastic, h, s):
                        if plane_impact(i, row, q, vi, wi, v_inelastic, h, s):
                            coupled = True
    if coupled:
        for _ in range(PLANE_ROUNDS):
            v_was = vi
            for p in range(model.plane_n.shape[0]):
                if plane_impact(i, row, p, vi, wi, v_inelastic, h, s):
                    n = model.plane_n[p]
                    gap = (state.x[i] - model.plane_p[p]).dot(n) - r
                    v_in = surface_inelastic_speed(i, n, vi, wi, v_inelastic, h, s, False)
                    vi, wi = surface_contact_step(
                        i,
                        row,
                        p,
                        n,
                        gap,
                        vi,
                        wi,
                        r,
                        contact=contact,
                        h=h,
                        v_inelastic=v_in,
                        s=s,
                        warm=False,
                        phase=Phase.BOUNCE,
                        resist=0,
                    )
            if (vi - v_was).norm_sqr() <= ROUNDS_TOLERANCE**2 * vi.norm_sqr():
                break
    return vi, wi


@ti.func
def surface_inelastic_speed(i, n, vi, wi, v_inelastic, h, s: ti.template(), warm: ti.template()):
    """The inelastic speed [m/s] of ball i against a surface of unit normal ``n``: ``v_inelastic``
    plus twice what the air pushes the ball into it in the step (:func:`air_push`). The push is
    worked out only for a ball approaching faster than ``v_inelastic`` (at the end of its free
    flight or now, ``vi``): a slower approach is a resting contact whatever the push, and a warm
    start reads no inelastic speed."""
    v_in = v_inelastic
    if ti.static(not warm):
        if ti.min(s.scratch.v_free[i].dot(n), vi.dot(n)) < -v_inelastic:
            v_in += 2.0 * ti.max(-air_push(i, wi, h, s).dot(n), 0.0)
    return v_in


@ti.func
def air_push(i, w, h, s: ti.template()):
    """What the air adds to ball i's velocity in a step of ``h`` [s] [m/s]: h times its drag and
    Magnus acceleration at the end of its free flight (``scratch.x_free``, ``scratch.v_free``),
    spinning at ``w`` [rad/s]. A surface's inelastic speed grows by twice what it pushes the ball
    into the surface, as :func:`ti_golf.physics.kernels.advance` does for a ball alone: the
    report's Magnus law presses a ball rolling with topspin into the ground, and each step's
    approach would otherwise pass for an impact and bounce."""
    air, model, scratch = ti.static((s.air, s.model, s.scratch))
    coef = coefficients(air, s.kinds, ti.Vector([of_ball(model.radius, i)]), ti.Vector([of_ball(model.mass, i)]))
    dS = rates(lane_state(scratch.x_free[i], scratch.v_free[i], w), coef, air, s.kinds, s.params.gravity)
    return h * (column(dS, V, 0) - s.params.gravity)


@ti.func
def surface_contact_step(
    i, row, column, n, gap, vi, wi, r, contact, h, v_inelastic, s: ti.template(), warm: ti.template(), phase, resist=1
):
    """Ball i's contact with one surface of normal ``n`` and surface gap ``gap`` [m], whose resting
    impulse (and, for the Gauss–Seidel sweeps, friction impulse) per unit mass is kept in
    ``column`` of the ball's ``row`` of ``lists.surface_impulse``: see :func:`surface_impulses`. A
    ball without a row (``row`` −1) meets a surface that the lists' build found out of its reach
    (:func:`list_surfaces`), as a ball knocked more than the skin in one step does: from no
    carried impulse, and with nothing kept from one sweep to the next; the lists are then rebuilt
    before the next step (``s``: the step's :class:`.step.Step`; ``contact``: the surface's
    contact parameters). Returns (v, ω)."""
    lists, scratch, kinds = ti.static((s.lists, s.scratch, s.kinds))
    lam0, F0 = 0.0, zero3()
    if row >= 0:  # f32 in the table (see surface_impulses)
        kept = lists.surface_impulse[row, column]
        lam0 = ti.cast(kept[LAMBDA], float)
        F0 = ti.cast(ti.Vector([kept[1], kept[2], kept[3]]), float)
    if ti.static(warm):
        if lam0 > 0.0:
            if ti.static(kinds.gauss_seidel):  # the normal and friction impulses carried from the last step
                P = lam0 * n + clamp_friction(F0, n, contact.mu * lam0)
                vi += P
                if ti.static(kinds.friction != CENTRE_FRICTION):
                    wi += spin_jolt(P, n, r, 1.0)
            else:
                P = zero3()
                if ti.static(kinds.friction == CENTRE_FRICTION):
                    P = lam0 * n + centre_friction(n, vi, 1.0, contact.mu * lam0)
                else:
                    P = warm_impulse(
                        n, vi, wi, r, v_b=zero3(), w_b=zero3(), r_b=0.0, m_eff=1.0, lam=lam0, mu=contact.mu
                    )
                vi, wi = plane_jolt(P, lam0, vi, wi, r, n, contact.mu_roll, kinds.friction)
    elif gap + h * ti.min(vi.dot(n), 0.0) < 0.0 or lam0 > 0.0:  # else no impulse (pair_impulse)
        lam_p = 0.0
        if row < 0:  # an impulse the lists did not foresee (see list_surfaces): rebuild them
            scratch.flag[0] = 1
        if ti.static(kinds.gauss_seidel):  # (phase: that of the sweep, else Phase.JACOBI)
            F = F0
            if phase == Phase.FIRST:  # what the warm start applied
                F = clamp_friction(F, n, contact.mu * lam0)
            vi, wi, lam_p, F = surface_step(
                phase,
                n,
                gap,
                scratch.v_free[i],
                vi,
                w=wi,
                radius=r,
                lam=lam0,
                F=F,
                contact=contact,
                v_inelastic=v_inelastic,
                h=h,
                kinds=kinds,
                resist=resist,
            )
            if row >= 0:
                lists.surface_impulse[row, column] = ti.Vector([lam_p, F[0], F[1], F[2]], dt=ti.f32)
        else:
            P, lam_p, _, n_eff = surface_impulse(
                n, gap, vi, wi, r, lam=lam0, contact=contact, v_inelastic=v_inelastic, h=h, kinds=kinds
            )
            if P.dot(n) != 0.0:
                vi, wi = plane_jolt(P, lam_p - lam0, vi, wi, r, n_eff, contact.mu_roll, kinds.friction)
            if row >= 0:
                lists.surface_impulse[row, column][LAMBDA] = ti.cast(lam_p, ti.f32)
        if lam_p > 0.0:
            scratch.clear[i] = ti.cast(NEAR, ti.f32)
    return vi, wi


@ti.func
def old_row(i, carry, old_start: ti.template(), reorder, old_index: ti.template()):
    """Ball i's row in the old tables of surface impulses (see :func:`carry_surfaces`), or −1."""
    old = -1
    if carry != 0:
        o = i
        if reorder != 0:
            o = old_index[i]
        old = surface_row(old_start, o)
    return old


@kernel
def list_surfaces(
    with_terrain: ti.template(),
    terrain: TerrainParams,
    model: ModelArrays,
    x: vec3_array,
    reach: float,
    carry: ti.i32,
    old_start: int_array,
    old_impulse: vec4f_table,
    reorder: ti.i32,
    old_index: int_array,
    start: int_array,
    chunk_start: int_array,
) -> ti.i32:
    """Give a row of surface impulses to each ball at ``x`` [m] that may touch a plane or the
    terrain before the next rebuild of the lists (:func:`near_a_surface`) or, with ``carry``, still
    holds a resting impulse in its old row (see :func:`carry_surfaces`: a Jacobi sweep gives an
    impulse back only as the ball moves away, and the warm start applies it again); ball i's row is
    ``start[i]`` when ``start[i + 1] > start[i]`` (see :func:`surface_row`), the rows numbered in
    ball order by the grid's chunked scan (``chunk_start``: its scratch, see
    ``links.pair_starts``). Returns the rows in all. ``with_terrain``: whether the scene has a
    terrain (``terrain.on``), a compile-time choice.

    ``reach`` [m] bounds how far a ball moves before the next rebuild: the skin between rebuilds
    with the Gauss–Seidel sweeps (a ball without a row that moves farther and may reach a surface
    forces a rebuild: ``stale.surface_unforeseen``), half of it with the Jacobi sweeps
    (``links.moved_past``), or in the step right after the build h·|v|, where |v| may be up to the
    fastest ball's speed for a ball that it knocks on; the caller passes max(skin, 2h·v_max), as
    ball pairs are listed within the skin (``grid.pair_reach``). A ball knocked farther within one
    step still meets the surface (see :func:`surface_contact_step`), and the lists are rebuilt
    before the next step."""
    for i in range(x.shape[0]):
        listed = near_a_surface(i, x[i], reach, with_terrain, terrain, model)
        old = old_row(i, carry, old_start, reorder, old_index)
        if old >= 0 and not listed:
            for c in range(old_impulse.shape[1]):
                if old_impulse[old, c][LAMBDA] > 0.0:
                    listed = True
                    break
        start[i + 1] = 0
        if listed:
            start[i + 1] = 1
    bucket_starts(start, chunk_start)
    return start[start.shape[0] - 1]


@kernel
def carry_surfaces(
    carry: ti.i32,
    old_start: int_array,
    old_impulse: vec4f_table,
    reorder: ti.i32,
    old_index: int_array,
    start: int_array,
    impulse: vec4f_table,
):
    """Fill each ball's new row of surface impulses (``start``, ``impulse``; see
    :func:`list_surfaces`) with its old row's (``old_start``, ``old_impulse``, of as many columns)
    when ``carry`` and it kept one, else with zeros. With ``reorder`` the balls were stored in
    another order since the old rows were made: ball i was ball ``old_index[i]`` (as
    ``links.link_and_carry`` reads it)."""
    for i in range(start.shape[0] - 1):
        row = surface_row(start, i)
        if row >= 0:
            old = old_row(i, carry, old_start, reorder, old_index)
            for c in range(impulse.shape[1]):
                kept = vec4f(0.0)
                if old >= 0:
                    kept = old_impulse[old, c]
                impulse[row, c] = kept


@kernel
def every_ball_a_row(start: int_array):
    """Give every ball a row of surface impulses, its own index (the serial steps, whose lists
    are rebuilt inside the kernel: see ``collide.collision_step``)."""
    for i in range(start.shape[0]):
        start[i] = i
