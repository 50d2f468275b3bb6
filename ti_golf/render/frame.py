"""What a picture shows, as geometry both renderers draw: balls, planes, terrain, hole, trails, wind."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:  # pragma: no cover
    from ti_golf.sim.simulation import Simulation
from ti_golf.render.camera import (
    View,
    _bounds,
    _hole_parts,
    _plane_basis,
    _terrain,
    _trail_array,
    ball_colors,
)
from ti_golf.render.style import (
    _FOLLOW_REACH,
    _MAX_TRAIL_SEGMENTS,
    GROUND_COLORS,
    SURFACE_COLORS,
    SURFACE_SHADE,
    TERRAIN_COLORS,
    TRAIL_WHITEN,
    WALL_COLORS,
)


# -- what is drawn --------------------------------------------------------------------------------
@dataclass
class _Frame:
    view: View
    centers: np.ndarray  # (N, 3)
    radius: np.ndarray  # (N,) drawn radius [m] (at least min_px pixels)
    colors: np.ndarray  # (N, 3)
    tiles: list[np.ndarray]  # T convex polygons (k, 3): plane tiles and terrain cells
    tile_normals: np.ndarray  # (T, 3)
    tile_colors: np.ndarray  # (T, 3)
    segments: np.ndarray  # (M, 2, 3) trail segments
    segment_colors: np.ndarray  # (M, 3)
    light: np.ndarray  # point-light position (3,)
    line_px: float


def _nice_step(x: float) -> float:
    e = 10.0 ** math.floor(math.log10(x))
    for m in (1.0, 2.0, 5.0, 10.0):
        if m * e >= x:
            return m * e
    return 10.0 * e  # pragma: no cover


def _footprint(view: View, p: np.ndarray, n: np.ndarray, reach: float) -> np.ndarray:
    """Where the rays through the picture's corners and edge midpoints meet the plane, at most
    ``reach`` from the camera."""
    r, u, f = view.basis()
    tan_y = math.tan(math.radians(view.fov) / 2.0)
    tan_x = tan_y * view.size[0] / view.size[1]
    cam = np.asarray(view.position, float)
    out = []
    for a in (-1.0, 0.0, 1.0):
        for b in (-1.0, 0.0, 1.0):
            ray = f + a * tan_x * r + b * tan_y * u
            ray /= np.linalg.norm(ray)
            denom = ray @ n
            t = ((p - cam) @ n) / denom if denom < -1e-12 else np.inf
            q = cam + min(t, reach) * ray
            out.append(q - ((q - p) @ n) * n)
    return np.array(out)


def _plane_tiles(
    view: View,
    plane_p: np.ndarray,
    plane_n: np.ndarray,
    lo: np.ndarray,
    hi: np.ndarray,
    r_max: float,
    reach: float = 0.0,
) -> tuple[list[np.ndarray], np.ndarray, np.ndarray]:
    """Checkered quads of every plane seen from its open side, sized to the box ``lo``–``hi`` (and,
    with ``reach`` > 0, to what the camera sees of the plane up to that distance)."""
    cam = np.asarray(view.position)
    corners = np.array([[a, b, c] for a in (lo[0], hi[0]) for b in (lo[1], hi[1]) for c in (lo[2], hi[2])])
    extra = [np.asarray(view.lookat)]
    if np.linalg.norm(np.subtract(view.lookat, cam)) > 0:  # include what the camera looks toward
        extra.append(cam + 3.0 * (np.asarray(view.lookat) - cam))
    pts = np.vstack([corners, *extra])
    tiles: list[np.ndarray] = []
    normals, colors = [], []
    span = float(np.max(hi - lo))
    planes = [(np.asarray(p, float), np.asarray(n, float) / np.linalg.norm(n)) for p, n in zip(plane_p, plane_n)]
    for j, (p, n) in enumerate(planes):
        if (cam - p) @ n <= 0.0:  # the camera is inside the solid side: cut the plane away
            continue
        t1, t2 = _plane_basis(n)
        seen = np.vstack([pts, _footprint(view, p, n, reach)]) if reach > 0 else pts
        uv = np.stack([(seen - p) @ t1, (seen - p) @ t2], axis=1)
        ground = abs(n[1]) > 0.7
        margin = (0.3 * span if ground else 0.05 * span) + 5.0 * r_max
        ulo, vlo = uv.min(axis=0) - margin
        uhi, vhi = uv.max(axis=0) + margin
        step = _nice_step(max(uhi - ulo, vhi - vlo) / 16.0)
        while max(uhi - ulo, vhi - vlo) / step > 64:
            step = _nice_step(step * 1.5)
        i0, i1 = math.floor(ulo / step), math.ceil(uhi / step)
        j0, j1 = math.floor(vlo / step), math.ceil(vhi / step)
        i_grid, j_grid = np.meshgrid(np.arange(i0, i1), np.arange(j0, j1), indexing="ij")
        ii, jj = i_grid.ravel(), j_grid.ravel()
        quad = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], float)
        u = (ii[:, None] + quad[None, :, 0]) * step
        v = (jj[:, None] + quad[None, :, 1]) * step
        quads = p + u[..., None] * t1 + v[..., None] * t2
        palette = np.array(GROUND_COLORS if ground else WALL_COLORS)
        kept, keep_idx = _clip_to_open_sides(quads, [pl for i, pl in enumerate(planes) if i != j])
        tiles.extend(kept)
        normals.append(np.broadcast_to(n, (len(kept), 3)))
        colors.append(palette[(ii + jj) % 2][keep_idx])
    if not tiles:
        return [], np.zeros((0, 3)), np.zeros((0, 3))
    return tiles, np.concatenate(normals), np.concatenate(colors)


def _clip_poly(poly: np.ndarray, d: np.ndarray) -> np.ndarray:
    """The part of a convex polygon (k, 3) where the signed distance ``d`` (k,) is >= 0."""
    out = []
    k = len(poly)
    for i in range(k):
        a, b, da, db = poly[i], poly[(i + 1) % k], d[i], d[(i + 1) % k]
        if da >= 0:
            out.append(a)
        if (da >= 0) != (db >= 0):
            out.append(a + (da / (da - db)) * (b - a))
    return np.array(out).reshape(-1, 3)


def _clip_to_open_sides(
    quads: np.ndarray, planes: list[tuple[np.ndarray, np.ndarray]]
) -> tuple[list[np.ndarray], np.ndarray]:
    """Cut a plane's tiles (T, 4, 3) to the open side of every other plane (the space balls can
    reach): a bin's floor stops at its walls and the walls at the floor. Returns the polygons and
    the indices of the tiles they come from."""
    if not planes:
        return list(quads), np.arange(len(quads))
    eps = 1e-9 * (1.0 + float(np.abs(quads).max()))
    d = np.stack([(quads - q) @ m for q, m in planes])  # (P, T, 4)
    inside = d >= -eps
    whole = np.asarray(inside.all(axis=(0, 2)))
    gone = np.asarray((~inside).all(axis=2).any(axis=0))
    out: list[np.ndarray] = []
    idx = []
    for t in range(len(quads)):
        if gone[t]:
            continue
        poly = quads[t]
        if not whole[t]:
            for q, m in planes:
                poly = _clip_poly(poly, (poly - q) @ m)
                if len(poly) < 3:
                    break
            if len(poly) < 3:
                continue
        out.append(poly)
        idx.append(t)
    return out, np.asarray(idx, dtype=int)


def _surface_types(sim: Simulation) -> tuple[np.ndarray, tuple[str, ...]] | None:
    """The terrain's surface type of every cell (nx − 1, nz − 1) and the types' names, if the scene
    names any that has a colour (``SURFACE_COLORS``)."""
    t = getattr(sim.model, "terrain", None)
    cells = getattr(t, "cells", None)
    names = tuple(f.name for f in sim.scene.surfaces)
    if cells is None or not any(name in SURFACE_COLORS for name in names):
        return None
    return np.asarray(cells), names


def _terrain_tiles(
    h: np.ndarray,
    origin: np.ndarray,
    spacing: np.ndarray,
    surfaces: tuple[np.ndarray, tuple[str, ...]] | None = None,
    max_cells: int = 128,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The height field as flat-shaded quads (at most ``max_cells`` per axis), tinted by height,
    or with ``surfaces`` (:func:`_surface_types`) coloured by the surface type of the cell at each
    quad's middle (``SURFACE_COLORS``, shaded by height)."""
    nx, nz = h.shape
    ii = np.unique(np.r_[np.arange(0, nx, max(1, math.ceil((nx - 1) / max_cells))), nx - 1])
    kk = np.unique(np.r_[np.arange(0, nz, max(1, math.ceil((nz - 1) / max_cells))), nz - 1])
    x = origin[0] + ii * spacing[0]
    z = origin[2] + kk * spacing[1]
    y = origin[1] + h[np.ix_(ii, kk)]
    p = np.stack(np.broadcast_arrays(x[:, None], y, z[None, :]), axis=-1)
    quads = np.stack([p[:-1, :-1], p[1:, :-1], p[1:, 1:], p[:-1, 1:]], axis=2).reshape(-1, 4, 3)
    n = np.cross(quads[:, 3] - quads[:, 1], quads[:, 2] - quads[:, 0])
    n *= np.where(n[:, 1] < 0, -1.0, 1.0)[:, None]
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-12)
    hy = quads[:, :, 1].mean(axis=1)
    span = float(np.ptp(hy)) if hy.size else 0.0
    t = (hy - hy.min()) / span if span > 0 else np.zeros_like(hy)
    low, high = np.array(TERRAIN_COLORS[0]), np.array(TERRAIN_COLORS[1])
    colors = low + t[:, None] * (high - low)
    if surfaces is not None:
        cells, names = surfaces
        mid_i = np.minimum((ii[:-1] + ii[1:]) // 2, cells.shape[0] - 1)
        mid_k = np.minimum((kk[:-1] + kk[1:]) // 2, cells.shape[1] - 1)
        kind = cells[np.ix_(mid_i, mid_k)].ravel()
        shade = SURFACE_SHADE[0] + t * (SURFACE_SHADE[1] - SURFACE_SHADE[0])
        for k, name in enumerate(names):
            if name in SURFACE_COLORS:
                here = kind == k
                colors[here] = np.clip(np.outer(shade[here], SURFACE_COLORS[name]), 0.0, 1.0)
    a, b = np.meshgrid(np.arange(len(ii) - 1), np.arange(len(kk) - 1), indexing="ij")
    colors *= np.where(((a // 4 + b // 4) % 2).ravel() == 1, 0.92, 1.0)[:, None]
    return quads, n, colors


def _trail_segments(trail: np.ndarray | None, x: np.ndarray, colors: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    if trail is None or len(trail) == 0:
        return np.zeros((0, 2, 3)), np.zeros((0, 3))
    if not np.allclose(trail[-1], x):
        trail = np.concatenate([trail, x[None]])
    s, n, _ = trail.shape
    if s < 2:
        return np.zeros((0, 2, 3)), np.zeros((0, 3))
    n_draw = min(n, _MAX_TRAIL_SEGMENTS)
    stride = max(1, math.ceil((s - 1) * n_draw / _MAX_TRAIL_SEGMENTS))
    idx = np.unique(np.r_[np.arange(0, s, stride), s - 1])
    t = trail[idx][:, :n_draw]
    seg = np.stack([t[:-1], t[1:]], axis=2).reshape(-1, 2, 3)
    tint = (1.0 - TRAIL_WHITEN) * colors[:n_draw] + TRAIL_WHITEN
    col = np.broadcast_to(tint, (len(idx) - 1, n_draw, 3)).reshape(-1, 3)
    ok = np.all(np.isfinite(seg), axis=(1, 2))
    return seg[ok], col[ok]


WIND_COLOR = (0.15, 0.35, 0.95)
"""Colour of the wind indicator."""


def _wind_arrow(wind: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Segments (k, 2, 3) and colours (k, 3) of an arrow showing the wind, centred high in the scene.

    Its length grows with the speed, |w|/(|w| + 5 m/s) of a third of the scene's extent; no arrow
    in still air.
    """
    speed = float(np.linalg.norm(wind))
    if speed == 0.0 or not np.all(np.isfinite(wind)):
        return np.zeros((0, 2, 3)), np.zeros((0, 3))
    extent = max(float(np.max(hi - lo)), 1e-6)
    d = wind / speed
    length = 0.33 * extent * speed / (speed + 5.0)
    center = 0.5 * (lo + hi)
    tail = np.array([center[0], hi[1] - 0.1 * (hi[1] - lo[1]), center[2]]) - 0.5 * length * d
    head = tail + length * d
    side = np.cross(d, [0.0, 1.0, 0.0])
    side = side / np.linalg.norm(side) if np.linalg.norm(side) > 1e-9 else np.array([1.0, 0.0, 0.0])
    up = np.cross(side, d)  # barbs in two planes: the head reads from any camera
    seg = np.array([[tail, head]] + [[head, head - 0.3 * length * (d + 0.5 * b)] for b in (side, -side, up, -up)])
    return seg, np.tile(WIND_COLOR, (len(seg), 1))


def build_frame(
    sim: "Simulation",
    view: View,
    color_by: Any,
    trails: Any,
    min_px: float,
    value_range: tuple[float, float] | None,
    follow: bool = False,
    extent: np.ndarray | None = None,
    x: np.ndarray | None = None,
) -> _Frame:
    """What :func:`render` draws of ``sim`` seen through ``view`` (arguments as there; ``follow``
    for the follow camera's reach): balls, planes, terrain, cup and flag, trails, wind arrow, light.
    ``x``: the balls' centres (N, 3) [m] when the caller has read them, else they are read."""
    x = sim.x if x is None else x
    radius = sim.model.radius_np.astype(float)
    colors = ball_colors(sim, color_by, value_range)
    trail = _trail_array(trails, sim.n)
    lo, hi = _bounds(sim, trail, extent, x)
    r_max = float(radius.max())
    reach = _FOLLOW_REACH * float(np.linalg.norm(np.subtract(view.lookat, view.position))) if follow else 0.0
    tiles, tile_n, tile_c = _plane_tiles(view, sim.model.plane_p, sim.model.plane_n, lo, hi, r_max, reach)
    terr = _terrain(sim)
    if terr is not None:
        t_tiles, t_n, t_c = _terrain_tiles(*terr, surfaces=_surface_types(sim))
        tiles = tiles + list(t_tiles)
        tile_n, tile_c = np.concatenate([tile_n, t_n]), np.concatenate([tile_c, t_c])
    h_tiles, h_n, h_c, h_seg, h_seg_c = _hole_parts(sim, view, min_px)
    tiles = tiles + h_tiles
    tile_n, tile_c = np.concatenate([tile_n, h_n]), np.concatenate([tile_c, h_c])
    seg, seg_c = _trail_segments(trail, x, colors)
    w_seg, w_col = _wind_arrow(np.asarray(sim.scene.air.wind, float), lo, hi)
    seg, seg_c = np.concatenate([seg, w_seg, h_seg]), np.concatenate([seg_c, w_col, h_seg_c])
    dist = np.linalg.norm(x - np.asarray(view.position), axis=1)
    drawn = np.maximum(radius, float(min_px) * dist / view.focal_px)
    right, _, fwd = view.basis()
    center = 0.5 * (lo + hi)
    far = max(float(np.linalg.norm(hi - lo)), float(np.linalg.norm(center - np.asarray(view.position))))
    light_dir = 0.35 * right + 1.0 * np.array([0.0, 1.0, 0.0]) - 0.5 * fwd
    light = center + 4.0 * far * light_dir / np.linalg.norm(light_dir)
    line_px = max(1.0, round(view.size[1] / 360.0))
    return _Frame(view, x, drawn, colors, tiles, tile_n, tile_c, seg, seg_c, light, line_px)
