"""One scene key's value checked against its declaration (:class:`~ti_golf.scene.keys.Key`): its
kind (a number, a whole number, a list of numbers, a range, text), its allowed values with the
key's unit, finite numbers; numpy numbers and vectors given from Python read as their numbers.
The errors are the loader's one line: the source, the dotted key, what is allowed, what was got."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ti_golf.scene.checks import Each, Interval, parse_range, raise_config
from ti_golf.scene.keys import Key

_LISTS = {
    "vec3": (3, "a list of 3 numbers{unit}, e.g. [0, 0, 0]"),
    "vec2": (2, "a list of 2 numbers{unit}, e.g. [1, 1]"),
    "list2": (2, "a list [min, max] of 2 numbers{unit}"),
}
"""Schema kinds that are fixed-length lists of finite numbers: (length, how the error describes them)."""


def coerce(value: Any, key: Key, source: str, dotted: str) -> Any:
    """Check the type of one value against its schema entry and return it normalised."""
    kind = key.kind
    if kind == "float" or kind == "int":
        value = _coerce_number(value, key, source, dotted)
    elif kind == "bool":
        if not isinstance(value, bool):
            raise_config(source, dotted, f"must be true or false (got {value!r})")
    elif kind in ("str", "text"):
        if not isinstance(value, str):
            raise_config(source, dotted, f"must be a string (got {value!r})")
    elif kind == "strs":
        if not isinstance(value, (list, tuple)) or not all(isinstance(v, str) for v in value):
            raise_config(source, dotted, f"must be a list of strings (got {value!r})")
        value = tuple(value)
    elif kind in _LISTS:
        value = _coerce_numbers(value, key, source, dotted)
    elif kind == "range":
        value = parse_range(value if isinstance(value, (list, tuple)) else str(value), source, dotted)
    problem = _problem(key, value)
    if problem:
        check = key.check
        if kind == "range" and isinstance(check, Each):  # the first value refused, not the whole list
            value = next(v for v in value if check.interval(v) is not None)
        raise_config(source, dotted, f"{problem} (got {value!r})")
    return value


def _problem(key: Key, value: Any) -> str | None:
    """Why ``value`` fails the key's check (``None``: it passes, or the key has none), with the
    key's unit after an interval that names none: ``must be in [-500, 5000] m``."""
    problem = key.check(value) if key.check is not None else None
    if problem and key.unit not in ("-", ""):
        if isinstance(key.check, Interval) and not key.check.unit_word:
            problem += f" {key.unit}"
        elif isinstance(key.check, Each) and key.check.n:  # must be in [-1000, 1000] m/s on all axes
            problem = problem.replace(" on ", f" {key.unit} on ", 1)
        elif isinstance(key.check, Each):  # must each be in [0, 1000] m/s
            problem += f" {key.unit}"
    return problem


def _coerce_number(value: Any, key: Key, source: str, dotted: str) -> int | float:
    """A ``float`` key's value as a finite float, an ``int`` key's as an int (a whole number, within
    the key's check: the check sees the value as given)."""
    if isinstance(value, (np.integer, np.floating)):  # (a numpy number from Python)
        value = value.item()
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise_config(source, dotted, f"must be a number{_allowed_numbers(key)} (got {value!r})")
    if key.kind == "int":
        if isinstance(value, float) and not (math.isfinite(value) and value.is_integer()):
            raise_config(source, dotted, f"must be an integer (got {value!r})")
        problem = _problem(key, value)
        if problem:
            raise_config(source, dotted, f"{problem} (got {value!r})")
        return int(value)
    number = float(value)
    if not math.isfinite(number):
        raise_config(source, dotted, f"must be a finite number (got {number!r})")
    return number


def _coerce_numbers(value: Any, key: Key, source: str, dotted: str) -> tuple[float, ...]:
    """The value of a key of a fixed-length list kind (:data:`_LISTS`) as a tuple of finite floats."""
    count, shape = _LISTS[key.kind]
    if isinstance(value, np.ndarray) and value.ndim == 1 and value.dtype.kind in "iuf":  # (a numpy vector)
        value = value.tolist()
    if (
        not isinstance(value, (list, tuple))
        or len(value) != count
        or any(isinstance(c, bool) or not isinstance(c, (int, float)) for c in value)
    ):
        raise_config(source, dotted, f"must be {shape.format(unit=unit_text(key))} (got {value!r})")
    numbers = tuple(float(c) for c in value)
    if not all(math.isfinite(c) for c in numbers):
        raise_config(source, dotted, f"must hold finite numbers (got {list(numbers)!r})")
    return numbers


def check_value(value: Any, key: Key, source: str, dotted: str) -> Any:
    """``value`` of the key ``key`` (named ``dotted`` in ``source``) checked and normalised as a
    scene file's value is (the same one-line errors): for other files declared with the same keys,
    such as study files (:mod:`ti_golf.study.spec`)."""
    return coerce(value, key, source, dotted)


def _allowed_numbers(key: Key) -> str:
    """`` in [0, 1000] m/s`` for an error that names a number key's allowed values and unit (the
    unit alone when its check is no interval)."""
    check = key.check
    if not isinstance(check, Interval):
        return unit_text(key)
    unit = f" {key.unit}" if key.unit not in ("-", "") and not check.unit_word else ""
    return f" {check.text}{unit}{f' {check.unit_word}' if check.unit_word else ''}"


def unit_text(key: Key) -> str:
    """`` in UNIT`` for an error that names the key's unit, or nothing for a dimensionless key."""
    return f" in {key.unit}" if key.unit not in ("-", "") else ""
