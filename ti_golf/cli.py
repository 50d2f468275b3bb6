"""Command line: ``ti-golf {scenes,keys,sweep,run,table,render,bench,play}``; ``main(argv) -> exit code``.

Bad input exits with code 2 and one line naming the file, the key and what is allowed.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path
from typing import Sequence

from .errors import ConfigError, SimulationError, TiGolfError

LAB_TABLE = (
    ("lab_vacuum", "Reference solution (in vacuo)", 45.0, 652.0, "40:50:0.5"),
    ("lab_laminar", "Laminar flow, drag, no Magnus", 44.5, 626.0, "40:50:0.5"),
    ("lab_turbulent", "Turbulent flow, drag, no Magnus", 36.5, 212.0, "32:42:0.5"),
    ("lab_magnus", "Turbulent flow, drag and Magnus", 11.5, 244.0, "7:17:0.5"),
)
"""The scenes of the report's Table 3.1-1: the table's best angle [deg] and distance [m], and the
angles of its Figures 3.1-1 to 3.1-4 (trajectories 0.5° apart)."""


class _Parser(argparse.ArgumentParser):
    """argparse that reports usage errors as one line with exit code 2 (its default code)."""

    def error(self, message: str) -> None:  # type: ignore[override]
        self.print_usage(sys.stderr)
        self.exit(2, f"ti-golf: error: {message}\n")


def _runtime_options(p: argparse.ArgumentParser) -> None:
    p.add_argument("--arch", choices=("cpu", "cuda", "vulkan", "gpu"), default=None,
                   help="Taichi backend (default: $TI_GOLF_ARCH or cpu)")
    p.add_argument("--precision", choices=("f32", "f64"), default=None,
                   help="float precision (default: $TI_GOLF_PRECISION or f64)")


def _scene_options(p: argparse.ArgumentParser) -> None:
    p.add_argument("scene", help="scene file, or the name of a bundled scene (see `ti-golf scenes`)")
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                   help="override a scene key with a TOML value, e.g. --set air.wind=[-5,0,0] (repeatable)")


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of ``ti-golf``."""
    p = _Parser(prog="ti-golf", description="Golf-ball physics on Taichi: flights, sweeps, collisions.")
    sub = p.add_subparsers(dest="command", required=True, parser_class=_Parser)

    sub.add_parser("scenes", help="list the bundled scenes with a one-line description")
    sub.add_parser("keys", help="print every scene key with unit, default and allowed values")

    s = sub.add_parser("sweep", help="fly one ball per launch condition, all at once, and report carry")
    _scene_options(s)
    s.add_argument("--angles", help="elevations [deg]: START:STOP:STEP (STOP included) or a,b,c")
    s.add_argument("--speeds", help="launch speeds [m/s]: START:STOP:STEP or a,b,c")
    s.add_argument("--spins", help="spin magnitudes [rad/s] along the scene's spin axis: START:STOP:STEP or a,b,c")
    s.add_argument("--out", help="write one CSV row per launch condition")
    s.add_argument("--plot", help="write a PNG: trajectories (side view) and carry vs angle")
    s.add_argument("--trajectories", type=int, default=21, help="trajectories drawn in --plot (default 21)")
    _runtime_options(s)

    r = sub.add_parser("run", help="run a scene and save the final state (and trajectories)")
    _scene_options(r)
    g = r.add_mutually_exclusive_group()
    g.add_argument("--t", type=float, help="simulated time [s] (default: world.t_end)")
    g.add_argument("--steps", type=int, help="number of time steps")
    r.add_argument("--until", choices=("rest", "landed"), help="stop early once every ball is at rest / has landed")
    r.add_argument("--record-every", type=int, default=0, metavar="K", help="record positions and spins every K steps")
    r.add_argument("--out", help="write an .npz with x, v, w (N, 3), t, status (and traj_* when recording)")
    r.add_argument("--plot", help="write a PNG: trajectory and |ω| vs time (records automatically)")
    r.add_argument("--frames-every", type=int, default=0, metavar="K", help="render a frame every K steps")
    r.add_argument("--frames", metavar="DIR", help="write the frames as DIR/frame_00000.png, …")
    r.add_argument("--gif", help="write the frames as an animated GIF (Pillow)")
    r.add_argument("--camera", choices=("side", "top", "iso", "follow"), default="iso", help="camera of the frames")
    r.add_argument("--size", default="640x360", metavar="WxH", help="frame size (default 640x360)")
    _runtime_options(r)

    t = sub.add_parser("table", help="reproduce the report's Table 3.1-1 from the lab scenes")
    t.add_argument("--plot", help="write a PNG of the four lab trajectory families")
    _runtime_options(t)

    b = sub.add_parser("bench", help="throughput benchmarks (JSON with --json)")
    bsub = b.add_subparsers(dest="bench", required=True, parser_class=_Parser)
    bs = bsub.add_parser("sweep", help="data-parallel sweep vs numpy and scipy baselines")
    bs.add_argument("--n", type=int, default=100_000, help="launch conditions (default 100000)")
    bs.add_argument("--dt", type=float, default=0.1, help="RK4 step [s] (default 0.1)")
    bs.add_argument("--repeats", type=int, default=3, help="timed repeats; the best is reported")
    bs.add_argument("--json", action="store_true", help="end with one line of JSON")
    _runtime_options(bs)
    bc = bsub.add_parser("collide", help="full collision step on a dense pile of N balls")
    bc.add_argument("--n", type=int, default=131_072, help="balls (default 131072)")
    bc.add_argument("--steps", type=int, default=50, help="timed steps (default 50)")
    bc.add_argument("--terrain", action="store_true",
                    help="a flat height-field floor instead of the plane (the plane is timed too, as baseline)")
    bc.add_argument("--asleep", action="store_true",
                    help="every ball of the pile at rest, as a settled pile ends up (the pile awake is timed too, "
                         "as baseline)")
    bc.add_argument("--shuffled", action="store_true",
                    help="the pile's balls numbered in a random order, as balls given in no spatial order are "
                         "(the same pile left in that order, not stored in the grid's order, is timed too, as "
                         "baseline)")
    bc.add_argument("--boulder", type=float, default=0.0, metavar="R",
                    help="a ball of radius R [m], as dense as the golf balls, dropped at 3 m/s onto the pile (the "
                         "pile alone is timed too, as baseline)")
    bc.add_argument("--iterations", type=int, default=4,
                    help="Jacobi sweeps per step (default 4, the scenes' default; a deep pile at rest needs 8)")
    bc.add_argument("--json", action="store_true", help="end with one line of JSON")
    _runtime_options(bc)
    br = bsub.add_parser("render", help="seconds per off-screen frame of N balls over a terrain")
    br.add_argument("--n", type=int, default=100_000, help="balls (default 100000)")
    br.add_argument("--frames", type=int, default=3, help="timed frames (default 3)")
    br.add_argument("--json", action="store_true", help="end with one line of JSON")
    _runtime_options(br)

    from .render_cli import add_parser as _add_render_parser

    _add_render_parser(sub)
    from .play_cli import add_parser as _add_play_parser

    _add_play_parser(sub)
    return p


def run() -> None:
    """The ``ti-golf`` command and ``python -m ti_golf``: :func:`main`, whose code the process then
    exits with (see ``runtime.exit_process``: Taichi's runtime can crash the normal exit)."""
    try:
        code = main()
    except BrokenPipeError:  # the reader of stdout left (``ti-golf scenes | head``): no traceback
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        code = 1
    from . import runtime

    runtime.exit_process(code)


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of ``ti-golf`` and ``python -m ti_golf``; returns the exit code."""
    args = build_parser().parse_args(argv)
    from . import runtime

    runtime.announce_first_compile = True
    try:
        if args.command not in ("scenes", "keys"):  # before any output: a first run's notice comes first
            runtime.init(getattr(args, "arch", None), getattr(args, "precision", None))
        return _COMMANDS[args.command](args)
    except ConfigError as exc:
        print(f"ti-golf: error: {exc}", file=sys.stderr)
        return 2
    except SimulationError as exc:
        print(f"ti-golf: simulation stopped: {exc}", file=sys.stderr)
        return 3
    except TiGolfError as exc:  # pragma: no cover - future error kinds
        print(f"ti-golf: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:  # pragma: no cover
        print("ti-golf: interrupted", file=sys.stderr)
        return 130


def _check_writable(path: str | None, option: str) -> None:
    """Fail before a long computation rather than lose its result to an unwritable output path."""
    if not path:
        return
    parent = Path(path).resolve().parent
    if not parent.is_dir():
        raise ConfigError(option, None, f"cannot write {path!r}: folder {str(parent)!r} does not exist")
    if not os.access(parent, os.W_OK):
        raise ConfigError(option, None, f"cannot write {path!r}: folder is not writable")


def _cmd_scenes(args: argparse.Namespace) -> int:
    from .scene import load_scene, scenes_dir

    folder = scenes_dir()
    files = sorted(folder.glob("*.toml"))
    if not files:
        print(f"no scenes in {folder}")
        return 0
    width = max(len(f.stem) for f in files)
    for f in files:
        try:
            desc = load_scene(f).description
        except ConfigError as exc:
            desc = f"(invalid: {exc.reason})"
        print(f"{f.stem:<{width}}  {desc}")
    return 0


def _cmd_keys(args: argparse.Namespace) -> int:
    from .scene import describe_keys

    print(describe_keys())
    return 0


def _parse_opt_range(text: str | None, option: str) -> tuple[float, ...] | None:
    from .config import parse_range

    return None if text is None else parse_range(text, option, None)  # type: ignore[arg-type]


def _cmd_sweep(args: argparse.Namespace) -> int:
    from .scene import load_scene
    from .sweeps import sweep

    _check_writable(args.out, "--out")
    _check_writable(args.plot, "--plot")
    scene = load_scene(args.scene, args.overrides)
    angles = _parse_opt_range(args.angles, "--angles")
    speeds = _parse_opt_range(args.speeds, "--speeds")
    spins = _parse_opt_range(args.spins, "--spins")
    t0 = time.perf_counter()
    res = sweep(scene, angles, speeds, spins, trajectories=args.trajectories if args.plot else 0)
    elapsed = time.perf_counter() - t0
    n = res.angle_deg.size
    landed = int(res.flight.landed.sum())
    print(f"{scene.name}: {n} launch conditions, {landed} landed, {elapsed:.2f} s "
          f"({scene.world.integrator}, dt = {scene.world.dt:g} s)")
    if landed == 0:
        print(f"no ball landed within world.t_max = {scene.world.t_max:g} s")
    else:
        b = res.best()
        f = res.flight
        print(f"best: angle {res.angle_deg[b]:.4f} deg, speed {res.speed_mps[b]:g} m/s, spin {res.spin_radps[b]:g} rad/s"
              f" -> carry {f.carry[b]:.4f} m (apex {f.apex[b] - scene.launch_position()[1]:.2f} m, "
              f"flight {f.flight_time[b]:.3f} s, lands at {f.landing_angle[b]:.1f} deg, {f.landing_speed[b]:.2f} m/s)")
    if args.out:
        res.to_csv(args.out)
        print(f"wrote {args.out}")
    if args.plot:
        from .plots import plot_sweep

        plot_sweep(res, args.plot)
        print(f"wrote {args.plot}")
    return 0


def _cmd_run(args: argparse.Namespace) -> int:
    import numpy as np

    from .config import STATUS_NAMES
    from .sim import Simulation

    _check_writable(args.out, "--out")
    _check_writable(args.plot, "--plot")
    if args.t is not None and not args.t > 0:
        raise ConfigError("--t", None, f"must be > 0 seconds (got {args.t})")
    if args.steps is not None and args.steps <= 0:
        raise ConfigError("--steps", None, f"must be > 0 (got {args.steps})")
    if args.record_every < 0:
        raise ConfigError("--record-every", None, f"must be >= 0 (got {args.record_every})")
    sim = Simulation.from_scene(args.scene, args.overrides)
    record_every = args.record_every
    if args.plot and not record_every:
        duration = args.t if args.t is not None else (args.steps or 0) * sim.dt or sim.scene.world.t_end
        record_every = max(1, int(duration / sim.dt / 400))
    frames = _Frames(args, sim) if (args.frames or args.gif) else None
    progress = _Progress()
    t0 = time.perf_counter()
    rec = None
    try:
        if frames is not None:
            frames(sim)
        rec = sim.run(t=args.t, steps=args.steps, until=args.until, record_every=record_every, progress=progress,
                      every=frames.every if frames else 0, on_every=frames)
    finally:
        progress.close()
        if frames is not None:
            frames.close()  # the frames rendered so far are kept, and the GIF is written from them
        if args.out and (rec is not None or sim.t > 0):
            sim.save(args.out, rec)  # save what was simulated even if the run stopped early
    elapsed = time.perf_counter() - t0
    counts = sim.counts()
    print(f"{sim.scene.name}: {sim.n} ball(s), t = {sim.t:.4g} s in {elapsed:.2f} s; "
          + ", ".join(f"{counts[name]} {name.replace('_', ' ')}" for name in STATUS_NAMES.values()))
    if sim.solver is not None:
        deepest = sim.deepest_overlap()
        if deepest is None:
            print("no two balls overlap")
        elif deepest.fraction < 1e-6:  # resting contacts left at round-off
            print("no two balls overlap by more than a millionth of a radius")
        else:
            print(f"deepest overlap: {100 * deepest.fraction:.3g} % of a radius ({1e3 * deepest.depth:.3g} mm, "
                  f"balls {deepest.i} and {deepest.j})")
    f = sim.flight()
    x, status = sim.x, sim.status

    def state_of(i: int) -> str:  # "at rest", "out of bounds", ...
        return STATUS_NAMES[int(status[i])].replace("_", " ")

    for i in np.flatnonzero(f.landed)[:10]:
        print(f"ball {i}: carry {f.carry[i]:.3f} m, apex {f.apex[i]:.2f} m, flight {f.flight_time[i]:.3f} s, "
              f"lands at {f.landing_angle[i]:.1f} deg, {f.landing_speed[i]:.2f} m/s; now at "
              f"x = {x[i, 0]:.2f} m, z = {x[i, 2]:.2f} m ({state_of(i)})")
    hole = sim.scene.hole
    if hole is not None:
        away = np.hypot(x[:, 0] - hole.position[0], x[:, 2] - hole.position[1])
        for i in range(min(sim.n, 10)):
            print(f"ball {i}: {away[i]:.2f} m from the hole at x = {hole.position[0]:g} m, z = {hole.position[1]:g} m "
                  f"({state_of(i)})")
    if args.out:
        print(f"wrote {args.out}")
    if args.plot and rec is not None:
        from .plots import plot_run

        plot_run(rec, args.plot, title=sim.scene.description or sim.scene.name)
        print(f"wrote {args.plot}")
    return 0


def _cmd_table(args: argparse.Namespace) -> int:
    from .scene import load_scene
    from .sweeps import sweep

    _check_writable(args.plot, "--plot")
    print("Table 3.1-1 (report) reproduced: best launch angle and maximum distance, v0 = 80 m/s")
    print(f"{'conditions':<36} {'report':>16} {'ti_golf':>22}")
    from .config import parse_range

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
        _plot_table(results, args.plot)
        print(f"wrote {args.plot}")
    return 0


def _plot_table(results: list, path: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    fig, axes = plt.subplots(2, 2, figsize=(12, 7))
    for ax, (label, res, fig_res) in zip(axes.ravel(), results):
        k = len(fig_res.traj_index)
        for j, i in enumerate(fig_res.traj_index):
            p = fig_res.traj[j]
            ax.plot(p[:, 0], p[:, 1] - p[0, 1], lw=0.8, color=plt.get_cmap("viridis")(j / max(k - 1, 1)),
                    label=f"{fig_res.angle_deg[i]:g}°" if j in (0, k - 1) else None)
        b = res.best()
        ax.legend(fontsize=7, loc="upper right")
        ax.set_title(f"{label}: best {res.angle_deg[b]:.2f}°, {res.carry[b]:.2f} m", fontsize=9)
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m]")
        ax.grid(alpha=0.3)
        ax.set_ylim(bottom=0)
        ax.set_xlim(0, np.nanmax(fig_res.carry) * 1.05)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _cmd_bench(args: argparse.Namespace) -> int:
    from .bench import bench_collide, bench_sweep, to_json

    if args.n <= 0:
        raise ConfigError("--n", None, f"must be > 0 (got {args.n})")
    if args.bench == "render":
        from .bench import bench_render

        result = bench_render(n=args.n, frames=max(1, args.frames))
    elif args.bench == "collide":
        if args.n < 2 or args.steps <= 0:
            raise ConfigError("--n" if args.n < 2 else "--steps", None, "must be >= 2 balls and > 0 steps")
        if not 1 <= args.iterations <= 100:
            raise ConfigError("--iterations", None, f"must be in [1, 100] (got {args.iterations})")
        if not 0.0 <= args.boulder <= 10.0:  # (also false for NaN)
            raise ConfigError("--boulder", None, f"must be a radius in [0, 10] m (got {args.boulder})")
        result = bench_collide(n=args.n, steps=args.steps, terrain=args.terrain, asleep=args.asleep,
                               shuffled=args.shuffled, iterations=args.iterations, boulder=args.boulder)
    else:
        if not args.dt > 0:
            raise ConfigError("--dt", None, f"must be > 0 (got {args.dt})")
        result = bench_sweep(n=args.n, dt=args.dt, repeats=max(1, args.repeats))
    if args.json:
        print(to_json(result))
    return 0


class _Frames:
    """Renders a frame every K steps to numbered PNGs (``--frames DIR``) and/or an animated GIF."""

    def __init__(self, args: argparse.Namespace, sim) -> None:
        import tempfile

        from .render_cli import _size

        if args.frames_every < 0:
            raise ConfigError("--frames-every", None, f"must be >= 0 (got {args.frames_every})")
        _check_writable(args.gif, "--gif")
        if args.gif:
            try:
                import PIL  # noqa: F401
            except ImportError:
                raise ConfigError("--gif", None, "needs Pillow: pip install pillow") from None
        duration = args.t if args.t is not None else (args.steps or 0) * sim.dt or sim.scene.world.t_end
        self.every = args.frames_every or max(1, int(round(duration / sim.dt / 100)))  # ~100 frames
        self.size = _size(args.size)
        self.camera = args.camera
        self.gif = args.gif
        self.fps = max(1.0, min(50.0, 1.0 / (self.every * sim.dt)))
        self._tmp = None
        if args.frames:
            self.folder = Path(args.frames)
            self.folder.mkdir(parents=True, exist_ok=True)
        else:
            self._tmp = tempfile.TemporaryDirectory()
            self.folder = Path(self._tmp.name)
        self.paths: list[Path] = []

    def __call__(self, sim) -> None:
        from .render import render

        path = self.folder / f"frame_{len(self.paths):05d}.png"
        render(sim, path, camera=self.camera, size=self.size)
        self.paths.append(path)

    def close(self) -> None:
        if self.gif and self.paths:
            from PIL import Image

            images = [Image.open(p).convert("P", palette=Image.ADAPTIVE) for p in self.paths]
            images[0].save(self.gif, save_all=True, append_images=images[1:], duration=int(1000 / self.fps), loop=0)
            print(f"wrote {self.gif} ({len(images)} frames)")
        if self._tmp is None and self.paths:
            print(f"wrote {len(self.paths)} frames to {self.folder}")
        if self._tmp is not None:
            self._tmp.cleanup()


class _Progress:
    """Progress for runs longer than a few seconds: a bar on a terminal, plain lines otherwise."""

    def __init__(self, after_s: float = 3.0, every_s: float = 5.0) -> None:
        self.start = time.perf_counter()
        self.after_s, self.every_s = after_s, every_s
        self.last = 0.0
        self.tty = sys.stderr.isatty()
        self.shown = False

    def __call__(self, done: float, total: float) -> None:
        now = time.perf_counter() - self.start
        if now < self.after_s or (not self.tty and now - self.last < self.every_s) or (self.tty and now - self.last < 0.2):
            return
        self.last = now
        frac = done / total if total else 1.0
        if self.tty:
            bar = "#" * int(30 * frac)
            print(f"\r[{bar:<30}] {100 * frac:5.1f}%  t = {done:.3g}/{total:.3g} s", end="", file=sys.stderr)
        else:
            print(f"progress: {100 * frac:5.1f}% (t = {done:.3g} of {total:.3g} s, {now:.0f} s elapsed)", file=sys.stderr)
        self.shown = True

    def close(self) -> None:
        if self.shown and self.tty:
            print(file=sys.stderr)


def _cmd_render(args: argparse.Namespace) -> int:
    from .render_cli import cmd_render

    return cmd_render(args)


def _cmd_play(args: argparse.Namespace) -> int:
    from .play_cli import cmd_play

    return cmd_play(args)


_COMMANDS = {
    "render": _cmd_render,
    "play": _cmd_play,
    "scenes": _cmd_scenes,
    "keys": _cmd_keys,
    "sweep": _cmd_sweep,
    "run": _cmd_run,
    "table": _cmd_table,
    "bench": _cmd_bench,
}

if __name__ == "__main__":  # pragma: no cover
    run()
