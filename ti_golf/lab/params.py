"""The lab's editable parameters: every scene key a run reads, with its unit, current value, help
and the range its slider spans.

The keys are those of the scene's ``[air]`` (the wind too), ``[ball]``, ``[launch]``, ``[world]``,
``[contact]`` and ``[terrain]`` tables (:data:`TABLES`), less those no simulation reads
(``world.t_max``; see :mod:`ti_golf.sim.changes`). Plain Python, no Taichi.
"""

from __future__ import annotations

import math
import re
import textwrap
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

import numpy as np

from ti_golf.scene.across import read_across
from ti_golf.scene.balls import launch_position
from ti_golf.scene.checks import Interval, OneOf
from ti_golf.scene.keys import Key, help_text, is_read
from ti_golf.scene.readers import NOT_READ
from ti_golf.scene.schema import SCHEMA, Scene
from ti_golf.scene.weather import isa_pressure, isa_temperature
from ti_golf.sim.changes import at_t0

TABLES = ("air", "ball", "launch", "world", "contact", "terrain")
"""The scene tables whose keys the lab edits, in the panel's order."""

SLIDER_SPANS: dict[str, tuple[float, float]] = {
    "air.rho": (0.0, 2.0),
    "air.C_D": (0.0, 1.0),
    "air.C_M": (0.0, 0.1),
    "air.omega_M": (0.1, 10.0),
    "air.C_omega": (0.0, 0.05),
    "air.wind": (-20.0, 20.0),
    "air.viscosity": (1.0e-5, 3.0e-5),
    "air.wind_height": (1.0, 50.0),
    "air.wind_z0": (0.001, 1.0),
    "ball.mass": (0.01, 0.2),
    "ball.radius": (0.005, 0.1),
    "launch.speed": (0.0, 100.0),
    "launch.direction_deg": (-180.0, 180.0),
    "launch.spin": (-1000.0, 1000.0),
    "launch.position": (-10.0, 10.0),
    "world.dt": (1e-5, 0.02),
    "world.gravity": (-20.0, 20.0),
    "world.t_end": (0.5, 60.0),
    "world.ground_height": (-5.0, 5.0),
    "world.v_rest": (0.0, 0.1),
    "world.t_rest": (0.0, 1.0),
    "contact.mu": (0.0, 1.0),
    "contact.mu_roll": (0.0, 0.5),
    "contact.v_bounce": (0.0, 0.5),
    "terrain.origin": (-100.0, 100.0),
    "terrain.size": (1.0, 500.0),
    "terrain.resolution": (2.0, 513.0),
    "terrain.seed": (0.0, 1000.0),
    "terrain.amplitude": (0.0, 20.0),
    "terrain.slope": (-1.0, 1.0),
    "terrain.kill_height": (-100.0, 100.0),
}
"""The span [low, high] of each key's slider where the key's allowed values are unbounded (or
too wide to pick from on a slider); every vector component gets the same span. A slider always
reaches the current value, and a value typed into it (Ctrl+click) may lie outside: the scene
loader's check decides."""


@dataclass(frozen=True)
class Parameter:
    """One editable scene key as the lab shows it.

    Attributes:
        key: the dotted key, ``"air.C_D"``.
        kind: the key's kind (``"float"``, ``"int"``, ``"bool"``, ``"str"``, ``"vec3"``, ``"vec2"``,
            ``"range"``; see :class:`~ti_golf.scene.keys.Key`).
        unit: its unit (``"-"``: none).
        help: its one-line help, as ``ti-golf keys`` prints it.
        allowed: its allowed values in words (``"[0, 1]"``, ``">= 0"``), or ``""``.
        value: the value the run uses now; for a key left unset, the value that stands in for it
            (``launch.position``: the launch point; ``terrain.kill_height``: the origin's y − 10 m).
        read: whether the scene's settings read it (``air.C_D`` is unread with ``air.model =
            "spin_ratio"``); an unread key cannot be changed.
        at_t0: whether it sets up the balls or the ground, and so changes only at t0.
        choices: the values a string or integer key allows, when it lists them.
        low, high: the span of its slider (of each component of a vector).
    """

    key: str
    kind: str
    unit: str
    help: str
    allowed: str
    value: Any
    read: bool
    at_t0: bool
    choices: tuple[Any, ...] | None
    low: float
    high: float

    @property
    def table(self) -> str:
        """The key's table, ``"air"``."""
        return self.key.split(".", 1)[0]

    @property
    def name(self) -> str:
        """The key's name in its table, ``"C_D"``."""
        return self.key.split(".", 1)[1]

    @property
    def editable(self) -> bool:
        """Whether a slider, checkbox or choice can change it (numbers, vectors of numbers, booleans
        and keys with choices; not file names or lists of levels)."""
        return self.read and (self.kind in ("float", "int", "bool", "vec3", "vec2") or self.choices is not None)

    def label(self) -> str:
        """``C_D = 0.3 [-]``: the name, the value as the scene file would give it, the unit."""
        unit = "" if self.unit == "-" else f" [{self.unit}]"
        return f"{self.name} = {format_value(self.value)}{unit}"

    def help_lines(self, width: int = 64) -> list[str]:
        """The help, with the allowed values, wrapped to lines of ``width`` characters, in the
        window font's characters (:func:`panel_text`)."""
        text = self.help + (f"; allowed {self.allowed}" if self.allowed else "")
        return textwrap.wrap(panel_text(text), width)


PANEL_GLYPHS = {
    "\u2212": "-",
    "\u2013": "-",
    "\u2026": "...",
    "\u221d": "~",
    "\u03c9": "omega",
    "\u03c1": "rho",
    "\u03c6": "phi",
    "\u03bc": "mu",
    "\u03c0": "pi",
    "\u03b8": "theta",
    "\u03b3": "gamma",
    "\u0394": "Delta",
    "\u0177": "y^",
}
"""Characters of the keys' help that the window's font (Latin-1) lacks, as they are written there."""


def panel_text(text: str) -> str:
    """``text`` in the characters the window's font has (Latin-1): Greek letters by name
    (``ω`` as ``omega``), a minus sign as a hyphen, any other character as ``?``."""

    def name(m: re.Match[str]) -> str:
        before, after = text[m.start() - 1 : m.start()], text[m.end() : m.end() + 1]
        word = PANEL_GLYPHS[m.group()]
        if word.isalpha():  # a Greek letter between letters stays a word of its own: "½ rho A"
            word = (" " if before.isalnum() else "") + word + (" " if after.isalnum() else "")
        return word

    text = re.sub("|".join(PANEL_GLYPHS), name, text)
    return text.encode("latin-1", "replace").decode("latin-1")


def format_value(value: Any) -> str:
    """A value as a scene file writes it, numbers to 6 significant digits: ``0.3``, ``[0, 0, 10]``,
    ``true``, ``rk4``."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return f"{value:.6g}"
    if isinstance(value, (tuple, list)):
        return "[" + ", ".join(format_value(v) for v in value) + "]"
    if value is None:
        return "(unset)"
    return str(value) if value != "" else '""'


def parameters(scene: Scene) -> list[Parameter]:
    """The editable keys of ``scene``, table by table (:data:`TABLES`): a table the scene does not
    have (``[launch]`` of a scene of given balls, ``[terrain]``) has none."""
    return [p for table in TABLES for p in table_parameters(scene, table)]


def table_parameters(scene: Scene, table: str) -> list[Parameter]:
    """The editable keys of one table of ``scene`` (none when the scene lacks the table)."""
    obj = getattr(scene, table)
    if obj is None:
        return []
    return [_parameter(scene, table, obj, k) for k in _editable_keys(table)]


def _editable_keys(table: str) -> Iterator[Key]:
    for name, k in SCHEMA[table].items():
        if f"{table}.{name}" not in NOT_READ:
            yield k


def _parameter(scene: Scene, table: str, obj: Any, k: Key) -> Parameter:
    dotted = f"{table}.{k.name}"
    value = getattr(obj, k.name)
    if value is None and dotted == "launch.position":
        value = tuple(float(c) for c in launch_position(scene))
    elif value is None and dotted == "terrain.kill_height":
        value = scene.terrain.kill if scene.terrain is not None else None
    elif value is None and dotted.startswith("air."):
        value = _weather_stand_in(scene, k.name)
    choices = tuple(k.check.choices) if isinstance(k.check, OneOf) else None
    low, high = slider_span(dotted, k, value)
    return Parameter(
        dotted,
        k.kind,
        k.unit,
        help_text(k),
        k.allowed,
        value,
        is_read(k, obj, scene) and read_across(dotted, scene),
        at_t0(dotted),
        choices,
        low,
        high,
    )


def _weather_stand_in(scene: Scene, name: str) -> float | None:
    """The value an unset weather key stands for: the standard atmosphere's temperature [°C] and
    pressure [Pa] at the scene's altitude (sea level when that is unset too), dry air, sea level."""
    altitude = scene.air.altitude or 0.0
    stand_in = {
        "temperature": isa_temperature(altitude),
        "pressure": isa_pressure(altitude),
        "altitude": 0.0,
        "humidity": 0.0,
    }
    return stand_in.get(name)


def slider_span(dotted: str, k: Key, value: Any) -> tuple[float, float]:
    """The slider's [low, high] for key ``k``: its allowed interval where that is bounded, else
    :data:`SLIDER_SPANS` (else around the value), always reaching the current value."""
    lo, hi = SLIDER_SPANS.get(dotted, (math.nan, math.nan))
    check = k.check
    if isinstance(check, Interval) and check.hi is not None and dotted not in SLIDER_SPANS:
        lo, hi = check.lo, check.hi
    if isinstance(check, OneOf) and all(isinstance(c, (int, float)) for c in check.choices):
        lo, hi = min(check.choices), max(check.choices)
    if not _numeric(value):
        return 0.0, 0.0  # (no slider)
    numbers = [float(c) for c in (value if isinstance(value, (tuple, list)) else [value])]
    if math.isnan(lo):
        v = max((abs(c) for c in numbers), default=1.0)
        lo, hi = (-2.0 * max(v, 1.0), 2.0 * max(v, 1.0))
        if isinstance(check, Interval):
            lo = max(lo, check.lo)
    for c in numbers:
        lo, hi = min(lo, c), max(hi, c)
    return float(lo), float(hi)


def _numeric(value: Any) -> bool:
    if isinstance(value, (tuple, list)):
        return all(isinstance(c, (int, float)) and not isinstance(c, bool) for c in value)
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def slider_value(x: float, kind: str) -> float | int:
    """A slider's value as the key takes it: a float the widget holds in 32 bits (``0.30000001``)
    as its shortest decimal (``0.3``), an integer as an int."""
    if kind == "int":
        return int(x)
    return float(str(np.float32(x)))
