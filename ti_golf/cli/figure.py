"""``ti-golf figure``: the report's figures, one command each, from the bundled lab scenes.

Each figure is a :class:`ReportFigure`: the report's number and caption, and the function that
simulates what the figure shows, prints its numbers and writes the picture.
"""

from __future__ import annotations

import argparse
import textwrap
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ti_golf.cli._common import check_plot, plot_help, runtime_options
from ti_golf.cli.play import file_shots
from ti_golf.cli.table import LAB_TABLE
from ti_golf.game.course_map import plot_round
from ti_golf.game.rules import GolfGame, describe_round, describe_stroke, describe_wind
from ti_golf.golf.sweep import sweep
from ti_golf.render.plots import plot_spin_family, plot_sweep, plot_terrain_path
from ti_golf.scene.balls import launch_position
from ti_golf.scene.launch_monitor import RPM
from ti_golf.scene.loader import load_scene, scenes_dir
from ti_golf.scene.schema import AT_REST, launch_velocity, parse_range
from ti_golf.sim.simulation import Simulation


@dataclass(frozen=True)
class ReportFigure:
    """One of the report's figures: its ``number`` (``"3.2-3"``), what it shows, and ``make(path)``,
    which simulates it, prints its numbers and writes the picture to ``path``."""

    number: str
    caption: str
    make: Callable[[str], None]


# -- Figures 3.1-1 to 3.1-4, 3.2-4 and 3.2-5: families of shots ---------------------------------
def _family(scene_name: str, angles: str, caption: str, overrides: tuple[str, ...] = ()) -> Callable[[str], None]:
    """A family of shots 0.5° apart from ``scene_name`` (a sweep): trajectories and carry vs angle."""

    def make(path: str) -> None:
        scene = load_scene(scene_name, list(overrides))
        res = sweep(scene, parse_range(angles, scene_name, "figure angles"), trajectories=21)
        b = res.best()
        print(
            f"{scene_name}: angles {angles} deg; the longest carry {res.carry[b]:.2f} m at {res.angle_deg[b]:.4g} deg"
        )
        plot_sweep(res, path, title=caption)

    return make


# -- Figure 3.2-3: the 9-iron at several angles, its spin decaying ------------------------------
def _nine_iron(path: str) -> None:
    """The 9-iron of ``lab_spin_decay`` at each angle of its ``[sweep]``, flown until every ball
    has landed: trajectories and |ω|(t), each ball's curves ending where it lands."""
    scene = load_scene("lab_spin_decay", ["world.collisions=false"])
    launch = scene.launch
    assert launch is not None and scene.sweep is not None and scene.sweep.angles is not None
    angles = scene.sweep.angles
    n = len(angles)
    v0 = np.array([launch_velocity(launch.speed, a, launch.direction_deg) for a in angles])
    spin = float(np.linalg.norm(launch.spin))
    sim = Simulation(scene, x=np.tile(launch_position(scene), (n, 1)), v=v0, w=np.tile(launch.spin, (n, 1)))
    rec = sim.run(t=30.0, until="landed", record_every=max(1, round(0.01 / sim.dt)))
    a = rec.arrays()
    t, x, w = a["traj_t"], a["traj_x"], a["traj_w"]
    fl = sim.flight()
    w_land = [_spin_at(fl.flight_time[i], t, np.linalg.norm(w[:, i], axis=1)) for i in range(n)]
    for i in range(n):  # each ball's curves end at its landing
        after = t > fl.flight_time[i]
        x[after, i] = np.nan
        w[after, i] = np.nan
    print(f"lab_spin_decay: {launch.speed * 3.6:.0f} km/h, {spin / RPM:.0f} rpm, C_omega = {scene.air.C_omega:g}")
    print(f"{'angle':>7} {'carry':>9} {'apex':>8} {'flight':>8} {'spin at landing':>16}")
    apex = fl.apex - launch_position(scene)[1]  # (above the launch, as every other output gives it)
    for i, ang in enumerate(angles):
        print(
            f"{ang:6.1f}° {fl.carry[i]:7.2f} m {apex[i]:6.2f} m {fl.flight_time[i]:6.2f} s "
            f"{w_land[i]:8.1f} rad/s ({w_land[i] / spin:.0%})"
        )
    plot_spin_family(
        [f"{ang:g}°" for ang in angles],
        t,
        x,
        w,
        path,
        title=f"Figure 3.2-3: 9-iron, v0 = {launch.speed * 3.6:.0f} km/h, {spin / RPM:.0f} rpm backspin, turbulent drag, "
        f"Magnus and spin decay (C_ω = {scene.air.C_omega:g})",
    )


def _spin_at(t_land: float, t: np.ndarray, spin: np.ndarray) -> float:
    """|ω| [rad/s] at the landing time ``t_land`` [s] of a ball sampled at times ``t`` (T,) with
    |ω| = ``spin`` (T,): carried on from the last sample in flight at the decay rate of the two
    samples before (the flight's spin decays exponentially between samples; the sample after the
    landing holds the bounce's friction)."""
    k = int(np.searchsorted(t, t_land, side="right")) - 1  # the last sample at or before the landing
    if k < 1:
        return float(spin[max(k, 0)])
    rate = np.log(spin[k - 1] / spin[k]) / (t[k] - t[k - 1])
    return float(spin[k] * np.exp(-rate * (t_land - t[k])))


# -- Figures 3.2-1, 3.2-6 and 3.2-7: a ball on a 2-D terrain ------------------------------------
def _on_terrain(scene_name: str, overrides: tuple[str, ...], caption: str) -> Callable[[str], None]:
    """The one ball of ``scene_name`` (a terrain profile along x) run for its ``world.t_end`` or until
    it rests: its path over the profile and its energy per unit mass."""

    def make(path: str) -> None:
        scene = load_scene(scene_name, list(overrides))
        sim = Simulation(scene)
        terrain = sim.terrain
        assert terrain is not None
        g = float(np.linalg.norm(scene.world.gravity))
        every = max(1, round(0.01 / sim.dt))
        samples: list[tuple[float, np.ndarray, np.ndarray]] = [(sim.t, sim.x[0], sim.v[0])]
        sim.run(until="rest", every=every, on_every=lambda s: samples.append((s.t, s.x[0], s.v[0])))
        t = np.array([s[0] for s in samples])
        x = np.array([s[1] for s in samples])
        v = np.array([s[2] for s in samples])
        energy = 0.5 * np.einsum("ij,ij->i", v, v) + g * x[:, 1]
        rest = int(sim.status[0]) == AT_REST
        z = float(x[0, 2])
        px = np.linspace(terrain.origin[0], terrain.origin[0] + terrain.size[0], 4 * terrain.heights.shape[0])
        profile = (px, np.asarray(terrain.height(px, np.full_like(px, z))))
        c = scene.contact
        print(
            f"{scene_name}: e = {c.e:g}, mu = {c.mu:g} ({c.friction_model} friction); after {sim.t:.2f} s the ball "
            f"{'rests' if rest else 'still moves'} at x = {x[-1, 0]:.2f} m, y = {x[-1, 1]:.2f} m; "
            f"v^2/2 + g*y went from {energy[0]:.1f} to {energy[-1]:.1f} J/kg"
        )
        if rest:
            n = terrain.normal(x[-1, 0], x[-1, 2])
            print(f"it rests on a slope of {np.degrees(np.arctan2(np.hypot(n[0], n[2]), n[1])):.1f} deg")
        plot_terrain_path(profile, t, x, energy, path, title=caption, rest=rest)

    return make


# -- Figure 3.1-5: a round of five strokes ------------------------------------------------------
COURSE_SEED = 11
"""The ``--seed`` of Figure 3.1-5's round on ``lab_course`` (its random start and winds)."""


def _course_round(path: str) -> None:
    """The report's five strokes on ``lab_course`` from its random start (seed :data:`COURSE_SEED`),
    as ``ti-golf play lab_course --seed 11 --shots lab_course_round`` plays them."""
    game = GolfGame(load_scene("lab_course"), seed=COURSE_SEED)
    print(f"lab_course (seed {COURSE_SEED}): the hole at x = {game.cup[0]:g} m, z = {game.cup[2]:g} m")
    shots = file_shots(str(scenes_dir() / "lab_course_round.txt"), game)
    while not game.over:
        print(
            f"Stroke {len(game.strokes) + 1} from x = {game.ball[0]:.2f} m, z = {game.ball[2]:.2f} m, "
            f"{describe_wind(game.wind)}:"
        )
        shot = next(shots, None)
        if shot is None:
            break
        print(describe_stroke(game.play(shot)))
    summary = describe_round(game, "no more strokes")
    print(summary)
    plot_round(game, path, title=f"Figure 3.1-5: lab_course (seed {COURSE_SEED}): {summary}")


FIGURES = {
    f.number: f
    for f in (
        *(
            ReportFigure(
                f"3.1-{k}",
                f"Table 3.1-1 row {k}: {label}, v0 = 80 m/s at {angles.replace(':', ' to ', 1).split(':')[0]} deg",
                _family(name, angles, f"Figure 3.1-{k}: {label}, v0 = 80 m/s"),
            )
            for k, (name, label, _, _, angles) in enumerate(LAB_TABLE, 1)
        ),
        ReportFigure(
            "3.1-5",
            "a round of five strokes (the report's) on a generated course, from a seeded random start, into the hole",
            _course_round,
        ),
        ReportFigure(
            "3.2-1",
            "a 9-iron shot bouncing over a 2-D terrain height field",
            _on_terrain("terrain_2d", (), "Figure 3.2-1: collisions with a 2-D terrain height field"),
        ),
        ReportFigure("3.2-3", "the 9-iron at several angles: trajectories and decaying spin |ω|(t)", _nine_iron),
        ReportFigure(
            "3.2-4",
            "80 m/s into a 5 m/s headwind at 7 to 17 deg, turbulent drag and Magnus",
            _family("lab_headwind", "7:17:0.5", "Figure 3.2-4: 80 m/s into a 5 m/s headwind"),
        ),
        ReportFigure(
            "3.2-5",
            "the same shots with no wind",
            _family("lab_magnus", "7:17:0.5", "Figure 3.2-5: 80 m/s, no wind"),
        ),
        ReportFigure(
            "3.2-6",
            "a ball jumping on a non-planar surface without friction",
            _on_terrain(
                "lab_friction",
                ("contact.mu=0",),
                "Figure 3.2-6: a ball jumping on a non-planar surface without friction",
            ),
        ),
        ReportFigure(
            "3.2-7",
            "the same ball with the report's friction, mu = 0.4: it stops on a slope",
            _on_terrain("lab_friction", (), "Figure 3.2-7: the same ball with the report's friction (μ = 0.4)"),
        ),
    )
}
"""The report's figures that ``ti-golf figure`` makes, by number."""


def add_parser(sub: argparse._SubParsersAction) -> None:
    """Add ``figure`` to ``ti-golf``'s subcommands."""
    listing = "\n".join(
        textwrap.fill(f"{f.number:<7}{f.caption}", width=100, subsequent_indent=" " * 9, initial_indent="  ")
        for f in FIGURES.values()
    )
    p = sub.add_parser(
        "figure",
        help="make one of the report's figures (3.1-1 to 3.1-5, 3.2-1, 3.2-3 to 3.2-7)",
        description="Simulate one of the report's figures from the bundled lab scenes, print its numbers and "
        "write its picture.",
        epilog=f"the figures:\n{listing}",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("number", type=_figure_number, metavar="NUMBER", help="the report's figure number, e.g. 3.2-3")
    p.add_argument("--plot", help=plot_help("the picture (default figure_NUMBER.png)"))
    runtime_options(p)


RENDERED = {"3.2-2": "ti-golf render terrain_3d --t 3 --out figure_3_2_2.png"}
"""The report's figures that are a picture of balls, made by ``ti-golf render``, by number."""


def _figure_number(text: str) -> str:
    """``text`` when it names one of :data:`FIGURES`; else an error listing them (and, for a
    figure that is a render, the command that makes it)."""
    if text in FIGURES:
        return text
    if text in RENDERED:
        raise argparse.ArgumentTypeError(f"Figure {text} is a render of balls: `{RENDERED[text]}`")
    raise argparse.ArgumentTypeError(f"no figure {text!r} (choose from {', '.join(FIGURES)})")


def cmd_figure(args: argparse.Namespace) -> int:
    """Make figure ``args.number`` and write it to ``args.plot`` (default ``figure_NUMBER.png``)."""
    path = args.plot if args.plot is not None else f"figure_{args.number}.png"
    check_plot(path)
    figure = FIGURES[args.number]
    print(f"Figure {figure.number}: {figure.caption}")
    figure.make(path)
    print(f"wrote {path}")
    return 0
