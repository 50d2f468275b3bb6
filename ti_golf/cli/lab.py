"""``ti-golf lab [SCENE]``: the lab application in a window (report §2.4, "lab3"; see
:mod:`ti_golf.lab.window`): pick a scene, change its parameters, Start, Stop, Continue, Step,
Reset t0, and Save the run, its plots and a screenshot. ``--screenshot PNG`` draws the window off
screen instead (no display needed), after ``--t`` simulated seconds, and writes its picture."""

from __future__ import annotations

import argparse
import math
from pathlib import Path

from ti_golf.cli._common import (
    check_writable,
    given,
    parse_size,
    refuse_unread_keys,
    refuse_without,
    runtime_options,
    scene_options,
)
from ti_golf.errors import ConfigError
from ti_golf.lab.app import DEFAULT_SCENE, Lab
from ti_golf.lab.window import LabWindow, check_display
from ti_golf.scene.loader import load_scene


def add_parser(sub: argparse._SubParsersAction) -> argparse.ArgumentParser:
    """Add the ``lab`` subcommand to ``ti-golf``'s subparsers; returns its parser."""
    p = sub.add_parser(
        "lab",
        help="the lab in a window: pick a scene, change its parameters, start, stop, continue, reset t0, save",
    )
    scene_options(
        p,
        default=DEFAULT_SCENE,
        scene_help=f"the scene to open: a scene file or a bundled scene's name (default {DEFAULT_SCENE}); "
        "the window offers every bundled scene too",
        example="air.C_D=0.25",
    )
    p.add_argument(
        "--out",
        default=".",
        metavar="FOLDER",
        help="where Save (S) writes SCENE_NNN.npz, its trajectory, speed and spin plots and a screenshot "
        "(default: the current folder)",
    )
    p.add_argument(
        "--speed",
        type=float,
        default=1.0,
        help="simulated seconds per second of a running simulation (default 1: real time; 0: as fast as it goes)",
    )
    p.add_argument("--size", type=parse_size, default=(1280, 720), help="window size WIDTHxHEIGHT (default 1280x720)")
    p.add_argument(
        "--screenshot",
        metavar="PNG",
        help="draw the window off screen (no display needed: Vulkan's software driver will do) and write its "
        "picture, the panels with it, instead of opening it",
    )
    p.add_argument(
        "--t",
        type=float,
        default=0.0,
        metavar="SECONDS",
        help="with --screenshot: simulated seconds the scene runs before the picture (default 0: at t0)",
    )
    runtime_options(p, window=True)
    return p


def cmd_lab(args: argparse.Namespace) -> int:
    """Open the lab on ``args.scene`` until its window is closed; 0 then."""
    out = Path(args.out)
    if not args.out.strip():
        raise ConfigError("--out", None, "needs a folder name (got an empty path)")
    if out.exists() and not out.is_dir():
        raise ConfigError("--out", None, f"{args.out!r} is a file, not a folder (Save writes several files into it)")
    if not out.is_dir():
        raise ConfigError("--out", None, f"folder {args.out!r} does not exist (Save writes several files into it)")
    check_writable(str(out / "lab.npz"), "--out")
    if not (math.isfinite(args.speed) and args.speed >= 0):
        raise ConfigError("--speed", None, f"must be a finite number >= 0 (got {args.speed!r})")
    if not (math.isfinite(args.t) and args.t >= 0):
        raise ConfigError("--t", None, f"must be a number of seconds >= 0 (got {args.t!r})")
    if given(args, "t") and not args.screenshot:
        raise ConfigError("--t", None, "goes with --screenshot (the window runs the scene with Start)")
    check_writable(args.screenshot, "--screenshot", (".png",))
    if args.screenshot:  # (no window runs: the window's pace and its Save folder would have no effect)
        refuse_without(args, {"speed": "--speed", "out": "--out"}, "a window (leave out --screenshot)")
    refuse_unread_keys(args.overrides, "lab")
    scene = load_scene(args.scene, args.overrides)  # a bad scene is refused before any window opens
    if args.t > scene.world.t_end:
        raise ConfigError(
            "--t", None, f"must be at most the scene's world.t_end = {scene.world.t_end:g} s (got {args.t:g})"
        )
    check_display(on_screen=not args.screenshot)
    lab = Lab(args.scene, args.overrides, speed=args.speed or None)
    if args.screenshot:
        return _screenshot(lab, args.size, args.t, args.screenshot)
    try:
        LabWindow(lab, args.size, out_dir=out).run()
    except KeyboardInterrupt:
        return 130
    return 0


def _screenshot(lab: Lab, size: tuple[int, int], t: float, path: str) -> int:
    """Draw the lab's window off screen after ``t`` simulated seconds of its scene and write its
    picture to ``path`` (as the window's Save writes its screenshot); 0."""
    window = LabWindow(lab, size, show_window=False, rates=False)
    try:
        window.frame(max_steps=0)
        steps = math.ceil(t / lab.sim.dt - 1e-9)
        if steps:
            lab.start()
            window.frame(max_steps=steps)
            lab.stop()
            window.frame(max_steps=0)
        window.screenshot(path)
    finally:
        window.close()
    print(f"wrote {path}: the lab window, {size[0]}x{size[1]}, at t = {lab.sim.t:.4g} s")
    return 0
