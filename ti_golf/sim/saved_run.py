"""A run saved to ``.npz`` and loaded again to continue bit for bit (``Simulation.save``/``load``).

Beside the arrays a reader of the results wants (``x``, ``v``, ``w``, ``t``, ``status``, ``radius``,
``mass``, the terrain and the recording), the file holds ``run``, a JSON text: the format, the
scene as the document a TOML file holds (every change made by ``Simulation.set`` in it), the step
count, the precision and backend, and the collision solver's numbers; and the arrays the next steps
read: the sleeping timers (``rest_time``), the flight records (``landed``, ``apex``, ``t_land``,
``land_x``, ``land_v``, ``launch_x``), the storage order of a reordered pile (``order``), the
collision solver's lists and carried impulses (``solver.*``) and the balls at t0 as given to the
constructor (``initial.*``). Per-ball arrays are by ball id.
"""

from __future__ import annotations

import dataclasses
import json
import os
import struct
import zipfile
import zlib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import taichi as ti

from ti_golf.errors import ConfigError
from ti_golf.files import atomic_path
from ti_golf.physics.integrate import NOT_TRACKED
from ti_golf.physics.model import Model
from ti_golf.physics.state import State
from ti_golf.runtime import PRECISIONS, ensure_init, np_float, on_cpu
from ti_golf.scene.document import scene_document
from ti_golf.scene.loader import load_scene
from ti_golf.scene.schema import Scene
from ti_golf.sim import run_checks
from ti_golf.solvers import CollisionSolver, record
from ti_golf.solvers.record import SolverRecord
from ti_golf.solvers.record_checks import RecordError, Taker, read_record
from ti_golf.solvers.stepping import relists_in_kernel
from ti_golf.solvers.surface_rows import scene_surface_columns

FORMAT = 2
"""The layout of a saved run. Files without ``run`` (format 1) hold the final state only, and
cannot be continued."""

STATE = ("x", "v", "w", "status", "rest_time")
"""The state's per-ball arrays a saved run holds, by ball id."""

FLIGHT = ("landed", "apex", "t_land", "land_x", "land_v")
"""The flight record's arrays, saved while some ball is tracked."""

INITIAL = ("x", "v", "w", "radius", "mass", "track")
"""The fields of ``InitialBalls``, saved as ``initial.NAME`` when given."""


def write_run(sim: Any, path: str | os.PathLike[str], recording: Any, partial: bool) -> None:
    """Write the :class:`~ti_golf.sim.simulation.Simulation` ``sim`` to ``path`` (``.npz`` added
    to a name without a suffix; another suffix is a ValueError) as the module says, with its
    ``Recording`` (or ``None``)."""
    state = sim.state
    data: dict[str, Any] = {
        "x": sim.x,
        "v": sim.v,
        "w": sim.w,
        "t": np.float64(sim.t),
        "status": sim.status,
        "radius": sim.model.radius_np,
        "mass": sim.model.mass_np,
        "partial": np.bool_(partial),
        "rest_time": state.read("rest_time"),
    }
    if sim.terrain is not None:
        data.update(
            terrain_heights=sim.terrain.heights,
            terrain_origin=sim.terrain.origin,
            terrain_spacing=sim.terrain.spacing,
        )
    if recording is not None and recording.t:
        data.update(recording.arrays())
    if state.tracking:
        data.update({name: state.read(name) for name in FLIGHT})
        data["launch_x"] = sim.launch_x
        data["launch_t"] = sim.launch_t
    if state.order is not None:
        data["order"] = state.order
    solver_meta = None
    if sim.solver is not None:
        arrays, solver_meta = record.to_file(sim.solver.record())
        solver_meta["serial"], solver_meta["reorder"] = sim.solver.serial, sim.solver.reorder
        data.update({f"solver.{name}": a for name, a in arrays.items()})
    if sim.initial is not None:
        for name in INITIAL:
            value = getattr(sim.initial, name)
            if value is not None:
                data[f"initial.{name}"] = value
    runtime = ensure_init()
    meta = {
        "format": FORMAT,
        "scene": scene_document(sim.scene),
        "scene_name": sim.scene.name,
        "scene_path": sim.scene.path,
        "steps": sim.state.steps,
        "initial_kept": sim.initial_kept,
        "tracking": state.tracking,
        "precision": runtime.precision,
        "arch": runtime.arch,
        "solver": solver_meta,
    }
    data["run"] = np.array(json.dumps(meta))
    target = Path(path)
    if not str(path).strip():
        raise ValueError("cannot save the run: it needs a file name (got an empty path)")
    if target.is_dir():
        raise ValueError(f"cannot save the run to {str(path)!r}: it is a folder; give a file name")
    npz = target.suffix.lower() == ".npz"  # (any case, as the command's check of --out takes it)
    if target.suffix and not npz:  # (x.txt was saved as x.txt.npz, which load("x.txt") did not find)
        raise ValueError(f"cannot save the run to {str(path)!r}: a saved run is an .npz file; end its name in .npz")
    if not npz:
        target = target.with_name(target.name + ".npz")  # as np.savez names it
    if not target.resolve().parent.is_dir():
        raise FileNotFoundError(
            f"cannot save the run to {str(target)!r}: folder {str(target.resolve().parent)!r} does not exist"
        )
    with atomic_path(target) as tmp, open(tmp, "wb") as fh:
        np.savez(fh, **data)


@dataclass
class SavedRun:
    """A run read back from a saved file (:func:`read_run`): its scene, arrays and description,
    from which a simulation is set up again (:meth:`balls`, :attr:`solver_flags`) and then given
    its state (:func:`restore_run`)."""

    source: str
    """The file it was read from."""
    scene: Scene
    """The scene, with every change made by ``Simulation.set`` in it."""
    data: dict[str, np.ndarray]
    """The file's arrays by name."""
    meta: dict[str, Any]
    """The file's ``run`` description."""
    record: SolverRecord | None = None
    """The collision solver's record, checked, for the solver the simulation is set up with
    (:attr:`solver_flags`), or ``None`` without one."""

    @property
    def tracking(self) -> bool:
        """Whether some ball's flight is tracked (its flight records saved)."""
        return bool(self.meta["tracking"])

    @property
    def initial_kept(self) -> bool:
        """Whether the run can go back to its t0."""
        return bool(self.meta["initial_kept"])

    @property
    def solver_flags(self) -> dict[str, bool] | None:
        """``serial`` and ``reorder`` for a new collision solver, as the saved one stepped (serial
        only on the CPU), or ``None`` without one."""
        solver = self.meta["solver"]
        if solver is None:
            return None
        return {"serial": bool(solver["serial"]) and on_cpu(), "reorder": bool(solver["reorder"])}

    def balls(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, bool | np.ndarray]:
        """The balls to set the simulation up with: (launch points or positions (N, 3), radii,
        masses, which balls are tracked)."""
        data = self.data
        track = data["landed"] != NOT_TRACKED if self.tracking else False
        launch_x = data["launch_x"] if self.tracking else data["x"]
        return launch_x, data["radius"], data["mass"], track

    def initial(self) -> dict[str, Any] | None:
        """The fields of the ``InitialBalls`` saved with the run, or ``None``."""
        if not any(f"initial.{name}" in self.data for name in INITIAL):
            return None
        return {name: self.data.get(f"initial.{name}") for name in INITIAL}


def read_run(path: str | os.PathLike[str]) -> SavedRun:
    """The run saved in ``path``, every entry the next steps read checked (:mod:`.run_checks`,
    :mod:`~ti_golf.solvers.record_checks`), or a :class:`ConfigError` naming the file (and the
    entry at fault) that says why it cannot be continued."""
    source = str(path)
    if not Path(source).exists() and Path(source).suffix.lower() != ".npz" and Path(source + ".npz").is_file():
        source += ".npz"  # (as save() names it: .npz added to a path without it)
    data, meta = _read(source)
    precision = ensure_init().precision
    if meta["precision"] not in PRECISIONS:  # (an edited file: no option continues it)
        raise ConfigError(
            f"{source}: entry 'run'", "precision", f"must be one of {', '.join(PRECISIONS)} (got {meta['precision']!r})"
        )
    if meta["precision"] != precision:
        raise ConfigError(
            source,
            None,
            f"was saved in {meta['precision']} precision and this process runs in {precision}: "
            f"continue it in {meta['precision']} (--precision {meta['precision']})",
        )
    try:
        scene = load_scene(meta["scene_path"] or None, data=meta["scene"])
    except ConfigError as exc:
        raise ConfigError(f"{source}: entry 'run', its scene", exc.key, exc.reason) from None
    scene = dataclasses.replace(scene, name=meta["scene_name"], path=meta["scene_path"])
    n = run_checks.check_entries(source, data, meta)
    saved = SavedRun(source, scene, data, meta)
    run_checks.check_against_scene(source, data, meta, scene, saved.initial())
    saved.record = _solver_record(source, data, meta, scene, n)
    return saved


def _solver_record(
    source: str, data: dict[str, np.ndarray], meta: dict[str, Any], scene: Scene, n: int
) -> SolverRecord | None:
    """The collision solver's record of a saved run of ``n`` balls and ``scene``, read and
    checked for the solver a simulation of them is set up with; ``None`` without one."""
    kept = meta["solver"]
    if kept is None or n < 2 or not scene.world.collisions:
        return None
    kind = CollisionSolver.KINDS[scene.contact.solver]
    try:
        serial = (kept.get("serial") is True) and on_cpu()
        blocks = kind.sweeps_by_blocks(scene, relists_in_kernel(n, serial))
        taker = Taker(n, scene_surface_columns(scene), serial, kind.gauss_seidel, blocks)
        arrays = {name[len("solver.") :]: a for name, a in data.items() if name.startswith("solver.")}
        return read_record(arrays, kept, taker)
    except RecordError as exc:
        raise ConfigError(source, None, str(exc)) from None


def restore_run(saved: SavedRun, state: State, model: Model, solver: CollisionSolver | None) -> None:
    """Give the state, the model and the collision solver of a simulation set up again from
    ``saved`` (:meth:`SavedRun.balls`) what the saved run held: the storage order, the per-ball
    arrays, the time and step count, and the solver's lists and carried impulses."""
    data, meta = saved.data, saved.meta
    f = np_float()
    if "order" in data:  # the balls stored as the solver last sorted them, the model's per-ball arrays too
        order = data["order"].astype(np.int32)
        state.ids = ti.ndarray(ti.i32, state.n)
        state.ids.from_numpy(order)
        for name in model.per_ball():
            values = getattr(model, name)
            values.from_numpy(np.ascontiguousarray(values.to_numpy()[order]))
    for name in STATE + (FLIGHT if saved.tracking else ()):
        values = data[name]
        state.write(name, values.astype(f if values.dtype.kind == "f" else np.int32))
    state.t = float(data["t"])
    state.steps = int(meta["steps"])
    kept = meta["solver"]
    if saved.record is not None and solver is not None:
        solver.restore(saved.record, state)
        if relists_in_kernel(state.n, bool(kept["serial"])) != solver.relists:  # lists laid out for the other
            solver.invalidate()


READ_ERRORS = (
    OSError,
    EOFError,
    ValueError,
    zipfile.BadZipFile,
    zlib.error,
    struct.error,
    NotImplementedError,
    RuntimeError,
    OverflowError,
    MemoryError,
)
"""What reading a damaged ``.npz`` raises: a zip cut short or not a zip, a flipped byte (a CRC
or a header that does not parse, a compression method or encryption that was never used), an
array header that claims more than the file holds, or an object array (``allow_pickle`` stays
false: a saved run holds numbers and text only)."""


def _read(source: str) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
    """The arrays and the ``run`` description of a saved run, each entry read whole, or a
    :class:`ConfigError` that says why it cannot be continued."""
    p = Path(source)
    if not p.is_file():
        raise ConfigError(source, None, "file not found" if not p.exists() else "is not a file")
    data = _entries(source, p)
    if "run" not in data:
        if "x" in data and "t" in data:
            raise ConfigError(
                source,
                None,
                "holds the final state only (saved before runs could be continued): run its scene again, "
                "with --out, to get a run that can be continued",
            )
        raise ConfigError(source, None, "is not a run saved by ti-golf (no 'run' entry)")
    run = data["run"]
    try:
        if run.dtype.kind != "U" or run.shape != ():
            raise ValueError(f"dtype {run.dtype}, shape {run.shape}")
        meta = json.loads(str(run))
        fmt = meta["format"]
    except (ValueError, KeyError, TypeError, IndexError, RecursionError):
        raise ConfigError(source, None, "entry 'run': is not readable (a saved run's description, JSON text)") from None
    if fmt != FORMAT:
        raise ConfigError(
            source, None, f"entry 'run': is a saved run of format {fmt!r}; this ti-golf reads format {FORMAT}"
        )
    run_checks.check_description(source, meta)
    reason = None if meta["solver"] is None else record.unreadable(meta["solver"])
    if reason is not None:
        raise ConfigError(source, None, f"entry 'run': {reason}")
    return data, meta


def _entries(source: str, p: Path) -> dict[str, np.ndarray]:
    """Every entry of the ``.npz`` file ``p`` as a numpy array, or a :class:`ConfigError` naming the
    file (and the entry that cannot be read)."""
    data: dict[str, np.ndarray] = {}
    if not _is_zip(source, p):  # (np.load would take it for a .npy file, or a pickle)
        raise ConfigError(source, None, "is not a run saved by ti-golf (an .npz file): it is not a zip archive")
    try:
        with np.load(p, allow_pickle=False) as npz:
            for name in npz.files:
                try:
                    value = npz[name]
                except READ_ERRORS as exc:
                    raise ConfigError(source, None, f"entry '{name}': cannot be read ({_why(exc)})") from None
                if not isinstance(value, np.ndarray):
                    raise ConfigError(source, None, f"entry '{name}': is not an array (.npy) but {len(value)} bytes")
                data[name] = value
    except READ_ERRORS as exc:
        raise ConfigError(source, None, f"is not a run saved by ti-golf (an .npz file): {_why(exc)}") from None
    return data


def _is_zip(source: str, p: Path) -> bool:
    """Whether the file ``p`` is a zip archive, from its first bytes and its end (as ``np.load``
    tells an ``.npz`` file from a ``.npy`` file, and ``zipfile`` finds its entries)."""
    try:
        with open(p, "rb") as fh:
            head = fh.read(4)
    except OSError as exc:
        raise ConfigError(source, None, f"cannot be read: {exc.strerror or exc}") from None
    return head in (b"PK\x03\x04", b"PK\x05\x06") and zipfile.is_zipfile(p)


def _why(exc: BaseException) -> str:
    """What went wrong, in a few words: the exception's text, or its kind when it has none."""
    return str(exc) or type(exc).__name__
