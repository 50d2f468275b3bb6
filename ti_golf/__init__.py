"""ti_golf: golf-ball physics as a Taichi data-parallel particle engine.

Quick start::

    import numpy as np
    import ti_golf as tg

    res = tg.sweep("lab_turbulent", angles_deg=np.arange(36, 37.41, 0.02))
    print(res.angle_deg[res.best()], res.carry.max())

    sim = tg.Simulation.from_scene("lab_spin_decay", overrides={"launch.angle_deg": 40})
    sim.run(until="rest")
    print(sim.flight().carry, sim.counts())

Taichi is initialised on first use (CPU, f64) or explicitly with :func:`init`.
"""

from importlib.metadata import PackageNotFoundError, version

from ti_golf.errors import ConfigError, SimulationError, TiGolfError
from ti_golf.golf.sweep import SweepResult, sweep
from ti_golf.runtime import init
from ti_golf.scene.loader import load_scene
from ti_golf.scene.schema import AT_REST, FLYING, OUT_OF_BOUNDS, ROLLING, Scene
from ti_golf.sim.simulation import Overlap, Recording, Simulation

__all__ = [
    "AT_REST",
    "ConfigError",
    "FLYING",
    "OUT_OF_BOUNDS",
    "Overlap",
    "ROLLING",
    "Recording",
    "Scene",
    "Simulation",
    "SimulationError",
    "SweepResult",
    "TiGolfError",
    "init",
    "load_scene",
    "sweep",
]

try:
    __version__ = version("ti-golf")
    """The installed distribution's version (``version`` in pyproject.toml, the one place it is set)."""
except PackageNotFoundError:  # a source tree on sys.path, not installed
    __version__ = "0+unknown"
