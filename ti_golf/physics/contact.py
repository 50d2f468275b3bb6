"""Impulse contacts (report Appendix B): the pair impulse shared by ball–ball and ball–plane
contacts, plane position handling, and rest detection helpers.

A contact between body a (a ball) and body b (a ball, or a plane: a body of infinite mass, B.11)
along the unit normal n̂ (from b to a):

1. contact when the gap at the end of the step, gap + h·min(v_n, 0), would be negative (a
   speculative test on the signed gap, so nothing tunnels through at any speed, L.3, L.4);
   an impulse only while approaching (v_n < 0);
2. normal jolt of a: −(1 + e)·m_red·v_n·n̂ with m_red = m_b/(m_a + m_b) (B.5–B.9; 1 for a plane);
   approach speeds below ``v_inelastic`` use e = 0, so resting contacts do not micro-bounce;
3. Coulomb friction at the contact point, −μ·j_n·t̂ (B.15), clipped so that it can at most stop
   the slip there (solid spheres, I = 2/5·mR²: a friction impulse P changes the slip by
   (7/2)(1/m_a + 1/m_b)·P), and changing both spins;
4. (planes) rolling resistance while in resting contact, |Δv_t| ≤ μ_roll·j_n with Δω = n̂ × Δv/R,
   which leaves the contact-point slip unchanged (a rolling ball decelerates at μ_roll·g), and the
   like resistance to spin about the normal, |Δω_n| ≤ (5/2)·μ_roll·j_n/R (a ball spinning on the
   spot stops, its spin falling at (5/2)·μ_roll·g/R); two touching balls resist pivoting on each
   other in the same way, with the torque μ_roll·N·min(R_a, R_b) about their normal
   (:func:`pivot_impulse`, Gauss–Seidel sweeps only);
5. (planes) the step is split at the time of impact, so a bounce starts on the surface;
6. position projection of what still overlaps, k_p·m_red·Δx·n̂ (B.18).

Ball–surface friction has a second model (``contact.friction_model = "report"``,
:data:`CENTRE_FRICTION`): the report's own (Appendix B, c.3–c.4, B.15), in which friction opposes
the tangential velocity of the ball's centre, v_t = v − n̂⟨n̂, v⟩ (L.7, B.13), with the impulse
μ·j_n clipped so that it can at most stop v_t (:func:`centre_friction`); the spin plays no part and
no surface contact changes it (nor does rolling resistance, which then slows the centre only).
"""

import math

import taichi as ti

from ti_golf.physics.types import no_f64_transcendentals, zero3
from ti_golf.scene.schema import AT_REST, FLYING, FRICTION_MODELS, ROLLING

_TINY = 1e-12

CENTRE_FRICTION = FRICTION_MODELS.index("report")
"""``Kinds.friction`` of the report's friction from the centre's velocity (0: at the contact point)."""


@ti.func
def pair_impulse(n, gap, v_a, w_a, r_a, inv_m_a, v_b, w_b, r_b, inv_m_b, lam, e, mu, v_inelastic, h, relax=1.0):
    """One sweep's impulse P [N·s] on body a from body b (−P acts on b).

    ``n``: unit normal from b to a; ``gap``: surface distance [m] (negative when overlapping);
    ``inv_m_b = 0`` and ``r_b = 0`` make b a plane. ``lam`` is the pair's accumulated *resting*
    normal impulse [N·s] (warm-started from the last step). An approaching pair gets the report's
    jolt −(1+e)·m_red·v_n (B.9), an *impact*; a slow approach (below ``v_inelastic``), or one
    between bodies already pressing on each other (``lam`` at least a quarter of the impact's
    impulse), is inelastic and adds to ``lam`` (in a pile, noise must not turn into bounces); a
    separating pair gives back at most ``lam`` (so a warm start that pushed too hard is undone,
    but impacts are never pulled back). Coulomb friction, bounded by μ times the normal impulse
    of this sweep, can at most stop the slip at the contact point.
    ``relax`` ∈ (0, 1] scales, in a Jacobi sweep, the normal and friction impulses of lasting
    contacts and the give-back of a separating pair: a ball pressed by many neighbours at once
    would otherwise receive all their corrections together and overshoot. Impacts and slow
    approaches take their whole impulse, friction included (B.15).
    Returns (P, lam, touching, impact): ``impact`` is 1 when P is an impact's jolt (a Jacobi sweep
    takes one of a ball's simultaneous impacts at a time, see :func:`ti_golf.solvers.pairs.matched`).
    """
    P = zero3()
    touching = 0
    impact = 0
    inv_m = inv_m_a + inv_m_b
    m_eff = 1.0 / inv_m  # the pair's effective mass (m_red·m_a); one division, not one per use
    v_n = (v_a - v_b).dot(n)
    j_n = 0.0
    m_slip = m_eff  # the effective mass with which the friction stops the slip
    if gap + h * ti.min(v_n, 0.0) < 0.0:
        touching = 1
        if v_n < 0.0:
            # a lasting contact already presses with an impulse comparable to this approach: in a
            # pile, noise must not turn into bounces; a real impact is much larger
            lasting = lam * inv_m > -0.25 * v_n
            if -v_n < v_inelastic or lasting:
                j_n = -v_n * m_eff
                if lasting:
                    j_n *= relax
                    m_slip *= relax
                lam += j_n
            else:
                impact = 1
                j_n = -(1.0 + e) * v_n * m_eff  # e = 0: a plastic impact (not a support: not accumulated)
    if v_n > 0.0 and lam > 0.0:
        j_n = -ti.min(lam, relax * v_n * m_eff)
        lam += j_n
    if j_n != 0.0:
        P = j_n * n
        if j_n > 0.0:
            P += friction_impulse(n, v_a, w_a, r_a, v_b, w_b, r_b, m_slip, mu * j_n)
    return P, lam, touching, impact


@ti.func
def clamp_friction(F, n, bound):
    """The friction impulse F [N·s] in the tangent plane of ``n``, at most ``bound`` long."""
    F_t = F - F.dot(n) * n
    size = F_t.norm()
    if size > bound:
        F_t *= bound / size
    return F_t


@ti.func
def friction_impulse(n, v_a, w_a, r_a, v_b, w_b, r_b, m_eff, bound):
    """Friction impulse on a [N·s], at most ``bound`` and at most what stops the contact-point slip
    (solid spheres: an impulse P changes the slip by (7/2)·(1/m_a + 1/m_b)·P, so the stopping
    impulse is (2/7)·m_eff·slip with the effective mass m_eff = 1/(1/m_a + 1/m_b))."""
    slip = v_a + w_a.cross(-r_a * n) - v_b - w_b.cross(r_b * n)
    slip_t = slip - slip.dot(n) * n
    s = slip_t.norm()
    P = zero3()
    if s > _TINY:
        P = -ti.min(bound, s * m_eff * (2.0 / 7.0)) * (slip_t * (1.0 / s))
    return P


@ti.func
def centre_friction(n, v, m_eff, bound):
    """The report's friction impulse [N·s] on a body whose centre moves at ``v`` [m/s] relative to
    the other along the contact normal n̂ (Appendix B c.3–c.4, B.15): −min(``bound``, m_eff·|v_t|)·t̂
    with v_t = v − n̂⟨n̂, v⟩ (L.7, B.13) and t̂ = v_t/|v_t|, ``bound`` = μ·j_n and the clip
    m_eff·|v_t| (the report's "clip μ·v_jolt not to exceed v_t": at most stop the centre's
    sliding; ``m_eff``: the pair's effective mass, 1 per unit mass against a surface). Spin plays no
    part."""
    v_t = v - v.dot(n) * n
    s = v_t.norm()
    P = zero3()
    if s > _TINY:
        P = -ti.min(bound, s * m_eff) * (v_t * (1.0 / s))
    return P


@ti.func
def warm_impulse(n, v_a, w_a, r_a, v_b, w_b, r_b, m_eff, lam, mu):
    """The impulse that re-applies a pair's resting normal impulse ``lam`` with its friction
    (``m_eff``: the pair's effective mass, see :func:`friction_impulse`)."""
    return lam * n + friction_impulse(n, v_a, w_a, r_a, v_b, w_b, r_b, m_eff, mu * lam)


@ti.func
def inverse_inertia(radius, inv_mass):
    """1/I [1/(kg·m²)] of a solid sphere (I = 2/5·mR²); 0 for a body that stands firm."""
    return 2.5 * inv_mass / (radius * radius)


@ti.func
def spin_jolt(P, n, radius, inv_mass):
    """Δω [rad/s] of a solid sphere of ``radius`` receiving impulse P at the point −radius·n̂."""
    return (-radius * n).cross(P) * inverse_inertia(radius, inv_mass)


@ti.func
def kinetic_change(v, w, radius, inv_mass, P, n):
    """ΔKE [J] of a solid sphere of ``radius`` at velocity v [m/s] and spin ω [rad/s] receiving
    impulse P [N·s] at the point −radius·n̂ (0 for a body that stands firm, ``inv_mass`` = 0):
    m(v·Δv + |Δv|²/2) + I(ω·Δω + |Δω|²/2) with I = 2/5·mR²."""
    change = 0.0
    if inv_mass > 0.0:
        dv, dw = P * inv_mass, spin_jolt(P, n, radius, inv_mass)
        change = (
            v.dot(dv) + 0.5 * dv.norm_sqr() + 0.4 * radius * radius * (w.dot(dw) + 0.5 * dw.norm_sqr())
        ) / inv_mass
    return change


@ti.func
def rolling_resistance(v, radius, mu_roll, j_n, n):
    """(Δv, Δω) that slow a rolling ball by at most μ_roll·j_n [m/s], keeping the slip unchanged."""
    v_t = v - v.dot(n) * n
    speed = v_t.norm()
    dv = zero3()
    if speed > _TINY:
        dv = -ti.min(speed, mu_roll * j_n) * v_t / speed
    return dv, n.cross(dv) / radius


@ti.func
def pivot_resistance(w, radius, mu_roll, j_n, n):
    """Δω [rad/s] that slows a ball's spin about the contact normal n̂ (pivoting on the spot) by at
    most (5/2)·μ_roll·j_n/R: the turf resists it as it resists rolling, with a torque μ_roll·N·R
    (I = 2/5·mR², j_n = N·dt/m [m/s]). It changes no velocity: spin about n̂ moves no contact point."""
    w_n = w.dot(n)
    stop = ti.min(ti.abs(w_n), 2.5 * mu_roll * ti.max(j_n, 0.0) / radius)
    return -ti.math.sign(w_n) * stop * n


@ti.func
def pivot_impulse(w_n, inv_I_a, inv_I_b, bound):
    """Angular impulse L [N·m·s] about the contact normal n̂ on body a (−L on b) that resists two
    touching balls pivoting on each other at the relative spin ``w_n`` = (ω_a − ω_b)·n̂ [rad/s]: at
    most ``bound`` (μ_roll·λ·min(R_a, R_b), the torque with which a contact patch resists turning
    on the spot, as the turf does in :func:`pivot_resistance`), and at most what stops the
    relative spin, so it only takes kinetic energy out."""
    L = 0.0
    inv_I = inv_I_a + inv_I_b
    if inv_I > 0.0:
        L = -ti.math.sign(w_n) * ti.min(ti.abs(w_n) / inv_I, bound)
    return L


TURF_TILT, TURF_SPEED, TURF_ANGLE = math.radians(15.4), 18.6, math.radians(44.4)
"""Penner's turf-compliance tilt [rad] at his reference impact, 18.6 m/s at 44.4° (see :func:`turf_impact`)."""


@ti.func
def turf_restitution(v_n):
    """Normal restitution of a golf ball on turf at approach speed ``v_n`` [m/s] (Penner 2002,
    golf_data.md): 0.510 − 0.0375·v_n + 0.000903·v_n² up to 20 m/s, 0.120 above."""
    e = 0.120
    if v_n <= 20.0:
        e = 0.510 - 0.0375 * v_n + 0.000903 * v_n * v_n
    return e


@ti.func
def turf_impact(n, v, lam, gap, v_inelastic, h):
    """(n̂', e'): the frame in which an impact of a ball at velocity ``v`` on turf with normal n̂ is
    solved (Penner 2002, golf_data.md): the turf gives under the ball, so the impact happens on a
    surface tilted toward the incoming ball by θ_c = 15.4°·(|v|/18.6 m/s)·(φ/44.4°), φ the impact
    angle below the surface (at most 90° − φ, so the tilted surface never faces away); e' is
    :func:`turf_restitution` of the approach speed along n̂'. Only an impact is tilted: an approach
    faster than ``v_inelastic`` that meets the surface within the step, with no resting impulse
    ``lam``, and not head-on; otherwise n̂' = n̂."""
    v_n = v.dot(n)
    v_t = v - v_n * n
    u = v_t.norm()
    n_eff = n
    if -v_n >= v_inelastic and gap + h * v_n < 0.0 and lam == 0.0 and u > _TINY:
        cos_t, sin_t = turf_tilt(-v_n, u, v.norm())
        n_eff = cos_t * n - sin_t * (v_t / u)
    return n_eff, turf_restitution(ti.max(-v.dot(n_eff), 0.0))


@ti.func
def turf_tilt(v_n, u, speed):
    """(cos θ_c, sin θ_c) of the turf tilt (:func:`turf_impact`) of an impact at ``speed`` [m/s]
    that approaches the surface at ``v_n`` > 0 and moves along it at ``u`` > 0. Taichi's Vulkan
    backend has no 64-bit atan2, cos or sin (SPIR-V's GLSL.std.450 set stops at 32 bits): there,
    in f64, the angles are worked out in f32 (θ_c to about 1e-7 of itself), elsewhere in the
    float type."""
    cos_t, sin_t = 1.0, 0.0
    if ti.static(no_f64_transcendentals()):
        phi = ti.atan2(ti.cast(v_n, ti.f32), ti.cast(u, ti.f32))
        rate = ti.cast(TURF_TILT * (speed / TURF_SPEED) / TURF_ANGLE, ti.f32)
        theta = ti.min(rate * phi, ti.cast(0.5 * math.pi, ti.f32) - phi)
        cos_t, sin_t = ti.cast(ti.cos(theta), float), ti.cast(ti.sin(theta), float)
    else:
        phi = ti.atan2(v_n, u)
        theta = ti.min(TURF_TILT * (speed / TURF_SPEED) * (phi / TURF_ANGLE), 0.5 * math.pi - phi)
        cos_t, sin_t = ti.cos(theta), ti.sin(theta)
    return cos_t, sin_t


@ti.func
def impact_frame(n, gap, v, lam, contact, v_inelastic, h, kinds: ti.template()):
    """(n̂', e'): the normal and restitution of a ball's contact with a static surface of normal
    n̂ (``contact``: the surface's contact parameters): n̂ and ``contact.e``, or with
    ``contact.turf`` the turf frame of :func:`turf_impact`, whose code is built only with
    ``kinds.turf`` (the scene's :class:`ti_golf.physics.kinds.Kinds`)."""
    n_eff, e = n, contact.e
    if ti.static(kinds.turf):
        if contact.turf != 0:
            n_eff, e = turf_impact(n, v, lam, gap, v_inelastic, h)
    return n_eff, e


@ti.func
def surface_impulse(n, gap, v, w, radius, lam, contact, v_inelastic, h, kinds: ti.template()):
    """A ball's impulse per unit mass [m/s] from a static surface (a plane, or the terrain's patch)
    with normal n̂ and surface gap ``gap`` [m]: :func:`pair_impulse` against a body of infinite
    mass, with ``contact``'s restitution, or with ``contact.turf`` in the turf frame of
    :func:`turf_impact` (:func:`impact_frame`). With the report's friction (``kinds.friction``) the
    friction is :func:`centre_friction`, bounded by μ times the normal impulse. Returns (P, λ,
    touching, n̂'), n̂' the normal the impulse was solved along (its contact point is −R·n̂', see
    :func:`plane_jolt`)."""
    n_eff, e = impact_frame(n, gap, v, lam, contact, v_inelastic, h, kinds)
    mu = contact.mu
    if ti.static(kinds.friction == CENTRE_FRICTION):
        mu = 0.0  # (added below)
    P, lam_new, touching, _ = pair_impulse(
        n_eff, gap, v, w, radius, 1.0, zero3(), zero3(), 0.0, 0.0, lam, e, mu, v_inelastic, h
    )
    if ti.static(kinds.friction == CENTRE_FRICTION):
        j_n = P.dot(n_eff)  # the normal impulse per unit mass (P is j_n·n̂' so far)
        if j_n > 0.0:
            P += centre_friction(n_eff, v, 1.0, contact.mu * j_n)
    return P, lam_new, touching, n_eff


@ti.func
def plane_impulse(x, v, w, radius, p, n, contact, v_inelastic, h, kinds: ti.template()):
    """Velocity and spin of a ball after its contact with the plane (p, n̂) (``kinds``: the scene's
    kinds of code). Returns (v, ω, touching)."""
    gap = (x - p).dot(n) - radius
    P, lam, touching, n_eff = surface_impulse(n, gap, v, w, radius, 0.0, contact, v_inelastic, h, kinds)
    if touching != 0 and P.dot(n) > 0.0:
        v, w = plane_jolt(P, lam, v, w, radius, n_eff, contact.mu_roll, kinds.friction)
    return v, w, touching


@ti.func
def plane_jolt(P, lam, v, w, radius, n, mu_roll, friction: ti.template()):
    """Apply a plane's impulse per unit mass P [m/s] to a ball and, when it is a resting impulse
    (it added ``lam`` > 0), rolling resistance bounded by μ_roll·P·n̂ and the like resistance to
    spin about the normal (:func:`pivot_resistance`). With the report's friction (``friction`` =
    :data:`CENTRE_FRICTION`, a compile-time value) the spin is left as it is. Returns (v, ω)."""
    spin = ti.static(friction != CENTRE_FRICTION)
    v_new = v + P
    w_new = w
    if ti.static(spin):
        w_new = w + spin_jolt(P, n, radius, 1.0)
    if lam > 0.0:
        j_n = P.dot(n)
        dv, dw = rolling_resistance(v_new, radius, mu_roll, j_n, n)
        v_new += dv
        if ti.static(spin):
            w_new += dw + pivot_resistance(w_new, radius, mu_roll, j_n, n)
    return v_new, w_new


SPLIT_ROUNDING = 1e-6
"""How far a normal velocity taken to 0 may fall below it by rounding, as a share of the approach
speed, and still count as turned back (:func:`plane_position`): f32 keeps about 1e-7."""


@ti.func
def plane_position(x, x_free, x1, v_free, v, radius, p, n, k_p, h, g):
    """End-of-step position ``x1`` and velocity ``v`` of a ball corrected for the plane (p, n̂).

    ``x`` is the position at the start of the step, ``x_free``/``v_free`` the free-flight
    prediction, ``v`` the final velocity and ``x1`` the position so far (``x_free + h·(v − v_free)``
    before the first plane); ``g`` is gravity [m/s²]. When the free flight crosses the plane and the
    plane pushed back, the step is split at the time of impact (:func:`impact_fraction`) if the
    plane turned the ball back (v·n̂ ≥ 0, to :data:`SPLIT_ROUNDING`); a ball already touching, or
    one that the plane only slowed and still approaches, moves at ``v`` for the whole step, x + h·v
    (the Gauss–Seidel sweeps close such a contact's gap exactly within the step: the split would put
    it (1 − frac)·h·|v·n̂| into the plane, and the free flight's own path, with RK4's ½·g·h², would
    leave it hovering above). A ball that bounced (v·n̂ > 0) is also given the velocity and height
    of the bounce at the time of impact (:func:`bounce_split`). A ball that bounced though its free
    flight ends above the plane (the contact test's straight line x + h·v_free runs below RK4's
    curve, by up to ½·|g·n̂|·h²) meets it at the step's end: it ends the step on the plane, leaving
    it at e times the speed it would have reached it with (its rebound's height is kept; its
    clock runs ahead by that last gap's flight, under a µs). What still penetrates is projected
    out with k_p (B.18, m_red = 1). Returns (x1, v).
    """
    gap0 = (x - p).dot(n) - radius
    gap1 = (x_free - p).dot(n) - radius
    v_n, v_free_n = v.dot(n), v_free.dot(n)
    if gap1 < 0.0 and v_n > v_free_n:
        frac = 0.0  # touching at the start, or only slowed: the impulse acts from the step's start
        if gap0 > 0.0 and v_n >= -SPLIT_ROUNDING * ti.abs(v_free_n):
            frac = impact_fraction(gap0, gap1, v_free_n, h)
        after = (1.0 - frac) * h  # the step's time after the impact [s]
        at_impact = x + frac * (x_free - x)
        if frac > 0.0:  # on the plane at the impact (the straight line between x and x_free is not)
            at_impact -= ((at_impact - p).dot(n) - radius) * n
        x1 = at_impact + after * v
        if frac > 0.0 and v_n > 0.0 and v_free_n < 0.0:  # a bounce within the step
            v, rise = bounce_split(v, v_n, v_free_n, g.dot(n) * after, after, n)
            x1 = at_impact + after * (v - v.dot(n) * n) + rise * n
    elif gap0 > 0.0 and gap0 + h * v_free_n < 0.0 and v_n > 0.0 and v_free_n < -ti.abs(g.dot(n)) * h:
        # a bounce that the contact test's line met while RK4's curve ends above (gap1 < ½|g·n̂|h²),
        # at an approach faster than a step of gravity: at the step's end, on the plane
        x1 = x_free - gap1 * n
        reach_n = ti.sqrt(v_free_n * v_free_n - 2.0 * g.dot(n) * gap1)  # |v·n̂| on the plane [m/s]
        v += ti.min(v_n / -v_free_n, 1.0) * (reach_n + v_free_n) * n  # (e at most 1: at most |g·n̂|·h more)
    gap = (x1 - p).dot(n) - radius
    if gap < 0.0:
        x1 -= k_p * gap * n
    return x1, v


@ti.func
def impact_fraction(gap0, gap1, v_free_n, h):
    """The share of a step [0, 1] at which a ball meets a plane, from its gaps [m] at the start
    (``gap0`` > 0) and at the end of its free flight (``gap1`` < 0) and its normal velocity there
    (``v_free_n`` [m/s], approaching): the root of the parabola through those three, gap(h − s) =
    gap1 − v_free_n·s + c·s², c = (gap0 − gap1 + v_free_n·h)/h² (half the normal acceleration).
    It is exact for a flight under constant acceleration (RK4 without air), and the straight line
    between the gaps where the flight is one (semi-implicit Euler: c = 0); the line alone put RK4's
    impacts up to (1/8)·|g·n̂|·h²/|v·n̂| of a step late."""
    c = (gap0 - gap1 + v_free_n * h) / (h * h)
    b = -v_free_n
    den = b + ti.sqrt(ti.max(b * b - 4.0 * c * gap1, 0.0))
    frac = 0.0  # (den ≤ 0: no such parabola but by rounding; the impulse acts from the start)
    if den > 0.0:
        frac = ti.min(ti.max(1.0 + 2.0 * gap1 / (den * h), 0.0), 1.0)  # s = −2·gap1/den, the root nearest the end
    return frac


@ti.func
def bounce_split(v, v_n, v_free_n, g_after, after, n):
    """A bounce off a plane of normal n̂ split at the time of impact. The impulse gave the ball the
    normal velocity v_n = e·|v_free·n̂| from the free flight's end velocity, which holds gravity's
    pull g_after = (g·n̂)·after [m/s] over the time ``after`` [s] between the impact and the step's
    end: at the impact the ball approached at v_free·n̂ − g_after, so it left at u = v_n + e·g_after,
    and by the step's end it rose rise = after·(u + ½·g_after) and moves at u + g_after along n̂
    (e = v_n/|v_free·n̂|: the restitution the impulse used). Without the split, the step would end
    (1 + e)·|g_after| too fast along n̂, an error of first order in h that grows bounce by bounce. A
    ball that falls back within the step ends on the plane, at rest along n̂. Returns (v, rise [m])."""
    e = v_n / -v_free_n
    u = ti.max(v_n + e * g_after, 0.0)
    rise = after * (u + 0.5 * g_after)
    v_end_n = u + g_after
    if rise <= 0.0:
        rise, v_end_n = 0.0, ti.max(v_end_n, 0.0)
    return v + (v_end_n - v_n) * n, rise


PRESSED = 2
"""``touching`` of a ball that another ball overlaps by more than ``PRESSED_OVERLAP`` of its radius
(1 % with the Jacobi sweeps): the position projection (B.18) is still pushing them apart, so it is
not at rest (see :func:`rest_update`)."""

PRESSED_OVERLAP = 0.01
"""The overlap, as a share of a ball's radius, past which the Jacobi sweeps call a ball pressed
(:data:`PRESSED`; the Gauss–Seidel sweeps use ``colour.ASLEEP_OVERLAP``)."""

TOUCHING_GAP = 0.01
"""A surface gap below this share of a ball's radius counts as touching (a plane, the terrain or
another ball): the contacts that keep a ball's rest timer and its island's calm."""


@ti.func
def rest_update(touching, v, w, radius, rest_time, h, v_rest, t_rest, friction: ti.template()):
    """Status and rest timer of a ball after a step: a touching ball (``touching`` 1; not
    ``PRESSED``) whose speed and R|ω| stay below ``v_rest`` [m/s] for ``t_rest`` [s] is put at
    rest. With the report's friction (``friction`` = :data:`CENTRE_FRICTION`, a compile-time
    value) the spin is not asked: no contact changes it, so a ball that stopped sliding would
    otherwise never rest. Returns (status, rest_time)."""
    rt = 0.0
    slow = v.norm() < v_rest
    if ti.static(friction != CENTRE_FRICTION):
        slow = slow and radius * w.norm() < v_rest
    st = ROLLING if touching != 0 else FLYING
    if touching == 1 and slow:  # (only a slow ball rests: with t_rest = 0 too, where rt = 0 >= t_rest)
        rt = rest_time + h
        if rt >= t_rest:
            st = AT_REST
    return st, rt
