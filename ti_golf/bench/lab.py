"""``ti-golf bench lab``: the lab's window running a scene as fast as it goes, drawn every frame
(hidden, off screen): the pace a user watches, and where each frame's wall time goes."""

from __future__ import annotations

import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from ti_golf.lab.app import Lab
from ti_golf.lab.window import LabWindow
from ti_golf.runtime import ensure_init

PARTS = ("panels", "steps", "picture", "drawing")
"""Where a frame's wall time goes (:attr:`.lab.window.LabWindow.seconds`)."""


def bench_lab(
    scene: str = "ball_pit",
    overrides: list[str] | None = None,
    seconds: float = 20.0,
    size: tuple[int, int] = (1280, 720),
    screenshot: str | Path | None = None,
    log: Callable[[str], None] = print,
) -> dict[str, Any]:
    """Run ``scene`` (with ``overrides``) in a hidden lab window for ``seconds`` of wall time after
    its first step (which compiles or loads the scene's kernels), frame after frame as a window on
    screen runs it at ``--speed 0``: each frame steps for at most the lab's frame budget, then draws.
    Returns the simulated seconds per wall second (``sim_s_per_wall_s``; the issue's aim for the
    100,000-ball pit on a GPU: at least 0.1), frames per second, each part's seconds per frame
    (:data:`PARTS`), and as the baseline the pace of the same run's steps alone, without the
    window's frames (``stepping_sim_s_per_wall_s``); beside them the pile's deepest overlap at the
    end. With ``screenshot``, the last frame's picture is written there (a PNG). A run that ends
    before ``seconds`` (at ``world.t_end``, every ball at rest or out, a ball non-finite) says so,
    and why, in a line of its own (``stopped``)."""
    info = ensure_init()
    lab = Lab(scene, overrides, speed=None)
    sim = lab.sim
    window = LabWindow(lab, size, show_window=False, rates=False)
    try:
        window.frame(max_steps=0)  # (the window's first picture)
        lab.start()
        start = time.perf_counter()
        window.frame(max_steps=1)
        first_frame_s = time.perf_counter() - start
        t0, steps0 = sim.t, sim.step_count
        spent = dict.fromkeys(PARTS, 0.0)
        frames = 0
        start = time.perf_counter()
        while lab.running and time.perf_counter() - start < seconds:
            window.frame()
            frames += 1
            for part in PARTS:
                spent[part] += window.seconds.get(part, 0.0)
        wall = time.perf_counter() - start
        if screenshot is not None:
            window.screenshot(screenshot)
    finally:
        window.close()
    simulated, steps = sim.t - t0, sim.step_count - steps0
    deepest = sim.deepest_overlap()
    out: dict[str, Any] = {
        "benchmark": "lab",
        "scene": lab.scene.name,
        "n": sim.n,
        "arch": info.arch,
        "size": list(size),
        "dt_s": sim.dt,
        "first_frame_s": first_frame_s,
        "wall_s": wall,
        "frames": frames,
        "frames_per_s": frames / wall if wall > 0 else 0.0,
        "steps": steps,
        "sim_s": simulated,
        "sim_s_per_wall_s": simulated / wall if wall > 0 else 0.0,
        "seconds_per_frame": {part: spent[part] / max(frames, 1) for part in PARTS},
        "stepping_share": spent["steps"] / wall if wall > 0 else 0.0,
        "baselines": {"stepping_sim_s_per_wall_s": simulated / spent["steps"] if spent["steps"] > 0 else 0.0},
        "t_s": sim.t,
        "stopped": not lab.running,
        "deepest_overlap": 0.0 if deepest is None else float(deepest.fraction),
    }
    per = out["seconds_per_frame"]
    log(
        f"{out['scene']}: {sim.n:,} balls in the lab's window ({size[0]}x{size[1]}, hidden, {info.arch}): "
        f"{frames} frames in {wall:.1f} s ({out['frames_per_s']:.2f} frames/s), t = {t0:.4g} -> {sim.t:.4g} s: "
        f"{out['sim_s_per_wall_s']:.4g} simulated s per wall s"
    )
    log(
        "a frame: "
        + ", ".join(f"{part} {1e3 * per[part]:.1f} ms" for part in PARTS)
        + f"; the steps alone: {out['baselines']['stepping_sim_s_per_wall_s']:.4g} simulated s per wall s"
    )
    log(f"deepest overlap at t = {sim.t:.4g} s: {100 * out['deepest_overlap']:.3g} % of a radius")
    if out["stopped"]:  # (the figures are those of fewer wall seconds than asked for)
        why = lab.message.removesuffix(": Continue runs on") or "the lab stopped it"
        log(f"the run stopped after {wall:.1f} of the {seconds:g} wall seconds asked for: {why}")
    return out
