"""``ti-golf play --gui``: the golf game in a GGUI window (report §2.5, ``playGolf``).

The course is drawn in 3-D as :func:`ti_golf.render.render` draws it (terrain, cup, flag flying
downwind, the ball at least a few pixels across, its path). A panel holds the stroke: club presets
(tour averages at launch, golf_data.md), sliders for direction, speed, loft and spin, "Aim at the
hole" and "Hit". A stroke is simulated first (:meth:`GolfGame.play`), then replayed in the window
at twice real time; the camera can be moved at any time, during the replay too, as in the report:
hold the right mouse button and drag to look around, W/A/S/D/Q/E to move; "Behind the ball" and
"Above the green" put it back.

Taichi allows one GGUI window per process, so the window is opened once and the round is played in
it until it is closed (or Escape is pressed).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from typing import Any

import numpy as np
import taichi as ti

from ti_golf.errors import ConfigError
from ti_golf.game.rules import (
    CLUBS,
    SHOT_FIELDS,
    GolfGame,
    Shot,
    Stroke,
    describe_round,
    describe_stroke,
    describe_wind,
)
from ti_golf.render import (
    BACKGROUND_COLOR,
    View,
    build_frame,
    destroy_window,
    draw_scene,
    open_window,
    window_problem,
    write_png,
)
from ti_golf.sim.simulation import Simulation

REPLAY_SPEED = 2.0
"""Simulated seconds per second of a stroke's replay."""


def check_display() -> None:
    """Raise :class:`ConfigError` (exit 2 from the CLI) when no window can be shown here."""
    problem = window_problem()
    if problem:
        raise ConfigError("--gui", None, f"{problem}; play in the console without --gui")


def _three_floats(v: Any) -> tuple[float, float, float]:
    """A vector of the GGUI camera (position, look-at point, up) as three Python floats."""
    x, y, z = map(float, v)
    return x, y, z


class GolfWindow:
    """A round of :class:`GolfGame` in a GGUI window of ``size`` pixels (hidden with
    ``show_window=False``: then :meth:`hit`, :meth:`frame` and :meth:`save` drive it, for tests)."""

    def __init__(
        self,
        game: GolfGame,
        size: tuple[int, int] = (1280, 720),
        show_window: bool = True,
        replay_speed: float = REPLAY_SPEED,
        on_stroke: Callable[[Stroke], None] | None = None,
    ) -> None:
        self.game = game
        self.replay_speed = replay_speed
        self.on_stroke = on_stroke
        """Called with every stroke as soon as it is played (the CLI saves the round there)."""
        self.shown = show_window
        self._pending = False
        self.follow = True
        """Whether the camera follows the ball during a replay (and goes behind it for the next stroke)."""
        self.size = size
        self.window = open_window("ti-golf play", size, show_window, key="--gui")
        self.scene = self.window.get_scene()
        self.canvas = self.window.get_canvas()
        self.camera = ti.ui.Camera()
        self.gui = self.window.get_gui()
        self.shot = {
            "direction": round(game.to_hole()[1], 1),
            "speed": CLUBS["7-iron"][0],
            "loft": CLUBS["7-iron"][1],
            "spin": CLUBS["7-iron"][2],
        }
        self.message = "Choose a club, aim and hit."
        self.replay: tuple[Stroke, float] | None = None
        self._display: Simulation | None = None  # the drawn ball (_show_ball)
        self._show_ball(game.ball)
        self.behind_ball()

    # -- camera ------------------------------------------------------------------------------
    def _set_camera(self, position: np.ndarray, lookat: np.ndarray) -> None:
        self.camera.position(*map(float, position))
        self.camera.lookat(*map(float, lookat))
        self.camera.up(0.0, 1.0, 0.0)

    def behind_ball(self) -> None:
        """The camera 12 m behind the ball and 4 m above it, looking down the line to the hole."""
        d = np.radians(self.game.to_hole()[1])
        ahead = np.array([math.cos(d), 0.0, math.sin(d)])
        self._set_camera(self.game.ball - 12.0 * ahead + [0.0, 4.0, 0.0], self.game.ball + 20.0 * ahead)

    def above_green(self) -> None:
        """The camera 8 m above the cup and 6 m short of it, looking at it."""
        ahead = self.game.cup - self.game.ball
        ahead[1] = 0.0
        ahead /= max(float(np.linalg.norm(ahead)), 1e-9)
        self._set_camera(self.game.cup - 6.0 * ahead + [0.0, 8.0, 0.0], self.game.cup)

    def _view(self) -> Any:
        c = self.camera
        return View(
            _three_floats(c.curr_position),
            _three_floats(c.curr_lookat),
            _three_floats(c.curr_up),
            45.0,
            self.size,
            z_near=0.05,
            z_far=2000.0,
        )

    # -- the ball on show --------------------------------------------------------------------
    def _show_ball(self, x: np.ndarray) -> None:
        """Put the drawn ball at ``x`` [m] (3,); the flag flies with the coming stroke's wind."""
        wind = self.game.wind if self.replay is None else self.replay[0].wind
        scene = self.game.scene_with_wind(wind)
        if self._display is None or self._display.scene.air.wind != scene.air.wind:
            self._display = Simulation(scene, x=np.asarray(x, float)[None], track=False)
        else:
            self._display.x = np.asarray(x, float)[None]

    def _trail(self) -> np.ndarray | None:
        """The round's path so far (S, 1, 3): the strokes played, the replayed one up to now."""
        paths = [s.path for s in self.game.strokes[: -1 if self.replay else None]]
        if self.replay is not None:
            stroke = self.replay[0]
            paths.append(stroke.path[: max(int(np.searchsorted(stroke.t, self._replay_time())), 1)])
        return np.concatenate(paths)[:, None, :] if paths else None

    def _replay_time(self) -> float:
        """How far [s of the stroke] the replay has come."""
        assert self.replay is not None  # (asked only during a replay)
        return (time.perf_counter() - self.replay[1]) * self.replay_speed

    # -- one frame ---------------------------------------------------------------------------
    def hit(self, shot: Shot | None = None) -> Stroke:
        """Play ``shot`` (default: the panel's) and start its replay."""
        if shot is None:
            shot = Shot.checked([self.shot[f.name] for f in SHOT_FIELDS], "panel")
        stroke = self.game.play(shot)
        self.replay = (stroke, time.perf_counter())
        self.message = ""
        if self.on_stroke is not None:
            self.on_stroke(stroke)
        return stroke

    def _advance_replay(self) -> None:
        if self.replay is None:
            return
        stroke = self.replay[0]
        tau = self._replay_time()
        if tau >= stroke.t[-1]:
            self.replay = None
            self.message = self._verdict(stroke)
            self._show_ball(self.game.ball)
            if not self.game.over:
                self.shot["direction"] = round(self.game.to_hole()[1], 1)
                if self.follow:
                    self.behind_ball()
            return
        k = int(np.searchsorted(stroke.t, tau))
        x = stroke.path[min(k, len(stroke.path) - 1)]
        self._show_ball(x)
        if self.follow:  # 15 m behind the ball along the stroke's direction, 5 m above it
            d = np.radians(stroke.shot.direction)
            ahead = np.array([math.cos(d), 0.0, math.sin(d)])
            self._set_camera(x - 15.0 * ahead + [0.0, 5.0, 0.0], x)

    def _verdict(self, s: Stroke) -> str:
        text = describe_stroke(s).strip().replace("; ", ";\n")
        return text + ("\n" + describe_round(self.game, "") if self.game.over else "")

    def _panel(self) -> None:
        g = self.game
        with self.gui.sub_window("Stroke", 0.01, 0.01, 0.36, 0.7) as w:
            dist, bearing = g.to_hole()
            wind = g.wind if self.replay is None else self.replay[0].wind
            if self.replay is not None:
                w.text(f"Stroke {self.replay[0].number} on its way ...")
            elif g.over:
                w.text("The round is over: close the window.")
            else:
                w.text(f"Stroke {len(g.strokes) + 1}: {dist:.1f} m to the hole (direction {bearing:.1f} deg)")
            w.text(describe_wind(wind))
            busy = self.replay is not None or g.over
            for name, (speed, loft, spin) in CLUBS.items():
                if w.button(name) and not busy:
                    self.shot.update(speed=speed, loft=loft, spin=spin)
            for f in SHOT_FIELDS:
                lo, hi = (-180.0, 180.0) if f.name == "direction" else (f.low, f.high)
                self.shot[f.name] = w.slider_float(f"{f.name} [{f.unit}]", self.shot[f.name], lo, hi)
            if w.button("Aim at the hole") and not busy:
                self.shot["direction"] = round(bearing, 1)
            if w.button("Hit") and not busy:
                self.message = "simulating ..."  # shown for a frame, then the next frame plays it
                self._pending = True
            self.follow = w.checkbox("Follow the ball", self.follow)
            if w.button("Behind the ball"):
                self.behind_ball()
            if w.button("Above the green"):
                self.above_green()
            w.text(self.message)

    def frame(self) -> None:
        """Draw one frame: the panel, the camera's moves, the replay, the course."""
        if self._pending:
            self._pending = False
            self.hit()
        self._panel()
        if self.shown:  # (a hidden window has no cursor)
            self.camera.track_user_inputs(self.window, movement_speed=0.3, hold_key=ti.ui.RMB)
        self._advance_replay()
        assert self._display is not None  # (shown from the start)
        frame = build_frame(self._display, self._view(), "status", self._trail(), 3.0, None)
        draw = draw_scene(frame, self.scene, self.camera)
        self.canvas.set_background_color(BACKGROUND_COLOR)
        self.canvas.scene(self.scene)
        self._draw = draw  # (its buffers stay alive until the next frame has been handed over)
        if not self.shown:  # a hidden window cannot show(): reading the picture ends its frame
            self._image = self.window.get_image_buffer_as_numpy()

    def save(self, path: str) -> None:
        """Write the last frame drawn by a hidden window as a PNG."""
        write_png(self._image, path)

    def run(self) -> None:
        """Show the window until it is closed or Escape is pressed, then close it."""
        try:
            while self.window.running:
                if self.window.get_event(ti.ui.PRESS) and self.window.event.key == ti.ui.ESCAPE:
                    break
                self.frame()
                self.window.show()
        finally:
            self.close()

    def close(self) -> None:
        """Close the window (leaving no ``imgui.ini`` behind, see :func:`.render.destroy_window`)."""
        if self.window is not None:
            destroy_window(self.window)
            self.window = None
