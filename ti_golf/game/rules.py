"""The golf game (report §2.5): a ball on a course, played stroke by stroke until it is holed or
goes out of bounds.

A scene is a course when it has a ``[terrain]`` and a ``[hole]``; its ``[game]`` table sets where
the ball starts (else a random point of the course, as in the report), the wind of each stroke,
the most strokes and how long a stroke may take. Each stroke is a :class:`Shot` as the report's
player enters it (horizontal direction, speed in km/h, club loft, backspin in rpm), simulated with
the scene's flight and terrain physics until the ball rests, leaves the course or drops into the
cup (:mod:`ti_golf.game.cup`). :class:`GolfGame` holds the round; the console (:mod:`ti_golf.cli.play`)
and any other front end only ask it for shots.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from ti_golf.errors import ConfigError
from ti_golf.game.cup import LOW_GAP, holed_at
from ti_golf.scene.launch_monitor import RPM
from ti_golf.scene.schema import (
    AT_REST,
    OUT_OF_BOUNDS,
    HoleConfig,
    Scene,
    backspin_axis,
    launch_velocity,
)
from ti_golf.scene.terrain import build_terrain
from ti_golf.sim.simulation import Simulation

KMH = 1.0 / 3.6
"""m/s per km/h."""
HOLED, OUT, RESTS, MOVING = "holed", "out of bounds", "at rest", "still moving"
"""Outcomes of a stroke."""


@dataclass(frozen=True)
class Field:
    """One number of a shot: its name, unit and allowed range (both ends included)."""

    name: str
    unit: str
    low: float
    high: float
    doc: str

    def check(self, value: float, source: str, got: str | None = None) -> float:
        """``value`` when it is a finite number in range, else a :class:`ConfigError` naming
        ``source`` (the file and line, or the option), the field and the range, and quoting
        ``got`` (the text the value was read from; default: the value)."""
        if not (math.isfinite(value) and self.low <= value <= self.high):
            raise ConfigError(source, self.name, self.refusal(repr(value) if got is None else got))
        return float(value)

    def parse(self, text: str, source: str) -> float:
        """The value ``text`` spells, checked (:meth:`check`): a word that is no number gets the
        same error as a number out of range, so a mistake reads the same at a prompt, in a
        ``--shots`` file and in a window."""
        try:
            value = float(text)
        except ValueError:
            raise ConfigError(source, self.name, self.refusal(repr(text))) from None
        return self.check(value, source, repr(text))

    def refusal(self, got: str) -> str:
        """What a wrong value of this field is told: the allowed range and unit, and what was ``got``."""
        return f"must be a number in [{self.low:g}, {self.high:g}] {self.unit} (got {got})"


SHOT_FIELDS = (
    Field("direction", "deg", -360.0, 360.0, "horizontal direction, from +x toward +z"),
    Field("speed", "km/h", 0.0, 350.0, "ball speed (a tour driver: about 270 km/h)"),
    Field("loft", "deg", -10.0, 90.0, "launch angle above the horizontal (0 for a putt)"),
    Field("spin", "rpm", -12000.0, 12000.0, "backspin (negative: topspin)"),
)
"""The four numbers the player enters for a stroke, in order (report §2.5)."""

CLUBS = {
    "Driver": (275.0, 10.4, 2545.0),
    "7-iron": (198.0, 16.1, 7124.0),
    "Wedge": (167.0, 23.7, 9316.0),
    "Chip": (40.0, 30.0, 2000.0),
    "Putter": (8.0, 0.0, 0.0),
}
"""Club presets: ball speed [km/h], launch angle [deg], backspin [rpm]; driver, 7-iron and pitching
wedge are PGA Tour averages (TrackMan 2023, golf_data.md: 171, 123 and 104 mph)."""

TOUR_CARRY_M = {"Driver": 257.9, "7-iron": 160.9, "Wedge": 129.8}
"""What the tour clubs of :data:`CLUBS` carry on tour [m] (TrackMan 2023: 282, 176 and 142 yd),
to give a player a sense of scale; the course's air and wind make the game's carries differ."""


def club(name: str) -> tuple[float, float, float] | None:
    """The (speed, loft, spin) of the club called ``name`` (any case), or ``None``."""
    return {k.lower(): v for k, v in CLUBS.items()}.get(name.strip().lower())


def club_list() -> list[str]:
    """One line per club of :data:`CLUBS`: its name, speed, loft and spin, and the tour carry."""
    lines = []
    for name, (speed, loft, spin) in CLUBS.items():
        carry = f" (carries about {TOUR_CARRY_M[name]:.0f} m on tour)" if name in TOUR_CARRY_M else ""
        lines.append(f"  {name:<7} {speed:5g} km/h, loft {loft:4g} deg, {spin:5g} rpm{carry}")
    return lines


@dataclass(frozen=True)
class Shot:
    """A stroke as the player enters it: direction [deg] (from +x toward +z), ball speed [km/h],
    loft (launch angle) [deg] and backspin [rpm]."""

    direction: float
    speed: float
    loft: float
    spin: float = 0.0

    @classmethod
    def checked(cls, values: tuple[float, ...] | list[float], source: str) -> Shot:
        """A shot from its four numbers, each checked against :data:`SHOT_FIELDS`."""
        return cls(*(f.check(float(v), source) for f, v in zip(SHOT_FIELDS, values)))

    def velocity(self) -> np.ndarray:
        """Launch velocity (3,) [m/s]."""
        return np.array(launch_velocity(self.speed * KMH, self.loft, self.direction))

    def angular_velocity(self) -> np.ndarray:
        """Launch spin ω (3,) [rad/s]: backspin about the axis d × ŷ of the shot's direction d."""
        return self.spin * RPM * np.array(backspin_axis(self.direction))


@dataclass(frozen=True)
class Stroke:
    """One stroke played: the shot, the wind it met, and where the ball went.

    ``t`` (S,) [s] and ``path`` (S, 3) [m] sample the ball from the hit until it rested, left the
    course or dropped into the cup (then the path ends there and ``end`` is the cup).
    """

    number: int
    shot: Shot
    wind: np.ndarray
    start: np.ndarray
    end: np.ndarray
    t: np.ndarray
    path: np.ndarray
    outcome: str
    to_hole: float
    carry: float
    """Horizontal distance [m] from where the ball was hit to where it first came down (0 for a putt,
    NaN when it never came down: out of bounds in the air, or still flying when the stroke ended)."""

    @property
    def distance(self) -> float:
        """Horizontal distance [m] from where the ball was hit to where it ended."""
        return float(np.hypot(*(self.end - self.start)[[0, 2]]))

    @property
    def apex(self) -> float:
        """Highest point of the path above the start [m]."""
        return float(self.path[:, 1].max() - self.start[1])


class GolfGame:
    """A round on a course: the ball, the wind and the strokes so far.

    Args:
        scene: a scene with a ``[terrain]`` and a ``[hole]`` on it.
        seed: seeds the random start (when ``game.start`` is not set) and the winds.
    """

    def __init__(self, scene: Scene, seed: int | None = None) -> None:
        source = scene.path or scene.name
        if scene.terrain is None or scene.hole is None:
            missing = "[terrain]" if scene.terrain is None else "[hole]"
            raise ConfigError(
                source,
                None,
                f"is not a course: the golf game needs a [terrain] and a [hole] "
                f"(it has no {missing}; try the bundled scene golf_hole)",
            )
        self.scene = scene
        self.hole: HoleConfig = scene.hole
        """The course's cup: its position (x, z) and radius, in metres."""
        self.terrain = build_terrain(scene.terrain, scene.path)
        self.rng = np.random.default_rng(seed)
        self.radius = scene.ball.radius
        self.g = float(np.linalg.norm(scene.world.gravity))
        hole = np.asarray(scene.hole.position, dtype=float)
        if not self.terrain.contains(*hole):
            raise ConfigError(
                *scene.where("hole.position"),
                f"must lie on the terrain (x in {self._span(0)}, z in {self._span(2)}; got {_point(hole)})",
            )
        self.cup = self._on_ground(hole)
        if scene.game.start is not None:
            start = np.asarray(scene.game.start, dtype=float)
            if not self.terrain.contains(*start):
                raise ConfigError(
                    *scene.where("game.start"),
                    f"must lie on the terrain (x in {self._span(0)}, z in {self._span(2)}; got {_point(start)})",
                )
            if np.hypot(*(start - hole)) <= self.hole.radius:
                raise ConfigError(
                    *scene.where("game.start"),
                    f"must lie outside the cup (within {self.hole.radius:g} m of {_point(hole)})",
                )
        else:
            start = self._random_start(hole)
            if np.hypot(*(start - hole)) <= self.hole.radius:
                raise ConfigError(
                    *scene.where("hole.radius"),
                    f"= {self.hole.radius:g} m leaves no point of the course to start from outside the cup: a "
                    "smaller cup, or a game.start",
                )
        self.ball = self._on_ground(start)
        """Where the ball lies [m] (3,): its centre, resting on the terrain."""
        self.strokes: list[Stroke] = []
        self.outcome: str | None = None
        """``None`` while the round goes on, else ``HOLED``, ``OUT`` or ``"no strokes left"``."""
        self.wind = self._draw_wind()
        """The wind of the next stroke [m/s] (3,)."""

    def _span(self, axis: int) -> str:
        lo = self.terrain.origin[axis]
        return f"[{lo:g}, {lo + self.terrain.size[0 if axis == 0 else 1]:g}] m"

    def _on_ground(self, xz: np.ndarray) -> np.ndarray:
        """The centre (3,) of a ball resting on the terrain at horizontal point ``xz`` (its gap zero)."""
        x, z = float(xz[0]), float(xz[1])
        n_y = float(self.terrain.normal(x, z)[1])
        return np.array([x, float(self.terrain.height(x, z)) + self.radius / n_y, z])

    def _random_start(self, hole: np.ndarray) -> np.ndarray:
        """A random point of the course, 10 % of its size in from the edges and at least a quarter of
        the course's length from the hole and outside the cup (the report's game puts the ball
        anywhere); on a course too small for that, the draw farthest from the hole."""
        lo = self.terrain.origin[[0, 2]] + 0.1 * self.terrain.size
        hi = lo + 0.8 * self.terrain.size
        far = max(0.25 * float(self.terrain.size.max()), np.nextafter(self.hole.radius, np.inf))
        farthest, reach = lo, -1.0
        for _ in range(1000):
            p = self.rng.uniform(lo, hi)
            d = float(np.hypot(*(p - hole)))
            if d >= far:
                return p
            if d > reach:
                farthest, reach = p, d
        return farthest

    def _draw_wind(self) -> np.ndarray:
        """Level wind of up to ``game.wind_max`` from a random direction; the scene's wind when it is 0."""
        w_max = self.scene.game.wind_max
        if w_max <= 0.0:
            return np.asarray(self.scene.air.wind, dtype=float)
        speed, heading = self.rng.uniform(0.0, w_max), self.rng.uniform(0.0, 2.0 * math.pi)
        return np.array([speed * math.cos(heading), 0.0, speed * math.sin(heading)])

    @property
    def over(self) -> bool:
        """Whether the round has ended."""
        return self.outcome is not None

    def to_hole(self) -> tuple[float, float]:
        """(horizontal distance [m], direction [deg] from +x toward +z) from the ball to the cup."""
        d = (self.cup - self.ball)[[0, 2]]
        return float(np.hypot(*d)), math.degrees(math.atan2(d[1], d[0]))

    def scene_with_wind(self, wind: np.ndarray) -> Scene:
        """The course's scene with a stroke's ``wind`` [m/s] (3,) in place of its own."""
        return dataclasses.replace(
            self.scene, air=dataclasses.replace(self.scene.air, wind=(float(wind[0]), float(wind[1]), float(wind[2])))
        )

    def play(self, shot: Shot) -> Stroke:
        """Hit the ball: simulate the stroke, move the ball, end the round when it is holed, out of
        bounds, or the last stroke allowed was played."""
        if self.over:
            raise RuntimeError(f"the round is over ({self.outcome})")
        scene = self.scene_with_wind(self.wind)
        sim = Simulation(
            scene, x=self.ball[None], v=shot.velocity()[None], w=shot.angular_velocity()[None], track=False
        )
        every = max(1, round(0.005 / sim.dt))  # samples 5 ms apart: a 1.6 m/s putt moves 8 mm
        rec = sim.run(t=scene.game.shot_time, until="rest", record_every=every)
        t = np.asarray(rec.t)
        path = np.asarray(rec.x)[:, 0, :]
        out = int(sim.status[0]) == OUT_OF_BOUNDS
        gap = self.terrain.gap(path, self.radius)
        t_in = None if out else holed_at(t, path, gap, self.hole.position, self.hole.radius, self.radius, self.g)
        carry = _carry(path, gap < LOW_GAP * self.radius)
        if t_in is not None:
            keep = t < t_in
            t, path = np.append(t[keep], t_in), np.vstack([path[keep], self.cup])
            outcome, end = HOLED, self.cup.copy()
        elif out:
            outcome, end = OUT, path[-1].copy()
        else:
            outcome = RESTS if int(sim.status[0]) == AT_REST else MOVING
            end = self._on_ground(path[-1][[0, 2]])
        stroke = Stroke(
            len(self.strokes) + 1,
            shot,
            self.wind.copy(),
            self.ball.copy(),
            end,
            t - t[0],
            path,
            outcome,
            float(np.hypot(*(self.cup - end)[[0, 2]])),
            carry,
        )
        self.strokes.append(stroke)
        self.ball = end
        if outcome in (HOLED, OUT):
            self.outcome = outcome
        elif len(self.strokes) >= self.scene.game.max_strokes:
            self.outcome = "no strokes left"
        self.wind = self._draw_wind()
        return stroke


def describe_wind(wind: np.ndarray) -> str:
    """``wind 3.2 m/s toward 58 deg`` (level speed, direction from +x toward +z), or ``no wind``."""
    speed = math.hypot(wind[0], wind[2])
    if speed <= 0.05:
        return "no wind"
    return f"wind {speed:.1f} m/s toward {math.degrees(math.atan2(wind[2], wind[0])):.0f} deg"


def describe_stroke(s: Stroke) -> str:
    """What a stroke did, one line (indented for the console)."""
    flew = f"carried {s.carry:.1f} m (apex {s.apex:.1f} m), " if s.carry >= 1.0 else ""  # (not a putt's hop)
    if s.outcome == HOLED:
        return f"  {flew}went {s.distance:.1f} m and dropped into the cup!"
    if s.outcome == OUT:
        return f"  {flew}went out of bounds at x = {s.end[0]:.1f} m, z = {s.end[2]:.1f} m."
    moving = " (still moving when the stroke's time ran out)" if s.outcome == MOVING else ""
    return f"  {flew}went {s.distance:.1f} m; the ball is {s.to_hole:.2f} m from the hole{moving}."


def describe_round(game: GolfGame, ended: str) -> str:
    """The round's last line; ``ended`` says why an unfinished round stopped."""
    n = len(game.strokes)
    strokes = f"{n} stroke{'s' if n != 1 else ''}"
    if game.outcome == HOLED:
        return f"Holed in {strokes}."
    if game.outcome == OUT:
        return f"Out of bounds after {strokes}."
    if game.outcome is not None:
        return f"No strokes left: {strokes} played, the ball lies {game.to_hole()[0]:.2f} m from the hole."
    return f"The round ends unfinished ({ended}) after {strokes}, {game.to_hole()[0]:.2f} m from the hole."


def _carry(path: np.ndarray, low: np.ndarray) -> float:
    """Horizontal distance [m] from the first point of ``path`` (S, 3) to where the ball first came
    down after being in the air (``low`` (S,): down on the ground); 0 when it never left it, NaN
    when it never came down (out of bounds in the air, or still flying when the stroke ended)."""
    up = np.flatnonzero(~low)
    if up.size == 0:
        return 0.0
    down = np.flatnonzero(low[up[0] :])
    if down.size == 0:
        return math.nan
    return float(np.hypot(*(path[up[0] + down[0]] - path[0])[[0, 2]]))


def _point(p: np.ndarray) -> str:
    """A point (x, z) [m] as the error messages write it: ``[130, 4]``."""
    return "[" + ", ".join(f"{float(c):g}" for c in p) + "]"
