"""The Gauss–Seidel update of one contact (sequential impulses, ``contact.solver =
"gauss_seidel"``): a ball pair (:func:`pair_step`) or a ball on a static surface
(:func:`surface_step`), in the phase of the step that :class:`.phases.Phase` names. The Jacobi
sweeps' impulse is the report's, :func:`ti_golf.physics.contact.pair_impulse`."""

import taichi as ti

from ti_golf.physics.contact import (
    CENTRE_FRICTION,
    centre_friction,
    clamp_friction,
    friction_impulse,
    pivot_resistance,
    rolling_resistance,
    spin_jolt,
    turf_impact,
)
from ti_golf.physics.types import zero3
from ti_golf.solvers.phases import Phase


@ti.func
def pair_step(
    phase, n, gap, v_n0, v_a, w_a, r_a, inv_m_a, v_b, w_b, r_b, inv_m_b, lam, F, e, mu, v_inelastic, h, friction=0
):
    """One Gauss–Seidel update of a contact (``contact.solver = "gauss_seidel"``): (the impulse P
    [N·s] on body a, −P on b; the contact's new accumulated normal impulse λ [N·s] and friction
    impulse F [N·s] on a). ``n``: unit normal from b to a; ``gap``: surface gap [m] at the start
    of the step; ``v_n0``: the normal velocity [m/s] before the step's contacts (after the free
    flight); ``lam``, ``F``: what the contact has applied so far; ``inv_m_b = 0`` and ``r_b = 0``
    make b a plane.

    ``SOLVE``: sequential impulses toward a normal velocity v_n ≥ −max(gap, 0)/h, the pair
    closing its gap within the step but not overlapping more (what overlaps is projected out
    after the step, B.18). What is clamped is the accumulated λ ≥ 0, so a warm start that pushed
    too hard is taken back. Every contact is inelastic here. Coulomb friction (B.15): the
    accumulated F, toward stopping the slip at the contact point (solid spheres, see
    :func:`ti_golf.physics.contact.friction_impulse`), is clamped to |F| ≤ μ·λ.

    ``BOUNCE``: restitution, once per step after the sweeps, for a contact that approached faster
    than ``v_inelastic`` and is pressed (λ > 0): toward v_n = −e·v_n0 (B.9), again through the
    clamped λ. Slower approaches are resting contacts and never bounce: a resting contact gains no
    energy. A plastic pair (e = 0) still apart at the step's start is left as the sweeps made it,
    closing its gap exactly within the step (the next step stops it, touching): v_n = 0 would stop
    it short, up to h·|v_n0| apart. With e > 0 such a pair bounces from where it is, up to
    h·|v_n0| before touching, as with the speculative contacts of other engines: moving it to the
    contact first would take speed from the bounce. ``friction`` = :data:`ti_golf.physics.contact.CENTRE_FRICTION`: the friction stops the centres' tangential
    velocity instead (:func:`ti_golf.physics.contact.centre_friction`)."""
    m_eff = 1.0 / (inv_m_a + inv_m_b)
    v_n = (v_a - v_b).dot(n)
    target = -ti.max(gap, 0.0) / h
    if phase == Phase.BOUNCE:
        target = v_n  # no change
        if v_n0 < -v_inelastic and lam > 0.0 and (e > 0.0 or gap <= 0.0):
            target = -e * v_n0
    lam_new = ti.max(lam + m_eff * (target - v_n), 0.0)
    P = (lam_new - lam) * n
    F_new = F
    if phase != Phase.BOUNCE:
        F_new = zero3()  # |F| ≤ μ·λ: a contact that presses no more holds no friction
        if lam_new > 0.0:
            if friction == CENTRE_FRICTION:
                F_new = F + centre_friction(n, v_a - v_b, m_eff, 1e30)
            else:
                F_new = F + friction_impulse(n, v_a, w_a, r_a, v_b, w_b, r_b, m_eff, 1e30)
            F_new = clamp_friction(F_new, n, mu * lam_new)
        P += F_new - F
    return P, lam_new, F_new


@ti.func
def surface_step(phase, n, gap, v0, v, w, radius, lam, F, contact, v_inelastic, h):
    """:func:`pair_step` of a ball against a static surface (a plane, or the terrain's patch) with
    normal n̂, per unit mass [m/s] (``v0``: the ball's velocity before the step's contacts; ``F``:
    the friction impulse applied so far), with
    ``contact``'s restitution, or with ``contact.turf`` in the turf frame of :func:`ti_golf.physics.contact.turf_impact`.
    In the ``BOUNCE`` pass a pressed ball also meets rolling resistance and the resistance to spin
    about the normal, bounded by μ_roll·λ (once per step, as :func:`ti_golf.physics.contact.plane_jolt` does). With the
    report's friction (``contact.friction``) the spin is left as it is. Returns (v, ω, λ, F)."""
    n_eff, e = n, contact.e
    if contact.turf != 0:
        n_eff, e = turf_impact(n, v, lam, gap, v_inelastic, h)
    P, lam_new, F_new = pair_step(
        phase,
        n_eff,
        gap,
        v0.dot(n_eff),
        v,
        w,
        radius,
        1.0,
        zero3(),
        zero3(),
        0.0,
        0.0,
        lam,
        F,
        e,
        contact.mu,
        v_inelastic,
        h,
        contact.friction,
    )
    spin = contact.friction != CENTRE_FRICTION
    v_new = v + P
    w_new = w
    if spin:
        w_new = w + spin_jolt(P, n_eff, radius, 1.0)
    if phase == Phase.BOUNCE and lam_new > 0.0:
        dv, dw = rolling_resistance(v_new, radius, contact.mu_roll, lam_new, n_eff)
        v_new += dv
        if spin:
            w_new += dw + pivot_resistance(w_new, radius, contact.mu_roll, lam_new, n_eff)
    return v_new, w_new, lam_new, F_new
