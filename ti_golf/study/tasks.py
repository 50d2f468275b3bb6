"""One task of a study, run in this process: its scene built, the application run, its figures.

The one module of the study layer that imports the applications (the simulation, sweeps, shots,
dispersion, the tour table and the pit benchmark), so that where they live is written here alone.
The process's Taichi runtime must be initialised first (:mod:`ti_golf.study.worker` does it once
per worker process).
"""

from __future__ import annotations

import dataclasses
import math
import os
import signal
import time
from pathlib import Path
from typing import Any

import numpy as np

from ti_golf.bench.pit import bench_pit, pile_quality
from ti_golf.golf.dispersion import PLAYER_SPREAD, dispersion
from ti_golf.golf.rollout import has_ground
from ti_golf.golf.shots import shots
from ti_golf.golf.sweep import sweep
from ti_golf.golf.tour import fly_tour
from ti_golf.golf.trackman import TOURS, YD
from ti_golf.scene.balls import scaled_block
from ti_golf.scene.launch_monitor import along, right_of, scene_launch, target_direction
from ti_golf.scene.loader import load_scene
from ti_golf.scene.schema import OUT_OF_BOUNDS, Scene
from ti_golf.sim.results import Flight, Shots
from ti_golf.sim.simulation import Simulation
from ti_golf.study.figures import FIGURES, landed_mean, pile_height, repose_angle

KILL_ONCE_ENV = "TI_GOLF_STUDY_KILL_ONCE"
"""For the tests of a worker lost mid-task: when this environment variable names a file that does
not exist yet, the first run task to pass its first stretch of steps makes the file and kills its
own process (SIGKILL), as a crashed or pre-empted node would."""


def task_scene(task: dict[str, Any]) -> Scene:
    """The task's scene: the base scene with the task's changes, its seed in every random block,
    and its random block scaled to ``task.balls``."""
    scene = load_scene(task["scene"], task["changes"])
    if task["task"]["kind"] != "run":
        return scene
    if task["seed"] is not None:
        blocks = tuple(dataclasses.replace(b, seed=task["seed"]) if b.kind == "random" else b for b in scene.blocks)
        scene = dataclasses.replace(scene, blocks=blocks)
    if task["task"]["balls"] is not None:
        scene = scaled_block(scene, task["task"]["balls"])
    return scene


def execute(task: dict[str, Any], run_dir: str | None) -> dict[str, Any]:
    """Run one task (:meth:`~ti_golf.study.spec.TaskSpec.as_dict`) here; returns its figures by
    column, ``sim_wall_s`` and ``run_path`` (the saved run, or ``""``)."""
    kind = task["task"]["kind"]
    out: dict[str, Any] = {"run_path": ""}
    t0 = time.perf_counter()
    if kind == "pit":
        opts = task["task"]
        result = bench_pit(n=opts["balls"], t=opts["t"] or 4.0, overrides=task["changes"], log=lambda line: None)
        figures = {"deepest_overlap": result["deepest_overlap"], "p99_speed": result["p99_speed_mps"]}
        out["sim_wall_s"] = result["wall_s"]
        return _pick(task, figures, out)
    scene = task_scene(task)
    if kind == "run":
        figures, path = _run(task, scene, run_dir)
        out["run_path"] = path
    elif kind == "sweep":
        res = sweep(scene)
        best = res.best()
        figures = _shot_figures(res.shots, np.arange(res.shots.carry.size) == best) if res.shots else {}
    elif kind == "shot":
        figures = _shot_figures(shots(scene, scene_launch(scene), to_rest=has_ground(scene)))
    elif kind == "dispersion":
        seed = 0 if task["seed"] is None else task["seed"]
        d = dispersion(
            scene, scene_launch(scene), PLAYER_SPREAD, task["task"]["shots"], seed, to_rest=has_ground(scene)
        )
        figures = _shot_figures(d.shots)
    elif kind == "tour":
        flight = fly_tour(scene, TOURS[task["task"]["tour"]])
        figures = {}
        for name, values in (("carry", flight.carry * YD), ("apex", flight.apex * YD), ("landing_angle", flight.land)):
            for row, value in zip(flight.rows, values):
                figures[f"{name}[{row.name}]"] = float(value)
    else:  # pragma: no cover - the spec allows no other
        raise ValueError(f"unknown task kind {kind!r}")
    out.setdefault("sim_wall_s", time.perf_counter() - t0)
    return _pick(task, figures, out)


def _pick(task: dict[str, Any], figures: dict[str, float], out: dict[str, Any]) -> dict[str, Any]:
    """The figures the task asked for, by column (``carry[PGA Driver]`` -> ``carry_m[PGA Driver]``)."""
    wanted = set(task["figures"])
    for name, value in figures.items():
        base, _, club = name.partition("[")
        if base in wanted:
            column = FIGURES[base].column + (f"[{club}" if club else "")
            out[column] = float(value)
    if "wall_time" not in wanted:
        out.pop("sim_wall_s", None)
    return out


def _shot_figures(s: Shots, which: np.ndarray | None = None) -> dict[str, float]:
    """Carry, apex, land angle and offline of shots (a mean over those landed, or of ``which``)."""
    landed = s.landed if which is None else (s.landed & which)
    return {
        "carry": landed_mean(s.carry, landed),
        "apex": landed_mean(s.apex, landed),
        "landing_angle": landed_mean(s.land_angle, landed),
        "lateral_offset": landed_mean(s.offline, landed),
    }


def _run(task: dict[str, Any], scene: Scene, run_dir: str | None) -> tuple[dict[str, float], str]:
    """A run of the scene as ``ti-golf run`` makes it (to task.t, task.steps or world.t_end, until
    rest or landing), its figures, and the path of its saved run."""
    opts = task["task"]
    sim = Simulation(scene)
    t0 = time.perf_counter()
    sim.run(t=opts["t"], steps=opts["steps"], until=opts["until"] or None, progress=_kill_once())
    wall = time.perf_counter() - t0
    path = ""
    if opts["save"] and run_dir is not None:
        path = str(Path(run_dir) / f"{task['id']}.npz")
        sim.save(path)
    figures = run_figures(sim)
    figures["wall_time"] = wall
    return figures, path


def run_figures(sim: Simulation) -> dict[str, float]:
    """The figures of a simulation where it stands: its flight (a mean over the tracked balls that
    landed), the pile's height, angle of repose, deepest overlap and 99th-percentile speed. Also
    what the tests compare with a saved ``ti-golf run``."""
    f: Flight = sim.flight()
    launch = sim.launch_x if sim.launch_x is not None else np.full((sim.n, 3), math.nan)
    target = target_direction(sim.scene)
    land = np.stack([f.landing_x - launch[:, 0], np.zeros(sim.n), f.landing_z - launch[:, 2]], axis=1)
    carry = np.copysign(f.carry, land @ along(target))  # (behind the tee: negative, as the shots' carry)
    in_play = sim.status != OUT_OF_BOUNDS
    radius = np.asarray(sim.model.radius_np, float)
    quality = pile_quality(sim, math.inf)
    return {
        "carry": landed_mean(carry, f.landed),
        "apex": landed_mean(f.apex - launch[:, 1], f.landed),
        "landing_angle": landed_mean(f.landing_angle, f.landed),
        "lateral_offset": landed_mean(land @ right_of(target), f.landed),
        "pile_height": pile_height(sim.x, radius, in_play),
        "repose_angle": repose_angle(sim.x, radius, in_play),
        "deepest_overlap": quality["deepest_overlap"],
        "p99_speed": quality["p99_speed_mps"],
    }


def _kill_once():
    """The progress callback of :data:`KILL_ONCE_ENV` (``None`` when it is not set)."""
    marker = os.environ.get(KILL_ONCE_ENV)
    if not marker:
        return None

    def progress(done: float, total: float, finished: tuple[int, int, str] | None = None) -> None:
        try:
            fd = os.open(marker, os.O_CREAT | os.O_EXCL | os.O_WRONLY)
        except FileExistsError:
            return
        os.close(fd)
        os.kill(os.getpid(), signal.SIGKILL)

    return progress
