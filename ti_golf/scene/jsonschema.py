"""The JSON Schema of scene files, made from the key declarations (:mod:`ti_golf.scene.schema`).

Editors that read JSON Schema for TOML (Taplo, Even Better TOML in VS Code) check and complete a
scene file as it is typed: ``ti-golf schema --out scene.schema.json``, then the first line of the
scene file ``#:schema ./scene.schema.json`` (see the docs' scene page).
"""

from __future__ import annotations

from typing import Any

from ti_golf.scene.keys import Key, help_text
from ti_golf.scene.schema import ARRAY_SCHEMA, SCHEMA, TOP_LEVEL

DIALECT = "https://json-schema.org/draft/2020-12/schema"

_NUMBER = {"type": "number"}
_TYPES: dict[str, dict[str, Any]] = {
    "float": _NUMBER,
    "int": {"type": "integer"},
    "bool": {"type": "boolean"},
    "str": {"type": "string"},
    "text": {"type": "string"},
    "vec3": {"type": "array", "items": _NUMBER, "minItems": 3, "maxItems": 3},
    "vec2": {"type": "array", "items": _NUMBER, "minItems": 2, "maxItems": 2},
    "list2": {"type": "array", "items": _NUMBER, "minItems": 2, "maxItems": 2},
    "strs": {"type": "array", "items": {"type": "string"}},
    "range": {"anyOf": [{"type": "string"}, {"type": "array", "items": _NUMBER, "minItems": 1}]},
}
"""JSON Schema of each kind of key (see :class:`~ti_golf.scene.keys.Key`)."""


def key_schema(k: Key) -> dict[str, Any]:
    """The JSON Schema of one key: its type, bounds or choices, default and description (with unit)."""
    out: dict[str, Any] = dict(_TYPES[k.kind])
    bounds = getattr(k.check, "json_schema", None)
    if bounds is not None:
        extra = bounds()
        if "items" in extra and "anyOf" in out:  # a range: the bounds hold for its list (its text is parsed)
            out["anyOf"] = [
                {**b, "items": {**b["items"], **extra["items"]}} if "items" in b else b for b in out["anyOf"]
            ]
            del extra["items"]
        elif "items" in extra:  # bounds on each number of a list
            out["items"] = {**out["items"], **extra.pop("items")}
        out.update(extra)
    if k.default is not None:
        out["default"] = list(k.default) if isinstance(k.default, tuple) else k.default
    unit = "" if k.unit in ("", "-") else f" [{k.unit}]"
    allowed = f" Allowed: {k.allowed}." if k.allowed else ""
    out["description"] = f"{help_text(k)}{unit}.{allowed}"
    return out


def _table(keys: dict[str, Key]) -> dict[str, Any]:
    required = [name for name, k in keys.items() if k.required]
    out: dict[str, Any] = {
        "type": "object",
        "additionalProperties": False,
        "properties": {name: key_schema(k) for name, k in keys.items()},
    }
    if required:
        out["required"] = required
    return out


def json_schema() -> dict[str, Any]:
    """The JSON Schema (draft 2020-12) of a scene file: every table, array of tables and key."""
    props: dict[str, Any] = {name: key_schema(k) for name, k in TOP_LEVEL.items()}
    props.update({name: _table(keys) for name, keys in SCHEMA.items()})
    props.update({name: {"type": "array", "items": _table(keys)} for name, keys in ARRAY_SCHEMA.items()})
    return {
        "$schema": DIALECT,
        "$id": "https://ti-golf.invalid/scene.schema.json",
        "title": "ti_golf scene",
        "description": "A ti_golf scene file (TOML): its tables and keys, SI units.",
        "type": "object",
        "additionalProperties": False,
        "properties": props,
    }
