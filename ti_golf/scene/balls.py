"""Initial balls of a scene: the launched ball, ``[[balls]]`` and ``[[blocks]]`` as numpy arrays.

Random blocks use numpy's PCG64 generator with the block's seed, so a seed gives the same balls
on every machine.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from ti_golf.scene.checks import raise_config
from ti_golf.scene.schema import Block, Scene, Vec3, backspin_axis, launch_velocity
from ti_golf.scene.terrain import build_terrain


@dataclass(frozen=True)
class Balls:
    """Initial state of N balls: x [m], v [m/s], w [rad/s] (N, 3); radius [m], mass [kg] (N,);
    ``track`` (N,) marks balls whose flight (carry, apex, landing) is recorded."""

    x: np.ndarray
    v: np.ndarray
    w: np.ndarray
    radius: np.ndarray
    mass: np.ndarray
    track: np.ndarray

    @property
    def n(self) -> int:
        """How many balls."""
        return len(self.x)


def launch_position(scene: Scene) -> Vec3:
    """Launch point [m] of the scene's launched ball: ``launch.position``, or the ball resting on the
    ground (the terrain, if any) at x = z = 0."""
    if scene.launch is not None and scene.launch.position is not None:
        return scene.launch.position
    if scene.terrain is not None:
        terrain = build_terrain(scene.terrain, scene.path)
        if not terrain.contains(0.0, 0.0):  # (the ball would be out of bounds before its first step)
            (x0, _, z0), (sx, sz) = scene.terrain.origin, scene.terrain.size
            raise_config(
                *scene.where("terrain.origin"),
                f"leaves x = z = 0, where the [launch] ball rests, off the terrain (x in [{x0:g}, {x0 + sx:g}], "
                f"z in [{z0:g}, {z0 + sz:g}] m): move the terrain, or give launch.position",
            )
        height, n_y = float(terrain.height(0.0, 0.0)), float(terrain.normal(0.0, 0.0)[1])
        return (0.0, height + scene.ball.radius / n_y, 0.0)  # (touching the tangent plane: R/cos θ above it)
    return (0.0, scene.world.ground_height + scene.ball.radius, 0.0)


def flies_alone_problem(scene: Scene) -> tuple[str, str] | None:
    """(key, reason) naming the scene's first ``[[balls]]`` or ``[[blocks]]`` table, which flights to
    landing (a sweep, a shot, a dispersion, the tour table) would not read: they fly each launch
    alone. None when the scene has neither. ``ti-golf run`` simulates them with the launched ball."""
    for table, given in (("balls", scene.balls), ("blocks", scene.blocks)):
        if given:
            return f"{table}[0]", (
                "has no effect on a sweep, a shot, a dispersion or the tour table, which fly each launch alone; "
                f"`ti-golf run` simulates the scene's [[{table}]] with its launch"
            )
    return None


def tracks_landing(scene: Scene) -> bool:
    """Whether some ball of the scene may be tracked for its landing (carry, apex): a ``[launch]``
    shot upward, or a block launching balls at angles reaching above 0 (as :func:`build_balls`
    marks them), without creating the balls."""
    launched = scene.launch is not None and scene.launch.angle_deg > 0.0
    return launched or any(
        b.speed is not None and b.angle_deg is not None and b.angle_deg[1] > 0.0 for b in scene.blocks
    )


def check_flies_alone(scene: Scene) -> None:
    """A ConfigError from :func:`flies_alone_problem`, naming the scene's file, when there is one."""
    problem = flies_alone_problem(scene)
    if problem is not None:
        raise_config(scene.path or scene.name, *problem)


def _one(x, v, w, r, m, track) -> Balls:
    return Balls(
        np.array([x], float),
        np.array([v], float),
        np.array([w], float),
        np.array([r], float),
        np.array([m], float),
        np.array([track]),
    )


def block_size(block: Block) -> int:
    """How many balls a ``[[blocks]]`` table creates."""
    if block.kind == "random":
        return int(block.number)
    return int(math.prod(int(c) for c in block.count))


def ball_count(scene: Scene) -> int:
    """How many balls the scene creates (launch, ``[[balls]]``, blocks), without creating them."""
    return int(scene.launch is not None) + len(scene.balls) + sum(block_size(b) for b in scene.blocks)


def build_balls(scene: Scene) -> Balls:
    """All balls the scene creates, in order: launch, ``[[balls]]``, then each block."""
    parts: list[Balls] = []
    R, M = scene.ball.radius, scene.ball.mass
    if scene.launch is not None:
        L = scene.launch
        # a shot that leaves the ground is a flight (carry, apex, landing); a putt (angle 0) is not
        parts.append(
            _one(
                launch_position(scene),
                launch_velocity(L.speed, L.angle_deg, L.direction_deg),
                L.spin,
                R,
                M,
                L.angle_deg > 0.0,
            )
        )
    for spec in scene.balls:
        parts.append(_one(spec.position, spec.velocity, spec.spin, spec.radius or R, spec.mass or M, False))
    for i, block in enumerate(scene.blocks):
        parts.append(_block_balls(scene, block, i))
    if not parts:
        raise_config(scene.path, None, "the scene creates no ball: add a [launch] table, [[balls]] or [[blocks]]")
    balls = Balls(*(np.concatenate([getattr(p, f) for p in parts]) for f in ("x", "v", "w", "radius", "mass", "track")))
    buried = buried_ball(scene, balls.x, balls.radius)
    if buried is not None:
        i, depth, what, count = buried
        raise_config(
            *scene.where(_key_of_ball(scene, i)),
            f"puts ball {i} {depth:.6g} m inside {what}, {balls.x[i].tolist()} m, the whole ball in the solid "
            f"({count} ball(s) are): a ball must start at least partly on the open side",
        )
    pair = coincident_pair(balls.x) if scene.world.collisions and len(parts) > 1 else None  # (a block's are apart)
    if pair is not None:
        i, j = pair
        raise_config(
            scene.path,
            _key_of_ball(scene, j),
            f"puts ball {j} at the point of ball {i} ({_key_of_ball(scene, i)}), {balls.x[i].tolist()} m: a contact "
            "between two balls at one point has no direction, so they would never part; move one, or set "
            "world.collisions = false for balls that fly apart without meeting",
        )
    return balls


def buried_ball(scene: Scene, x: np.ndarray, radius: np.ndarray) -> tuple[int, float, str, int] | None:
    """The first of the balls of centres ``x`` (N, 3) [m] and radii ``radius`` [m] (N,) that lies
    wholly below the scene's ground plane, behind one of its planes or, over the terrain's grid,
    under the terrain's surface (along its normal), which no contact sorts out (a
    ball 5 m under the ground came to rest inside it; one that overlaps a solid is pushed out by the
    position projection, B.18): (its index, the depth [m] of its centre behind the face, the solid,
    how many balls are so); None when every ball starts at least partly on the open side."""
    solids = [(scene.world.ground_height * np.array([0.0, 1.0, 0.0]), np.array([0.0, 1.0, 0.0]), "the ground")]
    solids = solids[: 1 if scene.world.ground else 0] + [
        (np.asarray(p.point, float), np.asarray(p.normal, float), f"planes[{k}]") for k, p in enumerate(scene.planes)
    ]
    heights = [((x - point) @ (normal / np.linalg.norm(normal)), what) for point, normal, what in solids]
    if scene.terrain is not None and len(x):  # (over its grid: the height along the normal under the centre)
        terrain = build_terrain(scene.terrain, scene.path)
        over = terrain.contains(x[:, 0], x[:, 2])
        heights.append((np.where(over, terrain.gap(x, 0.0), np.inf), "the terrain"))
    for height, what in heights:
        inside = np.flatnonzero(height < -radius)
        if inside.size:
            return int(inside[0]), float(-height[inside[0]]), what, int(inside.size)
    return None


def coincident_pair(x: np.ndarray) -> tuple[int, int] | None:
    """Two balls whose centres ``x`` (N, 3) [m] are one point (the pair of lowest ids), or None."""
    if len(x) < 2:
        return None
    order = np.lexsort(x.T[::-1])
    same = np.flatnonzero(np.all(x[order[1:]] == x[order[:-1]], axis=1))
    if same.size == 0:
        return None
    pairs = np.sort(np.stack([order[same], order[same + 1]], axis=1), axis=1)
    i, j = pairs[np.lexsort(pairs.T[::-1])[0]]
    return int(i), int(j)


def _key_of_ball(scene: Scene, i: int) -> str:
    """The scene key that creates ball i (in :func:`build_balls`' order)."""
    if scene.launch is not None:
        if i == 0:
            return "launch.position"
        i -= 1
    if i < len(scene.balls):
        return f"balls[{i}].position"
    i -= len(scene.balls)
    for k, block in enumerate(scene.blocks):
        if i < block_size(block):
            return f"blocks[{k}]"
        i -= block_size(block)
    raise IndexError(i)


def _site_grid(size: np.ndarray, n: int, r_max: float) -> tuple[float, np.ndarray]:
    """The spacing [m] and the sites per axis (3,) of a random block's grid of sites over ``size``
    (3,) [m] (the box less a ball's diameter) for ``n`` balls of radius up to ``r_max`` [m]: as
    wide as the box allows, narrowed until the sites hold the balls or the balls touch."""
    spacing = max(2.02 * r_max, float(np.prod(size + 2 * r_max) / max(n, 1)) ** (1.0 / 3.0))
    while True:
        per_axis = np.floor(size / spacing).astype(int) + 1
        if np.prod(per_axis) >= n or spacing <= 2.02 * r_max:
            return spacing, per_axis
        spacing = max(2.02 * r_max, spacing * 0.98)


def random_sites(block: Block, r_max: float) -> int:
    """How many sites a random block's box offers balls of radius up to ``r_max`` [m] (0 when it is
    narrower than one), of which its balls take ``block.number``."""
    size = np.asarray(block.box_max) - np.asarray(block.box_min) - 2.0 * r_max
    if np.any(size < 0):
        return 0
    return int(np.prod(_site_grid(size, block.number, r_max)[1]))


def _block_balls(scene: Scene, block: Block, index: int) -> Balls:
    rng = np.random.default_rng(block.seed)
    R0 = block.radius or scene.ball.radius
    M0 = block.mass or scene.ball.mass
    r_max = R0 * (1.0 + block.radius_jitter)
    key = f"blocks[{index}]"
    if block.kind == "lattice":
        counts = [int(c) for c in block.count]
        spacing = block.spacing or 2.02 * r_max
        if spacing < 2.0 * r_max:
            raise_config(
                *scene.where(f"{key}.spacing"),
                f"must be at least one diameter ({2 * r_max:g} m) so balls do not overlap",
            )
        grid = np.stack(np.meshgrid(*[np.arange(c) for c in counts], indexing="ij"), axis=-1).reshape(-1, 3)
        x = np.asarray(block.origin) + spacing * grid
        free = 0.5 * (spacing - 2.0 * r_max)
        if block.jitter > free * (1.0 + 1e-12):
            raise_config(
                *scene.where(f"{key}.jitter", f"{key}.spacing"),
                f"must be at most half the free gap between the lattice's balls, (spacing − 2R)/2 = {free:.6g} m "
                f"(got {block.jitter:g}), or balls could overlap: a larger {key}.spacing leaves more room",
            )
        jitter = min(block.jitter, free)
    else:
        n = block.number
        lo, hi = np.asarray(block.box_min), np.asarray(block.box_max)
        size = hi - lo - 2.0 * r_max
        if np.any(size < 0):
            raise_config(
                *scene.where(f"{key}.box_max", f"{key}.box_min"),
                f"the box is smaller than one ball (diameter {2 * r_max:g} m)",
            )
        spacing, per_axis = _site_grid(size, n, r_max)
        if np.prod(per_axis) < n:
            raise_config(
                *scene.where(f"{key}.number", f"{key}.box_max", f"{key}.box_min"),
                f"{n} balls of radius up to {r_max:g} m do not fit in the box (at most {int(np.prod(per_axis))})",
            )
        sites = rng.choice(int(np.prod(per_axis)), size=n, replace=False)
        grid = np.stack(np.unravel_index(np.sort(sites), per_axis), axis=-1)
        x = lo + r_max + spacing * grid
        jitter = 0.5 * (spacing - 2.0 * r_max)
    n = len(x)
    if jitter > 0:
        x = x + rng.uniform(-jitter, jitter, size=(n, 3))
        if block.kind != "lattice":  # the centres in the box: a wide spacing's jitter took them out of it
            x = np.clip(x, block.box_min, block.box_max)
    radius = R0 * (1.0 + block.radius_jitter * rng.uniform(-1.0, 1.0, n)) if block.radius_jitter else np.full(n, R0)
    mass = M0 * (radius / R0) ** 3
    v = np.tile(np.asarray(block.velocity, float), (n, 1))
    if block.velocity_jitter:
        v = v + rng.uniform(-block.velocity_jitter, block.velocity_jitter, size=(n, 3))
    w = np.tile(np.asarray(block.spin, float), (n, 1))
    track = np.zeros(n, bool)
    if block.speed is not None and block.angle_deg is not None:
        speed = rng.uniform(*block.speed, n)
        angle = rng.uniform(*block.angle_deg, n)
        direction = rng.uniform(*block.direction_deg, n)
        spin = rng.uniform(*block.backspin, n)
        v = v + np.array([launch_velocity(s, a, d) for s, a, d in zip(speed, angle, direction)])
        w = w + spin[:, None] * np.array([backspin_axis(d) for d in direction])
        track[:] = angle > 0.0
    return Balls(x, v, w, radius, mass, track)


def scaled_block(scene: Scene, n: int) -> Scene:
    """``scene`` with its one random block holding ``n`` balls, its box widened or narrowed across
    (x and z about its centre) so that the balls are as densely packed and the column as tall
    (a study's ``task.balls``; :func:`scaled_block_problem` says when it cannot be)."""
    problem = scaled_block_problem(scene, n)
    if problem is not None:
        raise_config("task.balls", None, problem)
    i = next(k for k, b in enumerate(scene.blocks) if b.kind == "random")
    return dataclasses.replace(scene, blocks=scene.blocks[:i] + (_scaled(scene.blocks[i], n),) + scene.blocks[i + 1 :])


def _scaled(b: Block, n: int) -> Block:
    """Random block ``b`` holding ``n`` balls, its box scaled across (x and z about its centre) by
    sqrt(n / b.number), its height kept."""
    scale = math.sqrt(n / b.number) if b.number else 1.0
    centre = [(lo + hi) / 2 for lo, hi in zip(b.box_min, b.box_max)]

    def across(corner: tuple[float, float, float]) -> tuple[float, float, float]:
        return (centre[0] + (corner[0] - centre[0]) * scale, corner[1], centre[2] + (corner[2] - centre[2]) * scale)

    return dataclasses.replace(b, number=n, box_min=across(b.box_min), box_max=across(b.box_max))


def scaled_block_problem(scene: Scene, n: int) -> str | None:
    """Why :func:`scaled_block` cannot give ``scene``'s random block ``n`` balls (the scene has
    none or several, or its box scaled to them holds fewer sites), or ``None``."""
    randoms = [b for b in scene.blocks if b.kind == "random"]
    if len(randoms) != 1:
        return f"scales a scene's one random block; {scene.name!r} has {len(randoms)}"
    b = randoms[0]
    sites = random_sites(_scaled(b, n), (b.radius or scene.ball.radius) * (1.0 + b.radius_jitter))
    if sites < n:
        return f"asks for {n:,} balls: the random block of {scene.name!r}, scaled to them, holds at most {sites:,}"
    return None
