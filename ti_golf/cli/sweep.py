"""``ti-golf sweep``: one ball per launch condition, all flown at once; carry and best angle."""

from __future__ import annotations

import argparse
import time

import numpy as np

from ti_golf.cli._common import (
    check_plot,
    check_writable,
    options_named,
    plot_help,
    refuse_replaced,
    refuse_unread_keys,
    refuse_without,
    runtime_options,
    scene_options,
)
from ti_golf.cli._launch import golfer_table
from ti_golf.errors import ConfigError
from ti_golf.golf.aero_fit import beyond_the_fit
from ti_golf.golf.rollout import has_ground
from ti_golf.golf.sweep import SweepResult, sweep
from ti_golf.scene.balls import launch_position
from ti_golf.scene.launch_monitor import UNITS
from ti_golf.scene.loader import load_scene
from ti_golf.scene.readers import FLIGHTS_NOT_READ, SWEEP_NOT_READ
from ti_golf.scene.schema import Scene, parse_range
from ti_golf.signals import KeptInterrupt

TRAJECTORIES = 21
"""The trajectories ``--plot`` draws by default."""

SWEEP_OPTIONS = {"angles_deg": "--angles", "speeds": "--speeds", "spins": "--spins"}
"""The option of each argument of :func:`ti_golf.golf.sweep.sweep` that ``ti-golf sweep`` gives."""


def add_parser(sub: argparse._SubParsersAction) -> None:
    """Add ``sweep`` to ``ti-golf``'s subcommands."""
    s = sub.add_parser("sweep", help="fly one ball per launch condition, all at once, and report carry")
    scene_options(s)
    s.add_argument(
        "--angles",
        help="elevations [deg]: START:STOP:STEP (STOP included) or a,b,c (default: the scene's sweep.angles, "
        "else its launch.angle_deg)",
    )
    s.add_argument(
        "--speeds", help="launch speeds [m/s]: START:STOP:STEP or a,b,c (default: sweep.speeds, else launch.speed)"
    )
    s.add_argument(
        "--spins",
        help="spin magnitudes [rad/s] along the scene's spin axis: START:STOP:STEP or a,b,c (default: sweep.spins, "
        "else the launch's spin)",
    )
    s.add_argument("--out", help="write one CSV row per launch condition")
    s.add_argument("--plot", help=plot_help("trajectories (side view) and carry vs angle"))
    s.add_argument(
        "--trajectories", type=int, default=TRAJECTORIES, help=f"trajectories drawn in --plot (default {TRAJECTORIES})"
    )
    s.add_argument(
        "--to-rest",
        action="store_true",
        help="also bounce and roll every ball to rest on the scene's ground, for total and roll (CSV and --units)",
    )
    s.add_argument(
        "--units",
        choices=tuple(UNITS),
        help="also print one row per launch condition of the numbers golfers read (carry, total, roll, "
        "offline, apex, hang time, land angle, speed and spin) in imperial (yd, mph, rpm) or metric "
        "(m, m/s, rad/s) units",
    )
    runtime_options(s)


def _parse_opt_range(text: str | None, option: str) -> tuple[float, ...] | None:
    return None if text is None else parse_range(text, option, None)


def cmd_sweep(args: argparse.Namespace) -> int:
    """Fly a ball per launch condition of ``args.scene`` (``--angles``, ``--speeds``, ``--spins`` or
    the scene's [sweep]) in one launch, print the best carry, and write the table (``--out``)
    and its plot (``--plot``); 0."""
    check_writable(args.out, "--out", (".csv",))
    if args.trajectories < 0:
        raise ConfigError("--trajectories", None, f"must be >= 0 (got {args.trajectories})")
    if not args.plot:
        refuse_without(args, {"trajectories": "--trajectories"}, "--plot (which draws them)")
    check_plot(args.plot)
    replaced = {}
    if args.angles is not None:
        replaced.update({"sweep.angles": "--angles", "launch.angle_deg": "--angles"})
    if args.speeds is not None:
        replaced.update({"sweep.speeds": "--speeds", "launch.speed": "--speeds"})
    if args.spins is not None:
        replaced["sweep.spins"] = "--spins"
    refuse_replaced(args.overrides, replaced)
    refuse_unread_keys(
        args.overrides, "sweep" + " --to-rest" * args.to_rest, FLIGHTS_NOT_READ if args.to_rest else SWEEP_NOT_READ
    )
    scene = load_scene(args.scene, args.overrides)
    if args.to_rest:
        _check_to_rest(args, scene)
    angles = _parse_opt_range(args.angles, "--angles")
    speeds = _parse_opt_range(args.speeds, "--speeds")
    spins = _parse_opt_range(args.spins, "--spins")
    t0 = time.perf_counter()
    stopped = None
    try:
        with options_named(SWEEP_OPTIONS):
            res = sweep(
                scene, angles, speeds, spins, trajectories=args.trajectories if args.plot else 0, to_rest=args.to_rest
            )
    except KeptInterrupt as stop:  # the flights (one launch, waited for) and the rests reached: written below
        res, stopped = stop.kept, stop
    elapsed = time.perf_counter() - t0
    n = res.angle_deg.size
    landed = int(res.flight.landed.sum())
    print(
        f"{scene.name}: {n} launch condition{'s' if n != 1 else ''}, {landed} landed, {elapsed:.2f} s "
        f"({scene.world.integrator}, dt = {scene.world.dt:g} s)"
    )
    if landed == 0:
        print(f"no ball landed within world.t_max = {scene.world.t_max:g} s")
    else:
        b = res.best()
        f = res.flight
        print(
            f"best: angle {res.angle_deg[b]:.4f} deg, speed {res.speed_mps[b]:g} m/s, spin {res.spin_radps[b]:g} rad/s"
            f" -> carry {res.carry[b]:.4f} m (apex {f.apex[b] - launch_position(scene)[1]:.2f} m, "
            f"flight {f.flight_time[b]:.3f} s, lands at {f.landing_angle[b]:.1f} deg, {f.landing_speed[b]:.2f} m/s)"
        )
        note = beyond_the_fit(scene, res.speed_mps, res.spin_radps)
        if note:
            print(note)
        edge = edge_of_angles(res.angle_deg, res.angle_deg[b])
        if edge:
            print(f"the best angle is the {edge} swept: the longest carry may lie beyond it")
    if args.to_rest and stopped is None and res.shots is not None and int(res.shots.at_rest.sum()) < landed:
        print(
            f"{landed - int(res.shots.at_rest.sum())} of the {landed} balls landed were still moving at "
            f"world.t_max = {scene.world.t_max:g} s: no total or roll for them (NaN)"
        )
    if args.units and res.shots is not None:
        u = UNITS[args.units]
        first = {
            "angle [deg]": res.angle_deg,
            f"speed [{u.speed_label}]": np.round(res.speed_mps / u.speed, 1),
            f"spin [{u.spin_label}]": np.round(res.spin_radps / u.spin),
        }
        print("\n".join(golfer_table(res.shots, UNITS[args.units], first)))
    if args.out:
        res.to_csv(args.out)
        print(f"wrote {args.out}")
    if args.plot:
        from ti_golf.render.plots import plot_sweep  # (matplotlib: imported only to plot)

        plot_sweep(res, args.plot)
        print(f"wrote {args.plot}")
    if stopped is not None:
        raise KeyboardInterrupt(_stopped_where(args, res, landed))
    return 0


def _check_to_rest(args: argparse.Namespace, scene: Scene) -> None:
    """Refuse ``--to-rest`` where there is no ground to rest on, or nothing shows total and roll."""
    if not has_ground(scene):
        raise ConfigError(
            "--to-rest", None, f"{scene.name} has no ground to come to rest on (world.ground, [terrain] or planes)"
        )
    if not (args.out or args.units):
        raise ConfigError("--to-rest", None, "has no effect without --out or --units (which show total and roll)")


def _stopped_where(args: argparse.Namespace, res: SweepResult, landed: int) -> str:
    """What a sweep that Ctrl-C or SIGTERM stopped ran, and where its results are."""
    kept = ", ".join(p for p in (args.out, args.plot) if p)
    saved = f"; saved in {kept}" if kept else ""
    if args.to_rest and res.shots is not None and res.shots.rolled_out:
        rested = int(res.shots.at_rest.sum())
        return f"during the roll-out: {rested} of the {landed} balls landed had come to rest{saved}"
    rolled = ", before the roll-out" if args.to_rest else ""
    return f"during the sweep's flights, one kernel launch: they ran to their end{rolled}{saved}"


def edge_of_angles(angles: np.ndarray, best: float) -> str | None:
    """``"highest"`` or ``"lowest"`` when the best launch angle ``best`` [deg] is an end of the
    ``angles`` swept (more than one), where the carry may still grow beyond the range; else ``None``."""
    values = np.unique(angles)
    if values.size < 2:
        return None
    return "highest" if best == values[-1] else "lowest" if best == values[0] else None
