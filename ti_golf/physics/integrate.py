"""Time integrators for one ball and the landing/apex bookkeeping of a flight.

Integrators (``integrator`` code passed to kernels):

* ``SEMI_IMPLICIT`` (0): the report's semi-implicit (symplectic) Euler,
  v' = v + h·a(v, ω), ω' = ω + h·α(v, ω), x' = x + h·v'. First order; contact impulses are applied
  between the velocity and the position update ("in the half step").
* ``RK4`` (1): classical fourth-order Runge–Kutta on (x, v, ω); global error O(h⁴).

Landing: the first downward crossing of the launch height is located inside the step by cubic
Hermite interpolation of (x, v) at both ends (error O(h⁴), matching RK4), so carry does not
depend on where the step boundaries fall.
"""


import taichi as ti

from .aero import derivatives

SEMI_IMPLICIT = 0
RK4 = 1
INTEGRATOR_CODES = {"semi_implicit": SEMI_IMPLICIT, "rk4": RK4}

NOT_TRACKED, IN_FLIGHT, LANDED = -1, 0, 1
"""Values of the per-ball ``landed`` flag."""


@ti.func
def step_free(x, v, w, h, integrator: ti.template(), coef, air, gravity):
    """One free-flight step of size ``h`` [s]; returns the new (x, v, ω)."""
    x1, v1, w1 = x, v, w
    if ti.static(integrator == RK4):
        a1, b1 = derivatives(v, w, coef, air, gravity)
        v2, w2 = v + 0.5 * h * a1, w + 0.5 * h * b1
        a2, b2 = derivatives(v2, w2, coef, air, gravity)
        v3, w3 = v + 0.5 * h * a2, w + 0.5 * h * b2
        a3, b3 = derivatives(v3, w3, coef, air, gravity)
        v4, w4 = v + h * a3, w + h * b3
        a4, b4 = derivatives(v4, w4, coef, air, gravity)
        x1 = x + (h / 6.0) * (v + 2.0 * v2 + 2.0 * v3 + v4)
        v1 = v + (h / 6.0) * (a1 + 2.0 * a2 + 2.0 * a3 + a4)
        w1 = w + (h / 6.0) * (b1 + 2.0 * b2 + 2.0 * b3 + b4)
    else:
        a, b = derivatives(v, w, coef, air, gravity)
        v1 = v + h * a
        w1 = w + h * b
        x1 = x + h * v1
    return x1, v1, w1


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
    return (6.0 * s2 - 6.0 * s) * p0 + (3.0 * s2 - 4.0 * s + 1.0) * m0 + (6.0 * s - 6.0 * s2) * p1 + (3.0 * s2 - 2.0 * s) * m1


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
        if f > 0:
            lo = s
        else:
            hi = s
        df = hermite_ds(y0, y1, m0, m1, s)
        s_new = s - f / df if df != 0 else 0.5 * (lo + hi)
        if s_new <= lo or s_new >= hi:
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
def track_flight(x, v, x1, v1, h, t, level, landed, apex, t_land, land_x, land_v):
    """Update the apex and detect the landing of one ball during the step (x, v) → (x1, v1).

    ``level`` is the landing height [m] (the launch height), ``t`` the time at the start of the
    step [s]. Returns the updated (landed, apex, t_land, land_x, land_v).
    """
    if landed == IN_FLIGHT:
        if v[1] > 0.0 and v1[1] <= 0.0:
            s = hermite_extremum(x[1], x1[1], h * v[1], h * v1[1])
            apex = ti.max(apex, hermite(x[1], x1[1], h * v[1], h * v1[1], s))
        else:
            apex = ti.max(apex, x1[1])
        if x[1] >= level and x1[1] < level:
            s = hermite_root(x[1], x1[1], h * v[1], h * v1[1], level)
            land_x = hermite(x, x1, h * v, h * v1, s)
            land_x[1] = level
            land_v = hermite_ds(x, x1, h * v, h * v1, s) / h
            t_land = t + s * h
            landed = LANDED
    return landed, apex, t_land, land_x, land_v
