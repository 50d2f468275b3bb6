"""A round of the golf game drawn on a map of its course (``ti-golf play --plot``)."""

from __future__ import annotations

import os

import matplotlib
import numpy as np
from matplotlib.colors import ListedColormap
from matplotlib.figure import Figure
from matplotlib.patches import Patch

from ti_golf.game.rules import GolfGame
from ti_golf.render.plots import save_figure, top_view
from ti_golf.render.style import SURFACE_COLORS


def plot_round(game: GolfGame, path: str | os.PathLike[str], title: str = "") -> None:
    """Top view of a golf round (z down the page, as seen from above: :func:`ti_golf.render.plots.top_view`): the course (its surface types, else its heights, with height
    contours), the cup and every stroke's path, numbered; beside it the 12 m around the cup."""
    ter = game.terrain
    (x0, z0), (sx, sz) = ter.origin[[0, 2]], ter.size
    extent = (x0, x0 + sx, z0, z0 + sz)
    fig = Figure(figsize=(13, 13 / (sx / sz + 1.0) + 1.2))
    ax, zoom = fig.subplots(1, 2, gridspec_kw={"width_ratios": [sx / sz, 1.0]})
    xs, zs = np.linspace(x0, x0 + sx, ter.shape[0]), np.linspace(z0, z0 + sz, ter.shape[1])
    heights = ter.heights.T + ter.origin[1]
    surfaces = game.scene.surfaces
    handles = []
    for a in (ax, zoom):
        if ter.cells is not None and surfaces:
            colors = [SURFACE_COLORS.get(f.name, (0.69, 0.69, 0.69)) for f in surfaces]
            a.imshow(
                ter.cells.T,
                origin="lower",
                extent=extent,
                cmap=ListedColormap(colors),
                vmin=-0.5,
                vmax=len(surfaces) - 0.5,
                interpolation="nearest",
            )
            handles = [Patch(color=c, label=f.name or f"surface {k}") for k, (f, c) in enumerate(zip(surfaces, colors))]
        else:
            a.imshow(heights, origin="lower", extent=extent, cmap="summer")
        cs = a.contour(xs, zs, heights, levels=12 if a is ax else 40, colors="k", linewidths=0.3, alpha=0.5)
        a.clabel(cs, fontsize=6, fmt="%.2f m")
        for s in game.strokes:
            color = matplotlib.colormaps.get_cmap("autumn")((s.number - 1) / max(len(game.strokes) - 1, 1))
            a.plot(s.path[:, 0], s.path[:, 2], color=color, lw=1.5)
            a.annotate(
                str(s.number),
                s.start[[0, 2]],
                color="k",
                fontsize=8,
                ha="center",
                va="center",
                bbox={"boxstyle": "circle,pad=0.2", "fc": "white", "ec": color},
                annotation_clip=True,
            )
        a.plot(*game.cup[[0, 2]], "k^", ms=8, zorder=5, label="the hole")
        a.plot(*game.ball[[0, 2]], "o", color="white", mec="k", ms=5, zorder=6, label="the ball")
        a.set_xlabel("x [m]")
    cup = game.cup[[0, 2]]
    zoom.set_xlim(cup[0] - 6.0, cup[0] + 6.0)
    zoom.set_ylim(cup[1] - 6.0, cup[1] + 6.0)
    for a in (ax, zoom):
        top_view(a, "z [m]")
    zoom.set_title("12 m around the cup", fontsize=9)
    ax.legend(handles=ax.get_legend_handles_labels()[0] + handles, loc="upper left", fontsize=7)
    ax.set_title(title or game.scene.name, fontsize=10)
    fig.tight_layout()
    save_figure(fig, path, dpi=110)
