"""Matplotlib figures written to files (no pyplot, no global backend): sweep trajectories and carry,
the report's Table 3.1-1 families, run trajectories and spin decay, the tour table beside the model, and a
golf round on its course."""

from __future__ import annotations

import logging
import os
from pathlib import Path
from typing import TYPE_CHECKING

import matplotlib
import numpy as np
from matplotlib.figure import Figure

from ti_golf.files import atomic_path, plot_format
from ti_golf.scene.balls import launch_position

TERRAIN_FILL = (0.62, 0.74, 0.50)
"""The ground under a terrain profile: pale green."""

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.axes import Axes

    from ti_golf.golf.sweep import SweepResult
    from ti_golf.golf.tour import TourFlight
    from ti_golf.sim.results import Recording


class _NoTransparencyNotice(logging.Filter):
    """Drops the PostScript backend's notice that EPS has no transparency (said in the help)."""

    def filter(self, record: logging.LogRecord) -> bool:
        return "does not support transparency" not in record.getMessage()


def save_figure(fig: Figure, path: str | os.PathLike[str], dpi: int) -> None:
    """Write ``fig`` to ``path`` whole or not at all, in the format of its suffix (:data:`ti_golf.files.PLOT_FORMATS`;
    ``.png`` is added to a path without one, as matplotlib does). In EPS, which has no
    transparency, see-through parts come out opaque."""
    fmt = plot_format(path)
    target = Path(path)
    if not target.suffix:
        target = target.with_name(target.name + ".png")
    quiet = _NoTransparencyNotice()
    ps_log = logging.getLogger("matplotlib.backends.backend_ps")
    ps_log.addFilter(quiet)
    try:
        # (written through a file object: EPS takes its title from a path's name, the temporary one)
        with atomic_path(target) as tmp, open(tmp, "wb") as fh:
            fig.savefig(fh, dpi=dpi, format=fmt)
    finally:
        ps_log.removeFilter(quiet)


def top_view(ax: "Axes", label: str = "z [m] (top view)") -> None:
    """Make ``ax``, which plots x across and z up the page, the view from above: z grows down the
    page, as the ``top`` camera shows it. With y up the frame is right-handed, so the golfer's
    right (+z, facing +x) lies below the line of play seen from above; z up the page was the view
    from below, a mirror image."""
    if not ax.yaxis_inverted():
        ax.invert_yaxis()
    ax.set_ylabel(label)


def plot_sweep(res: "SweepResult", path: str | os.PathLike[str], title: str | None = None) -> None:
    """Side view of the recorded trajectories (as the report's Figures 3.1-1 to 3.1-4) and carry vs angle."""
    fig = Figure(figsize=(12, 4.5))
    ax1, ax2 = fig.subplots(1, 2, gridspec_kw={"width_ratios": [1.6, 1]})
    best = res.best() if np.any(res.flight.landed) else None  # (none: no ball landed within world.t_max)
    x0 = np.asarray(launch_position(res.scene))
    if res.traj is not None and res.traj_index is not None:
        cmap = matplotlib.colormaps.get_cmap("viridis")
        k = len(res.traj_index)
        for j, i in enumerate(res.traj_index):
            p = res.traj[j]
            d = np.hypot(p[:, 0] - x0[0], p[:, 2] - x0[2])
            ax1.plot(
                d,
                p[:, 1] - x0[1],
                color=cmap(j / max(k - 1, 1)),
                lw=1.0,
                label=f"{res.angle_deg[i]:.4g}°" if k <= 12 else None,
            )
        if k <= 12:
            ax1.legend(fontsize=7, ncol=2, title="launch angle")
    ax1.set_xlabel("downrange distance [m]")
    ax1.set_ylabel("height above launch [m]")
    ax1.set_aspect("equal", adjustable="datalim")
    ax1.grid(alpha=0.3)
    ax1.set_title(title or res.scene.description or res.scene.name, fontsize=9)
    order = np.argsort(res.angle_deg, kind="stable")
    groups = {(s, w) for s, w in zip(res.speed_mps, res.spin_radps)}
    for s, w in sorted(groups):
        m = (res.speed_mps[order] == s) & (res.spin_radps[order] == w)
        ax2.plot(
            res.angle_deg[order][m],
            res.carry[order][m],
            ".-",
            ms=3,
            label=f"{s:g} m/s, {w:g} rad/s" if len(groups) > 1 else None,
        )
    if best is not None:
        ax2.plot(
            [res.angle_deg[best]],
            [res.carry[best]],
            "r*",
            ms=12,
            label=f"best {res.angle_deg[best]:.4g}°: {res.carry[best]:.3f} m",
        )
    ax2.set_xlabel("launch angle [deg]")
    ax2.set_ylabel("carry [m]")
    ax2.grid(alpha=0.3)
    if ax2.get_legend_handles_labels()[0]:  # (nothing to label when no ball landed)
        ax2.legend(fontsize=7)
    fig.tight_layout()
    save_figure(fig, path, dpi=120)


def plot_table(results: list, path: str | os.PathLike[str]) -> None:
    """The four lab trajectory families of Table 3.1-1 (report Figures 3.1-1 to 3.1-4), 2x2 panels.

    ``results``: (label, best-angle sweep, figure sweep with trajectories) per row of the table.
    """
    fig = Figure(figsize=(12, 7))
    axes = fig.subplots(2, 2)
    for ax, (label, res, fig_res) in zip(axes.ravel(), results):
        k = len(fig_res.traj_index)
        for j, i in enumerate(fig_res.traj_index):
            p = fig_res.traj[j]
            ax.plot(
                p[:, 0],
                p[:, 1] - p[0, 1],
                lw=0.8,
                color=matplotlib.colormaps.get_cmap("viridis")(j / max(k - 1, 1)),
                label=f"{fig_res.angle_deg[i]:g}°" if j in (0, k - 1) else None,
            )
        b = res.best()
        ax.legend(fontsize=7, loc="upper right")
        ax.set_title(f"{label}: best {res.angle_deg[b]:.2f}°, {res.carry[b]:.2f} m", fontsize=9)
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m]")
        ax.grid(alpha=0.3)
        ax.set_ylim(bottom=0)
        ax.set_xlim(0, np.nanmax(fig_res.carry) * 1.05)
    fig.tight_layout()
    save_figure(fig, path, dpi=110)


def plot_run(rec: "Recording", path: str | os.PathLike[str], title: str = "", max_balls: int = 20) -> None:
    """Trajectory side view and spin magnitude |ω| vs time (as the report's Figure 3.2-3)."""
    a = rec.arrays()
    t, x, w = a["traj_t"], a["traj_x"], a["traj_w"]
    fig = Figure(figsize=(9, 7))
    ax1, ax2 = fig.subplots(2, 1, gridspec_kw={"height_ratios": [1.3, 1]})
    n = x.shape[1] if x.ndim == 3 else 0
    shown = x[:, :max_balls] if n else x
    spread = np.ptp(shown.reshape(-1, 3), axis=0) if n else np.zeros(3)
    top = spread[1] < 0.05 * max(spread[0], spread[2], 1e-12)  # everything on the ground: show the top view
    for i in range(min(n, max_balls)):
        ax1.plot(x[:, i, 0], x[:, i, 2] if top else x[:, i, 1], lw=1.0)
        ax2.plot(t, np.linalg.norm(w[:, i, :], axis=1), lw=1.0)
    ax1.set_xlabel("x [m]")
    ax1.set_ylabel("y [m]")
    if top:
        top_view(ax1)
    ax1.set_aspect("equal", adjustable="datalim")
    ax1.grid(alpha=0.3)
    ax1.set_title(title, fontsize=9)
    ax2.set_xlabel("t [s]")
    ax2.set_ylabel("|ω| [rad/s]")
    ax2.grid(alpha=0.3)
    fig.tight_layout()
    save_figure(fig, path, dpi=120)


def plot_terrain_path(
    profile: tuple[np.ndarray, np.ndarray],
    t: np.ndarray,
    x: np.ndarray,
    energy: np.ndarray,
    path: str | os.PathLike[str],
    title: str = "",
    rest: bool = False,
) -> None:
    """A ball on a 2-D terrain (as the report's Figures 3.2-1, 3.2-6 and 3.2-7): the profile (x [m],
    height [m]), each (K,), with the ball's path ``x`` (S, 3) [m] and, below, its mechanical
    energy per unit mass ``energy`` (S,) [J/kg] against ``t`` (S,) [s]. ``rest``: the ball ended
    at rest (its last point is marked so). The heights are drawn to a larger scale than the
    distances when the profile is long and low."""
    px, ph = profile
    fig = Figure(figsize=(10, 6))
    ax1, ax2 = fig.subplots(2, 1, gridspec_kw={"height_ratios": [1.4, 1]})
    low = float(min(ph.min(), x[:, 1].min())) - 0.5
    ax1.fill_between(px, ph, low, color=TERRAIN_FILL, lw=0)
    ax1.plot(px, ph, color="darkgreen", lw=1.0)
    ax1.plot(x[:, 0], x[:, 1], color="tab:red", lw=0.9, label="the ball's centre")
    ax1.plot(x[0, 0], x[0, 1], "o", color="tab:red", ms=5, label="start")
    ax1.plot(x[-1, 0], x[-1, 1], "s" if rest else "D", color="tab:blue", ms=6, label="at rest" if rest else "end")
    top = float(max(ph.max(), np.nanmax(x[:, 1])))
    ax1.set_xlim(float(px.min()), float(px.max()))
    ax1.set_ylim(low, top + 0.15 * (top - low))
    ax1.set_xlabel("x [m]")
    ax1.set_ylabel("y [m]")
    ax1.grid(alpha=0.3)
    ax1.legend(fontsize=7, loc="upper right")
    ax1.set_title(title, fontsize=9)
    ax2.plot(t, energy, color="tab:purple", lw=1.0)
    ax2.set_xlabel("t [s]")
    ax2.set_ylabel("v²/2 + g·y [J/kg]")
    ax2.set_ylim(bottom=min(0.0, float(energy.min())))
    ax2.grid(alpha=0.3)
    fig.tight_layout()
    save_figure(fig, path, dpi=110)


def plot_spin_family(
    labels: list[str],
    t: np.ndarray,
    x: np.ndarray,
    w: np.ndarray,
    path: str | os.PathLike[str],
    title: str = "",
) -> None:
    """Shots launched at several angles (as the report's Figure 3.2-3): the spin |ω| [rad/s] of each
    against time on top, the trajectories (side view, distance and height from the launch point)
    below. ``labels`` (N,), ``t`` (S,) [s], ``x`` and ``w`` (S, N, 3) [m], [rad/s]."""
    fig = Figure(figsize=(10, 7.5))
    ax1, ax2 = fig.subplots(2, 1, gridspec_kw={"height_ratios": [1, 1.3]})
    cmap = matplotlib.colormaps.get_cmap("viridis")
    n = x.shape[1]
    for i in range(n):
        color = cmap(i / max(n - 1, 1))
        ax1.plot(t, np.linalg.norm(w[:, i], axis=1), color=color, lw=1.0, label=labels[i])
        d = np.hypot(x[:, i, 0] - x[0, i, 0], x[:, i, 2] - x[0, i, 2])
        ax2.plot(d, x[:, i, 1] - x[0, i, 1], color=color, lw=1.0, label=labels[i])
    ax1.set_xlabel("t [s]")
    ax1.set_ylabel("|ω| [rad/s]")
    ax1.set_ylim(bottom=0)
    ax1.grid(alpha=0.3)
    ax1.legend(fontsize=7, ncol=2, title="launch angle")
    ax1.set_title(title, fontsize=9)
    ax2.set_xlabel("downrange distance [m]")
    ax2.set_ylabel("height above launch [m]")
    ax2.set_aspect("equal", adjustable="datalim")
    ax2.grid(alpha=0.3)
    fig.tight_layout()
    save_figure(fig, path, dpi=110)


def plot_trajectory(x: np.ndarray, path: str | os.PathLike[str], title: str = "", max_balls: int = 20) -> None:
    """The balls' paths ``x`` (S, N, 3) [m] seen from the side (x, y), or from above (x, z) when
    they stay near the ground; at most ``max_balls`` of them."""
    fig = Figure(figsize=(8, 4.5))
    ax = fig.subplots()
    shown = x[:, :max_balls]
    spread = np.ptp(shown.reshape(-1, 3), axis=0)
    top = spread[1] < 0.05 * max(spread[0], spread[2], 1e-12)  # everything on the ground: the top view
    for i in range(shown.shape[1]):
        ax.plot(shown[:, i, 0], shown[:, i, 2] if top else shown[:, i, 1], lw=1.0)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    if top:
        top_view(ax)
    ax.set_aspect("equal", adjustable="datalim")
    ax.grid(alpha=0.3)
    ax.set_title(title, fontsize=9)
    fig.tight_layout()
    save_figure(fig, path, dpi=120)


def plot_speed(
    t: np.ndarray, v: np.ndarray, path: str | os.PathLike[str], title: str = "", max_balls: int = 20
) -> None:
    """Speed |v| [m/s] against time ``t`` (S,) [s] of velocities ``v`` (S, N, 3), at most ``max_balls``."""
    _time_series(t, np.linalg.norm(v[:, :max_balls], axis=2), "|v| [m/s]", path, title)


def plot_spin(t: np.ndarray, w: np.ndarray, path: str | os.PathLike[str], title: str = "", max_balls: int = 20) -> None:
    """Spin |ω| [rad/s] against time ``t`` (S,) [s] of angular velocities ``w`` (S, N, 3), at most
    ``max_balls`` (as the report's Figure 3.2-3, lower panel)."""
    _time_series(t, np.linalg.norm(w[:, :max_balls], axis=2), "|ω| [rad/s]", path, title)


def _time_series(t: np.ndarray, values: np.ndarray, ylabel: str, path: str | os.PathLike[str], title: str) -> None:
    """One line per ball of ``values`` (S, N) against ``t`` (S,) [s]."""
    fig = Figure(figsize=(8, 3.5))
    ax = fig.subplots()
    for i in range(values.shape[1]):
        ax.plot(t, values[:, i], lw=1.0)
    ax.set_xlabel("t [s]")
    ax.set_ylabel(ylabel)
    ax.grid(alpha=0.3)
    ax.set_title(title, fontsize=9)
    fig.tight_layout()
    save_figure(fig, path, dpi=120)


def plot_tour(flight: "TourFlight", path: str | os.PathLike[str], title: str = "") -> None:
    """Each row of the tour table: the model's carry, apex and land-angle errors against the table,
    with the tolerance shaded (bars in blue within it, red outside)."""
    from ti_golf.golf.tour import APEX_TOL, CARRY_TOL, LAND_TOL

    rows = flight.rows
    n = len(rows)
    x = np.arange(n)
    fig = Figure(figsize=(12, 8))
    axes = fig.subplots(3, 1, sharex=True)
    panels = (
        (flight.carry_error, CARRY_TOL, "carry error [%]", [r.carry_yd for r in rows], "{:.0f} yd"),
        (flight.apex_error, APEX_TOL, "apex error [yd]", [r.apex_yd for r in rows], "{:.0f} yd"),
        (flight.land_error, LAND_TOL, "land angle error [deg]", [r.land_deg for r in rows], "{:.0f}°"),
    )
    for ax, (err, tol, label, table, fmt) in zip(axes, panels):
        ax.axhspan(-tol, tol, color="0.88", label=f"within ±{tol:g}")
        inside = np.abs(err) <= tol
        ax.bar(x, err, width=0.6, color=np.where(inside, "tab:blue", "tab:red"))
        for i in range(n):  # the table's value under each bar
            ax.annotate(
                fmt.format(table[i]),
                (x[i], 0),
                xytext=(0, -3 if err[i] >= 0 else 3),
                textcoords="offset points",
                ha="center",
                va="top" if err[i] >= 0 else "bottom",
                fontsize=6,
                color="0.3",
            )
        ax.axhline(0.0, color="k", lw=0.6)
        lim = max(2.0 * tol, float(np.nanmax(np.abs(err))) * 1.15)
        ax.set_ylim(-lim, lim)
        ax.set_ylabel(label)
        ax.grid(alpha=0.3, axis="y")
        for s in (i for i in range(1, n) if rows[i].tour != rows[i - 1].tour):
            ax.axvline(s - 0.5, color="0.5", lw=0.8)
        ax.legend(fontsize=7, loc="upper right")
    axes[-1].set_xticks(x)
    axes[-1].set_xticklabels([r.name for r in rows], rotation=60, ha="right", fontsize=8)
    axes[0].set_title(
        (title or "TrackMan 2023 tour averages") + ": model − table (grey numbers: the table's values)", fontsize=10
    )
    fig.tight_layout()
    save_figure(fig, path, dpi=110)
