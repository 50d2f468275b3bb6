"""Flight outcomes (carry, apex, landing) as numpy arrays; shared by sweeps and simulations."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: CSV columns of a sweep, in order (units in the names).
CSV_COLUMNS = (
    "angle_deg",
    "speed_mps",
    "spin_radps",
    "carry_m",
    "landing_x_m",
    "landing_z_m",
    "apex_m",
    "flight_time_s",
    "landing_angle_deg",
    "landing_speed_mps",
)


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
