"""``ti-golf bench pit``: the bundled ball pit poured to rest, timed, with the pile's quality figures.

The pour of ``scenes/ball_pit.toml`` (N balls dropped into a square bin), scaled to ``n`` balls by
widening the bin so the pile stays as deep, is run to ``t`` simulated seconds. The benchmark
reports the wall time after compilation and the compile time on its own (a warm-up pour of a few
balls compiles the same kernels first), simulated seconds per wall second, ball-steps per second,
the peak memory above the runtime's baseline, the steps in which every ball was asleep (skipped:
``CollisionSolver.skip_still``), and the quality of the pile at the end: its deepest
overlap, its 99th-percentile speed, the balls outside the bin and the share asleep. A bare gather
over the final pile is timed in the same run as the yardstick (``step_cost_in_bare_gathers``).
With ``every``, the pour runs in stretches of that many simulated seconds, and the benchmark also
reports each stretch: its wall time, the rebuilds of the neighbour lists in it, and the pile's
figures at its end (``timeline``), so that where the pour's time goes can be read off one run.
With Taichi's kernel profiler on (``--profile``), the benchmark also reports the seconds and
launches of each kernel, in all and in each stretch, and the host's part of the wall time (see
:mod:`ti_golf.bench.kernel_times`); the profiler waits for every launch to end, so the wall time
is then a little longer than without it. Without the profiler, the benchmark reports the host
calls of the project's kernels a step (``host_calls_per_step``: each call a launch of one kernel,
whose top-level loops Taichi runs as parallel loops one after another) and an estimate of the
host's share of the wall time (``host_share``): the time the steps spent in Python outside the
kernels' calls, plus the calls times the host's cost of one call (``launch_host_s``: a kernel
that does no work, called with the solver's neighbour lists and step scratch as arguments, 1,000
times, the last waited for), as a share of the pour's wall time. On a GPU backend a launch
returns once queued, so that is the time the device may wait on the host (none while the queue
holds work; all of it after each result a step reads back); on a CPU backend the kernels run in
the calling thread, and it is the time the threads of the kernels' loops stand idle. Beside it,
what one more parallel loop in a kernel costs (``loop_s`` with no item, ``ball_loop_s`` over the
balls: :func:`loop_costs`), and with the parallel Gauss–Seidel sweeps the share of the wall time
that at least went to starting their loops (``sweep_loops_share``: the steps taken, times
``launches_per_step``, times ``loop_s``). Ctrl-C or SIGTERM ends the pour at the step it reached,
and the benchmark reports that much of it (``interrupted``).
"""

from __future__ import annotations

import dataclasses
import functools
import math
import time
from collections.abc import Callable, Sequence
from typing import Any, TypeVar

import numpy as np
import taichi as ti

from ti_golf.bench.collide import bare_gather_rate
from ti_golf.bench.common import _peak_rss_bytes, _restart_peak_rss, _rss_bytes
from ti_golf.bench.kernel_times import FOLD_EVERY, KernelTimes, profiling
from ti_golf.errors import ConfigError
from ti_golf.physics.kernels import int_at
from ti_golf.physics.types import LAUNCHES, NeighbourLists, StepScratch, kernel
from ti_golf.runtime import ensure_init, release_freed_memory
from ti_golf.scene.balls import random_sites
from ti_golf.scene.loader import load_scene
from ti_golf.scene.schema import AT_REST, Block, Plane, Scene
from ti_golf.signals import whole_steps
from ti_golf.sim.simulation import Simulation
from ti_golf.solvers.colour import COLOURS as COLUMN_COLOURS
from ti_golf.solvers.colour import PROJECTIONS, moving_balls, step_phases
from ti_golf.solvers.gauss_seidel import GaussSeidelSolver

T = TypeVar("T")

PIT_SCENE = "ball_pit"
"""The bundled scene the benchmark pours."""

PIT_BALLS = 100_000
"""Balls of the bundled pour (``[[blocks]].number`` of the scene)."""

WARM_UP_BALLS = 8192
"""Balls of the warm-up pour that compiles the kernels: enough for the parallel step stored in
the grid's order, as the full pour is; a smaller pour warms up with its own number of balls,
which are stepped as it is (serially or in parallel: ``stepping.SERIAL_MAX_BALLS``)."""


def pit_scene(n: int | None = None, overrides: Sequence[str] = ()) -> tuple[Scene, float]:
    """The bundled ball pit with ``n`` balls (default: the scene's), its bin widened or narrowed
    so that the pile is as deep, and the scene's keys changed by ``overrides`` (``--set``
    syntax); returns the scene and the bin's side [m]."""
    scene = load_scene(PIT_SCENE, overrides)
    launched = sorted(k for k in scene.overridden if k.startswith("launch."))
    if scene.launch is not None:  # (a ball more than the pour's n, counted in none of its figures)
        raise ConfigError(*scene.where(*launched, "launch"), "makes a launched ball: the pit pours its block alone")
    if not scene.world.collisions:
        raise ConfigError(
            *scene.where("world.collisions"), "must be true for the pit: balls that do not collide make no pile"
        )
    block = scene.blocks[0]
    side = max(p.point[0] for p in scene.planes)  # the wall at x = side
    if n is None or n == block.number:
        return scene, side
    # as deep a pile: the bin's area in proportion to the balls, but never narrower than MIN_SIDE
    scale = max(math.sqrt(n / block.number), MIN_SIDE / side)
    new_side = side * scale

    def widen(v: tuple[float, float, float]) -> tuple[float, float, float]:
        return (v[0] * scale, v[1], v[2] * scale)

    planes = tuple(Plane(point=widen(p.point), normal=p.normal) for p in scene.planes)
    block = dataclasses.replace(block, number=n, box_min=widen(block.box_min), box_max=widen(block.box_max))
    block = _box_that_holds(block, scene.ball.radius)
    desc = f"{scene.description} (scaled to {n:,} balls in a {new_side:.2f} m bin)"
    return dataclasses.replace(scene, planes=planes, blocks=(block,), description=desc), new_side


MIN_SIDE = 0.15
"""The narrowest bin [m] of a scaled pit (some 3.5 golf balls across): fewer balls than fill a bin
this wide as deep as the bundled pit (about 560) make a shallower pile, not a bin narrower than a
ball."""


def _box_that_holds(block: Block, radius: float) -> Block:
    """``block`` with its box raised (``box_max``'s height) until its random sites hold its balls
    (:func:`~ti_golf.scene.balls.random_sites`): a box scaled in its width alone holds a whole
    number of sites across, and some counts fell between (100 to 150 balls did not fit)."""
    r_max = radius * (1.0 + block.radius_jitter)
    across = min(block.box_max[0] - block.box_min[0], block.box_max[2] - block.box_min[2])
    for _ in range(100):  # (each raise adds a tenth: some 14,000 times as tall at most)
        if across < 2.0 * r_max or random_sites(block, r_max) >= block.number:
            break  # (narrower than a ball: no height helps, and the build says so)
        lo, hi = block.box_min[1], block.box_max[1]
        block = dataclasses.replace(block, box_max=(block.box_max[0], hi + 0.1 * (hi - lo), block.box_max[2]))
    return block


def pile_quality(sim: Simulation, side: float) -> dict[str, Any]:
    """The pile's figures at the end of a pour into a bin of ``side`` [m]: the deepest overlap (a
    share of a radius), the 99th-percentile and greatest speed [m/s], the balls outside the bin,
    the share of balls asleep, and the kinetic energy [J]."""
    x, v = sim.x, sim.v
    speed = np.linalg.norm(v, axis=1)
    r = np.asarray(sim.model.radius_np)
    outside = (x[:, 0] < -r) | (x[:, 0] > side + r) | (x[:, 2] < -r) | (x[:, 2] > side + r) | (x[:, 1] < -r)
    deepest = sim.deepest_overlap()
    mass = np.asarray(sim.model.mass_np)
    return {
        "deepest_overlap": 0.0 if deepest is None else float(deepest.fraction),
        "p99_speed_mps": float(np.percentile(speed, 99)),
        "max_speed_mps": float(speed.max()),
        "outside_bin": int(outside.sum()),
        "asleep_fraction": float(np.mean(sim.status == AT_REST)),
        "kinetic_energy_J": float(0.5 * np.sum(mass * speed**2)),
    }


def asleep_share(fraction: float) -> str:
    """The share of the balls asleep, as a percentage that says 100 % only when every ball is
    (99.997 %, three balls of 100,000 awake, was printed as 100 %)."""
    text = f"{100 * fraction:.3g}"
    digits = 3
    while fraction < 1.0 and float(text) >= 100.0:
        digits += 1
        text = f"{100 * fraction:.{digits}g}"
    return f"{text} %"


MAX_STEPS = 10_000_000
"""The most steps a pour may take (10 s at 1 µs): a step count held in one launch cannot be
interrupted, so a mistyped ``world.dt`` would run for hours."""


def _scaled_simulation(scene: Scene, n: int | None) -> Simulation:
    """The simulation of a pit ``scene`` scaled to ``n`` balls; a scaled bin whose box cannot hold
    them is a ConfigError naming ``--n`` (the scene file's block says nothing the user gave)."""
    try:
        return Simulation(scene)
    except ConfigError as exc:
        if n is None or not (exc.key or "").startswith("blocks[0]"):
            raise
        raise ConfigError(
            "--n", None, f"{n:,} balls do not fit the pit's bin scaled to them ({exc.reason}); try another count"
        ) from None


def bench_pit(
    n: int | None = None,
    t: float = 4.0,
    overrides: Sequence[str] = (),
    log: Callable[[str], None] = print,
    every: float | None = None,
) -> dict[str, Any]:
    """Pour the ball pit (``n`` balls, default the scene's 100,000) for ``t`` simulated seconds,
    with the scene's keys changed by ``overrides`` (``--set`` syntax), in stretches of ``every``
    simulated seconds when given, and measure it (see the module's docstring); returns the figures
    as a dict."""
    info = ensure_init()
    scene, side = pit_scene(n, overrides)
    n_balls = scene.blocks[0].number
    if t / scene.world.dt > MAX_STEPS:
        raise ConfigError(
            "--t",
            None,
            f"{t:g} s at world.dt = {scene.world.dt:g} s is {t / scene.world.dt:,.0f} steps; at most {MAX_STEPS:,}",
        )
    if every is not None and every < scene.world.dt:  # (a stretch is whole steps: it was one step)
        raise ConfigError("--every", None, f"must be at least world.dt = {scene.world.dt:g} s (got {every:g})")
    t0 = time.perf_counter()
    warm_scene, _ = pit_scene(min(n_balls, WARM_UP_BALLS), overrides)  # (stepped as the pour is)
    warm = _scaled_simulation(warm_scene, n)
    warm.run(steps=3)
    if warm.solver is not None and warm.solver.skip_still:  # (the pour's steps asleep count the balls awake)
        moving_balls(warm.state.status)
    compile_s = time.perf_counter() - t0
    del warm
    release_freed_memory()
    _restart_peak_rss()
    base_rss = _rss_bytes()
    log(f"{scene.name}: {n_balls:,} balls into a {side:.2f} m bin, {t:g} s at dt = {scene.world.dt:g} s ...")
    t1 = time.perf_counter()
    sim = _scaled_simulation(scene, n)
    setup_s = time.perf_counter() - t1
    times = KernelTimes() if profiling() else None
    LAUNCHES.on, LAUNCHES.calls, LAUNCHES.inside_s = times is None, 0, 0.0
    try:
        wall_s, timeline, peak, interrupted = _pour(sim, t, every, side, log, times)
    finally:
        LAUNCHES.on = False
    steps = round(sim.t / sim.dt)
    if interrupted and steps == 0:
        raise KeyboardInterrupt("before the pour's first step")
    if interrupted:
        log(f"interrupted at t = {sim.t:.4g} s: the figures below are of the pour so far")
    # the figures, with Ctrl-C and SIGTERM held until they are taken (a second Ctrl-C soon after the
    # one that ended the pour lost them); the command prints them, and then ends
    try:
        with whole_steps("taking the figures of the pour so far; they are printed before it stops"):
            quality, gather_rate = pile_quality(sim, side), bare_gather_rate(sim.x)
            ball_steps_per_s = n_balls * steps / wall_s
            result: dict[str, Any] = {
                "benchmark": "pit",
                "n": n_balls,
                "interrupted": interrupted,
                "set": list(overrides),
                "t_s": sim.t,
                "dt_s": sim.dt,
                "steps": steps,
                "steps_asleep": sim.solver.still_steps if sim.solver is not None else 0,
                "arch": info.arch,
                "precision": info.precision,
                "wall_s": wall_s,
                "setup_s": setup_s,
                "compile_s": compile_s,
                "sim_s_per_wall_s": sim.t / wall_s,
                "ball_steps_per_s": ball_steps_per_s,
                "peak_rss_bytes": peak,
                "bytes_per_ball_above_baseline": max(peak - base_rss, 0) / n_balls,
                **quality,
                "baselines": {"bare_gather_balls_per_s": gather_rate},
                "step_cost_in_bare_gathers": gather_rate / ball_steps_per_s,
            }
            result.update(solver_launches(sim))
            result.update(pair_tables(sim))
            if times is None and steps > 0 and sim.solver is not None:
                result.update(host_share(sim, wall_s, steps))
            if "loop_s" in result and "launches_per_step" in result:  # (the parallel Gauss–Seidel sweeps)
                taken = steps - result["steps_asleep"]  # (a step skipped asleep starts no loop)
                result["sweep_loops_share"] = min(taken * result["launches_per_step"] * result["loop_s"] / wall_s, 1.0)
            if every is not None:
                result["timeline"] = timeline
            if times is not None:
                result["kernel_profiler"] = {"kernel_s": times.total_s(), "host_s": wall_s - times.total_s()}
                result["kernels"] = times.as_dict()
            log(
                f"{wall_s:.1f} s after {compile_s:.1f} s of compiling ({result['sim_s_per_wall_s']:.3g} simulated s per "
                f"wall s, {ball_steps_per_s:.3g} ball-steps/s, {result['bytes_per_ball_above_baseline']:.0f} bytes/ball)"
            )
            log(
                f"pile at t = {sim.t:.3g} s: deepest overlap {100 * quality['deepest_overlap']:.3g} % of a radius, "
                f"p99 speed {1e3 * quality['p99_speed_mps']:.3g} mm/s, {quality['outside_bin']} outside the bin, "
                f"{asleep_share(quality['asleep_fraction'])} asleep"
            )
            if "launches_per_step" in result:
                log(
                    f"{result['layout']} layout: {result['launches_per_step']} parallel loops a step in the sweeps and "
                    f"projections, a median of {result['median_items_per_launch']:.0f} work items each"
                )
            if "host_share" in result:
                log(
                    f"{result['host_calls_per_step']:.1f} kernel calls a step, {1e6 * result['launch_host_s']:.1f} µs of host "
                    f"time each: the host's share of the wall time about {100 * result['host_share']:.2g} %"
                )
            if "loop_s" in result:
                share = result.get("sweep_loops_share")
                at_least = (
                    ""
                    if share is None
                    else f" ({100 * share:.2g} % of the wall time at least, to start the sweeps' loops)"
                )
                log(
                    f"one parallel loop more in a kernel: {1e6 * result['loop_s']:.1f} µs of no item, "
                    f"{1e6 * result['ball_loop_s']:.1f} µs over the balls{at_least}"
                )
            log(
                f"baseline bare_gather: {gather_rate:.3g} balls/s -> a step costs {result['step_cost_in_bare_gathers']:.1f}"
            )
            if times is not None:
                dearest = ", ".join(f"{name} {s:.1f} s" for name, s in times.seconds.most_common(6))
                log(
                    f"kernels {times.total_s():.1f} s of the {wall_s:.1f} s (dearest: {dearest}); the host {wall_s - times.total_s():.1f} s"
                )
    except KeyboardInterrupt:  # (raised as the block ends, once the result is made)
        result["interrupted"] = True
    return result


def _pour(
    sim: Simulation,
    t: float,
    every: float | None,
    side: float,
    log: Callable[[str], None],
    times: KernelTimes | None = None,
) -> tuple[float, list[dict[str, Any]], int, bool]:
    """Run ``sim`` for ``t`` simulated seconds, in stretches of ``every`` [s] when given (each
    stretch's wall time, rebuilds of the lists and the pile's figures at its end, logged and
    listed); returns the wall time of the steps alone [s], the stretches, the peak resident
    memory of the steps [bytes] (the count restarts after each stretch's pile is measured, but
    what the measuring's numpy copies leave in the process still counts) and whether the pour was
    interrupted: Ctrl-C or SIGTERM ends it after the whole step it reached, which closes the last
    stretch (or, while a stretch's pile is measured, once that stretch is listed). With
    ``times``, the kernels' seconds are summed into it (every ``FOLD_EVERY`` steps, outside the
    wall time), and each stretch also lists its own."""
    steps = int(math.ceil(t / sim.dt - 1e-9))  # (as Simulation.run counts them)
    stretch = steps if every is None else max(1, int(math.ceil(every / sim.dt - 1e-9)))
    start = round(sim.t / sim.dt)
    wall_s, timeline, done, peak, interrupted = 0.0, [], 0, 0, False
    while done < steps and not interrupted:
        rebuilds = sim.solver.rebuilds if sim.solver is not None else 0
        asleep = sim.solver.still_steps if sim.solver is not None else 0
        kernel_s, kernels = 0.0, {}
        if times is not None:
            times.drop()
            kernel_s, kernels = times.total_s(), dict(times.seconds)
        wall, interrupted = _timed_steps(sim, min(stretch, steps - done), times)
        taken = round(sim.t / sim.dt) - start - done  # (fewer than asked for when interrupted)
        wall_s, done, peak = wall_s + wall, done + taken, max(peak, _peak_rss_bytes())
        if every is None or taken == 0:
            continue
        q, held = _held(lambda: _measure_stretch(sim, side))  # (a signal ends the pour after this row)
        interrupted = interrupted or held
        row = {
            "t_s": sim.t,
            "wall_s": wall,
            "rebuilds": (sim.solver.rebuilds if sim.solver is not None else 0) - rebuilds,
            "steps_asleep": (sim.solver.still_steps if sim.solver is not None else 0) - asleep,
            **{k: q[k] for k in ("deepest_overlap", "p99_speed_mps", "asleep_fraction", "kinetic_energy_J")},
        }
        if times is not None:
            row["kernel_s"] = times.total_s() - kernel_s
            row["kernels"] = {name: s - kernels.get(name, 0.0) for name, s in times.seconds.most_common()}
        timeline.append(row)
        in_kernels = "" if times is None else f" ({row['kernel_s']:.1f} s in kernels)"
        log(
            f"  t = {sim.t:.3g} s: {wall:.1f} s of wall time{in_kernels}, {row['rebuilds']} rebuilds in {taken} steps "
            f"({row['steps_asleep']} with every ball asleep), deepest "
            f"overlap {100 * q['deepest_overlap']:.3g} % of a radius, p99 speed {1e3 * q['p99_speed_mps']:.3g} mm/s, "
            f"{asleep_share(q['asleep_fraction'])} asleep"
        )
    return wall_s, timeline, peak, interrupted


def _measure_stretch(sim: Simulation, side: float) -> dict[str, Any]:
    """The pile's figures at the end of a stretch (:func:`pile_quality`); then the numpy copies
    freed and the count of the peak memory restarted for the next stretch."""
    q = pile_quality(sim, side)
    release_freed_memory()
    _restart_peak_rss()
    return q


def _held(measure: Callable[[], T]) -> tuple[T, bool]:
    """``measure()`` with Ctrl-C and SIGTERM held until it returns (``whole_steps``): its result, and
    whether a signal came meanwhile (so that what was measured is kept and reported)."""
    try:
        with whole_steps():
            value = measure()
    except KeyboardInterrupt:  # (raised as the block ends, once value is set)
        return value, True
    return value, False


def _timed_steps(sim: Simulation, k: int, times: KernelTimes | None) -> tuple[float, bool]:
    """Run ``k`` steps of ``sim`` (with ``times``, in runs of ``FOLD_EVERY`` steps, the kernels'
    seconds folded into it after each); returns their wall time [s] and whether Ctrl-C or SIGTERM
    ended them early (``Simulation.run`` stops after the whole step it reached)."""
    wall, chunk = 0.0, k if times is None else FOLD_EVERY
    try:
        for first in range(0, k, chunk):
            t0 = time.perf_counter()
            try:
                sim.run(steps=min(chunk, k - first))
                ti.sync()  # (the last launches ended: on a GPU backend they return once queued)
            finally:
                wall += time.perf_counter() - t0
                if times is not None:
                    times.fold()
    except KeyboardInterrupt:
        return wall, True
    return wall, False


def pair_tables(sim: Simulation) -> dict[str, Any]:
    """What the collision solver's tables hold at the end of a pour beside the room they were made
    with: the pairs listed, the room of the pair tables (made for the pairs of a build that outgrew
    them plus 1/``PAIR_ROOM`` of them, ``CollisionSolver._fit_pair_tables``) and the width of the
    neighbour table (the longest list of pairs a ball owns). A pile that outgrew its tables once
    more as it settled holds about 1/16 of its pairs more room, and so more bytes a ball; nothing
    without a collision solver."""
    solver = sim.solver
    if solver is None:
        return {}
    return {
        "pairs_listed": int_at(solver.first, solver.first.shape[0] - 1),
        "pair_table_room": int(solver.pair_capacity),
        "neighbour_table_width": int(solver.capacity),
    }


def solver_launches(sim: Simulation) -> dict[str, Any]:
    """The parallel loops of a step's Gauss–Seidel sweeps and position projections with the lists
    of the last build, and the independent work items of each (threads that share no ball): the
    blocks of grid columns of each colour (``contact.layout = columns``), or the pairs of each
    colour and the balls (``contacts``); a serial loop (the pairs left to ``colour.far_pairs`` or
    to the overflow set) counts one. Returns the layout, the loops a step, the median items a loop
    and (contacts) the colours in use and the colouring rounds of the last build; nothing without
    the parallel Gauss–Seidel sweeps."""
    solver = sim.solver
    if not isinstance(solver, GaussSeidelSolver) or solver.serial:  # (only its class has gauss_seidel)
        return {}
    iterations = sim.scene.contact.iterations
    if solver.colours is not None:
        cc = solver.colours
        items = cc.launches(sim.n, iterations)
        colours, _, overflow = cc.sizes()
        extra: dict[str, Any] = {"colours": colours, "overflow_pairs": overflow}
        extra["colouring_rounds_mean"] = cc.rounds / max(cc.builds, 1)
        extra["colouring_rounds_max"] = cc.rounds_max
        if cc.fresh:
            extra["fresh_pairs_mean"] = float(np.mean(cc.fresh))
            extra["fresh_pairs_max"] = int(np.max(cc.fresh))
        layout = "contacts"
    else:
        assert solver.col_start is not None, "the pour built the lists"
        start, colour = solver.col_start.to_numpy(), solver.col_colour.to_numpy()
        filled = np.nonzero(np.diff(start))[0]
        blocks = np.bincount(colour[start[filled]], minlength=COLUMN_COLOURS).tolist()
        far = [1] if solver.far_owners else []
        items = (blocks + far) * (len(step_phases(iterations)) + PROJECTIONS)
        extra, layout = {}, "columns"
    return {
        "layout": layout,
        "launches_per_step": len(items),
        "median_items_per_launch": float(np.median(items)),
        **extra,
    }


PROBE_CALLS = 1000
"""Calls of :func:`_no_work` that measure the host's cost of a kernel call."""


def _no_work_body(lists, scratch):
    """A kernel that does no work, with the solver's arguments (:func:`host_share`)."""
    for _ in range(lists.first.shape[0] * 0):
        scratch.flag[0] += 0


PROBE_LOOPS = 32
"""Parallel loops a call of the loop probe (:func:`loop_costs`): as many as a pass of the contact
colours holds on CUDA."""

LOOP_PROBE_CALLS = 100
"""Calls of each kernel of :func:`loop_costs`."""


def _loops_body(lists, scratch, loops, every_ball):
    """``loops`` parallel loops one after another, each with its bounds read on the device, as the
    contact colours' loops are (:func:`~ti_golf.solvers.contact_colour.colour_pass`): with
    ``every_ball``, over the balls, each thread reading one number and writing nothing, as a
    sweep's thread for a ball asleep; else over no item (:func:`loop_costs`)."""
    for _ in ti.static(range(loops)):
        start = lists.first[0]  # (0: the pair table's first start)
        count = 0
        if ti.static(every_ball):
            count = lists.first.shape[0] - 1 - start
        for k in range(count):  # (from 0: Vulkan's code generator takes no loop start read on the device)
            if scratch.calm[start + k] < -1.0:  # (never: a rest timer is not negative)
                scratch.flag[1] = 1


# (the annotations as objects: this module's are strings, which ti.kernel cannot read)
_no_work_body.__annotations__ = {"lists": NeighbourLists, "scratch": StepScratch}
_no_work = kernel(_no_work_body)
_loops_body.__annotations__ = {
    "lists": NeighbourLists,
    "scratch": StepScratch,
    "loops": ti.template(),
    "every_ball": ti.template(),
}
_loops = kernel(_loops_body)


def _per_call_s(call: Callable[[], Any], calls: int = PROBE_CALLS) -> float:
    """Seconds a call of a probe kernel, over ``calls`` calls after one that compiles it, the last
    waited for."""
    call()
    ti.sync()
    t0 = time.perf_counter()
    for _ in range(calls):
        call()
    ti.sync()
    return (time.perf_counter() - t0) / calls


def loop_costs(lists: Any, scratch: Any) -> dict[str, float]:
    """What one more parallel loop in a kernel costs, on the device and for the host's launch of
    it, from kernels that differ in their number of loops alone (``_loops``): a loop of no item
    (``loop_s``: starting it, on a CPU backend waking the thread pool and waiting for it, on a GPU a
    launch of its own) and a loop over the balls in which each thread reads one number
    (``ball_loop_s``: a sweep's loop over a pile asleep), each from ``PROBE_LOOPS`` loops a call
    against one."""
    costs = {}
    for name, every_ball in (("loop_s", False), ("ball_loop_s", True)):
        one = _per_call_s(functools.partial(_loops, lists, scratch, 1, every_ball), LOOP_PROBE_CALLS)
        many = _per_call_s(functools.partial(_loops, lists, scratch, PROBE_LOOPS, every_ball), LOOP_PROBE_CALLS)
        costs[name] = max(many - one, 0.0) / (PROBE_LOOPS - 1)
    return costs


def host_share(sim: Simulation, wall_s: float, steps: int) -> dict[str, Any]:
    """The host calls of the project's kernels a step in the pour just timed (``LAUNCHES``), the
    host's cost of one call (``PROBE_CALLS`` calls of :func:`_no_work`) and the host's estimated
    share of the pour's ``wall_s`` (see the module's docstring)."""
    calls, inside = LAUNCHES.calls, LAUNCHES.inside_s
    solver = sim.solver
    assert solver is not None  # a pour: its balls collide
    lists, scratch = solver.packs.lists(solver), solver.packs.scratch(solver)
    per_call = _per_call_s(lambda: _no_work(lists, scratch))
    host = max(wall_s - inside, 0.0) + calls * per_call
    return {
        "host_calls_per_step": calls / steps,
        "launch_host_s": per_call,
        "host_share": min(host / wall_s, 1.0),
        **loop_costs(lists, scratch),
    }
