"""Colours and constants of the pictures (RGB in [0, 1]), shared by both renderers."""

from __future__ import annotations

from typing import TYPE_CHECKING

from ti_golf.errors import TiGolfError
from ti_golf.scene.schema import AT_REST, FLYING, OUT_OF_BOUNDS, ROLLING

if TYPE_CHECKING:  # pragma: no cover
    pass


# -- colours (RGB in [0, 1]) ----------------------------------------------------------------------
FLYING_COLOR = (0.95, 0.36, 0.08)
"""Balls in the air: orange."""
ROLLING_COLOR = (0.98, 0.82, 0.10)
"""Balls touching a plane or another ball and moving: yellow."""
AT_REST_COLOR = (0.15, 0.36, 0.92)
"""Balls put at rest: blue."""
OUT_OF_BOUNDS_COLOR = (0.66, 0.18, 0.80)
"""Balls out of bounds: purple."""
STATUS_COLORS = {
    FLYING: FLYING_COLOR,
    ROLLING: ROLLING_COLOR,
    AT_REST: AT_REST_COLOR,
    OUT_OF_BOUNDS: OUT_OF_BOUNDS_COLOR,
}
"""Ball colour per status code (``color_by="status"``)."""
BACKGROUND_COLOR = (0.80, 0.86, 0.92)
"""The sky: a pale grey-blue."""
GROUND_COLORS = ((0.38, 0.58, 0.30), (0.33, 0.52, 0.26))
"""Checker colours of planes facing up (|n_y| > 0.7): two greens."""
WALL_COLORS = ((0.72, 0.70, 0.66), (0.64, 0.62, 0.58))
"""Checker colours of other planes: two greys."""
TERRAIN_COLORS = ((0.30, 0.50, 0.24), (0.62, 0.66, 0.40))
"""Terrain colours from its lowest to its highest point: dark green to dry grass."""
SURFACE_COLORS = {
    "green": (0.36, 0.72, 0.36),
    "fairway": (0.55, 0.78, 0.40),
    "rough": (0.42, 0.56, 0.14),
    "bunker": (0.91, 0.85, 0.63),
}
"""Terrain colours of the surface types (``[[surfaces]]``) by name; the cells of a type not named
here, and a terrain without types, are tinted by height (``TERRAIN_COLORS``). The course map of
:func:`ti_golf.game.course_map.plot_round` uses the same colours."""
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
