"""The lab application's logic (report §2.2 and §2.4, "lab3"), apart from its window.

A :class:`Lab` holds one :class:`~ti_golf.Simulation` of a scene (a configuration profile: a
bundled scene or a scene file) and does what the window's buttons do: Start, Stop, Continue,
Step, Reset t0; change a scene key, checked as the scene loader checks it (a refused value comes
back as a message naming the key and the allowed values, never as an exception); edit the
selected ball's position, velocity and spin; read out the run; save it. :meth:`Lab.advance`
steps the simulation a frame's worth at a time, within a time budget, so that a window drawing
between calls stays responsive. No GGUI here: tests drive a :class:`Lab` headless.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ti_golf.errors import ConfigError, SimulationError, TiGolfError
from ti_golf.lab.params import Parameter, format_value, parameters
from ti_golf.render.plots import plot_speed, plot_spin, plot_trajectory
from ti_golf.scene.loader import load_scene, scenes_dir
from ti_golf.scene.schema import AT_REST, OUT_OF_BOUNDS, Scene
from ti_golf.sim.changes import at_t0
from ti_golf.sim.results import Recording
from ti_golf.sim.simulation import Simulation

DEFAULT_SCENE = "lab_magnus"
"""The scene the lab opens with: one ball launched with backspin (report Table 3.1-1, row 4)."""

RECORD_DT = 0.01
"""Simulated time [s] between the samples of a run (trails and plots): at least one time step."""

MAX_SAMPLES = 4000
"""Samples kept of a run; beyond, every other one is dropped and the interval doubled."""

MAX_RECORDED_BALLS = 100
"""Runs of more balls keep no samples (no trails, no plots: a pile's would fill the memory)."""

FRAME_BUDGET_S = 0.03
"""Wall-clock time [s] :meth:`Lab.advance` spends stepping per frame, at most (one step at least)."""


def bundled_scenes() -> list[str]:
    """The names of the bundled scenes (``ti-golf scenes``), sorted."""
    return sorted(p.stem for p in scenes_dir().glob("*.toml"))


class LabRecording(Recording):
    """A :class:`~ti_golf.Recording` with the velocities too: ``traj_v`` (S, N, 3) [m/s] beside
    ``traj_t``, ``traj_x`` and ``traj_w`` (saved with the run)."""

    def __init__(self) -> None:
        super().__init__()
        self.v: list[np.ndarray] = []

    def arrays(self) -> dict[str, np.ndarray]:
        """``traj_t`` (S,), ``traj_x``, ``traj_v``, ``traj_w`` (S, N, 3)."""
        return {**super().arrays(), "traj_v": np.asarray(self.v)}

    def append(self, t: float, x: np.ndarray, v: np.ndarray, w: np.ndarray) -> None:
        """Add the sample of time ``t`` [s]."""
        self.t.append(t)
        self.x.append(x)
        self.v.append(v)
        self.w.append(w)

    def thin(self) -> None:
        """Keep every other sample, from the first."""
        self.t = self.t[::2]
        self.x, self.v, self.w = self.x[::2], self.v[::2], self.w[::2]


@dataclass(frozen=True)
class Readout:
    """What the lab shows of its run.

    Attributes:
        scene: the scene's name.
        t: simulated time [s]; ``steps``: time steps taken since t0; ``dt``: the time step h [s].
        n: number of balls; ``counts``: how many are flying, rolling, at_rest, out_of_bounds.
        ball: the selected ball's id; ``x``, ``v``, ``w``: its position [m], velocity [m/s] and
            spin [rad/s], each (3,).
        running: whether the run goes on in the next frames; ``t_stop``: the time [s] it stops at.
        steps_per_s: time steps per second of wall-clock time over the last frames (of the
            time spent stepping, when no frame times are given; 0: stopped).
        message: the last thing the lab has to say (a refused value, a saved file ...).
    """

    scene: str
    t: float
    steps: int
    dt: float
    n: int
    counts: dict[str, int]
    ball: int
    x: np.ndarray
    v: np.ndarray
    w: np.ndarray
    running: bool
    t_stop: float
    steps_per_s: float
    message: str

    @property
    def speed(self) -> float:
        """The selected ball's speed |v| [m/s]."""
        return float(np.linalg.norm(self.v))

    @property
    def spin(self) -> float:
        """The selected ball's spin |ω| [rad/s]."""
        return float(np.linalg.norm(self.w))

    @property
    def height(self) -> float:
        """The selected ball's height [m]: the y of its centre."""
        return float(self.x[1])

    def lines(self, rates: bool = True) -> list[str]:
        """The readout as lines of text (``rates``: with the steps per second, which vary from run
        to run)."""
        c = self.counts
        state = f"running to t = {self.t_stop:.4g} s" if self.running else "stopped"
        out = [
            f"t = {self.t:.4f} s  ({self.steps} steps of {self.dt:.4g} s), {state}",
            f"{self.n} ball{'s' if self.n != 1 else ''}: {c['flying']} flying, {c['rolling']} rolling, "
            f"{c['at_rest']} at rest, {c['out_of_bounds']} out",
            f"ball {self.ball}: speed {self.speed:.3f} m/s, spin {self.spin:.2f} rad/s "
            f"({self.spin * 30.0 / math.pi:.0f} rpm), height {self.height:.3f} m",
        ]
        if rates and self.running:
            out.append(f"{self.steps_per_s:,.0f} steps/s: {self.steps_per_s * self.dt:.2f} s simulated per second")
        return out


@dataclass
class _Pace:
    """Wall-clock pacing: simulated time owed to real time [s], and the steps per second over
    the last frames."""

    owed_s: float = 0.0
    rate: float = 0.0
    window: list[tuple[float, int]] = field(default_factory=list)

    def note(self, seconds: float, steps: int) -> None:
        self.window = (self.window + [(seconds, steps)])[-20:]
        spent = sum(s for s, _ in self.window)
        self.rate = sum(k for _, k in self.window) / spent if spent > 0 else 0.0


class Lab:
    """The lab on one scene: run, stop, change, continue, reset, save.

    Args:
        scene: a bundled scene's name or a scene file (default :data:`DEFAULT_SCENE`).
        overrides: ``--set`` changes of the scene, as :func:`~ti_golf.load_scene` takes them.
        speed: simulated seconds per second of wall-clock time while running (1: real time), or
            ``None``: as fast as :data:`FRAME_BUDGET_S` per frame allows.

    Raises:
        ConfigError: the scene cannot be loaded (naming the file and the key).
    """

    def __init__(
        self,
        scene: str | Path = DEFAULT_SCENE,
        overrides: Iterable[str] | dict[str, Any] | None = None,
        *,
        speed: float | None = 1.0,
    ) -> None:
        self.speed = speed
        self.message = ""
        """The last thing the lab has to say: a refused value with its allowed range, a saved file."""
        self.refused = False
        """Whether :attr:`message` says that something was refused or went wrong."""
        self.scenes = bundled_scenes()
        """The scenes the lab offers: the bundled ones, and the scene file it was given."""
        self.sim: Simulation = None  # type: ignore[assignment]
        self._params: tuple[Scene | None, list[Parameter]] = (None, [])
        self._open(load_scene(scene, overrides))

    # -- the scene --------------------------------------------------------------------------------
    @property
    def scene(self) -> Scene:
        """The scene with every change made so far."""
        return self.sim.scene

    def load(self, scene: str | Path, overrides: Iterable[str] | dict[str, Any] | None = None) -> str | None:
        """Open another scene (a bundled scene's name or a scene file) at t0, stopped; returns
        ``None``, or the message that says why it cannot be loaded (the lab keeps its scene)."""
        try:
            loaded = load_scene(scene, overrides)
        except ConfigError as exc:
            return self._say(str(exc), refused=True)
        try:
            self._open(loaded)
        except (TiGolfError, ValueError, MemoryError) as exc:
            return self._say(str(exc), refused=True)
        self._say(f"loaded {loaded.name}")
        return None

    def _open(self, scene: Scene) -> None:
        self.sim = Simulation(scene)  # (made first: when it cannot be, the lab keeps its scene)
        if scene.path and Path(scene.path).resolve().parent != scenes_dir().resolve() and scene.path not in self.scenes:
            self.scenes.append(scene.path)  # a scene file of the user's, offered beside the bundled ones
        self.selected = 0
        self.running = False
        self.finished = False
        self.t_stop = self.scene.world.t_end
        self._pace = _Pace()
        self._new_recording()

    def parameters(self, table: str | None = None) -> list[Parameter]:
        """The scene's editable keys (of ``table`` only, when given) with unit, value, help and
        slider span (:mod:`.params`); worked out once per change of the scene."""
        if self._params[0] is not self.scene:
            self._params = (self.scene, parameters(self.scene))
        return [p for p in self._params[1] if table is None or p.table == table]

    def set(self, key: str, value: Any) -> str | None:
        """Change the scene key ``key`` (``"air.C_D"``) to ``value``, checked as the scene loader
        checks ``--set`` (the same ranges), from the next step on. The keys that set up the balls
        or the ground (``launch.*``, ``ball.*``, ``terrain.*``) change at t0 only. Returns ``None``,
        or the message saying why the value was refused (the run is then unchanged)."""
        if at_t0(key) and self.sim.step_count > 0:
            return self._say(
                f"{key} sets up the balls or the ground at t0, and the run is at t = {self.sim.t:.4g} s: "
                "press Reset t0, then change it",
                refused=True,
            )
        at_start = self.sim.step_count == 0
        try:
            self.sim.set(key, value)
        except ConfigError as exc:
            return self._say(f"{exc.key}: {exc.reason}" if exc.key else exc.reason, refused=True)
        except (TiGolfError, ValueError, MemoryError) as exc:
            return self._say(f"{key}: {exc}", refused=True)
        if at_start:  # the balls may have been set up again
            self.selected = min(self.selected, self.sim.n - 1)
            self._new_recording()
        elif key == "world.dt" and self.recording is not None:
            self._record_every = self._sampling_steps()
        if key == "world.t_end" and self.scene.world.t_end > self.sim.t:
            self.t_stop = self.scene.world.t_end
        self._say(f"{key} = {format_value(self._current(key))}")
        return None

    def _current(self, key: str) -> Any:
        table, name = key.split(".", 1)
        return getattr(getattr(self.scene, table), name)

    # -- the selected ball ------------------------------------------------------------------------
    def select(self, ball: int) -> None:
        """Select ball ``ball`` (clamped to 0 … N − 1) for the readout and :meth:`set_ball`."""
        self.selected = int(min(max(int(ball), 0), self.sim.n - 1))

    def set_ball(self, x: Any = None, v: Any = None, w: Any = None) -> str | None:
        """Give the selected ball the position ``x`` [m], velocity ``v`` [m/s] and spin ``w``
        [rad/s] (each (3,), or ``None`` to leave it); it flies on from there. Returns ``None``, or
        the message saying why the values were refused."""
        values: dict[str, np.ndarray] = {}
        for name, value in (("x", x), ("v", v), ("w", w)):  # (checked before anything changes)
            if value is None:
                continue
            try:
                values[name] = np.asarray(value, dtype=np.float64).reshape(-1)
            except (ValueError, TypeError):
                values[name] = np.zeros(0)
            if values[name].shape != (3,):
                return self._say(f"{name} of ball {self.selected} takes three numbers [x, y, z] (got {value!r})", True)
        try:
            self.sim.set_ball(self.selected, **values)
        except ValueError as exc:
            return self._say(str(exc), refused=True)
        if self.recording is not None and self.recording.t:
            self._sample()  # the trail goes on from the ball's new state
        edited = ", ".join(f"{n} = {format_value(tuple(map(float, a)))}" for n, a in values.items())
        self._say(f"ball {self.selected}: {edited}")
        return None

    # -- Start, Stop, Continue, Step, Reset t0 -------------------------------------------------------
    def start(self) -> None:
        """Run from t0 (going back to it first when the run has begun) to ``world.t_end``."""
        if self.sim.step_count > 0:
            self.reset()
        self.t_stop = self.scene.world.t_end
        self._go("running")

    def stop(self) -> None:
        """Stop after the current frame's steps; :meth:`resume` goes on from here."""
        if self.running:
            self.running = False
            self._say(f"stopped at t = {self.sim.t:.4f} s")

    def resume(self) -> None:
        """Continue from the current state with the current parameters: to ``world.t_end``, or,
        once that is reached, for ``world.t_end`` more."""
        if self.sim.t >= self.t_stop - 0.5 * self.sim.dt:
            self.t_stop = self.sim.t + self.scene.world.t_end
        self._go("continuing")

    def toggle(self) -> None:
        """Space: stop a running run, else continue one that has begun, else start."""
        if self.running:
            self.stop()
        elif self.sim.step_count > 0:
            self.resume()
        else:
            self.start()

    def step(self, n: int = 1) -> int:
        """Stop, then advance ``n`` time steps (the Step button: one); returns the steps taken."""
        self.running = False
        self._begin()
        self._say("")
        done = self._steps(int(n), math.inf)
        if not self.message:  # (else the steps had something to say)
            self._say(f"t = {self.sim.t:.6g} s")
        return done

    def reset(self) -> None:
        """Reset t0: stop and go back to the initial conditions, keeping the changed parameters
        (bit for bit the state of a new simulation of the changed scene)."""
        self.sim.reset()
        self.selected = min(self.selected, self.sim.n - 1)
        self.running = False
        self.finished = False
        self.t_stop = self.scene.world.t_end
        self._new_recording()
        self._say("back at t0")

    def _go(self, what: str) -> None:
        self.running = True
        self.finished = False
        self._pace = _Pace()
        self._begin()
        self._say(f"{what} from t = {self.sim.t:.4f} s")

    def _begin(self) -> None:
        """The first sample of a run that starts at t0."""
        if self.recording is not None and not self.recording.t:
            self._sample()

    def advance(
        self, wall_dt: float | None = None, budget_s: float = FRAME_BUDGET_S, max_steps: int | None = None
    ) -> int:
        """One frame of a running run: the steps ``wall_dt`` seconds of wall-clock time call for at
        the lab's :attr:`speed` (all that fit in ``budget_s`` when the speed is ``None`` or no
        ``wall_dt`` is given; one at least), or exactly ``max_steps``; never past the run's stop
        time. The run stops by itself at its stop time, when every ball is at rest or out of
        bounds, or when a ball goes non-finite (the message names it). Returns the steps taken."""
        if not self.running:
            return 0
        dt = self.sim.dt
        wanted: float
        if max_steps is not None:
            wanted = int(max_steps)
        elif self.speed is None or wall_dt is None:
            wanted = math.inf
        else:
            self._pace.owed_s += self.speed * wall_dt
            wanted = max(int(self._pace.owed_s / dt + 1e-9), 0)
        left = max(int(math.ceil((self.t_stop - self.sim.t) / dt - 1e-9)), 0)
        want = min(wanted, left)
        budget = math.inf if max_steps is not None else budget_s
        start = time.perf_counter()
        done = self._steps(want, budget) if want > 0 else 0
        self._pace.note(time.perf_counter() - start if wall_dt is None else wall_dt, done)
        if max_steps is None and self.speed is not None and wall_dt is not None:
            self._pace.owed_s = 0.0 if done < want else self._pace.owed_s - done * dt  # (too slow: no catching up)
        if self.running and self.sim.t >= self.t_stop - 0.5 * dt:
            self.running, self.finished = False, True
            self._say(f"reached t = {self.sim.t:.4g} s (world.t_end = {self.scene.world.t_end:g} s): Continue runs on")
        return done

    def _steps(self, n: float, budget_s: float) -> int:
        """Take up to ``n`` steps within ``budget_s`` seconds (at least one), sampling the run;
        stops the run when every ball has settled or one went non-finite."""
        start = time.perf_counter()
        done, chunk = 0, 1
        while done < n:
            k = int(min(n - done, chunk))
            if self.recording is not None:  # (a sample falls due after at most this many)
                k = max(min(k, self._record_every - self._since_sample), 1)
            try:
                self.sim.step(k)
            except SimulationError as exc:
                self.running = False
                self._say(f"stopped: {exc}", refused=True)
                return done + k
            done += k
            if self.recording is not None:
                self._since_sample += k
                if self._since_sample >= self._record_every:
                    self._sample()
            if self._settled():
                if self.running:
                    self.running, self.finished = False, True
                    self._say(f"every ball is at rest or out of bounds at t = {self.sim.t:.4g} s")
                break
            elapsed = time.perf_counter() - start
            if elapsed >= budget_s:
                break
            if math.isfinite(budget_s):  # as many steps as the rest of the budget holds, at the rate so far
                chunk = max(1, min(int(done * (budget_s - elapsed) / max(elapsed, 1e-9)), 2 * chunk + 1))
            else:
                chunk = max(chunk, int(min(n - done, 1 << 16)))
        return done

    def _settled(self) -> bool:
        s = self.sim.status
        return bool(np.all((s == AT_REST) | (s == OUT_OF_BOUNDS)))

    # -- the recording ----------------------------------------------------------------------------
    def _new_recording(self) -> None:
        self.recording: LabRecording | None = LabRecording() if self.sim.n <= MAX_RECORDED_BALLS else None
        """The run's samples (every :data:`RECORD_DT` of simulated time), or ``None`` for a scene
        of more than :data:`MAX_RECORDED_BALLS` balls."""
        self._record_every = self._sampling_steps()
        self._since_sample = 0

    def _sampling_steps(self) -> int:
        return max(1, int(round(RECORD_DT / self.sim.dt)))

    def _sample(self) -> None:
        rec = self.recording
        assert rec is not None
        rec.append(self.sim.t, self.sim.x, self.sim.v, self.sim.w)
        self._since_sample = 0
        if len(rec.t) > MAX_SAMPLES:
            rec.thin()
            self._record_every *= 2

    def trails(self) -> np.ndarray | None:
        """The balls' recorded path (S, N, 3) [m] up to now, or ``None``."""
        rec = self.recording
        if rec is None or len(rec.x) < 1:
            return None
        return np.asarray(rec.x)

    # -- what the window shows ----------------------------------------------------------------------
    def readout(self) -> Readout:
        """The run's time, the balls' states and the selected ball (see :class:`Readout`)."""
        sim, i = self.sim, self.selected
        x, v, w = sim.ball(i)
        return Readout(
            self.scene.name,
            sim.t,
            sim.step_count,
            sim.dt,
            sim.n,
            sim.counts(),
            i,
            x,
            v,
            w,
            self.running,
            self.t_stop,
            self._pace.rate if self.running else 0.0,
            self.message,
        )

    # -- Save ---------------------------------------------------------------------------------------
    def save(self, folder: str | Path = ".", screenshot: Callable[[Path], None] | None = None) -> list[Path]:
        """Save the run into ``folder``: ``SCENE_NNN.npz`` (:meth:`Simulation.save`, with the
        samples, so that ``ti-golf run --resume`` or :meth:`Simulation.load` continues it), its
        plots ``SCENE_NNN_trajectory.png``, ``_speed.png`` and ``_spin.png`` (when the run has
        samples) and, given ``screenshot`` (a function writing a PNG to the path it gets),
        ``SCENE_NNN_screen.png``; NNN is the first number not yet saved there. Every file is
        written whole or not at all. Returns the files written: when one cannot be written, those
        before it stay, and the message names them and says why the rest were not."""
        folder = Path(folder)
        stem = _free_stem(folder, self.scene.name)
        rec = self.recording
        written: list[Path] = []
        try:
            npz = folder / f"{stem}.npz"
            self.sim.save(npz, rec, partial=not self.finished)
            written.append(npz)
            if rec is not None and len(rec.t) >= 2:
                a = rec.arrays()
                title = f"{self.scene.name}: t = 0 to {self.sim.t:.4g} s"
                plots = (
                    ("trajectory", lambda p: plot_trajectory(a["traj_x"], p, title)),
                    ("speed", lambda p: plot_speed(a["traj_t"], a["traj_v"], p, title)),
                    ("spin", lambda p: plot_spin(a["traj_t"], a["traj_w"], p, title)),
                )
                for name, draw in plots:
                    path = folder / f"{stem}_{name}.png"
                    draw(path)
                    written.append(path)
            if screenshot is not None:
                path = folder / f"{stem}_screen.png"
                screenshot(path)
                written.append(path)
        except OSError as exc:
            kept = f" (saved {', '.join(p.name for p in written)} before it)" if written else ""
            self._say(f"cannot save into {str(folder)!r}: {exc.strerror or exc}{kept}", refused=True)
            return written
        note = "" if rec is not None else f" (no plots: more than {MAX_RECORDED_BALLS} balls are not sampled)"
        self._say(f"saved {', '.join(p.name for p in written)} in {folder}{note}")
        return written

    def _say(self, text: str, refused: bool = False) -> str:
        self.message, self.refused = text, refused
        return text


def _free_stem(folder: Path, name: str) -> str:
    """``NAME_NNN`` with the first NNN (from 001) whose run file is not in ``folder`` yet."""
    k = 1
    while (folder / f"{name}_{k:03d}.npz").exists():
        k += 1
    return f"{name}_{k:03d}"
