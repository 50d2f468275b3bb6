"""``ti-golf bench render``: seconds per off-screen picture of many balls over a terrain."""

from __future__ import annotations

import os
import tempfile
import time
from collections.abc import Callable
from typing import Any

import numpy as np

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
    """Seconds per off-screen frame of n balls over a generated terrain (GGUI), with the matplotlib
    fallback timed in the same run as the baseline."""
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
    out: dict[str, Any] = {"benchmark": "render", "n": n, "size": list(size), "arch": info.arch}
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "frame.png")
        for backend, key in (("auto", "seconds_per_frame"), ("matplotlib", "matplotlib")):
            used = render(sim, path, camera="iso", size=size, backend=backend)  # first frame: window, compile
            t0 = time.perf_counter()
            for _ in range(frames if key == "seconds_per_frame" else 1):
                render(sim, path, camera="iso", size=size, backend=backend)
            per_frame = (time.perf_counter() - t0) / (frames if key == "seconds_per_frame" else 1)
            if key == "seconds_per_frame":
                out["seconds_per_frame"], out["renderer"] = per_frame, used
            else:
                out["baselines"] = {"matplotlib_seconds_per_frame": per_frame}
    log(
        f"ti_golf render: {n} balls + terrain at {size[0]}x{size[1]}: {out['seconds_per_frame']:.3f} s/frame "
        f"({out['renderer']}); matplotlib {out['baselines']['matplotlib_seconds_per_frame']:.3f} s/frame"
    )
    return out
