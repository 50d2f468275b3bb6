"""Off-screen pictures of a :class:`~ti_golf.Simulation`: GGUI (Vulkan) when it works, else matplotlib.

:func:`render` draws the balls (lit spheres coloured by status, speed, spin or id), every plane of
the scene as a shaded checkered quad sized to the balls' extent, a terrain height field if the
scene has one, and optional trails, and writes a PNG. A plane is drawn only where balls can be: it
is cut to the open side of the other planes (a bin's floor ends at its walls), and left out when
the camera is on its solid side (a wall between the camera and the balls is cut away). Both
renderers use the same :class:`View` (a pinhole camera: position, look-at point, up, vertical
field of view), so the fallback shows the same picture, only flatter (no depth test between
balls, trails and the ground: they are painted in that order).

GGUI needs Vulkan; without a GPU the software driver works (Debian/Ubuntu:
``apt-get install mesa-vulkan-drivers libvulkan1``, ``make system-deps``). Taichi allows one GGUI
window per process and cannot resize it: the first GGUI picture fixes the size for the process, and
a later picture of another size is drawn with matplotlib (``backend="auto"``) or raises
:class:`RenderError` (``backend="ggui"``).

Camera presets (x downrange, y up, z lateral), each fitted to the bounding box of the balls and
trails (and the horizontal ground below them):

* ``side``: from the +z side, x to the right and y up, as the report's trajectory figures;
* ``top``: from above, x to the right (+z points down the picture);
* ``iso``: an oblique three-quarter view from behind (−x), above and the +z side;
* ``follow``: behind and above ball 0, looking along its horizontal direction of travel.
"""

from __future__ import annotations

import os
import sys
import tempfile
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.collections import LineCollection, PolyCollection
from matplotlib.figure import Figure

from ti_golf.files import atomic_path
from ti_golf.runtime import info

if TYPE_CHECKING:  # pragma: no cover
    from ti_golf.sim.simulation import Simulation
from ti_golf.render.camera import View, _check_size, camera_view
from ti_golf.render.frame import _clip_poly, _Frame, build_frame
from ti_golf.render.ggui import _draw_ggui, _ggui, _GGUIUnavailable, ggui_problem
from ti_golf.render.style import (
    _FALLBACK_NOTE,
    AMBIENT,
    BACKENDS,
    BACKGROUND_COLOR,
    LIGHT,
    RenderError,
)


# -- matplotlib -----------------------------------------------------------------------------------
def _shade(frame: _Frame, points: np.ndarray, normals: np.ndarray) -> np.ndarray:
    to_light = frame.light - points
    to_light /= np.linalg.norm(to_light, axis=1, keepdims=True)
    return AMBIENT + LIGHT * np.clip(np.sum(to_light * normals, axis=1), 0.0, 1.0)


def _tile_collection(frame: _Frame, PolyCollection: Any) -> Any:
    """The planes' and terrain's polygons, cut at the near plane, shaded, far ones first."""
    view = frame.view
    w, h = view.size
    f = view.focal_px
    counts = np.array([len(poly) for poly in frame.tiles])
    shade = _shade(frame, np.array([poly.mean(axis=0) for poly in frame.tiles]), frame.tile_normals)
    colors = np.clip(frame.tile_colors * shade[:, None], 0.0, 1.0)
    polys: list[np.ndarray] = []
    depth: list[float] = []
    source: list[int] = []

    def add(cam: np.ndarray, k: int) -> None:
        polys.append(np.stack([0.5 * w + f * cam[:, 0] / cam[:, 2], 0.5 * h - f * cam[:, 1] / cam[:, 2]], axis=1))
        depth.append(float(cam[:, 2].mean()))
        source.append(k)

    for k_corners in np.unique(counts):  # polygons with the same corner count at once
        sel = np.flatnonzero(counts == k_corners)
        cam = view.to_camera(np.stack([frame.tiles[i] for i in sel]))
        front = (cam[..., 2] >= view.z_near).all(axis=1)
        for i, c in zip(sel[front], cam[front]):
            add(c, i)
        for i, c in zip(sel[~front], cam[~front]):
            c = _clip_poly(c, c[:, 2] - view.z_near)
            if len(c) >= 3:
                add(c, i)
    order = np.argsort(depth, kind="stable")[::-1]
    return PolyCollection(
        [polys[i] for i in order],
        facecolors=colors[np.asarray(source, int)[order]],
        edgecolors="none",
        antialiased=False,
        zorder=1,
    )


def _render_matplotlib(frame: _Frame, path: str) -> None:
    view = frame.view
    w, h = view.size
    dpi = 100.0
    fig = Figure(figsize=(w / dpi, h / dpi), dpi=dpi, facecolor=BACKGROUND_COLOR)
    FigureCanvasAgg(fig)
    ax = fig.add_axes((0.0, 0.0, 1.0, 1.0))
    ax.set_xlim(0, w)
    ax.set_ylim(h, 0)
    ax.set_axis_off()
    ax.set_facecolor(BACKGROUND_COLOR)
    f = view.focal_px
    pt_per_px = 72.0 / dpi
    if frame.tiles:
        ax.add_collection(_tile_collection(frame, PolyCollection))
    if len(frame.segments):
        seg = view.to_camera(frame.segments)  # (M, 2, 3); clip at the near plane
        za, zb = seg[:, 0, 2], seg[:, 1, 2]
        ok = (za > view.z_near) | (zb > view.z_near)
        seg, za, zb = seg[ok], za[ok], zb[ok]
        with np.errstate(divide="ignore", invalid="ignore"):
            s_cut = np.clip((view.z_near - za) / (zb - za), 0.0, 1.0)
        cut_a, cut_b = za < view.z_near, zb < view.z_near
        point = seg[:, 0] + s_cut[:, None] * (seg[:, 1] - seg[:, 0])
        seg[cut_a, 0] = point[cut_a]
        seg[cut_b, 1] = point[cut_b]
        px = np.stack([0.5 * w + f * seg[..., 0] / seg[..., 2], 0.5 * h - f * seg[..., 1] / seg[..., 2]], axis=-1)
        ax.add_collection(
            LineCollection(  # (matplotlib's stubs ask for sequences where it takes arrays)
                px,  # type: ignore[arg-type]
                colors=np.clip(frame.segment_colors[ok], 0, 1),
                linewidths=frame.line_px * pt_per_px,
                zorder=2,
            )
        )
    if len(frame.centers):
        px, depth = view.project(frame.centers)
        dist = np.linalg.norm(frame.centers - np.asarray(view.position), axis=1)
        r_px = frame.radius * f / dist
        ok = (depth > view.z_near) & (depth < view.z_far)
        order = np.flatnonzero(ok)[np.argsort(-depth[ok], kind="stable")]
        c = np.clip(frame.colors[order] * (AMBIENT + 0.75 * LIGHT), 0, 1)
        edge = np.clip(frame.colors[order] * AMBIENT, 0, 1)
        ax.scatter(
            px[order, 0],
            px[order, 1],
            s=(2.0 * r_px[order] * pt_per_px) ** 2,
            c=c,
            edgecolors=edge,  # type: ignore[arg-type]
            linewidths=np.where(r_px[order] > 3.0, 0.6, 0.0),  # type: ignore[arg-type]
            marker="o",
            zorder=3,
        )
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=dpi, facecolor=BACKGROUND_COLOR, format="png")


# -- entry point ----------------------------------------------------------------------------------
def render(
    sim: "Simulation",
    path: str | os.PathLike[str],
    camera: str | View = "iso",
    size: tuple[int, int] = (1280, 720),
    color_by: str | np.ndarray = "status",
    trails: Any = None,
    fov: float = 45.0,
    *,
    backend: str = "auto",
    min_px: float | None = None,
    value_range: tuple[float, float] | None = None,
    extent: np.ndarray | None = None,
) -> str:
    """Draw the simulation's balls to a PNG at ``path``; returns the renderer used, ``"ggui"`` or ``"matplotlib"``.

    Args:
        sim: the simulation to draw (its current state).
        path: the PNG to write (replaced atomically).
        camera: ``"side"``, ``"top"``, ``"iso"``, ``"follow"`` (fitted to the balls) or a :class:`View`.
        size: picture (width, height) in pixels.
        color_by: ``"status"`` (:data:`STATUS_COLORS`), ``"speed"``, ``"spin"``, ``"id"`` or RGB (N, 3).
        trails: past positions to draw as lines: a :class:`~ti_golf.Recording`, a list of (N, 3)
            arrays or an (S, N, 3) array.
        fov: vertical field of view [deg] of the presets.
        backend: ``"auto"`` (GGUI when Vulkan works and Taichi runs on a backend GGUI draws from, the CPU or CUDA, else
            matplotlib with one line on stderr, once per reason and process), ``"ggui"`` (raise
            :class:`RenderError` if GGUI cannot draw) or ``"matplotlib"``.
        min_px: smallest drawn ball radius in pixels, so that far-away balls stay visible
            (default: 1.5, or height/300 on larger pictures).
        value_range: colormap range of ``"speed"`` / ``"spin"`` (default 0 to the largest value).
        extent: points [m], shape (M, 3), that the preset camera and the ground drawn take in
            besides the balls: the frames of a run drawn with the same ``extent`` (and a
            :class:`View` from :func:`camera_view` with it) show one still stage.
    """
    if backend not in BACKENDS:
        raise ValueError(f"backend must be one of {', '.join(BACKENDS)} (got {backend!r})")
    size = _check_size(size)
    if min_px is None:
        min_px = max(1.5, size[1] / 300.0)
    if not float(min_px) >= 0:
        raise ValueError(f"min_px must be >= 0 (got {min_px})")
    view = camera_view(sim, camera, size, fov, trails, extent)
    if isinstance(camera, View) and tuple(view.size) != size:
        view = View(view.position, view.lookat, view.up, view.fov, size, view.z_near, view.z_far)
    frame = build_frame(sim, view, color_by, trails, min_px, value_range, follow=camera == "follow", extent=extent)
    target = Path(path)
    if not target.parent.is_dir():
        raise ValueError(f"cannot write {str(target)!r}: folder {str(target.parent)!r} does not exist")
    fd, tmp = tempfile.mkstemp(suffix=".png", prefix=".ti_golf_render_", dir=target.parent)
    os.close(fd)
    try:
        used = "matplotlib"
        other_arch = arch_ggui_refuses() if backend == "auto" else None
        if other_arch:
            _note(f"GGUI pictures are only drawn with the CPU and CUDA backends (this process runs on {other_arch})")
        elif backend != "matplotlib":
            try:
                _draw_ggui(frame, tmp)
                used = "ggui"
            except _GGUIUnavailable as exc:
                if backend == "ggui":
                    raise RenderError(f"GGUI cannot render: {exc}") from None
                _note(str(exc))
        if used == "matplotlib":
            _render_matplotlib(frame, tmp)
        os.replace(tmp, target)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)
    return used


GGUI_ARCHES = ("x64", "arm64", "cpu", "cuda")
"""The Taichi backends GGUI draws with here: the CPU's, which the tests check, and CUDA, GGUI's own
GPU backend (Taichi's GGUI guide: x64, CUDA, Vulkan)."""


def arch_ggui_refuses() -> str | None:
    """The Taichi backend's name when GGUI is not drawn with it (not in ``GGUI_ARCHES``), else None.

    With ``arch=vulkan`` (software driver, Taichi 1.7.4) GGUI draws particles from garbled vertex
    data (balls missing or huge), so ``backend="auto"`` draws with matplotlib there and the windows
    refuse it; ``backend="ggui"`` still tries any backend.
    """
    rt = info()
    return rt.arch if rt is not None and rt.arch not in GGUI_ARCHES else None


NO_DISPLAY = "needs a display (neither DISPLAY nor WAYLAND_DISPLAY is set)"
"""Why no window can be shown on screen here (see :func:`window_problem`)."""


def window_problem(on_screen: bool = True) -> str | None:
    """Why a GGUI window cannot be opened in this process (one line: what is wrong and what to
    do), or ``None`` when it can; ``on_screen=False`` asks for a hidden window, which needs no
    display. GGUI draws with the CPU and CUDA backends (see :func:`arch_ggui_refuses`) and needs Vulkan."""
    arch = arch_ggui_refuses()
    if arch:
        return f"draws with the CPU or CUDA backend (this process runs on {arch}); leave out --arch and TI_GOLF_ARCH"
    if on_screen and not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
        return NO_DISPLAY
    problem = ggui_problem()
    if problem:
        return f"cannot open a window: {problem} (Debian: apt-get install mesa-vulkan-drivers)"
    return None


def _note(reason: str) -> None:
    """One line on stderr per reason and process: the fallback is noticed, not repeated per frame."""
    if reason not in _ggui.noted:
        _ggui.noted.add(reason)
        print(_FALLBACK_NOTE.format(reason=reason), file=sys.stderr)
