"""The Gauss–Seidel update of one contact (sequential impulses, ``contact.solver =
"gauss_seidel"``), in the phase of the step that :class:`.phases.Phase` names: the equations of a
contact between two bodies (:func:`pair_step`) or of a ball on a static surface
(:func:`surface_step`), and the update of a listed ball pair in place on the step's arrays
(:func:`sweep_pair`) and its position projection (:func:`project_pair`), which both layouts of
the sweeps make (the grid columns of :mod:`.colour`, the contact colours of
:mod:`.contact_colour`). The Jacobi sweeps' impulse is the report's,
:func:`ti_golf.physics.contact.pair_impulse`."""

import taichi as ti

from ti_golf.physics.contact import (
    CENTRE_FRICTION,
    centre_friction,
    clamp_friction,
    friction_impulse,
    impact_frame,
    inverse_inertia,
    kinetic_change,
    pivot_impulse,
    pivot_resistance,
    rolling_resistance,
    spin_jolt,
)
from ti_golf.physics.types import INV, of_ball, zero3
from ti_golf.scene.schema import AT_REST, OUT_OF_BOUNDS
from ti_golf.solvers.pairs import QUIET, kept_gap, kept_normal, skip_pair
from ti_golf.solvers.phases import Phase


@ti.func
def body(v, w, r, inv_m):
    """A body of a contact, as :func:`pair_step` reads it: its velocity ``v`` [m/s], spin ``w``
    [rad/s], radius ``r`` [m] and inverse mass ``inv_m`` [1/kg] (0 when it stands firm; r = 0 and
    1/m = 0 for a static surface, :func:`static_surface`)."""
    return ti.Struct(v=v, w=w, r=r, inv_m=inv_m)


@ti.func
def static_surface():
    """The :func:`body` of a static surface (a plane, the terrain's patch): at rest, no radius, no
    inverse mass."""
    return body(zero3(), zero3(), 0.0, 0.0)


LAM_ROUNDING = 1e-6
"""How far the restitution pass's Poisson bound (1 + e)·λ is loosened for the rounding of λ, which
the sweeps carry in f32 (2^-24): a binary impact, where it equals Newton's −e·v_n0, keeps that."""


@ti.func
def pair_step(
    phase,
    n,
    gap,
    v_n0,
    a,
    b,
    lam,
    F,
    e,
    mu,
    v_inelastic,
    h,
    friction: ti.template() = 0,
    poisson: ti.template() = False,
):
    """One Gauss–Seidel update of a contact (``contact.solver = "gauss_seidel"``): (the impulse P
    [N·s] on body a, −P on b; the contact's new accumulated normal impulse λ [N·s] and friction
    impulse F [N·s] on a). ``n``: unit normal from b to a; ``gap``: surface gap [m] at the start
    of the step; ``v_n0``: the normal velocity [m/s] before the step's contacts (after the free
    flight); ``a``, ``b``: the bodies (:func:`body`; b a plane: :func:`static_surface`); ``lam``,
    ``F``: what the contact has applied so far; ``e``, ``mu``: restitution and friction
    coefficient; ``v_inelastic`` [m/s]: see ``BOUNCE``; ``h`` [s]: the time step.

    ``SOLVE``: sequential impulses toward a normal velocity v_n ≥ −max(gap, 0)/h, the pair
    closing its gap within the step but not overlapping more (what overlaps is projected out
    after the step, B.18). What is clamped is the accumulated λ ≥ 0, so a warm start that pushed
    too hard is taken back. Every contact is inelastic here. Coulomb friction (B.15): the
    accumulated F, toward stopping the slip at the contact point (solid spheres, see
    :func:`ti_golf.physics.contact.friction_impulse`), is clamped to |F| ≤ μ·λ.

    ``BOUNCE``: restitution, once per step after the sweeps, for a contact that approached faster
    than ``v_inelastic`` and is pressed (λ > 0): toward v_n = −e·v_n0 (B.9), again through the
    clamped λ, and the friction again, bounded by the larger μ·λ. Slower approaches are resting contacts and never bounce: a resting contact gains no
    energy. A plastic pair (e = 0) still apart at the step's start is left as the sweeps made it,
    closing its gap exactly within the step (the next step stops it, touching): v_n = 0 would stop
    it short, up to h·|v_n0| apart. With e > 0 such a pair bounces from where it is, up to
    h·|v_n0| before touching, as with the speculative contacts of other engines: moving it to the
    contact first would take speed from the bounce. ``friction`` = :data:`ti_golf.physics.contact.CENTRE_FRICTION` (a
    compile-time value): the friction stops the centres' tangential velocity instead
    (:func:`ti_golf.physics.contact.centre_friction`).

    ``poisson`` (a compile-time value; two balls): an impact (e > 0, approaching faster than
    ``v_inelastic``, meeting within the step: gap + h·v_n0 < 0) is stopped by the sweeps (v_n ≥ 0:
    its compression λ), and ``BOUNCE`` gives back at most e·λ more (Poisson's restitution) as
    well as at most Newton's −e·v_n0. For one impact the two agree; for a ball meeting several at
    once, Newton's rebounds met in turn made energy (a ball into two touching balls at ±30°, e = 1:
    29 % more than it brought), while Poisson's leave at most the inelastic impact's energy plus e²
    of what the compression took (to the sweeps' convergence)."""
    v_a, w_a, r_a, inv_m_a = a.v, a.w, a.r, a.inv_m
    v_b, w_b, r_b, inv_m_b = b.v, b.w, b.r, b.inv_m
    m_eff = 1.0 / (inv_m_a + inv_m_b)
    v_n = (v_a - v_b).dot(n)
    target = -ti.max(gap, 0.0) / h
    impact = False
    if ti.static(poisson):  # (an approach that meets within the step, gap + h·v_n0 < 0)
        impact = v_n0 < -v_inelastic and e > 0.0 and gap + h * v_n0 < 0.0
    if impact:
        target = 0.0  # the sweeps stop an impact (its compression); the bounce gives it back
    if phase == Phase.BOUNCE:
        target = v_n  # no change
        if v_n0 < -v_inelastic and lam > 0.0 and (e > 0.0 or gap <= 0.0):
            target = -e * v_n0
    lam_new = ti.max(lam + m_eff * (target - v_n), 0.0)
    if phase == Phase.BOUNCE and impact and lam > 0.0:  # Poisson: at most e times the compression back
        lam_new = ti.min(lam_new, (1.0 + e) * lam * (1.0 + LAM_ROUNDING))
    P = (lam_new - lam) * n
    F_new = F
    # the friction, toward stopping the slip, in the sweeps; in the bounce only when it pressed
    # harder: its bound μ·λ then takes in the restitution's impulse, μ·(1 + e)·m·|v_n0| in all (B.15)
    if phase != Phase.BOUNCE or lam_new > lam:
        F_new = zero3()  # |F| ≤ μ·λ: a contact that presses no more holds no friction
        if lam_new > 0.0:
            if ti.static(friction == CENTRE_FRICTION):
                F_new = F + centre_friction(n, v_a - v_b, m_eff, 1e30)
            else:
                F_new = F + friction_impulse(n, v_a, w_a, r_a, v_b, w_b, r_b, m_eff=m_eff, bound=1e30)
            F_new = clamp_friction(F_new, n, mu * lam_new)
        P += F_new - F
    return P, lam_new, F_new


@ti.func
def surface_step(phase, n, gap, v0, v, w, radius, lam, F, contact, v_inelastic, h, kinds: ti.template(), resist=1):
    """:func:`pair_step` of a ball against a static surface (a plane, or the terrain's patch) with
    normal n̂, per unit mass [m/s] (``v0``: the ball's velocity before the step's contacts; ``F``:
    the friction impulse applied so far), with
    ``contact``'s restitution, or with ``contact.turf`` in the turf frame of :func:`ti_golf.physics.contact.turf_impact`
    (:func:`ti_golf.physics.contact.impact_frame`).
    In the ``BOUNCE`` pass a pressed ball that did not approach faster than ``v_inelastic`` (a
    resting contact, not an impact) also meets rolling resistance and the resistance to spin about
    the normal, bounded by μ_roll·λ (once per step), as :func:`ti_golf.physics.contact.plane_jolt`
    applies them to a resting impulse only: an impact's jolt does not brake the ball's rolling. With the report's friction
    (``kinds.friction``) the spin is left as it is; ``resist`` 0 leaves both out (a ball's later
    restitution rounds over its planes, :func:`.surfaces.joint_plane_bounce`, which revisit only
    impacts). Returns (v, ω, λ, F)."""
    n_eff, e = impact_frame(n, gap, v, lam, contact, v_inelastic, h, kinds)
    ball = body(v, w, radius, 1.0)
    P, lam_new, F_new = pair_step(
        phase,
        n_eff,
        gap,
        v0.dot(n_eff),
        ball,
        static_surface(),
        lam,
        F,
        e=e,
        mu=contact.mu,
        v_inelastic=v_inelastic,
        h=h,
        friction=kinds.friction,
    )
    spin = ti.static(kinds.friction != CENTRE_FRICTION)
    v_new = v + P
    w_new = w
    if ti.static(spin):
        w_new = w + spin_jolt(P, n_eff, radius, 1.0)
    if phase == Phase.BOUNCE and resist and lam_new > 0.0 and v0.dot(n_eff) >= -v_inelastic:  # resting, no impact
        dv, dw = rolling_resistance(v_new, radius, contact.mu_roll, lam_new, n_eff)
        v_new += dv
        if ti.static(spin):
            w_new += dw + pivot_resistance(w_new, radius, contact.mu_roll, lam_new, n_eff)
    return v_new, w_new, lam_new, F_new


@ti.func
def stands_firm(kinds: ti.template(), status_i):
    """Whether a ball with status ``status_i`` stands firm in a step: with the Gauss–Seidel sweeps
    (``kinds.gauss_seidel``), a ball asleep takes no impulse and does not move, and the awake balls
    touching it meet it as they meet a wall, until a moving ball touches it
    (:func:`.pairs.touched_by_moving`)."""
    firm = False
    if ti.static(kinds.gauss_seidel):
        firm = status_i == AT_REST
    return firm


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
def sweep_constants(contact: ti.template(), params: ti.template()):
    """What every pair of a Gauss–Seidel sweep reads of the step, worked out once: the time step
    ``h`` [s], the inelastic speed ``v_inelastic`` [m/s] (:func:`inelastic_speed`) and ``up``, the
    unit vector against gravity (:func:`upward`)."""
    return ti.Struct(h=params.h, v_inelastic=inelastic_speed(contact, params), up=upward(params))


@ti.func
def sweep_pair(i, j, p, phase, xi, a, k, s: ti.template()):
    """One Gauss–Seidel update of pair p, ball i (at ``xi`` [m]; ``a``: its :func:`body`, its
    inverse mass 0 when it stands firm) with ball j, from the current velocities of both balls,
    applied to both at once, with the normal and gap the warm start stored in ``scratch.J``
    (:func:`meet_pair`; ``k``: :func:`sweep_constants`; ``s``: the step's :class:`.step.Step`):
    ball j's velocity and spin are written,
    ball i's returned, as (v_i, ω_i, approached), ``approached`` 1 when the pair approached faster
    than the inelastic speed before the step's contacts (read in ``FIRST`` and ``BOUNCE``). Both
    layouts of the sweeps (:func:`.colour.sweep_ball`, :mod:`.contact_colour`) make this update."""
    lists, state, scratch = ti.static((s.lists, s.state, s.scratch))
    vi, wi, approached = a.v, a.w, 0
    if state.status[j] == OUT_OF_BOUNDS:
        lists.lam[p] = ti.f32(0.0)  # a frozen ball no longer supports anything
    elif not skip_pair(state.status, i, j):
        n = kept_normal(xi, state.x[j], scratch.J[p, INV])
        if n.norm_sqr() > 0.0:
            vi, wi, approached = meet_pair(i, j, p, phase, n, a, k, s)
    return vi, wi, approached


@ti.func
def meet_pair(i, j, p, phase, n, a, k, s: ti.template()):
    """:func:`sweep_pair` of balls i and j whose centres lie apart along the unit normal ``n``
    (from j to i): the update of :func:`pair_step`, in the shock sweep (``SHOCK``) with the lower
    ball standing firm (:func:`shock_masses`) unless that would add energy, the pair's carried
    impulses written back to ``lists``, and in the shock sweep the resistance to pivoting
    (:func:`pivot_pair`). Returns (v_i, ω_i, approached)."""
    contact, model, lists, state, scratch = ti.static((s.contact, s.model, s.lists, s.state, s.scratch))
    vi, wi, ri, inv_mi = a.v, a.w, a.r, a.inv_m
    approached = 0
    rj, inv_mj = of_ball(model.radius, j), 1.0 / of_ball(model.mass, j)
    if stands_firm(s.kinds, state.status[j]):
        inv_mj = 0.0
    F = ti.cast(lists.friction[p], float)
    lam = ti.cast(lists.lam[p], float)
    if phase == Phase.FIRST:  # what the warm start applied (pairs.carried_friction)
        F = clamp_friction(F, n, contact.mu * lam)
    inv_a, inv_b = shock_masses(phase, n, k.up, inv_mi, inv_mj)
    if inv_a + inv_b > 0.0:  # (not both standing firm: a ball asleep, and the shock sweep)
        v_n0 = 0.0  # the approach before the contacts: read where it is used
        if phase == Phase.FIRST or phase == Phase.BOUNCE or scratch.impact[i] != 0:
            v_n0 = (scratch.v_free[i] - scratch.v_free[j]).dot(n)
            if v_n0 < -k.v_inelastic:
                approached = 1
        vj, wj = state.v[j], state.w[j]
        shocked = inv_a + inv_b != inv_mi + inv_mj  # (the lower ball made to stand firm)
        P, lam_new, F_new = zero3(), lam, F
        gap = kept_gap(scratch.J, p)  # (once: its two halves joined)
        for attempt in range(2):
            a_now, b_now = body(vi, wi, ri, inv_a), body(vj, wj, rj, inv_b)
            P, lam_new, F_new = pair_step(
                phase,
                n,
                gap,
                v_n0,
                a_now,
                b_now,
                lam,
                F,
                e=contact.e,
                mu=contact.mu,
                v_inelastic=k.v_inelastic,
                h=k.h,
                poisson=True,
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
            wi = pivot_pair(j, n, body(vi, wi, ri, inv_mi), body(vj, wj, rj, inv_mj), lam_new, s)
    return vi, wi, approached


@ti.func
def shock_masses(phase, n, up, inv_mi, inv_mj):
    """The inverse masses (1/m_i, 1/m_j) [1/kg] with which balls i and j, apart along the unit
    normal ``n`` (from j to i), meet in a sweep of ``phase``: their own, but in the shock sweep
    (``SHOCK``, with gravity: ``up`` not zero) the lower ball stands firm (0)."""
    inv_a, inv_b = inv_mi, inv_mj
    if phase == Phase.SHOCK and up.norm_sqr() > 0.0:  # the lower ball stands firm
        if n.dot(up) > 0.0:
            inv_b = 0.0
        else:
            inv_a = 0.0
    return inv_a, inv_b


@ti.func
def pivot_pair(j, n, a, b, lam, s: ti.template()):
    """The resistance to pivoting of a pair that presses with the accumulated impulse ``lam``
    [N·s] (:func:`ti_golf.physics.contact.pivot_impulse`, once a step, in the shock sweep): ball
    i (the :func:`body` ``a``, its own inverse mass) and ball j (``b``; its spin read from
    ``state.w[j]``, and written there, unless it is quiet) apart along the unit normal ``n``
    (from j to i). Returns ball i's spin ω_i [rad/s]."""
    contact, state, scratch = ti.static((s.contact, s.state, s.scratch))
    wi, ri, rj = a.w, a.r, b.r
    inv_Ia, inv_Ib = inverse_inertia(ri, a.inv_m), inverse_inertia(rj, b.inv_m)
    if scratch.calm[j] == QUIET:
        inv_Ib = 0.0
    L = pivot_impulse((wi - state.w[j]).dot(n), inv_Ia, inv_Ib, contact.mu_roll * lam * ti.min(ri, rj))
    if L != 0.0:
        wi += L * inv_Ia * n
        state.w[j] -= L * inv_Ib * n
    return wi


@ti.func
def project_pair(j, xi, ri, inv_mi, k_p, model: ti.template(), state: ti.template(), scratch: ti.template()):
    """The position projection (B.18) of a pair of a ball at ``xi`` [m] (radius ``ri``, inverse
    mass ``inv_mi``: 0 at rest) with ball j, on the step's new positions: when they overlap by Δx,
    they move apart by k_p·Δx, ball j's share written to ``scratch.x_free[j]`` (none when it is out
    of bounds, at rest or quiet), the ball's returned. Both layouts of the sweeps
    (:func:`.colour.project_ball`, :mod:`.contact_colour`) make this update."""
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
