"""Launches as a launch monitor reports them, and the units golfers read.

A launch monitor gives ball speed, vertical and horizontal launch angle (VLA, HLA: + right of the
target line), total spin and spin axis (+ tilts the lift to the right: a fade for a right-handed
player). The engine's frame: y is up, the target line runs along the azimuth ``direction_deg``
measured from +x toward +z (0: the +x axis), and "right" of it is r̂ = d̂ × ŷ (+z for a target
along +x), seen from above with the target ahead.

Spin axis (the convention of launch monitors and ball-flight software): the spin vector is
perpendicular to the initial velocity and is the backspin axis b̂ = unit(v̂ × ŷ) (horizontal,
pointing to the right of the flight: +z for a shot along +x) turned by the axis angle α about the
flight direction v̂,

    ω = |ω| (cos α · b̂ + sin α · (v̂ × b̂))                                 (Rodrigues, b̂ ⊥ v̂)

so the Magnus lift, along ω × v, turns by the same α about v̂ from straight up toward the right.

Everything here is SI inside (m, m/s, rad/s, angles in degrees as launch monitors give them);
:data:`UNITS` converts at the input/output boundary.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields

import numpy as np

from ti_golf.errors import ConfigError
from ti_golf.scene.schema import Scene

MPH = 0.44704
"""Metres per second in one mile per hour."""
YARD = 0.9144
"""Metres in one yard."""
RPM = 2.0 * math.pi / 60.0
"""Radians per second in one revolution per minute."""


@dataclass(frozen=True)
class Units:
    """A system of units at the input/output boundary: each factor multiplies a value in these
    units to give SI (``value * speed`` → m/s), and each label names the unit."""

    name: str
    distance: float
    distance_label: str
    speed: float
    speed_label: str
    spin: float
    spin_label: str


UNITS = {
    "imperial": Units("imperial", YARD, "yd", MPH, "mph", RPM, "rpm"),
    "metric": Units("metric", 1.0, "m", 1.0, "m/s", 1.0, "rad/s"),
}
"""Units golfers read: yards, mph and rpm, or metres, m/s and rad/s (angles in degrees in both)."""


def right_of(direction_deg: float) -> np.ndarray:
    """Unit vector r̂ = d̂ × ŷ to the right of a target line along azimuth ``direction_deg``, shape (3,)."""
    ph = math.radians(direction_deg)
    return np.array([-math.sin(ph), 0.0, math.cos(ph)])


def target_direction(scene: Scene) -> float:
    """Azimuth of the scene's target line [deg]: its ``launch.direction_deg`` (0, the +x axis, without a launch)."""
    return scene.launch.direction_deg if scene.launch is not None else 0.0


def along(direction_deg: float) -> np.ndarray:
    """Unit vector d̂ of a target line along azimuth ``direction_deg`` (from +x toward +z), shape (3,)."""
    ph = math.radians(direction_deg)
    return np.array([math.cos(ph), 0.0, math.sin(ph)])


def launch_vectors(
    speed: np.ndarray | float,
    vla_deg: np.ndarray | float,
    hla_deg: np.ndarray | float,
    spin: np.ndarray | float,
    axis_deg: np.ndarray | float,
    direction_deg: float = 0.0,
) -> tuple[np.ndarray, np.ndarray]:
    """Initial velocity and spin of launch-monitor launches, in the engine's frame.

    Args:
        speed: ball speed |v| [m/s], a scalar or shape (N,).
        vla_deg: vertical launch angle above the horizontal [deg], likewise.
        hla_deg: horizontal launch angle [deg], + right of the target line, likewise.
        spin: total spin |ω| [rad/s], likewise.
        axis_deg: spin axis α [deg], + tilts the lift to the right (fade), likewise.
        direction_deg: azimuth of the target line, from +x toward +z [deg].

    Returns:
        (v, ω): velocities [m/s] and angular velocities [rad/s], shape (N, 3) each (N = 1 for scalars).
    """
    sp, th, hl, w, al = np.broadcast_arrays(
        *(np.atleast_1d(np.asarray(a, dtype=float)) for a in (speed, vla_deg, hla_deg, spin, axis_deg))
    )
    th, al = np.radians(th), np.radians(al)
    ph = np.radians(direction_deg + hl)
    v_hat = np.stack([np.cos(th) * np.cos(ph), np.sin(th), np.cos(th) * np.sin(ph)], axis=1)
    b = np.stack([-np.sin(ph), np.zeros_like(ph), np.cos(ph)], axis=1)  # unit(v̂ × ŷ): backspin
    up = np.cross(v_hat, b)  # v̂ × b̂, so that ω × v̂ turns from ŷ-ward toward r̂ as α grows
    omega = w[:, None] * (np.cos(al)[:, None] * b + np.sin(al)[:, None] * up)
    return sp[:, None] * v_hat, omega


def launch_monitor(v: np.ndarray, w: np.ndarray, direction_deg: float = 0.0) -> dict[str, np.ndarray]:
    """The launch-monitor numbers of initial velocities and spins (the inverse of
    :func:`launch_vectors`; a spin component along v, rifle spin, which launch monitors do not
    report, is left out of the axis but counted in the total spin).

    Args:
        v: velocities [m/s], shape (N, 3) or (3,).
        w: angular velocities [rad/s], likewise.
        direction_deg: azimuth of the target line [deg].

    Returns:
        ``speed`` [m/s], ``vla_deg``, ``hla_deg``, ``spin`` [rad/s] and ``axis_deg``, shape (N,) each.
    """
    v, w = np.atleast_2d(np.asarray(v, dtype=float)), np.atleast_2d(np.asarray(w, dtype=float))
    speed = np.linalg.norm(v, axis=1)
    v_hat = v / np.maximum(speed, 1e-300)[:, None]
    horizontal = np.hypot(v[:, 0], v[:, 2])
    vla = np.degrees(np.arctan2(v[:, 1], horizontal))
    az = np.degrees(np.arctan2(v[:, 2], v[:, 0]))
    hla = (az - direction_deg + 180.0) % 360.0 - 180.0
    ph = np.radians(az)
    b = np.stack([-np.sin(ph), np.zeros_like(ph), np.cos(ph)], axis=1)
    up = np.cross(v_hat, b)
    axis = np.degrees(np.arctan2(np.einsum("ij,ij->i", w, up), np.einsum("ij,ij->i", w, b)))
    return {"speed": speed, "vla_deg": vla, "hla_deg": hla, "spin": np.linalg.norm(w, axis=1), "axis_deg": axis}


@dataclass(frozen=True)
class MonitorLaunch:
    """Launches as a launch monitor reports them, SI with angles in degrees; each a float, or an
    array of shape (N,) for N launches (also used for a player's standard deviations).

    Attributes:
        speed: ball speed [m/s].
        vla_deg: vertical launch angle [deg].
        hla_deg: horizontal launch angle [deg], + right of the target line.
        spin: total spin [rad/s].
        axis_deg: spin axis [deg], + tilts the lift to the right (fade).
    """

    speed: float | np.ndarray
    vla_deg: float | np.ndarray
    hla_deg: float | np.ndarray
    spin: float | np.ndarray
    axis_deg: float | np.ndarray

    def vectors(self, direction_deg: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
        """(v, ω) in the engine's frame, shape (N, 3) each (:func:`launch_vectors`)."""
        return launch_vectors(self.speed, self.vla_deg, self.hla_deg, self.spin, self.axis_deg, direction_deg)

    def in_units(self, units: Units) -> dict[str, float | np.ndarray]:
        """The values in ``units`` (speed and spin converted; angles stay in degrees), by field name."""
        return {f.name: getattr(self, f.name) / field_factor(units, f.name) for f in fields(self)}

    @classmethod
    def from_units(cls, values: dict[str, float | np.ndarray], units: Units) -> "MonitorLaunch":
        """From values in ``units`` by field name (see :meth:`in_units`); floats stay floats."""
        si = {name: np.asarray(v, dtype=float) * field_factor(units, name) for name, v in values.items()}
        return cls(**{name: v if v.ndim else float(v) for name, v in si.items()})


LAUNCH_LIMITS = {
    "speed": (0.0, 150.0),
    "vla_deg": (-90.0, 90.0),
    "hla_deg": (-90.0, 90.0),
    "spin": (0.0, 2000.0),
    "axis_deg": (-90.0, 90.0),
}
"""Allowed launch values, SI (ball speed up to 150 m/s ≈ 335 mph, spin up to 2000 rad/s ≈ 19,100 rpm):
the range of golf shots, which a launch monitor reports. A scene's ``[launch]`` and ``ti-golf
sweep`` take any ball up to ``scene.checks.SPEED_LIMIT`` and ``SPIN_LIMIT``."""

SHOT_RANGE = ": the range of golf shots; a scene's [launch] and `ti-golf sweep` take faster balls and more spin"
"""What an error on a shot's speed or spin beyond :data:`LAUNCH_LIMITS` says of the bound."""


def field_factor(units: Units, name: str) -> float:
    """SI per unit of the launch field ``name`` in ``units`` (m/s per mph, rad/s per rpm; 1 for angles)."""
    return units.speed if name == "speed" else units.spin if name == "spin" else 1.0


def field_label(units: Units, name: str) -> str:
    """The unit of the launch field ``name`` in ``units`` (mph, rpm, deg ...)."""
    return units.speed_label if name == "speed" else units.spin_label if name == "spin" else "deg"


def check_launch(launch: MonitorLaunch, units: Units, options: dict[str, str], spread: bool = False) -> None:
    """Raise :class:`ConfigError` naming the option (``options[field]``, e.g. ``"--speed"``) of a
    value that is not finite or outside :data:`LAUNCH_LIMITS` (stated in ``units``). With
    ``spread``, the values are standard deviations: finite, ≥ 0 and at most the range's width."""
    for name, (lo, hi) in LAUNCH_LIMITS.items():
        value = float(np.asarray(getattr(launch, name)))
        f, label = field_factor(units, name), field_label(units, name)
        if spread:
            lo, hi = 0.0, hi - lo
        if not (math.isfinite(value) and lo <= value <= hi) or (name == "speed" and not spread and value <= 0.0):
            low = "(" if name == "speed" and not spread else "["
            why = SHOT_RANGE if name in ("speed", "spin") and not spread else ""
            raise ConfigError(
                options[name], None, f"must be in {low}{lo / f:.6g}, {hi / f:.6g}] {label} (got {value / f:.6g}){why}"
            )


def scene_launch(scene: Scene) -> MonitorLaunch:
    """The scene's ``[launch]`` as a launch monitor would report it (zeros without one), relative to
    its own azimuth (so HLA = 0)."""
    if scene.launch is None:
        return MonitorLaunch(0.0, 0.0, 0.0, 0.0, 0.0)
    L = scene.launch
    th, ph = math.radians(L.angle_deg), math.radians(L.direction_deg)
    v = L.speed * np.array([math.cos(th) * math.cos(ph), math.sin(th), math.cos(th) * math.sin(ph)])
    m = launch_monitor(v, np.asarray(L.spin, float), L.direction_deg)
    return MonitorLaunch(*(float(m[k][0]) for k in ("speed", "vla_deg", "hla_deg", "spin", "axis_deg")))
