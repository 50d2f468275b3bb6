"""The camera of a picture: a pinhole :class:`View` fitted to the balls, and the balls' colours."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import matplotlib
import numpy as np

if TYPE_CHECKING:  # pragma: no cover
    from ti_golf.sim.simulation import Simulation
from ti_golf.render.style import (
    _FOLLOW_REACH,
    CAMERAS,
    COLOR_BY,
    COLORMAPS,
    FLAG_COLOR,
    FLAGSTICK_COLOR,
    HOLE_COLOR,
    STATUS_COLORS,
)


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


def _fit(
    lo: np.ndarray,
    hi: np.ndarray,
    forward: np.ndarray,
    up: np.ndarray,
    size: tuple[int, int],
    fov: float,
    margin: float = 1.1,
) -> View:
    """The camera looking along ``forward`` at the box's centre from just far enough to see all of it."""
    center = 0.5 * (lo + hi)
    corners = np.array([[a, b, c] for a in (lo[0], hi[0]) for b in (lo[1], hi[1]) for c in (lo[2], hi[2])]) - center
    probe = View(tuple(center - forward), tuple(center), tuple(up), fov, size)
    r, u, f = probe.basis()
    a, b, w = corners @ r, corners @ u, corners @ f
    tan_y = math.tan(math.radians(fov) / 2.0)
    tan_x = tan_y * size[0] / size[1]
    d = max(
        float(np.max(margin * np.abs(a) / tan_x - w)),
        float(np.max(margin * np.abs(b) / tan_y - w)),
        float(np.max(-w)) * 1.05,
    )
    half_diag = float(np.linalg.norm(hi - lo)) / 2.0
    d = max(d, 1e-6)
    z_near = max(1e-4 * d, 0.5 * (d - half_diag))
    z_far = 4.0 * (d + half_diag) + 10.0 * half_diag
    return View(tuple(center - d * f), tuple(center), tuple(u), float(fov), size, z_near, z_far)


def _scene_bounds(
    points: np.ndarray, radius: np.ndarray, plane_p: np.ndarray, plane_n: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Bounding box of the balls (with their radii) and trail points, reaching down to a horizontal
    ground below them, at least 10 ball radii wide along each axis."""
    r_max = float(np.max(radius)) if radius.size else 0.02
    pts = points if np.isfinite(points).all() else points[np.all(np.isfinite(points), axis=1)]
    if len(pts) == 0:
        pts = np.zeros((1, 3))
    # (column by column: numpy reduces a column of (N, 3) several times faster than the rows' axis 0)
    lo = np.array([pts[:, k].min() for k in range(3)]) - r_max
    hi = np.array([pts[:, k].max() for k in range(3)]) + r_max
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
        return (
            np.array([x, float(t.height(x, z)), z]),
            np.asarray(t.normal(x, z), float).reshape(3),
            float(hole.radius),
            float(hole.flag_height),
        )
    y, n = 0.0, np.array([0.0, 1.0, 0.0])
    for p, m in zip(np.asarray(sim.model.plane_p, float), np.asarray(sim.model.plane_n, float)):
        if m[1] > 0.7:  # the ground: y where the plane meets the vertical through (x, z)
            y, n = float(p[1] - (m[0] * (x - p[0]) + m[2] * (z - p[2])) / m[1]), m / np.linalg.norm(m)
            break
    return np.array([x, y, z]), n, float(hole.radius), float(hole.flag_height)


def _hole_parts(
    sim: "Simulation", view: View, min_px: float
) -> tuple[list[np.ndarray], np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
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


def _bounds(
    sim: "Simulation", trail: np.ndarray | None, extent: np.ndarray | None = None, x: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """The box a camera is fitted to: balls (their centres ``x`` (N, 3) [m] when given, else
    read), trails, the points of ``extent`` (M, 3), and the ground (planes or terrain) under them."""
    x = sim.x if x is None else x
    pts = x if trail is None else np.concatenate([x, trail.reshape(-1, 3)])
    if extent is not None:
        pts = np.concatenate([pts, np.asarray(extent, float).reshape(-1, 3)])
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
        under = h[i[0] : i[1] + 1, k[0] : k[1] + 1]
        if under.size:
            lo[1] = min(lo[1], origin[1] + float(under.min()))
    return lo, hi


def camera_view(
    sim: "Simulation",
    camera: str | View = "iso",
    size: tuple[int, int] = (1280, 720),
    fov: float = 45.0,
    trails: Any = None,
    extent: np.ndarray | None = None,
) -> View:
    """The :class:`View` :func:`render` uses for ``camera`` (a preset name, or a View returned as
    is); a preset also takes in the points of ``extent`` (M, 3) [m]."""
    if isinstance(camera, View):
        return camera
    if camera not in CAMERAS:
        raise ValueError(f"camera must be one of {', '.join(CAMERAS)} or a View (got {camera!r})")
    size = _check_size(size)
    if not 1.0 <= float(fov) <= 170.0:
        raise ValueError(f"fov must be in [1, 170] degrees (got {fov})")
    radius = sim.model.radius_np
    lo, hi = _bounds(sim, _trail_array(trails, sim.n), extent)
    if camera != "follow":
        forward, up = _preset_direction(camera)
        return _fit(lo, hi, forward, up, size, fov)
    p0, v0, _ = sim.ball(0)
    heading = np.array([v0[0], 0.0, v0[2]])
    if np.linalg.norm(heading) < 1e-9 and sim.launch_x is not None:  # None: no ball tracked, no launch point kept
        heading = np.array([p0[0] - sim.launch_x[0, 0], 0.0, p0[2] - sim.launch_x[0, 2]])
    if np.linalg.norm(heading) < 1e-9:
        heading = np.array([1.0, 0.0, 0.0])
    heading /= np.linalg.norm(heading)
    d = 60.0 * float(radius[0])  # a chase camera: ball 0 stays large, whatever the scene's extent
    position = p0 - d * heading + np.array([0.0, 0.4 * d, 0.0])
    lookat = p0 + d * heading
    return View(
        tuple(position),
        tuple(lookat),
        (0.0, 1.0, 0.0),
        float(fov),
        size,
        z_near=0.05 * d,
        z_far=_FOLLOW_REACH * d + 4.0 * float(np.linalg.norm(hi - lo)),
    )


def orbit_view(
    sim: "Simulation",
    yaw_deg: float,
    pitch_deg: float,
    zoom: float = 1.0,
    size: tuple[int, int] = (1280, 720),
    fov: float = 45.0,
    trails: Any = None,
    target: Sequence[float] | None = None,
    x: np.ndarray | None = None,
) -> View:
    """A camera on a sphere around the scene: at azimuth ``yaw_deg`` (from +x toward +z) and
    elevation ``pitch_deg`` above the horizontal, seen from the look-at point. Without ``target``
    it looks at the middle of the balls, trails and ground under them from the distance that
    shows all of them (as the presets do) times ``zoom``; with ``target`` (3,) [m] it looks at
    that point from ``zoom`` × 60 ball radii (as ``follow`` does). ``x``: the balls' centres
    (N, 3) [m] when the caller has read them, else they are read."""
    size = _check_size(size)
    yaw, pitch = math.radians(yaw_deg), math.radians(pitch_deg)
    toward_camera = np.array([math.cos(pitch) * math.cos(yaw), math.sin(pitch), math.cos(pitch) * math.sin(yaw)])
    forward = -toward_camera
    up = np.array([0.0, 1.0, 0.0])
    lo, hi = _bounds(sim, _trail_array(trails, sim.n), x=x)
    if target is None:
        fitted = _fit(lo, hi, forward, up, size, fov)
        center = np.asarray(fitted.lookat)
        d = zoom * float(np.linalg.norm(np.subtract(fitted.position, center)))
        half_diag = float(np.linalg.norm(hi - lo)) / 2.0
        z_near = max(1e-4 * d, 0.5 * (d - half_diag), 1e-3 * float(np.max(sim.model.radius_np)))
        z_far = 4.0 * (d + half_diag) + 10.0 * half_diag
    else:
        center = np.asarray(target, float)
        d = zoom * 60.0 * float(np.max(sim.model.radius_np))
        z_near, z_far = 0.05 * d, _FOLLOW_REACH * d + 4.0 * float(np.linalg.norm(hi - lo))
    return View(tuple(center + d * toward_camera), tuple(center), tuple(up), float(fov), size, z_near, z_far)


# -- colours --------------------------------------------------------------------------------------
def ball_colors(
    sim: "Simulation", color_by: str | np.ndarray = "status", value_range: tuple[float, float] | None = None
) -> np.ndarray:
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
    cmap = matplotlib.colormaps[COLORMAPS[color_by]]
    if color_by == "id":
        return np.asarray(cmap(np.arange(n) % cmap.N))[:, :3]
    value = np.linalg.norm(sim.v if color_by == "speed" else sim.w, axis=1)
    lo, hi = value_range if value_range is not None else (0.0, float(np.max(value)) if n else 1.0)
    t = np.clip((value - lo) / (hi - lo), 0.0, 1.0) if hi > lo else np.zeros(n)
    return np.asarray(cmap(t))[:, :3]


def _check_size(size: Sequence[int]) -> tuple[int, int]:
    try:
        w, h = (int(s) for s in size)
    except (TypeError, ValueError):
        raise ValueError(f"size must be (width, height) in pixels (got {size!r})") from None
    if not (16 <= w <= 8192 and 16 <= h <= 8192):
        raise ValueError(f"size must be between 16 and 8192 pixels per side (got {w}x{h})")
    return w, h


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
