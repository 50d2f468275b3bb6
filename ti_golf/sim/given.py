"""What a :class:`~ti_golf.sim.simulation.Simulation` is given, checked before anything is made:
the memory a scene's balls need, the balls' vectors and per-ball numbers, and step counts. Each
refusal names the argument (a ValueError) or the scene's file and block (a ConfigError)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ti_golf.errors import ConfigError
from ti_golf.runtime import available_memory
from ti_golf.scene.balls import ball_count, block_size, buried_ball, coincident_pair
from ti_golf.scene.checks import REACH, TIME_LIMIT
from ti_golf.scene.schema import Scene

BYTES_PER_BALL = 2048
"""Peak memory [bytes] a ball of a scene's blocks takes while the simulation is set up and run
(the balls made in numpy, then the solver's arrays), bounded from the ball pit's (see the docs'
performance page)."""


def check_memory(scene: Scene) -> None:
    """Refuse a scene whose balls would not fit in the memory available, before making any,
    naming the scene's file, the balls and the bytes they would need against what there is."""
    n = ball_count(scene)
    need = n * BYTES_PER_BALL
    avail = available_memory()
    if avail is None or need <= avail:
        return
    sizes = [block_size(b) for b in scene.blocks]
    key = f"blocks[{sizes.index(max(sizes))}]" if sizes else None  # the biggest block
    raise ConfigError(
        scene.path or scene.name,
        key,
        f"the scene's {n:,} balls would need about {need / 2**30:.1f} GiB of memory "
        f"({BYTES_PER_BALL} bytes per ball); this machine has {avail / 2**30:.1f} GiB available",
    )


SPEED_OF_LIGHT = 299_792_458.0
"""[m/s]."""

VECTOR_LIMITS = {
    "x": (REACH, "m", "as in a scene file: past it the grid's cell coordinates overflow"),
    "v": (SPEED_OF_LIGHT, "m/s", "the speed of light"),
}
"""The bound on each axis of a ball's centre and velocity given as arrays, and why. The centre's
is the scene files' own (:data:`ti_golf.scene.checks.REACH`); the velocity's is not their
1000 m/s, which a ball falls past in vacuum (and a state of such a run may be given back), but the
speed of light, far short of the speeds whose drag overflows (1e300 m/s said "world.dt must be at
most 0 s")."""


def as_vectors(a: Any, name: str, n: int | None = None, bounded: bool = False) -> np.ndarray:
    """``a`` as N vectors of 3 finite numbers, (N, 3) (one vector (3,) for one ball), N >= 1 (or
    ``n``), or a ValueError naming ``name``; ``bounded``: ``x`` and ``v`` (the first word of
    ``name``) within :data:`VECTOR_LIMITS`, as given by a user (a saved run's balls may have gone
    past them)."""
    try:
        if np.iscomplexobj(a):  # (numpy would drop the imaginary parts with a warning)
            raise TypeError
        arr = np.asarray(a, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be real numbers, shape (N, 3) (got {_short(a)})") from None
    if arr.ndim == 1 and arr.shape == (3,):
        arr = arr[None, :]
    if arr.ndim != 2 or arr.shape[1] != 3 or arr.shape[0] < 1 or (n is not None and arr.shape[0] != n):
        want = f"({n}, 3)" if n is not None else "(N, 3)"
        raise ValueError(f"{name} must have shape {want} (got {arr.shape})")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} holds NaN or infinite values")
    limit, unit, why = VECTOR_LIMITS.get(name.split()[0], (math.inf, "", "")) if bounded else (math.inf, "", "")
    beyond = np.flatnonzero(np.any(np.abs(arr) > limit, axis=1))
    if beyond.size:
        i = int(beyond[0])
        raise ValueError(
            f"{name} must be within ±{limit:g} {unit} on each axis, {why} (got {arr[i].tolist()} for ball {i})"
        )
    return arr


def whole_number(value: Any, name: str) -> int:
    """``value`` as a whole number >= 0 (a float with no fraction, such as 2.0, is one), or a
    ValueError naming ``name``: a negative or fractional count moved the clock without stepping."""
    number = isinstance(value, (int, np.integer, float)) and not isinstance(value, bool)
    if not number or not math.isfinite(value) or value < 0 or value != int(value):
        raise ValueError(f"{name} must be a whole number >= 0 (got {value!r})")
    return int(value)


def per_ball(a: Any, n: int, name: str) -> np.ndarray:
    """Per-ball values (N,) from a scalar or an array, read-only: one number broadcast, when it is
    one, takes no memory per ball (the model copies what it keeps)."""
    try:
        if np.iscomplexobj(a):
            raise TypeError
        given = np.asarray(a, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be one real number or one per ball, shape ({n},) (got {_short(a)})") from None
    if given.shape not in ((), (n,)):
        raise ValueError(f"{name} must be one number or one per ball, shape ({n},) (got shape {given.shape})")
    arr = np.broadcast_to(given, (n,))
    if not np.all(np.isfinite(arr)) or np.any(arr <= 0):
        raise ValueError(f"{name} must be finite and > 0 for every ball")
    return arr


STEPS_PER_CALL = 100_000
"""The most steps a run takes in one call of ``Simulation.step`` (one kernel launch, for balls
without collisions): Ctrl-C and SIGTERM are heard between calls, so with a step of 1e-11 s a run
still stops within a fraction of a second (a launch of a run's check interval of steps, 5e9, ran
for minutes). With steps of 0.5 µs or more no run reaches it."""

RUN_STEPS_MAX = 10**12
"""The most steps one run may take: a ball's step costs some 0.1 µs at best, so more would run for
days (a tiny ``world.dt`` is the likely cause)."""


def steps_to_run(t: Any, steps: Any, dt: float, t_end: float, scene: Scene) -> int:
    """The steps of ``dt`` [s] that a run of ``t`` seconds or ``steps`` steps takes (neither given:
    ``t_end`` [s]), each checked: a number of seconds >= 0 or a whole number of steps, and at most
    :data:`~ti_golf.scene.checks.TIME_LIMIT` of simulated time (past it a step no longer moves the
    time on); more than :data:`RUN_STEPS_MAX` steps is a ConfigError naming ``scene``'s
    ``world.dt``."""
    if t is not None and steps is not None:
        raise ValueError("give t or steps, not both")
    if steps is not None:
        steps = whole_number(steps, "steps")
        if steps * dt > TIME_LIMIT:
            raise ValueError(f"steps must be at most {TIME_LIMIT / dt:.3g}, {TIME_LIMIT:g} s of steps (got {steps})")
        if steps > RUN_STEPS_MAX:
            raise ValueError(f"steps must be at most {RUN_STEPS_MAX:.0e}, which would take days (got {steps})")
        return steps
    if t is not None and not (
        isinstance(t, (int, float, np.integer, np.floating)) and not isinstance(t, bool) and t >= 0
    ):
        raise ValueError(f"t must be a number of seconds >= 0 (got {t!r})")  # (numpy's scalars too)
    duration = t_end if t is None else float(t)
    if not (math.isfinite(duration) and duration <= TIME_LIMIT):
        raise ValueError(f"t must be at most {TIME_LIMIT:g} s (got {t!r})")
    if duration / dt > RUN_STEPS_MAX:
        raise ConfigError(
            *scene.where("world.dt"),
            f"= {dt:g} s makes a run of {duration:g} s {duration / dt:.3g} steps; at most {RUN_STEPS_MAX:.0e}, which "
            "would take days: a longer step or a shorter run",
        )
    return int(math.ceil(duration / dt - 1e-9))


def flags(a: Any, n: int, name: str) -> np.ndarray:
    """Per-ball true or false (N,) from one bool or an array of N bools, or a ValueError naming
    ``name``: a text or numbers were taken as true, and a wrong shape failed inside numpy."""
    given = np.asarray(a)
    if given.dtype != bool or given.shape not in ((), (n,)):
        raise ValueError(f"{name} must be true or false, or one of them per ball, shape ({n},) (got {_short(a)})")
    return np.broadcast_to(given, (n,))


def copied(a: Any) -> Any:
    """A copy of an array given (``None`` kept; one numpy cannot make, a ragged list, as it came,
    for the checks that name it)."""
    try:
        return None if a is None else np.array(a, copy=True)
    except ValueError:
        return a


def _short(a: Any) -> str:
    """``a`` written on one line, cut to 60 characters."""
    text = " ".join(repr(a).split())
    return text if len(text) <= 60 else text[:57] + "..."


def check_placement(scene: Scene, x: np.ndarray, radius: np.ndarray) -> None:
    """Refuse given centres ``x`` (N, 3) [m] of balls of radii ``radius`` [m] (N,) that no contact
    could sort out: a ball wholly below the ground plane or behind one of the scene's planes (a
    ball 5 m under the ground came to rest inside it), naming the ball and the solid. A ball that
    overlaps a solid is pushed out by the position projection (B.18). With ball–ball collisions,
    two balls at one point are refused too: their contact has no direction."""
    buried = buried_ball(scene, x, radius)
    if buried is not None:
        i, depth, what, count = buried
        raise ValueError(
            f"x of ball {i} ({x[i].tolist()}) lies {depth:.6g} m inside {what}, the whole ball in the "
            f"solid: a ball must start at least partly on the open side ({count} ball(s) do not)"
        )
    pair = coincident_pair(x) if scene.world.collisions else None
    if pair is not None:
        i, j = pair
        raise ValueError(
            f"x of balls {i} and {j} is one point, {x[i].tolist()}: a contact between them has no direction, so "
            "they would never part; move one, or set world.collisions = false for balls that fly apart without meeting"
        )


def given_balls(scene: Scene, x: Any, v: Any, w: Any, radius: Any) -> tuple[np.ndarray | None, ...]:
    """The centres, velocities and spins a user gave (each ``None`` or (N, 3)), checked: within
    :data:`VECTOR_LIMITS`, and with the radii given (``None``: the scene's) placed where a contact
    can sort them out (:func:`check_placement`)."""
    x, v, w = (None if a is None else as_vectors(a, name, bounded=True) for name, a in (("x", x), ("v", v), ("w", w)))
    if x is not None:
        check_placement(scene, x, per_ball(scene.ball.radius if radius is None else radius, len(x), "radius"))
    return x, v, w
