"""Scene configuration: frozen dataclasses and the schema every scene key is checked against.

Plain Python, no Taichi import, so scenes can be parsed and validated before ``ti.init``.
The schema (:data:`SCHEMA`) is the single source of truth for key names, units, defaults and
allowed ranges: the loader validates against it and ``ti-golf keys`` prints it as documentation.

Conventions: SI units, x downrange, y up, z lateral. Symbols follow the lab report
(``C_D``, ``C_M``, ``omega_M``, ``C_omega``, ``k_p``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Callable, Sequence

Vec3 = tuple[float, float, float]

#: Ball status codes stored per ball (``State.status``).
FLYING, ROLLING, AT_REST, OUT_OF_BOUNDS = 0, 1, 2, 3
STATUS_NAMES = {FLYING: "flying", ROLLING: "rolling", AT_REST: "at_rest", OUT_OF_BOUNDS: "out_of_bounds"}

INTEGRATORS = ("semi_implicit", "rk4")
AIR_MODELS = ("lab", "spin_ratio")
"""Aerodynamic models (``air.model``): the report's laws, or coefficients of the spin ratio."""


# ----------------------------------------------------------------------------------------------
# Schema
# ----------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Key:
    """One scene key: its type, default, unit, allowed range and meaning.

    ``kind`` is one of ``"float"``, ``"int"``, ``"bool"``, ``"str"``, ``"vec3"``, ``"vec2"`` (2 numbers),
    ``"list2"`` ([min, max]), ``"range"`` (a START:STOP:STEP string or a list of numbers) or ``"text"``
    (free text).
    ``check`` returns ``None`` when a (type-correct) value is allowed, else a phrase such as
    ``"must be > 0"``.
    """

    name: str
    kind: str
    default: Any
    unit: str
    doc: str
    check: Callable[[Any], str | None] | None = None
    allowed: str = ""


def _positive(v: float) -> str | None:
    return None if v > 0 else "must be > 0"


def _non_negative(v: float) -> str | None:
    return None if v >= 0 else "must be >= 0"


def _unit_interval(v: float) -> str | None:
    return None if 0.0 <= v <= 1.0 else "must be in [0, 1]"


def _one_of(*choices: Any) -> Callable[[Any], str | None]:
    def check(v: Any) -> str | None:
        return None if v in choices else "must be one of " + ", ".join(repr(c) for c in choices)

    return check


def _angle(limit: float) -> Callable[[float], str | None]:
    def check(v: float) -> str | None:
        return None if -limit <= v <= limit else f"must be in [-{limit:g}, {limit:g}] degrees"

    return check


SCHEMA: dict[str, dict[str, Key]] = {
    "air": {
        k.name: k
        for k in [
            Key("rho", "float", 1.3, "kg/m^3", "air density ρ", _non_negative, ">= 0"),
            Key("gamma", "int", 2, "-", "flow type γ: 1 laminar (drag ∝ v), 2 turbulent (drag ∝ v²)",
                _one_of(1, 2), "1 or 2"),
            Key("C_D", "float", 0.3, "-", "drag coefficient; k_D = ½ρA·C_D (L.22)", _non_negative, ">= 0"),
            Key("C_M", "float", 0.0, "-", "Magnus coefficient; k_M = ½ρA·C_M/ω_M (L.2, L.21)",
                _non_negative, ">= 0"),
            Key("omega_M", "float", 1.0, "1/s", "reference angular velocity ω_M of the Magnus law (L.2)",
                _positive, "> 0"),
            Key("C_omega", "float", 0.0, "-", "spin-decay coefficient; k_ω = ½ρA·C_ω/m (L.17, L.23)",
                _non_negative, ">= 0"),
            Key("wind", "vec3", (0.0, 0.0, 0.0), "m/s", "constant wind; forces use v_rel = v − wind (L.21–L.23)"),
            Key("model", "str", "lab", "-",
                "drag and lift: lab = the report's constant C_D and Magnus law (L.21, L.22); spin_ratio = "
                "C_D(S) and C_L(S) of the spin ratio S = R|ω|/|v_rel| fitted to launch-monitor shots "
                "(Ferguson, McNally & McPhee 2022; C_D, C_M and omega_M unused; needs gamma = 2)",
                _one_of(*AIR_MODELS), " | ".join(AIR_MODELS)),
        ]
    },
    "ball": {
        k.name: k
        for k in [
            Key("mass", "float", 0.045, "kg", "ball mass m", _positive, "> 0"),
            Key("radius", "float", 0.02, "m", "ball radius R (cross-section A = πR²)", _positive, "> 0"),
        ]
    },
    "launch": {
        k.name: k
        for k in [
            Key("speed", "float", 80.0, "m/s", "launch speed |v0|", _non_negative, ">= 0"),
            Key("angle_deg", "float", 45.0, "deg", "elevation above the horizontal", _angle(90), "[-90, 90]"),
            Key("direction_deg", "float", 0.0, "deg", "azimuth, from +x toward +z", _angle(360), "[-360, 360]"),
            Key("spin", "vec3", (0.0, 0.0, 0.0), "rad/s", "initial angular velocity ω0 (+z is backspin for a shot toward +x)"),
            Key("position", "vec3", None, "m",
                "launch point of the ball's centre (default: resting on the ground, [0, ground_height + radius, 0], "
                "or on the terrain at x = z = 0)"),
        ]
    },
    "world": {
        k.name: k
        for k in [
            Key("dt", "float", 0.001, "s", "time step h", _positive, "> 0"),
            Key("gravity", "vec3", (0.0, -9.81, 0.0), "m/s^2", "gravitational acceleration g"),
            Key("integrator", "str", "semi_implicit", "-",
                "semi_implicit (the report's leapfrog-style Euler) or rk4 (4th order, for flights)",
                _one_of(*INTEGRATORS), " | ".join(INTEGRATORS)),
            Key("t_end", "float", 20.0, "s", "default duration of `ti-golf run`", _positive, "> 0"),
            Key("t_max", "float", 60.0, "s", "longest flight a sweep integrates before giving up on a ball",
                _positive, "> 0"),
            Key("ground", "bool", True, "-",
                "an impenetrable ground plane y = ground_height "
                "(off by default when the scene has [[planes]] or a [terrain])"),
            Key("collisions", "bool", True, "-", "ball–ball collisions (hash grid + impulses) when there are several balls"),
            Key("ground_height", "float", 0.0, "m", "height of the ground plane"),
            Key("v_rest", "float", 0.01, "m/s", "a touching ball slower than this (and R|ω| below it) may come to rest",
                _non_negative, ">= 0"),
            Key("t_rest", "float", 0.2, "s",
                "how long a ball and the balls it touches must stay below v_rest before they are put at rest",
                _non_negative, ">= 0"),
        ]
    },
    "contact": {
        k.name: k
        for k in [
            Key("e", "float", 0.5, "-", "coefficient of restitution e (B.9)", _unit_interval, "[0, 1]"),
            Key("mu", "float", 0.4, "-", "Coulomb friction coefficient μ (B.15)", _non_negative, ">= 0"),
            Key("k_p", "float", 0.2, "-", "position-projection factor k_p (B.18; stable below 0.5)",
                _unit_interval, "[0, 1]"),
            Key("mu_roll", "float", 0.05, "-", "rolling-resistance coefficient: a rolling ball decelerates at μ_roll·g",
                _non_negative, ">= 0"),
            Key("iterations", "int", 4, "-",
                "Jacobi sweeps over all touching pairs per step (more: stiffer stacks)",
                lambda v: None if 1 <= v <= 100 else "must be in [1, 100]", "[1, 100]"),
            Key("relax", "float", 0.5, "-",
                "Jacobi relaxation of resting ball–ball impulses (1: full; lower is steadier in dense piles)",
                lambda v: None if 0 < v <= 1 else "must be in (0, 1]", "(0, 1]"),
            Key("skin", "float", 0.1, "-",
                "neighbour-list skin as a fraction of the largest radius, bar a few much bigger balls "
                "(lists are rebuilt when a ball moves skin/2)",
                lambda v: None if 0 < v <= 2 else "must be in (0, 2]", "(0, 2]"),
            Key("turf", "bool", False, "-",
                "ground impacts (planes, terrain) as on turf (Penner 2002, golf_data.md): restitution "
                "e(v_n) = 0.510 − 0.0375 v_n + 0.000903 v_n² (0.120 above 20 m/s) instead of e, in a frame "
                "tilted toward the incoming ball by θ_c = 15.4°·(v/18.6 m/s)·(φ/44.4°), φ the impact angle"),
            Key("v_bounce", "float", 0.05, "m/s",
                "normal approach speeds below v_bounce + 2|g|h are treated as inelastic (no micro-bounces) "
                "and as resting contacts, whose impulse carries over to the next step",
                _non_negative, ">= 0"),
        ]
    },
    "sweep": {
        k.name: k
        for k in [
            Key("angles", "range", None, "deg", "default elevation angles of `ti-golf sweep` (START:STOP:STEP or list)"),
            Key("speeds", "range", None, "m/s", "default launch speeds of `ti-golf sweep`"),
            Key("spins", "range", None, "rad/s", "default spin magnitudes of `ti-golf sweep` (along the scene's spin axis)"),
        ]
    },
    "terrain": {
        k.name: k
        for k in [
            Key("kind", "str", "generated", "-",
                "generated: seeded fractal noise on a resolution[0]×resolution[1] grid; file: heights from a .npy "
                "array (first axis along x)", _one_of("generated", "file"), "generated | file"),
            Key("file", "str", "", "-",
                "the .npy file of heights [m], shape (nx, nz), nx, nz >= 2 (relative paths: from the scene file's "
                "folder; from the current folder for --set)"),
            Key("origin", "vec3", (0.0, 0.0, 0.0), "m",
                "the grid's first corner [x, y, z]; heights are added to its y"),
            Key("size", "vec2", (100.0, 100.0), "m", "extent [size_x, size_z] of the grid (the heights span it)",
                lambda v: None if v[0] > 0 and v[1] > 0 else "must be > 0 on both axes", "[> 0, > 0]"),
            Key("resolution", "vec2", (129.0, 129.0), "-", "grid points [nx, nz] of generated terrain",
                lambda v: None if all(c >= 2 and float(c).is_integer() for c in v) and v[0] * v[1] <= 50_000_000
                else "must be 2 whole numbers >= 2 (at most 50 million points)", "2 whole numbers >= 2"),
            Key("seed", "int", 0, "-", "random seed of generated terrain (the same seed gives the same heights everywhere)"),
            Key("amplitude", "float", 1.0, "m", "generated heights lie within ±amplitude", _non_negative, ">= 0"),
            Key("roughness", "float", 0.5, "-",
                "amplitude ratio of successive noise octaves (each half the wavelength): small is smooth, near 1 rugged",
                lambda v: None if 0 < v < 1 else "must be in (0, 1)", "(0, 1)"),
            Key("profile", "bool", False, "-",
                "generated heights vary along x only (a 2-D profile, constant along z; resolution [nx, 2] suffices)"),
            Key("slope", "vec2", (0.0, 0.0), "-",
                "tilt [dh/dx, dh/dz] added to the heights of either kind (an incline: amplitude 0 and a slope)"),
            Key("kill_height", "float", None, "m",
                "balls below this height are out of bounds, as are balls whose x or z leaves the grid "
                "(default: origin y − 10 m)"),
            Key("surface_levels", "range", None, "m",
                "per-cell surface types by height: a cell whose mean height (above origin y) is below "
                "levels[k] (and not below levels[k−1]) uses [[surfaces]] k, the highest cells the last; "
                "needs one level fewer than there are surfaces"),
        ]
    },
    "hole": {
        k.name: k
        for k in [
            Key("position", "vec2", None, "m",
                "the cup's centre [x, z] (required); it sits on the terrain, else on the ground or the first "
                "upward-facing plane"),
            Key("radius", "float", 0.054, "m", "cup radius (regulation: 108 mm across)", _positive, "> 0"),
            Key("flag_height", "float", 2.13, "m", "flagstick height above the cup (2.13 m = 7 ft is usual; 0: none)",
                _non_negative, ">= 0"),
        ]
    },
    "game": {
        k.name: k
        for k in [
            Key("start", "vec2", None, "m",
                "where the ball lies for the first stroke of `ti-golf play`, [x, z] on the terrain (default: a "
                "random point of the course, from --seed)"),
            Key("wind_max", "float", 0.0, "m/s",
                "each stroke's wind blows level from a random direction at a random speed up to this (0: the "
                "scene's air.wind throughout)", _non_negative, ">= 0"),
            Key("max_strokes", "int", 20, "-", "the round ends unfinished after this many strokes",
                lambda v: None if 1 <= v <= 1000 else "must be in [1, 1000]", "[1, 1000]"),
            Key("shot_time", "float", 60.0, "s",
                "longest a stroke is simulated; a ball still moving then is played from where it is",
                _positive, "> 0"),
        ]
    },
}

#: Top-level keys that are not tables.
TOP_LEVEL: dict[str, Key] = {
    "description": Key("description", "text", "", "-", "one line shown by `ti-golf scenes`"),
}


def _nonzero(v: tuple[float, ...]) -> str | None:
    return None if any(c != 0 for c in v) else "must not be the zero vector"


def _pair(lo: float, hi: float = math.inf) -> Callable[[Any], str | None]:
    def check(v: tuple[float, ...]) -> str | None:
        if len(v) != 2 or v[0] > v[1]:
            return "must be [min, max] with min <= max"
        return None if lo <= v[0] and v[1] <= hi else f"must lie in [{lo:g}, {hi:g}]"

    return check


def _count3(v: tuple[float, ...]) -> str | None:
    return None if all(c >= 1 and float(c).is_integer() for c in v) and math.prod(v) <= 50_000_000 else \
        "must be 3 whole numbers >= 1 (at most 50 million balls)"


#: Arrays of tables: ``[[balls]]``, ``[[blocks]]``, ``[[planes]]``.
ARRAY_SCHEMA: dict[str, dict[str, Key]] = {
    "balls": {
        k.name: k
        for k in [
            Key("position", "vec3", None, "m", "centre of the ball (required)"),
            Key("velocity", "vec3", (0.0, 0.0, 0.0), "m/s", "initial velocity"),
            Key("spin", "vec3", (0.0, 0.0, 0.0), "rad/s", "initial angular velocity"),
            Key("radius", "float", None, "m", "radius (default ball.radius)", _positive, "> 0"),
            Key("mass", "float", None, "kg", "mass (default ball.mass)", _positive, "> 0"),
        ]
    },
    "blocks": {
        k.name: k
        for k in [
            Key("kind", "str", "lattice", "-",
                "lattice: count[0]×count[1]×count[2] balls from origin, spacing apart; "
                "random: `number` balls at seeded random non-overlapping places inside [box_min, box_max]",
                _one_of("lattice", "random"), "lattice | random"),
            Key("count", "vec3", (1.0, 1.0, 1.0), "-", "lattice size along x, y, z", _count3, "3 whole numbers >= 1"),
            Key("number", "int", 0, "-", "number of balls of a random block", lambda v: None if 0 <= v <= 50_000_000
                else "must be in [0, 50000000]", "[0, 50000000]"),
            Key("origin", "vec3", (0.0, 0.0, 0.0), "m", "centre of the lattice's first ball"),
            Key("spacing", "float", None, "m", "lattice spacing (default: one diameter plus 1 %)", _positive, "> 0"),
            Key("jitter", "float", 0.0, "m", "uniform random offset of each lattice ball (at most half the free gap)",
                _non_negative, ">= 0"),
            Key("box_min", "vec3", (0.0, 0.0, 0.0), "m", "lower corner of a random block's box"),
            Key("box_max", "vec3", (1.0, 1.0, 1.0), "m", "upper corner of a random block's box"),
            Key("velocity", "vec3", (0.0, 0.0, 0.0), "m/s", "initial velocity of every ball"),
            Key("velocity_jitter", "float", 0.0, "m/s", "uniform random velocity added per component",
                _non_negative, ">= 0"),
            Key("speed", "list2", None, "m/s", "launch speeds [min, max]: the block's balls are shots", _pair(0.0), "[min, max] >= 0"),
            Key("angle_deg", "list2", None, "deg", "launch elevations [min, max] of shots", _pair(-90.0, 90.0), "[min, max] in [-90, 90]"),
            Key("direction_deg", "list2", (0.0, 0.0), "deg", "launch azimuths [min, max] of shots", _pair(-360.0, 360.0),
                "[min, max] in [-360, 360]"),
            Key("backspin", "list2", (0.0, 0.0), "rad/s", "backspin [min, max] of shots", _pair(-1e5, 1e5), "[min, max]"),
            Key("spin", "vec3", (0.0, 0.0, 0.0), "rad/s", "initial angular velocity of every ball"),
            Key("radius", "float", None, "m", "radius (default ball.radius)", _positive, "> 0"),
            Key("radius_jitter", "float", 0.0, "-", "relative spread of radii: R·(1 ± jitter)",
                lambda v: None if 0 <= v < 0.5 else "must be in [0, 0.5)", "[0, 0.5)"),
            Key("mass", "float", None, "kg", "mass (default ball.mass; scaled with R³ when radii vary)", _positive, "> 0"),
            Key("seed", "int", 0, "-", "random seed (the same seed gives the same balls everywhere)"),
        ]
    },
    "surfaces": {
        k.name: k
        for k in [
            Key("name", "str", "", "-", "what the surface is (fairway, rough, green, bunker, water …)"),
            Key("e", "float", None, "-", "restitution on this surface (default contact.e)", _unit_interval, "[0, 1]"),
            Key("mu", "float", None, "-", "Coulomb friction on this surface (default contact.mu)", _non_negative, ">= 0"),
            Key("mu_roll", "float", None, "-", "rolling resistance on this surface (default contact.mu_roll)",
                _non_negative, ">= 0"),
            Key("turf", "bool", None, "-", "impacts on this surface as on turf (default contact.turf)"),
        ]
    },
    "planes": {
        k.name: k
        for k in [
            Key("point", "vec3", (0.0, 0.0, 0.0), "m", "a point on the plane"),
            Key("normal", "vec3", (0.0, 1.0, 0.0), "-", "normal pointing out of the solid side (normalised on load)",
                _nonzero, "non-zero vec3"),
        ]
    },
}


# ----------------------------------------------------------------------------------------------
# Dataclasses (static parameters; per-step state lives in ti_golf.sim.state)
# ----------------------------------------------------------------------------------------------
def _default(section: str, name: str) -> Any:
    """Dataclass defaults come from :data:`SCHEMA`, so the two can never disagree."""
    return SCHEMA[section][name].default


@dataclass(frozen=True)
class Air:
    """Air properties (report L.1–L.23)."""

    rho: float = _default("air", "rho")
    gamma: int = _default("air", "gamma")
    C_D: float = _default("air", "C_D")
    C_M: float = _default("air", "C_M")
    omega_M: float = _default("air", "omega_M")
    C_omega: float = _default("air", "C_omega")
    wind: Vec3 = _default("air", "wind")
    model: str = _default("air", "model")


@dataclass(frozen=True)
class Ball:
    """Properties of the default ball [kg, m]."""

    mass: float = _default("ball", "mass")
    radius: float = _default("ball", "radius")


@dataclass(frozen=True)
class Launch:
    """One launched ball: speed [m/s], elevation and azimuth [deg], spin [rad/s], position [m]."""

    speed: float = _default("launch", "speed")
    angle_deg: float = _default("launch", "angle_deg")
    direction_deg: float = _default("launch", "direction_deg")
    spin: Vec3 = _default("launch", "spin")
    position: Vec3 | None = _default("launch", "position")


@dataclass(frozen=True)
class World:
    """Time stepping, gravity and the ground plane."""

    dt: float = _default("world", "dt")
    gravity: Vec3 = _default("world", "gravity")
    integrator: str = _default("world", "integrator")
    t_end: float = _default("world", "t_end")
    t_max: float = _default("world", "t_max")
    ground: bool = _default("world", "ground")
    ground_height: float = _default("world", "ground_height")
    collisions: bool = _default("world", "collisions")
    v_rest: float = _default("world", "v_rest")
    t_rest: float = _default("world", "t_rest")


@dataclass(frozen=True)
class Contact:
    """Impulse-contact parameters (report Appendix B)."""

    e: float = _default("contact", "e")
    mu: float = _default("contact", "mu")
    k_p: float = _default("contact", "k_p")
    mu_roll: float = _default("contact", "mu_roll")
    iterations: int = _default("contact", "iterations")
    relax: float = _default("contact", "relax")
    skin: float = _default("contact", "skin")
    v_bounce: float = _default("contact", "v_bounce")
    turf: bool = _default("contact", "turf")


@dataclass(frozen=True)
class TerrainConfig:
    """The ``[terrain]`` table: a height field (built by :func:`ti_golf.scene.terrain.build_terrain`).

    ``file`` is the resolved path of the .npy heights (kind ``"file"``); ``resolution`` holds ints.
    """

    kind: str = _default("terrain", "kind")
    file: str = _default("terrain", "file")
    origin: Vec3 = _default("terrain", "origin")
    size: tuple[float, float] = _default("terrain", "size")
    resolution: tuple[int, int] = (129, 129)
    seed: int = _default("terrain", "seed")
    amplitude: float = _default("terrain", "amplitude")
    roughness: float = _default("terrain", "roughness")
    profile: bool = _default("terrain", "profile")
    slope: tuple[float, float] = _default("terrain", "slope")
    kill_height: float | None = _default("terrain", "kill_height")
    surface_levels: tuple[float, ...] | None = _default("terrain", "surface_levels")

    @property
    def kill(self) -> float:
        """Height [m] below which a ball is out of bounds (``kill_height``, default origin y − 10 m)."""
        return self.origin[1] - 10.0 if self.kill_height is None else self.kill_height


@dataclass(frozen=True)
class HoleConfig:
    """The ``[hole]`` table: a cup at ``position`` [x, z] [m] on the course, and its flagstick."""

    position: tuple[float, float]
    radius: float = _default("hole", "radius")
    flag_height: float = _default("hole", "flag_height")


@dataclass(frozen=True)
class GameConfig:
    """The ``[game]`` table of ``ti-golf play`` (see :mod:`ti_golf.game.rules`)."""

    start: tuple[float, float] | None = _default("game", "start")
    wind_max: float = _default("game", "wind_max")
    max_strokes: int = _default("game", "max_strokes")
    shot_time: float = _default("game", "shot_time")


@dataclass(frozen=True)
class Surface:
    """A terrain surface type (``[[surfaces]]``): its own restitution, friction, rolling resistance
    and turf impacts (``None``: the ``[contact]`` value)."""

    name: str = ""
    e: float | None = None
    mu: float | None = None
    mu_roll: float | None = None
    turf: bool | None = None


@dataclass(frozen=True)
class Plane:
    """An impenetrable plane: ``point`` [m] on it, unit ``normal`` out of the solid side."""

    point: Vec3 = (0.0, 0.0, 0.0)
    normal: Vec3 = (0.0, 1.0, 0.0)


@dataclass(frozen=True)
class BallSpec:
    """One ball listed in a ``[[balls]]`` table (radius and mass default to the scene's ball)."""

    position: Vec3
    velocity: Vec3 = (0.0, 0.0, 0.0)
    spin: Vec3 = (0.0, 0.0, 0.0)
    radius: float | None = None
    mass: float | None = None


@dataclass(frozen=True)
class Block:
    """Many balls at once (``[[blocks]]``): a lattice or a seeded random fill; optionally shots."""

    kind: str = "lattice"
    count: Vec3 = (1.0, 1.0, 1.0)
    number: int = 0
    origin: Vec3 = (0.0, 0.0, 0.0)
    spacing: float | None = None
    jitter: float = 0.0
    box_min: Vec3 = (0.0, 0.0, 0.0)
    box_max: Vec3 = (1.0, 1.0, 1.0)
    velocity: Vec3 = (0.0, 0.0, 0.0)
    velocity_jitter: float = 0.0
    speed: tuple[float, float] | None = None
    angle_deg: tuple[float, float] | None = None
    direction_deg: tuple[float, float] = (0.0, 0.0)
    backspin: tuple[float, float] = (0.0, 0.0)
    spin: Vec3 = (0.0, 0.0, 0.0)
    radius: float | None = None
    radius_jitter: float = 0.0
    mass: float | None = None
    seed: int = 0


@dataclass(frozen=True)
class SweepDefaults:
    """Default launch-condition lists for ``ti-golf sweep`` (``None``: use the launch table)."""

    angles: tuple[float, ...] | None = None
    speeds: tuple[float, ...] | None = None
    spins: tuple[float, ...] | None = None


@dataclass(frozen=True)
class Scene:
    """A validated scene: everything static a simulation needs.

    ``launch`` is ``None`` when the scene has no ``[launch]`` table (no launched ball), ``terrain``
    when it has no ``[terrain]`` table, ``hole`` when it has no ``[hole]`` table.
    """

    name: str = "scene"
    description: str = ""
    path: str = ""
    air: Air = field(default_factory=Air)
    ball: Ball = field(default_factory=Ball)
    launch: Launch | None = field(default_factory=Launch)
    world: World = field(default_factory=World)
    contact: Contact = field(default_factory=Contact)
    sweep: SweepDefaults = field(default_factory=SweepDefaults)
    balls: tuple[BallSpec, ...] = ()
    blocks: tuple[Block, ...] = ()
    planes: tuple[Plane, ...] = ()
    terrain: TerrainConfig | None = None
    surfaces: tuple[Surface, ...] = ()
    hole: HoleConfig | None = None
    game: GameConfig = field(default_factory=GameConfig)

    def launch_position(self) -> Vec3:
        """Launch point [m]: the scene's, or the ball resting on the ground (the terrain, if any) at x = z = 0."""
        if self.launch is not None and self.launch.position is not None:
            return self.launch.position
        if self.terrain is not None:
            from ti_golf.scene.terrain import build_terrain

            return (0.0, float(build_terrain(self.terrain, self.path).height(0.0, 0.0)) + self.ball.radius, 0.0)
        return (0.0, self.world.ground_height + self.ball.radius, 0.0)


def launch_velocity(speed: float, angle_deg: float, direction_deg: float) -> Vec3:
    """Velocity [m/s] for a launch at ``angle_deg`` elevation and ``direction_deg`` azimuth (+x toward +z)."""
    th, ph = math.radians(angle_deg), math.radians(direction_deg)
    return (speed * math.cos(th) * math.cos(ph), speed * math.sin(th), speed * math.cos(th) * math.sin(ph))


def backspin_axis(direction_deg: float) -> Vec3:
    """Unit backspin axis d × ŷ for a shot along azimuth ``direction_deg`` (+z for a shot toward +x)."""
    ph = math.radians(direction_deg)
    return (-math.sin(ph), 0.0, math.cos(ph))


def parse_range(text: str | Sequence[float], source: str, key: str) -> tuple[float, ...]:
    """Parse ``START:STOP:STEP`` (STOP included) or ``a,b,c`` (or a list) into a tuple of floats."""
    if isinstance(text, (list, tuple)):
        values = []
        for v in text:
            if isinstance(v, bool) or not isinstance(v, (int, float)):
                raise_config(source, key, f"must be a list of numbers (got {v!r})")
            values.append(float(v))
        out = tuple(values)
    else:
        s = str(text).strip()
        try:
            if ":" in s:
                parts = [float(p) for p in s.split(":")]
                if len(parts) != 3:
                    raise ValueError
                start, stop, step = parts
                if not step > 0:
                    raise_config(source, key, f"STEP must be > 0 in START:STOP:STEP (got {s!r})")
                if stop < start:
                    raise_config(source, key, f"STOP must be >= START in START:STOP:STEP (got {s!r})")
                n = int(math.floor((stop - start) / step + 1e-9)) + 1
                if n > 10_000_000:
                    raise_config(source, key, f"gives {n} values; at most 10,000,000 are allowed")
                out = tuple(round(start + i * step, 12) for i in range(n))
            else:
                out = tuple(float(p) for p in s.split(",") if p.strip() != "")
        except ValueError:
            raise_config(source, key, f"must be START:STOP:STEP (STOP included) or a comma list of numbers (got {s!r})")
    if not out:
        raise_config(source, key, "must list at least one value")
    if not all(math.isfinite(v) for v in out):
        raise_config(source, key, "values must be finite numbers")
    return out


def raise_config(source: str, key: str | None, reason: str) -> None:
    """Raise a :class:`~ti_golf.errors.ConfigError` (helper that keeps call sites one line)."""
    from ti_golf.errors import ConfigError

    raise ConfigError(source, key, reason)
