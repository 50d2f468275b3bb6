"""``ti-golf bench sweep``: a data-parallel sweep against numpy and scipy baselines timed in the same run."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from typing import Any

import numpy as np

from ti_golf.bench.common import _best_time, faster
from ti_golf.bench.reference import carry_numpy, carry_scipy
from ti_golf.golf.sweep import fly
from ti_golf.runtime import ensure_init
from ti_golf.scene.schema import (
    Air,
    Ball,
    Launch,
    Scene,
    SweepDefaults,
    World,
)


def bench_scene(dt: float = 0.1) -> Scene:
    """The full model: turbulent drag, Magnus (lab coefficients), spin decay and a quartering wind."""
    return Scene(
        name="bench_sweep",
        description="benchmark: turbulent drag + Magnus + spin decay + wind",
        air=Air(rho=1.3, gamma=2, C_D=0.3, C_M=0.025, omega_M=1.0, C_omega=1.0, wind=(-3.0, 0.0, 1.5)),
        ball=Ball(mass=0.045, radius=0.02),
        launch=Launch(speed=70.0, angle_deg=15.0, spin=(0.0, 0.0, 10.0)),
        world=World(dt=dt, integrator="rk4", t_max=60.0),
        sweep=SweepDefaults(),
    )


def bench_conditions(n: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``n`` seeded random launches: angle 5–45°, speed 40–80 m/s, backspin 0–15 rad/s, azimuth ±10°."""
    rng = np.random.default_rng(seed)
    th = np.radians(rng.uniform(5.0, 45.0, n))
    ph = np.radians(rng.uniform(-10.0, 10.0, n))
    speed = rng.uniform(40.0, 80.0, n)
    spin = rng.uniform(0.0, 15.0, n)
    x0 = np.tile([0.0, 0.02, 0.0], (n, 1))
    v0 = np.stack([speed * np.cos(th) * np.cos(ph), speed * np.sin(th), speed * np.cos(th) * np.sin(ph)], axis=1)
    w0 = spin[:, None] * np.stack([-np.sin(ph), np.zeros(n), np.cos(ph)], axis=1)
    return x0, v0, w0


def bench_sweep(
    n: int = 100_000,
    dt: float = 0.1,
    repeats: int = 3,
    n_reference: int = 64,
    n_numpy: int | None = None,
    n_scipy: int = 100,
    log: Callable[[str], None] = print,
) -> dict[str, Any]:
    """Time a data-parallel sweep of ``n`` launches and compare with numpy and scipy baselines.

    Returns the JSON-able result (``trajectories_per_s``, ``max_rel_carry_error``, ``baselines``, ...).
    """
    info = ensure_init()
    scene = bench_scene(dt)
    x0, v0, w0 = bench_conditions(n)
    fly(scene, x0[:16], v0[:16], w0[:16])  # compile outside the timing
    raw: dict[str, np.ndarray] = {}

    def run() -> None:
        raw.update(fly(scene, x0, v0, w0))

    seconds = _best_time(run, repeats)
    landed = raw["landed"] == 1
    d = raw["land_x"] - x0
    carry = np.where(landed, np.hypot(d[:, 0], d[:, 2]), np.nan)
    log(
        f"ti_golf sweep: {n} trajectories in {seconds:.3f} s ({n / seconds:,.0f}/s, best of {repeats}), "
        f"arch={info.arch}, {info.precision}, RK4 h={dt} s"
    )

    rng = np.random.default_rng(1)
    pick = rng.choice(n, size=min(n_reference, n), replace=False)
    ref = carry_scipy(replace(scene, world=replace(scene.world, t_max=60.0)), x0[pick], v0[pick], w0[pick])
    rel = np.abs(carry[pick] - ref) / np.abs(ref)
    max_rel = float(np.nanmax(rel)) if np.all(np.isfinite(rel)) else float("inf")
    log(f"max relative carry error vs scipy DOP853 (rtol 1e-12) on {pick.size} trajectories: {max_rel:.2e}")

    k_np = n if n_numpy is None else min(n_numpy, n)
    t_np = _best_time(lambda: carry_numpy(scene, x0[:k_np], v0[:k_np], w0[:k_np], dt), 1)
    k_sp = min(n_scipy, n)
    t_sp = _best_time(lambda: carry_scipy(scene, x0[:k_sp], v0[:k_sp], w0[:k_sp], rtol=1e-9, atol=1e-9), 1)
    baselines = {"numpy_rk4_vectorised": k_np / t_np, "scipy_solve_ivp_dop853": k_sp / t_sp}
    tps = n / seconds
    for name, rate in baselines.items():
        log(f"baseline {name}: {rate:,.0f} trajectories/s -> ti_golf is {faster(tps / rate)}")
    return {
        "benchmark": "sweep",
        "n": n,
        "dt_s": dt,
        "integrator": "rk4",
        "arch": info.arch,
        "precision": info.precision,
        "seconds": seconds,
        "trajectories_per_s": tps,
        "max_rel_carry_error": max_rel,
        "landed_fraction": float(np.mean(landed)),
        "baselines": baselines,
        "speedup": {name: tps / rate for name, rate in baselines.items()},
        "baseline_sizes": {"numpy_rk4_vectorised": k_np, "scipy_solve_ivp_dop853": k_sp},
    }
