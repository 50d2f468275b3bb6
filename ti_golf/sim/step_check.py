"""Whether a step of ``world.dt`` can integrate each ball's drag and spin decay: an explicit step
diverges where the drag acts faster than a step, and a ground under the ball hides it (a 10 m ball
of a milligram fell its 10 m in one step and lay there, exit code 0). Plain numpy, no Taichi.

The drag's rate is λ = ∂|a_D|/∂|v| = 2(k/m)|v_rel| with quadratic drag (γ = 2) and k/m with
laminar drag (γ = 1), k/m = ½ρπR²·C_D/m [1/m or 1/s], C_D the air model's greatest (the spin-ratio
fits over their range of S, with the drag crisis at its full height). An explicit Euler step of
the drag is stable while h·λ ≤ 2 (RK4's limit, 2.79, is wider). The speed is the greater of the
ball's start against the wind (|v| + |wind|) and, under gravity g, its terminal speed
v_t = √(g/(k/m)), which a falling ball reaches within about v_t/g: so h ≤ v_t/g at least.

The spin decays as dω/dt = −r·ω (:mod:`ti_golf.physics.aero`) at the rate r = k_ω (γ = 1),
k_ω(|v_rel| + R|ω|) (γ = 2) or (ρ/1.225)·λ|v_rel|/R (``spin_reynolds``), greatest at the start spin and at
the speed above. A step scales the spin by 1 − h·r, so it must keep h·r ≤ 1: beyond it a step turns
the spin around (the Magnus force with it), beyond 2 it grows without bound.

Where balls collide, a step must also not let gravity carry a ball at rest through a good part of
its radius (:func:`check_contact_step`).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from ti_golf.errors import ConfigError
from ti_golf.scene.air import SPIN_DECAY_RHO, SPIN_RATIO_C_D, SPIN_RATIOS, quadratic_range
from ti_golf.scene.schema import Scene


def greatest_C_D(scene: Scene) -> float:
    """The greatest drag coefficient of the scene's air model."""
    a = scene.air
    if a.model == "spin_ratio":
        return quadratic_range(SPIN_RATIO_C_D, *SPIN_RATIOS)[1]
    if a.model == "spin_reynolds":
        return quadratic_range(a.C_D_S, *SPIN_RATIOS)[1] + a.C_D_crisis
    return a.C_D


def check_step(scene: Scene, radius: np.ndarray, mass: np.ndarray, v: np.ndarray | None, w: np.ndarray | None) -> None:
    """Raise :class:`ConfigError` naming ``world.dt`` when a step is too long for the drag or the
    spin decay of balls of radii ``radius`` [m] and masses ``mass`` [kg] (N,), starting at
    velocities ``v`` [m/s] and spins ``w`` [rad/s] (N, 3; ``None``: zero)."""
    h, g, a = scene.world.dt, float(np.linalg.norm(scene.world.gravity)), scene.air
    half_rho_A = 0.5 * a.rho * math.pi * np.square(radius)
    k = half_rho_A * greatest_C_D(scene) / mass  # k/m
    terminal = np.sqrt(g / np.maximum(k, 1e-300))
    speed = np.maximum(float(np.linalg.norm(a.wind)) + (0.0 if v is None else np.linalg.norm(v, axis=1)), terminal)
    drag_max = 2.0 / np.maximum(k, 1e-300) if a.gamma == 1 else 1.0 / np.maximum(k * speed, 1e-300)
    i = int(np.argmin(drag_max))
    if h > drag_max[i]:
        raise ConfigError(
            *scene.where("world.dt"),
            f"= {h:g} s is too long a step for the drag of ball {i} (radius {radius[i]:g} m, mass {mass[i]:g} kg): "
            f"it must be at most {drag_max[i]:.3g} s, or the explicit step of the drag diverges (a light, large "
            "ball reaches its terminal speed within a step): a smaller world.dt, or a heavier or smaller ball",
        )
    check_contact_step(scene, radius)
    spin = np.zeros_like(radius) if w is None else np.linalg.norm(w, axis=1)
    if a.model == "spin_reynolds":
        key, value = "air.spin_decay", a.spin_decay
        rate = value * (a.rho / SPIN_DECAY_RHO) * speed / radius
    else:
        key, value = "air.C_omega", a.C_omega
        k_omega = half_rho_A * value / mass
        rate = k_omega if a.gamma == 1 else k_omega * (speed + radius * spin)
    i = int(np.argmax(rate))
    if h * rate[i] > 1.0:
        source, blamed = scene.where("world.dt", key)
        what = "is too long a step for the spin decay" if blamed == "world.dt" else "makes the spin decay too fast"
        raise ConfigError(
            source,
            blamed,
            f"{what}: with world.dt = {h:g} s and {key} = {value:g}, the spin of ball {i} "
            f"(radius {radius[i]:g} m, mass {mass[i]:g} kg, spin {spin[i]:.6g} rad/s) decays at up to "
            f"{rate[i]:.3g} per second, so a step must be at most {1.0 / rate[i]:.3g} s, or it turns the spin "
            f"around: a smaller world.dt or {key}",
        )


CONTACT_STEP_FALL = 0.5
"""The most a step may let gravity carry a ball at rest, g·h², as a fraction of the smallest
radius, when balls collide: the contacts are solved from each step's start, so a longer step sinks
a pile into itself (the docs' solver page gives the heap's overlaps against the step)."""


def check_contact_step(scene: Scene, radius: np.ndarray) -> None:
    """Raise :class:`ConfigError` naming ``world.dt`` when balls of radii ``radius`` [m] (N,)
    collide (``world.collisions``, two balls or more) and a step lets gravity carry a ball at rest
    further than :data:`CONTACT_STEP_FALL` of the smallest radius."""
    h, g = scene.world.dt, float(np.linalg.norm(scene.world.gravity))
    if not scene.world.collisions or len(radius) < 2 or g == 0.0:
        return
    r_min = float(np.min(radius))
    fall = g * h * h
    if fall > CONTACT_STEP_FALL * r_min:
        h_max = math.sqrt(CONTACT_STEP_FALL * r_min / g)
        raise ConfigError(
            *scene.where("world.dt"),
            f"= {h:g} s is too long a step for balls that collide: gravity carries a ball at rest g·h² = "
            f"{1e3 * fall:.3g} mm in a step, more than {CONTACT_STEP_FALL:g} times the smallest radius "
            f"({1e3 * r_min:.3g} mm), and a pile sinks into itself; at most {h_max:.3g} s "
            "(overlaps grow as h²: docs' solver page)",
        )


def check_changed_step(
    old: Scene,
    scene: Scene,
    radius: np.ndarray,
    mass: np.ndarray,
    motion: Callable[[], tuple[np.ndarray, np.ndarray]],
) -> None:
    """:func:`check_step` of ``scene``'s balls when its air, step, gravity or collisions differ from ``old``'s
    (a change of any other key leaves the limits as they were, and the balls' velocities and spins,
    read from the device by ``motion``, are not read then)."""
    new, was = ((s.air, s.world.dt, s.world.gravity, s.world.collisions) for s in (scene, old))
    if new != was:
        check_step(scene, radius, mass, *motion())
