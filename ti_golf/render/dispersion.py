"""Top view of a dispersion: landing points, points of rest and the landing ellipses."""

from __future__ import annotations

import os
from typing import TYPE_CHECKING

import numpy as np
from matplotlib.figure import Figure

from ti_golf.render.plots import save_figure
from ti_golf.scene.launch_monitor import Units

if TYPE_CHECKING:  # pragma: no cover
    from ti_golf.golf.dispersion import Dispersion

MAX_DRAWN = 50_000
"""The most points drawn (the first ones: the draws are in random order); the ellipses use all."""


def plot_dispersion(d: "Dispersion", units: Units, path: str | os.PathLike[str], title: str = "") -> None:
    """Landing points (and points of rest, when rolled out) seen from above, the target up the page,
    right to the right, with the 68 % and 95 % landing ellipses, in ``units``' distances."""
    f, lab = units.distance, units.distance_label
    fig = Figure(figsize=(8.0, 5.5))
    ax = fig.subplots()
    n = len(d.shots)
    k = min(n, MAX_DRAWN)
    rest = d.rest_points()[:k] / f
    if np.any(np.isfinite(rest)):
        ax.plot(rest[:, 0], rest[:, 1], ".", ms=1.5, color="0.6", alpha=0.35, rasterized=True)
        ax.plot([], [], ".", ms=8, color="0.6", label="at rest")  # the legend's marker
    land = d.landing_points()[:k] / f
    ax.plot(land[:, 0], land[:, 1], ".", ms=1.5, color="tab:blue", alpha=0.35, rasterized=True)
    ax.plot([], [], ".", ms=8, color="tab:blue", label="landing")
    for e, colour in zip(d.ellipses(), ("tab:orange", "tab:red")):
        o = e.outline() / f
        ax.plot(
            o[:, 0],
            o[:, 1],
            color=colour,
            lw=1.8,
            label=f"{100 * e.p:.0f} % ellipse: {e.semi_major / f:.1f} × {e.semi_minor / f:.1f} {lab} "
            f"(holds {100 * e.inside:.1f} %)",
        )
    c = d.ellipses((0.68,))[0].center / f
    ax.plot([c[0]], [c[1]], "k+", ms=12, mew=2, label=f"mean landing: {c[1]:.1f} {lab}, {c[0]:+.1f} {lab} offline")
    ax.axvline(0.0, color="k", lw=0.8, ls="--", alpha=0.6)
    ax.set_xlabel(f"offline [{lab}] (+ right of the target line)")
    ax.set_ylabel(f"along the target line [{lab}]")
    ax.set_aspect("equal", adjustable="datalim")
    ax.grid(alpha=0.3)
    shown = f" ({k:,} drawn)" if k < n else ""
    ax.set_title(title or f"{n:,} shots{shown}, seed {d.seed}", fontsize=9)
    ax.legend(fontsize=7, loc="lower left")
    fig.tight_layout()
    save_figure(fig, path, dpi=130)
