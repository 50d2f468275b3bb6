"""Height-field terrain in numpy (no Taichi): build the heights from a scene's ``[terrain]`` table,
and evaluate the surface height and normal anywhere on it (for tests, plots and checks).

The terrain is a grid of heights ``heights[i, k]`` [m] at the points
(origin_x + i·dx, origin_y + heights[i, k], origin_z + k·dz), i = 0 … nx−1 along x, k = 0 … nz−1
along z, with spacing (dx, dz) = size / (n − 1). Between grid points the surface is the bilinear
patch of its cell: with s, t ∈ [0, 1] the position inside cell (i, k),

    h = h00·(1−s)(1−t) + h10·s(1−t) + h01·(1−s)·t + h11·s·t,

and its normal is that patch's, n̂ = (−∂h/∂x, 1, −∂h/∂z)/|…|. Outside the grid the edge cells
are used with s, t clamped to [0, 1] (the Taichi version in :mod:`ti_golf.physics.terrain` does the
same, operation for operation).

Generated terrain is fractal value noise: octave o has random values on a lattice of cell size
L/2^o (L the larger extent) drawn with ``numpy.random.default_rng(seed)``, smoothly interpolated,
weighted by roughness^o and normalised so heights lie within ±amplitude. Octaves are added until
the lattice is as fine as the grid. PCG64 and plain arithmetic make a seed give the same heights
on every machine.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from ti_golf.scene.checks import raise_config
from ti_golf.scene.schema import HEIGHT_LIMIT, TERRAIN_POINTS_MAX, TerrainConfig


@dataclass(frozen=True)
class Terrain:
    """A height field: ``heights`` (nx, nz) [m] above ``origin`` (3,) [m], grid ``spacing`` (dx, dz) [m]."""

    heights: np.ndarray
    origin: np.ndarray
    spacing: np.ndarray
    cells: np.ndarray | None = None
    """Surface type of every cell, (nx − 1, nz − 1) int indices into the scene's [[surfaces]]."""

    @property
    def shape(self) -> tuple[int, int]:
        """Grid points (nx, nz)."""
        return self.heights.shape

    @property
    def size(self) -> np.ndarray:
        """Extent [size_x, size_z] [m]."""
        return self.spacing * (np.asarray(self.heights.shape) - 1)

    def _cell(self, x, z):
        """Cell indices (i, k) and positions s, t ∈ [0, 1] inside the cell (clamped at the edges)."""
        nx, nz = self.heights.shape
        u = (np.asarray(x, dtype=float) - self.origin[0]) / self.spacing[0]
        w = (np.asarray(z, dtype=float) - self.origin[2]) / self.spacing[1]
        u = np.where(u > 0.0, np.minimum(u, nx - 1.0), 0.0)  # NaN -> 0 as in the kernel
        w = np.where(w > 0.0, np.minimum(w, nz - 1.0), 0.0)
        i = np.minimum(np.floor(u).astype(np.int64), nx - 2)
        k = np.minimum(np.floor(w).astype(np.int64), nz - 2)
        return i, k, u - i, w - k

    def _corners(self, i, k):
        H = self.heights
        return H[i, k], H[i + 1, k], H[i, k + 1], H[i + 1, k + 1]

    def height(self, x, z) -> np.ndarray:
        """Surface height y [m] at (x, z) (bilinear; arrays broadcast)."""
        i, k, s, t = self._cell(x, z)
        h00, h10, h01, h11 = self._corners(i, k)
        return self.origin[1] + ((h00 * (1.0 - s) + h10 * s) * (1.0 - t) + (h01 * (1.0 - s) + h11 * s) * t)

    def gradient(self, x, z) -> tuple[np.ndarray, np.ndarray]:
        """(∂h/∂x, ∂h/∂z) of the bilinear patch under (x, z)."""
        i, k, s, t = self._cell(x, z)
        h00, h10, h01, h11 = self._corners(i, k)
        hx = ((h10 - h00) * (1.0 - t) + (h11 - h01) * t) / self.spacing[0]
        hz = ((h01 - h00) * (1.0 - s) + (h11 - h10) * s) / self.spacing[1]
        return hx, hz

    def normal(self, x, z) -> np.ndarray:
        """Unit surface normal (…, 3) at (x, z): (−∂h/∂x, 1, −∂h/∂z) normalised."""
        hx, hz = self.gradient(x, z)
        n = np.stack(np.broadcast_arrays(-hx, np.ones_like(hx), -hz), axis=-1)
        return n / np.linalg.norm(n, axis=-1, keepdims=True)

    def contains(self, x, z) -> np.ndarray:
        """Whether (x, z) lies over the grid: balls elsewhere are out of bounds, and so are balls
        below the scene's ``terrain.kill_height`` anywhere (the kernels' test, which this one
        leaves out: it takes no height)."""
        x, z = np.asarray(x, dtype=float), np.asarray(z, dtype=float)
        ex, ez = self.size
        return (x >= self.origin[0]) & (x <= self.origin[0] + ex) & (z >= self.origin[2]) & (z <= self.origin[2] + ez)

    def gap(self, x: np.ndarray, radius) -> np.ndarray:
        """Signed distance [m] of balls (N, 3) of ``radius`` from the tangent plane under their centres
        (negative when they penetrate it): (y − h)·n_y − R."""
        x = np.asarray(x, dtype=float)
        return (x[..., 1] - self.height(x[..., 0], x[..., 2])) * self.normal(x[..., 0], x[..., 2])[..., 1] - radius


def load_heights_file(path: str | os.PathLike[str], source: str = "") -> np.ndarray:
    """Read and check a .npy array of heights: 2-D, at least 2 points per axis, finite real numbers
    within ±:data:`~ti_golf.scene.schema.HEIGHT_LIMIT`.

    Raises ConfigError naming ``terrain.file``.
    """
    key = "terrain.file"
    p = os.fspath(path)
    if not os.path.exists(p):
        raise_config(source, key, f"file not found: {p}")
    if os.path.isdir(p):
        raise_config(source, key, f"is a directory, not a .npy file: {p}")
    if not os.path.isfile(p):  # (a FIFO or a device: reading it could wait for ever)
        raise_config(source, key, f"is not a regular file: {p}")
    magic = b""
    try:  # (mapped: the header's shape is checked against the file before anything is read)
        with open(p, "rb") as fh:
            magic = fh.read(6)
        a = np.load(p, mmap_mode="r", allow_pickle=False)
    except (OSError, ValueError, EOFError) as exc:  # (EOFError: an empty file)
        if len(magic) == 6 and magic != b"\x93NUMPY":  # (numpy's reason would be the pickle's)
            raise_config(source, key, f"is not a .npy file (one begins with the bytes \\x93NUMPY): {p}")
        raise_config(source, key, f"cannot be read as a .npy array ({exc or 'empty file'}): {p}")
    if not isinstance(a, np.ndarray) or a.dtype.kind not in "iuf":
        raise_config(
            source, key, f"must hold a numeric array of heights in m (got {getattr(a, 'dtype', type(a))}): {p}"
        )
    if a.ndim != 2 or min(a.shape) < 2:
        raise_config(
            source, key, f"must hold a 2-D array (nx, nz) of heights with nx, nz >= 2 (got shape {a.shape}): {p}"
        )
    if a.size > TERRAIN_POINTS_MAX:
        raise_config(source, key, f"holds {a.size:,} points; at most {TERRAIN_POINTS_MAX:,}: {p}")
    a = np.array(a, dtype=np.float64)  # (read, and the file let go; abs of int64's least would overflow)
    if not np.all(np.isfinite(a)):
        raise_config(
            source, key, f"holds NaN or infinite heights ({int(np.count_nonzero(~np.isfinite(a)))} of them): {p}"
        )
    if np.max(np.abs(a)) > HEIGHT_LIMIT:
        raise_config(source, key, f"holds heights beyond ±{HEIGHT_LIMIT:g} m (got {float(np.max(np.abs(a))):g}): {p}")
    return a


def _smooth(f: np.ndarray) -> np.ndarray:
    """Smoothstep 3f² − 2f³ (interpolation weights with zero slope at lattice points)."""
    return f * f * (3.0 - 2.0 * f)


def _interp_axis(values: np.ndarray, pos: np.ndarray, axis: int) -> np.ndarray:
    """Interpolate lattice ``values`` along ``axis`` at lattice coordinates ``pos`` (smoothstep weights)."""
    i = np.minimum(np.floor(pos).astype(np.int64), values.shape[axis] - 2)
    f = _smooth(pos - i)
    a, b = np.take(values, i, axis=axis), np.take(values, i + 1, axis=axis)
    shape = [1] * values.ndim
    shape[axis] = len(pos)
    f = f.reshape(shape)
    return a * (1.0 - f) + b * f


def generate_heights(
    resolution: tuple[int, int],
    size: tuple[float, float],
    seed: int = 0,
    amplitude: float = 1.0,
    roughness: float = 0.5,
    profile: bool = False,
) -> np.ndarray:
    """Seeded fractal value noise (nx, nz) [m] within ±amplitude (see the module docstring).

    With ``profile`` the heights vary along x only (every column along z is equal).
    """
    nx, nz = int(resolution[0]), int(resolution[1])
    sx, sz = float(size[0]), float(size[1])
    rng = np.random.default_rng(seed)
    length = sx if profile else max(sx, sz)
    finest = min(sx / (nx - 1), length) if profile else min(sx / (nx - 1), sz / (nz - 1))
    octaves = int(np.clip(np.ceil(np.log2(length / finest)), 1, 24))
    x, z = np.linspace(0.0, sx, nx), np.linspace(0.0, sz, nz)
    total = np.zeros((nx, 1) if profile else (nx, nz))
    weight = 0.0
    for o in range(octaves):
        cell = length / 2.0**o
        cx = max(cell, sx / (nx - 1))  # no lattice finer than the grid along an axis
        kx = int(np.ceil(sx / cx - 1e-9)) + 1
        if profile:
            lattice = rng.uniform(-1.0, 1.0, size=(kx, 1))
            noise = _interp_axis(lattice, x / cx, 0)
        else:
            cz = max(cell, sz / (nz - 1))
            kz = int(np.ceil(sz / cz - 1e-9)) + 1
            lattice = rng.uniform(-1.0, 1.0, size=(kx, kz))
            noise = _interp_axis(_interp_axis(lattice, x / cx, 0), z / cz, 1)
        total = total + roughness**o * noise
        weight += roughness**o
    heights = amplitude * total / weight
    return np.ascontiguousarray(np.broadcast_to(heights, (nx, nz)), dtype=np.float64)


@lru_cache(maxsize=8)
def _generated(cfg: TerrainConfig) -> np.ndarray:
    heights = generate_heights(cfg.resolution, cfg.size, cfg.seed, cfg.amplitude, cfg.roughness, cfg.profile)
    heights.flags.writeable = False
    return heights


def build_terrain(cfg: TerrainConfig, source: str = "") -> Terrain:
    """The :class:`Terrain` of a validated ``[terrain]`` table (heights generated or read, plus the slope).

    Generated heights are cached per table (read-only arrays); files are read on every call.
    """
    heights = load_heights_file(cfg.file, source) if cfg.kind == "file" else _generated(cfg)
    nx, nz = heights.shape
    spacing = np.array([cfg.size[0] / (nx - 1), cfg.size[1] / (nz - 1)])
    if cfg.slope[0] or cfg.slope[1]:
        heights = (
            heights
            + cfg.slope[0] * (spacing[0] * np.arange(nx))[:, None]
            + cfg.slope[1] * (spacing[1] * np.arange(nz))[None, :]
        )
    cells = np.zeros((nx - 1, nz - 1), dtype=np.int32)
    if cfg.surface_levels:
        mean = 0.25 * (heights[:-1, :-1] + heights[1:, :-1] + heights[:-1, 1:] + heights[1:, 1:])
        cells = np.searchsorted(np.asarray(cfg.surface_levels), mean, side="right").astype(np.int32)
    return Terrain(heights=heights, origin=np.asarray(cfg.origin, dtype=float), spacing=spacing, cells=cells)
