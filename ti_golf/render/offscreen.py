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

import atexit
import math
import os
import shutil
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Sequence

import numpy as np

from ti_golf.scene.schema import AT_REST, FLYING, OUT_OF_BOUNDS, ROLLING
from ti_golf.errors import TiGolfError

if TYPE_CHECKING:  # pragma: no cover
    from ti_golf.sim.simulation import Simulation

__all__ = [
    "AT_REST_COLOR",
    "BACKGROUND_COLOR",
    "CAMERAS",
    "COLOR_BY",
    "FLYING_COLOR",
    "GROUND_COLORS",
    "OUT_OF_BOUNDS_COLOR",
    "ROLLING_COLOR",
    "STATUS_COLORS",
    "TERRAIN_COLORS",
    "WALL_COLORS",
    "RenderError",
    "View",
    "ball_colors",
    "build_frame",
    "camera_view",
    "draw_scene",
    "ggui_available",
    "ggui_problem",
    "non_cpu_arch",
    "render",
    "write_png",
]

# -- colours (RGB in [0, 1]) ----------------------------------------------------------------------
FLYING_COLOR = (0.95, 0.36, 0.08)
"""Balls in the air: orange."""
ROLLING_COLOR = (0.98, 0.82, 0.10)
"""Balls touching a plane or another ball and moving: yellow."""
AT_REST_COLOR = (0.15, 0.36, 0.92)
"""Balls put at rest: blue."""
OUT_OF_BOUNDS_COLOR = (0.66, 0.18, 0.80)
"""Balls out of bounds: purple."""
STATUS_COLORS = {FLYING: FLYING_COLOR, ROLLING: ROLLING_COLOR, AT_REST: AT_REST_COLOR,
                 OUT_OF_BOUNDS: OUT_OF_BOUNDS_COLOR}
"""Ball colour per status code (``color_by="status"``)."""
BACKGROUND_COLOR = (0.80, 0.86, 0.92)
"""The sky: a pale grey-blue."""
GROUND_COLORS = ((0.38, 0.58, 0.30), (0.33, 0.52, 0.26))
"""Checker colours of planes facing up (|n_y| > 0.7): two greens."""
WALL_COLORS = ((0.72, 0.70, 0.66), (0.64, 0.62, 0.58))
"""Checker colours of other planes: two greys."""
TERRAIN_COLORS = ((0.30, 0.50, 0.24), (0.62, 0.66, 0.40))
"""Terrain colours from its lowest to its highest point: dark green to dry grass."""
SURFACE_COLORS = {"green": (0.36, 0.72, 0.36), "fairway": (0.55, 0.78, 0.40), "rough": (0.42, 0.56, 0.14),
                  "bunker": (0.91, 0.85, 0.63)}
"""Terrain colours of the surface types (``[[surfaces]]``) by name; the cells of a type not named
here, and a terrain without types, are tinted by height (``TERRAIN_COLORS``). The course map of
:func:`ti_golf.render.plots.plot_round` uses the same colours."""
SURFACE_SHADE = (0.88, 1.05)
"""A surface type's colour is scaled from the first factor at the terrain's lowest point to the
second at its highest, so that the relief still reads within one type."""
HOLE_COLOR = (0.03, 0.03, 0.03)
"""The cup: near black."""
FLAG_COLOR = (0.90, 0.08, 0.10)
"""The flag: red, on a white stick (``FLAGSTICK_COLOR``)."""
FLAGSTICK_COLOR = (0.97, 0.97, 0.97)
AMBIENT = 0.45
LIGHT = 0.65
TRAIL_WHITEN = 0.5
"""Trails are drawn in the ball's colour blended this much toward white."""
COLORMAPS = {"speed": "viridis", "spin": "plasma", "id": "tab20"}

CAMERAS = ("side", "top", "iso", "follow")
COLOR_BY = ("status", "speed", "spin", "id")
BACKENDS = ("auto", "ggui", "matplotlib")
_MAX_TRAIL_SEGMENTS = 1_000_000
_FOLLOW_REACH = 300.0
"""The follow camera shows planes up to this many camera distances away."""
_FALLBACK_NOTE = "ti_golf: {reason}, rendering with matplotlib"


class RenderError(TiGolfError):
    """GGUI was asked for explicitly (``backend="ggui"``) and cannot draw this picture."""


# -- camera ---------------------------------------------------------------------------------------
@dataclass(frozen=True)
class View:
    """A pinhole camera and the picture size.

    Attributes:
        position, lookat, up: camera position, the point it looks at and the up hint [m].
        fov: vertical field of view [deg].
        size: picture (width, height) in pixels.
        z_near, z_far: clipping distances along the viewing direction [m].
    """

    position: tuple[float, float, float]
    lookat: tuple[float, float, float]
    up: tuple[float, float, float] = (0.0, 1.0, 0.0)
    fov: float = 45.0
    size: tuple[int, int] = (1280, 720)
    z_near: float = 0.01
    z_far: float = 1.0e4

    def basis(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Unit vectors (right, up, forward) of the camera, right-handed as GGUI's."""
        f = np.subtract(self.lookat, self.position).astype(float)
        f /= np.linalg.norm(f)
        r = np.cross(f, self.up)
        if np.linalg.norm(r) < 1e-12:  # up hint parallel to the viewing direction
            r = np.cross(f, (0.0, 0.0, -1.0) if abs(f[1]) > 0.5 else (0.0, 1.0, 0.0))
        r /= np.linalg.norm(r)
        return r, np.cross(r, f), f

    @property
    def focal_px(self) -> float:
        """Pixels per unit of (lateral offset / depth): H / (2 tan(fov/2))."""
        return self.size[1] / (2.0 * math.tan(math.radians(self.fov) / 2.0))

    def to_camera(self, points: np.ndarray) -> np.ndarray:
        """Points (..., 3) in camera coordinates (right, up, depth along the viewing direction)."""
        r, u, f = self.basis()
        d = np.asarray(points, dtype=float) - np.asarray(self.position, dtype=float)
        return np.stack([d @ r, d @ u, d @ f], axis=-1)

    def project(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Pixel coordinates (..., 2) (x right, y down, pixel centres at +0.5) and depth (...,).

        Points at or behind the camera get NaN pixel coordinates; compare the depth with ``z_near``.
        """
        c = self.to_camera(points)
        depth = c[..., 2]
        with np.errstate(divide="ignore", invalid="ignore"):
            inv = np.where(depth > 0, 1.0 / depth, np.nan)
        w, h = self.size
        px = np.stack([0.5 * w + self.focal_px * c[..., 0] * inv, 0.5 * h - self.focal_px * c[..., 1] * inv], axis=-1)
        return px, depth


def _preset_direction(camera: str) -> tuple[np.ndarray, np.ndarray]:
    """Viewing direction (camera toward scene) and up hint of a fixed preset."""
    if camera == "side":
        return np.array([0.0, 0.0, -1.0]), np.array([0.0, 1.0, 0.0])
    if camera == "top":
        return np.array([0.0, -1.0, 0.0]), np.array([0.0, 0.0, -1.0])
    f = -np.array([-0.5, 0.6, 1.0])  # iso: camera behind (−x), above and on the +z side
    return f / np.linalg.norm(f), np.array([0.0, 1.0, 0.0])


def _fit(lo: np.ndarray, hi: np.ndarray, forward: np.ndarray, up: np.ndarray, size: tuple[int, int],
         fov: float, margin: float = 1.1) -> View:
    """The camera looking along ``forward`` at the box's centre from just far enough to see all of it."""
    center = 0.5 * (lo + hi)
    corners = np.array([[a, b, c] for a in (lo[0], hi[0]) for b in (lo[1], hi[1]) for c in (lo[2], hi[2])]) - center
    probe = View(tuple(center - forward), tuple(center), tuple(up), fov, size)
    r, u, f = probe.basis()
    a, b, w = corners @ r, corners @ u, corners @ f
    tan_y = math.tan(math.radians(fov) / 2.0)
    tan_x = tan_y * size[0] / size[1]
    d = max(float(np.max(margin * np.abs(a) / tan_x - w)), float(np.max(margin * np.abs(b) / tan_y - w)),
            float(np.max(-w)) * 1.05)
    half_diag = float(np.linalg.norm(hi - lo)) / 2.0
    d = max(d, 1e-6)
    z_near = max(1e-4 * d, 0.5 * (d - half_diag))
    z_far = 4.0 * (d + half_diag) + 10.0 * half_diag
    return View(tuple(center - d * f), tuple(center), tuple(u), float(fov), size, z_near, z_far)


def _scene_bounds(points: np.ndarray, radius: np.ndarray, plane_p: np.ndarray, plane_n: np.ndarray
                  ) -> tuple[np.ndarray, np.ndarray]:
    """Bounding box of the balls (with their radii) and trail points, reaching down to a horizontal
    ground below them, at least 10 ball radii wide along each axis."""
    r_max = float(np.max(radius)) if radius.size else 0.02
    pts = points[np.all(np.isfinite(points), axis=1)]
    if len(pts) == 0:
        pts = np.zeros((1, 3))
    lo, hi = pts.min(axis=0) - r_max, pts.max(axis=0) + r_max
    for p, n in zip(plane_p, plane_n):
        if n[1] > 0.99 and p[1] <= lo[1]:  # an upward-facing floor under the balls
            lo[1] = float(p[1])
    half = np.maximum(0.5 * (hi - lo), 5.0 * r_max)
    c = 0.5 * (lo + hi)
    return c - half, c + half


def _terrain(sim: "Simulation") -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """The scene's height field as (heights (nx, nz), origin (3,), spacing (2,)), if it has one."""
    t = getattr(sim.model, "terrain", None)
    if t is None:
        return None
    try:
        h = np.asarray(t.heights, float)
        origin, spacing = np.asarray(t.origin, float).reshape(3), np.asarray(t.spacing, float).reshape(2)
    except (AttributeError, TypeError, ValueError):  # pragma: no cover - another terrain representation
        return None
    if h.ndim != 2 or min(h.shape) < 2 or not np.all(np.isfinite(h)):
        return None
    return h, origin, spacing


def _hole(sim: "Simulation") -> tuple[np.ndarray, np.ndarray, float, float] | None:
    """The scene's cup as (centre (3,) on the course, surface normal (3,), radius, flag height) [m],
    or None. The centre sits on the terrain, else on the first upward-facing plane (the ground)."""
    hole = getattr(sim.scene, "hole", None)
    if hole is None:
        return None
    x, z = map(float, hole.position)
    t = getattr(sim.model, "terrain", None)
    if t is not None:
        return (np.array([x, float(t.height(x, z)), z]), np.asarray(t.normal(x, z), float).reshape(3),
                float(hole.radius), float(hole.flag_height))
    y, n = 0.0, np.array([0.0, 1.0, 0.0])
    for p, m in zip(np.asarray(sim.model.plane_p, float), np.asarray(sim.model.plane_n, float)):
        if m[1] > 0.7:  # the ground: y where the plane meets the vertical through (x, z)
            y, n = float(p[1] - (m[0] * (x - p[0]) + m[2] * (z - p[2])) / m[1]), m / np.linalg.norm(m)
            break
    return np.array([x, y, z]), n, float(hole.radius), float(hole.flag_height)


def _hole_parts(sim: "Simulation", view: View, min_px: float) -> tuple[list[np.ndarray], np.ndarray, np.ndarray,
                                                                       np.ndarray, np.ndarray]:
    """The cup (a dark disc just above the surface, at least ``min_px`` pixels across), the
    flagstick (a segment) and the flag (a triangle flying downwind, else along +x): tiles, tile
    normals, tile colours, segments (k, 2, 3) and segment colours."""
    got = _hole(sim)
    if got is None:
        return [], np.zeros((0, 3)), np.zeros((0, 3)), np.zeros((0, 2, 3)), np.zeros((0, 3))
    c, n, r, flag_h = got
    a, b = _plane_basis(n)
    dist = float(np.linalg.norm(c - np.asarray(view.position)))
    r = max(r, min_px * dist / view.focal_px)
    ang = np.linspace(0.0, 2.0 * np.pi, 24, endpoint=False)[:, None]
    disc = c + 0.02 * r * n + r * (np.cos(ang) * a + np.sin(ang) * b)
    tiles, normals, colors = [disc], [n], [HOLE_COLOR]
    seg, seg_c = np.zeros((0, 2, 3)), np.zeros((0, 3))
    if flag_h > 0:
        up = np.array([0.0, 1.0, 0.0])
        top = c + flag_h * up
        wind = np.asarray(sim.scene.air.wind, float) * np.array([1.0, 0.0, 1.0])
        d = wind / np.linalg.norm(wind) if np.linalg.norm(wind) > 1e-9 else np.array([1.0, 0.0, 0.0])
        tiles.append(np.array([top, top - 0.2 * flag_h * up, top + 0.3 * flag_h * d - 0.1 * flag_h * up]))
        normals.append(np.cross(d, up))
        colors.append(FLAG_COLOR)
        seg, seg_c = np.array([[c, top]]), np.array([FLAGSTICK_COLOR])
    return tiles, np.array(normals), np.array(colors), seg, seg_c


def _bounds(sim: "Simulation", trail: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
    """The box a camera is fitted to: balls, trails, and the ground (planes or terrain) under them."""
    x = sim.x
    pts = x if trail is None else np.concatenate([x, trail.reshape(-1, 3)])
    hole = _hole(sim)
    if hole is not None:  # the cup and the top of its flagstick are in view too
        pts = np.concatenate([pts, [hole[0], hole[0] + [0.0, hole[3], 0.0]]])
    radius = sim.model.radius_np
    lo, hi = _scene_bounds(pts, radius, sim.model.plane_p, sim.model.plane_n)
    terr = _terrain(sim)
    if terr is not None:
        h, origin, spacing = terr
        i = np.clip(np.round((np.array([lo[0], hi[0]]) - origin[0]) / spacing[0]).astype(int), 0, h.shape[0] - 1)
        k = np.clip(np.round((np.array([lo[2], hi[2]]) - origin[2]) / spacing[1]).astype(int), 0, h.shape[1] - 1)
        under = h[i[0]:i[1] + 1, k[0]:k[1] + 1]
        if under.size:
            lo[1] = min(lo[1], origin[1] + float(under.min()))
    return lo, hi


def camera_view(sim: "Simulation", camera: str | View = "iso", size: tuple[int, int] = (1280, 720),
                fov: float = 45.0, trails: Any = None) -> View:
    """The :class:`View` :func:`render` uses for ``camera`` (a preset name, or a View returned as is)."""
    if isinstance(camera, View):
        return camera
    if camera not in CAMERAS:
        raise ValueError(f"camera must be one of {', '.join(CAMERAS)} or a View (got {camera!r})")
    size = _check_size(size)
    if not 1.0 <= float(fov) <= 170.0:
        raise ValueError(f"fov must be in [1, 170] degrees (got {fov})")
    x = sim.x
    radius = sim.model.radius_np
    lo, hi = _bounds(sim, _trail_array(trails, sim.n))
    if camera != "follow":
        forward, up = _preset_direction(camera)
        return _fit(lo, hi, forward, up, size, fov)
    p0 = x[0]
    v0 = sim.v[0]
    heading = np.array([v0[0], 0.0, v0[2]])
    if np.linalg.norm(heading) < 1e-9 and sim.launch_x is not None:  # None: no ball tracked, no launch point kept
        heading = np.array([p0[0] - sim.launch_x[0, 0], 0.0, p0[2] - sim.launch_x[0, 2]])
    if np.linalg.norm(heading) < 1e-9:
        heading = np.array([1.0, 0.0, 0.0])
    heading /= np.linalg.norm(heading)
    d = 60.0 * float(radius[0])  # a chase camera: ball 0 stays large, whatever the scene's extent
    position = p0 - d * heading + np.array([0.0, 0.4 * d, 0.0])
    lookat = p0 + d * heading
    return View(tuple(position), tuple(lookat), (0.0, 1.0, 0.0), float(fov), size, z_near=0.05 * d,
                z_far=_FOLLOW_REACH * d + 4.0 * float(np.linalg.norm(hi - lo)))


# -- colours --------------------------------------------------------------------------------------
def ball_colors(sim: "Simulation", color_by: str | np.ndarray = "status",
                value_range: tuple[float, float] | None = None) -> np.ndarray:
    """Per-ball RGB (N, 3) in [0, 1]: by status (:data:`STATUS_COLORS`), by ``speed`` |v| or ``spin``
    |ω| through a colormap over ``value_range`` (default 0 to the largest value), by ``id`` (a cycle
    of 20 colours), or given directly as an (N, 3) array."""
    n = sim.n
    if not isinstance(color_by, str):
        c = np.asarray(color_by, dtype=float)
        if c.shape != (n, 3) or not np.all(np.isfinite(c)):
            raise ValueError(f"color_by as an array must be finite RGB of shape ({n}, 3) (got {c.shape})")
        return np.clip(c, 0.0, 1.0)
    if color_by not in COLOR_BY:
        raise ValueError(f"color_by must be one of {', '.join(COLOR_BY)} or an (N, 3) array (got {color_by!r})")
    if color_by == "status":
        table = np.array([STATUS_COLORS[k] for k in range(len(STATUS_COLORS))])
        return table[np.clip(sim.status, 0, len(table) - 1)]
    import matplotlib

    cmap = matplotlib.colormaps[COLORMAPS[color_by]]
    if color_by == "id":
        return np.asarray(cmap(np.arange(n) % cmap.N))[:, :3]
    value = np.linalg.norm(sim.v if color_by == "speed" else sim.w, axis=1)
    lo, hi = value_range if value_range is not None else (0.0, float(np.max(value)) if n else 1.0)
    t = np.clip((value - lo) / (hi - lo), 0.0, 1.0) if hi > lo else np.zeros(n)
    return np.asarray(cmap(t))[:, :3]


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


def _check_size(size: Sequence[int]) -> tuple[int, int]:
    try:
        w, h = (int(s) for s in size)
    except (TypeError, ValueError):
        raise ValueError(f"size must be (width, height) in pixels (got {size!r})") from None
    if not (16 <= w <= 8192 and 16 <= h <= 8192):
        raise ValueError(f"size must be between 16 and 8192 pixels per side (got {w}x{h})")
    return w, h


def _trail_array(trails: Any, n: int) -> np.ndarray | None:
    """Past positions as (S, N, 3): from a Recording, a list of (N, 3) arrays, or an array."""
    if trails is None:
        return None
    if hasattr(trails, "x") and isinstance(trails.x, list):  # a Recording
        trails = trails.x
    if isinstance(trails, (list, tuple)) and len(trails) == 0:
        return None
    a = np.asarray(trails, dtype=float)
    if a.ndim == 2 and a.shape[1] == 3 and n == 1:
        a = a[:, None, :]
    if a.ndim != 3 or a.shape[1:] != (n, 3):
        raise ValueError(f"trails must be past positions of shape (S, {n}, 3) or a Recording (got {a.shape})")
    return a


def _nice_step(x: float) -> float:
    e = 10.0 ** math.floor(math.log10(x))
    for m in (1.0, 2.0, 5.0, 10.0):
        if m * e >= x:
            return m * e
    return 10.0 * e  # pragma: no cover


def _plane_basis(n: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit tangents of a plane, as close to world axes as possible (tiles line up with x, y, z)."""
    cand = np.eye(3) - np.outer(np.eye(3) @ n, n)
    order = np.argsort(-np.linalg.norm(cand, axis=1), kind="stable")
    t1 = cand[order[0]] / np.linalg.norm(cand[order[0]])
    t2 = cand[order[1]] - (cand[order[1]] @ t1) * t1
    t2 /= np.linalg.norm(t2)
    if order[0] > order[1]:
        t1, t2 = t2, t1
    return t1, t2


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


def _plane_tiles(view: View, plane_p: np.ndarray, plane_n: np.ndarray, lo: np.ndarray, hi: np.ndarray,
                 r_max: float, reach: float = 0.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
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
        ii, jj = np.meshgrid(np.arange(i0, i1), np.arange(j0, j1), indexing="ij")
        ii, jj = ii.ravel(), jj.ravel()
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


def _clip_to_open_sides(quads: np.ndarray, planes: list[tuple[np.ndarray, np.ndarray]]
                        ) -> tuple[list[np.ndarray], np.ndarray]:
    """Cut a plane's tiles (T, 4, 3) to the open side of every other plane (the space balls can
    reach): a bin's floor stops at its walls and the walls at the floor. Returns the polygons and
    the indices of the tiles they come from."""
    if not planes:
        return list(quads), np.arange(len(quads))
    eps = 1e-9 * (1.0 + float(np.abs(quads).max()))
    d = np.stack([(quads - q) @ m for q, m in planes])  # (P, T, 4)
    inside = d >= -eps
    whole = inside.all(axis=(0, 2))
    gone = (~inside).all(axis=2).any(axis=0)
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


def _terrain_tiles(h: np.ndarray, origin: np.ndarray, spacing: np.ndarray,
                   surfaces: tuple[np.ndarray, tuple[str, ...]] | None = None, max_cells: int = 128
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


def build_frame(sim: "Simulation", view: View, color_by: Any, trails: Any, min_px: float,
                 value_range: tuple[float, float] | None, follow: bool = False) -> _Frame:
    """What :func:`render` draws of ``sim`` seen through ``view`` (arguments as there; ``follow``
    for the follow camera's reach): balls, planes, terrain, cup and flag, trails, wind arrow, light."""
    x = sim.x
    radius = sim.model.radius_np.astype(float)
    colors = ball_colors(sim, color_by, value_range)
    trail = _trail_array(trails, sim.n)
    lo, hi = _bounds(sim, trail)
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


# -- GGUI -----------------------------------------------------------------------------------------
class _GGUIUnavailable(Exception):
    pass


class _GGUIState:
    """The process's one GGUI window (created lazily, reused for every picture) and its helpers."""

    def __init__(self) -> None:
        self.window: Any = None
        self.size: tuple[int, int] | None = None
        self.scene: Any = None
        self.camera: Any = None
        self.canvas: Any = None
        self.failed: str | None = None
        self.noted: set[str] = set()


_ggui = _GGUIState()


class _quiet_stderr:
    """Silence C++ messages on file descriptor 2 (Taichi's "RHI Error: ..." when Vulkan is missing)."""

    def __enter__(self) -> "_quiet_stderr":
        self.saved = None
        try:
            sys.stderr.flush()
            self.saved = os.dup(2)
            self.devnull = os.open(os.devnull, os.O_WRONLY)
            os.dup2(self.devnull, 2)
        except OSError:  # pragma: no cover - no real fd 2
            self.saved = None
        return self

    def __exit__(self, *exc: Any) -> None:
        if self.saved is not None:
            os.dup2(self.saved, 2)
            os.close(self.saved)
            os.close(self.devnull)


def ggui_problem() -> str | None:
    """Why GGUI cannot be used in this process, or None when it can (no window is opened)."""
    if _ggui.window is not None:
        return None
    if _ggui.failed:
        return _ggui.failed
    try:
        from taichi._lib import core as ti_core  # (works before ti.init: asks no backend to start)

        if not getattr(ti_core, "GGUI_AVAILABLE", False):
            return "this Taichi build has no GGUI"
        with _quiet_stderr():
            vulkan = bool(ti_core.with_vulkan())
        if not vulkan:
            return "Vulkan is not available"
    except Exception as exc:  # pragma: no cover - unusual Taichi builds
        return f"GGUI is not available ({exc})"
    return None


def ggui_available() -> bool:
    """Whether GGUI can draw in this process (Taichi has GGUI and a Vulkan instance can be created)."""
    return ggui_problem() is None


def _ggui_window(size: tuple[int, int]) -> Any:
    if _ggui.window is not None:
        if _ggui.size != size:
            raise _GGUIUnavailable(
                f"the GGUI window of this process is {_ggui.size[0]}x{_ggui.size[1]} and cannot be resized "
                f"to {size[0]}x{size[1]}")
        return _ggui.window
    problem = ggui_problem()
    if problem:
        raise _GGUIUnavailable(problem)
    import taichi as ti

    try:
        with _quiet_stderr():
            window = ti.ui.Window("ti_golf", size, show_window=False)
        _ggui.scene = window.get_scene()
        _ggui.camera = ti.ui.Camera()
        _ggui.canvas = window.get_canvas()
    except Exception as exc:
        msg = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        _ggui.failed = "Vulkan is not available" if "vulkan" in msg.lower() else f"GGUI failed ({msg})"
        raise _GGUIUnavailable(_ggui.failed) from None
    _ggui.window, _ggui.size = window, size
    atexit.register(_close_window)
    return window


def _close_window() -> None:
    """Destroy the picture window at exit (see :func:`destroy_window`)."""
    if _ggui.window is None:
        return
    destroy_window(_ggui.window)
    _ggui.window = None


def destroy_window(window: Any) -> None:
    """Destroy a GGUI window inside a scratch folder: Dear ImGui writes ``imgui.ini`` into the
    current folder when its context goes, and the user's folder should not get one."""
    cwd = os.getcwd()
    scratch = tempfile.mkdtemp(prefix="ti_golf_ggui_")
    try:
        os.chdir(scratch)
        window.destroy()
    except Exception:  # pragma: no cover - best effort at exit
        pass
    finally:
        os.chdir(cwd)
        shutil.rmtree(scratch, ignore_errors=True)


# GGUI's vertex layout: 12 float32 per vertex (position 0:3, normal or particle radius 3:6, texture
# coordinates 6:8, RGBA colour 8:12), as Taichi's own staging code fills it.
_VBO_STRIDE = 12


def _vbo(points: np.ndarray, colors: np.ndarray, normals: np.ndarray | None = None,
         radius: np.ndarray | None = None) -> np.ndarray:
    """One GGUI vertex buffer, shape (n, 12) float32, built in numpy (no Taichi kernel runs)."""
    vbo = np.zeros((len(points), _VBO_STRIDE), np.float32)
    vbo[:, 0:3] = points
    if normals is not None:
        vbo[:, 3:6] = normals
    if radius is not None:
        vbo[:, 3] = radius
    vbo[:, 8:11] = colors
    vbo[:, 11] = 1.0
    return vbo


class _GGUIDraw:
    """Hands GGUI vertex and index buffers that stay alive until the picture is saved.

    Taichi 1.7's ``SceneV2.mesh/particles/lines`` copy the data into a numpy staging array that
    they drop on return, yet GGUI reads it only at ``canvas.scene()``: the memory may be reused by
    then, and a mesh came out missing or shifted about once in 60 pictures. Here the buffers are
    built in numpy, passed to GGUI's C++ scene directly and held in :attr:`keep` until the frame
    has been drawn and read back.
    """

    def __init__(self, scene: Any) -> None:
        from taichi.ui.utils import get_field_info

        self.scene, self.info, self.keep = scene.scene, get_field_info, []

    def _hold(self, *arrays: np.ndarray | None) -> list[Any]:
        self.keep.extend(a for a in arrays if a is not None)
        return [self.info(a) for a in arrays]

    def mesh(self, vbo: np.ndarray, indices: np.ndarray) -> None:
        vbo_info, idx_info = self._hold(vbo, indices)
        self.scene.mesh(vbo_info, True, idx_info, (0.5, 0.5, 0.5), True,  # per-vertex colour, two-sided
                        len(indices), 0, len(vbo), 0, False)  # index count/offset, vertex count/offset, wireframe

    def lines(self, vbo: np.ndarray, width: float) -> None:
        vbo_info, idx_info = self._hold(vbo, None)
        self.scene.lines(vbo_info, idx_info, True, (0.5, 0.5, 0.5), width, len(vbo), 0, len(vbo), 0)

    def particles(self, vbo: np.ndarray) -> None:
        (vbo_info,) = self._hold(vbo)
        self.scene.particles(vbo_info, True, True, (0.5, 0.5, 0.5), float(vbo[:, 3].max()), len(vbo), 0)


def _draw_ggui(frame: _Frame, path: str) -> None:
    # The first picture of a window is drawn twice and the second kept: twice in CI (the same test,
    # the session's first GGUI picture, with other processes using the Vulkan driver), the first
    # picture of a process came out without its mesh (the ground); alone it never did.
    passes = 2 if _ggui.window is None else 1
    window = _ggui_window(frame.view.size)
    for _ in range(passes):
        draw = draw_scene(frame, _ggui.scene, _ggui.camera)
        _ggui.canvas.set_background_color(BACKGROUND_COLOR)
        _ggui.canvas.scene(_ggui.scene)
        rgba = window.get_image_buffer_as_numpy()  # (width, height, 4) float32 in [0, 1], y up
        draw.keep.clear()
    write_png(rgba, path)


def draw_scene(frame: _Frame, scene: Any, cam: Any) -> _GGUIDraw:
    """Hand a frame to a GGUI scene through camera ``cam`` (set to the frame's view): lights, tiles,
    segments and balls. Returns the holder of its buffers: keep it until the canvas has drawn the
    scene (see :class:`_GGUIDraw`), then clear it. Also used by the game's window (:mod:`.game_gui`)."""
    import taichi as ti

    view = frame.view
    cam.projection_mode(ti.ui.ProjectionMode.Perspective)
    cam.position(*map(float, view.position))
    cam.lookat(*map(float, view.lookat))
    _, u, _ = view.basis()
    cam.up(*map(float, u))
    cam.fov(float(view.fov))
    cam.z_near(float(view.z_near))
    cam.z_far(float(view.z_far))
    scene.set_camera(cam)
    scene.ambient_light((AMBIENT,) * 3)
    scene.point_light(tuple(map(float, frame.light)), (LIGHT,) * 3)
    draw = _GGUIDraw(scene)
    if frame.tiles:
        counts = np.array([len(poly) for poly in frame.tiles])
        starts = np.r_[0, np.cumsum(counts)[:-1]]
        fans = []
        for k in np.unique(counts):  # fan triangulation of the convex polygons with k corners
            first = starts[counts == k][:, None]
            j = np.arange(1, k - 1)[None, :]
            fans.append(np.stack(np.broadcast_arrays(first, first + j, first + j + 1), axis=-1).reshape(-1))
        draw.mesh(_vbo(np.concatenate(frame.tiles), np.repeat(frame.tile_colors, counts, axis=0),
                       normals=np.repeat(frame.tile_normals, counts, axis=0)),
                  np.ascontiguousarray(np.concatenate(fans), np.int32))
    if len(frame.segments):
        draw.lines(_vbo(frame.segments.reshape(-1, 3), np.repeat(frame.segment_colors, 2, axis=0)),
                   float(frame.line_px))
    if len(frame.centers):
        # GGUI 1.7 scales sprite radii by width/height (it uses the window width where the height
        # belongs): divide by the aspect ratio so a ball is drawn at its true size.
        aspect = view.size[0] / view.size[1]
        draw.particles(_vbo(frame.centers, frame.colors, radius=frame.radius / aspect))
    return draw


def write_png(rgba: np.ndarray, path: str) -> None:
    """Write GGUI's (width, height, 4) float buffer as an RGB PNG with Pillow at fast compression
    (Taichi's own ``save_image`` takes about 0.1 s for 1280x720)."""
    from PIL import Image

    rgb = np.clip(rgba[:, ::-1, :3].transpose(1, 0, 2) * 255.0 + 0.5, 0.0, 255.0).astype(np.uint8)
    Image.fromarray(rgb).save(path, format="PNG", compress_level=1)


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
    return PolyCollection([polys[i] for i in order], facecolors=colors[np.asarray(source, int)[order]],
                          edgecolors="none", antialiased=False, zorder=1)


def _render_matplotlib(frame: _Frame, path: str) -> None:
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.collections import LineCollection, PolyCollection
    from matplotlib.figure import Figure

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
        ax.add_collection(LineCollection(px, colors=np.clip(frame.segment_colors[ok], 0, 1),
                                         linewidths=frame.line_px * pt_per_px, zorder=2))
    if len(frame.centers):
        px, depth = view.project(frame.centers)
        dist = np.linalg.norm(frame.centers - np.asarray(view.position), axis=1)
        r_px = frame.radius * f / dist
        ok = (depth > view.z_near) & (depth < view.z_far)
        order = np.flatnonzero(ok)[np.argsort(-depth[ok], kind="stable")]
        c = np.clip(frame.colors[order] * (AMBIENT + 0.75 * LIGHT), 0, 1)
        edge = np.clip(frame.colors[order] * AMBIENT, 0, 1)
        ax.scatter(px[order, 0], px[order, 1], s=(2.0 * r_px[order] * pt_per_px) ** 2, c=c, edgecolors=edge,
                   linewidths=np.where(r_px[order] > 3.0, 0.6, 0.0), marker="o", zorder=3)
    fig.savefig(path, dpi=dpi, facecolor=BACKGROUND_COLOR, format="png")


# -- entry point ----------------------------------------------------------------------------------
def render(sim: "Simulation", path: str | os.PathLike[str], camera: str | View = "iso",
           size: tuple[int, int] = (1280, 720), color_by: str | np.ndarray = "status", trails: Any = None,
           fov: float = 45.0, *, backend: str = "auto", min_px: float | None = None,
           value_range: tuple[float, float] | None = None) -> str:
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
        backend: ``"auto"`` (GGUI when Vulkan works and Taichi runs on the CPU backend, else
            matplotlib with one line on stderr, once per reason and process), ``"ggui"`` (raise
            :class:`RenderError` if GGUI cannot draw) or ``"matplotlib"``.
        min_px: smallest drawn ball radius in pixels, so that far-away balls stay visible
            (default: 1.5, or height/300 on larger pictures).
        value_range: colormap range of ``"speed"`` / ``"spin"`` (default 0 to the largest value).
    """
    if backend not in BACKENDS:
        raise ValueError(f"backend must be one of {', '.join(BACKENDS)} (got {backend!r})")
    size = _check_size(size)
    if min_px is None:
        min_px = max(1.5, size[1] / 300.0)
    if not float(min_px) >= 0:
        raise ValueError(f"min_px must be >= 0 (got {min_px})")
    view = camera_view(sim, camera, size, fov, trails)
    if isinstance(camera, View) and tuple(view.size) != size:
        view = View(view.position, view.lookat, view.up, view.fov, size, view.z_near, view.z_far)
    frame = build_frame(sim, view, color_by, trails, min_px, value_range, follow=camera == "follow")
    target = Path(path)
    if not target.parent.is_dir():
        raise ValueError(f"cannot write {str(target)!r}: folder {str(target.parent)!r} does not exist")
    fd, tmp = tempfile.mkstemp(suffix=".png", prefix=".ti_golf_render_", dir=target.parent)
    os.close(fd)
    try:
        used = "matplotlib"
        other_arch = non_cpu_arch() if backend == "auto" else None
        if other_arch:
            _note(f"GGUI pictures are only drawn with the CPU backend (this process runs on {other_arch})")
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


def non_cpu_arch() -> str | None:
    """The Taichi backend's name when it is not the CPU, else None.

    With ``arch=vulkan`` (software driver, Taichi 1.7.4) GGUI draws particles from garbled vertex
    data (balls missing or huge), so ``backend="auto"`` uses GGUI only on the CPU backend, the one
    the tests check; ``backend="ggui"`` still tries any backend.
    """
    from ti_golf.runtime import info

    rt = info()
    return rt.arch if rt is not None and rt.arch not in ("x64", "arm64", "cpu") else None


def _note(reason: str) -> None:
    """One line on stderr per reason and process: the fallback is noticed, not repeated per frame."""
    if reason not in _ggui.noted:
        _ggui.noted.add(reason)
        print(_FALLBACK_NOTE.format(reason=reason), file=sys.stderr)
