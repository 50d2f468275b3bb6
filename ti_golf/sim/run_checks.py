"""Checks of a saved run's entries (:mod:`.saved_run`) before a simulation is set up from them:
each array the next steps read present, of numbers of the right kind, shaped for the run's
balls, and within what a simulation holds (finite positions, velocities and spins, radii and
masses > 0, a time >= 0, the statuses and flight states a step knows); and the ``run``
description's fields of the right types. A failed check raises a
:class:`~ti_golf.errors.ConfigError` naming the file and the entry: ``run.npz: entry 'v': shape
(9, 3) but the run has 10 balls (expects (10, 3))``.
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Callable
from typing import Any, NoReturn

import numpy as np

from ti_golf.errors import ConfigError
from ti_golf.physics.integrate import IN_FLIGHT, LANDED, NOT_TRACKED
from ti_golf.scene.checks import TIME_LIMIT
from ti_golf.scene.schema import STATUS_NAMES, Scene

Check = Callable[[np.ndarray], np.ndarray]
"""Which values of an array are allowed (a boolean array of its shape)."""


def fail(source: str, entry: str, reason: str) -> NoReturn:
    """Raise the error of ``entry`` of the saved run ``source``: what is wrong and what is allowed."""
    raise ConfigError(source, None, f"entry '{entry}': {reason}")


def _finite(a: np.ndarray) -> np.ndarray:
    return np.isfinite(a)


BOUND = 1.0e24
"""The largest magnitude of a saved position [m], velocity [m/s] or spin [rad/s]: past what any run
reaches (a ball falling freely under the largest gravity until the latest time moves at 1e12 m/s
and 5e20 m at most), and far from the floats whose squares overflow (a position of 1e300 gave
overflow warnings, and a velocity of 1e30 a ball reported rolling at 8e28 m)."""


def _bounded(a: np.ndarray) -> np.ndarray:
    return np.isfinite(a) & (np.abs(a) <= BOUND)


def _positive(a: np.ndarray) -> np.ndarray:
    return np.isfinite(a) & (a > 0)


def _non_negative(a: np.ndarray) -> np.ndarray:
    return np.isfinite(a) & (a >= 0)


BALLS: dict[str, tuple[str, tuple[int, ...], Check, str]] = {
    "x": ("the balls' positions [m]", (3,), _bounded, "finite and within ±1e24"),
    "v": ("the balls' velocities [m/s]", (3,), _bounded, "finite and within ±1e24"),
    "w": ("the balls' spins [rad/s]", (3,), _bounded, "finite and within ±1e24"),
    "radius": ("the balls' radii [m]", (), _positive, "finite and > 0"),
    "mass": ("the balls' masses [kg]", (), _positive, "finite and > 0"),
    "rest_time": ("the balls' rest timers [s]", (), _non_negative, "finite and >= 0"),
}
"""The per-ball numbers every saved run holds: (what they are, the shape of a ball's entry, the
check of their values and what it allows)."""

FLIGHT: dict[str, tuple[str, tuple[int, ...], Check, str]] = {
    "apex": ("the tracked balls' highest heights [m]", (), _finite, "finite"),
    "t_land": ("the tracked balls' landing times [s]", (), _finite, "finite"),
    "land_x": ("the tracked balls' landing points [m]", (3,), _finite, "finite"),
    "land_v": ("the tracked balls' landing velocities [m/s]", (3,), _finite, "finite"),
    "launch_x": ("the tracked balls' launch points [m]", (3,), _finite, "finite"),
}
"""The flight record's numbers, held while some ball's flight is tracked."""

LAUNCH_T = ("the tracked balls' launch times [s]", (), _non_negative, "finite and >= 0")
"""The launch times, held with the flight record by runs saved since balls are launched again
when moved or struck (older runs launched every ball at t0)."""

LANDED_NAMES = {NOT_TRACKED: "not tracked", IN_FLIGHT: "in flight", LANDED: "landed"}
"""The flight states of ``landed``."""

DESCRIPTION: dict[str, tuple[Callable[[Any], bool], str]] = {
    "scene": (lambda v: isinstance(v, dict), "a table (the scene)"),
    "scene_name": (lambda v: isinstance(v, str), "a text"),
    "scene_path": (lambda v: v is None or isinstance(v, str), "a text or null"),
    "steps": (lambda v: isinstance(v, int) and not isinstance(v, bool) and v >= 0, "a whole number >= 0"),
    "initial_kept": (lambda v: isinstance(v, bool), "true or false"),
    "tracking": (lambda v: isinstance(v, bool), "true or false"),
    "precision": (lambda v: isinstance(v, str), "a text (f32 or f64)"),
    "solver": (lambda v: v is None or isinstance(v, dict), "a table (the collision solver's record) or null"),
}
"""The fields of the ``run`` description that a saved run is continued from, and what each allows."""


NOTED = ("format", "arch")
"""The fields of the ``run`` description besides :data:`DESCRIPTION`: its format (checked as it is
read) and the backend the run was saved on (a note: a run continues on any backend)."""


def check_description(source: str, meta: Any) -> None:
    """The ``run`` description: a table with each field of :data:`DESCRIPTION`."""
    if not isinstance(meta, dict):
        fail(source, "run", f"is {_short(meta)}; expects a table (the run's description)")
    for key, (allowed, what) in DESCRIPTION.items():
        if key not in meta:
            fail(source, "run", f"'{key}' is missing; expects {what}")
        if not allowed(meta[key]):
            fail(source, "run", f"'{key}' is {_short(meta[key])}; expects {what}")
    extra = sorted(set(meta) - set(DESCRIPTION) - set(NOTED))
    if extra:
        fail(source, "run", f"'{extra[0]}' is not a field of a saved run's description, so it would have no effect")


T_MAX = TIME_LIMIT
"""The latest time [s] a saved run may hold (:data:`~ti_golf.scene.checks.TIME_LIMIT`)."""

ENTRIES = (
    *BALLS,
    *FLIGHT,
    "status",
    "t",
    "partial",
    "landed",
    "launch_t",
    "order",
    "terrain_heights",
    "terrain_origin",
    "terrain_spacing",
    "run",
)
"""The entries a saved run may hold, besides the ``solver.*``, ``initial.*`` and ``traj_*`` ones (a
recording, for its readers)."""


def check_entries(source: str, data: dict[str, np.ndarray], meta: dict[str, Any]) -> int:
    """The arrays a simulation is set up from and continued with (see the module); returns the
    number of balls. An entry that a saved run does not hold (:data:`ENTRIES`) is refused: it
    would have no effect."""
    for name in data:
        if name not in ENTRIES and not name.startswith(("solver.", "initial.", "traj_")):
            fail(source, name, "is not an entry of a saved run, so it would have no effect")
    n = _ball_count(source, data)
    if meta["precision"] == "f64":  # (an f32 run's fields round to f32 whatever the entry holds)
        for name in (*BALLS, *FLIGHT, "launch_t", "t"):
            if name in data and data[name].dtype.kind == "f" and data[name].dtype.itemsize < 8:
                fail(
                    source,
                    name,
                    f"dtype {data[name].dtype}; a run saved in f64 holds float64 (a narrower float rounds the "
                    "state, and the run would not go on as it was)",
                )
    for name, (what, shape, allowed, words) in BALLS.items():
        _numbers(source, data, name, what, (n, *shape), allowed, words)
    _codes(source, data, "status", "the balls' statuses", n, STATUS_NAMES)
    _time(source, data)
    if "partial" in data and (data["partial"].dtype.kind != "b" or data["partial"].shape != ()):
        fail(
            source,
            "partial",
            f"is {_short(data['partial'])}; expects true or false (whether the run was stopped early)",
        )
    if meta["tracking"]:
        landed = _codes(source, data, "landed", "the balls' flight states", n, LANDED_NAMES)
        if np.all(landed == NOT_TRACKED):
            fail(source, "landed", "tracks no ball, but the run says some ball is tracked (entry 'run', 'tracking')")
        for name, (what, shape, allowed, words) in FLIGHT.items():
            _numbers(source, data, name, what, (n, *shape), allowed, words)
        if "launch_t" in data:
            what, shape, allowed, words = LAUNCH_T
            _numbers(source, data, "launch_t", what, (n, *shape), allowed, words)
    if "order" in data:
        _order(source, data["order"], n)
    _initial(source, data, n)
    return n


def _ball_count(source: str, data: dict[str, np.ndarray]) -> int:
    """The number of balls: the length that most of the per-ball entries (:data:`BALLS`) have, the
    positions' when as many have another, so that an entry cut or padded alone is the one named
    (the positions first checked to be rows of 3)."""
    x = _present(source, data, "x", "the balls' positions [m], shape (N, 3)")
    if x.ndim != 2 or x.shape[1] != 3 or x.shape[0] < 1:
        fail(source, "x", f"shape {x.shape}; expects (N, 3), a row of 3 for each of N >= 1 balls")
    lengths = Counter(int(data[name].shape[0]) for name in BALLS if name in data and np.ndim(data[name]) >= 1)
    most = max(lengths.values())
    if lengths[int(x.shape[0])] == most:
        return int(x.shape[0])
    return min(length for length, count in lengths.items() if count == most)


def _present(source: str, data: dict[str, np.ndarray], name: str, what: str) -> np.ndarray:
    """The entry ``name``, which a saved run holds (``what``: what it is)."""
    if name not in data:
        fail(source, name, f"missing; a saved run holds {what}")
    return data[name]


def _numbers(
    source: str,
    data: dict[str, np.ndarray],
    name: str,
    what: str,
    shape: tuple[int, ...],
    allowed: Check,
    words: str,
) -> np.ndarray:
    """The entry ``name`` (``what``: what it holds): floating-point numbers of ``shape`` (its first
    axis the balls), each ``allowed`` (``words`` says what is)."""
    a = _present(source, data, name, f"{what}, shape {shape}")
    _kind(source, name, a, "f")
    if a.shape != shape:
        fail(source, name, f"shape {a.shape} but the run has {shape[0]} balls (expects {shape})")
    ok = allowed(a)
    if not np.all(ok):
        where = np.argwhere(~ok)[0]
        fail(source, name, f"ball {where[0]} holds {a[tuple(where)].item()!r}; expects {what}, {words}")
    return a


def _kind(source: str, name: str, a: np.ndarray, kinds: str) -> None:
    """``a`` holds numbers of a numpy kind in ``kinds``."""
    if a.dtype.kind not in kinds:
        numbers = "floating-point numbers" if kinds == "f" else "whole numbers" if kinds == "iu" else "numbers"
        fail(source, name, f"dtype {a.dtype}; expects {numbers}")


def _codes(source: str, data: dict[str, np.ndarray], name: str, what: str, n: int, codes: dict[int, str]) -> np.ndarray:
    """The entry ``name``, a code of ``codes`` for each ball."""
    a = _present(source, data, name, f"{what}, shape (N,)")
    _kind(source, name, a, "iu")
    if a.shape != (n,):
        fail(source, name, f"shape {a.shape} but the run has {n} balls (expects ({n},))")
    bad = ~np.isin(a, list(codes))
    if np.any(bad):
        ball = int(np.argmax(bad))
        allowed = ", ".join(f"{code} ({word})" for code, word in codes.items())
        fail(source, name, f"ball {ball} holds {a[ball]}; expects one of {allowed}")
    return a


def _time(source: str, data: dict[str, np.ndarray]) -> None:
    """``t``, the simulated time [s]: one number, finite and >= 0."""
    t = _present(source, data, "t", "the simulated time [s]")
    _kind(source, "t", t, "fiu")
    if t.shape != ():
        fail(source, "t", f"shape {t.shape}; expects one number, shape ()")
    if not (math.isfinite(float(t)) and 0 <= float(t) <= T_MAX):
        fail(source, "t", f"is {float(t)!r} s; expects a time in [0, {T_MAX:g}] s")


def _order(source: str, order: np.ndarray, n: int) -> None:
    """``order``, the storage order of the balls: each ball id from 0 to n − 1 once."""
    _kind(source, "order", order, "iu")
    if order.shape != (n,):
        fail(source, "order", f"shape {order.shape} but the run has {n} balls (expects ({n},))")
    if not np.array_equal(np.sort(order), np.arange(n)):
        fail(source, "order", f"is not an order of the balls; expects each ball id from 0 to {n - 1} once")


def _initial(source: str, data: dict[str, np.ndarray], n: int) -> None:
    """The balls at t0 as given to the simulation (``initial.NAME``, each optional), which a reset
    goes back to: positions, velocities and spins (N, 3) (or (3,) for one ball) finite; radii and
    masses one number or (N,), finite and > 0; which balls are tracked, one or (N,)."""
    for name in ("x", "v", "w"):
        _given(source, data, name, n, [(n, 3), (3,)] if n == 1 else [(n, 3)], _finite, "finite numbers")
    for name in ("radius", "mass"):
        _given(source, data, name, n, [(), (n,)], _positive, "numbers finite and > 0")
    _given(source, data, "track", n, [(), (n,)], None, "true or false")


def _given(
    source: str,
    data: dict[str, np.ndarray],
    name: str,
    n: int,
    shapes: list[tuple[int, ...]],
    allowed: Check | None,
    words: str,
) -> None:
    """``initial.NAME``, when the run holds it: numbers (with ``allowed`` None, true or false or
    whole numbers) of one of ``shapes`` for ``n`` balls, each ``allowed`` (``words`` says what is)."""
    entry = f"initial.{name}"
    if entry not in data:
        return
    a = data[entry]
    if a.dtype.kind not in ("fiu" if allowed is not None else "biu"):
        fail(source, entry, f"dtype {a.dtype}; expects {words}")
    if a.shape not in shapes:
        fail(source, entry, f"shape {a.shape} but the run has {n} balls (expects {' or '.join(map(str, shapes))})")
    if allowed is not None and not np.all(allowed(a)):
        fail(source, entry, f"holds {a[~allowed(a)].ravel()[0].item()!r}; expects {words}")


def _short(v: Any) -> str:
    """``v`` written out, cut to 60 characters."""
    text = repr(v)
    return text if len(text) <= 60 else text[:57] + "..."


def check_against_scene(
    source: str, data: dict[str, np.ndarray], meta: dict[str, Any], scene: Scene, initial: dict[str, Any] | None
) -> None:
    """The run's balls and ground are those its scene sets up, as the simulation that saved it
    had them: as many balls, the same radii and masses (the scene's, or those given at t0,
    ``initial``; not checked for a run that did not keep its t0, whose balls may have been given
    as arrays), the terrain's heights as the scene's ``[terrain]`` makes them now (a heights
    file changed since would continue another run), and a collision solver's record wherever the
    balls collide (without it the carried impulses would start from zero)."""
    from ti_golf.scene.balls import ball_count, build_balls  # (numpy only)
    from ti_golf.scene.terrain import build_terrain

    n = int(data["x"].shape[0])
    given = initial or {}
    radius: Any
    mass: Any
    if not meta["initial_kept"]:
        radius = mass = None
    elif given.get("x") is None:
        made = ball_count(scene)
        if made != n:
            fail(source, "x", f"holds {n} balls but the run's scene (entry 'run') makes {made}")
        balls = build_balls(scene)
        radius, mass = balls.radius, balls.mass
    else:
        radius, mass = scene.ball.radius, scene.ball.mass
    radius = radius if given.get("radius") is None else given["radius"]
    mass = mass if given.get("mass") is None else given["mass"]
    for name, expected, unit in (("radius", radius, "m"), ("mass", mass, "kg")) if radius is not None else ():
        expected = np.broadcast_to(np.asarray(expected, float), (n,))
        saved = data[name].astype(float)
        off = np.flatnonzero(~np.isclose(saved, expected, rtol=1e-6, atol=0.0))
        if off.size:
            b = int(off[0])
            fail(
                source,
                name,
                f"ball {b} holds {saved[b]:g} {unit} but the run's scene gives it {expected[b]:g} {unit} "
                f"({off.size} ball{'s' if off.size > 1 else ''} differ)",
            )
    if scene.terrain is not None:
        if "terrain_heights" not in data:
            fail(source, "terrain_heights", "is missing; the run's scene has a terrain")
        heights = build_terrain(scene.terrain, source).heights
        if not np.array_equal(np.asarray(data["terrain_heights"], float), heights):
            where = f" (its file {scene.terrain.file!r} changed since)" if scene.terrain.kind == "file" else ""
            fail(source, "terrain_heights", f"differ from the heights of the run's terrain{where}")
    if meta["solver"] is None and n >= 2 and scene.world.collisions:
        fail(source, "run", "'solver' is null, but the run's balls collide: its carried impulses are missing")
