"""Scene configuration: one frozen dataclass per scene table, each key declared once.

Every scene key is a dataclass field declared with :func:`~ti_golf.scene.keys.key`: its kind,
default, unit, help and allowed values (a check from :mod:`ti_golf.scene.checks`) live in that one
declaration. :data:`SCHEMA`, :data:`ARRAY_SCHEMA` and :data:`TOP_LEVEL` collect them; from those
come the loader's checks and errors (:mod:`ti_golf.scene.loader`), ``ti-golf keys`` and the docs'
key reference (:mod:`ti_golf.scene.reference`) and ``ti-golf schema`` (:mod:`ti_golf.scene.jsonschema`).
Plain Python, no Taichi import, so scenes can be parsed and validated before ``ti.init``.

Conventions: SI units, x downrange, y up, z lateral. Symbols follow the lab report
(``C_D``, ``C_M``, ``omega_M``, ``C_omega``, ``k_p``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from ti_golf.errors import OVERRIDES
from ti_golf.scene.air import (  # re-exported: the [air] table lives in its own module
    AIR_MODELS as AIR_MODELS,
)
from ti_golf.scene.air import (
    SPIN_REYNOLDS_C_D as SPIN_REYNOLDS_C_D,
)
from ti_golf.scene.air import (
    SPIN_REYNOLDS_C_L as SPIN_REYNOLDS_C_L,
)
from ti_golf.scene.air import (
    SPIN_REYNOLDS_CRISIS as SPIN_REYNOLDS_CRISIS,
)
from ti_golf.scene.air import (
    WIND_PROFILES as WIND_PROFILES,
)
from ti_golf.scene.air import (
    Air as Air,
)
from ti_golf.scene.checks import (
    DURATION,
    ELEVATIONS,
    GRAVITY,
    MASS,
    NON_NEGATIVE,
    POSITION,
    POSITIVE,
    RADIUS,
    REACH,
    SPEED_LIMIT,
    SPEEDS,
    SPIN,
    SPINS,
    UNIT_INTERVAL,
    VELOCITY,
    Each,
    Interval,
    MinMax,
    NonZero,
    OneOf,
    WholeCounts,
    angle,
)
from ti_golf.scene.checks import parse_range as parse_range  # re-exported: the CLI parses --angles with it
from ti_golf.scene.course import GameConfig as GameConfig  # re-exported: the course's tables live apart
from ti_golf.scene.course import HoleConfig as HoleConfig
from ti_golf.scene.keys import REQUIRED, Key, key, keys_of

Vec3 = tuple[float, float, float]


#: Ball status codes stored per ball (``State.status``).
FLYING, ROLLING, AT_REST, OUT_OF_BOUNDS = 0, 1, 2, 3
STATUS_NAMES = {FLYING: "flying", ROLLING: "rolling", AT_REST: "at_rest", OUT_OF_BOUNDS: "out_of_bounds"}

INTEGRATORS = ("semi_implicit", "rk4")
SOLVERS = ("jacobi", "gauss_seidel")
"""Contact solvers (``contact.solver``): the report's Jacobi sweeps, or coloured Gauss–Seidel sweeps."""
LAYOUTS = ("auto", "columns", "contacts")
"""Layouts of the Gauss–Seidel sweeps (``contact.layout``): by blocks of grid columns, or by contact
colours, or chosen by the backend (see :mod:`ti_golf.solvers.contact_colour`)."""
FRICTION_MODELS = ("spin", "report")
"""Friction of the ball–surface contacts (``contact.friction_model``): at the contact point, coupled
to the spin, or the report's, from the centre's velocity alone (see :mod:`ti_golf.physics.contact`)."""

HEIGHT_LIMIT = 10_000.0
"""The largest height [m] of a terrain, above or below 0 (generated amplitudes and the heights of a
file): 10 km, past any golf course, so that the slopes and normals stay finite numbers."""

TERRAIN_POINTS_MAX = 50_000_000
"""The most grid points a terrain may have, generated or read from a file (400 MB of heights in
f64)."""

SLOPE_LIMIT = 100.0
"""The steepest tilt (dh/dx, dh/dz) of ``terrain.slope``: 89.4°."""


# -- the scene's tables -------------------------------------------------------------------------
@dataclass(frozen=True)
class Ball:
    """Properties of the default ball [kg, m]."""

    mass: float = key("float", 0.045, "kg", "ball mass m", MASS)
    radius: float = key("float", 0.02, "m", "ball radius R (cross-section A = πR²)", RADIUS)


@dataclass(frozen=True)
class Launch:
    """One launched ball: speed [m/s], elevation and azimuth [deg], spin [rad/s], position [m]."""

    speed: float = key("float", 80.0, "m/s", "launch speed |v0|", Interval(0.0, SPEED_LIMIT))
    angle_deg: float = key("float", 45.0, "deg", "elevation above the horizontal", angle(90))
    direction_deg: float = key("float", 0.0, "deg", "azimuth, from +x toward +z", angle(360))
    spin: Vec3 = key(
        "vec3", (0.0, 0.0, 0.0), "rad/s", "initial angular velocity ω0 (+z is backspin for a shot toward +x)", SPIN
    )
    position: Vec3 | None = key(
        "vec3",
        None,
        "m",
        "launch point of the ball's centre (default: resting on the ground, [0, ground_height + radius, 0], "
        "or on the terrain at x = z = 0)",
        POSITION,
    )


@dataclass(frozen=True)
class World:
    """Time stepping, gravity and the ground plane."""

    dt: float = key(
        "float",
        0.001,
        "s",
        "time step h; where balls collide, at most √(R/2g) for the smallest radius R (0.032 s for golf balls)",
        Interval(0.0, 1.0, lo_open=True),
    )
    gravity: Vec3 = key("vec3", (0.0, -9.81, 0.0), "m/s^2", "gravitational acceleration g", GRAVITY)
    integrator: str = key(
        "str",
        "semi_implicit",
        "-",
        "semi_implicit (the report's leapfrog-style Euler) or rk4 (4th order, for flights)",
        OneOf(INTEGRATORS),
    )
    t_end: float = key("float", 20.0, "s", "default duration of `ti-golf run`", DURATION)
    t_max: float = key("float", 60.0, "s", "longest flight a sweep integrates before giving up on a ball", DURATION)
    ground: bool = key(
        "bool",
        True,
        "-",
        "an impenetrable ground plane y = ground_height (off by default when the scene has [[planes]] or a [terrain])",
    )
    collisions: bool = key(
        "bool", True, "-", "ball–ball collisions (hash grid + impulses) when there are several balls"
    )
    ground_height: float = key(
        "float",
        0.0,
        "m",
        "height of the ground plane, of a [launch] ball resting on the ground and of the log wind "
        "profile's zero (read only when one of the three is in the scene)",
        Interval(-REACH, REACH),
    )
    v_rest: float = key(
        "float",
        0.01,
        "m/s",
        "a touching ball slower than this (and R|ω| below it, unless contact.friction_model = report) may come to rest",
        NON_NEGATIVE,
    )
    t_rest: float = key(
        "float",
        0.2,
        "s",
        "how long a ball and the balls it touches must stay below v_rest before they are put at rest",
        NON_NEGATIVE,
    )


@dataclass(frozen=True)
class Contact:
    """Impulse-contact parameters (report Appendix B)."""

    e: float = key("float", 0.5, "-", "coefficient of restitution e (B.9)", UNIT_INTERVAL)
    mu: float = key("float", 0.4, "-", "Coulomb friction coefficient μ (B.15)", NON_NEGATIVE)
    friction_model: str = key(
        "str",
        "spin",
        "-",
        "friction of the ball on the planes and the terrain: spin (at the contact point, which it "
        "spins up: a ball rolls) or report (the report's B.15 from the centre's tangential velocity "
        "alone, clipped to stop it; spin untouched: a ball stops on a slope with tan θ ≤ μ)",
        OneOf(FRICTION_MODELS),
    )
    k_p: float = key("float", 0.2, "-", "position-projection factor k_p (B.18; stable below 0.5)", UNIT_INTERVAL)
    mu_roll: float = key(
        "float",
        0.05,
        "-",
        "rolling-resistance coefficient: a rolling ball decelerates at μ_roll·g; it also resists spin about a "
        "contact's normal (a ball pivoting on the ground, and with the gauss_seidel solver two touching balls)",
        NON_NEGATIVE,
    )
    solver: str = key(
        "str",
        "gauss_seidel",
        "-",
        "gauss_seidel (each pair at once after the last, columns of balls bottom-up: holds piles, heavy "
        "balls on light ones and bouncing balls) or jacobi (the report's B.5-B.18: every pair at once "
        "from the last sweep's velocities, as the lab scenes use)",
        OneOf(SOLVERS),
        read_when=("world.collisions", (True,)),
    )
    layout: str = key(
        "str",
        "auto",
        "-",
        "how the gauss_seidel sweeps are spread over threads: columns (blocks of grid columns, each "
        "walked bottom-up by one thread: fastest on a few CPU cores), contacts (the pairs coloured so "
        "that no two of a colour share a ball, a thread per pair: thousands of threads, for GPUs) or "
        "auto (columns on CPU backends, contacts elsewhere)",
        OneOf(LAYOUTS),
        read_when=("contact.solver", ("gauss_seidel",)),
    )
    iterations: int = key(
        "int",
        4,
        "-",
        "sweeps over all touching pairs per step (more: stiffer stacks)",
        Interval(1, 100),
        read_when=("world.collisions", (True,)),
    )
    relax: float = key(
        "float",
        0.5,
        "-",
        "Jacobi relaxation of resting ball–ball impulses (1: full; lower is steadier in dense piles)",
        Interval(0.0, 1.0, lo_open=True),
        read_when=("contact.solver", ("jacobi",)),
    )
    skin: float = key(
        "float",
        0.1,
        "-",
        "neighbour-list skin as a fraction of the largest radius, bar a few much bigger balls "
        "(lists are rebuilt when a ball moves skin/2; under gauss_seidel, when a pair they miss may "
        "touch, a ball moving up to the skin)",
        Interval(0.0, 2.0, lo_open=True),
        read_when=("world.collisions", (True,)),
    )
    turf: bool = key(
        "bool",
        False,
        "-",
        "ground impacts (planes, terrain) as on turf (Penner 2002, golf_data.md): restitution "
        "e(v_n) = 0.510 − 0.0375 v_n + 0.000903 v_n² (0.120 above 20 m/s) instead of e, in a frame "
        "tilted toward the incoming ball by θ_c = 15.4°·(v/18.6 m/s)·(φ/44.4°), φ the impact angle",
    )
    v_bounce: float = key(
        "float",
        0.05,
        "m/s",
        "normal approach speeds below v_bounce + 2|g|h (for a ball without collisions, plus twice what the air "
        "pushed it into the surface in the step) are treated as inelastic (no micro-bounces) and as resting "
        "contacts, whose impulse carries over to the next step",
        NON_NEGATIVE,
    )


@dataclass(frozen=True)
class TerrainConfig:
    """The ``[terrain]`` table: a height field (built by :func:`ti_golf.scene.terrain.build_terrain`).

    ``file`` is the resolved path of the .npy heights (kind ``"file"``); ``resolution`` holds ints.
    """

    kind: str = key(
        "str",
        "generated",
        "-",
        "generated: seeded fractal noise on a resolution[0]×resolution[1] grid; file: heights from a .npy "
        "array (first axis along x)",
        OneOf(("generated", "file")),
    )
    file: str = key(
        "str",
        "",
        "-",
        "the .npy file of heights [m], shape (nx, nz), nx, nz >= 2 (relative paths: from the scene file's "
        "folder; from the current folder for --set)",
        read_when=("kind", ("file",)),
    )
    origin: Vec3 = key(
        "vec3", (0.0, 0.0, 0.0), "m", "the grid's first corner [x, y, z]; heights are added to its y", POSITION
    )
    size: tuple[float, float] = key(
        "vec2",
        (100.0, 100.0),
        "m",
        "extent [size_x, size_z] of the grid (the heights span it)",
        Each(POSITIVE),
    )
    resolution: tuple[int, int] = key(
        "vec2",
        (129, 129),
        "-",
        "grid points [nx, nz] of generated terrain",
        WholeCounts(2, 2, TERRAIN_POINTS_MAX, "points"),
        read_when=("kind", ("generated",)),
    )
    seed: int = key(
        "int",
        0,
        "-",
        "random seed of generated terrain (the same seed gives the same heights everywhere)",
        NON_NEGATIVE,
        read_when=("kind", ("generated",)),
    )
    amplitude: float = key(
        "float",
        1.0,
        "m",
        "generated heights lie within ±amplitude",
        Interval(0.0, HEIGHT_LIMIT),
        read_when=("kind", ("generated",)),
    )
    roughness: float = key(
        "float",
        0.5,
        "-",
        "amplitude ratio of successive noise octaves (each half the wavelength): small is smooth, near 1 rugged",
        Interval(0.0, 1.0, lo_open=True, hi_open=True),
        read_when=("kind", ("generated",)),
    )
    profile: bool = key(
        "bool",
        False,
        "-",
        "generated heights vary along x only (a 2-D profile, constant along z; resolution [nx, 2] suffices)",
        read_when=("kind", ("generated",)),
    )
    slope: tuple[float, float] = key(
        "vec2",
        (0.0, 0.0),
        "-",
        "tilt [dh/dx, dh/dz] added to the heights of either kind (an incline: amplitude 0 and a slope)",
        Each(Interval(-SLOPE_LIMIT, SLOPE_LIMIT)),
    )
    kill_height: float | None = key(
        "float",
        None,
        "m",
        "balls below this height are out of bounds, as are balls whose x or z leaves the grid "
        "(default: origin y − 10 m)",
    )
    surface_levels: tuple[float, ...] | None = key(
        "range",
        None,
        "m",
        "per-cell surface types by height: a cell whose mean height (above origin y) is below "
        "levels[k] (and not below levels[k−1]) uses [[surfaces]] k, the highest cells the last; "
        "needs one level fewer than there are surfaces",
    )

    @property
    def kill(self) -> float:
        """Height [m] below which a ball is out of bounds (``kill_height``, default origin y − 10 m)."""
        return self.origin[1] - 10.0 if self.kill_height is None else self.kill_height


@dataclass(frozen=True)
class Surface:
    """A terrain surface type (``[[surfaces]]``): its own restitution, friction, rolling resistance
    and turf impacts (``None``: the ``[contact]`` value)."""

    name: str = key("str", "", "-", "what the surface is (fairway, rough, green, bunker, water …)")
    e: float | None = key("float", None, "-", "restitution on this surface (default contact.e)", UNIT_INTERVAL)
    mu: float | None = key("float", None, "-", "Coulomb friction on this surface (default contact.mu)", NON_NEGATIVE)
    mu_roll: float | None = key(
        "float", None, "-", "rolling resistance on this surface (default contact.mu_roll)", NON_NEGATIVE
    )
    turf: bool | None = key("bool", None, "-", "impacts on this surface as on turf (default contact.turf)")


@dataclass(frozen=True)
class Plane:
    """An impenetrable plane: ``point`` [m] on it, unit ``normal`` out of the solid side."""

    point: Vec3 = key("vec3", (0.0, 0.0, 0.0), "m", "a point on the plane", POSITION)
    normal: Vec3 = key(
        "vec3",
        (0.0, 1.0, 0.0),
        "-",
        "normal pointing out of the solid side (normalised on load)",
        NonZero(),
    )


@dataclass(frozen=True)
class BallSpec:
    """One ball listed in a ``[[balls]]`` table (radius and mass default to the scene's ball)."""

    position: Vec3 = key("vec3", REQUIRED, "m", "centre of the ball (required)", POSITION)
    velocity: Vec3 = key("vec3", (0.0, 0.0, 0.0), "m/s", "initial velocity", VELOCITY)
    spin: Vec3 = key("vec3", (0.0, 0.0, 0.0), "rad/s", "initial angular velocity", SPIN)
    radius: float | None = key("float", None, "m", "radius (default ball.radius)", RADIUS)
    mass: float | None = key("float", None, "kg", "mass (default ball.mass)", MASS)


@dataclass(frozen=True)
class Block:
    """Many balls at once (``[[blocks]]``): a lattice or a seeded random fill; optionally shots."""

    kind: str = key(
        "str",
        "lattice",
        "-",
        "lattice: count[0]×count[1]×count[2] balls from origin, spacing apart; "
        "random: `number` balls at seeded random non-overlapping places inside [box_min, box_max]",
        OneOf(("lattice", "random")),
    )
    count: Vec3 = key(
        "vec3",
        (1.0, 1.0, 1.0),
        "-",
        "lattice size along x, y, z",
        WholeCounts(3, 1, 50_000_000, "balls"),
        read_when=("kind", ("lattice",)),
    )
    number: int = key(
        "int",
        0,
        "-",
        "number of balls of a random block (required)",
        Interval(1, 50_000_000),
        read_when=("kind", ("random",)),
    )
    origin: Vec3 = key(
        "vec3", (0.0, 0.0, 0.0), "m", "centre of the lattice's first ball", read_when=("kind", ("lattice",))
    )
    spacing: float | None = key(
        "float",
        None,
        "m",
        "lattice spacing (default: one diameter plus 1 %)",
        POSITIVE,
        read_when=("kind", ("lattice",)),
    )
    jitter: float = key(
        "float",
        0.0,
        "m",
        "uniform random offset of each lattice ball (at most half the free gap)",
        NON_NEGATIVE,
        read_when=("kind", ("lattice",)),
    )
    box_min: Vec3 = key(
        "vec3",
        (0.0, 0.0, 0.0),
        "m",
        "lower corner of the box a random block's centres lie in",
        read_when=("kind", ("random",)),
    )
    box_max: Vec3 = key(
        "vec3",
        (1.0, 1.0, 1.0),
        "m",
        "upper corner of the box a random block's centres lie in",
        read_when=("kind", ("random",)),
    )
    velocity: Vec3 = key("vec3", (0.0, 0.0, 0.0), "m/s", "initial velocity of every ball", VELOCITY)
    velocity_jitter: float = key(
        "float", 0.0, "m/s", "uniform random velocity added per component", Interval(0.0, SPEED_LIMIT)
    )
    speed: tuple[float, float] | None = key(
        "list2", None, "m/s", "launch speeds [min, max]: the block's balls are shots", MinMax(0.0, SPEED_LIMIT)
    )
    angle_deg: tuple[float, float] | None = key(
        "list2", None, "deg", "launch elevations [min, max] of shots", MinMax(-90.0, 90.0)
    )
    direction_deg: tuple[float, float] = key(
        "list2",
        (0.0, 0.0),
        "deg",
        "launch azimuths [min, max] of shots",
        MinMax(-360.0, 360.0),
    )
    backspin: tuple[float, float] = key("list2", (0.0, 0.0), "rad/s", "backspin [min, max] of shots", MinMax(-1e5, 1e5))
    spin: Vec3 = key("vec3", (0.0, 0.0, 0.0), "rad/s", "initial angular velocity of every ball", SPIN)
    radius: float | None = key("float", None, "m", "radius (default ball.radius)", RADIUS)
    radius_jitter: float = key(
        "float", 0.0, "-", "relative spread of radii: R·(1 ± jitter)", Interval(0.0, 0.5, hi_open=True)
    )
    mass: float | None = key("float", None, "kg", "mass (default ball.mass; scaled with R³ when radii vary)", MASS)
    seed: int = key("int", 0, "-", "random seed (the same seed gives the same balls everywhere)", NON_NEGATIVE)


@dataclass(frozen=True)
class SweepDefaults:
    """Default launch-condition lists for ``ti-golf sweep`` (``None``: use the launch table)."""

    angles: tuple[float, ...] | None = key(
        "range", None, "deg", "default elevation angles of `ti-golf sweep` (START:STOP:STEP or list)", ELEVATIONS
    )
    speeds: tuple[float, ...] | None = key("range", None, "m/s", "default launch speeds of `ti-golf sweep`", SPEEDS)
    spins: tuple[float, ...] | None = key(
        "range", None, "rad/s", "default spin magnitudes of `ti-golf sweep` (along the scene's spin axis)", SPINS
    )


@dataclass(frozen=True)
class Scene:
    """A validated scene: everything static a simulation needs.

    ``launch`` is ``None`` when the scene has no ``[launch]`` table (no launched ball), ``terrain``
    when it has no ``[terrain]`` table, ``hole`` when it has no ``[hole]`` table.
    """

    name: str = "scene"
    description: str = key("text", "", "-", "one line shown by `ti-golf scenes`")
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
    overridden: frozenset[str] = field(default=frozenset(), compare=False)
    """Dotted keys whose values the overrides gave (``--set``, a study's changes), not the file."""

    def where(self, *keys: str) -> tuple[str, str]:
        """(source, key) for an error about ``keys`` (dotted): the first that the overrides gave,
        with :data:`~ti_golf.errors.OVERRIDES` (``--set``), else the first, with the scene's file."""
        given = next((k for k in keys if k in self.overridden), None)
        return (OVERRIDES, given) if given else (self.path or self.name, keys[0])


# -- the tables of a scene file, from the declarations above ---------------------------------------
SCHEMA: dict[str, dict[str, Key]] = {
    "air": keys_of(Air),
    "ball": keys_of(Ball),
    "launch": keys_of(Launch),
    "world": keys_of(World),
    "contact": keys_of(Contact),
    "sweep": keys_of(SweepDefaults),
    "terrain": keys_of(TerrainConfig),
    "hole": keys_of(HoleConfig),
    "game": keys_of(GameConfig),
}
"""Keys of each ``[table]``, by table and key name."""

ARRAY_SCHEMA: dict[str, dict[str, Key]] = {
    "balls": keys_of(BallSpec),
    "blocks": keys_of(Block),
    "surfaces": keys_of(Surface),
    "planes": keys_of(Plane),
}
"""Keys of each ``[[array]]`` of tables."""

TOP_LEVEL: dict[str, Key] = {"description": keys_of(Scene)["description"]}
"""Top-level keys that are not tables."""


def launch_velocity(speed: float, angle_deg: float, direction_deg: float) -> Vec3:
    """Velocity [m/s] for a launch at ``angle_deg`` elevation and ``direction_deg`` azimuth (+x toward +z)."""
    th, ph = math.radians(angle_deg), math.radians(direction_deg)
    return (speed * math.cos(th) * math.cos(ph), speed * math.sin(th), speed * math.cos(th) * math.sin(ph))


def backspin_axis(direction_deg: float) -> Vec3:
    """Unit backspin axis d × ŷ for a shot along azimuth ``direction_deg`` (+z for a shot toward +x)."""
    ph = math.radians(direction_deg)
    return (-math.sin(ph), 0.0, math.cos(ph))
