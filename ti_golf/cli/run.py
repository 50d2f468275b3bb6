"""``ti-golf run``: simulate a scene, print what happened, save the state, plots and frames."""

from __future__ import annotations

import argparse
import math
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from ti_golf.cli._common import (
    Progress,
    check_plot,
    check_steps_span,
    check_until,
    check_writable,
    parse_size,
    plot_help,
    refuse_replaced,
    refuse_without,
    resume_option,
    runtime_options,
    say_unfinished,
    scene_options,
    scene_or_saved_run,
)
from ti_golf.errors import ConfigError
from ti_golf.files import atomic_path
from ti_golf.scene.checks import TIME_LIMIT
from ti_golf.scene.schema import STATUS_NAMES
from ti_golf.signals import whole_steps
from ti_golf.sim.results import Recording
from ti_golf.sim.simulation import Simulation

RUN_DEFAULTS: dict[str, Any] = {
    "record_every": 0,
    "frames_every": 0,
    "camera": "iso",
    "follow": False,
    "size": (640, 360),
}
"""The defaults of the options that need another (``--record-every`` needs ``--out`` or ``--plot``;
the frames' options, ``--frames`` or ``--gif``): given otherwise, they are refused."""


def add_parser(sub: argparse._SubParsersAction) -> None:
    """Add ``run`` to ``ti-golf``'s subcommands."""
    r = sub.add_parser("run", help="run a scene and save the final state (and trajectories)")
    scene_options(
        r,
        default="",
        scene_help="scene file, or the name of a bundled scene (see `ti-golf scenes`); none with --resume",
    )
    resume_option(
        r,
        "continue it from where it stopped, for --t (or --steps) more, with its scene and any --set changes (air, "
        "contact, world keys): it ends bit for bit where one unbroken run ends",
    )
    g = r.add_mutually_exclusive_group()
    g.add_argument("--t", type=float, help="simulated time [s] (default: world.t_end); more time with --resume")
    g.add_argument("--steps", type=int, help="number of time steps")
    r.add_argument("--until", choices=("rest", "landed"), help="stop early once every ball is at rest / has landed")
    r.add_argument(
        "--record-every",
        type=int,
        default=RUN_DEFAULTS["record_every"],
        metavar="K",
        help="record positions and spins every K steps (kept by --out, drawn by --plot; default 0: "
        "none, or about 400 samples for --plot)",
    )
    r.add_argument(
        "--out",
        help="write an .npz with x, v, w (N, 3), t, status (and traj_* when recording), which --resume continues",
    )
    r.add_argument("--plot", help=plot_help("trajectory and |ω| vs time (records automatically)"))
    r.add_argument(
        "--frames-every",
        type=int,
        default=RUN_DEFAULTS["frames_every"],
        metavar="K",
        help="render a frame every K steps (default 0: about 100 frames over the run)",
    )
    r.add_argument("--frames", metavar="DIR", help="write the frames as DIR/frame_00000.png, …")
    r.add_argument("--gif", help="write the frames as an animated GIF (Pillow)")
    r.add_argument(
        "--camera",
        choices=("side", "top", "iso", "follow"),
        default=RUN_DEFAULTS["camera"],
        help="camera of the frames (default iso); side, top and iso hold still, framing all that the run shows; "
        "follow chases ball 0",
    )
    r.add_argument(
        "--follow",
        action="store_true",
        help="the side, top or iso camera follows the balls instead: framed anew on them at every frame",
    )
    r.add_argument(
        "--size", type=parse_size, default=RUN_DEFAULTS["size"], metavar="WxH", help="frame size (default 640x360)"
    )
    runtime_options(r)


def cmd_run(args: argparse.Namespace) -> int:  # noqa: C901 (a branch per option checked and output written)
    """Run ``args.scene`` (or continue the saved run ``--resume``) for ``--t`` / ``--steps`` or
    ``--until`` its balls are done; save the run (``--out``), its plot, frames and GIF; 0, or
    ``KeyboardInterrupt`` raised again after saving what was simulated."""
    check_writable(args.out, "--out", (".npz",))
    check_plot(args.plot)
    check_writable(args.gif, "--gif", (".gif",))
    if not (args.out or args.plot):
        refuse_without(args, {"record_every": "--record-every"}, "--out or --plot (which keep the record)")
    if not (args.frames or args.gif):
        frame_options = {"frames_every": "--frames-every", "camera": "--camera", "follow": "--follow", "size": "--size"}
        refuse_without(args, frame_options, "--frames or --gif (which the frames are drawn for)")
    if args.follow and args.camera == "follow":
        raise ConfigError("--follow", None, "has no effect with --camera follow, which chases ball 0 itself")
    if args.frames is not None and not args.frames.strip():
        raise ConfigError("--frames", None, "needs a folder name (got an empty path)")
    if args.frames is not None and Path(args.frames).exists() and not Path(args.frames).is_dir():
        raise ConfigError("--frames", None, f"{args.frames!r} is a file, not a folder")
    if args.frames is not None and not Path(args.frames).resolve().parent.is_dir():
        parent = str(Path(args.frames).resolve().parent)
        raise ConfigError("--frames", None, f"cannot make {args.frames!r}: folder {parent!r} does not exist")
    if args.t is not None and not (math.isfinite(args.t) and 0 < args.t <= TIME_LIMIT):
        raise ConfigError("--t", None, f"must be in (0, {TIME_LIMIT:g}] seconds (got {args.t})")
    if args.steps is not None and args.steps <= 0:
        raise ConfigError("--steps", None, f"must be > 0 (got {args.steps})")
    if args.record_every < 0:
        raise ConfigError("--record-every", None, f"must be >= 0 (got {args.record_every})")
    if args.t is not None or args.steps is not None:  # (world.t_end is the length of a run given neither)
        refuse_replaced(args.overrides, {"world.t_end": "--t" if args.t is not None else "--steps"})
    sim = scene_or_saved_run(args, "run")
    check_until(args.until, sim)
    check_steps_span(args.steps, sim.dt)
    resumed_at = sim.t if args.resume else None
    record_every = args.record_every
    if args.plot and not record_every:
        duration = args.t if args.t is not None else (args.steps or 0) * sim.dt or sim.scene.world.t_end
        record_every = max(1, int(duration / sim.dt / 400))
    frames = _Frames(args, sim) if (args.frames or args.gif) else None
    progress = Progress()
    t0 = time.perf_counter()
    rec = Recording()  # (filled as the run goes: what was sampled is kept if it is interrupted)
    partial = False
    try:
        if frames is not None:
            frames(sim)
        sim.run(
            t=args.t,
            steps=args.steps,
            until=args.until,
            record_every=record_every,
            progress=progress,
            every=frames.every if frames else 0,
            on_every=frames,
            recording=rec,
        )
    except KeyboardInterrupt:  # Ctrl-C, or SIGTERM (see cli.main)
        partial = True
        gif = args.gif if frames is not None and frames.any else None
        kept = [p for p in (args.out, args.plot if len(rec.t) > 1 else None, gif) if p and sim.t > 0]
        listed = ", ".join(kept[:-1]) + " and " + kept[-1] if len(kept) > 1 else "".join(kept)
        saved = f"; what was simulated is kept in {listed} (marked partial)" if kept else ""
        raise KeyboardInterrupt(f"at t = {sim.t:.4g} s{saved}") from None
    finally:
        # a second Ctrl-C or SIGTERM waits until what was simulated is written (SIGKILL does not)
        with whole_steps("writing what was simulated first") as came:
            progress.close()
            if frames is not None:
                frames.close()  # the frames rendered so far are kept, and the GIF is written from them
            if args.out and sim.t > 0:
                sim.save(args.out, rec, partial=partial)  # save what was simulated even if the run stopped early
            if partial and args.plot and len(rec.t) > 1:
                _plot(rec, args.plot, sim)
            if partial:
                came.clear()  # (stopping already: a second signal asks nothing more)
    elapsed = time.perf_counter() - t0
    counts = sim.counts()
    resumed = "" if resumed_at is None else f" (resumed at t = {resumed_at:.4g} s)"
    print(
        f"{sim.scene.name}: {sim.n} ball(s), t = {sim.t:.4g} s{resumed} in {elapsed:.2f} s; "
        + ", ".join(f"{counts[name]} {name.replace('_', ' ')}" for name in STATUS_NAMES.values())
    )
    if args.until:
        say_unfinished(sim, args)
    if sim.solver is not None:
        deepest = sim.deepest_overlap()
        if deepest is None:
            print("no two balls overlap")
        elif deepest.fraction < 1e-6:  # resting contacts left at round-off
            print("no two balls overlap by more than a millionth of a radius")
        else:
            print(
                f"deepest overlap: {100 * deepest.fraction:.3g} % of a radius ({1e3 * deepest.depth:.3g} mm, "
                f"balls {deepest.i} and {deepest.j})"
            )
    f = sim.flight()
    x, status = sim.x, sim.status

    def state_of(i: int) -> str:  # "at rest", "out of bounds", ...
        return STATUS_NAMES[int(status[i])].replace("_", " ")

    launch_y = sim.launch_x[:, 1] if sim.launch_x is not None else np.zeros(sim.n)
    for i in np.flatnonzero(f.landed)[:10]:  # (apex above the launch point, as the shots' and sweeps' tables)
        print(
            f"ball {i}: carry {f.carry[i]:.3f} m, apex {f.apex[i] - launch_y[i]:.2f} m above launch, "
            f"flight {f.flight_time[i]:.3f} s, "
            f"lands at {f.landing_angle[i]:.1f} deg, {f.landing_speed[i]:.2f} m/s; now at "
            f"x = {x[i, 0]:.2f} m, z = {x[i, 2]:.2f} m ({state_of(i)})"
        )
    hole = sim.scene.hole
    if hole is not None:
        away = np.hypot(x[:, 0] - hole.position[0], x[:, 2] - hole.position[1])
        for i in range(min(sim.n, 10)):
            print(
                f"ball {i}: {away[i]:.2f} m from the hole at x = {hole.position[0]:g} m, z = {hole.position[1]:g} m "
                f"({state_of(i)})"
            )
    if args.out:
        print(f"wrote {args.out}")
    if args.plot:
        _plot(rec, args.plot, sim)
        print(f"wrote {args.plot}")
    return 0


def _plot(rec: Recording, path: str, sim: Simulation) -> None:
    """Draw the run's trajectory and spin (:func:`ti_golf.render.plots.plot_run`) to ``path``."""
    from ti_golf.render.plots import plot_run  # (matplotlib: imported only to plot)

    plot_run(rec, path, title=sim.scene.description or sim.scene.name)


class _Frames:
    """Renders a frame every K steps to numbered PNGs (``--frames DIR``) and/or an animated GIF.

    The ``side``, ``top`` and ``iso`` cameras hold still (unless ``--follow``): the balls'
    positions and status are kept at every frame (13 bytes per ball and frame) and the frames
    drawn once the run ends, through one camera that frames everything the run showed. With
    ``--follow`` or the ``follow`` camera, each frame is drawn as the run reaches it."""

    def __init__(self, args: argparse.Namespace, sim: Simulation) -> None:
        if args.frames_every < 0:
            raise ConfigError("--frames-every", None, f"must be >= 0 (got {args.frames_every})")
        check_writable(args.gif, "--gif", (".gif",))
        duration = args.t if args.t is not None else (args.steps or 0) * sim.dt or sim.scene.world.t_end
        self.every = args.frames_every or max(1, int(round(duration / sim.dt / 100)))  # ~100 frames
        self.size = args.size
        self.camera = args.camera
        self.still = args.camera != "follow" and not args.follow
        self.gif = args.gif
        self.fps = max(1.0, min(50.0, 1.0 / (self.every * sim.dt)))
        self._sim = sim
        self._kept: list[tuple[np.ndarray, np.ndarray]] = []
        self._lo = np.full(3, np.inf)
        self._hi = np.full(3, -np.inf)
        self._tmp = None
        if args.frames:
            self.folder = Path(args.frames)
            self.folder.mkdir(exist_ok=True)  # (its folder exists: checked, as every output's is)
        else:
            self._tmp = tempfile.TemporaryDirectory()
            self.folder = Path(self._tmp.name)
        self.paths: list[Path] = []

    def __call__(self, sim: Simulation) -> None:
        if not self.still:
            self._draw(sim, self.camera)
            return
        x = sim.x
        seen = x[np.all(np.isfinite(x), axis=1)]
        if len(seen):
            self._lo, self._hi = np.minimum(self._lo, seen.min(axis=0)), np.maximum(self._hi, seen.max(axis=0))
        self._kept.append((x.astype(np.float32), sim.status.astype(np.int8)))

    def _draw(self, sim: Any, camera: Any, extent: np.ndarray | None = None) -> None:
        from ti_golf.render import render  # (imports matplotlib: only when frames are drawn)

        path = self.folder / f"frame_{len(self.paths):05d}.png"
        render(sim, path, camera=camera, size=self.size, extent=extent)
        self.paths.append(path)

    def _draw_kept(self) -> None:
        """Draw the frames kept, through one camera that frames all of them."""
        from ti_golf.render import camera_view

        if not self._kept:
            return
        extent = np.array([self._lo, self._hi]) if np.all(np.isfinite(self._lo)) else None
        view = camera_view(self._sim, self.camera, self.size, extent=extent)
        progress = Progress(unit="frames")
        try:
            for k, (x, status) in enumerate(self._kept):
                self._draw(_Kept(self._sim, x, status), view, extent)
                progress(k + 1, len(self._kept))
        finally:
            progress.close()
        self._kept.clear()

    @property
    def any(self) -> bool:
        """Whether a frame was drawn or kept to draw."""
        return bool(self.paths or self._kept)

    def close(self) -> None:
        self._draw_kept()
        if self.gif and self.paths:
            from PIL import Image  # (Pillow: imported only to write a GIF)

            images = [Image.open(p).convert("P", palette=Image.Palette.ADAPTIVE) for p in self.paths]
            with atomic_path(self.gif) as tmp:
                images[0].save(
                    tmp, format="GIF", save_all=True, append_images=images[1:], duration=int(1000 / self.fps), loop=0
                )
            with Image.open(self.gif) as gif:  # what the file holds: Pillow merges identical neighbours
                frames = getattr(gif, "n_frames", 1)
            merged = (
                f"; {len(images) - frames} unchanged frames merged into the one before" if frames < len(images) else ""
            )
            print(
                f"wrote {self.gif}: {frames} frames, {len(images) * int(1000 / self.fps) / 1000:.3g} s "
                f"at {1000 / int(1000 / self.fps):.3g} frames/s{merged}"
            )
        if self._tmp is None and self.paths:
            print(f"wrote {len(self.paths)} frames to {self.folder}")
        if self._tmp is not None:
            self._tmp.cleanup()


class _Kept:
    """A simulation as it was at a frame kept for drawing (its balls' positions and status); the
    balls' sizes, the ground and the scene (:attr:`SAME`) are those of the simulation itself."""

    SAME = ("model", "scene", "n", "launch_x")

    def __init__(self, sim: Simulation, x: np.ndarray, status: np.ndarray) -> None:
        self._sim = sim
        self.x = x.astype(np.float64)
        self.status = status.astype(np.int32)

    def __getattr__(self, name: str) -> Any:
        if name in self.SAME:
            return getattr(self._sim, name)
        raise AttributeError(f"a kept frame has no {name!r} (only x, status and {', '.join(self.SAME)})")
