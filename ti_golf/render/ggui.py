"""GGUI (Vulkan) off screen: the one window a process may have, drawing a frame, writing the PNG."""

from __future__ import annotations

import atexit
import os
import shutil
import sys
import tempfile
from typing import TYPE_CHECKING, Any

import numpy as np
import taichi as ti
from PIL import Image
from taichi._lib import (
    core as ti_core,  # (asks no backend to start: usable before ti.init)
)
from taichi.ui.utils import get_field_info

if TYPE_CHECKING:  # pragma: no cover
    pass
from ti_golf.errors import ConfigError
from ti_golf.files import atomic_path
from ti_golf.render.frame import _Frame
from ti_golf.render.style import AMBIENT, BACKGROUND_COLOR, LIGHT
from ti_golf.runtime import ensure_init, on_cpu


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
        made = _ggui.size
        assert made is not None  # set with the window
        if made != size:
            raise _GGUIUnavailable(
                f"the GGUI window of this process is {made[0]}x{made[1]} and cannot be resized to {size[0]}x{size[1]}"
            )
        return _ggui.window
    problem = ggui_problem()
    if problem:
        raise _GGUIUnavailable(problem)
    try:
        with _quiet_stderr():
            window = ti.ui.Window("ti_golf", size, show_window=False)
        _ggui.scene = window.get_scene()
        _ggui.camera = ti.ui.Camera()
        _ggui.canvas = window.get_canvas()
    except Exception as exc:
        msg = _first_line(exc)
        _ggui.failed = "Vulkan is not available" if "vulkan" in msg.lower() else f"GGUI failed ({msg})"
        raise _GGUIUnavailable(_ggui.failed) from None
    _ggui.window, _ggui.size = window, size
    atexit.register(_close_window)
    return window


def open_window(title: str, size: tuple[int, int], show_window: bool, key: str) -> Any:
    """A GGUI window (``ti.ui.Window``, vsync on) of ``size`` pixels, shown or hidden, for the lab
    or the game; where GGUI cannot open one after :func:`ggui_problem` found nothing wrong (its
    Vulkan device made for a backend it cannot share memory with, say), a :class:`ConfigError`
    on ``key`` that names the backend and GGUI's first line, instead of GGUI's traceback."""
    try:
        with _quiet_stderr():
            return ti.ui.Window(title, size, show_window=show_window, vsync=True)
    except Exception as exc:
        arch = ensure_init().arch
        hint = "" if on_cpu() else "; on the CPU backend: leave out --arch and TI_GOLF_ARCH"
        raise ConfigError(
            key, None, f"GGUI could not open a window on the {arch} backend ({_first_line(exc)}){hint}"
        ) from None


def _first_line(exc: Exception) -> str:
    """The first line of what an exception of GGUI's says (its name when it says nothing)."""
    text = str(exc).strip()
    return text.splitlines()[0] if text else type(exc).__name__


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


def _vbo(
    points: np.ndarray, colors: np.ndarray, normals: np.ndarray | None = None, radius: np.ndarray | None = None
) -> np.ndarray:
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
        self.scene, self.info = scene.scene, get_field_info
        self.keep: list[np.ndarray] = []

    def _hold(self, *arrays: np.ndarray | None) -> list[Any]:
        self.keep.extend(a for a in arrays if a is not None)
        return [self.info(a) for a in arrays]

    def mesh(self, vbo: np.ndarray, indices: np.ndarray) -> None:
        vbo_info, idx_info = self._hold(vbo, indices)
        self.scene.mesh(
            vbo_info,
            True,
            idx_info,
            (0.5, 0.5, 0.5),
            True,  # per-vertex colour, two-sided
            len(indices),
            0,
            len(vbo),
            0,
            False,
        )  # index count/offset, vertex count/offset, wireframe

    def lines(self, vbo: np.ndarray, width: float) -> None:
        vbo_info, idx_info = self._hold(vbo, None)
        self.scene.lines(vbo_info, idx_info, True, (0.5, 0.5, 0.5), width, len(vbo), 0, len(vbo), 0)

    def particles(self, vbo: np.ndarray) -> None:
        (vbo_info,) = self._hold(vbo)
        self.scene.particles(vbo_info, True, True, (0.5, 0.5, 0.5), float(vbo[:, 3].max()), len(vbo), 0)


FIRST_PICTURE_PASSES = 8
"""Most passes of a window's first picture after its discarded first pass (see :func:`_draw_ggui`)."""


def _draw_ggui(frame: _Frame, path: str) -> None:
    # A window's first picture is drawn once and discarded, then again until two passes agree (at
    # most FIRST_PICTURE_PASSES): in CI, with other processes using the Vulkan driver, the first
    # picture of a process came out now and then without its mesh (the ground; the camera, balls and
    # trails in place), and two or four passes until two agreed did not always mend it; alone it
    # never happened.
    first = _ggui.window is None
    window = _ggui_window(frame.view.size)
    rgba, before = None, None
    for k in range(1 + FIRST_PICTURE_PASSES if first else 1):
        draw = draw_scene(frame, _ggui.scene, _ggui.camera)
        _ggui.canvas.set_background_color(BACKGROUND_COLOR)
        _ggui.canvas.scene(_ggui.scene)
        rgba = window.get_image_buffer_as_numpy()  # (width, height, 4) float32 in [0, 1], y up
        draw.keep.clear()
        if before is not None and np.array_equal(rgba, before):
            break
        before = rgba if k > 0 else None  # (the first pass of a first picture is not compared)
    assert rgba is not None  # (one pass at least)
    write_png(rgba, path)


def draw_scene(frame: _Frame, scene: Any, cam: Any) -> _GGUIDraw:
    """Hand a frame to a GGUI scene through camera ``cam`` (set to the frame's view): lights, tiles,
    segments and balls. Returns the holder of its buffers: keep it until the canvas has drawn the
    scene (see :class:`_GGUIDraw`), then clear it. Also used by the game's window (:mod:`.game_gui`)."""
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
        draw.mesh(
            _vbo(
                np.concatenate(frame.tiles),
                np.repeat(frame.tile_colors, counts, axis=0),
                normals=np.repeat(frame.tile_normals, counts, axis=0),
            ),
            np.ascontiguousarray(np.concatenate(fans), np.int32),
        )
    if len(frame.segments):
        draw.lines(
            _vbo(frame.segments.reshape(-1, 3), np.repeat(frame.segment_colors, 2, axis=0)), float(frame.line_px)
        )
    if len(frame.centers):
        # GGUI 1.7 scales sprite radii by width/height (it uses the window width where the height
        # belongs): divide by the aspect ratio so a ball is drawn at its true size.
        aspect = view.size[0] / view.size[1]
        draw.particles(_vbo(frame.centers, frame.colors, radius=frame.radius / aspect))
    return draw


def write_png(rgba: np.ndarray, path: str) -> None:
    """Write GGUI's (width, height, 4) float buffer as an RGB PNG (Pillow, fast compression), whole
    or not at all."""
    rgb = np.clip(rgba[:, ::-1, :3].transpose(1, 0, 2) * 255.0 + 0.5, 0.0, 255.0).astype(np.uint8)
    with atomic_path(path) as tmp:
        Image.fromarray(rgb).save(tmp, format="PNG", compress_level=1)
