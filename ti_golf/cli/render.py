"""``ti-golf render``: run a scene and write a picture of its balls (GGUI off screen, else matplotlib)."""

from __future__ import annotations

import argparse
import math
import time

from ti_golf.cli._common import (
    Progress,
    check_steps_span,
    check_until,
    check_writable,
    parse_size,
    refuse_given,
    refuse_replaced,
    refuse_unread_keys,
    resume_option,
    runtime_options,
    say_unfinished,
    scene_options,
    scene_or_saved_run,
)
from ti_golf.errors import ConfigError
from ti_golf.render import BACKENDS, CAMERAS, COLOR_BY, render
from ti_golf.scene.checks import TIME_LIMIT
from ti_golf.scene.readers import STILL_NOT_READ
from ti_golf.sim.given import steps_to_run


def add_parser(sub: argparse._SubParsersAction) -> argparse.ArgumentParser:
    """Add the ``render`` subcommand to ``ti-golf``'s subparsers; returns its parser."""
    p = sub.add_parser("render", help="run a scene and write a PNG of its balls (GGUI off screen, else matplotlib)")
    scene_options(
        p,
        default="",
        scene_help="scene file, or the name of a bundled scene (see `ti-golf scenes`); none with --resume",
    )
    resume_option(p, "draw it where it stopped, or --t (or --steps) later")
    g = p.add_mutually_exclusive_group()
    g.add_argument(
        "--t",
        type=float,
        help="simulated time before the picture [s] (default: the initial state; world.t_end with --until)",
    )
    g.add_argument("--steps", type=int, help="time steps before the picture")
    p.add_argument("--until", choices=("rest", "landed"), help="stop early once every ball is at rest / has landed")
    p.add_argument("--out", required=True, help="the PNG to write")
    p.add_argument("--camera", choices=CAMERAS, default="iso", help="camera preset (default iso)")
    p.add_argument(
        "--size", type=parse_size, default=(1280, 720), metavar="WxH", help="picture size (default 1280x720)"
    )
    p.add_argument("--color-by", choices=COLOR_BY, default="status", help="ball colours (default status)")
    p.add_argument("--trails", action="store_true", help="draw each ball's path (records about 200 samples)")
    p.add_argument("--fov", type=float, default=45.0, help="vertical field of view [deg] (default 45)")
    p.add_argument(
        "--backend",
        choices=BACKENDS,
        default="auto",
        help="auto: GGUI, else matplotlib with a note (default); ggui: fail without Vulkan",
    )
    runtime_options(p)
    return p


def cmd_render(args: argparse.Namespace) -> int:
    """Run ``args.scene`` (or the saved run ``--resume``) for ``--t`` / ``--steps`` (default: not at
    all) and write ``--out``."""
    check_writable(args.out, "--out", (".png",))
    if args.t is not None and not (math.isfinite(args.t) and 0 <= args.t <= TIME_LIMIT):
        raise ConfigError("--t", None, f"must be in [0, {TIME_LIMIT:g}] seconds (got {args.t})")
    if args.steps is not None and args.steps < 0:
        raise ConfigError("--steps", None, f"must be >= 0 (got {args.steps})")
    w, h = args.size
    if not 1.0 <= args.fov <= 170.0:
        raise ConfigError("--fov", None, f"must be in [1, 170] degrees (got {args.fov})")
    if args.t is not None or args.steps is not None or not args.until:  # (world.t_end: the length with --until)
        refuse_replaced(args.overrides, {"world.t_end": "--t or --steps, or without --until"})
    if args.t == 0 or args.steps == 0 or (args.t is None and args.steps is None and not args.until):
        still = "on a picture of the initial state, which simulates nothing (give --t, --steps or --until)"
        refuse_given(args, {"until": "--until", "precision": "--precision"}, still)
        if not args.resume:  # (a saved run's own refusal follows: its keys act on its next steps)
            refuse_unread_keys(args.overrides, "render", STILL_NOT_READ)
    sim = scene_or_saved_run(args, "render")
    check_until(args.until, sim)
    check_steps_span(args.steps, sim.dt)
    if args.steps is not None:
        steps = args.steps
    else:  # default: the initial state, or up to world.t_end with --until
        duration = args.t if args.t is not None else (sim.scene.world.t_end if args.until else 0.0)
        steps = steps_to_run(duration, None, sim.dt, sim.scene.world.t_end, sim.scene)
    if steps == 0 and args.resume and args.overrides:  # (a saved run takes only keys that act on its next steps)
        raise ConfigError("--set", None, "has no effect on a saved run drawn as it is: give --t, --steps or --until")
    if steps == 0 and args.trails:  # (nothing is simulated: no path to draw)
        raise ConfigError("--trails", None, "has no effect without a time to simulate (--t, --steps or --until)")
    rec = None
    interrupted = False
    progress = Progress()
    t_run = time.perf_counter()
    try:
        if steps > 0:
            rec = sim.run(
                steps=steps,
                until=args.until,
                record_every=max(1, steps // 200) if args.trails else 0,
                progress=progress,
            )
    except KeyboardInterrupt:  # Ctrl-C or SIGTERM: the picture shows the state reached
        interrupted = True
    finally:
        progress.close()
    t0 = time.perf_counter()
    ran = f"simulated in {t0 - t_run:.2f} s, " if steps > 0 else ""
    used = render(
        sim,
        args.out,
        camera=args.camera,
        size=(w, h),
        color_by=args.color_by,
        trails=rec if args.trails and rec is not None else None,
        fov=args.fov,
        backend=args.backend,
    )
    print(
        f"wrote {args.out} ({used}, {sim.n} ball(s) at t = {sim.t:.4g} s; {ran}drawn in {time.perf_counter() - t0:.2f} s)"
    )
    if args.until and steps > 0 and not interrupted:
        say_unfinished(sim, args)
    if interrupted:
        raise KeyboardInterrupt(f"at t = {sim.t:.4g} s; the picture of that state is saved in {args.out}")
    return 0
