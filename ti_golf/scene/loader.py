"""TOML scene files -> validated :class:`~ti_golf.scene.schema.Scene`, with ``--set KEY=VALUE`` overrides.

Every problem raises :class:`~ti_golf.errors.ConfigError` naming the file (or ``--set``), the
dotted key and what is allowed. No Taichi import here.
"""

from __future__ import annotations

import difflib
import importlib.resources
import math
import os
import sys
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - Python 3.10
    import tomli as tomllib

from ti_golf.errors import OVERRIDES, ConfigError
from ti_golf.scene.across import READ_ACROSS, read_across, unread_text, with_value
from ti_golf.scene.air import SPIN_RATIOS, quadratic_range
from ti_golf.scene.checks import REACH, SPEED_LIMIT, raise_config
from ti_golf.scene.course import check_hole
from ti_golf.scene.keys import Key, read_when_text
from ti_golf.scene.overrides import apply_override, parse_override, suggest
from ti_golf.scene.schema import (
    ARRAY_SCHEMA,
    SCHEMA,
    TOP_LEVEL,
    Air,
    Ball,
    BallSpec,
    Block,
    Contact,
    GameConfig,
    HoleConfig,
    Launch,
    Plane,
    Scene,
    Surface,
    SweepDefaults,
    TerrainConfig,
    World,
)
from ti_golf.scene.terrain import load_heights_file
from ti_golf.scene.values import coerce
from ti_golf.scene.weather import WEATHER_KEYS, air_from_weather

_SECTION_TYPES = {"air": Air, "ball": Ball, "launch": Launch, "world": World, "contact": Contact, "game": GameConfig}


def read_toml(path: str | os.PathLike[str]) -> dict[str, Any]:
    """Read a TOML file, turning every I/O or syntax problem into a :class:`ConfigError`."""
    p = Path(path)
    if not p.exists():
        raise ConfigError(str(p), None, "file not found")
    if p.is_dir():
        raise ConfigError(str(p), None, "is a directory, not a scene file")
    if not p.is_file():  # (a FIFO or a device: reading it could wait for ever)
        raise ConfigError(str(p), None, "is not a regular file")
    try:
        text = p.read_bytes().decode("utf-8-sig")  # (a byte-order mark, as Windows editors write, is dropped)
    except OSError as exc:
        raise ConfigError(str(p), None, f"cannot be read ({exc.strerror or exc})") from None
    except UnicodeDecodeError:
        raise ConfigError(str(p), None, "is not UTF-8 text") from None
    try:
        doc: dict[str, Any] = tomllib.loads(text)
        return doc
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(str(p), None, f"is not valid TOML: {exc}") from None


def resolve_scene_path(name: str | os.PathLike[str], folder: Path | None = None) -> Path:
    """A scene path as given, or a bare name looked up in the bundled ``scenes/`` folder (or in
    ``folder``: the bundled studies'); a :class:`ConfigError` suggesting the closest name there
    when there is none."""
    p = Path(name)
    if p.exists() or p.suffix == ".toml" and ("/" in str(name) or os.sep in str(name)):  # (./x.toml: a path)
        return p
    look_in = scenes_dir() if folder is None else folder
    for cand in (look_in / p, look_in / f"{p}.toml"):
        if cand.exists():
            return cand
    if p.parent == Path(".") and p.suffix in ("", ".toml"):  # a bare name: a bundled one's, misspelled?
        close = difflib.get_close_matches(p.stem, [f.stem for f in look_in.glob("*.toml")], n=1)
        hint = f"did you mean '{close[0]}'? " if close else ""
        if folder is None:
            raise ConfigError(
                str(name), None, f"file not found, nor a bundled scene ({hint}`ti-golf scenes` lists them)"
            )
        raise ConfigError(
            str(name),
            None,
            f"file not found, nor a file of that name in {look_in}" + (f" ({hint.strip()})" if hint else ""),
        )
    return p


def scenes_dir() -> Path:
    """The folder of the bundled scenes: the source tree's ``scenes/`` when ti_golf runs from a
    checkout, else the package data ``ti_golf.scene.data`` of the installed wheel (the environment
    variable ``TI_GOLF_SCENES`` overrides both)."""
    env = os.environ.get("TI_GOLF_SCENES")
    if env:
        if not Path(env).is_dir():
            raise ConfigError("TI_GOLF_SCENES", None, f"must name a folder of scene files ({env!r} is none)")
        return Path(env)
    checkout = Path(__file__).resolve().parents[2]
    if (checkout / "pyproject.toml").is_file() and (checkout / "scenes").is_dir():
        return checkout / "scenes"
    return Path(str(importlib.resources.files("ti_golf.scene.data")))


def load_scene(
    path: str | os.PathLike[str] | None = None,
    overrides: Mapping[str, Any] | Iterable[str] | None = None,
    *,
    data: Mapping[str, Any] | None = None,
) -> Scene:
    """Load and validate a scene.

    Args:
        path: a TOML file, or a bundled scene's name (``"lab_turbulent"``); ``None`` with ``data``.
        overrides: ``{"air.C_D": 0.25}``, ``["air.C_D=0.25", ...]`` (``--set`` syntax) or one such
            text; a value ``None`` (``"game.start="``) clears the key, back to its default; a
            list value may be a numpy vector.
        data: an already-parsed TOML document (used instead of reading ``path``).

    Raises:
        ConfigError: naming the file, the key and what is allowed.
    """
    if isinstance(path, bytes) or (path is not None and not isinstance(path, (str, os.PathLike))):
        raise TypeError(f"path must be a scene file's path or a bundled scene's name, a str (got {path!r:.60})")
    if overrides is not None and not isinstance(overrides, (str, Mapping, list, tuple)):
        raise TypeError(f"overrides must be a mapping of keys to values or KEY=VALUE texts (got {overrides!r:.60})")
    if data is None:
        if path is None or not str(path).strip():
            raise ConfigError("", None, "no scene given")
        p = resolve_scene_path(path)
        raw = read_toml(p)
        source = str(p)
    else:
        raw = dict(data)
        p = Path(path) if path else Path("<scene>")
        source = str(path) if path else "<scene>"
    doc = _copied(raw)
    if isinstance(overrides, str):  # one KEY=VALUE text, not its characters
        overrides = [overrides]
    file_doc = None
    if overrides:
        file_doc = _copied(doc)
        items = overrides.items() if isinstance(overrides, Mapping) else (parse_override(o) for o in overrides)
        for dotted, value in items:
            apply_override(doc, dotted, value)
    return _build(doc, source, p.stem, file_doc)


def _copied(doc: Mapping[str, Any]) -> dict[str, Any]:
    """A copy of a scene document that overrides can change: its tables, and the tables of its
    ``[[...]]`` arrays, copied (the values themselves are not changed in place)."""
    return {
        k: dict(v)
        if isinstance(v, dict)
        else [dict(t) if isinstance(t, dict) else t for t in v]
        if isinstance(v, list)
        else v
        for k, v in doc.items()
    }


def _build(doc: dict[str, Any], source: str, name: str, file_doc: dict[str, Any] | None = None) -> Scene:
    """The :class:`Scene` of a scene document (the file's tables with the overrides applied), every
    key checked: the top-level keys and table names, then each table in :data:`SCHEMA`'s order,
    then the ``[[...]]`` arrays (``file_doc``: the file's document before the overrides, when
    there are any; see :func:`_refuse_unread_across`)."""
    kwargs: dict[str, Any] = {"name": name, "path": source}
    _build_top_level(doc, source, kwargs)
    for section, keys in SCHEMA.items():
        table = doc.get(section)
        if table is not None:
            _build_section(section, keys, table, source, doc, kwargs)
    if "launch" not in doc:
        kwargs["launch"] = None
    _build_arrays(doc, source, kwargs)
    if (kwargs["planes"] or kwargs.get("terrain") is not None) and "ground" not in doc.get("world", {}):
        world = kwargs.get("world", World())
        kwargs["world"] = World(**{**world.__dict__, "ground": False})
    kwargs["overridden"] = frozenset(
        f"{table}.{name}" if name else table
        for table, value in doc.items()
        for name, given in (value.items() if isinstance(value, dict) else [("", value)])
        if _with_source(given, source)[0] == OVERRIDES
    ) | frozenset(
        f"{table}[{i}].{name}"
        for table in ARRAY_SCHEMA
        for i, values in enumerate(doc[table] if isinstance(doc.get(table), list) else [])
        for name, given in (values.items() if isinstance(values, dict) else ())
        if _with_source(given, source)[0] == OVERRIDES
    )
    scene = Scene(**kwargs)
    check_hole(scene)
    return _refuse_unread_across(doc, scene, source, file_doc)


def _refuse_unread_across(doc: Mapping[str, Any], scene: Scene, source: str, file_doc: dict[str, Any] | None) -> Scene:
    """Refuse each key of :data:`~ti_golf.scene.across.READ_ACROSS` that the document sets and
    the ``scene`` built from it leaves unread (``world.ground_height`` without a ground plane,
    log wind or a launch resting on the ground): a key never silently does nothing. A key of the
    file that the file's scene reads, and ``--set`` keys leave unread (``--set world.ground=false``
    on a scene with ``contact.turf``), goes back to its default: the command line wins (``file_doc``:
    the file's document, ``None`` without overrides). Returns the scene."""
    file_scene: Scene | None = None
    for dotted in READ_ACROSS:
        table, name = dotted.split(".")
        given = doc.get(table)
        if not isinstance(given, dict) or name not in given or read_across(dotted, scene):
            continue
        where, _value = _with_source(given[name], source)
        if where != OVERRIDES and file_doc is not None:
            file_scene = file_scene or _build(file_doc, source, scene.name)
            if read_across(dotted, file_scene):
                scene = with_value(scene, dotted, SCHEMA[table][name].default)
                continue
        raise_config(where, dotted, unread_text(dotted))
    return scene


def _with_source(value: Any, source: str) -> tuple[str, Any]:
    """A value of the document and where it came from: ``OVERRIDES`` for an override's (stored as
    ``(OVERRIDES, value)``), else ``source``."""
    if isinstance(value, tuple) and len(value) == 2 and value[0] == OVERRIDES:
        return value[0], value[1]
    return source, value


def _build_top_level(doc: dict[str, Any], source: str, kwargs: dict[str, Any]) -> None:
    """Check the document's top level into ``kwargs``: its keys (:data:`TOP_LEVEL`) coerced, and
    every other name a table of :data:`SCHEMA` or an array of :data:`ARRAY_SCHEMA`."""
    for top, value in doc.items():
        if top in TOP_LEVEL:
            src, value = _with_source(value, source)
            kwargs[top] = coerce(value, TOP_LEVEL[top], src, top)
            continue
        if top in ARRAY_SCHEMA:
            continue
        if top not in SCHEMA:
            names = list(TOP_LEVEL) + list(SCHEMA) + [f"[[{a}]]" for a in ARRAY_SCHEMA]
            raise_config(
                source,
                top,
                f"is not a scene table or key{suggest(top, list(SCHEMA) + list(TOP_LEVEL) + list(ARRAY_SCHEMA))}; "
                f"allowed: {', '.join(names)}",
            )
        if not isinstance(value, dict):
            raise_config(source, top, f"must be a table [{top}] (got {value!r})")


def _check_log_wind(wind: tuple[float, float, float], z_ref: float, z0: float, source: str, key: str) -> None:
    """The log profile's wind u(z) = wind·ln(z/z₀)/ln(z_ref/z₀) within the wind's limit
    (:data:`~ti_golf.scene.checks.SPEED_LIMIT` on each axis) up to :data:`REACH` above the ground,
    as far as a scene reaches (a z₀ just below z_ref makes the profile steep without bound), else
    a ConfigError naming ``key`` of ``source``."""
    peak = max(abs(c) for c in wind) * math.log(REACH / z0) / math.log(z_ref / z0)
    if peak > SPEED_LIMIT:
        raise_config(
            source,
            key,
            f"makes the log profile's wind {peak:.3g} m/s at {REACH:g} m above the ground (wind_z0 = {z0:.7g} m, "
            f"wind_height = {z_ref:.7g} m), past the wind's limit of {SPEED_LIMIT:g} m/s: less wind, or a "
            "wind_z0 further below wind_height",
        )


def _build_section(
    section: str, keys: dict[str, Key], table: dict[str, Any], source: str, doc: dict[str, Any], kwargs: dict[str, Any]
) -> None:
    """Check the table ``[section]`` against its ``keys`` and put its dataclass into ``kwargs``."""
    values: dict[str, Any] = {}
    sources: dict[str, str] = {}
    for name, value in table.items():
        dotted = f"{section}.{name}"
        src, value = _with_source(value, source)
        if name not in keys:
            raise_config(src, dotted, f"is unknown{suggest(name, keys)}; allowed in [{section}]: " + ", ".join(keys))
        values[name] = coerce(value, keys[name], src, dotted)
        sources[name] = src
    if section == "terrain" and "file" in values and "kind" not in values:
        values["kind"] = "file"  # a heights file names the kind of terrain it is
    _refuse_unread(values, keys, section, sources, source, doc)
    if section == "air":
        values = _air(values, sources, source)
    if section == "sweep":
        kwargs["sweep"] = SweepDefaults(**values)
    elif section == "terrain":
        kwargs["terrain"] = _terrain(values, sources, source)
    elif section == "hole":
        if "position" not in values:
            raise_config(source, "hole.position", "is required (the cup's centre [x, z] in m)")
        kwargs["hole"] = HoleConfig(**values)
    else:
        kwargs[section] = _SECTION_TYPES[section](**values)
    if section == "air" and kwargs["air"].model in ("spin_ratio", "spin_reynolds") and kwargs["air"].gamma != 2:
        raise_config(
            sources.get("gamma", sources.get("model", source)),
            "air.gamma",
            f'must be 2 with air.model = "{kwargs["air"].model}" (its drag and lift are for turbulent flow)',
        )


def _build_arrays(doc: dict[str, Any], source: str, kwargs: dict[str, Any]) -> None:
    """Check the ``[[balls]]``, ``[[blocks]]``, ``[[planes]]`` and ``[[surfaces]]`` arrays into
    ``kwargs``, and the surface types against the terrain's ``surface_levels``."""
    arrays = {name: _array_tables(doc.get(name), name, source, doc) for name in ARRAY_SCHEMA}
    kwargs["balls"] = tuple(_ball_spec(t, source, i) for i, t in enumerate(arrays["balls"]))
    kwargs["blocks"] = tuple(_block(t, source, i) for i, t in enumerate(arrays["blocks"]))
    kwargs["planes"] = tuple(_plane(t) for t in arrays["planes"])
    kwargs["surfaces"] = tuple(Surface(**t) for t in arrays["surfaces"])
    levels = kwargs["terrain"].surface_levels if kwargs.get("terrain") is not None else None
    if levels is not None:
        if len(levels) != len(kwargs["surfaces"]) - 1:
            raise_config(
                source,
                "terrain.surface_levels",
                f"needs one level fewer than there are [[surfaces]] "
                f"({len(kwargs['surfaces'])} surfaces, {len(levels)} levels)",
            )
        if any(b <= a for a, b in zip(levels, levels[1:])):
            raise_config(source, "terrain.surface_levels", "must increase")
    elif kwargs["surfaces"] and kwargs.get("terrain") is None:
        raise_config(source, "surfaces", "surface types need a [terrain] (with terrain.surface_levels)")
    elif len(kwargs["surfaces"]) > 1:  # (without levels every cell is the first's: the others had no effect)
        raise_config(
            source,
            "terrain.surface_levels",
            f"is required with {len(kwargs['surfaces'])} [[surfaces]]: the heights that divide them, one level "
            "fewer than surfaces",
        )


def _array_tables(value: Any, name: str, source: str, doc: Mapping[str, Any]) -> list[dict[str, Any]]:
    """Validate the tables of one ``[[name]]`` array against :data:`ARRAY_SCHEMA`."""
    if value is None:
        return []
    if not isinstance(value, list) or not all(isinstance(t, dict) for t in value):
        raise_config(source, name, f"must be an array of tables written [[{name}]]")
    keys = ARRAY_SCHEMA[name]
    out = []
    for i, table in enumerate(value):
        values, sources = {}, {}
        for k, given in table.items():
            dotted = f"{name}[{i}].{k}"
            sources[k], v = _with_source(given, source)
            if k not in keys:
                raise_config(source, dotted, f"is unknown{suggest(k, keys)}; allowed in [[{name}]]: " + ", ".join(keys))
            values[k] = coerce(v, keys[k], sources[k], dotted)
        _refuse_unread(values, keys, f"{name}[{i}]", sources, source, doc)
        out.append(values)
    return out


def _refuse_unread(
    values: dict[str, Any],
    keys: dict[str, Key],
    prefix: str,
    sources: dict[str, str],
    source: str,
    doc: Mapping[str, Any],
) -> None:
    """Refuse each key of one table that its setting would leave unread (``Key.read_when``): a key
    never silently does nothing. Across places the command line wins, as everywhere: a key of the
    file that a ``--set`` setting leaves unread is dropped from ``values`` (``--set air.model =
    "spin_ratio"`` on a file with ``air.C_D``), not refused."""
    for name in list(values):
        key = keys[name]
        if key.read_when is None:
            continue
        other, allowed = key.read_when
        setting_set = False  # whether the setting comes from the command line
        if other.startswith("["):  # a table the scene must have
            read = other.strip("[]") in doc
        elif "." in other:  # a key of another table, as given (its value is checked there) or its default
            table, other_key = other.split(".")
            given = doc.get(table, {})
            current = given.get(other_key, SCHEMA[table][other_key].default) if isinstance(given, dict) else None
            if isinstance(current, tuple) and len(current) == 2 and current[0] == OVERRIDES:
                current, setting_set = current[1], True
            read = current in allowed
        else:
            read = values.get(other, keys[other].default) in allowed
            setting_set = sources.get(other) == OVERRIDES
        if read:
            continue
        if setting_set and sources.get(name, source) != OVERRIDES:
            del values[name]
            continue
        raise_config(sources.get(name, source), f"{prefix}.{name}", f"is only read when {read_when_text(key, prefix)}")


def _air(values: dict[str, Any], sources: dict[str, str], source: str) -> dict[str, Any]:
    """The ``[air]`` table's values with ρ and μ from the weather when a weather key is given
    (:func:`~ti_golf.scene.weather.air_from_weather`).

    Keys that would leave another without effect are refused when they come from the same place
    (both in the file, or both ``--set``): ``rho`` or ``viscosity`` beside a weather key,
    ``altitude`` beside both ``pressure`` and ``temperature``. Across places the command line wins, as ``--set`` does
    everywhere: a ``--set`` weather key replaces the file's ``rho`` and ``viscosity``, a ``--set``
    ``rho`` or ``viscosity`` what the file's weather gives for that one quantity, ``--set``
    ``pressure`` the file's ``altitude`` and the other way round. A log profile's reference height
    must exceed its roughness length.
    """
    values = dict(values)
    cli = {k for k in values if sources.get(k) == OVERRIDES}
    if values.get("model") == "spin_reynolds":
        _spin_coefficients(values, sources, source)

    def drop_file(*names: str) -> None:
        for name in names:
            if name in values and name not in cli:
                del values[name]

    if values.get("wind_profile") == "log":
        z_ref, z0 = values.get("wind_height", Air.wind_height), values.get("wind_z0", Air.wind_z0)
        if z_ref <= z0:
            where, rule = (
                ("wind_height", "exceed air.wind_z0")
                if "wind_height" in values
                else ("wind_z0", "be below air.wind_height")
            )
            raise_config(
                sources.get(where, source),
                f"air.{where}",
                f"must {rule} (got wind_height = {z_ref:g} m, wind_z0 = {z0:g} m)",
            )
        given = next((k for k in ("wind", "wind_z0", "wind_height", "wind_profile") if k in cli), "wind_z0")
        _check_log_wind(values.get("wind", Air.wind), z_ref, z0, sources.get(given, source), f"air.{given}")
    if cli & set(WEATHER_KEYS):
        drop_file("rho", "viscosity")
    if "pressure" in cli:
        drop_file("altitude")
    if "altitude" in cli:
        drop_file("pressure")
    weather = [k for k in WEATHER_KEYS if k in values]
    if not weather:
        return values
    given = ", ".join(f"air.{k}" for k in weather)
    if {"pressure", "altitude", "temperature"} <= values.keys():
        raise_config(
            sources.get("altitude", source),
            "air.altitude",
            "cannot be given with air.pressure and air.temperature: the altitude only sets the pressure and the "
            "default temperature",
        )
    rho, mu = air_from_weather(**{k: values[k] for k in weather})
    for name, what, value in (("rho", "ρ", rho), ("viscosity", "μ", mu)):
        if name not in values:
            values[name] = value
        elif name not in cli or cli & set(weather):  # (a --set value over the file's weather stays)
            raise_config(
                sources.get(name, source),
                f"air.{name}",
                f"cannot be given with the weather ({given}), which sets {what}: give one or the other",
            )
    return values


def _spin_coefficients(values: dict[str, Any], sources: dict[str, str], source: str) -> None:
    """``air.C_D_S`` and ``air.C_L_S`` give a drag coefficient C_D(S) in [0, 100] and a lift
    coefficient C_L(S) in [-100, 100] over the fits' spin ratios (``SPIN_RATIOS``), where the
    flight holds S: a negative drag feeds the ball energy, and larger coefficients overflow the
    forces, as the lab's C_D and C_M are bounded."""
    lo_s, hi_s = SPIN_RATIOS
    for name, least in (("C_D_S", 0.0), ("C_L_S", -100.0)):
        if name not in values:
            continue
        lo, hi = quadratic_range(values[name], lo_s, hi_s)
        if lo < least or hi > 100.0:
            raise_config(
                sources.get(name, source),
                f"air.{name}",
                f"gives {name[:3]}(S) from {lo:.4g} to {hi:.4g} over the spin ratios {lo_s:g} ≤ S ≤ {hi_s:g}; "
                f"it must stay within [{least:g}, 100]",
            )


def _ball_spec(values: dict[str, Any], source: str, i: int) -> BallSpec:
    if "position" not in values:
        raise_config(source, f"balls[{i}].position", "is required (the ball's centre [x, y, z] in m)")
    return BallSpec(**values)


BLOCK_REACH = REACH
"""The farthest a block of balls reaches [m]: its corners within ±1,000 km of the origin, a lattice
at most as long (far past any course, and far from the floats' limits that a box's volume or a
lattice's sites would overflow)."""


def _block(values: dict[str, Any], source: str, i: int) -> Block:
    block = Block(**values)
    if block.kind == "random" and "number" not in values:
        raise_config(source, f"blocks[{i}].number", "is required for a random block: how many balls, 1 to 50,000,000")
    if block.kind == "random" and any(lo >= hi for lo, hi in zip(block.box_min, block.box_max)):
        raise_config(source, f"blocks[{i}].box_max", "must exceed box_min on every axis")
    corners = ("box_min", "box_max") if block.kind == "random" else ("origin",)
    for name in corners:
        if any(abs(c) > BLOCK_REACH for c in getattr(block, name)):
            raise_config(
                source,
                f"blocks[{i}].{name}",
                f"must lie within ±{BLOCK_REACH:,.0f} m on every axis (got {getattr(block, name)})",
            )
    if block.kind == "lattice" and (block.spacing or 0.0) * (max(block.count) - 1) > BLOCK_REACH:
        raise_config(
            source,
            f"blocks[{i}].spacing",
            f"spans more than {BLOCK_REACH:,.0f} m with count {[int(c) for c in block.count]}",
        )
    if block.kind == "lattice" and "seed" in values and not _draws_at_random(block):
        raise_config(
            source,
            f"blocks[{i}].seed",
            "has no effect: the lattice draws nothing at random (no jitter, radius_jitter, velocity_jitter, "
            "nor shots' ranges)",
        )
    if (block.speed is None) != (block.angle_deg is None):
        raise_config(source, f"blocks[{i}].speed", "shots need both speed and angle_deg ([min, max] each)")
    for name in ("direction_deg", "backspin"):
        if name in values and block.speed is None:
            raise_config(source, f"blocks[{i}].{name}", "is read only for shots (a block with speed and angle_deg)")
    return block


def _draws_at_random(block: Block) -> bool:
    """Whether a lattice block draws something from its seed (:func:`~.balls.build_balls`)."""
    shots = block.speed is not None and any(
        r is not None and r[0] < r[1] for r in (block.speed, block.angle_deg, block.direction_deg, block.backspin)
    )
    return block.jitter > 0 or block.radius_jitter > 0 or block.velocity_jitter > 0 or shots


def _terrain(values: dict[str, Any], sources: dict[str, str], source: str) -> TerrainConfig:
    """The ``[terrain]`` table: resolve and check the heights file (shape, finite values) now, so a
    bad terrain is reported when the scene loads."""
    if "resolution" in values:
        values["resolution"] = tuple(int(c) for c in values["resolution"])
    cfg = TerrainConfig(**values)
    if cfg.kind == "file":
        src = sources.get("file", source)
        if not cfg.file:
            raise_config(
                src,
                "terrain.file",
                'is required when terrain.kind = "file" (a .npy array of heights [m], shape (nx, nz))',
            )
        path = Path(cfg.file).expanduser()
        if not path.is_absolute() and src != OVERRIDES:
            path = Path(source).parent / path
        load_heights_file(path, src)
        cfg = TerrainConfig(**{**cfg.__dict__, "file": str(path)})
    return cfg


def _plane(values: dict[str, Any]) -> Plane:
    plane = Plane(**values)
    n = plane.normal
    length = math.sqrt(sum(c * c for c in n))
    if abs(length - 1.0) <= UNIT_LENGTH_ULPS * sys.float_info.epsilon:
        return plane  # already a unit normal: dividing again could move its last bit (see scene.document)
    if not 0.0 < length < math.inf:  # |n|² under- or overflowed (1e-170, 1e300): scaled first (n ≠ 0: NonZero)
        big = max(abs(c) for c in n)
        n = (n[0] / big, n[1] / big, n[2] / big)
        length = math.sqrt(sum(c * c for c in n))
    return Plane(point=plane.point, normal=(n[0] / length, n[1] / length, n[2] / length))


UNIT_LENGTH_ULPS = 4
"""A plane's normal whose length is within this many units of round-off of 1 is taken as it is: a
normalised normal is (its length within 1.5 of them), and so a scene written back from a loaded one
(``scene.document.scene_document``) loads with the same normals, bit for bit."""
