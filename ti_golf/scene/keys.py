"""The declaration of a scene key: :func:`key` makes a dataclass field that carries its :class:`Key`.

Plain Python, no Taichi import.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

KINDS = ("float", "int", "bool", "str", "vec3", "vec2", "list2", "range", "text")
"""Kinds of value a key takes: see :class:`Key`."""


class _Required:
    """The default of a key that a table must give (``hole.position``, ``[[balls]].position``)."""

    def __repr__(self) -> str:
        return "REQUIRED"


REQUIRED: Any = _Required()
"""Pass as a key's default to make the key required: its field then has no default."""


@dataclass(frozen=True)
class Key:
    """One scene key: its type, default, unit, allowed range and meaning.

    ``kind`` is one of :data:`KINDS`: ``"float"``, ``"int"``, ``"bool"``, ``"str"``, ``"vec3"``,
    ``"vec2"`` (2 numbers), ``"list2"`` ([min, max]), ``"range"`` (a START:STOP:STEP string or a
    list of numbers) or ``"text"`` (free text). ``default`` is ``None`` for a key that is unset
    unless given (and for a required key). ``check`` returns ``None`` when a (type-correct) value
    is allowed, else a phrase such as ``"must be > 0"``; ``allowed`` says the same for people.
    """

    name: str
    kind: str
    default: Any
    unit: str
    doc: str
    check: Callable[[Any], str | None] | None = None
    allowed: str = ""
    required: bool = False


def key(
    kind: str, default: Any, unit: str, doc: str, check: Callable[[Any], str | None] | None = None, allowed: str = ""
) -> Any:
    """A dataclass field declaring a scene key of ``kind`` with its ``default`` [``unit``], help
    ``doc`` and allowed values (``check``, ``allowed``); ``default`` :data:`REQUIRED` makes the key
    required and the field default-less."""
    if kind not in KINDS:
        raise ValueError(f"unknown key kind {kind!r}")
    required = default is REQUIRED
    info = Key("", kind, None if required else default, unit, doc, check, allowed, required)
    if required:
        return dataclasses.field(metadata={"key": info})
    return dataclasses.field(default=default, metadata={"key": info})


def keys_of(cls: type) -> dict[str, Key]:
    """The keys a dataclass declares with :func:`key`, by field name, in declaration order."""
    return {
        f.name: dataclasses.replace(f.metadata["key"], name=f.name)
        for f in dataclasses.fields(cls)
        if "key" in f.metadata
    }


def _number(x: float) -> str:
    """A bound as people write it: 50000000, 0.5, -90."""
    return str(int(x)) if float(x).is_integer() else f"{x:g}"


@dataclass(frozen=True)
class Interval:
    """The allowed values lo ≤ v ≤ hi (``lo_open``/``hi_open``: strict; ``hi`` None: no upper
    bound), checked like the functions of :class:`Key` (``None`` when allowed, else a phrase)."""

    lo: float
    hi: float | None = None
    lo_open: bool = False
    hi_open: bool = False
    unit_word: str = ""

    def __call__(self, v: float) -> str | None:
        above = v > self.lo if self.lo_open else v >= self.lo
        below = self.hi is None or (v < self.hi if self.hi_open else v <= self.hi)
        return None if above and below else "must be " + self.text + (f" {self.unit_word}" if self.unit_word else "")

    @property
    def text(self) -> str:
        """``> 0``, ``>= 0`` or ``in [0, 1]``, ``in (0, 1]``, …"""
        if self.hi is None:
            return f"{'>' if self.lo_open else '>='} {_number(self.lo)}"
        return f"in {'(' if self.lo_open else '['}{_number(self.lo)}, {_number(self.hi)}{')' if self.hi_open else ']'}"

    def json_schema(self) -> dict[str, float]:
        """The interval as JSON Schema keywords."""
        out = {"exclusiveMinimum" if self.lo_open else "minimum": self.lo}
        if self.hi is not None:
            out["exclusiveMaximum" if self.hi_open else "maximum"] = self.hi
        return out


@dataclass(frozen=True)
class OneOf:
    """The allowed values are ``choices``, checked like the functions of :class:`Key`."""

    choices: tuple[Any, ...]

    def __call__(self, v: Any) -> str | None:
        return None if v in self.choices else "must be one of " + ", ".join(repr(c) for c in self.choices)

    def json_schema(self) -> dict[str, list[Any]]:
        """The choices as a JSON Schema ``enum``."""
        return {"enum": list(self.choices)}
