"""Aerodynamics of a spinning ball in the wind: drag, Magnus force and spin decay.

All laws use the velocity relative to the air, v_rel = v − u(y) (report L.21–L.23), u the wind
at the ball's height: the scene's ``air.wind`` at every height, or with ``air.wind_profile =
"log"`` the logarithmic profile of the surface layer, u(z) = wind·ln(z/z₀)/ln(z_ref/z₀) for
z > z₀ and 0 below, z = y − ``world.ground_height`` (:func:`wind_scale`):

* drag       f_D = −k_D |v_rel|^(γ−1) v_rel,          k_D = ½ρA·C_D          (L.22)
* Magnus     f_M = k_M |v_rel| (ω × v_rel),            k_M = ½ρA·C_M/ω_M      (L.1, L.2, L.21)
* spin decay dω/dt = −k_ω (|v_rel| + R|ω|)^(γ−1) ω,    k_ω = ½ρA·C_ω/m        (L.17, L.20, L.23)

with A = πR² the cross-section. Forces depend on position only through the wind's height.

With ``air.model = "spin_ratio"`` (γ = 2) drag and lift take coefficients of the spin ratio
S = R|ω|/|v_rel| instead (golf_data.md: Ferguson, McNally & McPhee 2022, a fit to 1040
launch-monitor shots over S = 0.02–0.75):

* drag       f_D = −½ρA·C_D(S) |v_rel| v_rel,          C_D = 0.1304 + 0.9287 S − 0.8259 S²
* lift       f_L = ½ρA·C_L(S) |v_rel|² (ω̂ × v̂_rel),    C_L = 0.0504 + 1.2031 S − 1.1490 S²

held at their S = 0.75 values beyond the fit, and at their S = 0.02 values below it, where C_L
also falls in proportion to S so that a ball without spin feels no lift (:func:`spin_ratio_coefficients`).
Real lift depends on S and saturates; the lab's constant k_M makes it grow with spin alone, so
that one constant cannot fit both a driver (S ≈ 0.07 at launch) and a wedge (S ≈ 0.45).
Spin decay keeps the law above.

With ``air.model = "spin_reynolds"`` (γ = 2) drag also depends on the Reynolds number
Re = ρ|v_rel|·2R/μ (μ = ``air.viscosity``): a dimpled ball's drag crisis, C_D rising as the ball
slows late in flight; and spin decays as Smits & Smith (1994) measured it (golf_data.md):

* C_D = C_D0 + C_D1 S + C_D2 S² + ΔC_D / (1 + (Re/Re_c)⁴)        (``air.C_D_S``, ``C_D_crisis``, ``Re_crisis``)
* C_L = C_L0 + C_L1 S + C_L2 S²                                  (``air.C_L_S``)
* spin decay dω/dt = −(ρ/ρ_λ)·λ |v_rel| ω / R                    (λ = ``air.spin_decay``, ρ_λ = 1.225 kg/m³)

with S held within S_MIN–S_MAX and C_L in proportion to S below S_MIN, as for ``spin_ratio``
(:func:`spin_reynolds_coefficients`). The coefficients' defaults are fitted to the PGA Tour
averages by ``ti-golf fit-aero`` (:mod:`ti_golf.golf.aero_fit`).

Balls are integrated in *lanes*: a state matrix ``S`` of shape (10, L) holds L balls side by side,
rows x, y, z, v_x, v_y, v_z, ω_x, ω_y, ω_z and |ω|. The spin magnitude has a row of its own because
spin decay only scales ω (dω/dt ∥ ω), so d|ω|/dt = −(decay rate)·|ω| exactly and no square root of
ω is needed per force evaluation. Every operation is element-wise across the lanes, so
L independent balls fill the CPU's SIMD units and hide the latency of the square roots (L = 1 is
a single ball). ``coef`` is a (4, L) matrix with rows k_D/m, k_M/m, k_ω and R of each lane.
"""

import math
from typing import Any

import taichi as ti

from ti_golf import front_end
from ti_golf.physics.types import AirParams, log, vec, vec3
from ti_golf.scene.air import SPIN_DECAY_RHO, SPIN_RATIOS

LAB, SPIN_RATIO, SPIN_REYNOLDS = 0, 1, 2
AIR_MODEL_CODES = {"lab": LAB, "spin_ratio": SPIN_RATIO, "spin_reynolds": SPIN_REYNOLDS}
"""Kernel codes of ``air.model`` (:data:`ti_golf.scene.schema.AIR_MODELS`)."""
CONSTANT_WIND, LOG_WIND = 0, 1
WIND_PROFILE_CODES = {"constant": CONSTANT_WIND, "log": LOG_WIND}
"""Kernel codes of ``air.wind_profile`` (:data:`ti_golf.scene.schema.WIND_PROFILES`)."""
S_MIN, S_MAX = SPIN_RATIOS
"""The range of spin ratios of the C_D(S), C_L(S) fit; the coefficients are held at its ends."""
_TINY = 1e-12

X, V, W, SPIN = 0, 3, 6, 9
"""Rows of a lane state matrix: first row of position, velocity, angular velocity; spin magnitude |ω|."""
ROWS = 10


@front_end.expanded
def row(S, i: ti.template()):
    """Row ``i`` of a matrix as a vector over its columns (lanes)."""
    return front_end.float_vector(*[front_end.element(S, i, l) for l in ti.static(range(S.m))])


@front_end.expanded
def column(S, first: ti.template(), lane: ti.template()):
    """The 3-vector in rows first..first+2 of column ``lane`` (e.g. the velocity of one ball)."""
    return vec(
        front_end.element(S, first, lane), front_end.element(S, first + 1, lane), front_end.element(S, first + 2, lane)
    )


def air_params(air: Any, ground_height: float) -> Any:
    """The kernels' :data:`~.types.AirParams` of a scene's ``Air`` (see ``ti_golf.scene.schema.Air``),
    whose log wind profile measures heights from y = ``ground_height`` [m] (``world.ground_height``)."""
    if air.model in ("spin_ratio", "spin_reynolds") and air.gamma != 2:
        raise ValueError(f"air.gamma must be 2 with air.model = {air.model!r} (got {air.gamma})")
    if air.wind_profile == "log" and not 0.0 < air.wind_z0 < air.wind_height:
        raise ValueError(f"air.wind_z0 must lie in (0, air.wind_height) (got {air.wind_z0}, {air.wind_height})")
    return AirParams(
        rho=air.rho,
        gamma=air.gamma,
        C_D=air.C_D,
        C_M=air.C_M,
        omega_M=air.omega_M,
        C_omega=air.C_omega,
        wind=vec3(*air.wind),
        viscosity=air.viscosity,
        wind_height=air.wind_height,
        wind_z0=air.wind_z0,
        ground_height=ground_height,
        C_D_S=vec3(*air.C_D_S),
        C_L_S=vec3(*air.C_L_S),
        C_D_crisis=air.C_D_crisis,
        Re_crisis=air.Re_crisis,
        spin_decay=air.spin_decay,
    )


@ti.func
def coefficients(air, kinds: ti.template(), radius, mass):
    """(4, L) matrix of k_D/m, k_M/m, k_ω [1/m] and R [m] for lanes of radius [m] and mass [kg];
    with the spin-ratio models the first two rows are ½ρA/m, which :func:`rates` multiplies by
    C_D and C_L/|ω|, and with ``spin_reynolds`` k_ω is (ρ/ρ_λ)·λ/R (``SPIN_DECAY_RHO``)."""
    half_rho_A = 0.5 * air.rho * math.pi * radius * radius
    c_D, c_M = air.C_D, air.C_M / air.omega_M
    k_omega = half_rho_A * air.C_omega / mass
    if ti.static(kinds.air_model != LAB):
        c_D, c_M = 1.0, 1.0
    if ti.static(kinds.air_model == SPIN_REYNOLDS):
        k_omega = air.spin_decay / radius * (air.rho / SPIN_DECAY_RHO)
    return ti.Matrix.rows(
        [
            half_rho_A * c_D / mass,
            half_rho_A * c_M / mass,
            k_omega,
            radius,
        ]
    )


@ti.func
def spin_ratio_coefficients(s):
    """(C_D, C_L) at spin ratios ``s`` (lanes): the fit of Ferguson, McNally & McPhee (2022) over
    S_MIN ≤ S ≤ S_MAX, held at its ends, C_L times S/S_MIN below S_MIN (no spin, no lift)."""
    c = ti.min(ti.max(s, S_MIN), S_MAX)
    C_D = 0.1304 + c * (0.9287 - 0.8259 * c)
    C_L = (0.0504 + c * (1.2031 - 1.1490 * c)) * ti.min(s / S_MIN, 1.0)
    return C_D, C_L


@ti.func
def wind_scale(y, air, kinds: ti.template()):
    """u(z)/|wind| at heights ``y`` [m] (a vector over lanes): 1 with the constant profile; with
    the log profile ln(z/z₀)/ln(z_ref/z₀) for z = y − ground_height > z₀, else 0."""
    scale = ti.Vector([1.0 for _ in ti.static(range(y.n))], dt=float)
    if ti.static(kinds.wind_profile == LOG_WIND):
        z0 = air.wind_z0
        scale = log(ti.max(y - air.ground_height, z0) / z0) / log(air.wind_height / z0)
    return scale


@ti.func
def spin_reynolds_coefficients(s, re, air):
    """(C_D, C_L) at spin ratios ``s`` and Reynolds numbers ``re`` (lanes): quadratics in S held
    within S_MIN ≤ S ≤ S_MAX (C_L times S/S_MIN below S_MIN), C_D raised by the drag crisis
    C_D_crisis/(1 + (Re/Re_crisis)⁴)."""
    c = ti.min(ti.max(s, S_MIN), S_MAX)
    r2 = (re / air.Re_crisis) ** 2
    C_D = air.C_D_S[0] + c * (air.C_D_S[1] + air.C_D_S[2] * c) + air.C_D_crisis / (1.0 + r2 * r2)
    C_L = (air.C_L_S[0] + c * (air.C_L_S[1] + air.C_L_S[2] * c)) * ti.min(s / S_MIN, 1.0)
    return C_D, C_L


@ti.func
def rates(S, coef, air, kinds: ti.template(), gravity):
    """dS/dt of a lane state matrix S (10, L): (v, dv/dt [m/s²], dω/dt [rad/s²], d|ω|/dt) per lane."""
    vx, vy, vz = row(S, 3), row(S, 4), row(S, 5)
    wx, wy, wz = row(S, 6), row(S, 7), row(S, 8)
    u = wind_scale(row(S, 1), air, kinds)
    rx, ry, rz = vx - u * air.wind[0], vy - u * air.wind[1], vz - u * air.wind[2]
    speed = ti.sqrt(rx * rx + ry * ry + rz * rz)
    drag = row(coef, 0)
    decay = row(coef, 2)
    if air.gamma == 2:
        drag = drag * speed
        decay = decay * (speed + row(coef, 3) * row(S, SPIN))
    lift = row(coef, 1) * speed
    if ti.static(kinds.air_model != LAB):  # (γ = 2: the scene is checked when read)
        spin = row(S, SPIN)
        s = row(coef, 3) * spin / ti.max(speed, _TINY)
        C_D, C_L = 0.0 * s, 0.0 * s
        if ti.static(kinds.air_model == SPIN_REYNOLDS):
            C_D, C_L = spin_reynolds_coefficients(s, (2.0 * air.rho / air.viscosity) * row(coef, 3) * speed, air)
            decay = row(coef, 2) * speed  # λ|v_rel|/R
        else:
            C_D, C_L = spin_ratio_coefficients(s)
        drag = row(coef, 0) * C_D * speed
        lift = row(coef, 1) * C_L * speed / ti.max(spin, _TINY)  # |ω × v_rel|/|ω| = |v_rel| at right angles
    return ti.Matrix.rows(
        [
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
        ]
    )
