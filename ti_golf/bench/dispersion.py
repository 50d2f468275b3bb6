"""``ti-golf bench dispersion``: a player's shots to landing and to rest, with baselines timed in
the same run and the accuracy of what is timed."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from typing import Any

import numpy as np

from ti_golf.bench.common import _best_time, faster
from ti_golf.bench.reference import carry_numpy, landing_scipy
from ti_golf.golf.dispersion import PLAYER_SPREAD, draw_launches
from ti_golf.golf.rollout import roll_out
from ti_golf.golf.sweep import fly
from ti_golf.runtime import ensure_init
from ti_golf.scene.balls import launch_position
from ti_golf.scene.launch_monitor import scene_launch, target_direction
from ti_golf.scene.loader import load_scene
from ti_golf.scene.schema import Scene
from ti_golf.sim.simulation import Simulation

SCENE = "tour_shot"
"""The bundled scene the benchmark flies: a PGA Tour 7-iron landing on turf."""


def _with_dt(scene: Scene, dt: float) -> Scene:
    return replace(scene, world=replace(scene.world, dt=dt))


def bench_dispersion(
    n: int = 100_000,
    rest: int = 10_000,
    flight_dt: float = 0.01,
    seed: int = 0,
    n_reference: int = 32,
    n_single: int = 20,
    n_numpy: int = 5_000,
    n_scipy: int = 20,
    n_compare: int = 8,
    log: Callable[[str], None] = print,
) -> dict[str, Any]:
    """Time ``n`` shots of the tour 7-iron with the default player spread to landing, at the
    scene's ``world.dt`` and at ``flight_dt`` [s], a coarser step (``ValueError`` otherwise), and
    ``rest`` of them from their landings at ``world.dt`` to rest.

    Baselines timed in the same run, on the same shots: the engine called once per shot, a
    vectorised numpy RK4 at the scene's step, and scipy ``solve_ivp`` (DOP853, rtol 1e-9) per shot.
    Quality: the largest carry and offline errors of ``n_reference`` shots against DOP853 at
    rtol = atol = 1e-12, at each timed step; and the largest distance between the points of rest of
    the two-phase path (lanes to landing, then the roll-out) and one step-by-step Simulation from
    the tee, for ``n_compare`` shots.
    """
    info = ensure_init()
    scene = load_scene(SCENE)
    if not flight_dt > scene.world.dt:  # (also true for NaN)
        raise ValueError(f"flight_dt must be coarser than {SCENE}'s world.dt = {scene.world.dt:g} s (got {flight_dt})")
    mean = scene_launch(scene)
    launches = draw_launches(mean, PLAYER_SPREAD, n, seed)
    v0, w0 = launches.vectors(target_direction(scene))
    x0 = np.tile(np.asarray(launch_position(scene), float), (n, 1))
    rng = np.random.default_rng(1)
    pick = rng.choice(n, size=min(n_reference, n), replace=False)
    ref = landing_scipy(scene, x0[pick], v0[pick], w0[pick])
    log(
        f"bench dispersion: {n:,} shots of {SCENE} (7-iron, the default spread), arch={info.arch}, {info.precision}, "
        f"{scene.world.integrator}"
    )

    landing: dict[str, dict[str, float]] = {}
    flights: dict[float, dict[str, np.ndarray]] = {}  # each step's landings: the roll-out starts from world.dt's
    for dt in (scene.world.dt, flight_dt):
        flown = _with_dt(scene, dt)
        fly(flown, x0[:16], v0[:16], w0[:16])  # compile outside the timing
        raw: dict[str, np.ndarray] = flights.setdefault(dt, {})

        def run(flown: Scene = flown, raw: dict[str, np.ndarray] = raw) -> None:
            raw.update(fly(flown, x0, v0, w0))

        seconds = _best_time(run, 1)
        d = raw["land_x"][pick] - ref
        landing[f"dt_{dt:g}"] = {
            "dt_s": dt,
            "seconds": seconds,
            "shots_per_s": n / seconds,
            "max_carry_error_m": float(
                np.nanmax(np.abs(_carry(raw["land_x"][pick], x0[pick]) - _carry(ref, x0[pick])))
            ),
            "max_offline_error_m": float(np.nanmax(np.abs(d[:, 2]))),
            "landed_fraction": float(np.mean(raw["landed"] == 1)),
        }
        r = landing[f"dt_{dt:g}"]
        log(
            f"to landing, RK4 h = {dt:g} s: {seconds:.2f} s ({r['shots_per_s']:,.0f} shots/s); "
            f"largest error vs DOP853 over {pick.size} shots: carry {r['max_carry_error_m']:.1e} m, "
            f"offline {r['max_offline_error_m']:.1e} m"
        )

    out: dict[str, Any] = {
        "benchmark": "dispersion",
        "scene": SCENE,
        "n": n,
        "arch": info.arch,
        "precision": info.precision,
        "integrator": scene.world.integrator,
        "landing": landing,
    }
    k = min(rest, n)
    if k > 0:
        fine_raw = flights[scene.world.dt]
        x, v, w = (fine_raw[key][:k].astype(np.float64) for key in ("land_x", "land_v", "land_w"))
        roll_out(scene, x[:16], v[:16], w[:16])  # compile outside the timing
        box: list[Any] = []
        seconds = _best_time(lambda: box.append(roll_out(scene, x, v, w)), 1)
        at_rest = box[-1][1]
        fine = landing[f"dt_{scene.world.dt:g}"]["shots_per_s"]
        per_shot = 1.0 / fine + seconds / k
        gap = _two_phase_gap(scene, x0[:n_compare], v0[:n_compare], w0[:n_compare])
        out["rest"] = {
            "n": k,
            "roll_out_seconds": seconds,
            "roll_out_shots_per_s": k / seconds,
            "shots_per_s_tee_to_rest": 1.0 / per_shot,
            "at_rest_fraction": float(np.mean(at_rest)),
            "max_rest_gap_vs_one_simulation_m": gap,
        }
        log(
            f"landing to rest (world.dt = {scene.world.dt:g} s, no ball-ball contact): {k:,} shots in {seconds:.2f} s "
            f"({k / seconds:,.0f} shots/s); tee to rest {1.0 / per_shot:,.0f} shots/s; rest points within "
            f"{gap * 1000:.1f} mm of one Simulation from the tee ({n_compare} shots)"
        )

    dt0 = scene.world.dt
    k1 = min(n_single, n)
    fly(scene, x0[:1], v0[:1], w0[:1], lanes=1)  # compile the one-lane kernel outside the timing
    t1 = _best_time(lambda: [fly(scene, x0[i : i + 1], v0[i : i + 1], w0[i : i + 1], lanes=1) for i in range(k1)], 1)
    k_np = min(n_numpy, n)
    t_np = _best_time(lambda: carry_numpy(scene, x0[:k_np], v0[:k_np], w0[:k_np], dt0), 1)
    k_sp = min(n_scipy, n)
    t_sp = _best_time(lambda: landing_scipy(scene, x0[:k_sp], v0[:k_sp], w0[:k_sp], rtol=1e-9, atol=1e-9), 1)
    baselines = {
        "engine_one_shot_per_call": k1 / t1,
        "numpy_rk4_vectorised": k_np / t_np,
        "scipy_solve_ivp_dop853": k_sp / t_sp,
    }
    fastest = landing[f"dt_{dt0:g}"]["shots_per_s"]
    for name, rate in baselines.items():
        log(
            f"baseline {name}: {rate:,.0f} shots/s to landing -> the lanes at h = {dt0:g} s are {faster(fastest / rate)}"
        )
    out["baselines"] = baselines
    out["baseline_sizes"] = {
        "engine_one_shot_per_call": k1,
        "numpy_rk4_vectorised": k_np,
        "scipy_solve_ivp_dop853": k_sp,
    }
    out["speedup"] = {name: fastest / rate for name, rate in baselines.items()}
    return out


def _carry(land: np.ndarray, x0: np.ndarray) -> np.ndarray:
    """Horizontal distance [m] from launch points to landing points, both (N, 3)."""
    d = land - x0
    return np.hypot(d[:, 0], d[:, 2])


def _two_phase_gap(scene: Scene, x0: np.ndarray, v0: np.ndarray, w0: np.ndarray) -> float:
    """Largest distance [m] between the points of rest of the two-phase path (lanes to landing at
    ``world.dt``, roll-out) and of one Simulation from the tee, shots without ball-ball contact."""
    raw = fly(scene, x0, v0, w0)
    land_x, land_v, land_w = (raw[k].astype(np.float64) for k in ("land_x", "land_v", "land_w"))
    rest, _ = roll_out(scene, land_x, land_v, land_w)
    sim = Simulation(replace(scene, world=replace(scene.world, collisions=False)), x=x0, v=v0, w=w0, track=False)
    sim.run(t=scene.world.t_max, until="rest")
    return float(np.max(np.linalg.norm(rest - sim.x, axis=1)))
