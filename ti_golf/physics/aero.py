"""Aerodynamics of a spinning ball in a constant wind: drag, Magnus force and spin decay.

All laws use the velocity relative to the air, v_rel = v − wind (report L.21–L.23):

* drag       f_D = −k_D |v_rel|^(γ−1) v_rel,          k_D = ½ρA·C_D          (L.22)
* Magnus     f_M = k_M |v_rel| (ω × v_rel),            k_M = ½ρA·C_M/ω_M      (L.1, L.2, L.21)
* spin decay dω/dt = −k_ω (|v_rel| + R|ω|)^(γ−1) ω,    k_ω = ½ρA·C_ω/m        (L.17, L.20, L.23)

with A = πR² the cross-section. Forces do not depend on position.

Balls are integrated in *lanes*: a state matrix ``S`` of shape (10, L) holds L balls side by side,
rows x, y, z, v_x, v_y, v_z, ω_x, ω_y, ω_z and |ω|. The spin magnitude has a row of its own because
spin decay only scales ω (dω/dt ∥ ω), so d|ω|/dt = −(decay rate)·|ω| exactly and no square root of
ω is needed per force evaluation. Every operation is element-wise across the lanes, so
L independent balls fill the CPU's SIMD units and hide the latency of the square roots (L = 1 is
a single ball). ``coef`` is a (4, L) matrix with rows k_D/m, k_M/m, k_ω and R of each lane.
"""

import math

import taichi as ti

from .types import vec3

X, V, W, SPIN = 0, 3, 6, 9
"""Rows of a lane state matrix: first row of position, velocity, angular velocity; spin magnitude |ω|."""
ROWS = 10


@ti.func
def row(S, i: ti.template()):
    """Row ``i`` of a matrix as a vector over its columns (lanes)."""
    return ti.Vector([S[i, l] for l in ti.static(range(S.m))])


@ti.func
def column(S, first: ti.template(), lane: ti.template()):
    """The 3-vector in rows first..first+2 of column ``lane`` (e.g. the velocity of one ball)."""
    return vec3(S[first, lane], S[first + 1, lane], S[first + 2, lane])


@ti.func
def coefficients(air, radius, mass):
    """(4, L) matrix of k_D/m, k_M/m, k_ω [1/m] and R [m] for lanes of radius [m] and mass [kg]."""
    half_rho_A = 0.5 * air.rho * math.pi * radius * radius
    return ti.Matrix.rows([
        half_rho_A * air.C_D / mass,
        half_rho_A * air.C_M / air.omega_M / mass,
        half_rho_A * air.C_omega / mass,
        radius,
    ])


@ti.func
def rates(S, coef, air, gravity):
    """dS/dt of a lane state matrix S (10, L): (v, dv/dt [m/s²], dω/dt [rad/s²], d|ω|/dt) per lane."""
    vx, vy, vz = row(S, 3), row(S, 4), row(S, 5)
    wx, wy, wz = row(S, 6), row(S, 7), row(S, 8)
    rx, ry, rz = vx - air.wind[0], vy - air.wind[1], vz - air.wind[2]
    speed = ti.sqrt(rx * rx + ry * ry + rz * rz)
    drag = row(coef, 0)
    decay = row(coef, 2)
    if air.gamma == 2:
        drag = drag * speed
        decay = decay * (speed + row(coef, 3) * row(S, SPIN))
    lift = row(coef, 1) * speed
    return ti.Matrix.rows([
        vx,
        vy,
        vz,
        gravity[0] - drag * rx + lift * (wy * rz - wz * ry),
        gravity[1] - drag * ry + lift * (wz * rx - wx * rz),
        gravity[2] - drag * rz + lift * (wx * ry - wy * rx),
        -decay * wx,
        -decay * wy,
        -decay * wz,
        -decay * row(S, SPIN),
    ])
