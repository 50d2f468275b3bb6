"""``ti-golf table``: the report's Table 3.1-1 reproduced from the four lab scenes."""

from __future__ import annotations

import argparse

from ti_golf.cli._common import check_plot, plot_help, runtime_options
from ti_golf.golf.sweep import sweep
from ti_golf.scene.loader import load_scene
from ti_golf.scene.schema import parse_range

LAB_TABLE = (
    ("lab_vacuum", "Reference solution (in vacuo)", 45.0, 652.0, "40:50:0.5"),
    ("lab_laminar", "Laminar flow, drag, no Magnus", 44.5, 626.0, "40:50:0.5"),
    ("lab_turbulent", "Turbulent flow, drag, no Magnus", 36.5, 212.0, "32:42:0.5"),
    ("lab_magnus", "Turbulent flow, drag and Magnus", 11.5, 244.0, "7:17:0.5"),
)
"""The scenes of the report's Table 3.1-1: the table's best angle [deg] and distance [m], and the
angles of its Figures 3.1-1 to 3.1-4 (trajectories 0.5° apart)."""


def add_parser(sub: argparse._SubParsersAction) -> None:
    """Add ``table`` to ``ti-golf``'s subcommands."""
    t = sub.add_parser("table", help="reproduce the report's Table 3.1-1 from the lab scenes")
    t.add_argument("--plot", help=plot_help("the four lab trajectory families (Figures 3.1-1 to 3.1-4)"))
    runtime_options(t)


def cmd_table(args: argparse.Namespace) -> int:
    """Print the report's Table 3.1-1 beside ti_golf's sweeps of the lab scenes (and plot the four
    trajectory families with ``--plot``); 0."""
    check_plot(args.plot)
    print("Table 3.1-1 (report) reproduced: best launch angle and maximum distance, v0 = 80 m/s")
    print(f"{'conditions':<36} {'report':>16} {'ti_golf':>22}")
    results = []
    for name, label, angle, dist, figure_angles in LAB_TABLE:
        scene = load_scene(name)
        res = sweep(scene)
        b = res.best()
        if args.plot:
            fig = sweep(scene, parse_range(figure_angles, name, "figure angles"), trajectories=21)
            results.append((label, res, fig))
        print(f"{label:<36} {angle:6.1f}° {dist:7.0f} m {res.angle_deg[b]:9.2f}° {res.carry[b]:10.3f} m")
    print("(report: 0.5° spacing; ti_golf: RK4 h = 0.01 s, the [sweep] angles of each scene)")
    if args.plot:
        from ti_golf.render.plots import plot_table  # (matplotlib: imported only to plot)

        plot_table(results, args.plot)
        print(f"wrote {args.plot}")
    return 0
