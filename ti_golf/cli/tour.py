"""``ti-golf tour`` and ``ti-golf fit-aero``: the TrackMan tour averages flown by a scene's air, and
the fit of the ``spin_reynolds`` air model to the PGA Tour rows."""

from __future__ import annotations

import argparse
import time

from ti_golf.cli._common import (
    check_plot,
    plot_help,
    refuse_replaced,
    refuse_unread_keys,
    runtime_options,
    scene_options,
)
from ti_golf.errors import ConfigError
from ti_golf.golf.aero_fit import FIT_PARAMETERS, START, bounds, fit
from ti_golf.golf.tour import fly_tour, within_tolerance_text
from ti_golf.golf.trackman import LPGA_TOUR, PGA_TOUR, TOUR
from ti_golf.scene.loader import load_scene
from ti_golf.scene.readers import FIT_NOT_READ, TOUR_NOT_READ

ROWS = {"all": TOUR, "pga": PGA_TOUR, "lpga": LPGA_TOUR}
"""The rows ``--rows`` picks."""


def add_parser(sub: argparse._SubParsersAction) -> None:
    """Add ``tour`` and ``fit-aero`` to ``ti-golf``'s subcommands."""
    t = sub.add_parser(
        "tour",
        help="fly the TrackMan 2023 tour averages (23 clubs, PGA and LPGA) and print model beside table",
    )
    scene_options(t, default="tour_shot", example="air.rho=1.15")
    t.add_argument("--rows", choices=tuple(ROWS), default="all", help="which tour's rows (default all)")
    t.add_argument("--plot", help=plot_help("carry, apex and land angle of each row, table and model"))
    runtime_options(t)
    f = sub.add_parser(
        "fit-aero",
        help="fit the spin_reynolds air model to the 12 PGA Tour rows and print its coefficients (needs scipy)",
    )
    scene_options(f, default="tour_shot", example="air.spin_decay=3e-5")
    f.add_argument(
        "--free",
        action="store_true",
        help="let the coefficients leave their published ranges (to see what the data asks for)",
    )
    runtime_options(f)


def cmd_tour(args: argparse.Namespace) -> int:
    """Fly the TrackMan tour-average shots (``--rows``) in ``args.scene`` and print them beside the
    published figures (and plot them with ``--plot``); 0."""
    check_plot(args.plot)
    rows = "the tour's rows, which give every launch (only launch.position is the scene's)"
    refuse_replaced(args.overrides, {f"launch.{k}": rows for k in ("speed", "angle_deg", "direction_deg", "spin")})
    refuse_unread_keys(args.overrides, "tour", TOUR_NOT_READ)
    scene = load_scene(args.scene, args.overrides)
    if scene.launch is None:  # the rows launch from the scene's launch point
        raise ConfigError(
            *scene.where("launch"), "is required: the tour rows are launched as the scene's [launch] table says"
        )
    t0 = time.perf_counter()
    flight = fly_tour(scene, ROWS[args.rows])
    elapsed = time.perf_counter() - t0
    print(
        f"TrackMan 2023 tour averages flown in {scene.name} (air.model = {scene.air.model!r}; "
        f"{len(flight.rows)} balls at once, {elapsed:.2f} s); targets: {within_tolerance_text()}"
    )
    print(flight.table())
    if args.plot:
        from ti_golf.render.plots import plot_tour  # (matplotlib: imported only to plot)

        plot_tour(
            flight, args.plot, title=f"TrackMan 2023 tour averages and {scene.name} (air.model = {scene.air.model})"
        )
        print(f"wrote {args.plot}")
    return 0


def cmd_fit_aero(args: argparse.Namespace) -> int:
    """Fit the spin_reynolds air model's coefficients of ``args.scene`` to the 12 PGA Tour rows and
    print them (as scene keys too) and the fitted model on every row; 0."""
    refuse_replaced(args.overrides, {"air.model": 'fit-aero, which fits air.model = "spin_reynolds"'})
    refuse_unread_keys(args.overrides, "fit-aero", FIT_NOT_READ)
    scene = load_scene(args.scene, args.overrides)
    if scene.launch is None:
        raise ConfigError(
            *scene.where("launch"), "is required: the tour rows are launched as the scene's [launch] table says"
        )
    if scene.air.gamma != 2:
        raise ConfigError(*scene.where("air.gamma"), 'must be 2 to fit air.model = "spin_reynolds" (turbulent drag)')
    air = scene.air
    print(
        f"fitting air.model = 'spin_reynolds' to the {len(PGA_TOUR)} PGA Tour rows in {scene.name}'s air "
        f"(rho = {air.rho:g} kg/m^3, viscosity = {air.viscosity:g} Pa*s) and ball; held: "
        f"C_D0 = {air.C_D_S[0]:g}, C_L0 = {air.C_L_S[0]:g}, spin_decay = {air.spin_decay:g}"
    )
    t0 = time.perf_counter()
    res = fit(scene, bounded=not args.free)
    elapsed = time.perf_counter() - t0
    print(
        f"{'converged' if res.converged else 'NOT converged'} after {res.evaluations} flights of the "
        f"{len(PGA_TOUR)} rows ({elapsed:.1f} s): cost ½Σ(error/tolerance)² = {res.cost:.3f} ({res.message})"
    )
    at_bound = res.at_bound()
    print(f"{'coefficient':<11} {'start':>10} {'fitted':>10}   published range")
    for p, s, v in zip(FIT_PARAMETERS, START, res.values):
        lo, hi = bounds(p, scene.air)
        mark = ""
        if not lo <= v <= hi:
            mark = "  (OUTSIDE its range)"
        elif p.name in at_bound:
            mark = "  (at an end of its range)"
        print(f"{p.name:<11} {s:>10.5g} {v:>10.5g}   [{lo:.5g}, {hi:.5g}]: {p.source}{mark}")
    a = res.scene.air
    print("as scene keys:")
    print('[air]\nmodel = "spin_reynolds"')
    print(f"C_D_S = [{a.C_D_S[0]:.4f}, {a.C_D_S[1]:.4f}, {a.C_D_S[2]:.4f}]")
    print(f"C_L_S = [{a.C_L_S[0]:.4f}, {a.C_L_S[1]:.4f}, {a.C_L_S[2]:.4f}]")
    print(f"C_D_crisis = {a.C_D_crisis:.4f}\nRe_crisis = {a.Re_crisis:.4g}")
    print("the fitted model on all 23 rows (the LPGA rows were not part of the fit):")
    print(fly_tour(res.scene, TOUR).table())
    return 0
