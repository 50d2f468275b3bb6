"""The TrackMan tour averages (2023 dataset): launch and flight of the average shot of each club.

Source: the TrackMan blog "Introducing updated tour averages" (2024-05-02), as collected in the
project's reference notes (``golf_data.md``). Carry, apex ("max height") and land angle are
measured to the launch height; weather and altitude are not normalised. Units as published (mph,
degrees, rpm, yards); the ``*_si`` properties give SI.

The air model's fit (:mod:`ti_golf.golf.aero_fit`) sees :data:`PGA_TOUR` only; :data:`LPGA_TOUR`
is the check on data the fit never saw.
"""

from __future__ import annotations

from dataclasses import dataclass

from ti_golf.scene.launch_monitor import RPM, YARD

MPH = 0.44704
"""1 mph in m/s."""
YD = YARD
"""1 yard in m."""


@dataclass(frozen=True)
class TourShot:
    """One row of the table: a tour's average shot with one club."""

    tour: str  # "PGA" or "LPGA"
    club: str
    club_mph: float  # club speed [mph]
    attack_deg: float  # attack angle [deg], + upward
    ball_mph: float  # ball speed [mph]
    launch_deg: float  # vertical launch angle [deg]
    spin_rpm: float  # total spin [rpm] (backspin: the spin axis averages about zero)
    apex_yd: float  # max height above launch [yd]
    land_deg: float  # descent angle at launch height [deg]
    carry_yd: float  # carry to launch height [yd]

    @property
    def name(self) -> str:
        """``"PGA 7-iron"``."""
        return f"{self.tour} {self.club}"

    @property
    def speed_si(self) -> float:
        """Ball speed [m/s]."""
        return self.ball_mph * MPH

    @property
    def spin_si(self) -> float:
        """Spin [rad/s]."""
        return self.spin_rpm * RPM


def _rows(tour: str, table: str) -> tuple[TourShot, ...]:
    out = []
    for line in table.strip().splitlines():
        club, *numbers = line.split("|")
        out.append(TourShot(tour, club.strip(), *(float(v) for v in numbers)))
    return tuple(out)


# club | club mph | attack deg | ball mph | launch deg | spin rpm | max height yd | land angle deg | carry yd
PGA_TOUR = _rows(
    "PGA",
    """
Driver | 115 | -0.9 | 171 | 10.4 | 2545 | 35 | 39 | 282
3-wood | 110 | -2.3 | 162 |  9.3 | 3663 | 32 | 44 | 249
5-wood | 106 | -2.5 | 156 |  9.7 | 4322 | 33 | 48 | 236
Hybrid | 102 | -2.4 | 149 | 10.2 | 4587 | 31 | 49 | 231
3-iron | 100 | -2.5 | 145 | 10.3 | 4404 | 30 | 48 | 218
4-iron |  98 | -2.9 | 140 | 10.8 | 4782 | 31 | 49 | 209
5-iron |  96 | -3.4 | 135 | 11.9 | 5280 | 33 | 50 | 199
6-iron |  94 | -3.7 | 130 | 14.0 | 6204 | 32 | 50 | 188
7-iron |  92 | -3.9 | 123 | 16.1 | 7124 | 34 | 51 | 176
8-iron |  89 | -4.2 | 118 | 17.8 | 8078 | 33 | 51 | 164
9-iron |  87 | -4.3 | 112 | 20.0 | 8793 | 32 | 52 | 152
PW     |  84 | -4.7 | 104 | 23.7 | 9316 | 32 | 52 | 142
""",
)
"""The PGA Tour's 12 clubs (the fit's data)."""

LPGA_TOUR = _rows(
    "LPGA",
    """
Driver | 96 |  2.8 | 143 | 12.6 | 2506 | 26 | 36 | 223
3-wood | 92 | -0.8 | 135 | 11.6 | 2595 | 25 | 38 | 200
5-wood | 90 | -1.6 | 130 | 12.3 | 4320 | 25 | 43 | 189
Hybrid | 87 | -1.9 | 125 | 13.9 | 4504 | 25 | 45 | 178
4-iron | 82 | -1.7 | 118 | 13.9 | 4608 | 25 | 43 | 175
5-iron | 81 | -2.0 | 114 | 14.6 | 4966 | 25 | 45 | 166
6-iron | 80 | -2.3 | 111 | 16.7 | 5904 | 25 | 46 | 155
7-iron | 78 | -2.5 | 106 | 18.5 | 6630 | 26 | 47 | 143
8-iron | 76 | -2.8 | 102 | 20.8 | 7413 | 27 | 47 | 133
9-iron | 74 | -3.2 |  95 | 23.5 | 7605 | 27 | 48 | 123
PW     | 72 | -3.2 |  88 | 25.2 | 8465 | 27 | 48 | 111
""",
)
"""The LPGA Tour's 11 clubs (never seen by the fit)."""

TOUR = PGA_TOUR + LPGA_TOUR

TOURS = {"PGA": PGA_TOUR, "LPGA": LPGA_TOUR, "all": TOUR}
"""The rows of each ``tour`` a study's tour task may fly."""
"""All 23 rows, PGA first."""
