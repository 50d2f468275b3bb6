"""Time integrators for one ball and the landing/apex bookkeeping of a flight.

Integrators (``Kinds.integrator``, a compile-time argument of the kernels):

* ``SEMI_IMPLICIT`` (0): the report's semi-implicit (symplectic) Euler,
  v' = v + h·a(v, ω), ω' = ω + h·α(v, ω), x' = x + h·v'. First order; contact impulses are applied
  between the velocity and the position update ("in the half step").
* ``RK4`` (1): classical fourth-order Runge–Kutta on (x, v, ω); global error O(h⁴).

Landing: the first downward crossing of the launch height is located inside the step by cubic
Hermite interpolation of (x, v) at both ends (error O(h⁴), matching RK4), so carry does not
depend on where the step boundaries fall.
"""

import taichi as ti

from ti_golf.physics.aero import V, X, rates

SEMI_IMPLICIT = 0
RK4 = 1
INTEGRATOR_CODES = {"semi_implicit": SEMI_IMPLICIT, "rk4": RK4}

NOT_TRACKED, IN_FLIGHT, LANDED = -1, 0, 1
"""Values of the per-ball ``landed`` flag."""


@ti.func
def step_free(S, h, kinds: ti.template(), coef, air, gravity):
    """One free-flight step of size ``h`` [s] of a lane state matrix S (10, L) (``aero.ROWS``; see :mod:`.aero`) by
    ``kinds.integrator`` in ``kinds.air_model``'s air (:class:`~ti_golf.physics.kinds.Kinds`)."""
    S1 = S
    if ti.static(kinds.integrator == RK4):
        k1 = rates(S, coef, air, kinds, gravity)
        k2 = rates(S + (0.5 * h) * k1, coef, air, kinds, gravity)
        k3 = rates(S + (0.5 * h) * k2, coef, air, kinds, gravity)
        k4 = rates(S + h * k3, coef, air, kinds, gravity)
        S1 = S + (h / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
    else:
        S1 = S + h * rates(S, coef, air, kinds, gravity)  # v' = v + h·a(v, ω), ω' likewise
        for c, l in ti.static(ti.ndrange(3, S.m)):  # x' = x + h·v' (the new velocity: symplectic)
            S1[X + c, l] = S[X + c, l] + h * S1[V + c, l]
    return S1


@ti.func
def hermite(p0, p1, m0, m1, s):
    """Cubic Hermite interpolant on s ∈ [0, 1]; ``m0``, ``m1`` are h·(dp/dt) at the ends."""
    s2 = s * s
    s3 = s2 * s
    return (2.0 * s3 - 3.0 * s2 + 1.0) * p0 + (s3 - 2.0 * s2 + s) * m0 + (3.0 * s2 - 2.0 * s3) * p1 + (s3 - s2) * m1


@ti.func
def hermite_ds(p0, p1, m0, m1, s):
    """d/ds of :func:`hermite`."""
    s2 = s * s
    return (
        (6.0 * s2 - 6.0 * s) * p0
        + (3.0 * s2 - 4.0 * s + 1.0) * m0
        + (6.0 * s - 6.0 * s2) * p1
        + (3.0 * s2 - 2.0 * s) * m1
    )


@ti.func
def hermite_ds2(p0, p1, m0, m1, s):
    """d²/ds² of :func:`hermite`."""
    return (12.0 * s - 6.0) * p0 + (6.0 * s - 4.0) * m0 + (6.0 - 12.0 * s) * p1 + (6.0 * s - 2.0) * m1


@ti.func
def hermite_root(y0, y1, m0, m1, level):
    """s ∈ [0, 1] where the Hermite cubic through (y0, m0), (y1, m1) equals ``level``.

    Requires y0 ≥ level > y1; Newton's method from the linear guess, kept inside the bracket.
    """
    lo, hi = 0.0, 1.0
    s = (y0 - level) / (y0 - y1)
    for _ in ti.static(range(8)):
        f = hermite(y0, y1, m0, m1, s) - level
        if f > 0.0:
            lo = s
        elif f < 0.0:
            hi = s
        df = hermite_ds(y0, y1, m0, m1, s)
        s_new = 0.5 * (lo + hi)
        if df != 0.0:
            s_new = s - f / df
        if s_new < lo or s_new > hi:  # Newton left the bracket: bisect instead
            s_new = 0.5 * (lo + hi)
        s = s_new
    return s


@ti.func
def hermite_extremum(p0, p1, m0, m1):
    """s ∈ [0, 1] where the Hermite cubic's derivative vanishes (the apex when m0 > 0 ≥ m1)."""
    s = m0 / (m0 - m1)
    for _ in ti.static(range(6)):
        d2 = hermite_ds2(p0, p1, m0, m1, s)
        if d2 != 0:
            s = ti.min(ti.max(s - hermite_ds(p0, p1, m0, m1, s) / d2, 0.0), 1.0)
    return s


@ti.func
def apex_in_step(y, y1, vy, vy1, h):
    """Highest y [m] inside a step whose vertical velocity turns from vy > 0 to vy1 ≤ 0 (Hermite)."""
    s = hermite_extremum(y, y1, h * vy, h * vy1)
    return hermite(y, y1, h * vy, h * vy1, s)


@ti.func
def landing_in_step(x, v, x1, v1, h, t, level):
    """(time [s], point [m], velocity [m/s]) where y crosses ``level`` downward inside the step.

    The step runs from (x, v) at time ``t`` to (x1, v1); requires y ≥ level > y1.
    """
    s = hermite_root(x[1], x1[1], h * v[1], h * v1[1], level)
    p = hermite(x, x1, h * v, h * v1, s)
    p[1] = level
    return t + s * h, p, hermite_ds(x, x1, h * v, h * v1, s) / h


@ti.func
def track_flight(x, v, x1, v1, h, t, level, landed, apex, t_land, land_x, land_v):
    """Update the apex and detect the landing of one ball during the step (x, v) → (x1, v1).

    ``level`` is the landing height [m] (the launch height), ``t`` the time at the start of the
    step [s]. Returns the updated (landed, apex, t_land, land_x, land_v).
    """
    if landed == IN_FLIGHT:
        apex = ti.max(apex, x1[1])
        if v[1] > 0.0 and v1[1] <= 0.0:
            apex = ti.max(apex, apex_in_step(x[1], x1[1], v[1], v1[1], h))
        if x[1] >= level and x1[1] < level:
            t_land, land_x, land_v = landing_in_step(x, v, x1, v1, h, t, level)
            landed = LANDED
    return landed, apex, t_land, land_x, land_v
