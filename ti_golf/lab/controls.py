"""What the lab window's keys and mouse do, apart from GGUI: the shortcuts, the orbit camera and
the actions left for the next frame. Tests drive :class:`Controls` headless."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from ti_golf.lab.app import Lab
from ti_golf.render import View, orbit_view

LEFT = (0.005, 0.01, 0.28, 0.98)
"""The "Lab" panel: x, y, width, height as fractions of the window (y from the top)."""
RIGHT = (0.715, 0.01, 0.28, 0.98)
"""The "Parameters" panel."""

YAW_DEG, PITCH_DEG = 116.6, 28.2
"""The camera's first azimuth and elevation [deg]: behind (−x), above and on the +z side, as the
``iso`` preset of ``ti-golf render``."""

ORBIT_DEG = (180.0, 90.0)
"""Degrees of azimuth and elevation a drag across the whole window turns the camera by."""

ZOOM_STEP = 1.03
"""Factor of the camera's distance per frame with Up (closer) or Down (farther) held."""


class Controls:
    """The lab window's keys, mouse and camera on ``lab``."""

    def __init__(self, lab: Lab) -> None:
        self.lab = lab
        self.yaw, self.pitch, self.zoom = YAW_DEG, PITCH_DEG, 1.0
        self.follow = False
        """Whether the camera follows the selected ball (else it frames the whole scene)."""
        self.pending: str | None = None
        """``"load"`` or ``"save"``: done in the next frame, once this one has said so."""
        self.scene_index = self.current_scene()
        """The scene picked in the panel (an index into ``lab.scenes``)."""
        self._drag: str | None = None
        self._cursor: tuple[float, float] | None = None

    def current_scene(self) -> int:
        """The index of the lab's scene in ``lab.scenes`` (0 when it is not there)."""
        lab = self.lab
        for i, name in enumerate(lab.scenes):
            if name in (lab.scene.name, lab.scene.path):
                return i
        return 0

    # -- keys ---------------------------------------------------------------------------------------
    def key(self, key: str) -> None:
        """A key pressed: space starts, stops or continues, R resets to t0, S saves, F follows
        the selected ball (or not), C frames the whole scene from the first angle; other keys do
        nothing."""
        key = key.lower()
        if key == " ":
            self.lab.toggle()
        elif key == "r":
            self.lab.reset()
        elif key == "s":
            self.ask("save")
        elif key == "f":
            self.follow = not self.follow
        elif key == "c":
            self.frame_scene()

    def ask(self, what: str) -> None:
        """Do ``what``, ``"load"`` (the scene picked) or ``"save"``, in the next frame, after this
        one has said that it is under way (loading compiles kernels; saving draws plots)."""
        self.pending = what
        name = Path(self.lab.scenes[self.scene_index]).stem
        self.lab.message, self.lab.refused = (f"loading {name} ..." if what == "load" else "saving ..."), False

    def take_pending(self) -> str | None:
        """The action asked for in the last frame, which the next frame does (once)."""
        what, self.pending = self.pending, None
        return what

    # -- the mouse and the camera ---------------------------------------------------------------------
    def pointer(self, x: float, y: float, left: bool, right: bool) -> None:
        """The cursor at (x, y), fractions of the window from its top left corner, with the left
        and right buttons held or not: a right drag, or a left drag that began outside the
        panels, orbits the camera (a left drag on a panel moves its sliders)."""
        if not (left or right):
            self._drag = None
        elif self._drag is None:
            in_panel = any(p[0] <= x <= p[0] + p[2] and p[1] <= y <= p[1] + p[3] for p in (LEFT, RIGHT))
            self._drag = "orbit" if right or not in_panel else "panel"
        if self._drag == "orbit" and self._cursor is not None:
            self.orbit(x - self._cursor[0], y - self._cursor[1])
        self._cursor = (x, y)

    def orbit(self, dx: float, dy: float) -> None:
        """Turn the camera around its look-at point by a cursor move (dx, dy) [window fractions]:
        right turns the scene with the cursor, down raises the camera; the elevation stays within
        ±89°."""
        self.yaw += ORBIT_DEG[0] * dx
        self.pitch = float(np.clip(self.pitch + ORBIT_DEG[1] * dy, -89.0, 89.0))

    def zoom_in(self, steps: int = 1) -> None:
        """Bring the camera closer by :data:`ZOOM_STEP` per step (at most 50 times closer)."""
        self.zoom = max(self.zoom / ZOOM_STEP**steps, 0.02)

    def zoom_out(self, steps: int = 1) -> None:
        """Move the camera away by :data:`ZOOM_STEP` per step (at most 50 times farther)."""
        self.zoom = min(self.zoom * ZOOM_STEP**steps, 50.0)

    def frame_scene(self) -> None:
        """Look at the whole scene again from the first angle (C)."""
        self.yaw, self.pitch, self.zoom, self.follow = YAW_DEG, PITCH_DEG, 1.0, False

    def view(self, size: tuple[int, int], x: np.ndarray | None = None) -> View:
        """The camera of a window of ``size`` pixels: around the selected ball when following it,
        else fitted to the balls, their trails and the ground between the panels (``x``: the
        balls' centres (N, 3) [m] when the caller has read them for its picture, else read)."""
        lab = self.lab
        target = None
        if self.follow:
            target = tuple(lab.sim.ball(lab.selected)[0] if x is None else x[lab.selected])
        w, h = size
        between = max(int((RIGHT[0] - LEFT[0] - LEFT[2]) * w), 16)
        view = orbit_view(lab.sim, self.yaw, self.pitch, self.zoom, (between, h), 45.0, lab.trails(), target, x)
        return dataclasses.replace(view, size=(w, h))
