"""``ti-golf bench``: throughput with a baseline timed in the same run, and quality figures (JSON)."""

from __future__ import annotations

import argparse
import math

from ti_golf.bench.collide import bench_collide, widest_boulder
from ti_golf.bench.common import to_json
from ti_golf.bench.dispersion import SCENE as DISPERSION_SCENE
from ti_golf.bench.dispersion import bench_dispersion
from ti_golf.bench.lab import bench_lab
from ti_golf.bench.pit import PIT_BALLS, bench_pit
from ti_golf.bench.reductions import bench_reductions
from ti_golf.bench.render import bench_render
from ti_golf.bench.startup import bench_startup, profile_lines, scene_names, start_profile
from ti_golf.bench.sweep import bench_sweep
from ti_golf.cli._common import (
    Parser,
    check_writable,
    parse_size,
    refuse_given,
    refuse_unread_keys,
    runtime_options,
    scene_options,
    set_option,
)
from ti_golf.errors import ConfigError
from ti_golf.scene.checks import RADIUS
from ti_golf.scene.loader import load_scene
from ti_golf.scene.readers import POUR_NOT_READ
from ti_golf.solvers.solver import REORDER_MIN_BALLS

DISPERSION_REST = 10_000
"""Shots of ``bench dispersion`` rolled out to rest unless ``--rest`` says (all, when fewer)."""


def add_parser(sub: argparse._SubParsersAction) -> None:
    """Add ``bench`` and its benchmarks to ``ti-golf``'s subcommands."""
    b = sub.add_parser("bench", help="throughput benchmarks (JSON with --json)")
    bsub = b.add_subparsers(dest="bench", required=True, parser_class=Parser)
    bs = bsub.add_parser("sweep", help="data-parallel sweep vs numpy and scipy baselines")
    bs.add_argument("--n", type=int, default=100_000, help="launch conditions (default 100000)")
    bs.add_argument("--dt", type=float, default=0.1, help="RK4 step [s] (default 0.1)")
    bs.add_argument("--repeats", type=int, default=3, help="timed repeats; the best is reported (default 3)")
    bs.add_argument("--json", action="store_true", help="end with one line of JSON")
    runtime_options(bs)
    bc = bsub.add_parser("collide", help="full collision step on a dense pile of N balls")
    bc.add_argument("--n", type=int, default=131_072, help="balls (default 131072)")
    bc.add_argument("--steps", type=int, default=50, help="timed steps (default 50)")
    bc.add_argument(
        "--terrain",
        action="store_true",
        help="a flat height-field floor instead of the plane (the plane is timed too, as baseline)",
    )
    bc.add_argument(
        "--asleep",
        action="store_true",
        help="every ball of the pile at rest, as a settled pile ends up (the pile awake is timed too, as baseline)",
    )
    bc.add_argument(
        "--shuffled",
        action="store_true",
        help="the pile's balls numbered in a random order, as balls given in no spatial order are "
        "(the same pile left in that order, not stored in the grid's order, is timed too, as "
        f"baseline; from {REORDER_MIN_BALLS:,} balls, the least the solver reorders)",
    )
    bc.add_argument(
        "--boulder",
        type=float,
        default=0.0,
        metavar="R",
        help="a ball of radius R [m], as dense as the golf balls, dropped at 3 m/s onto the pile (the "
        f"pile alone is timed too, as baseline); from {RADIUS.lo:g} m to the widest that falls between the "
        "walls of the pile's bin (half its width: 0.1 m at --n 300)",
    )
    bc.add_argument(
        "--iterations",
        type=int,
        default=4,
        help="Gauss–Seidel sweeps per step (the scenes' default solver); the last is the shock sweep (default 4, "
        "as the scenes')",
    )
    bc.add_argument("--json", action="store_true", help="end with one line of JSON")
    runtime_options(bc)
    bp = bsub.add_parser("pit", help="the ball pit poured to rest: wall time, compile time and the pile's quality")
    bp.add_argument(
        "--n", type=int, default=PIT_BALLS, help=f"balls (default {PIT_BALLS}, the scene's; the bin scales)"
    )
    bp.add_argument("--t", type=float, default=4.0, help="simulated time [s] (default 4)")
    set_option(bp, "override a key of the pit's scene with a TOML value, e.g. --set contact.e=0.8 (repeatable)")
    bp.add_argument(
        "--every",
        type=float,
        default=None,
        help="also report each stretch of this many simulated seconds: wall time, rebuilds, the pile's figures",
    )
    bp.add_argument(
        "--profile",
        action="store_true",
        help="also report the seconds and launches of each kernel, with Taichi's kernel profiler (which waits "
        "for every launch to end: the wall time is a little longer)",
    )
    bp.add_argument("--json", action="store_true", help="end with one line of JSON")
    runtime_options(bp)
    bd = bsub.add_parser(
        "dispersion", help="a player's shots to landing and to rest (tour_shot) vs one-at-a-time, numpy and scipy"
    )
    bd.add_argument("--n", type=int, default=100_000, help="shots flown to landing (default 100000)")
    bd.add_argument(
        "--rest", type=int, default=None, help="of them rolled out to rest (default 10000, or --n if fewer; 0: none)"
    )
    bd.add_argument(
        "--flight-dt",
        type=float,
        default=0.01,
        help=f"a second RK4 step timed to landing [s], coarser than {DISPERSION_SCENE}'s world.dt (timed first) and "
        "at most 0.05 (default 0.01)",
    )
    bd.add_argument("--json", action="store_true", help="end with one line of JSON")
    runtime_options(bd)
    bst = bsub.add_parser(
        "study", help="eight equal study tasks without Dask, on one and on two local workers: speed-up and overhead"
    )
    bst.add_argument("--tasks", type=int, default=8, help="tasks (default 8)")
    bst.add_argument(
        "--steps", type=int, default=120_000, help="time steps of each task (default 120000: about 8 s on the CI class)"
    )
    bst.add_argument("--json", action="store_true", help="end with one line of JSON")
    br = bsub.add_parser("render", help="seconds per off-screen frame of N balls over a terrain")
    br.add_argument("--n", type=int, default=100_000, help="balls (default 100000)")
    br.add_argument(
        "--frames",
        type=int,
        default=3,
        help="timed frames of each, GGUI and matplotlib; the best is reported (default 3)",
    )
    br.add_argument("--json", action="store_true", help="end with one line of JSON")
    runtime_options(br, window=True)
    bl = bsub.add_parser(
        "lab",
        help="the lab's window running a scene as fast as it goes, hidden: simulated seconds per wall second, "
        "frames per second, and where a frame's time goes",
    )
    scene_options(bl, default="ball_pit", scene_help="a scene file or a bundled scene's name (default ball_pit)")
    bl.add_argument(
        "--seconds", type=float, default=20.0, help="wall seconds of frames after the first step (default 20)"
    )
    bl.add_argument("--size", type=parse_size, default=(1280, 720), help="window size WIDTHxHEIGHT (default 1280x720)")
    bl.add_argument("--screenshot", metavar="PNG", help="also write the last frame's picture, the panels with it")
    bl.add_argument("--json", action="store_true", help="end with one line of JSON")
    runtime_options(bl, window=True)
    bx = bsub.add_parser(
        "reductions",
        help="a list build's reductions over N balls, both ways their threads can meet, against a loop "
        "that reduces nothing",
    )
    bx.add_argument("--n", type=int, default=100_000, help="balls (default 100000)")
    bx.add_argument("--repeats", type=int, default=50, help="timed calls of each (default 50)")
    bx.add_argument("--json", action="store_true", help="end with one line of JSON")
    runtime_options(bx)
    bu = bsub.add_parser(
        "startup",
        help="seconds to start and end commands in fresh processes (warm and cold kernel cache) against the "
        "targets; --kernels SCENE: where one run's start goes, kernel by kernel",
    )
    bu.add_argument(
        "--cache",
        choices=("warm", "cold", "both"),
        default=None,
        help="warm: Taichi's kernel cache holds the kernels; cold: an empty temporary one (default both; "
        "with --kernels, warm)",
    )
    bu.add_argument(
        "--scenes", metavar="A,B,...", help="the bundled scenes whose `run --steps 1` is timed (default: all)"
    )
    bu.add_argument(
        "--repeats", type=int, default=1, help="warm timings per command, 1 to 100; the best is reported (default 1)"
    )
    bu.add_argument(
        "--kernels",
        metavar="SCENE",
        help="instead: one `run SCENE --steps 1` in a fresh process, its stages and each kernel's front end "
        "(Python AST transform) and compile (or cache load) seconds; with --cache cold from an empty cache",
    )
    bu.add_argument("--top", type=int, default=None, help="with --kernels: the N kernels of longest front end")
    bu.add_argument("--json", action="store_true", help="end with one line of JSON")
    runtime_options(bu)
    bu.set_defaults(no_runtime=True)  # (the commands timed run in processes of their own)


def cmd_startup(args: argparse.Namespace) -> int:
    """``ti-golf bench startup``: see :mod:`ti_golf.bench.startup`."""
    from ti_golf.runtime import resolve

    arch, precision = resolve(args.arch, args.precision)  # (the timed processes start from these: checked here)
    if args.top is not None and args.top < 1:
        raise ConfigError("--top", None, f"must be >= 1 kernels (got {args.top})")
    if args.kernels:
        unused = {"scenes": "--scenes", "repeats": "--repeats"}
        refuse_given(args, unused, "with --kernels (one profiled run of its scene)")
        args.cache = args.cache or "warm"
        if args.cache == "both":
            raise ConfigError("--cache", None, "with --kernels: warm or cold (one profiled run)")
        load_scene(args.kernels)  # a bad scene is refused here, in one line, not in the profiled process
        result = start_profile(args.kernels, cold=args.cache == "cold", arch=arch, precision=precision)
        print("\n".join(profile_lines(result, args.top)))
    else:
        if args.top is not None:
            raise ConfigError("--top", None, "has no effect without --kernels")
        if not 1 <= args.repeats <= 100:  # (as bench sweep's: each repeat starts every command again)
            raise ConfigError("--repeats", None, f"must be in [1, 100] (got {args.repeats})")
        scenes = [s.strip() for s in args.scenes.split(",") if s.strip()] if args.scenes is not None else None
        if scenes == []:
            raise ConfigError("--scenes", None, f"names no scene (got {args.scenes!r}); leave it out for all")
        args.cache = args.cache or "both"
        if args.cache == "cold":
            refuse_given(args, {"repeats": "--repeats"}, "with --cache cold (it repeats the warm timings only)")
        unknown = sorted(set(scenes or ()) - set(scene_names()))
        if unknown:
            raise ConfigError(
                "--scenes", None, f"not bundled scenes: {', '.join(unknown)} (`ti-golf scenes` lists them)"
            )
        caches = ("warm", "cold") if args.cache == "both" else (args.cache,)
        result = bench_startup(scenes, caches, args.repeats, arch, precision, say=print)
        load = (
            f"; load average {result['load_average']:.1f} on {result['cpu_count']} cores"
            if result["load_average"]
            else ""
        )
        print(f"{result['passed']} of {result['passed'] + result['failed']} targets met ({arch}, {precision}{load})")
        if result.get("bytecode_stale"):
            print(
                f"note: {len(result['bytecode_stale'])} of ti_golf's modules have no current compiled bytecode, so "
                "every start compiled them (`python -m compileall ti_golf`, or `make setup`, compiles them)"
            )
    if args.json:
        print(to_json(result))
    return 0


MAX_N = 10_000_000
"""The most balls, launches or shots a benchmark takes (ten times the million-ball pour)."""

MAX_STEPS = 1_000_000
"""The most steps ``bench collide`` times: its steps run in launches that hold Ctrl-C."""


N_LEAST = {"pit": 16, "collide": 2}
"""The fewest ``--n`` of the benchmarks that need more than one: a bin of balls, a pair."""


def cmd_bench(args: argparse.Namespace) -> int:  # noqa: C901 (a branch per bench and per option checked)
    """Run the benchmark ``args.bench`` (sweep, collide, pit, reductions, render, dispersion, startup, study) after
    checking its options; print its summary, or its JSON with ``--json``; 0."""
    if args.bench == "startup":
        return cmd_startup(args)
    if args.bench == "study":
        return _bench_study(args)
    if args.bench == "lab":
        return _bench_lab(args)
    least = N_LEAST.get(args.bench, 1)
    if not least <= args.n <= MAX_N:
        raise ConfigError("--n", None, f"must be in [{least:,}, {MAX_N:,}] (got {args.n})")
    if args.bench == "dispersion":
        dt = load_scene(DISPERSION_SCENE).world.dt
        if not dt < args.flight_dt <= 0.05:  # (also false for NaN)
            raise ConfigError(
                "--flight-dt",
                None,
                f"must be coarser than {DISPERSION_SCENE}'s world.dt = {dt:g} s, the step timed first, and at most "
                f"0.05 s: in ({dt:g}, 0.05] s (got {args.flight_dt})",
            )
        rest = min(DISPERSION_REST, args.n) if args.rest is None else args.rest
        if not 0 <= rest <= args.n:
            raise ConfigError("--rest", None, f"must be in [0, --n] shots (got {rest})")
        result = bench_dispersion(n=args.n, rest=rest, flight_dt=args.flight_dt)
    elif args.bench == "reductions":
        if not 1 <= args.repeats <= 10_000:
            raise ConfigError("--repeats", None, f"must be in [1, 10,000] (got {args.repeats})")
        result = bench_reductions(n=args.n, repeats=args.repeats)
    elif args.bench == "render":
        if not 1 <= args.frames <= 1000:
            raise ConfigError("--frames", None, f"must be in [1, 1000] (got {args.frames})")
        _check_ggui()
        result = bench_render(n=args.n, frames=args.frames)
    elif args.bench == "pit":
        if not 0.0 < args.t <= 60.0:  # (also false for NaN)
            raise ConfigError("--t", None, f"must be in (0, 60] s (got {args.t})")
        if args.every is not None and not 0.0 < args.every <= args.t:  # (also false for NaN)
            raise ConfigError("--every", None, f"must be in (0, --t] s (got {args.every})")
        refuse_unread_keys(args.overrides, "bench pit", POUR_NOT_READ)
        result = bench_pit(n=args.n, t=args.t, overrides=args.overrides, every=args.every)
    elif args.bench == "collide":
        if not 1 <= args.steps <= MAX_STEPS:
            raise ConfigError("--steps", None, f"must be in [1, {MAX_STEPS:,}] (got {args.steps})")
        if not 1 <= args.iterations <= 100:
            raise ConfigError("--iterations", None, f"must be in [1, 100] (got {args.iterations})")
        _check_boulder(args.boulder, args.n)
        balls = args.n + (args.boulder > 0)  # (the boulder is a ball of the pile's solver)
        if args.shuffled and balls < REORDER_MIN_BALLS:  # (both runs would keep the random order)
            least = REORDER_MIN_BALLS - (args.boulder > 0)
            raise ConfigError(
                "--shuffled",
                None,
                f"has no effect on {args.n:,} balls{' and the boulder' if args.boulder > 0 else ''}: the solver stores the balls in the grid's order from "
                f"{REORDER_MIN_BALLS:,} balls on (smaller piles stay in the CPU's caches in any order), so both "
                f"runs would keep the random order: give --n >= {least:,}",
            )
        result = bench_collide(
            n=args.n,
            steps=args.steps,
            terrain=args.terrain,
            asleep=args.asleep,
            shuffled=args.shuffled,
            iterations=args.iterations,
            boulder=args.boulder,
        )
    else:
        if not 1e-5 <= args.dt <= 1.0:  # (also false for NaN)
            raise ConfigError("--dt", None, f"must be in [1e-05, 1] s (got {args.dt})")
        if not 1 <= args.repeats <= 100:
            raise ConfigError("--repeats", None, f"must be in [1, 100] (got {args.repeats})")
        result = bench_sweep(n=args.n, dt=args.dt, repeats=args.repeats)
    if args.json:
        print(to_json(result))
    if result.get("interrupted"):
        raise KeyboardInterrupt(f"at t = {result['t_s']:.4g} s; the figures of the pour so far are printed above")
    return 0


def _check_ggui() -> None:
    """Refuse ``bench render`` where GGUI does not draw (it would time the matplotlib fallback
    against itself): a backend GGUI is not drawn with (``TI_GOLF_ARCH=vulkan``; ``--arch`` offers
    cpu and cuda alone), or no window can be opened."""
    from ti_golf.render import arch_ggui_refuses, window_problem

    problem = window_problem(on_screen=False)
    if problem:
        option = "--arch" if arch_ggui_refuses() else "bench render"
        raise ConfigError(option, None, f"times GGUI against matplotlib, and GGUI {problem}")


def _check_boulder(radius: float, n: int) -> None:
    """Refuse a ``bench collide --boulder`` radius [m] other than 0 (no boulder) that is below a
    scene's least ball radius or too wide for the bin of the pile of ``n`` balls
    (:func:`~ti_golf.bench.collide.widest_boulder`), or the largest a scene takes."""
    if radius == 0.0:
        return
    widest = min(RADIUS.hi or math.inf, widest_boulder(n))
    if not RADIUS.lo <= radius <= widest:  # (also false for NaN)
        raise ConfigError(
            "--boulder",
            None,
            f"must be 0 (no boulder) or a radius in [{RADIUS.lo:g}, {widest:g}] m for --n {n}: from a scene's "
            f"least ball radius to the widest that falls between the walls of the bin of {n:,} balls "
            f"(got {radius})",
        )


MAX_STUDY_TASKS = 1_000
"""The most tasks ``bench study`` runs (each three times: without Dask, on one and on two workers)."""
MAX_STUDY_STEPS = 10_000_000
"""The most steps of each ``bench study`` task: about 11 minutes a task on the CI class."""


def _bench_study(args: argparse.Namespace) -> int:
    from ti_golf.study.benchmark import bench_study
    from ti_golf.study.cluster import require_dask

    if not 2 <= args.tasks <= MAX_STUDY_TASKS:
        raise ConfigError("--tasks", None, f"must be in [2, {MAX_STUDY_TASKS:,}] (got {args.tasks})")
    if not 1 <= args.steps <= MAX_STUDY_STEPS:
        raise ConfigError("--steps", None, f"must be in [1, {MAX_STUDY_STEPS:,}] (got {args.steps})")
    require_dask()
    result = bench_study(n=args.tasks, steps=args.steps)
    if args.json:
        print(to_json(result))
    return 0


def _bench_lab(args: argparse.Namespace) -> int:
    from ti_golf.lab.window import check_display

    if not 0.0 < args.seconds <= 3600.0:  # (also false for NaN)
        raise ConfigError("--seconds", None, f"must be in (0, 3600] s (got {args.seconds})")
    check_writable(args.screenshot, "--screenshot", (".png",))
    refuse_unread_keys(args.overrides, "bench lab")
    load_scene(args.scene, args.overrides)  # a bad scene is refused before the window opens
    check_display(on_screen=False)
    result = bench_lab(args.scene, args.overrides, args.seconds, args.size, args.screenshot)
    if args.json:
        print(to_json(result))
    return 0
