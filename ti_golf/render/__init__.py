"""Pictures of a simulation: off-screen 3-D renders (GGUI, else matplotlib) and plots.

:func:`render` writes a PNG of a :class:`~ti_golf.Simulation` through a :class:`View`;
:mod:`ti_golf.render.plots` draws sweeps, runs and golf rounds with matplotlib. Importing this
package starts no Taichi runtime.
"""

from ti_golf.render.camera import View, ball_colors, camera_view, orbit_view
from ti_golf.render.frame import build_frame
from ti_golf.render.ggui import (
    destroy_window,
    draw_scene,
    ggui_available,
    ggui_problem,
    open_window,
    write_png,
)
from ti_golf.render.offscreen import GGUI_ARCHES, NO_DISPLAY, arch_ggui_refuses, render, window_problem
from ti_golf.render.style import (
    AT_REST_COLOR,
    BACKENDS,
    BACKGROUND_COLOR,
    CAMERAS,
    COLOR_BY,
    FLAG_COLOR,
    FLAGSTICK_COLOR,
    FLYING_COLOR,
    GROUND_COLORS,
    OUT_OF_BOUNDS_COLOR,
    ROLLING_COLOR,
    STATUS_COLORS,
    SURFACE_COLORS,
    TERRAIN_COLORS,
    WALL_COLORS,
    RenderError,
)

__all__ = [
    "AT_REST_COLOR",
    "NO_DISPLAY",
    "BACKENDS",
    "BACKGROUND_COLOR",
    "CAMERAS",
    "COLOR_BY",
    "FLAGSTICK_COLOR",
    "FLAG_COLOR",
    "FLYING_COLOR",
    "GROUND_COLORS",
    "OUT_OF_BOUNDS_COLOR",
    "ROLLING_COLOR",
    "STATUS_COLORS",
    "SURFACE_COLORS",
    "TERRAIN_COLORS",
    "WALL_COLORS",
    "RenderError",
    "GGUI_ARCHES",
    "View",
    "arch_ggui_refuses",
    "ball_colors",
    "build_frame",
    "camera_view",
    "destroy_window",
    "draw_scene",
    "ggui_available",
    "ggui_problem",
    "open_window",
    "orbit_view",
    "render",
    "window_problem",
    "write_png",
]
