"""Aerodynamics of a spinning ball in a constant wind: drag, Magnus force and spin decay.

All laws use the velocity relative to the air, v_rel = v − wind (report L.21–L.23):

* drag       f_D = −k_D |v_rel|^(γ−1) v_rel,          k_D = ½ρA·C_D          (L.22)
* Magnus     f_M = k_M |v_rel| (ω × v_rel),            k_M = ½ρA·C_M/ω_M      (L.1, L.2, L.21)
* spin decay dω/dt = −k_ω (|v_rel| + R|ω|)^(γ−1) ω,    k_ω = ½ρA·C_ω/m        (L.17, L.20, L.23)

with A = πR² the cross-section. Forces do not depend on position, so integrators need (v, ω) only.
"""


import math

import taichi as ti

from .types import BallCoef


@ti.func
def ball_coefficients(air, radius, mass) -> BallCoef:
    """k_D/m, k_M/m, k_ω and R of one ball (``air``: AirParams; radius [m]; mass [kg])."""
    half_rho_A = 0.5 * air.rho * math.pi * radius * radius
    return BallCoef(
        kD=half_rho_A * air.C_D / mass,
        kM=half_rho_A * air.C_M / air.omega_M / mass,
        kw=half_rho_A * air.C_omega / mass,
        radius=radius,
    )


@ti.func
def derivatives(v, w, coef, air, gravity):
    """(dv/dt [m/s²], dω/dt [rad/s²]) of one ball with velocity ``v`` and spin ``w``."""
    v_rel = v - air.wind
    speed = v_rel.norm()
    drag = coef.kD
    decay = coef.kw
    if air.gamma == 2:
        drag *= speed
        decay *= speed + coef.radius * w.norm()
    dv = gravity - drag * v_rel + coef.kM * speed * w.cross(v_rel)
    return dv, -decay * w
