"""``ti-golf dispersion``: N shots of a player's spread flown at once; where they land and stop."""

from __future__ import annotations

import argparse
import json
import math
import sys
import time

from ti_golf.cli._common import (
    Progress,
    check_plot,
    check_writable,
    given,
    plot_help,
    refuse_unread_keys,
    runtime_options,
    scene_options,
    seed_value,
)
from ti_golf.cli._launch import LAUNCH_OPTIONS, launch_line, launch_options, read_launch, units_option
from ti_golf.errors import ConfigError
from ti_golf.golf.dispersion import MAX_SHOTS, PLAYER_SPREAD, Dispersion, dispersion, held_at_limits
from ti_golf.golf.rollout import has_ground
from ti_golf.golf.shots import FLIGHT_DT_RANGE
from ti_golf.scene.launch_monitor import (
    LAUNCH_LIMITS,
    UNITS,
    MonitorLaunch,
    Units,
    check_launch,
    field_factor,
    field_label,
)
from ti_golf.scene.loader import load_scene
from ti_golf.scene.readers import LANDING_NOT_READ, SHOTS_NOT_READ
from ti_golf.signals import KeptInterrupt
from ti_golf.sim.results import Shots

SPREAD = PLAYER_SPREAD
SPREAD_OPTIONS = {name: f"--sd-{option[2:]}" for name, option in LAUNCH_OPTIONS.items()}
"""The option of each standard deviation."""


def add_parser(sub: argparse._SubParsersAction) -> None:
    """Add ``dispersion`` to ``ti-golf``'s subcommands."""
    d = sub.add_parser(
        "dispersion",
        help="fly N shots of a player's spread at once: carry, total, offline, landing ellipses and a plot",
        description="Draw N launches about a mean launch with a player's standard deviations (normal, "
        "independent, seeded), fly them all at once to landing and roll them out to rest on the "
        "scene's ground, and report the spread and the 68 % and 95 % landing ellipses.",
    )
    scene_options(d)
    d.add_argument("--n", type=int, default=10_000, help=f"shots, 2 to {MAX_SHOTS} (default 10000)")
    d.add_argument(
        "--seed", type=seed_value, default=0, help="seed of the draw (default 0): a seed gives the same shots"
    )
    launch_options(d)
    g = d.add_argument_group("spread (standard deviations, in the units of the launch options)")
    g.add_argument("--sd-speed", type=float, help="of ball speed [mph; m/s with --units metric] (default 1.5 mph)")
    g.add_argument("--sd-vla", type=float, help=f"of VLA [deg] (default {SPREAD.vla_deg:g})")
    g.add_argument("--sd-hla", type=float, help=f"of HLA [deg] (default {SPREAD.hla_deg:g})")
    g.add_argument("--sd-spin", type=float, help="of total spin [rpm; rad/s with --units metric] (default 300 rpm)")
    g.add_argument("--sd-axis", type=float, help=f"of spin axis [deg] (default {SPREAD.axis_deg:g})")
    units_option(d)
    d.add_argument(
        "--flight-dt",
        type=float,
        help="step of the flight to landing [s] (default: the scene's world.dt; the roll-out always "
        "uses world.dt). RK4's carry error at 0.01 s is below a micrometre (docs: Shots and dispersion)",
    )
    d.add_argument("--no-roll", action="store_true", help="stop at landing (no total or roll): much faster")
    d.add_argument("--plot", help=plot_help("the landing points from above with the 68 %% and 95 %% ellipses"))
    d.add_argument("--out", help="write every shot (launch and outcome, in --units) as .csv or .npz")
    d.add_argument("--json", action="store_true", help="end with one line of JSON (the summary, in --units)")
    runtime_options(d)


def read_spread(args: argparse.Namespace, units: Units) -> MonitorLaunch:
    """The standard deviations given, the defaults for the others, checked (SI)."""
    values = SPREAD.in_units(units)
    for name, option in SPREAD_OPTIONS.items():
        if getattr(args, option[2:].replace("-", "_")) is not None:
            values[name] = getattr(args, option[2:].replace("-", "_"))
    sd = MonitorLaunch.from_units(values, units)
    check_launch(sd, units, SPREAD_OPTIONS, spread=True)
    return sd


def cmd_dispersion(args: argparse.Namespace) -> int:
    """Fly ``--n`` shots of ``args.scene`` drawn about the mean launch with the given spread (seed
    ``--seed``), rolled out where the scene has a ground; print the spread of the results and
    write the shots (``--out``) and their picture (``--plot``); 0."""
    units = UNITS[args.units]
    if not 2 <= args.n <= MAX_SHOTS:
        raise ConfigError("--n", None, f"must be in [2, {MAX_SHOTS}] shots (got {args.n})")
    if args.flight_dt is not None and not FLIGHT_DT_RANGE[0] <= args.flight_dt <= FLIGHT_DT_RANGE[1]:
        lo, hi = FLIGHT_DT_RANGE
        raise ConfigError("--flight-dt", None, f"must be in [{lo:g}, {hi:g}] s (got {args.flight_dt})")
    check_writable(args.out, "--out", (".csv", ".npz"))
    check_plot(args.plot)
    unread = LANDING_NOT_READ if args.no_roll else SHOTS_NOT_READ
    if args.no_roll and args.flight_dt is not None:
        unread = {**unread, "world.dt": "--flight-dt steps the flights, and --no-roll leaves out the roll-out"}
    refuse_unread_keys(args.overrides, "dispersion" + " --no-roll" * args.no_roll, unread)
    scene = load_scene(args.scene, args.overrides)
    mean = read_launch(args, scene, units)
    sd = read_spread(args, units)
    if given(args, "seed") and not any(sd.in_units(units).values()):
        raise ConfigError(
            "--seed", None, "has no effect: every standard deviation is 0, so every shot is the mean launch"
        )
    to_rest = not args.no_roll and has_ground(scene)
    progress = Progress()
    t0 = time.perf_counter()
    # the flights are one kernel launch: an interrupt waits for it, and the shots computed are kept
    stopped: KeptInterrupt | None = None
    try:
        d = dispersion(scene, mean, sd, args.n, args.seed, to_rest=to_rest, flight_dt=args.flight_dt, progress=progress)
    except KeptInterrupt as stop:
        d, stopped = stop.kept, stop
    finally:
        progress.close()
    elapsed = time.perf_counter() - t0
    f, lab = units.distance, units.distance_label
    s = d.shots
    landed, rested = int(s.landed.sum()), int(s.at_rest.sum())
    unflown = int((s.landed & ~(s.apex > 0.0)).sum())  # (down through the launch height at once: carry 0)
    dt = args.flight_dt if args.flight_dt is not None else scene.world.dt
    rest_note = f", {rested:,} at rest" if to_rest else " (not rolled out)"
    print(
        f"{scene.name}: {args.n:,} shots (seed {args.seed}), {landed:,} landed{rest_note}, {elapsed:.2f} s "
        f"({args.n / elapsed:,.0f} shots/s; flight {scene.world.integrator}, dt = {dt:g} s)"
    )
    print(f"mean launch: {launch_line(mean, units)}")
    print(f"spread (sd): {launch_line(sd, units, signed=False)}")
    _notes(d, units, unflown, to_rest)
    summary = d.summary()
    if landed == 0:
        print(f"no shot landed within world.t_max = {scene.world.t_max:g} s")
    else:
        print(f"{'':<8} {'mean':>9} {'sd':>7}")
    for name, (m, sdv) in summary.items():
        if not math.isfinite(m):
            continue  # total without a roll-out, or nothing landed
        print(f"{name:<8} {m / f:9.1f} {sdv / f:7.1f} {lab}" + ("  (+ right)" if name == "offline" else ""))
    ellipses = d.ellipses() if landed > 2 else []
    for e in ellipses:
        angle = 90.0 if e.angle_deg < -89.5 else e.angle_deg  # ±90°: across the target line either way
        print(
            f"{100 * e.p:.0f} % landing ellipse: semi-axes {e.semi_major / f:.1f} × {e.semi_minor / f:.1f} {lab}, "
            f"major axis {angle:+.0f}° from the target line, holds {100 * e.inside:.1f} % of the shots"
        )
    if args.out:
        d.save(args.out, units)
        print(f"wrote {args.out}")
    code = 0
    if args.plot and landed > 2:
        from ti_golf.render.dispersion import plot_dispersion  # (matplotlib: imported only to plot)

        plot_dispersion(d, units, args.plot, title=f"{scene.name}: {args.n:,} shots, seed {args.seed}")
        print(f"wrote {args.plot}")
    elif args.plot:
        print(f"{args.plot} not written: {landed} of the shots landed, and the plot's ellipses need 3", file=sys.stderr)
        code = 1
    if args.json:
        out = {
            "scene": scene.name,
            "n": args.n,
            "seed": args.seed,
            "units": units.name,
            "seconds": elapsed,
            "landed": landed,
            "unflown": unflown,
            "at_rest": rested,
            "mean_launch": mean.in_units(units),
            "sd_launch": sd.in_units(units),
            **{f"{k}_mean": m / f for k, (m, _) in summary.items()},
            **{f"{k}_sd": v / f for k, (_, v) in summary.items()},
            "ellipses": [
                {
                    "p": e.p,
                    "semi_major": e.semi_major / f,
                    "semi_minor": e.semi_minor / f,
                    "angle_deg": e.angle_deg,
                    "inside": e.inside,
                }
                for e in ellipses
            ],
        }
        print(json.dumps(_finite(out)))
    if stopped is not None:
        raise _stopped(s, to_rest, ", ".join(p for p in (args.out, args.plot) if p))
    return code


def _notes(d: Dispersion, units: Units, unflown: int, to_rest: bool) -> None:
    """Print what a reader of the figures must know: shots that never flew (``unflown``), and
    launch values drawn beyond the launch monitor's limits and held there."""
    if unflown:
        print(
            f"note: {unflown:,} of the shots never rose above their launch height: no flight, they land where they "
            "start (carry 0)" + (" and roll out from there" if to_rest else "")
        )
    for name, share in held_at_limits(d.launches, d.sd).items():
        lo, hi = (v / field_factor(units, name) for v in LAUNCH_LIMITS[name])
        print(
            f"note: {100 * share:.1f} % of the drawn {LAUNCH_OPTIONS[name][2:]} values fell beyond "
            f"[{lo:g}, {hi:g}] {field_label(units, name)} and were held there: the spread flown is narrower than its sd"
        )


def _stopped(s: Shots, to_rest: bool, kept: str) -> KeyboardInterrupt:
    """What an interrupt kept of the shots ``s`` (``kept``: the files they are saved in, or "")."""
    if s.rolled_out:
        landed, rested = int(s.landed.sum()), int(s.at_rest.sum())
        return KeyboardInterrupt(
            f"during the roll-out: {rested:,} of the {landed:,} landed shots had come to rest (no total for the"
            " others)" + (f"; the shots are saved in {kept}" if kept else "")
        )
    return KeyboardInterrupt(
        "during the shots' flights, which are one kernel launch: they ran to their end"
        + (", not rolled out" if to_rest else "")
        + (f", and are saved in {kept}" if kept else "")
    )


def _finite(o: object) -> object:
    """JSON-able: NaN as null, numpy scalars as floats."""
    if isinstance(o, dict):
        return {k: _finite(v) for k, v in o.items()}
    if isinstance(o, list):
        return [_finite(v) for v in o]
    if isinstance(o, (int, str, bool)) or o is None:
        return o
    v = float(o)  # type: ignore[arg-type]
    return v if math.isfinite(v) else None
