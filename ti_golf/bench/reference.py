"""Independent integrations of the same flight model, for benchmarks' baselines and tests.

* :func:`carry_numpy`: a vectorised numpy RK4 over all balls with the same Hermite landing as the
  kernels (the "obvious numpy code" baseline).
* :func:`carry_scipy`, :func:`landing_scipy`: one ``scipy.integrate.solve_ivp`` call per
  trajectory with event location (DOP853 at tight tolerances is the high-accuracy reference).

Model (report L.21–L.23), v_rel = v − u(y), A = πR², u the wind at the ball's height
(:func:`wind_at`: ``air.wind``, or its log profile):
dv/dt = g − (k_D/m)|v_rel|^(γ−1) v_rel + (k_M/m)|v_rel| (ω × v_rel),
dω/dt = −k_ω (|v_rel| + R|ω|)^(γ−1) ω;
with ``air.model = "spin_ratio"`` drag and lift take C_D(S) and C_L(S) of S = R|ω|/|v_rel|
(:func:`spin_ratio_coefficients`): dv/dt = g − (½ρA/m)|v_rel|·(C_D v_rel − C_L (ω × v_rel)/|ω|);
with ``air.model = "spin_reynolds"`` C_D(S, Re) and C_L(S) (:func:`spin_reynolds_coefficients`),
Re = ρ|v_rel|·2R/μ, and dω/dt = −λ|v_rel|ω/R.
"""

from __future__ import annotations

import math

import numpy as np

from ti_golf.scene.air import SPIN_DECAY_RHO
from ti_golf.scene.schema import Scene


def coefficients(scene: Scene) -> tuple[float, float, float]:
    """(k_D/m, k_M/m, k_ω) of the scene's ball."""
    a, b = scene.air, scene.ball
    half_rho_A = 0.5 * a.rho * math.pi * b.radius**2
    return half_rho_A * a.C_D / b.mass, half_rho_A * a.C_M / a.omega_M / b.mass, half_rho_A * a.C_omega / b.mass


def spin_ratio_coefficients(s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(C_D, C_L) at spin ratios ``s``: Ferguson, McNally & McPhee (2022), C_D = 0.1304 + 0.9287 S
    − 0.8259 S², C_L = 0.0504 + 1.2031 S − 1.1490 S², fitted over 0.02 ≤ S ≤ 0.75 and held at
    the ends; below S = 0.02, C_L in proportion to S (golf_data.md; physics/aero.py)."""
    c = np.clip(s, 0.02, 0.75)
    return 0.1304 + 0.9287 * c - 0.8259 * c**2, (0.0504 + 1.2031 * c - 1.1490 * c**2) * np.minimum(s / 0.02, 1.0)


def spin_reynolds_coefficients(scene: Scene, s: np.ndarray, re: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(C_D, C_L) at spin ratios ``s`` and Reynolds numbers ``re``: C_D = C_D0 + C_D1 S + C_D2 S² +
    C_D_crisis/(1 + (Re/Re_crisis)⁴), C_L = C_L0 + C_L1 S + C_L2 S², S held within 0.02–0.75 and
    C_L in proportion to S below 0.02 (physics/aero.py)."""
    a = scene.air
    c = np.clip(s, 0.02, 0.75)
    C_D = a.C_D_S[0] + a.C_D_S[1] * c + a.C_D_S[2] * c**2 + a.C_D_crisis / (1.0 + (re / a.Re_crisis) ** 4)
    C_L = (a.C_L_S[0] + a.C_L_S[1] * c + a.C_L_S[2] * c**2) * np.minimum(s / 0.02, 1.0)
    return C_D, C_L


def wind_at(scene: Scene, y: np.ndarray) -> np.ndarray:
    """The wind [m/s] (N, 3) at heights ``y`` [m] (N,): ``air.wind``, or with ``air.wind_profile =
    "log"`` wind·ln(z/z₀)/ln(z_ref/z₀) at z = y − world.ground_height above z₀, zero below."""
    a = scene.air
    wind = np.asarray(a.wind, dtype=float)[None, :]
    if a.wind_profile == "constant":
        return np.repeat(wind, len(y), axis=0)
    z = np.asarray(y, dtype=float) - scene.world.ground_height
    scale = np.where(z > a.wind_z0, np.log(np.maximum(z, a.wind_z0) / a.wind_z0), 0.0) / math.log(
        a.wind_height / a.wind_z0
    )
    return scale[:, None] * wind


def derivatives(
    scene: Scene, v: np.ndarray, w: np.ndarray, x: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """(dv/dt, dω/dt) for velocities, angular velocities and positions ``x`` of shape (N, 3)
    (``x`` may be left out when the wind does not vary with height)."""
    kD, kM, kw = coefficients(scene)
    if x is None and scene.air.wind_profile != "constant":
        raise ValueError("the log wind profile needs the positions x")
    v_rel = v - (wind_at(scene, np.asarray(x)[:, 1]) if x is not None else np.asarray(scene.air.wind))
    speed = np.sqrt(np.einsum("ij,ij->i", v_rel, v_rel))[:, None]
    spin = np.sqrt(np.einsum("ij,ij->i", w, w))[:, None]
    if scene.air.gamma == 2:
        drag = kD * speed
        decay = kw * (speed + scene.ball.radius * spin)
    else:
        drag, decay = kD, kw
    lift = kM * speed
    if scene.air.model in ("spin_ratio", "spin_reynolds"):
        R = scene.ball.radius
        half_rho_A_over_m = 0.5 * scene.air.rho * math.pi * R**2 / scene.ball.mass
        s = R * spin / np.maximum(speed, 1e-12)
        if scene.air.model == "spin_ratio":
            C_D, C_L = spin_ratio_coefficients(s)
        else:
            C_D, C_L = spin_reynolds_coefficients(scene, s, scene.air.rho * speed * 2.0 * R / scene.air.viscosity)
            decay = scene.air.spin_decay * (scene.air.rho / SPIN_DECAY_RHO) * speed / R
        drag = half_rho_A_over_m * C_D * speed
        lift = half_rho_A_over_m * C_L * speed / np.maximum(spin, 1e-12)
    dv = np.asarray(scene.world.gravity) - drag * v_rel + lift * np.cross(w, v_rel)
    return dv, -decay * w


def carry_numpy(
    scene: Scene, x0: np.ndarray, v0: np.ndarray, w0: np.ndarray, h: float, t_max: float | None = None
) -> np.ndarray:
    """Carry [m] of each ball by vectorised RK4 with step ``h`` and cubic-Hermite landing; NaN if not landed."""
    t_max = scene.world.t_max if t_max is None else t_max
    x, v, w = (np.array(a, dtype=float) for a in (x0, v0, w0))
    level = x[:, 1].copy()
    carry = np.full(len(x), np.nan)
    idx = np.arange(len(x))
    t = 0.0
    while idx.size and t < t_max:
        xa, va, wa = x[idx], v[idx], w[idx]
        a1, b1 = derivatives(scene, va, wa, xa)
        v2, w2 = va + 0.5 * h * a1, wa + 0.5 * h * b1
        a2, b2 = derivatives(scene, v2, w2, xa + 0.5 * h * va)
        v3, w3 = va + 0.5 * h * a2, wa + 0.5 * h * b2
        a3, b3 = derivatives(scene, v3, w3, xa + 0.5 * h * v2)
        v4, w4 = va + h * a3, wa + h * b3
        a4, b4 = derivatives(scene, v4, w4, xa + h * v3)
        x1 = xa + h / 6 * (va + 2 * v2 + 2 * v3 + v4)
        v1 = va + h / 6 * (a1 + 2 * a2 + 2 * a3 + a4)
        w1 = wa + h / 6 * (b1 + 2 * b2 + 2 * b3 + b4)
        lv = level[idx]
        hit = (xa[:, 1] >= lv) & (x1[:, 1] < lv)
        if np.any(hit):
            s = _hermite_root(xa[hit, 1], x1[hit, 1], h * va[hit, 1], h * v1[hit, 1], lv[hit])
            p = _hermite(xa[hit], x1[hit], h * va[hit], h * v1[hit], s[:, None])
            d = p - np.asarray(x0)[idx[hit]]
            carry[idx[hit]] = np.hypot(d[:, 0], d[:, 2])
        x[idx], v[idx], w[idx] = x1, v1, w1
        idx = idx[~hit]
        t += h
    return carry


def _hermite(p0, p1, m0, m1, s):
    s2, s3 = s * s, s * s * s
    return (2 * s3 - 3 * s2 + 1) * p0 + (s3 - 2 * s2 + s) * m0 + (3 * s2 - 2 * s3) * p1 + (s3 - s2) * m1


def _hermite_root(y0, y1, m0, m1, level):
    s = (y0 - level) / (y0 - y1)
    for _ in range(8):
        f = _hermite(y0, y1, m0, m1, s) - level
        s2 = s * s
        df = (6 * s2 - 6 * s) * y0 + (3 * s2 - 4 * s + 1) * m0 + (6 * s - 6 * s2) * y1 + (3 * s2 - 2 * s) * m1
        s = np.clip(s - f / np.where(df == 0, 1.0, df), 0.0, 1.0)
    return s


def carry_scipy(
    scene: Scene,
    x0: np.ndarray,
    v0: np.ndarray,
    w0: np.ndarray,
    method: str = "DOP853",
    rtol: float = 1e-12,
    atol: float = 1e-12,
    t_max: float | None = None,
) -> np.ndarray:
    """Carry [m] of each ball by ``solve_ivp`` (one call per trajectory) with an exact landing event."""
    p = landing_scipy(scene, x0, v0, w0, method, rtol, atol, t_max)
    d = p - np.asarray(x0, dtype=float)
    return np.hypot(d[:, 0], d[:, 2])


def landing_scipy(
    scene: Scene,
    x0: np.ndarray,
    v0: np.ndarray,
    w0: np.ndarray,
    method: str = "DOP853",
    rtol: float = 1e-12,
    atol: float = 1e-12,
    t_max: float | None = None,
) -> np.ndarray:
    """Landing points [m] (N, 3) of each ball, where it comes down through its launch height, by
    ``solve_ivp`` (one call per trajectory) with an exact event; NaN where it has not landed."""
    from scipy.integrate import solve_ivp  # scipy is optional (the bench and test extras): imported on use

    t_max = scene.world.t_max if t_max is None else t_max
    out = np.full((len(x0), 3), np.nan)
    for i in range(len(x0)):
        level = float(x0[i][1])

        def rhs(_t: float, y: np.ndarray) -> np.ndarray:
            dv, dw = derivatives(scene, y[3:6][None, :], y[6:9][None, :], y[0:3][None, :])
            return np.concatenate([y[3:6], dv[0], dw[0]])

        def landing(_t: float, y: np.ndarray, level: float = level) -> float:
            return y[1] - level

        landing.terminal, landing.direction = True, -1  # type: ignore[attr-defined]
        y0 = np.concatenate([x0[i], v0[i], w0[i]]).astype(float)
        sol = solve_ivp(rhs, (0.0, t_max), y0, method=method, rtol=rtol, atol=atol, events=landing)
        if sol.t_events[0].size:
            out[i] = sol.y_events[0][0][0:3]
    return out
