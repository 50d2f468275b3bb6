"""The declaration of a scene key: :func:`key` makes a dataclass field that carries its :class:`Key`.

Plain Python, no Taichi import.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

KINDS = ("float", "int", "bool", "str", "vec3", "vec2", "list2", "range", "text", "strs")
"""Kinds of value a key takes: see :class:`Key`."""


class _Required:
    """The default of a key that a table must give (``hole.position``, ``[[balls]].position``)."""

    def __repr__(self) -> str:
        return "REQUIRED"


REQUIRED: Any = _Required()
"""Pass as a key's default to make the key required: its field then has no default."""


@dataclass(frozen=True)
class Key:
    """One scene key: its type, default, unit, allowed values and meaning.

    ``kind`` is one of :data:`KINDS`: ``"float"``, ``"int"``, ``"bool"``, ``"str"``, ``"vec3"``,
    ``"vec2"`` (2 numbers), ``"list2"`` ([min, max]), ``"range"`` (a START:STOP:STEP string or a
    list of numbers), ``"text"`` (free text) or ``"strs"`` (a list of strings, of study files). ``default`` is ``None`` for a key that is unset
    unless given (and for a required key). ``check`` returns ``None`` when a (type-correct) value
    is allowed, else a phrase such as ``"must be > 0"`` (see :mod:`ti_golf.scene.checks`);
    ``allowed`` says the same for people. ``unit`` is ``"-"`` for dimensionless keys.
    """

    name: str
    kind: str
    default: Any
    unit: str
    doc: str
    check: Callable[[Any], str | None] | None = None
    allowed: str = ""
    required: bool = False
    read_when: tuple[str, tuple[Any, ...]] | None = None
    """``(other, values)``: the key is read only while the key ``other`` (of the same table, or
    dotted, ``"world.collisions"``) has one of ``values``, or, for ``other`` a table in brackets
    (``"[hole]"``), while the scene has that table; given otherwise, it is refused."""


def key(
    kind: str,
    default: Any,
    unit: str,
    doc: str,
    check: Callable[[Any], str | None] | None = None,
    allowed: str = "",
    read_when: tuple[str, tuple[Any, ...]] | None = None,
) -> Any:
    """A dataclass field declaring a scene key of ``kind`` with its ``default`` [``unit``], help
    ``doc`` and allowed values: ``check``, and ``allowed`` (by default the check's own ``allowed``
    text); ``read_when`` names the setting under which the key takes effect (see :class:`Key`).
    ``default`` :data:`REQUIRED` makes the key required and the field default-less."""
    if kind not in KINDS:
        raise ValueError(f"unknown key kind {kind!r}")
    required = default is REQUIRED
    allowed = allowed or getattr(check, "allowed", "")
    info = Key("", kind, None if required else default, unit, doc, check, allowed, required, read_when)
    if required:
        return dataclasses.field(metadata={"key": info})
    return dataclasses.field(default=default, metadata={"key": info})


def toml_value(value: Any) -> str:
    """A value as a TOML file writes it: ``"file"``, ``true``, ``2``."""
    if isinstance(value, bool):
        return "true" if value else "false"
    return f'"{value}"' if isinstance(value, str) else str(value)


def read_when_text(k: Key, table: str = "") -> str:
    """The setting under which key ``k`` is read, in words (``kind = "file"``, ``the scene has a
    [hole] table``); a key of the same table is named after ``table`` when one is given."""
    assert k.read_when is not None
    other, values = k.read_when
    if other.startswith("["):
        return f"the scene has a {other} table"
    if table and "." not in other:
        other = f"{table}.{other}"
    return f"{other} = " + " or ".join(toml_value(v) for v in values)


def help_text(k: Key) -> str:
    """A key's help, with the setting under which it is read (``read_when``) when it has one."""
    return k.doc if k.read_when is None else f"{k.doc} (read only when {read_when_text(k)})"


def keys_of(cls: type) -> dict[str, Key]:
    """The keys a dataclass declares with :func:`key`, by field name, in declaration order."""
    return {
        f.name: dataclasses.replace(f.metadata["key"], name=f.name)
        for f in dataclasses.fields(cls)
        if "key" in f.metadata
    }


def is_read(k: Key, obj: Any, scene: Any) -> bool:
    """Whether key ``k`` of table ``obj`` (a dataclass of a :class:`~ti_golf.scene.schema.Scene`)
    is read under ``scene``'s settings (``Key.read_when``): ``air.C_D`` is not once ``air.model``
    is ``spin_ratio``."""
    if k.read_when is None:
        return True
    other, allowed = k.read_when
    if other.startswith("["):
        return getattr(scene, other.strip("[]")) is not None
    if "." in other:
        table, name = other.split(".")
        return getattr(getattr(scene, table), name) in allowed
    return getattr(obj, other) in allowed
