"""The figures a study collects, and the measures of a pile (its height and angle of repose).

Each figure has a name (what a study file's ``task.figures`` lists), a column of the results table
(its unit in the name) and the task kinds that give it. A task of many balls or launches reduces
them to one number as the table below says. Plain numpy, no Taichi.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

KINDS = ("run", "sweep", "shot", "dispersion", "tour", "pit")
"""What a task runs (``task.kind``)."""

_FLIGHT = ("run", "sweep", "shot", "dispersion", "tour")
_PILE = ("run", "pit")


@dataclass(frozen=True)
class Figure:
    """One figure: its column in the results table, the task kinds that give it, and its meaning."""

    column: str
    kinds: tuple[str, ...]
    doc: str


FIGURES: dict[str, Figure] = {
    "carry": Figure(
        "carry_m",
        _FLIGHT,
        "horizontal distance from launch to landing at launch height; the mean over the balls that landed (a "
        "sweep: its longest carry; tour: one column per club)",
    ),
    "apex": Figure("apex_m", _FLIGHT, "highest point above the launch point (as carry: a mean, a sweep's longest)"),
    "landing_angle": Figure("landing_angle_deg", _FLIGHT, "descent angle below the horizontal at landing"),
    "lateral_offset": Figure(
        "lateral_offset_m",
        ("run", "sweep", "shot", "dispersion"),
        "landing point's distance right of the target line (launch.direction_deg)",
    ),
    "pile_height": Figure("pile_height_m", ("run",), "top of the highest ball in play above the lowest ball's bottom"),
    "repose_angle": Figure(
        "repose_angle_deg",
        ("run",),
        "angle of repose: the slope of the heap's top surface, NaN without a flank (see repose_angle)",
    ),
    "deepest_overlap": Figure("deepest_overlap", _PILE, "deepest overlap of two balls, a fraction of a radius"),
    "p99_speed": Figure("p99_speed_mps", _PILE, "99th percentile of the balls' speeds at the end"),
    "wall_time": Figure(
        "sim_wall_s", KINDS, "wall time of the simulation proper (the row's wall_s is the whole task's)"
    ),
}
"""Every figure by name."""


def default_figures(kind: str) -> tuple[str, ...]:
    """The figures a task of ``kind`` collects unless the study names them: all it gives."""
    return tuple(name for name, f in FIGURES.items() if kind in f.kinds)


def pile_height(x: np.ndarray, radius: np.ndarray, in_play: np.ndarray) -> float:
    """The top of the highest ball in play above the bottom of the lowest one [m] (NaN: none in play)."""
    if not np.any(in_play):
        return float("nan")
    y, r = x[in_play, 1], radius[in_play]
    return float(np.max(y + r) - np.min(y - r))


def repose_angle(x: np.ndarray, radius: np.ndarray, in_play: np.ndarray) -> float:
    """The angle of repose of a heap [deg]: the slope of its flank.

    The axis is the vertical through the balls' median x and z. The heap's surface is the highest
    ball top in each ring two mean diameters wide about the axis. Going out from the axis, the
    flank is the rings whose top lies between 80 % and 20 % of the way down from the summit to one
    layer of balls on the floor; the angle is the arctangent of the least-squares slope of their
    tops against the rings' distances. The rounded summit and the skirt of single balls that rolled
    away are left out, however far the skirt reaches. NaN for fewer than three such rings."""
    if np.count_nonzero(in_play) < 10:
        return float("nan")
    p, r = x[in_play], radius[in_play]
    centre = np.median(p[:, [0, 2]], axis=0)
    rho = np.hypot(p[:, 0] - centre[0], p[:, 2] - centre[1])
    top = p[:, 1] + r
    width = 4.0 * float(np.mean(r))
    ring = np.floor(rho / width).astype(np.int64)
    rings = np.unique(ring)
    tops = np.array([top[ring == k].max() for k in rings])
    layer = float(np.min(p[:, 1] - r) + 2.0 * np.mean(r))
    summit = float(tops.max())
    high, low = layer + 0.8 * (summit - layer), layer + 0.2 * (summit - layer)
    below = np.flatnonzero(tops < low)
    end = below[0] if below.size else rings.size  # the flank ends where the heap thins out
    flank = np.arange(end)[tops[:end] <= high]
    if flank.size < 3:
        return float("nan")
    slope = np.polyfit((rings[flank] + 0.5) * width, tops[flank], 1)[0]
    return float(np.degrees(np.arctan(max(-slope, 0.0))))


def landed_mean(values: np.ndarray, landed: np.ndarray) -> float:
    """The mean of ``values`` over the balls that landed (NaN when none did); one ball: its value."""
    v = np.asarray(values, float)[np.asarray(landed, bool)]
    return float(np.mean(v)) if v.size else float("nan")
