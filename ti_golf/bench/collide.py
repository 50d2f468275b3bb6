"""``ti-golf bench collide``: the collision step on a pile of N balls, with same-run yardsticks."""

from __future__ import annotations

import gc
import time
from collections.abc import Callable
from typing import Any

import numpy as np
import taichi as ti

from ti_golf.bench import baseline
from ti_golf.bench.common import _best_time, _peak_rss_bytes, _restart_peak_rss, _rss_bytes, faster
from ti_golf.physics.types import vec3
from ti_golf.runtime import ensure_init, release_freed_memory
from ti_golf.scene.schema import (
    AT_REST,
    Air,
    Contact,
    Plane,
    Scene,
    TerrainConfig,
    World,
)
from ti_golf.sim.simulation import Simulation
from ti_golf.solvers import CollisionSolver
from ti_golf.solvers.stepping import RELIST_MAX_BALLS, relists_in_kernel, steps_serially

PILE_RADIUS = 0.02
"""The radius [m] of the balls of :func:`pile_scene`'s pile (the scenes' default ball)."""

DROP_GAP = 0.005
"""How far above the top of the pile :func:`drop_boulder` starts a boulder's lowest point [m]."""


def pile_lattice(n: int) -> tuple[np.ndarray, float, int]:
    """The pile of :func:`pile_scene`: the centres (n, 3) [m] of n touching balls of radius
    :data:`PILE_RADIUS` on a cubic lattice in a square bin about 16 layers deep, the bin's width
    [m] and the number of layers (the top one partly filled unless n fills it)."""
    r = PILE_RADIUS
    side = int(np.ceil(np.sqrt(n / 16.0)))  # a bin about 16 layers deep
    layers = int(np.ceil(n / side**2))
    idx = np.arange(n)
    grid = np.stack([idx % side, idx // (side * side), (idx // side) % side], axis=1)
    return r + 2.0 * r * grid.astype(float), 2.0 * r * side, layers


def pile_scene(n: int, terrain: bool = False, iterations: int = 4) -> tuple[Scene, np.ndarray]:
    """A dense pile: n balls on a cubic lattice of touching balls in a square bin, resting on the floor
    (:func:`pile_lattice`).

    Every inner ball touches six neighbours. With ``terrain`` the floor is a flat height field
    instead of a plane (same results, the terrain's cost); ``iterations`` Gauss–Seidel sweeps per
    step (``contact.solver``'s default; the last is the shock sweep).
    Returns the scene (planes, full contact model, air, no sleeping) and the positions (n, 3) [m].
    """
    x, width, layers = pile_lattice(n)
    planes: tuple[Plane, ...] = (
        Plane((0, 0, 0), (0, 1, 0)),
        Plane((0, 0, 0), (1, 0, 0)),
        Plane((width, 0, 0), (-1, 0, 0)),
        Plane((0, 0, 0), (0, 0, 1)),
        Plane((0, 0, width), (0, 0, -1)),
    )
    floor = None
    if terrain:
        planes = planes[1:]
        floor = TerrainConfig(
            kind="generated",
            origin=(-0.1, 0.0, -0.1),
            size=(width + 0.2, width + 0.2),
            resolution=(65, 65),
            amplitude=0.0,
        )
    scene = Scene(
        name="bench_collide",
        description=f"benchmark: {n} balls in a {width:.2f} m bin, {layers} layers",
        air=Air(rho=1.2, gamma=2, C_D=0.3),
        launch=None,
        world=World(dt=0.001, integrator="semi_implicit", ground=False, v_rest=0.0),
        contact=Contact(e=0.0, mu=0.3, k_p=0.2, iterations=iterations),
        planes=planes,
        terrain=floor,
    )
    return scene, x


def boulder_centre(x: np.ndarray, r: float, radius: float) -> np.ndarray:
    """Where :func:`drop_boulder` starts a boulder of ``radius`` [m] above the pile of balls of
    radius ``r`` [m] at ``x`` (n, 3) [m]: over the middle of the pile, :data:`DROP_GAP` above its
    top (3,) [m]."""
    return np.array([x[:, 0].mean(), x[:, 1].max() + r + DROP_GAP + radius, x[:, 2].mean()])


def widest_boulder(n: int) -> float:
    """The largest radius [m] of a boulder that :func:`drop_boulder` drops onto the pile of
    ``n`` balls of :func:`pile_scene` without it reaching through the bin's walls: the distance
    from its centre to the nearest wall, to the 0.1 mm below."""
    x, width, _ = pile_lattice(n)
    c = boulder_centre(x, PILE_RADIUS, 0.0)
    room = min(c[0], width - c[0], c[2], width - c[2])
    return float(np.floor(room * 1e4 + 1e-6) / 1e4)


def drop_boulder(
    scene: Scene, x: np.ndarray, radius: float, speed: float = 3.0
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """A ball of ``radius`` [m], as dense as the scene's balls, :data:`DROP_GAP` above the middle
    of the top of the pile at ``x`` (n, 3) [m], falling at ``speed`` [m/s]: a boulder thrown into a
    ball pit (:func:`widest_boulder`: the widest that fits the bin of :func:`pile_scene`).
    Returns the positions, velocities, radii and masses of the n + 1 balls (the boulder last)."""
    r, m = scene.ball.radius, scene.ball.mass
    x = np.vstack([x, boulder_centre(x, r, radius)])
    v = np.zeros_like(x)
    v[-1, 1] = -speed
    radii = np.full(len(x), r)
    radii[-1] = radius
    return x, v, radii, m * (radii / r) ** 3


def bench_collide(
    n: int = 131_072,
    steps: int = 50,
    terrain: bool = False,
    asleep: bool = False,
    shuffled: bool = False,
    iterations: int = 4,
    boulder: float = 0.0,
    log: Callable[[str], None] = print,
) -> dict[str, Any]:
    """Time the full collision step (flight forces, grid, ball–ball and plane contacts) on a dense pile.

    With ``terrain`` the floor is a flat height field, and the same pile on the plane floor is
    timed in the same run as the baseline (``terrain_overhead``: relative extra time per step).
    With ``asleep`` every ball of the pile is at rest, as a settled pile ends up, and the same pile
    awake is timed in the same run as the baseline (``asleep_speedup``). A pile small enough to be
    stepped serially (``serial``, see ``stepping.SERIAL_MAX_BALLS``) is also timed stepped in
    parallel, one launch per step, as the baseline (``serial_speedup``).
    With ``shuffled`` the balls are numbered in a random order, as balls given in no spatial order
    are, and the same pile kept in that order (no reordering, see ``CollisionSolver.reorder``) is
    timed in the same run as the baseline (``reorder_speedup``).
    With ``boulder`` [m] a ball of that radius is dropped onto the pile at 3 m/s (see
    :func:`drop_boulder`; it lands within the untimed first steps and sinks in during the timed
    ones), and the pile alone is timed in the same run as the baseline (``boulder_slowdown``).
    """
    info = ensure_init()
    # the solver decides by the balls it holds: the boulder is one more
    balls = n + 1 if boulder > 0 else n
    serial = steps_serially(balls)

    def pile(
        m: int, floor: bool, parallel: bool = False, reorder: bool | None = None, with_boulder: bool = boulder > 0
    ) -> Simulation:
        scene, x = pile_scene(m, floor, iterations)
        if shuffled:
            x = x[np.random.default_rng(0).permutation(m)]
        v = radius = mass = None
        if with_boulder:
            x, v, radius, mass = drop_boulder(scene, x, boulder)
        # a pile keeps no flight records, as a scene's [[blocks]]
        sim = Simulation(scene, x=x, v=v, radius=radius, mass=mass, track=False, keep_initial=False)
        if parallel or reorder is not None:
            sim.solver = CollisionSolver(sim.model, serial=False if parallel else None, reorder=reorder)
        return sim

    # a serial pile relists in its kernel or is built between launches (stepping.RELIST_MAX_BALLS): the
    # warm-up's serial pile is of the same kind
    serial_warm = 64 if relists_in_kernel(balls, serial) else RELIST_MAX_BALLS + 1
    for floor in (False, True) if terrain else (False,):  # compile every kernel before timing
        for parallel, reorder in ((False, None),) * serial + ((True, False), (True, True)):
            warm = pile(64 if parallel else serial_warm, floor, parallel, reorder)
            warm.step(2)
            assert warm.solver is not None  # 64 balls that collide
            warm.solver.invalidate()  # a rebuild that carries the pairs' impulses over
            warm.step(1)
            del warm
    gc.collect()
    # the peak from here on is the pile's: compiling the kernels above from an empty kernel cache
    # peaks at 800 MiB and more, which the process's lifetime peak would report instead; and the
    # heap gives back what the compiler freed, so that the pile's arrays are not counted in it
    release_freed_memory()
    _restart_peak_rss()
    base_rss = _rss_bytes()

    def timed(
        floor: bool,
        sleeping: bool,
        parallel: bool = False,
        reorder: bool | None = None,
        with_boulder: bool = boulder > 0,
    ) -> tuple[Any, float]:
        sim = pile(n, floor, parallel, reorder, with_boulder)
        sim.step(10)  # settle the first contacts, build the lists
        if sleeping:
            put_to_sleep(sim)
            sim.step(1)
        t0 = time.perf_counter()
        sim.step(steps)
        return sim, time.perf_counter() - t0

    sim, seconds = timed(terrain, asleep)
    # the high-water mark of the simulation itself: before the copies below and any baseline run
    peak = _peak_rss_bytes()
    scene, xn, rebuilds, sim_reordered = sim.scene, sim.x, sim.solver.rebuilds, sim.solver.reorder
    i, j = sim.solver.pairs().T
    touching = int(np.count_nonzero(np.linalg.norm(xn[i] - xn[j], axis=1) < 2 * 0.02 * 1.001))
    deepest = sim.deepest_overlap()  # speed is only worth quoting while the pile keeps its shape
    one_pass_rate = one_pass_contact_rate(sim)  # after the peak: its two arrays are not the step's
    del sim
    gc.collect()
    plane_seconds = timed(False, asleep)[1] if terrain else None  # the baselines, timed in the same run
    awake_seconds = timed(terrain, False)[1] if asleep else None
    parallel_seconds = timed(terrain, asleep, parallel=True)[1] if serial else None
    in_id_order_seconds = timed(terrain, asleep, reorder=False)[1] if shuffled and not serial else None
    alone_seconds = timed(terrain, asleep, with_boulder=False)[1] if boulder > 0 else None
    gather_rate = bare_gather_rate(xn)
    result = {
        "benchmark": "collide",
        "n": n,
        "steps": steps,
        "arch": info.arch,
        "precision": info.precision,
        "iterations": scene.contact.iterations,
        "ball_steps_per_s": n * steps / seconds,
        "ms_per_step": 1e3 * seconds / steps,
        "contacts_per_ball": 2 * touching / n,
        "deepest_overlap": 0.0 if deepest is None else deepest.fraction,  # share of a radius, after the timed steps
        "list_rebuilds": rebuilds,
        "serial": serial,  # stepped serially, many steps per launch (few balls; see stepping.SERIAL_MAX_BALLS)
        "floor": "terrain" if terrain else "plane",
        "asleep": asleep,
        "shuffled": shuffled,
        "boulder_radius": boulder,
        "reordered": sim_reordered,
        "peak_rss_bytes": peak,
        # the OS's high-water mark can lag the current RSS by a few pages: no negative growth
        "bytes_per_ball_above_baseline": max(peak - base_rss, 0) / n,
    }
    result["baselines"] = {"bare_gather_balls_per_s": gather_rate, "one_pass_contacts_balls_per_s": one_pass_rate}
    result["step_cost_in_bare_gathers"] = gather_rate / result["ball_steps_per_s"]
    result["step_cost_in_one_pass_contacts"] = one_pass_rate / result["ball_steps_per_s"]
    # the baselines timed in the same run: (its seconds, key of its ms per step, key of the ratio, the
    # ratio from (seconds, its seconds), the line that says it)
    for base, key, name, ratio, say in (
        (
            plane_seconds,
            "plane_floor_ms_per_step",
            "terrain_overhead",
            lambda s, b: s / b - 1.0,
            lambda q: f"terrain floor vs plane floor: {100 * q:+.1f} % time per step",
        ),
        (
            awake_seconds,
            "awake_ms_per_step",
            "asleep_speedup",
            lambda s, b: b / s,
            lambda q: f"the pile asleep vs awake: {faster(q, 2)} per step",
        ),
        (
            in_id_order_seconds,
            "not_reordered_ms_per_step",
            "reorder_speedup",
            lambda s, b: b / s,
            lambda q: f"stored in the grid's order vs left in random id order: {faster(q, 2)} per step",
        ),
        (
            alone_seconds,
            "pile_alone_ms_per_step",
            "boulder_slowdown",
            lambda s, b: s / b,
            lambda q: f"with a {boulder:g} m boulder vs the pile alone: {q:.2f}x the time per step",
        ),
        (
            parallel_seconds,
            "parallel_ms_per_step",
            "serial_speedup",
            lambda s, b: b / s,
            lambda q: f"stepped serially vs one parallel launch per step: {faster(q)} per step",
        ),
    ):
        if base is not None:
            result["baselines"][key] = 1e3 * base / steps
            result[name] = ratio(seconds, base)
            log(say(result[name]))
    log(
        f"ti_golf collide: {n} balls, {result['ms_per_step']:.2f} ms/step, {result['ball_steps_per_s']:.3g} ball-steps/s, "
        f"{result['contacts_per_ball']:.2f} contacts/ball, deepest overlap {100 * result['deepest_overlap']:.2g} % "
        f"of a radius, peak RSS {peak / 2**20:.0f} MiB "
        f"({result['bytes_per_ball_above_baseline']:.0f} B/ball above baseline), arch={info.arch}, {info.precision}"
    )
    log(
        f"baseline: a bare 12-neighbour gather runs at {gather_rate:.3g} balls/s; "
        f"one collision step costs {result['step_cost_in_bare_gathers']:.1f} such passes"
    )
    log(
        f"floor: one pass of the pair impulse over every ball's neighbours runs at {one_pass_rate:.3g} balls/s; "
        f"one collision step costs {result['step_cost_in_one_pass_contacts']:.1f} such passes"
    )
    return result


def put_to_sleep(sim: Any) -> None:
    """Put every ball of ``sim`` at rest (zero velocity and spin, rest timer at ``t_rest``)."""
    s, n = sim.state, sim.n
    f = s.v.to_numpy().dtype
    s.v.from_numpy(np.zeros((n, 3), f))
    s.w.from_numpy(np.zeros((n, 3), f))
    s.status.from_numpy(np.full(n, AT_REST, np.int32))
    s.rest_time.from_numpy(np.full(n, sim.scene.world.t_rest, f))
    if sim.solver is not None:  # (the statuses edited between steps: see Stepping.forget_quiet)
        sim.solver.forget_quiet()


def bare_gather_rate(x: np.ndarray, repeats: int = 5) -> float:
    """Balls per second of a bare contact gather on the same positions ``x`` (n, 3): every ball sums
    x_i − x_j over a fixed 12-entry list of lattice neighbours (memory traffic, no physics). It is
    the yardstick of the collision benchmark, measured in the same run: one collision step costs
    ``bare_gather_rate / ball_steps_per_s`` such passes, a ratio that survives a noisy machine."""
    n = len(x)
    side = max(2, int(np.ceil(np.sqrt(n / 16.0))))
    offsets = np.array([1, side, side * side, side + 1, side * side + 1, side * side + side])
    nbr = (np.arange(n)[:, None] + np.concatenate([offsets, -offsets])[None, :]) % n
    xs = ti.ndarray(vec3.get(), n)
    xs.from_numpy(x.astype(xs.to_numpy().dtype))
    table = ti.ndarray(ti.i32, nbr.shape)
    table.from_numpy(nbr.astype(np.int32))
    out = ti.ndarray(vec3.get(), n)
    baseline.bare_gather(xs, table, out)  # compile
    ti.sync()

    def run() -> None:
        baseline.bare_gather(xs, table, out)
        ti.sync()

    return n / _best_time(run, repeats)


def one_pass_contacts(sim: Any) -> tuple[Callable[[], None], Any, Any]:
    """A runner of the one-pass contact yardstick (``physics.baseline.one_pass_contacts``) on the
    balls and neighbour lists of ``sim`` (built first if need be), and its outputs, Taichi arrays
    (N, 3) in the state's storage order: the contact impulses' Δv [m/s] and Δω [rad/s]."""
    m, s, solver = sim.model, sim.state, sim.solver
    solver.ensure_lists(s)
    dv, dw = ti.ndarray(vec3.get(), s.n), ti.ndarray(vec3.get(), s.n)

    def run() -> None:
        baseline.one_pass_contacts(
            m.contact,
            m.gravity,
            m.dt,
            s.x,
            s.v,
            s.w,
            m.radius,
            m.mass,
            solver.upper,
            solver.first,
            solver.lower,
            solver.lower_first,
            dv,
            dw,
        )
        ti.sync()

    return run, dv, dw


def one_pass_contact_rate(sim: Any, repeats: int = 5) -> float:
    """Balls per second of the one-pass contact yardstick on ``sim``'s pile, its own lists: every
    ball meets each of its neighbours through the report's pair impulse, once, with nothing else
    of the step (see ``physics.baseline.one_pass_contacts``). A step of the model cannot be
    cheaper than this pass (it makes it once per sweep, pairs shared, and much else besides), so
    it bounds the ball-steps per second that the collision model can reach on this machine."""
    run = one_pass_contacts(sim)[0]
    run()  # compile
    return sim.n / _best_time(run, repeats)
