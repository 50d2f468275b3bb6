"""Launch-condition sweeps: one ball per (angle, speed, spin), all integrated together to landing."""

from __future__ import annotations

import csv
import math
import os
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ti_golf.errors import ConfigError, SimulationError
from ti_golf.files import atomic_path
from ti_golf.golf.rollout import shots_from_landing
from ti_golf.physics import kernels
from ti_golf.physics.aero import air_params
from ti_golf.physics.kinds import kinds_of
from ti_golf.physics.types import vec3
from ti_golf.runtime import available_memory, ensure_init, np_float, on_cpu, plain_compile
from ti_golf.scene.balls import check_flies_alone, launch_position
from ti_golf.scene.checks import SPEED_LIMIT, SPIN_LIMIT, parse_range
from ti_golf.scene.document import check_values
from ti_golf.scene.loader import load_scene
from ti_golf.scene.schema import Scene, backspin_axis
from ti_golf.signals import KeptInterrupt, whole_steps
from ti_golf.sim.given import whole_number
from ti_golf.sim.results import CSV_COLUMNS, ROLLED_CSV_COLUMNS, Flight, Shots
from ti_golf.sim.simulation import RunProgress


@dataclass(frozen=True)
class SweepResult:
    """Outcome of a sweep, one entry per launch condition (N entries).

    Attributes:
        angle_deg, speed_mps, spin_radps: the launch conditions, shape (N,).
        flight: carry, apex, landing point, time, angle and speed, shape (N,) each.
        traj_index: indices of the conditions whose trajectories were recorded, shape (K,).
        traj: their centre positions [m], shape (K, S, 3), sampled every ``traj_dt`` seconds
            (after landing a trajectory repeats its landing point); ``None`` if not recorded.
        traj_dt: sampling interval of ``traj`` [s].
        scene: the scene the sweep ran.
        shots: the numbers golfers read (offline, apex above launch, land spin; total and roll
            when rolled out to rest), shape (N,) each; ``None`` for a result built without them.
    """

    angle_deg: np.ndarray
    speed_mps: np.ndarray
    spin_radps: np.ndarray
    flight: Flight
    scene: Scene
    traj_index: np.ndarray | None = None
    traj: np.ndarray | None = None
    traj_dt: float = 0.0
    shots: Shots | None = None

    @property
    def carry(self) -> np.ndarray:
        """Carry [m], shape (N,): negative for a ball that lands behind the launch point (along the
        target line, :attr:`Shots.carry`; the distance alone for a result built without shots)."""
        return self.flight.carry if self.shots is None else self.shots.carry

    def best(self) -> int:
        """Index of the longest carry down the target line (ignoring balls that did not land); a
        ValueError when no ball landed (within ``world.t_max``)."""
        if not np.any(self.flight.landed):
            raise ValueError("no ball of the sweep landed (within world.t_max): it has no best launch")
        c = np.where(self.flight.landed, self.carry, -np.inf)
        return int(np.argmax(c))

    def columns(self) -> dict[str, np.ndarray]:
        """The CSV columns (see :data:`ti_golf.sim.results.CSV_COLUMNS`), then, when the balls
        were rolled out, :data:`~ti_golf.sim.results.ROLLED_CSV_COLUMNS`, as arrays (SI)."""
        f, s = self.flight, self.shots
        if s is None:
            raise ValueError("the CSV columns need the sweep's shots (SweepResult.shots)")
        cols = dict(
            zip(
                CSV_COLUMNS,
                (
                    self.angle_deg,
                    self.speed_mps,
                    self.spin_radps,
                    s.carry,
                    f.landing_x,
                    f.landing_z,
                    s.apex,
                    f.flight_time,
                    f.landing_angle,
                    f.landing_speed,
                    s.offline,
                    s.land_spin,
                ),
            )
        )
        if s.rolled_out:
            cols.update(zip(ROLLED_CSV_COLUMNS, (s.total, s.roll)))
        return cols

    def to_csv(self, path: str | os.PathLike[str]) -> None:
        """Write one row per launch condition with the :meth:`columns` header (whole or not at
        all)."""
        cols = self.columns()
        with atomic_path(path) as tmp, open(tmp, "w", newline="") as fh:
            out = csv.writer(fh, lineterminator="\n")
            out.writerow(cols)
            for row in zip(*cols.values()):
                out.writerow([f"{v:.10g}" for v in row])


def _values(name: str, given: Sequence[float] | str | None, default: Sequence[float]) -> np.ndarray:
    """The values a sweep takes for ``name``: ``given`` (numbers, or the command line's
    ``START:STOP:STEP`` or ``a,b,c`` text) or else ``default``, as a flat float array; a ConfigError
    naming ``name`` when they are not numbers."""
    if given is None:
        return np.asarray(default, float)
    if isinstance(given, str):
        return np.asarray(parse_range(given, name, None), float)
    try:
        raw = np.asarray(given)
        if np.iscomplexobj(raw) or raw.dtype == bool or raw.ndim > 1:
            raise TypeError
        return raw.astype(float).ravel()
    except (TypeError, ValueError):
        raise ConfigError(
            name, None, f"must be a flat list of numbers or START:STOP:STEP (got {given!r:.60})"
        ) from None


def launch_grid(
    scene: Scene,
    angles_deg: Sequence[float] | str | None = None,
    speeds: Sequence[float] | str | None = None,
    spins: Sequence[float] | str | None = None,
) -> tuple[np.ndarray, ...]:
    """All combinations (angle fastest, then spin, then speed) as arrays.

    ``spins`` are magnitudes [rad/s] along the scene's spin axis (or the backspin axis when the
    scene's spin is zero). Returns (angle_deg, speed, spin, x0, v0, w0), the last three (N, 3).
    """
    if scene.launch is None:
        raise ConfigError(
            *scene.where("launch"), "is required: a sweep launches its balls as the scene's [launch] table says"
        )
    L = scene.launch
    angles = _values("angles_deg", angles_deg, scene.sweep.angles or (L.angle_deg,))
    speeds_ = _values("speeds", speeds, scene.sweep.speeds or (L.speed,))
    spin_vec = np.asarray(L.spin, float)
    spin_mag = float(np.linalg.norm(spin_vec))
    axis = spin_vec / spin_mag if spin_mag > 0 else np.asarray(backspin_axis(L.direction_deg))
    spins_ = _values("spins", spins, scene.sweep.spins or (spin_mag,))
    for name, arr, lo, hi, allowed in (
        ("angles_deg", angles, -90, 90, "finite and in [-90, 90] deg"),
        ("speeds", speeds_, 0, SPEED_LIMIT, f"in [0, {SPEED_LIMIT:g}] m/s"),
        ("spins", spins_, -SPIN_LIMIT, SPIN_LIMIT, f"in [{-SPIN_LIMIT:g}, {SPIN_LIMIT:g}] rad/s"),
    ):
        if arr.size == 0:
            raise ConfigError(name, None, "needs at least one value")
        bad = arr[~(np.isfinite(arr) & (arr >= lo) & (arr <= hi))]
        if bad.size:
            raise ConfigError(name, None, f"values must be {allowed} (got {bad[0]:g})")
    _check_grid_memory(angles.size * speeds_.size * spins_.size)
    sp, sn, an = np.meshgrid(speeds_, spins_, angles, indexing="ij")
    an, sp, sn = an.ravel(), sp.ravel(), sn.ravel()
    n = an.size
    x0 = np.tile(np.asarray(launch_position(scene), float), (n, 1))
    th, ph = np.radians(an), math.radians(L.direction_deg)
    v0 = np.stack([sp * np.cos(th) * math.cos(ph), sp * np.sin(th), sp * np.cos(th) * math.sin(ph)], axis=1)
    w0 = sn[:, None] * axis[None, :]
    return an, sp, sn, x0, v0, w0


SWEEP_BYTES_PER_BALL = 1024
"""Peak memory [bytes] a ball of a sweep takes: its launch, its flight's outcomes and the result's
arrays, in float64, some 60 numbers, bounded with room to spare."""


def _check_grid_memory(n: int) -> None:
    """Refuse a grid of ``n`` launches that would not fit in the memory available, before making it."""
    need, avail = n * SWEEP_BYTES_PER_BALL, available_memory()
    if avail is not None and need > avail:
        raise ConfigError(
            "angles_deg",
            None,
            f"with the speeds and spins makes {n:,} launches, which would need about {need / 2**30:.1f} GiB of "
            f"memory ({SWEEP_BYTES_PER_BALL} bytes each); this machine has {avail / 2**30:.1f} GiB available: "
            "fewer values or a coarser step",
        )


def default_lanes() -> int:
    """Balls per CPU thread stepped side by side: 8 in f64, 16 in f32 (one AVX-512 register), 1 on
    GPUs, which already run one ball per SIMT lane."""
    if not on_cpu():
        return 1
    return 8 if ensure_init().precision == "f64" else 16


FLIGHT_STEPS_MAX = 1e8
"""The most steps a flight to landing may take (``world.t_max`` / ``world.dt``): :func:`fly` is one
kernel launch, which an interrupt cannot stop, and a ball that never lands (no gravity toward the
ground) takes them all; 1e8 steps of one ball take seconds."""


def fly(
    scene: Scene,
    x0: np.ndarray,
    v0: np.ndarray,
    w0: np.ndarray,
    record_every: int = 0,
    n_samples: int = 0,
    lanes: int | None = None,
    step_name: str = "world.dt",
) -> dict[str, np.ndarray]:
    """Integrate balls from (x0, v0, w0) (each (N, 3)) to landing at their launch height.

    Uses the scene's integrator and ``world.dt``; gives up on a ball after ``world.t_max``. Each
    ball flies alone: a scene with ``[[balls]]`` or ``[[blocks]]`` is refused (ConfigError).
    ``step_name`` names the step in errors (``flight_dt`` where a caller put its own step there).
    Balls are ordered by their drag-free flight time before they are grouped into SIMD lanes, so a
    group's balls land at about the same step. Returns the raw per-ball arrays: landed (N,), apex
    (N,), t_land (N,), the landing point land_x, velocity land_v and spin land_w (N, 3) and, when
    recording, traj (N, n_samples, 3).
    """
    check_flies_alone(scene)
    steps = scene.world.t_max / scene.world.dt
    if steps > FLIGHT_STEPS_MAX:
        blamed = ("world.t_max", "world.dt") if step_name == "world.dt" else ("world.t_max",)
        raise ConfigError(
            *scene.where(*blamed),
            f"allows {steps:.3g} steps of {step_name} = {scene.world.dt:g} s to a landing, in one kernel launch "
            f"that Ctrl-C cannot stop; at most {FLIGHT_STEPS_MAX:.0e} (world.t_max / {step_name}): a shorter "
            f"world.t_max or a longer {step_name}",
        )
    ensure_init()
    lanes = default_lanes() if lanes is None else int(lanes)
    f = np_float()
    a, wld = scene.air, scene.world
    n0 = len(x0)
    g = max(float(np.linalg.norm(wld.gravity)), 1e-9)
    order = np.argsort(2.0 * np.asarray(v0)[:, 1] / g)
    pad = (-n0) % lanes
    order = np.concatenate([order, np.full(pad, order[-1])])

    # numpy arrays go to the kernel directly (zero-copy on the CPU)
    def arr(values: np.ndarray) -> np.ndarray:
        return np.ascontiguousarray(values, dtype=f)

    radius, mass = np.full(n0, scene.ball.radius, f), np.full(n0, scene.ball.mass, f)
    landed = np.zeros(n0, np.int32)
    apex, t_land = np.zeros(n0, f), np.zeros(n0, f)
    land_x, land_v, land_w = np.zeros((n0, 3), f), np.zeros((n0, 3), f), np.zeros((n0, 3), f)
    traj = np.zeros((n0, n_samples, 3) if record_every else (1, 1, 3), f)
    air = air_params(a, wld.ground_height)
    with plain_compile():  # minutes less of compiling on first use, see runtime.plain_compile
        kernels.fly_to_landing(
            air,
            vec3(*wld.gravity),
            wld.dt,
            kinds_of(scene),
            lanes,
            wld.t_max,
            int(record_every),
            radius,
            mass,
            order.astype(np.int32),
            arr(x0),
            arr(v0),
            arr(w0),
            landed,
            apex,
            t_land,
            land_x,
            land_v,
            land_w,
            traj,
        )
    out = dict(landed=landed, apex=apex, t_land=t_land, land_x=land_x, land_v=land_v, land_w=land_w)
    if record_every:
        out["traj"] = traj
    bad = ~np.all(np.isfinite(np.concatenate([out["land_x"], out["land_v"], out["apex"][:, None]], axis=1)), axis=1)
    if np.any(bad):
        ids = np.flatnonzero(bad)
        raise SimulationError(
            f"{ids.size} ball(s) went non-finite, first ball {ids[0]} "
            f"(launch v = {np.round(v0[ids[0]], 6).tolist()} m/s); try a smaller {step_name}",
            ids[:20].tolist(),
        )
    if wld.gravity[1] < 0.0:  # (the bound of a ball pulled down; nothing bounds one that is not)
        _check_rise(out["apex"], x0, v0, a.wind, -wld.gravity[1], wld.dt, step_name)
    _check_landing(out["landed"], out["land_v"], v0, max(-wld.gravity[1], 0.0), wld.dt, step_name)
    return out


def _check_landing(landed: np.ndarray, land_v: np.ndarray, v0: np.ndarray, g: float, dt: float, step_name: str) -> None:
    """Raise :class:`SimulationError` for balls that landed while rising: a ball comes down to its
    launch height, so a landing velocity with an upward y component means that a step threw the
    ball below that height in one go (the landing is then put at the launch, carry 0), the
    integration of forces that act faster than a step (a light, large ball's drag, a fast spin's
    lift or decay). A ball launched upward at less than a step of gravity (``g``·``dt``) [m/s]
    does the same by right: it barely rises, and lands at its launch (it stopped a sweep of small
    speeds with this error)."""
    rising_fast = np.asarray(v0, float)[:, 1] > g * dt
    ids = np.flatnonzero(np.asarray(landed, bool) & (np.asarray(land_v, float)[:, 1] > 0.0) & rising_fast)
    if ids.size:
        i = ids[0]
        raise SimulationError(
            f"{ids.size} ball(s) fell below their launch height in one step while rising, first ball {i} "
            f"(launch v = {np.round(v0[i], 6).tolist()} m/s): the flight's integration diverged at {step_name} = "
            f"{dt:g} s: try a smaller {step_name} (a light, large ball's drag, or a fast spin's lift or decay, acts "
            "faster than a step)",
            ids[:20].tolist(),
        )


RISE_MARGIN = 10.0
"""How many times the height its launch can lift a ball (:func:`_check_rise`) a flight may rise
before it is taken for an integration that diverged: the wind's log profile grows with height, so
the bound of a uniform wind is kept with room to spare."""


def _check_rise(
    apex: np.ndarray, x0: np.ndarray, v0: np.ndarray, wind: Any, g: float, dt: float, step_name: str
) -> None:
    """Raise :class:`SimulationError` for balls that rose past what their launch can lift them.
    In the frame of a uniform wind, lift does no work and drag only takes energy, so a ball rises
    at most |v0 − wind|²/2g ≤ (|v0| + |wind|)²/2g (g [m/s²]: gravity's downward component);
    beyond :data:`RISE_MARGIN` times that (and 1 m), the explicit step was too long for the forces
    (a light, large ball: the drag's time m/(k|v|) under world.dt) and the flight grew without
    bound while it stayed finite."""
    reach = np.linalg.norm(np.asarray(v0, float), axis=1) + float(np.linalg.norm(wind))
    limit = RISE_MARGIN * reach**2 / (2.0 * g) + 1.0
    rise = np.asarray(apex, float) - np.asarray(x0, float)[:, 1]
    ids = np.flatnonzero(rise > limit)
    if ids.size:
        i = ids[0]
        raise SimulationError(
            f"{ids.size} ball(s) rose past what their launch can lift them, first ball {i}: {rise[i]:.3g} m "
            f"against at most {limit[i]:.3g} m; the flight's integration diverged at {step_name} = {dt:g} s: "
            f"try a smaller {step_name} (a light, large ball's drag acts faster than a step)",
            ids[:20].tolist(),
        )


def fly_then_roll_out(
    scene: Scene,
    x0: np.ndarray,
    v0: np.ndarray,
    w0: np.ndarray,
    to_rest: bool,
    progress: RunProgress | None = None,
    flown: Scene | None = None,
    step_name: str = "world.dt",
) -> tuple[dict[str, np.ndarray], Shots, KeyboardInterrupt | None]:
    """Fly balls from (x0, v0, ω0) (each (N, 3), SI) to landing, under ``flown``'s air and step
    (default: ``scene``'s; :func:`fly`, ``step_name`` naming its step), and with ``to_rest`` roll
    them out to rest on ``scene``'s ground (``progress(t_done, t_total)`` follows the roll-out).

    The flights are one kernel launch, which an interrupt waits for; the roll-out stops between its
    launches. Returns (raw, shots, stopped): :func:`fly`'s record, the :class:`Shots`, and the
    interrupt that cut them short or None. Cut during the flights, the shots are not rolled out;
    during the roll-out, they hold the rests reached by then.
    """
    stopped: KeyboardInterrupt | None = None
    try:
        with whole_steps():  # (a signal is raised as the block ends, once raw is set)
            raw = fly(flown or scene, x0, v0, w0, step_name=step_name)
    except KeyboardInterrupt as stop:
        stopped = stop
    try:
        shots = shots_from_landing(scene, x0, raw, to_rest and stopped is None, progress)
    except KeptInterrupt as stop:
        shots, stopped = stop.kept, stop
    return raw, shots, stopped


def sweep(
    scene: Scene | str | os.PathLike[str],
    angles_deg: Sequence[float] | str | None = None,
    speeds: Sequence[float] | str | None = None,
    spins: Sequence[float] | str | None = None,
    overrides: Mapping[str, Any] | Iterable[str] | None = None,
    trajectories: int = 0,
    to_rest: bool = False,
) -> SweepResult:
    """Fly one ball per launch condition, all together, until every ball has landed.

    Args:
        scene: a Scene, a TOML path or a bundled scene name.
        angles_deg: launch elevations [deg], numbers or a ``"START:STOP:STEP"`` text (STOP
            included) as the command line takes (default: the scene's ``[sweep]`` list, else its
            ``[launch]`` value). Every combination of angle, speed and spin is flown.
        speeds: launch speeds [m/s], likewise.
        spins: spin magnitudes [rad/s] along the scene's spin axis, likewise.
        overrides: scene overrides (``{"air.wind": [-5, 0, 0]}`` or ``["air.wind=[-5,0,0]"]``).
        trajectories: also record the trajectories of up to this many evenly spaced conditions.
        to_rest: also bounce and roll every ball from its landing to rest on the scene's ground
            (:func:`ti_golf.golf.rollout.roll_out`), for total and roll.

    Ctrl-C (or SIGTERM) waits for the flights, one kernel launch, and stops the roll-out between
    its launches: it raises :class:`~ti_golf.signals.KeptInterrupt` holding the result so far (no
    trajectories; without the roll-out when it came during the flights, else the balls that came
    to rest by then).

    Example:
        >>> res = sweep("lab_turbulent", angles_deg=np.arange(36, 37.41, 0.02))   # doctest: +SKIP
        >>> res.angle_deg[res.best()], res.carry.max()                           # doctest: +SKIP
    """
    trajectories = whole_number(trajectories, "trajectories")
    if not isinstance(to_rest, (bool, np.bool_)):
        raise TypeError(f"to_rest must be True or False (got {to_rest!r:.60})")
    if not isinstance(scene, Scene):
        scene = load_scene(scene, overrides)
    elif overrides:
        raise ValueError(
            "overrides go with a scene's name or file: sweep(name, overrides=...), or a Scene from "
            "tg.load_scene(name, overrides)"
        )
    check_values(scene, "scene")
    an, sp, sn, x0, v0, w0 = launch_grid(scene, angles_deg, speeds, spins)
    raw, shots, stopped = fly_then_roll_out(scene, x0, v0, w0, to_rest)
    flight = Flight.from_arrays(x0, raw["landed"], raw["apex"], raw["t_land"], raw["land_x"], raw["land_v"])
    res = SweepResult(an, sp, sn, flight, scene, shots=shots)
    if stopped is not None:
        raise KeptInterrupt(res) from None
    if trajectories > 0:
        k = min(int(trajectories), an.size)
        idx = np.unique(np.linspace(0, an.size - 1, k).round().astype(int))
        t_longest = np.nanmax(np.append(flight.flight_time[idx], 0.0))
        dt = scene.world.dt
        t_span = min(t_longest if t_longest > 0 else scene.world.t_max, scene.world.t_max)
        every = max(1, int(t_span / dt / 400))
        n_samples = int(math.ceil(t_span / dt / every)) + 2
        rec = fly(scene, x0[idx], v0[idx], w0[idx], record_every=every, n_samples=n_samples)
        res = SweepResult(an, sp, sn, flight, scene, traj_index=idx, traj=rec["traj"], traj_dt=every * dt, shots=shots)
    return res
