"""Impulse contact of a ball with an impenetrable plane (report Appendix B), and rest detection.

The plane through ``p`` with unit normal ``n`` is the boundary of an impenetrable half-space
(behind the plane): the penetration Δx = R − (x − p)·n (L.3) is measured on the signed distance,
so a ball cannot tunnel through at any speed. A plane is a body of infinite mass: m_red = 1 (B.11).

Per step, with the free-flight prediction (x, v, ω) → (x1, v1, ω1):

1. contact if the predicted penetration is positive, impulse only if approaching (v1·n < 0);
2. normal jolt  Δv = −(1 + e)(v1·n) n  (B.9, B.11); approach speeds below
   ``v_bounce + 2|g|h`` use e = 0, so a resting ball does not micro-bounce;
3. Coulomb friction at the contact point, −μ·j_n·t̂ (B.15), clipped so that it can at most stop the
   sliding there (solid sphere, I = 2/5·mR²: the contact-point slip changes by 7/2 of the centre's
   change), and changing ω by (5/2)(j_t/R)(n × t̂);
4. rolling resistance while in resting contact: |Δv_t| ≤ μ_roll·j_n with Δω = n × Δv / R, which
   leaves the contact-point slip unchanged (a rolling ball decelerates at μ_roll·g and keeps rolling);
5. the step is split at the time of impact (linear in the gaps), so the bounce starts on the surface;
6. position projection of any remaining penetration, x += k_p·Δx·n (B.18).
"""


import taichi as ti

from .types import vec3

_TINY = 1e-12


@ti.func
def friction_jolt(vc_t, j_n, radius, mu, n):
    """Velocity and spin jolts of Coulomb friction for a contact-point slip ``vc_t`` [m/s].

    ``j_n`` is the normal jolt [m/s] (impulse per mass). The friction jolt is clipped to 2/7 of the
    slip so that it can only stop the sliding, never reverse it. Returns (Δv, Δω).
    """
    dv = vec3(0.0)
    dw = vec3(0.0)
    slip = vc_t.norm()
    if slip > _TINY:
        t_hat = vc_t / slip
        j_t = ti.min(mu * j_n, (2.0 / 7.0) * slip)
        dv = -j_t * t_hat
        dw = (2.5 * j_t / radius) * n.cross(t_hat)
    return dv, dw


@ti.func
def rolling_resistance(v, radius, mu_roll, j_n, n):
    """(Δv, Δω) that slow a rolling ball by at most μ_roll·j_n [m/s], keeping ω = n × v / R."""
    v_t = v - v.dot(n) * n
    speed = v_t.norm()
    dv = vec3(0.0)
    if speed > _TINY:
        dv = -ti.min(speed, mu_roll * j_n) * v_t / speed
    return dv, n.cross(dv) / radius


@ti.func
def plane_contact(x, x1, v1, w1, radius, p, n, contact, v_inelastic, h):
    """Resolve the contact of one ball with the plane (``p``, ``n``) during the step x → x1.

    ``v_inelastic`` [m/s]: approach speeds below it get e = 0. Returns (x1, v1, ω1, touching).
    """
    touching = 0
    gap0 = (x - p).dot(n) - radius
    gap1 = (x1 - p).dot(n) - radius
    if gap1 < 0.0:
        touching = 1
        v_n = v1.dot(n)
        if v_n < 0.0:
            e = contact.e
            resting = -v_n < v_inelastic
            if resting:
                e = 0.0
            j_n = -(1.0 + e) * v_n
            v_c = v1 + w1.cross(-radius * n)  # velocity of the contact point
            dv, dw = friction_jolt(v_c - v_c.dot(n) * n, j_n, radius, contact.mu, n)
            v_new = v1 + j_n * n + dv
            w_new = w1 + dw
            if resting:
                dv_r, dw_r = rolling_resistance(v_new, radius, contact.mu_roll, j_n, n)
                v_new += dv_r
                w_new += dw_r
            frac = 0.0
            if gap0 > 0.0:
                frac = gap0 / (gap0 - gap1)
            x1 = x + frac * (x1 - x) + (1.0 - frac) * h * v_new
            v1 = v_new
            w1 = w_new
        gap = (x1 - p).dot(n) - radius
        if gap < 0.0:
            x1 -= contact.k_p * gap * n
    return x1, v1, w1, touching
