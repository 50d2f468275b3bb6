"""The TrackMan tour table flown by a scene's air: every row at once, model beside measurement.

Each row's ball leaves the scene's launch point along +x with the row's ball speed, launch angle
and backspin (spin about the backspin axis); carry, apex and land angle are taken where the ball
comes back down through its launch height, as the table's are.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ti_golf.golf.sweep import fly
from ti_golf.golf.trackman import TOUR, YD, TourShot
from ti_golf.scene.balls import launch_position
from ti_golf.scene.launch_monitor import launch_vectors
from ti_golf.scene.schema import Scene
from ti_golf.sim.results import Flight

CARRY_TOL, APEX_TOL, LAND_TOL = 3.0, 2.0, 2.0
"""How close the model must come to the table: carry within 3 % [%], apex within 2 yd [yd], land
angle within 2° [deg]."""


@dataclass(frozen=True)
class TourFlight:
    """The rows of the table flown by a scene, shape (N,) each: the model's carry [yd], apex above
    the launch height [yd] and land angle [deg], beside the rows' measurements."""

    rows: tuple[TourShot, ...]
    carry: np.ndarray
    apex: np.ndarray
    land: np.ndarray

    @property
    def carry_error(self) -> np.ndarray:
        """Model − table carry, in % of the table's."""
        return 100.0 * (self.carry / np.array([r.carry_yd for r in self.rows]) - 1.0)

    @property
    def apex_error(self) -> np.ndarray:
        """Model − table apex [yd]."""
        return self.apex - np.array([r.apex_yd for r in self.rows])

    @property
    def land_error(self) -> np.ndarray:
        """Model − table land angle [deg]."""
        return self.land - np.array([r.land_deg for r in self.rows])

    def within(self) -> np.ndarray:
        """Whether each row is within :data:`CARRY_TOL`, :data:`APEX_TOL` and :data:`LAND_TOL`
        (NaN, a ball that did not land, is not)."""
        return (
            (np.abs(self.carry_error) <= CARRY_TOL)
            & (np.abs(self.apex_error) <= APEX_TOL)
            & (np.abs(self.land_error) <= LAND_TOL)
        )

    def residuals(self) -> np.ndarray:
        """Carry, apex and land errors, each divided by its tolerance, shape (3N,) (the fit's
        residuals: a row at the edge of every tolerance contributes 1 three times)."""
        return np.concatenate([self.carry_error / CARRY_TOL, self.apex_error / APEX_TOL, self.land_error / LAND_TOL])

    def table(self) -> str:
        """The rows as text, the model beside the table with the errors, and a summary line."""
        lines = [
            f"{'':12} {'ball':>4} {'launch':>6} {'spin':>5} | {'carry yd':^22} | {'apex yd':^19} | {'land deg':^19}",
            f"{'club':12} {'mph':>4} {'deg':>6} {'rpm':>5} | {'table':>6} {'model':>6} {'error':>7} | "
            f"{'table':>5} {'model':>5} {'error':>5} | {'table':>5} {'model':>5} {'error':>5}",
        ]
        ok = self.within()
        for i, r in enumerate(self.rows):
            lines.append(
                f"{r.name:12} {r.ball_mph:4.0f} {r.launch_deg:6.1f} {r.spin_rpm:5.0f} | "
                f"{r.carry_yd:6.0f} {self.carry[i]:6.1f} {self.carry_error[i]:+6.1f}% | "
                f"{r.apex_yd:5.0f} {self.apex[i]:5.1f} {self.apex_error[i]:+5.1f} | "
                f"{r.land_deg:5.0f} {self.land[i]:5.1f} {self.land_error[i]:+5.1f}" + ("" if ok[i] else "  *")
            )
        for tour in sorted({r.tour for r in self.rows}, key=lambda t: [r.tour for r in self.rows].index(t)):
            m = np.array([r.tour == tour for r in self.rows])
            lines.append(
                f"{tour + ' worst':12} {'':18} | {'':13} {np.max(np.abs(self.carry_error[m])):6.1f}% | "
                f"{'':11} {np.max(np.abs(self.apex_error[m])):5.1f} | {'':11} {np.max(np.abs(self.land_error[m])):5.1f}"
            )
        lines.append(
            f"{int(ok.sum())} of {len(ok)} rows within {CARRY_TOL:g} % carry, {APEX_TOL:g} yd apex and "
            f"{LAND_TOL:g}° land angle" + ("" if ok.all() else " (* marks the others)")
        )
        return "\n".join(line.rstrip() for line in lines)


def launch_states(scene: Scene, rows: Sequence[TourShot]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(x0, v0, w0), each (N, 3): the rows' balls at the scene's launch point, flying along +x with
    their ball speed [m/s] and launch angle, spinning backward at their spin [rad/s]."""
    x0 = np.tile(np.asarray(launch_position(scene), float), (len(rows), 1))
    speed, launch, spin = (np.array([getattr(r, a) for r in rows]) for a in ("speed_si", "launch_deg", "spin_si"))
    v0, w0 = launch_vectors(speed, launch, 0.0, spin, 0.0)  # straight along +x, pure backspin
    return x0, v0, w0


def fly_tour(scene: Scene, rows: Sequence[TourShot] = TOUR) -> TourFlight:
    """Fly the ``rows`` (default: all 23) in the scene's air, all at once, to their launch height."""
    rows = tuple(rows)
    x0, v0, w0 = launch_states(scene, rows)
    raw = fly(scene, x0, v0, w0)
    f = Flight.from_arrays(x0, raw["landed"], raw["apex"], raw["t_land"], raw["land_x"], raw["land_v"])
    return TourFlight(rows, f.carry / YD, (f.apex - x0[:, 1]) / YD, f.landing_angle)


def within_tolerance_text() -> str:
    """The tolerances in words."""
    return f"carry ±{CARRY_TOL:g} %, apex ±{APEX_TOL:g} yd, land angle ±{LAND_TOL:g}°"
