"""A study's figure against its varied keys: lines for one key (or two, with ``lines``), a heat map
for two. Repetitions (seeds) of a point are averaged; failed tasks are left out."""

from __future__ import annotations

import math
import os
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from ti_golf.errors import ConfigError
from ti_golf.render.plots import save_figure


def figure_columns(table: Mapping[str, list[Any]], keys: Sequence[str]) -> list[str]:
    """The columns of the table that hold figures."""
    from ti_golf.study.results import BOOKKEEPING

    return [c for c in table if c not in ("task_id", "seed", *keys, *BOOKKEEPING)]


def check_plottable(keys: Sequence[str]) -> None:
    """Refuse ``--plot`` for a study that varies other than one or two keys (``keys``)."""
    if not 1 <= len(keys) <= 2:
        raise ConfigError(
            "--plot", None, f"draws a figure against one or two varied keys (the study varies {len(keys)})"
        )


def plot_study(
    table: Mapping[str, list[Any]],
    keys: Sequence[str],
    column: str,
    path: str | os.PathLike[str],
    title: str = "",
    lines: bool = False,
) -> None:
    """Plot ``column`` of a study's ``table`` against its varied ``keys`` (one or two) to ``path``."""
    if column not in table:
        raise ConfigError(
            "--figure", None, f"the table has no column {column!r}; it has: {', '.join(figure_columns(table, keys))}"
        )
    check_plottable(keys)
    ok = [s == "ok" for s in table["status"]]
    means: dict[tuple[Any, ...], list[float]] = {}
    for i, good in enumerate(ok):
        value = table[column][i]
        if good and value is not None and math.isfinite(value):
            means.setdefault(tuple(table[k][i] for k in keys), []).append(value)
    if not means:
        raise ConfigError("--figure", None, f"no finished task has a value of {column!r} to plot")
    fig = Figure(figsize=(7.0, 4.5), layout="constrained")
    ax = fig.add_subplot()
    xs = sorted({p[0] for p in means}, key=_order)
    if len(keys) == 1:
        ax.plot(xs, [np.mean(means[(x,)]) for x in xs], "o-")
        ax.set_ylabel(column)
    else:
        ys = sorted({p[1] for p in means}, key=_order)
        if lines:
            for y in ys:
                pts = [(x, np.mean(means[(x, y)])) for x in xs if (x, y) in means]
                ax.plot([p[0] for p in pts], [p[1] for p in pts], "o-", label=f"{keys[1]} = {y}")
            ax.set_ylabel(column)
            ax.legend(fontsize="small")
        else:
            grid = np.full((len(ys), len(xs)), np.nan)
            for (x, y), values in means.items():
                grid[ys.index(y), xs.index(x)] = np.mean(values)
            image = ax.imshow(grid, origin="lower", aspect="auto", cmap="viridis")
            ax.set_xticks(range(len(xs)), [f"{x:g}" if isinstance(x, float) else str(x) for x in xs])
            ax.set_yticks(range(len(ys)), [f"{y:g}" if isinstance(y, float) else str(y) for y in ys])
            ax.set_ylabel(keys[1])
            fig.colorbar(image, ax=ax, label=column)
            for (j, i), v in np.ndenumerate(grid):
                if math.isfinite(v):
                    ax.text(i, j, f"{v:.4g}", ha="center", va="center", fontsize=7, color="white")
    ax.set_xlabel(keys[0])
    if len(keys) == 1 or lines:
        ax.grid(alpha=0.3)
    ax.set_title(title or column, fontsize="medium")
    save_figure(fig, path, dpi=120)


def _order(value: Any) -> tuple[int, Any]:
    return (0, value) if isinstance(value, (int, float)) else (1, str(value))
