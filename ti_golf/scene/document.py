"""A validated :class:`~ti_golf.scene.schema.Scene` written back as the document a TOML file holds,
and a scene with some keys changed, checked as ``--set`` checks them.

The document is plain data (tables as dicts, lists, numbers, strings: what ``tomllib`` returns and
JSON stores), so a saved run can carry its scene, and ``load_scene(scene.path, data=document)``
gives the same scene back (:func:`with_changes` does, with changes). Plain Python, no Taichi.
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Iterable, Mapping
from typing import Any

from ti_golf.scene.across import READ_ACROSS, read_across, with_value
from ti_golf.scene.keys import Key, is_read
from ti_golf.scene.loader import load_scene
from ti_golf.scene.overrides import parse_override
from ti_golf.scene.schema import ARRAY_SCHEMA, SCHEMA, TOP_LEVEL, Scene
from ti_golf.scene.values import coerce
from ti_golf.scene.weather import WEATHER_KEYS, air_from_weather

OPTIONAL_TABLES = ("launch", "terrain", "hole")
"""Tables whose presence means something even when every key is left at its default."""


def scene_document(scene: Scene) -> dict[str, Any]:
    """The TOML document (as ``tomllib`` would return it) that loads as ``scene``: every key that
    differs from its default and is read under the scene's settings, ``world.ground`` always (the
    loader turns it off when it is missing and the scene has planes or a terrain), an optional table
    (``[launch]``, ``[terrain]``, ``[hole]``) whenever the scene has it, and a heights file by its
    absolute path."""
    doc: dict[str, Any] = {}
    for name, key in TOP_LEVEL.items():
        value = getattr(scene, name)
        if value != key.default:
            doc[name] = _plain(value)
    for section, keys in SCHEMA.items():
        table = getattr(scene, section)
        if table is None:
            continue
        values = _table(table, keys, scene, section)
        if section == "world":
            values["ground"] = scene.world.ground
        if section == "air":
            _drop_weather_derived(values, table, scene)
        if section == "terrain" and values.get("file"):
            values["file"] = os.path.abspath(values["file"])
        if values or section in OPTIONAL_TABLES:
            doc[section] = values
    for name, keys in ARRAY_SCHEMA.items():
        tables = getattr(scene, name)
        if tables:
            doc[name] = [_table(t, keys, scene, name) for t in tables]
    return doc


def _drop_weather_derived(values: dict[str, Any], air: Any, scene: Scene) -> None:
    """Keep only one source of ρ and μ in the ``[air]`` table ``values`` of the scene's ``air``, as
    the loader refuses ρ or μ beside the weather: the weather keys when they give the scene's ρ
    and μ, else (a ``--set`` ρ or μ over a file's weather) ρ and μ themselves."""
    weather = {k: values[k] for k in WEATHER_KEYS if k in values}
    if not weather:
        return
    if air_from_weather(**weather) == (air.rho, air.viscosity):
        for name in ("rho", "viscosity"):
            values.pop(name, None)
    else:
        for name in weather:
            del values[name]
        values["rho"] = air.rho
        if is_read(SCHEMA["air"]["viscosity"], air, scene):
            values["viscosity"] = air.viscosity


def with_changes(scene: Scene, changes: Mapping[str, Any] | Iterable[str]) -> Scene:
    """``scene`` with the dotted keys of ``changes`` (``{"air.C_D": 0.25}`` or ``["air.C_D=0.25"]``)
    set, each checked as ``load_scene`` checks a ``--set`` override (the same errors and ranges,
    and a changed key that the scene's settings leave unread is refused). A key of the scene that
    the changes leave unread goes back to its default (``air.C_D`` once ``air.model`` is
    ``spin_ratio``, ``contact.relax`` once ``contact.solver`` is ``gauss_seidel``), as it would
    have no effect. The name and path stay the scene's."""
    items = dict(changes) if isinstance(changes, Mapping) else dict(parse_override(text) for text in changes)
    doc = scene_document(scene)
    _drop_unread(doc, items)
    kept = _take_across(doc, items)
    changed = load_scene(scene.path or None, items, data=doc)
    for dotted in kept:  # each put back where the changed scene still reads it (as it was: checked)
        if read_across(dotted, changed):
            table, name = dotted.split(".")
            changed = with_value(changed, dotted, getattr(getattr(scene, table), name))
    return dataclasses.replace(changed, name=scene.name, path=scene.path)


def _take_across(doc: dict[str, Any], changes: dict[str, Any]) -> list[str]:
    """Take out of ``doc`` each key of :data:`~ti_golf.scene.across.READ_ACROSS` that it sets and
    ``changes`` do not (the changes may leave it unread), and return their dotted names."""
    taken = []
    for dotted in READ_ACROSS:
        table, name = dotted.split(".")
        given = doc.get(table)
        if dotted not in changes and isinstance(given, dict) and name in given:
            del given[name]
            taken.append(dotted)
    return taken


def _drop_unread(doc: dict[str, Any], changes: dict[str, Any]) -> None:
    """Remove from ``doc`` each key, not among ``changes``, that ``changes`` leave unread."""
    for section, keys in SCHEMA.items():
        table = doc.get(section)
        if not isinstance(table, dict):
            continue
        for name in list(table):
            key = keys[name]
            if key.read_when is None or f"{section}.{name}" in changes:
                continue
            other, allowed = key.read_when
            if other.startswith("["):
                continue  # a table: set adds none and removes none
            table_name, other_key = other.split(".") if "." in other else (section, other)
            given = doc.get(table_name, {})
            current = changes.get(
                f"{table_name}.{other_key}", given.get(other_key, SCHEMA[table_name][other_key].default)
            )
            if current not in allowed:
                del table[name]


def _table(obj: Any, keys: dict[str, Key], scene: Scene, section: str) -> dict[str, Any]:
    """The keys of one table (a dataclass of ``keys``, the table ``section`` of the scene) that are
    set and read (:func:`~ti_golf.scene.keys.is_read`, :func:`~ti_golf.scene.across.read_across`)."""
    out = {}
    for name, key in keys.items():
        value = getattr(obj, name)
        if value is None or (value == key.default and not key.required):
            continue
        if not (is_read(key, obj, scene) and read_across(f"{section}.{name}", scene)):
            continue
        out[name] = _plain(value)
    return out


def _plain(value: Any) -> Any:
    """Tuples as lists (TOML arrays), the rest as it is."""
    return [_plain(v) for v in value] if isinstance(value, tuple) else value


def check_values(scene: Scene, source: str) -> None:
    """Refuse a scene whose values a scene file could not hold (a :class:`Scene` changed in Python
    with ``dataclasses.replace``: a negative ``world.dt`` ran backwards in time): each key that is
    set and read (:func:`_table`) checked as the loader checks it, its kind and allowed values,
    naming ``source`` and the dotted key."""
    tables = [(section, section, getattr(scene, section), keys) for section, keys in SCHEMA.items()]
    for name, keys in ARRAY_SCHEMA.items():
        tables += [(name, f"{name}[{i}]", table, keys) for i, table in enumerate(getattr(scene, name))]
    for section, prefix, table, keys in tables:
        for name, value in _table(table, keys, scene, section).items() if table is not None else ():
            coerce(value, keys[name], source, f"{prefix}.{name}")
