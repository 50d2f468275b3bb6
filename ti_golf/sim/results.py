"""Flight outcomes (carry, apex, landing) as numpy arrays; shared by sweeps and simulations."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ti_golf.scene.launch_monitor import Units, along, right_of

CSV_COLUMNS = (
    "angle_deg",
    "speed_mps",
    "spin_radps",
    "carry_m",
    "landing_x_m",
    "landing_z_m",
    "apex_height_m",
    "flight_time_s",
    "landing_angle_deg",
    "landing_speed_mps",
    "offline_m",
    "landing_spin_radps",
)
"""The columns of a sweep's CSV, in order, one per quantity, each with its unit in its name (the
docs' shots page describes each): the launch condition, then the flight to landing. The apex is
the height of the ball's centre above its launch point."""

ROLLED_CSV_COLUMNS = ("total_m", "roll_m")
"""Columns after :data:`CSV_COLUMNS` when the sweep rolled every ball out to rest (``--to-rest``);
NaN in the row of a ball that did not come to rest."""


@dataclass(frozen=True)
class Flight:
    """Per-ball flight outcomes, shape (N,) each; NaN where a ball has not landed.

    Attributes:
        landed: True where the ball came back down through its launch height.
        carry: horizontal distance from the launch point to the landing point [m].
        landing_x, landing_z: landing point [m].
        apex: highest point of the ball's centre [m] (absolute height), so far while in flight;
            NaN for a ball whose flight is not tracked.
        flight_time: time from launch to landing [s].
        landing_angle: descent angle below the horizontal at landing [deg].
        landing_speed: speed at landing [m/s].
    """

    landed: np.ndarray
    carry: np.ndarray
    landing_x: np.ndarray
    landing_z: np.ndarray
    apex: np.ndarray
    flight_time: np.ndarray
    landing_angle: np.ndarray
    landing_speed: np.ndarray

    @classmethod
    def from_arrays(
        cls,
        launch_x: np.ndarray,
        landed: np.ndarray,
        apex: np.ndarray,
        t_land: np.ndarray,
        land_x: np.ndarray,
        land_v: np.ndarray,
    ) -> "Flight":
        """Build from the kernels' raw record: launch points (N, 3), flags (−1 not tracked, 0 in
        flight, 1 landed), apex, landing time, point, velocity."""
        ok = np.asarray(landed) == 1
        nan = np.where(ok, 1.0, np.nan)
        d = (land_x - launch_x) * nan[:, None]
        v = land_v * nan[:, None]
        v_h = np.hypot(v[:, 0], v[:, 2])
        return cls(
            landed=ok,
            carry=np.hypot(d[:, 0], d[:, 2]),
            landing_x=land_x[:, 0] * nan,
            landing_z=land_x[:, 2] * nan,
            apex=np.where(np.asarray(landed) < 0, np.nan, np.asarray(apex, dtype=float)),  # −1: not tracked
            flight_time=np.asarray(t_land, dtype=float) * nan,
            landing_angle=np.degrees(np.arctan2(-v[:, 1], v_h)),
            landing_speed=np.linalg.norm(v, axis=1),
        )


GOLFER_COLUMNS = (
    ("carry", "distance"),
    ("total", "distance"),
    ("roll", "distance"),
    ("offline", "distance"),
    ("apex", "distance"),
    ("hang_time", "s"),
    ("land_angle", "deg"),
    ("land_speed", "speed"),
    ("land_spin", "spin"),
)
"""The numbers golfers read, in order, each with its kind of unit (a kind of
:class:`~ti_golf.scene.launch_monitor.Units`, or the unit itself)."""


@dataclass(frozen=True)
class Shots:
    """Per-shot outcomes as golfers read them, SI, shape (N,) each; NaN where not defined (a ball
    that did not land, or was not rolled out to rest).

    Distances are horizontal, from the launch point; "along" and "offline" are measured along and
    to the right of the target line (the launch azimuth ``launch.direction_deg``; + right).

    Attributes:
        landed: True where the ball came back down through its launch height.
        at_rest: True where the ball was rolled out and came to rest.
        carry: distance to the landing point at launch height [m], negative when that point lies
            behind the launch point (``along`` < 0: a ball blown or spun back over the tee).
        total: distance to the point of rest [m], negative when it lies behind the launch point.
        roll: total − carry [m] (negative when a ball checks and spins back).
        offline: the landing point's distance right of the target line [m].
        along: the landing point's distance along the target line [m].
        rest_offline, rest_along: the same for the point of rest [m].
        apex: highest point of the ball's centre above its launch point [m].
        hang_time: time from launch to landing [s].
        land_angle: descent angle below the horizontal at landing [deg].
        land_speed: speed at landing [m/s].
        land_spin: |ω| at landing [rad/s].
        rolled_out: whether the balls were rolled out to rest (else total and roll are NaN throughout).
    """

    landed: np.ndarray
    at_rest: np.ndarray
    carry: np.ndarray
    total: np.ndarray
    roll: np.ndarray
    offline: np.ndarray
    along: np.ndarray
    rest_offline: np.ndarray
    rest_along: np.ndarray
    apex: np.ndarray
    hang_time: np.ndarray
    land_angle: np.ndarray
    land_speed: np.ndarray
    land_spin: np.ndarray
    rolled_out: bool = False

    @classmethod
    def from_flight(
        cls,
        flight: Flight,
        launch_x: np.ndarray,
        land_w: np.ndarray,
        direction_deg: float = 0.0,
        rest_x: np.ndarray | None = None,
        at_rest: np.ndarray | None = None,
    ) -> "Shots":
        """Build from a :class:`Flight`, the launch points (N, 3), the spins at landing (N, 3)
        [rad/s], the target line's azimuth [deg] and, when rolled out, the points of rest (N, 3)
        [m] and which balls came to rest (N,)."""
        d_hat, r_hat = along(direction_deg), right_of(direction_deg)
        n = flight.carry.size
        land = np.stack([flight.landing_x, np.full(n, np.nan), flight.landing_z], axis=1) - launch_x
        land[:, 1] = 0.0
        nan = np.full(n, np.nan)
        rest_ok = np.zeros(n, bool) if at_rest is None else np.asarray(at_rest, bool) & flight.landed
        total, rest_along, rest_offline = nan, nan, nan
        if rest_x is not None:
            rest = np.where(rest_ok[:, None], np.asarray(rest_x, float) - launch_x, np.nan)
            rest_along, rest_offline = rest @ d_hat, rest @ r_hat
            total = np.copysign(np.hypot(rest[:, 0], rest[:, 2]), rest_along)  # (behind the tee: negative)
        land_along = land @ d_hat
        carry = np.copysign(flight.carry, land_along)  # (a ball that lands behind the tee: negative)
        return cls(
            landed=flight.landed,
            at_rest=rest_ok,
            carry=carry,
            total=total,
            roll=total - carry,
            offline=land @ r_hat,
            along=land_along,
            rest_offline=rest_offline,
            rest_along=rest_along,
            apex=flight.apex - launch_x[:, 1],
            hang_time=flight.flight_time,
            land_angle=flight.landing_angle,
            land_speed=flight.landing_speed,
            land_spin=np.where(flight.landed, np.linalg.norm(land_w, axis=1), np.nan),
            rolled_out=rest_x is not None,
        )

    def __len__(self) -> int:
        return int(self.carry.size)

    def columns(self, units: Units) -> dict[str, np.ndarray]:
        """:data:`GOLFER_COLUMNS` converted to ``units`` (a :class:`~ti_golf.scene.launch_monitor.Units`),
        keyed ``name_unit`` (e.g. ``carry_yd``, ``land_speed_mph``, ``land_spin_radps``)."""
        out = {}
        for name, kind in GOLFER_COLUMNS:
            factor, label = _unit(units, kind)
            out[f"{name}_{label.replace('/', 'p')}"] = getattr(self, name) / factor
        return out


def _unit(units: Units, kind: str) -> tuple[float, str]:
    """(SI per unit, label) of a kind of :data:`GOLFER_COLUMNS` in ``units``."""
    if kind in ("distance", "speed", "spin"):
        return getattr(units, kind), getattr(units, f"{kind}_label")
    return 1.0, kind


@dataclass
class Recording:
    """Samples taken every ``record_every`` steps: times (S,), positions and spins (S, N, 3)."""

    t: list[float] = field(default_factory=list)
    x: list[np.ndarray] = field(default_factory=list)
    w: list[np.ndarray] = field(default_factory=list)

    def arrays(self) -> dict[str, np.ndarray]:
        """``traj_t`` (S,), ``traj_x`` (S, N, 3), ``traj_w`` (S, N, 3)."""
        return {"traj_t": np.asarray(self.t), "traj_x": np.asarray(self.x), "traj_w": np.asarray(self.w)}


@dataclass(frozen=True)
class Overlap:
    """The deepest overlap between two balls: r_i + r_j − |x_i − x_j| [m] and as a fraction of the
    smaller radius (the report's Δx, B.18, which the position projection removes step by step)."""

    depth: float
    fraction: float
    i: int
    j: int
