"""``--set KEY=VALUE`` overrides: parsed as TOML values and applied to a scene's document
before it is checked (:func:`ti_golf.scene.loader.load_scene`). No Taichi import here."""

from __future__ import annotations

import difflib
import re
import sys
from collections.abc import Iterable
from typing import Any

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - Python 3.10
    import tomli as tomllib

from ti_golf.errors import OVERRIDES, ConfigError
from ti_golf.scene.keys import Key
from ti_golf.scene.schema import ARRAY_SCHEMA, SCHEMA, TOP_LEVEL

INDEXED = re.compile(r"^(\w+)\[(\d+)\]\.(\w+)$")
"""A key of one table of a ``[[...]]`` array: ``blocks[0].number``."""


def key_of(dotted: str) -> Key | None:
    """The declaration of the scene key ``dotted`` names (``air.C_D``, ``description``,
    ``blocks[0].number``), or None when it names none."""
    indexed = INDEXED.match(dotted)
    if indexed is not None:
        return ARRAY_SCHEMA.get(indexed.group(1), {}).get(indexed.group(3))
    table, _, name = dotted.partition(".")
    return SCHEMA.get(table, {}).get(name) if name else TOP_LEVEL.get(table)


def suggest(name: str, candidates: Iterable[str]) -> str:
    """`` (did you mean 'X'?)`` for the candidate closest to ``name``, or ``""``: one that differs
    only in case first (``C_d``: ``C_D``, not ``C_M``)."""
    candidates = list(candidates)
    same = [c for c in candidates if c.lower() == name.lower()]
    close = same or difflib.get_close_matches(name, candidates, n=1)
    return f" (did you mean '{close[0]}'?)" if close else ""


def parse_override(text: str) -> tuple[str, Any]:
    """Split ``KEY=VALUE`` and parse VALUE as TOML (``[-5,0,0]``, ``0.25``, ``true``); bare words and
    paths (letters, digits and ``_-./~``) are strings. An empty VALUE (``KEY=``) is ``None``: the
    key is cleared, back to its default (``game.start=``: a random start)."""
    if "=" not in text:
        raise ConfigError(OVERRIDES, text, "must be KEY=VALUE, e.g. air.wind=[-5,0,0]")
    dotted, raw = text.split("=", 1)
    dotted, raw = dotted.strip(), raw.strip()
    if not dotted:
        raise ConfigError(OVERRIDES, None, f"missing KEY in {text!r} (expected KEY=VALUE)")
    if not raw:
        return dotted, None
    try:
        value = tomllib.loads(f"v = {raw}")["v"]
    except tomllib.TOMLDecodeError:
        if raw and all(c.isalnum() or c in "_-./~" for c in raw):
            value = raw  # a bare word such as rk4, or a path such as data/hills.npy
        else:
            raise ConfigError(
                OVERRIDES, dotted, f'value {raw!r} is not valid TOML (numbers, [x, y, z], true/false, "text")'
            ) from None
    return dotted, value


def apply_override(data: dict[str, Any], dotted: str, value: Any) -> None:
    """Set ``dotted`` in the scene document ``data`` to ``value``, or clear it (``None``: the key
    takes its default; clearing a key that the scene does not set has no effect, and is refused).
    ``NAME[I].KEY`` names a key of the I-th table of a ``[[NAME]]`` array the scene has."""
    indexed = INDEXED.match(dotted)
    if indexed is not None:
        _apply_indexed(data, dotted, indexed.group(1), int(indexed.group(2)), indexed.group(3), value)
        return
    parts = dotted.split(".")
    if parts[0] in ARRAY_SCHEMA:
        raise ConfigError(
            OVERRIDES,
            dotted,
            f"names the scene's [[{parts[0]}]] tables: --set changes one key of one of them, "
            f"{parts[0]}[INDEX].KEY (e.g. {_example(parts[0])})",
        )
    if len(parts) == 1:
        if parts[0] not in TOP_LEVEL:
            raise ConfigError(OVERRIDES, dotted, f"is not a scene key{suggest(dotted, _all_keys())}")
        if value is None:
            _refuse_clearing_unset(parts[0] in data, dotted)
            data.pop(parts[0], None)
        else:
            data[parts[0]] = (OVERRIDES, value)
        return
    if len(parts) != 2:
        raise ConfigError(OVERRIDES, dotted, f"is not a scene key{suggest(dotted, _all_keys())}")
    section, name = parts
    if section not in SCHEMA or name not in SCHEMA[section]:
        raise ConfigError(OVERRIDES, dotted, f"is not a scene key{suggest(dotted, _all_keys())}")
    if value is None:
        cleared = data.get(section)
        _refuse_clearing_unset(isinstance(cleared, dict) and name in cleared, dotted)
        data[section].pop(name)
        return
    table = data.setdefault(section, {})
    if not isinstance(table, dict):
        raise ConfigError(OVERRIDES, dotted, f"cannot be set: '{section}' is not a table in the scene")
    table[name] = (OVERRIDES, value)


def _apply_indexed(data: dict[str, Any], dotted: str, name: str, index: int, key: str, value: Any) -> None:
    """Set (or clear, ``None``) ``key`` of the ``index``-th table of the scene's ``[[name]]`` array."""
    if name not in ARRAY_SCHEMA:
        raise ConfigError(OVERRIDES, dotted, f"is not a scene key{suggest(dotted, _all_keys())}")
    if key not in ARRAY_SCHEMA[name]:
        raise ConfigError(
            OVERRIDES,
            dotted,
            f"is unknown{suggest(key, ARRAY_SCHEMA[name])}; allowed in [[{name}]]: " + ", ".join(ARRAY_SCHEMA[name]),
        )
    tables = data.get(name)
    tables = tables if isinstance(tables, list) else []
    count = len(tables)
    if index >= count:
        raise ConfigError(
            OVERRIDES,
            dotted,
            f"names table {index} of [[{name}]], and the scene has {count}: --set changes the scene's tables, "
            "it adds none (add one in the scene file)",
        )
    table = tables[index]
    if not isinstance(table, dict):
        raise ConfigError(OVERRIDES, dotted, f"cannot be set: '{name}' is not an array of tables in the scene")
    if value is None:
        _refuse_clearing_unset(key in table, dotted)
        table.pop(key)
    else:
        table[key] = (OVERRIDES, value)


def _example(name: str) -> str:
    """An override of one key of a ``[[name]]`` table, for messages."""
    return {
        "balls": "balls[0].position=[0,1,0]",
        "blocks": "blocks[0].number=500",
        "planes": "planes[0].point=[0,0,0]",
    }.get(name, f"{name}[0].name=rough")


def _refuse_clearing_unset(is_set: bool, dotted: str) -> None:
    """A ConfigError for ``KEY=`` (clear) of a key the scene does not set: it is at its default already."""
    if not is_set:
        raise ConfigError(OVERRIDES, dotted, "is not set by the scene: clearing it (KEY=) has no effect")


def _all_keys() -> list[str]:
    return (
        list(TOP_LEVEL)
        + [f"{s}.{k}" for s, keys in SCHEMA.items() for k in keys]
        + [f"{a}[0].{k}" for a, keys in ARRAY_SCHEMA.items() for k in keys]
    )
