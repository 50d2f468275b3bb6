"""Dispersion: a player's spread of launches flown all at once, and where the shots land.

Launches are drawn independently and normally about a mean launch (ball speed, VLA, HLA, spin and
spin axis, each with its standard deviation) from a seeded generator, so a seed gives the same
shots bit for bit. The landing points' spread is summarised by ellipses of the covariance of the
points: for a 2-D normal distribution the squared Mahalanobis distance is χ² with 2 degrees of
freedom, so the ellipse holding a fraction p of the points has the radius k with
k² = −2 ln(1 − p) (2.279 for 68 %, 5.991 for 95 %) along each principal axis of unit variance.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, fields
from pathlib import Path

import numpy as np

from ti_golf.files import atomic_path
from ti_golf.golf.shots import shots
from ti_golf.scene.launch_monitor import LAUNCH_LIMITS, MPH, RPM, MonitorLaunch, Units
from ti_golf.scene.schema import Scene
from ti_golf.signals import KeptInterrupt
from ti_golf.sim.given import whole_number
from ti_golf.sim.results import Shots
from ti_golf.sim.simulation import RunProgress

MAX_SHOTS = 1_000_000
"""The most shots one dispersion flies."""

PLAYER_SPREAD = MonitorLaunch(speed=1.5 * MPH, vla_deg=1.0, hla_deg=1.5, spin=300.0 * RPM, axis_deg=3.0)
"""Default standard deviations (illustrative, not measured): ball speed 1.5 mph, VLA 1°, HLA 1.5°,
spin 300 rpm, spin axis 3°, about a consistent player's iron."""


def draw_launches(mean: MonitorLaunch, sd: MonitorLaunch, n: int, seed: int) -> MonitorLaunch:
    """``n`` launches, each value normal about ``mean`` with standard deviation ``sd``, independent,
    from ``numpy.random.default_rng(seed)`` (one (5, n) block of standard normals, fields in order);
    each kept within :data:`~ti_golf.scene.launch_monitor.LAUNCH_LIMITS` (ball speed and spin ≥ 0,
    angles within ±90°). Returns arrays of shape (n,)."""
    z = np.random.default_rng(seed).standard_normal((5, int(n)))
    out = {}
    for row, f in enumerate(fields(MonitorLaunch)):
        value = float(getattr(mean, f.name)) + float(getattr(sd, f.name)) * z[row]
        out[f.name] = np.clip(value, *LAUNCH_LIMITS[f.name])
    return MonitorLaunch(**out)


def held_at_limits(launches: MonitorLaunch, sd: MonitorLaunch) -> dict[str, float]:
    """The share of the drawn values of each launch field that :func:`draw_launches` held at a
    limit of :data:`~ti_golf.scene.launch_monitor.LAUNCH_LIMITS` (fields with a spread only, and
    only those where some were): there the spread flown is narrower than ``sd`` says."""
    out = {}
    for f in fields(MonitorLaunch):
        if float(getattr(sd, f.name)) > 0.0:
            value = np.asarray(getattr(launches, f.name))
            share = float(np.mean(np.isin(value, LAUNCH_LIMITS[f.name])))
            if share > 0.0:
                out[f.name] = share
    return out


def chi2_radius(p: float) -> float:
    """k with P(χ²₂ ≤ k²) = p: the Mahalanobis radius of the ellipse holding a fraction p of a 2-D normal."""
    return math.sqrt(-2.0 * math.log1p(-p))


@dataclass(frozen=True)
class Ellipse:
    """An ellipse of the points' covariance in the top view: (offline, along) [m].

    Attributes:
        p: the fraction of a normal distribution it holds.
        center: mean (offline, along) [m], shape (2,).
        semi_major, semi_minor: semi-axes [m].
        angle_deg: the major axis' angle from the target line toward the right [deg], in (−90, 90].
        inside: the fraction of the points that lie inside it.
    """

    p: float
    center: np.ndarray
    semi_major: float
    semi_minor: float
    angle_deg: float
    inside: float

    def outline(self, k: int = 181) -> np.ndarray:
        """Points on the ellipse, shape (k, 2) (offline, along) [m]."""
        t = np.linspace(0.0, 2.0 * math.pi, k)
        a = math.radians(self.angle_deg)
        major, minor = np.array([math.sin(a), math.cos(a)]), np.array([math.cos(a), -math.sin(a)])
        return self.center + np.outer(self.semi_major * np.cos(t), major) + np.outer(self.semi_minor * np.sin(t), minor)


def ellipse(points: np.ndarray, p: float) -> Ellipse:
    """The ellipse of the sample covariance C of ``points`` (N, 2) (offline, along) [m] that holds
    a fraction ``p`` of a normal distribution: semi-axes k·√λ for the eigenvalues λ of C,
    k = :func:`chi2_radius` (p). Rows with NaN are left out."""
    pts = np.asarray(points, dtype=float)
    pts = pts[np.all(np.isfinite(pts), axis=1)]
    center = pts.mean(axis=0)
    cov = np.cov(pts, rowvar=False)
    lam, vec = np.linalg.eigh(cov)  # ascending
    k = chi2_radius(p)
    major = vec[:, 1]
    angle = math.degrees(math.atan2(major[0], major[1]))  # from "along" toward "offline"
    if angle <= -90.0:
        angle += 180.0
    elif angle > 90.0:
        angle -= 180.0
    d = pts - center
    m2 = np.einsum("ij,jk,ik->i", d, np.linalg.pinv(cov), d)  # squared Mahalanobis distances
    return Ellipse(
        p=p,
        center=center,
        semi_major=k * math.sqrt(max(lam[1], 0.0)),
        semi_minor=k * math.sqrt(max(lam[0], 0.0)),
        angle_deg=angle,
        inside=float(np.mean(m2 <= k * k)),
    )


@dataclass(frozen=True)
class Dispersion:
    """N shots of one player: the launches drawn, their outcomes and the landing ellipses.

    Attributes:
        launches: the launches flown, arrays of shape (N,) (:class:`MonitorLaunch`).
        shots: their outcomes (:class:`~ti_golf.sim.results.Shots`).
        mean, sd: the player's mean launch and standard deviations.
        seed: the seed of the draw.
    """

    launches: MonitorLaunch
    shots: Shots
    mean: MonitorLaunch
    sd: MonitorLaunch
    seed: int

    def landing_points(self) -> np.ndarray:
        """Landing points (offline, along) [m] of the shots, shape (N, 2) (NaN where not landed)."""
        return np.stack([self.shots.offline, self.shots.along], axis=1)

    def rest_points(self) -> np.ndarray:
        """Points of rest (offline, along) [m], shape (N, 2) (NaN where not rolled out to rest)."""
        return np.stack([self.shots.rest_offline, self.shots.rest_along], axis=1)

    def ellipses(self, ps: tuple[float, ...] = (0.68, 0.95)) -> list[Ellipse]:
        """The landing ellipses holding these fractions of a normal distribution."""
        return [ellipse(self.landing_points(), p) for p in ps]

    def table(self, units: Units) -> dict[str, np.ndarray]:
        """One column per quantity, shape (N,) each, in ``units``, keyed ``name_unit``: the launch
        (``speed_mph``, ``vla_deg``, ``hla_deg``, ``spin_rpm``, ``axis_deg``), the golfer columns
        (:meth:`Shots.columns`) and the landing and rest points (``along``, ``rest_along``,
        ``rest_offline``); total, roll and the rest points only when the shots were rolled out."""
        out = {}
        for name, value in self.launches.in_units(units).items():
            unit = {"speed": units.speed_label, "spin": units.spin_label}.get(name)
            out[f"{name}_{unit.replace('/', 'p')}" if unit else name] = np.asarray(value)
        rolled = self.shots.rolled_out  # (else total, roll and the rest points are NaN throughout: left out)
        out.update(
            {k: v for k, v in self.shots.columns(units).items() if rolled or not k.startswith(("total", "roll"))}
        )
        for name in ("along", "rest_along", "rest_offline") if rolled else ("along",):
            out[f"{name}_{units.distance_label}"] = getattr(self.shots, name) / units.distance
        return out

    def save(self, path: str | os.PathLike[str], units: Units) -> None:
        """Write :meth:`table` as CSV (``.csv``: a header row, then one row per shot; NaN where a
        value is missing) or NPZ (``.npz``: one array per column, plus ``seed`` and ``units``),
        whole or not at all."""
        cols = self.table(units)
        suffix = Path(path).suffix.lower()
        if suffix not in (".csv", ".npz"):
            raise ValueError(f"the shots file must end in .csv or .npz (got {str(path)!r})")
        with atomic_path(path) as tmp, open(tmp, "wb") as fh:
            if suffix == ".npz":
                arrays: dict[str, np.ndarray] = {"seed": np.array(self.seed), "units": np.array(units.name), **cols}
                np.savez(fh, **arrays)  # type: ignore[arg-type]
            else:
                data = np.column_stack(list(cols.values()))
                np.savetxt(fh, data, fmt="%.9g", delimiter=",", header=",".join(cols), comments="")

    def summary(self) -> dict[str, tuple[float, float]]:
        """(mean, standard deviation) of carry, total and offline [m] over the shots that have them."""
        out = {}
        for name in ("carry", "total", "offline"):
            a = getattr(self.shots, name)
            a = a[np.isfinite(a)]
            out[name] = (float(a.mean()), float(a.std(ddof=1))) if a.size > 1 else (math.nan, math.nan)
        return out


def dispersion(
    scene: Scene | str | os.PathLike[str],
    mean: MonitorLaunch,
    sd: MonitorLaunch,
    n: int = 10_000,
    seed: int = 0,
    to_rest: bool = True,
    flight_dt: float | None = None,
    progress: RunProgress | None = None,
) -> Dispersion:
    """Fly ``n`` shots drawn from a player's spread (:func:`draw_launches`) all at once, to landing
    and, with ``to_rest``, to rest on the scene's ground (see :func:`ti_golf.golf.shots.shots`).

    Example:
        >>> from ti_golf.scene.launch_monitor import MonitorLaunch, MPH, RPM           # doctest: +SKIP
        >>> mean = MonitorLaunch(123 * MPH, 16.1, 0.0, 7124 * RPM, 0.0)                 # doctest: +SKIP
        >>> sd = MonitorLaunch(1.5 * MPH, 1.0, 1.5, 300 * RPM, 3.0)                     # doctest: +SKIP
        >>> d = dispersion(load_scene("tour_shot"), mean, sd, n=100_000, seed=1)        # doctest: +SKIP
        >>> d.summary()["carry"], d.ellipses()[1].semi_major                           # doctest: +SKIP

    An interrupt raises :class:`~ti_golf.signals.KeptInterrupt` holding the Dispersion of the
    shots computed by then (see :func:`~ti_golf.golf.shots.fly_shots`).
    """
    n, seed = whole_number(n, "n"), whole_number(seed, "seed")
    if not 2 <= n <= MAX_SHOTS:
        raise ValueError(f"n must be in [2, {MAX_SHOTS}] (got {n})")
    launches = draw_launches(mean, sd, n, seed)
    try:
        result = shots(scene, launches, to_rest=to_rest, flight_dt=flight_dt, progress=progress)
    except KeptInterrupt as stop:  # (the shots computed when it came)
        raise KeptInterrupt(Dispersion(launches, stop.kept, mean, sd, int(seed))) from None
    return Dispersion(launches, result, mean, sd, int(seed))
