"""``ti-golf lab``: the lab application in a GGUI window (report §2.4, "lab3").

The window shows the run in 3-D (balls coloured by status, their trails, the ground, planes and
terrain) between two panels. The left one, "Lab", picks the scene (the bundled scenes and the
file given), runs it (Start, Stop, Continue, Step, Reset t0, Save), reads it out (t, the balls
flying, rolling, at rest and out, the selected ball's speed, spin and height) and edits the
selected ball's position, velocity and spin. The right one, "Parameters", edits every key of the
scene's ``[air]`` (the wind too), ``[ball]``, ``[launch]``, ``[world]``, ``[contact]`` and
``[terrain]`` tables, a table at a time, each with its unit and its help from ``ti-golf keys``.

Numbers are edited with sliders over a span of sensible values (:data:`.params.SLIDER_SPANS`, or
the key's allowed interval); Ctrl+click a slider to type any value, which the scene loader's
checks then accept or refuse (the panel says why, with the allowed range). Booleans are
checkboxes, and keys with a few choices get a button per choice.

The camera orbits the scene: drag with the right mouse button (or with the left one outside the
panels) to turn around it, Up and Down to zoom; it frames the balls and their trails unless it
follows the selected ball (F). Keys: space starts, stops and continues, R resets to t0, S saves,
C frames the scene again. The window's close button ends the lab.

Taichi allows one GGUI window per process: the window is opened once and scenes are loaded into
it until it is closed.
"""

from __future__ import annotations

import textwrap
import time
from pathlib import Path
from typing import Any

import numpy as np
import taichi as ti

from ti_golf.errors import ConfigError
from ti_golf.lab.app import Lab
from ti_golf.lab.controls import LEFT, RIGHT, Controls
from ti_golf.lab.params import Parameter, panel_text, slider_value
from ti_golf.render import (
    BACKGROUND_COLOR,
    NO_DISPLAY,
    build_frame,
    destroy_window,
    draw_scene,
    open_window,
    window_problem,
    write_png,
)

BALL_SPANS = {"x": (-5.0, 5.0), "v": (-100.0, 100.0), "w": (-1000.0, 1000.0)}
"""Slider spans of the selected ball's position [m], velocity [m/s] and spin [rad/s] (widened to
reach the current values)."""

CHAR_PX = 7.0
"""Width [pixels] of a character of the panels' font (Dear ImGui's ProggyClean, 13 px)."""

ERROR_COLOR = (1.0, 0.55, 0.45)
HELP_COLOR = (0.72, 0.72, 0.72)
UNREAD_COLOR = (0.55, 0.55, 0.55)

KEYS_HELP = (
    "space: start/stop/continue  R: reset t0  S: save",
    "drag right (or outside the panels): orbit",
    "Up/Down: zoom  F: follow the ball  C: frame all",
    "Ctrl+click a slider to type a value",
)


SCREENSHOT_HINT = "for a picture of the window without one: ti-golf lab --screenshot lab.png [--t SECONDS]"
"""What ``ti-golf lab`` says where no window can be shown on screen."""


def check_display(on_screen: bool = True) -> None:
    """Raise :class:`ConfigError` (exit 2 from the CLI) when no window can be shown here
    (``on_screen=False``: a hidden one, for ``--screenshot``)."""
    problem = window_problem(on_screen)
    if problem == NO_DISPLAY:
        problem = f"{problem}; {SCREENSHOT_HINT}"
    if problem:
        raise ConfigError("lab", None, problem)


class LabWindow:
    """A :class:`Lab` in a GGUI window of ``size`` pixels (hidden with ``show_window=False``: then
    :meth:`frame` and :meth:`screenshot` drive it, for tests). ``out_dir`` is where Save writes;
    ``rates`` shows the steps per second in the readout (tests leave it out: it varies)."""

    def __init__(
        self,
        lab: Lab,
        size: tuple[int, int] = (1280, 720),
        show_window: bool = True,
        out_dir: str | Path = ".",
        rates: bool = True,
    ) -> None:
        self.lab = lab
        self.size = size
        self.shown = show_window
        self.out_dir = Path(out_dir)
        self.rates = rates
        self.window: Any = open_window("ti-golf lab", size, show_window, key="lab")
        self.scene = self.window.get_scene()
        self.canvas = self.window.get_canvas()
        self.camera = ti.ui.Camera()
        self.gui = self.window.get_gui()
        self.controls = Controls(lab)
        """The keys, the mouse and the camera."""
        self.table = "air"
        """The table the "Parameters" panel shows."""
        self.show_help = True
        self.edit_ball = False
        self._last = time.perf_counter()
        self._image: np.ndarray | None = None
        self.seconds: dict[str, float] = {}
        """Where the last :meth:`frame`'s wall time went [s]: ``panels`` (the keys, the mouse and
        the panels), ``steps`` (the run's steps), ``picture`` (the 3-D view made on the host and
        handed to GGUI) and, in a hidden window, ``drawing`` (GGUI drawing it and reading it back;
        a window on screen draws in :meth:`run`'s ``show``)."""
        self._draw: Any = None

    # -- the keys and the mouse -------------------------------------------------------------------
    def _input(self) -> None:
        """Hand the keys pressed and the cursor to :attr:`controls`; Up and Down zoom."""
        w = self.window
        for event in w.get_events(ti.ui.PRESS):
            self.controls.key(event.key)
        x, y = w.get_cursor_pos()
        self.controls.pointer(x, 1.0 - y, w.is_pressed(ti.ui.LMB), w.is_pressed(ti.ui.RMB))  # (GGUI's y goes up)
        if w.is_pressed(ti.ui.UP):
            self.controls.zoom_in()
        if w.is_pressed(ti.ui.DOWN):
            self.controls.zoom_out()

    # -- the panels ----------------------------------------------------------------------------------
    def _lab_panel(self) -> None:
        lab = self.lab
        with self.gui.sub_window("Lab", *LEFT) as g:
            c, names = self.controls, lab.scenes
            c.scene_index = g.slider_int(f"{Path(names[c.scene_index]).stem}###scene", c.scene_index, 0, len(names) - 1)
            if g.button("Load the scene"):
                c.ask("load")
            for line in textwrap.wrap(panel_text(lab.scene.description), self._chars(LEFT))[:3]:
                g.text(line, HELP_COLOR)
            if g.button("Start (from t0)"):
                lab.start()
            if g.button("Stop"):
                lab.stop()
            if g.button("Continue"):
                lab.resume()
            if g.button("Step (one time step)"):
                lab.step()
            if g.button("Reset t0"):
                lab.reset()
            if g.button("Save"):
                c.ask("save")
            real_time = g.checkbox("Real time (else as fast as it goes)", lab.speed is not None)
            if real_time and lab.speed is None:
                lab.speed = 1.0
            elif not real_time:
                lab.speed = None
            if lab.speed is not None:
                lab.speed = g.slider_float("sim. s per s###speed", lab.speed, 0.05, 10.0)
            readout = lab.readout()
            for line in readout.lines(rates=self.rates):
                for part in textwrap.wrap(panel_text(line), self._chars(LEFT), subsequent_indent="  "):
                    g.text(part)
            self._ball_editor(g)
            c.follow = g.checkbox("Follow the selected ball (F)", c.follow)
            for line in KEYS_HELP:
                g.text(line, HELP_COLOR)
            for line in textwrap.wrap(panel_text(lab.message), self._chars(LEFT))[:6]:
                g.text(line, ERROR_COLOR if lab.refused else None)

    def _ball_editor(self, g: Any) -> None:
        lab = self.lab
        if lab.sim.n > 1:
            lab.select(g.slider_int("selected ball###ball", lab.selected, 0, lab.sim.n - 1))
        self.edit_ball = g.checkbox(f"Edit ball {lab.selected}: position, velocity, spin", self.edit_ball)
        if not self.edit_ball:
            return
        sim, i = lab.sim, lab.selected
        for name, values, unit in zip("xvw", sim.ball(i), ("m", "m/s", "rad/s")):
            lo, hi = BALL_SPANS[name]
            lo, hi = min(lo, float(values.min())), max(hi, float(values.max()))
            for c, axis in enumerate("xyz"):
                got = g.slider_float(f"{name}_{axis} [{unit}]###ball-{name}{c}", float(values[c]), lo, hi)
                if np.float32(got) != np.float32(values[c]):
                    new = values.copy()
                    new[c] = slider_value(got, "float")
                    lab.set_ball(**{name: new})

    def _parameter_panel(self) -> None:
        lab = self.lab
        with self.gui.sub_window("Parameters", *RIGHT) as g:
            tables = list(dict.fromkeys(p.table for p in lab.parameters()))
            if self.table not in tables:
                self.table = tables[0]
            for t in tables:
                if g.button(f"[{t}]" + (" <" if t == self.table else "") + f"###table-{t}"):
                    self.table = t
            self.show_help = g.checkbox("Show the help", self.show_help)
            params = lab.parameters(self.table)
            if params and params[0].at_t0:
                g.text("These keys set up the balls or the ground:", HELP_COLOR)
                g.text("they change at t0 (Reset t0 first).", HELP_COLOR)
            for p in params:
                self._editor(g, p)

    def _editor(self, g: Any, p: Parameter) -> None:
        """The widgets of one key under a line with its name, value and unit: a slider (one per
        component), a checkbox or a button per choice; then its help."""
        lab = self.lab
        if not p.editable:
            why = "not read with these settings" if not p.read else "given in the scene file"
            g.text(panel_text(f"{p.label()} ({why})"), UNREAD_COLOR)
        elif p.kind == "bool":
            got = g.checkbox(f"{panel_text(p.label())}###{p.key}", bool(p.value))
            if got != p.value:
                lab.set(p.key, got)
        elif p.choices is not None and p.kind == "str":
            g.text(panel_text(p.label()))
            for choice in p.choices:
                if choice != p.value and g.button(f"use {choice}###{p.key}={choice}"):
                    lab.set(p.key, choice)
        elif p.kind in ("vec3", "vec2"):
            g.text(panel_text(p.label()))
            integer = p.key == "terrain.resolution"
            for c, axis in enumerate("xyz" if p.kind == "vec3" else "01"):
                label = f"{axis}###{p.key}.{c}"
                value = p.value[c]
                if integer:
                    got = g.slider_int(label, int(value), int(p.low), int(p.high))
                else:
                    got = g.slider_float(label, float(value), p.low, p.high)
                if np.float32(got) != np.float32(value):
                    new = list(p.value)
                    new[c] = int(got) if integer else slider_value(got, "float")
                    lab.set(p.key, new)
        elif p.kind == "int":
            g.text(panel_text(p.label()))
            got = g.slider_int(f"###{p.key}", int(p.value), int(p.low), int(p.high))
            if got != p.value:
                lab.set(p.key, int(got))
        else:
            g.text(panel_text(p.label()))
            got = g.slider_float(f"###{p.key}", float(p.value), p.low, p.high)
            if np.float32(got) != np.float32(p.value):
                lab.set(p.key, slider_value(got, "float"))
        if self.show_help:
            for line in p.help_lines(self._chars(RIGHT) - 2):
                g.text("  " + line, HELP_COLOR)

    def _chars(self, panel: tuple[float, float, float, float]) -> int:
        """How many characters of the panel's font fit on one of its lines."""
        return max(int((panel[2] * self.size[0] - 20) / CHAR_PX), 20)

    # -- one frame -----------------------------------------------------------------------------------
    def frame(self, max_steps: int | None = None) -> None:
        """One frame: what was asked last frame, the keys and the mouse, the panels, the run's
        steps for the time since the last frame (or exactly ``max_steps``), the 3-D view."""
        now = time.perf_counter()
        wall_dt, self._last = min(now - self._last, 0.1), now
        pending = self.controls.take_pending()
        if pending == "load":
            self.lab.load(self.lab.scenes[self.controls.scene_index])
            self.controls.scene_index = self.controls.current_scene()
            self.controls.frame_scene()
        if self.shown:  # (a hidden window has no keys and no cursor)
            self._input()
        self._lab_panel()
        self._parameter_panel()
        stepping = time.perf_counter()
        self.lab.advance(wall_dt, max_steps=max_steps)
        drawing = time.perf_counter()
        self._draw_view()
        self.seconds.update(panels=stepping - now, steps=drawing - stepping)
        if pending == "save":
            self.lab.save(self.out_dir, screenshot=self.screenshot)

    def _draw_view(self) -> None:
        lab = self.lab
        start = time.perf_counter()
        x = lab.sim.x  # (read once: the camera's box and the picture)
        frame = build_frame(lab.sim, self.controls.view(self.size, x), "status", lab.trails(), 3.0, None, x=x)
        draw = draw_scene(frame, self.scene, self.camera)
        self.canvas.set_background_color(BACKGROUND_COLOR)
        self.canvas.scene(self.scene)
        self._draw = draw  # (its buffers stay alive until the frame has been handed over)
        self._image = None
        handed = time.perf_counter()
        self.seconds.update(picture=handed - start)
        if not self.shown:  # a hidden window cannot show(): reading the picture ends its frame
            self._image = self.window.get_image_buffer_as_numpy()
            self.seconds.update(drawing=time.perf_counter() - handed)

    def screenshot(self, path: str | Path) -> None:
        """Write the frame just drawn (the panels with it) as a PNG, whole or not at all."""
        if self._image is None:
            self._image = self.window.get_image_buffer_as_numpy()
        write_png(self._image, str(path))

    def run(self) -> None:
        """Show the window until it is closed, then close it."""
        try:
            while self.window.running:
                self.frame()
                self.window.show()
        finally:
            self.close()

    def close(self) -> None:
        """Close the window (leaving no ``imgui.ini`` behind, see :func:`.render.destroy_window`)."""
        if self.window is not None:
            destroy_window(self.window)
            self.window = None
