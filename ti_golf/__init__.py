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

from __future__ import annotations

import os
from importlib import import_module
from typing import TYPE_CHECKING, Any

from ti_golf import front_end
from ti_golf.errors import ConfigError, SimulationError, TiGolfError

# Taichi reads these when it is imported, by whichever module imports it first: its banner would
# spoil standard output (JSON), and its notes below warnings would be noise
os.environ.setdefault("ENABLE_TAICHI_HEADER_PRINT", "0")
os.environ.setdefault("TI_LOG_LEVEL", "warn")
front_end.quicken_taichi_import()  # (its own decorators' method test, while Taichi is imported)

if TYPE_CHECKING:  # pragma: no cover
    from ti_golf.golf.sweep import SweepResult, sweep
    from ti_golf.runtime import init
    from ti_golf.scene.loader import load_scene
    from ti_golf.scene.schema import AT_REST, FLYING, OUT_OF_BOUNDS, ROLLING, Scene
    from ti_golf.sim.results import Overlap, Recording
    from ti_golf.sim.simulation import Simulation

_LAZY = {
    "init": "ti_golf.runtime",
    "load_scene": "ti_golf.scene.loader",
    **dict.fromkeys(("AT_REST", "FLYING", "OUT_OF_BOUNDS", "ROLLING", "Scene"), "ti_golf.scene.schema"),
    **dict.fromkeys(("Overlap", "Recording"), "ti_golf.sim.results"),
    "Simulation": "ti_golf.sim.simulation",
    **dict.fromkeys(("SweepResult", "sweep"), "ti_golf.golf.sweep"),
}
"""The public names imported on first use, each from its module: ``import ti_golf`` (and every
``ti-golf`` command, which imports the package first) then costs no Taichi, numpy or matplotlib
import until one is used (``ti-golf keys`` starts in a fraction of a second)."""


def __getattr__(name: str) -> Any:
    if name == "__version__":
        globals()[name] = value = _version()
        return value
    if name in _LAZY:
        value = getattr(import_module(_LAZY[name]), name)
        globals()[name] = value  # (found directly from now on)
        return value
    raise AttributeError(f"module 'ti_golf' has no attribute {name!r}")


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


def _version() -> str:
    """The installed distribution's version (``version`` in pyproject.toml, the one place it is
    set), read on first use of ``ti_golf.__version__`` (importlib.metadata costs some 20 ms)."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("ti-golf")
    except PackageNotFoundError:  # a source tree on sys.path, not installed
        return "0+unknown"
