"""The launch-monitor options and the golfer's table that ``ti-golf shot``, ``dispersion`` and
``sweep`` share: a launch read from ``--speed``, ``--vla`` ... or the scene, and the numbers golfers read."""

from __future__ import annotations

import argparse
import math

import numpy as np

from ti_golf.cli._common import refuse_replaced
from ti_golf.errors import ConfigError
from ti_golf.scene.launch_monitor import UNITS, MonitorLaunch, Units, check_launch, scene_launch
from ti_golf.scene.schema import Scene
from ti_golf.sim.results import GOLFER_COLUMNS, Shots

LAUNCH_OPTIONS = {"speed": "--speed", "vla_deg": "--vla", "hla_deg": "--hla", "spin": "--spin", "axis_deg": "--axis"}
"""The option of each launch-monitor value."""

SCENE_KEYS = {
    "speed": "launch.speed",
    "vla_deg": "launch.angle_deg",
    "hla_deg": "launch.direction_deg",
    "spin": "launch.spin",
    "axis_deg": "launch.spin",
}
"""The scene's keys that a launch value comes from when its option is not given."""

LABELS = {
    "carry": "carry",
    "total": "total",
    "roll": "roll",
    "offline": "offline",
    "apex": "apex",
    "hang_time": "hang time",
    "land_angle": "land angle",
    "land_speed": "land speed",
    "land_spin": "land spin",
}


def units_option(p: argparse.ArgumentParser) -> None:
    """``--units imperial|metric``."""
    p.add_argument(
        "--units",
        choices=tuple(UNITS),
        default="imperial",
        help="units of the launch options and of the output: imperial (mph, rpm, yards; the default) "
        "or metric (m/s, rad/s, metres); angles are in degrees in both",
    )


def launch_options(p: argparse.ArgumentParser) -> None:
    """The launch-monitor options: ball speed, VLA, HLA, total spin and spin axis (default: the scene's launch)."""
    g = p.add_argument_group("launch (as a launch monitor reports it; default: the scene's [launch])")
    g.add_argument("--speed", type=float, help="ball speed [mph; m/s with --units metric]")
    g.add_argument("--vla", type=float, help="vertical launch angle above the horizontal [deg]")
    g.add_argument("--hla", type=float, help="horizontal launch angle [deg], + right of the target line (default 0)")
    g.add_argument("--spin", type=float, help="total spin [rpm; rad/s with --units metric]")
    g.add_argument(
        "--axis",
        type=float,
        help="spin axis [deg]: + tilts the lift to the right, a fade for a right-handed player; − a draw",
    )


def refuse_replaced_launch(args: argparse.Namespace) -> None:
    """A ``--set`` of a ``[launch]`` key that the launch options given replace (see
    :func:`read_launch`) is refused: it would have no effect."""
    keys = {"speed": "launch.speed", "vla": "launch.angle_deg", "hla": "launch.direction_deg"}
    replaced = {key: f"--{option}" for option, key in keys.items() if getattr(args, option) is not None}
    if args.spin is not None and args.axis is not None:
        replaced["launch.spin"] = "--spin with --axis"
    refuse_replaced(args.overrides, replaced)


def read_launch(args: argparse.Namespace, scene: Scene, units: Units) -> MonitorLaunch:
    """The launch of the options given, the scene's launch for the others, checked (SI)."""
    refuse_replaced_launch(args)
    if scene.launch is None:
        missing = [option for option in ("--speed", "--vla", "--spin") if getattr(args, option[2:]) is None]
        if missing:
            raise ConfigError(
                missing[0],
                None,
                f"required: scene {scene.name!r} has no [launch] table to take it from (give --speed, --vla and --spin)",
            )
    values = scene_launch(scene).in_units(units)
    named = {}  # what an error names: the option given, or the scene's key the value came from
    for name, option in LAUNCH_OPTIONS.items():
        if getattr(args, option[2:]) is not None:
            values[name] = getattr(args, option[2:])
            named[name] = option
        else:
            named[name] = f"{SCENE_KEYS[name]} of scene {scene.name!r} (as a shot's {option[2:]})"
    launch = MonitorLaunch.from_units(values, units)
    check_launch(launch, units, named)
    return launch


def launch_line(launch: MonitorLaunch, units: Units, signed: bool = True) -> str:
    """``ball speed 123.0 mph, VLA 16.1°, HLA +0.0°, spin 7124 rpm, axis +0.0°`` (HLA and axis
    without their sign unless ``signed``: for standard deviations)."""
    u = launch.in_units(units)
    sign = "+" if signed else ""
    spin = f"{float(u['spin']):.0f}" if units.spin_label == "rpm" else f"{float(u['spin']):.1f}"
    return (
        f"ball speed {float(u['speed']):.1f} {units.speed_label}, VLA {float(u['vla_deg']):.1f}°, "
        f"HLA {float(u['hla_deg']):{sign}.1f}°, spin {spin} {units.spin_label}, axis {float(u['axis_deg']):{sign}.1f}°"
    )


def fmt(value: float, kind: str, units: Units) -> str:
    """A value of a :data:`GOLFER_COLUMNS` kind, in ``units``, with as many digits as golfers read."""
    if not math.isfinite(value):
        return "-"
    digits = 0 if kind == "spin" and units.spin_label == "rpm" else 2 if kind == "s" else 1
    return f"{round(value, digits) + 0.0:.{digits}f}"  # (+ 0.0: no "-0.0" for a roll of a few millimetres back)


def unit_label(kind: str, units: Units) -> str:
    """The unit of a :data:`GOLFER_COLUMNS` kind in ``units``."""
    return getattr(units, f"{kind}_label") if kind in ("distance", "speed", "spin") else kind


def golfer_table(res: Shots, units: Units, first: dict[str, np.ndarray] | None = None) -> list[str]:
    """Rows of the golfer columns, one per shot, with ``first`` columns (already formatted
    strings or numbers) in front; a header line first."""
    cols = list(res.columns(units).values())
    heads = [f"{LABELS[name]} [{unit_label(kind, units)}]" for name, kind in GOLFER_COLUMNS]
    pre = first or {}
    widths = [max(len(h), 7) for h in list(pre) + heads]
    lines = ["  ".join(h.rjust(w) for h, w in zip(list(pre) + heads, widths))]
    for i in range(len(res)):
        cells = [f"{float(v[i]):g}" for v in pre.values()]
        cells += [fmt(float(c[i]), kind, units) for c, (_, kind) in zip(cols, GOLFER_COLUMNS)]
        lines.append("  ".join(c.rjust(w) for c, w in zip(cells, widths)))
    return lines
