"""``ti-golf bench render``: seconds per off-screen picture of many balls over a terrain."""

from __future__ import annotations

import functools
import os
import tempfile
from collections.abc import Callable
from typing import Any

import numpy as np

from ti_golf.bench.common import _best_time
from ti_golf.render import render
from ti_golf.runtime import ensure_init
from ti_golf.scene.schema import (
    Scene,
    TerrainConfig,
    World,
)
from ti_golf.sim.simulation import Simulation


def bench_render(
    n: int = 100_000, size: tuple[int, int] = (1280, 720), frames: int = 3, log: Callable[[str], None] = print
) -> dict[str, Any]:
    """Seconds per off-screen frame of n balls over a generated terrain at ``size`` (width, height)
    [pixels] with GGUI (``seconds_per_frame``), and with the matplotlib fallback timed in the same
    run as the baseline: the best of ``frames`` frames each, after an untimed first frame (GGUI's
    window, the kernels). GGUI is asked for by name, so a process where it cannot draw raises
    :class:`~ti_golf.render.RenderError` instead of timing matplotlib twice."""
    info = ensure_init()
    side = int(np.ceil(np.sqrt(n / 10.0)))
    scene = Scene(
        name="bench_render",
        description=f"benchmark: {n} balls over a terrain",
        launch=None,
        world=World(dt=0.001, integrator="semi_implicit", ground=False),
        terrain=TerrainConfig(
            kind="generated",
            origin=(-1.0, 0.0, -1.0),
            size=(2.0 + 0.05 * side, 2.0 + 0.05 * side),
            resolution=(129, 129),
            amplitude=0.3,
            seed=3,
        ),
    )
    idx = np.arange(n)
    x = np.stack([0.05 * (idx % side), 0.6 + 0.05 * (idx // (side * side)), 0.05 * ((idx // side) % side)], axis=1)
    sim = Simulation(scene, x=x)
    out: dict[str, Any] = {
        "benchmark": "render",
        "n": n,
        "size": list(size),
        "arch": info.arch,
        "precision": info.precision,
        "frames": frames,
    }
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "frame.png")
        seconds: dict[str, float] = {}
        for backend in ("ggui", "matplotlib"):
            draw = functools.partial(render, sim, path, camera="iso", size=size, backend=backend)
            draw()  # the first frame: GGUI's window, the kernels
            seconds[backend] = _best_time(draw, frames)
    out["seconds_per_frame"], out["renderer"] = seconds["ggui"], "ggui"
    out["baselines"] = {"matplotlib_seconds_per_frame": seconds["matplotlib"]}
    log(
        f"ti_golf render: {n} balls + terrain at {size[0]}x{size[1]}: {out['seconds_per_frame']:.3f} s/frame "
        f"({out['renderer']}); matplotlib {out['baselines']['matplotlib_seconds_per_frame']:.3f} s/frame "
        f"(the best of {frames} frames each)"
    )
    return out
