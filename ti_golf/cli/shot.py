"""``ti-golf shot``: one launch as a launch monitor gives it, and the numbers golfers read."""

from __future__ import annotations

import argparse
import json
import math
import sys

from ti_golf.cli._common import refuse_unread_keys, runtime_options, scene_options
from ti_golf.cli._launch import (
    LABELS,
    fmt,
    launch_line,
    launch_options,
    read_launch,
    unit_label,
    units_option,
)
from ti_golf.golf.aero_fit import beyond_the_fit
from ti_golf.golf.rollout import has_ground
from ti_golf.golf.shots import shots
from ti_golf.scene.launch_monitor import UNITS
from ti_golf.scene.loader import load_scene
from ti_golf.scene.readers import SHOTS_NOT_READ
from ti_golf.sim.results import GOLFER_COLUMNS


def add_parser(sub: argparse._SubParsersAction) -> None:
    """Add ``shot`` to ``ti-golf``'s subcommands."""
    s = sub.add_parser(
        "shot",
        help="fly one launch-monitor launch to rest: carry, total, roll, offline, apex, hang time, landing",
        description="Fly one shot given as a launch monitor reports it and print the numbers golfers read. "
        "Carry is measured to launch height; total and roll need the ball to bounce and roll to rest on "
        "the scene's ground (tour_shot: turf).",
    )
    scene_options(s)
    launch_options(s)
    units_option(s)
    s.add_argument("--json", action="store_true", help="print one line of JSON instead (the same numbers and units)")
    runtime_options(s)


def cmd_shot(args: argparse.Namespace) -> int:
    """Fly one shot of ``args.scene`` from the launch given (rolled out where the scene has a
    ground) and print its carry, apex, landing and rest in ``--units`` (one JSON line with
    ``--json``); 0."""
    units = UNITS[args.units]
    refuse_unread_keys(args.overrides, "shot", SHOTS_NOT_READ)
    scene = load_scene(args.scene, args.overrides)
    launch = read_launch(args, scene, units)
    to_rest = has_ground(scene)
    res = shots(scene, launch, to_rest=to_rest)
    values = {k: float(v[0]) for k, v in res.columns(units).items()}
    note = beyond_the_fit(scene, launch.speed, launch.spin)
    if note and args.json:
        print(f"ti-golf: {note}", file=sys.stderr)
    if args.json:
        out: dict[str, object] = {
            "scene": scene.name,
            "units": units.name,
            "launch": {k: float(v) for k, v in launch.in_units(units).items()},
        }
        out.update({k: (round(v, 6) if math.isfinite(v) else None) for k, v in values.items()})
        out["landed"], out["at_rest"] = bool(res.landed[0]), bool(res.at_rest[0])
        print(json.dumps(out))
        return 0
    print(f"{scene.name}: {launch_line(launch, units)}")
    if not res.landed[0]:
        print(f"the ball did not land within world.t_max = {scene.world.t_max:g} s")
        return 0
    for (name, kind), v in zip(GOLFER_COLUMNS, values.values()):
        note = "  (+ right of the target line)" if name == "offline" else ""
        print(f"  {LABELS[name]:<11} {fmt(v, kind, units):>8} {unit_label(kind, units)}{note}")
    if not res.apex[0] > 0.0:
        print("  (the ball never rose above its launch height: no flight, it was down through it at once)")
    if not to_rest:
        print("  (total and roll need a ground to roll out on: the scene has none)")
    elif not res.at_rest[0]:
        print(f"  (the ball was still moving after world.t_max = {scene.world.t_max:g} s: no total)")
    if note:
        print(note)
    return 0
