"""Allowed values of scene keys, and the error every bad value raises.

A check is called with a type-correct value and returns ``None`` when the value is allowed, else a
phrase such as ``"must be > 0"`` that the loader's error message continues. The check classes here
also say what they allow for people (``allowed``, shown by ``ti-golf keys``) and for editors
(``json_schema()``, JSON Schema keywords merged into the key's schema). Plain Python, no Taichi.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, NoReturn

from ti_golf.errors import ConfigError


def raise_config(source: str, key: str | None, reason: str) -> NoReturn:
    """Raise a :class:`~ti_golf.errors.ConfigError` naming ``source`` (a file or ``--set``), the
    dotted ``key`` and the ``reason``."""
    raise ConfigError(source, key, reason)


def _number(x: float) -> str:
    """A bound as people write it: 50000000, 0.5, -90."""
    return str(int(x)) if float(x).is_integer() else f"{x:g}"


@dataclass(frozen=True)
class Interval:
    """The numbers lo ≤ v ≤ hi (``lo_open``/``hi_open``: strict; ``hi`` None: no upper bound);
    ``unit_word`` ends the error message (``"degrees"``)."""

    lo: float
    hi: float | None = None
    lo_open: bool = False
    hi_open: bool = False
    unit_word: str = ""

    def __call__(self, v: float) -> str | None:
        """``None`` when ``v`` is allowed, else the reason it is not (``must be …``)."""
        above = v > self.lo if self.lo_open else v >= self.lo
        below = self.hi is None or (v < self.hi if self.hi_open else v <= self.hi)
        return None if above and below else "must be " + self.text + (f" {self.unit_word}" if self.unit_word else "")

    @property
    def text(self) -> str:
        """The allowed values as the error says them: ``> 0``, ``>= 0``, ``in [0, 1]``, ``in (0, 1]``."""
        return self.allowed if self.hi is None else "in " + self.allowed

    @property
    def allowed(self) -> str:
        """The allowed values: ``> 0``, ``>= 0``, ``[0, 1]``, ``(0, 1]``."""
        if self.hi is None:
            return f"{'>' if self.lo_open else '>='} {_number(self.lo)}"
        lo, hi = _number(self.lo), _number(self.hi)
        return f"{'(' if self.lo_open else '['}{lo}, {hi}{')' if self.hi_open else ']'}"

    def json_schema(self) -> dict[str, Any]:
        """``minimum``/``exclusiveMinimum`` and ``maximum``/``exclusiveMaximum``."""
        out: dict[str, Any] = {"exclusiveMinimum" if self.lo_open else "minimum": self.lo}
        if self.hi is not None:
            out["exclusiveMaximum" if self.hi_open else "maximum"] = self.hi
        return out


@dataclass(frozen=True)
class OneOf:
    """One of ``choices``."""

    choices: tuple[Any, ...]

    def __call__(self, v: Any) -> str | None:
        """``None`` when ``v`` is allowed, else the reason it is not (``must be …``)."""
        return None if v in self.choices else "must be one of " + ", ".join(repr(c) for c in self.choices)

    @property
    def allowed(self) -> str:
        """The choices: ``lab | spin_ratio``."""
        return " | ".join(str(c) for c in self.choices)

    def json_schema(self) -> dict[str, Any]:
        """An ``enum`` of the choices."""
        return {"enum": list(self.choices)}


@dataclass(frozen=True)
class Each:
    """A list of ``n`` numbers, each inside ``interval`` (``[size_x, size_z]`` > 0); ``n`` = 0: a
    list of any length (a range of launch speeds)."""

    interval: Interval
    n: int = 2

    def __call__(self, v: Sequence[float]) -> str | None:
        """``None`` when ``v`` is allowed, else the reason it is not (``must be …``)."""
        if all(self.interval(c) is None for c in v):
            return None
        if self.n == 0:
            return f"must each be {self.interval.text}"
        return f"must be {self.interval.text} on {'both' if self.n == 2 else 'all'} axes"

    @property
    def allowed(self) -> str:
        """The allowed values of each number: ``[> 0, > 0]``; of a vector or list, ``each in [-1, 1]``."""
        if self.n != 2:
            return f"each in {self.interval.allowed}"
        return "[" + ", ".join([self.interval.allowed] * self.n) + "]"

    def json_schema(self) -> dict[str, Any]:
        """The interval's keywords on every item."""
        return {"items": {"type": "number", **self.interval.json_schema()}}


@dataclass(frozen=True)
class WholeCounts:
    """``n`` whole numbers ≥ ``least`` whose product is at most ``most`` ``things`` (a grid of
    points, a lattice of balls)."""

    n: int
    least: int
    most: int
    things: str

    def __call__(self, v: Sequence[float]) -> str | None:
        """``None`` when ``v`` is allowed, else the reason it is not (``must be …``)."""
        if all(c >= self.least and float(c).is_integer() for c in v) and math.prod(v) <= self.most:
            return None
        return (
            f"must be {self.n} whole numbers >= {self.least} (at most {self.most // 1_000_000} million {self.things})"
        )

    @property
    def allowed(self) -> str:
        """The allowed values: ``3 whole numbers >= 1``."""
        return f"{self.n} whole numbers >= {self.least}"

    def json_schema(self) -> dict[str, Any]:
        """Integer items of at least ``least``."""
        return {"items": {"type": "integer", "minimum": self.least}}


@dataclass(frozen=True)
class MinMax:
    """A pair [min, max] with min ≤ max, both in [lo, hi] (``hi`` infinite: no upper bound)."""

    lo: float
    hi: float = math.inf

    def __call__(self, v: Sequence[float]) -> str | None:
        """``None`` when ``v`` is allowed, else the reason it is not (``must be …``)."""
        if len(v) != 2 or v[0] > v[1]:
            return "must be [min, max] with min <= max"
        return None if self.lo <= v[0] and v[1] <= self.hi else f"must lie in [{self.lo:g}, {self.hi:g}]"

    @property
    def allowed(self) -> str:
        """The allowed pairs: ``[min, max] >= 0``, ``[min, max] in [-90, 90]``."""
        if math.isinf(self.hi):
            return f"[min, max] >= {_number(self.lo)}"
        return f"[min, max] in [{_number(self.lo)}, {_number(self.hi)}]"

    def json_schema(self) -> dict[str, Any]:
        """``minimum`` and ``maximum`` on both items."""
        bounds: dict[str, Any] = {"type": "number", "minimum": self.lo}
        if not math.isinf(self.hi):
            bounds["maximum"] = self.hi
        return {"items": bounds}


@dataclass(frozen=True)
class NonZero:
    """A vector other than the zero vector."""

    allowed: str = "non-zero vec3"

    def __call__(self, v: Sequence[float]) -> str | None:
        """``None`` when ``v`` is allowed, else the reason it is not (``must be …``)."""
        return None if any(c != 0 for c in v) else "must not be the zero vector"

    def json_schema(self) -> dict[str, Any]:
        """Nothing: JSON Schema has no plain keyword for it."""
        return {}


SPEED_LIMIT = 1000.0
"""The largest speed [m/s] a scene may give a ball or the wind, on each axis: about three times the
speed of sound (a driven golf ball leaves at 70–80 m/s), where the drag and lift laws, all for
subsonic flight, have long stopped holding; far larger speeds overflow the drag."""
SPIN_LIMIT = 1.0e5
"""The largest spin [rad/s] a scene may give a ball, on each axis: ten times the fastest a golf
ball is ever spun (a wedge's 10,000 rpm is about 1,050 rad/s)."""
REACH = 1.0e6
"""The farthest from the origin [m] a scene may place anything, on each axis: 1,000 km, far past
any course, and far from the floats' limits (and the grid's cell coordinates) that positions
beyond would overflow."""
TIME_LIMIT = 1.0e9
"""The latest simulated time [s] a run may reach (some 32 years): past about 1e12 s a step of a
millisecond no longer moves the time on in f64."""
GRAVITY_LIMIT = 1000.0
"""The largest gravitational acceleration [m/s²] on each axis: about 100 g."""

POSITIVE = Interval(0.0, lo_open=True)
"""v > 0"""
NON_NEGATIVE = Interval(0.0)
"""v ≥ 0"""
UNIT_INTERVAL = Interval(0.0, 1.0)
"""0 ≤ v ≤ 1"""
MASS = Interval(1.0e-6, 1.0e6)
"""A ball's mass [kg]: from a milligram to a thousand tonnes (a golf ball is 45.93 g at most);
far lighter balls overflow the drag's acceleration, far heavier ones the impulses."""
RADIUS = Interval(1.0e-4, 10.0)
"""A ball's radius [m]: from a grain of sand's 0.1 mm to a boulder's 10 m (a golf ball's is
21.3 mm); far larger radii overflow the drag's cross-section, and far smaller ones the grid's
cell coordinates."""
DURATION = Interval(0.0, TIME_LIMIT, lo_open=True)
"""A simulated duration [s]: > 0, at most :data:`TIME_LIMIT`."""
GRAVITY = Each(Interval(-GRAVITY_LIMIT, GRAVITY_LIMIT), 3)
"""A gravitational acceleration [m/s²] within :data:`GRAVITY_LIMIT` on each axis."""
POSITION = Each(Interval(-REACH, REACH), 3)
"""A point [m] within :data:`REACH` of the origin on each axis."""
ELEVATIONS = Each(Interval(-90.0, 90.0), 0)
"""Launch elevations [deg], from straight down to straight up."""
SPEEDS = Each(Interval(0.0, SPEED_LIMIT), 0)
"""A list of speeds [m/s] in [0, :data:`SPEED_LIMIT`]."""
VELOCITY = Each(Interval(-SPEED_LIMIT, SPEED_LIMIT), 3)
"""A velocity [m/s] within :data:`SPEED_LIMIT` on each axis."""
SPIN = Each(Interval(-SPIN_LIMIT, SPIN_LIMIT), 3)
"""An angular velocity [rad/s] within :data:`SPIN_LIMIT` on each axis."""
SPINS = Each(Interval(-SPIN_LIMIT, SPIN_LIMIT), 0)
"""A list of spins [rad/s] within :data:`SPIN_LIMIT`."""


def angle(limit: float) -> Interval:
    """An angle in [−limit, limit] degrees."""
    return Interval(-limit, limit, unit_word="degrees")


def parse_range(text: str | Sequence[float], source: str, key: str | None) -> tuple[float, ...]:
    """Parse ``START:STOP:STEP`` (STOP included) or ``a,b,c`` (or a list) into a tuple of floats."""
    if isinstance(text, (list, tuple)):
        values = []
        for v in text:
            if isinstance(v, bool) or not isinstance(v, (int, float)):
                raise_config(source, key, f"must be a list of numbers (got {v!r})")
            values.append(float(v))
        out = tuple(values)
    else:
        s = str(text).strip()
        try:
            if ":" in s:
                parts = [float(p) for p in s.split(":")]
                if len(parts) != 3:
                    raise ValueError
                start, stop, step = parts
                if not step > 0:
                    raise_config(source, key, f"STEP must be > 0 in START:STOP:STEP (got {s!r})")
                if stop < start:
                    raise_config(source, key, f"STOP must be >= START in START:STOP:STEP (got {s!r})")
                n = int(math.floor((stop - start) / step + 1e-9)) + 1
                if n > 10_000_000:
                    raise_config(source, key, f"gives {n} values; at most 10,000,000 are allowed")
                out = tuple(round(start + i * step, 12) for i in range(n))
            else:
                items = [p.strip() for p in s.split(",")]
                if s and "" in items:  # ("30,,40" or "30,": a number left out is not taken as none)
                    raise_config(source, key, f"has an empty item in {s!r}: give a number between every two commas")
                out = tuple(float(p) for p in items if p)
        except ValueError:
            raise_config(source, key, f"must be START:STOP:STEP (STOP included) or a comma list of numbers (got {s!r})")
    if not out:
        raise_config(source, key, "must list at least one value")
    if not all(math.isfinite(v) for v in out):
        raise_config(source, key, "values must be finite numbers")
    return out
