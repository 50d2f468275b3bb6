"""Whether a step of ``world.dt`` can integrate each ball's drag: an explicit step diverges where
the drag acts faster than a step, and a ground under the ball hides it (a 10 m ball of a
milligram fell its 10 m in one step and lay there, exit code 0). Plain numpy, no Taichi.

The drag's rate is λ = ∂|a_D|/∂|v| = 2(k/m)|v_rel| with quadratic drag (γ = 2) and k/m with
laminar drag (γ = 1), k/m = ½ρπR²·C_D/m [1/m or 1/s], C_D the air model's greatest (the spin-ratio
fits over their range of S, with the drag crisis at its full height). An explicit Euler step of
the drag is stable while h·λ ≤ 2 (RK4's limit, 2.79, is wider). The speed is the greater of the
ball's start against the wind (|v| + |wind|) and, under gravity g, its terminal speed
v_t = √(g/(k/m)), which a falling ball reaches within about v_t/g: so h ≤ v_t/g at least.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from ti_golf.errors import ConfigError
from ti_golf.scene.air import SPIN_RATIO_C_D, SPIN_RATIOS, quadratic_range
from ti_golf.scene.schema import Scene


def greatest_C_D(scene: Scene) -> float:
    """The greatest drag coefficient of the scene's air model."""
    a = scene.air
    if a.model == "spin_ratio":
        return quadratic_range(SPIN_RATIO_C_D, *SPIN_RATIOS)[1]
    if a.model == "spin_reynolds":
        return quadratic_range(a.C_D_S, *SPIN_RATIOS)[1] + a.C_D_crisis
    return a.C_D


def check_drag_step(scene: Scene, radius: np.ndarray, mass: np.ndarray, v: np.ndarray | None) -> None:
    """Raise :class:`ConfigError` naming ``world.dt`` when a step is too long for the drag of a ball
    of radii ``radius`` [m] and masses ``mass`` [kg] (N,), starting at velocities ``v`` [m/s]
    (N, 3; ``None``: at rest)."""
    h, g = scene.world.dt, float(np.linalg.norm(scene.world.gravity))
    k = 0.5 * scene.air.rho * math.pi * np.square(radius) * greatest_C_D(scene) / mass  # k/m
    if scene.air.gamma == 1:
        h_max = 2.0 / np.maximum(k, 1e-300)
    else:
        speed = float(np.linalg.norm(scene.air.wind)) + (0.0 if v is None else np.linalg.norm(v, axis=1))
        terminal = np.sqrt(g / np.maximum(k, 1e-300))
        h_max = 1.0 / np.maximum(k * np.maximum(speed, terminal), 1e-300)
    i = int(np.argmin(h_max))
    if h > h_max[i]:
        raise ConfigError(
            *scene.where("world.dt"),
            f"= {h:g} s is too long a step for the drag of ball {i} (radius {radius[i]:g} m, mass {mass[i]:g} kg): "
            f"it must be at most {h_max[i]:.3g} s, or the explicit step of the drag diverges (a light, large ball "
            "reaches its terminal speed within a step): a smaller world.dt, or a heavier or smaller ball",
        )


def check_changed_drag_step(
    old: Scene, scene: Scene, radius: np.ndarray, mass: np.ndarray, velocities: Callable[[], np.ndarray]
) -> None:
    """:func:`check_drag_step` of ``scene``'s balls when its air, step or gravity differ from
    ``old``'s (a change of any other key leaves the drag's limit as it was, and the balls'
    velocities, read from the device by ``velocities``, are not read then)."""
    if (scene.air, scene.world.dt, scene.world.gravity) != (old.air, old.world.dt, old.world.gravity):
        check_drag_step(scene, radius, mass, velocities())
