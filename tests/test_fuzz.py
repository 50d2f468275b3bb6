"""Fuzzed scene input: every generated scene and override either loads or is refused in one line.

Property-based (hypothesis), generated from the key table: wrong types, out-of-range and
non-finite numbers, wrong vector lengths, unknown keys, tables given as values, broken override
text. A case must load, or raise ``ConfigError`` with one line naming the source (file or
the overrides, ``--set`` on the command line); any other exception, or a multi-line message, is a defect. Examples are derandomised
(the same cases in every run) and bounded, so CI time is fixed; ``@example`` keeps the cases that
once failed as regression cases.
"""

from __future__ import annotations

import math

import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from ti_golf.errors import ConfigError
from ti_golf.scene.loader import load_scene
from ti_golf.scene.overrides import parse_override
from ti_golf.scene.schema import ARRAY_SCHEMA, SCHEMA, TOP_LEVEL, parse_range

SOURCE = "fuzz.toml"
FUZZ = settings(
    max_examples=300, derandomize=True, deadline=None, database=None, suppress_health_check=[HealthCheck.too_slow]
)

KEYS = [(s, k) for s, keys in SCHEMA.items() for k in keys] + [("", k) for k in TOP_LEVEL]
ARRAY_KEYS = [(a, k) for a, keys in ARRAY_SCHEMA.items() for k in keys]

numbers = st.one_of(
    st.integers(min_value=-(10**12), max_value=10**12),
    st.floats(allow_nan=True, allow_infinity=True),
    st.sampled_from([0, -1, 1, 0.5, 1e-300, 1e300, -0.0, 2, 3, 50_000_001]),
)
scalars = st.one_of(numbers, st.booleans(), st.text(max_size=12), st.sampled_from(["rk4", "file", "lab", "random"]))
values = st.recursive(
    scalars,
    lambda inner: st.one_of(st.lists(inner, max_size=5), st.dictionaries(st.text(max_size=6), inner, max_size=3)),
    max_leaves=8,
)

BASE = {"description": "fuzz", "launch": {"speed": 10.0, "angle_deg": 30.0}, "world": {"dt": 0.01}}


def loads_or_refuses(doc=None, overrides=None) -> None:
    """The property: the scene loads, or ConfigError names the source in one line."""
    try:
        load_scene(SOURCE, overrides, data=doc if doc is not None else BASE)
    except ConfigError as exc:
        text = str(exc)
        assert "\n" not in text, text
        assert text.startswith(SOURCE) or text.startswith("overrides: "), text


@FUZZ
@given(st.lists(st.tuples(st.sampled_from(KEYS), values), min_size=1, max_size=4))
@example([(("world", "dt"), math.nan)])
@example([(("terrain", "resolution"), [1e300, 2])])
@example([(("blocks", "count"), [1, 1, 1])])
def test_fuzzed_table_keys_load_or_are_refused(edits):
    doc = {k: dict(v) if isinstance(v, dict) else v for k, v in BASE.items()}
    for (section, key), value in edits:
        if section:
            table = doc.setdefault(section, {})
            if isinstance(table, dict):
                table[key] = value
        else:
            doc[key] = value
    loads_or_refuses(doc)


SETTINGS = [
    "world.ground=false",
    "world.ground=true",
    'air.model="spin_ratio"',
    'air.model="lab"',
    'air.wind_profile="log"',
    'contact.solver="jacobi"',
    "world.collisions=false",
    'terrain.kind="flat"',
    "launch.position=[0, 1, 0]",
    "contact.turf=true",
    "world.ground_height=0.5",
    "air.C_D=",
]
"""Overrides of the settings that decide whether other keys are read (and of two such keys)."""


def _plausible(section: str, key: str) -> st.SearchStrategy:
    """A key's default, a value of its kind that it allows, or any value."""
    decl = (SCHEMA[section] if section else TOP_LEVEL)[key]
    default = list(decl.default) if isinstance(decl.default, tuple) else decl.default
    choices = list(getattr(decl.check, "choices", ()))
    return st.one_of(st.sampled_from([default, *choices]), values)


@FUZZ
@given(
    st.lists(st.sampled_from(KEYS).flatmap(lambda k: st.tuples(st.just(k), _plausible(*k))), max_size=4),
    st.lists(st.sampled_from(SETTINGS), min_size=1, max_size=3, unique=True),
)
def test_fuzzed_files_with_setting_overrides_load_or_are_refused(edits, overrides):
    # a --set setting may leave keys of the file unread (they are dropped: the command line wins)
    doc = {k: dict(v) if isinstance(v, dict) else v for k, v in BASE.items()}
    for (section, key), value in edits:
        table = doc.setdefault(section, {}) if section else None
        if isinstance(table, dict):
            table[key] = value
    loads_or_refuses(doc, overrides)


@FUZZ
@given(
    st.sampled_from(sorted(ARRAY_SCHEMA)),
    st.lists(st.dictionaries(st.sampled_from(sorted({k for _, k in ARRAY_KEYS})), values, max_size=4), max_size=3),
)
def test_fuzzed_arrays_of_tables_load_or_are_refused(name, tables):
    doc = dict(BASE)
    doc[name] = tables
    loads_or_refuses(doc)


@FUZZ
@given(st.one_of(st.text(max_size=8), st.sampled_from(["air", "world", "blocks", "nonsense"])), values)
def test_unknown_tables_and_tables_as_values_are_refused(name, value):
    doc = dict(BASE)
    doc[name] = value
    loads_or_refuses(doc)


@FUZZ
@given(st.text(max_size=40))
@example("air.C_D=")
@example("=1")
@example("air.wind=[1,2")
@example("world.dt=1e999")
def test_fuzzed_set_overrides_parse_or_are_refused(text):
    try:
        parse_override(text)
    except ConfigError as exc:
        assert "\n" not in str(exc) and str(exc).startswith("overrides: "), str(exc)
        return
    loads_or_refuses(overrides=[text])


@FUZZ
@given(st.one_of(st.text(max_size=30), st.lists(numbers, max_size=6)))
@example("0:1e12:1e-12")
@example("1:0:1")
@example("nan")
def test_fuzzed_ranges_parse_or_are_refused(text):
    try:
        out = parse_range(text, "--angles", None)
    except ConfigError as exc:
        assert "\n" not in str(exc) and str(exc).startswith("--angles"), str(exc)
    else:
        assert out and all(math.isfinite(v) for v in out)


@pytest.mark.parametrize("doc", [BASE])
def test_the_fuzz_base_scene_loads(doc):
    load_scene(SOURCE, data=doc)


@FUZZ
@given(
    st.one_of(
        st.binary(max_size=200),
        st.text(max_size=200).map(lambda t: t.encode("utf-8")),
        st.lists(
            st.sampled_from(
                [
                    "[air]",
                    "[world]",
                    "[[blocks]]",
                    "[terrain]",
                    "rho = 1.2",
                    "rho = 1.2",
                    "dt = ",
                    "dt = 0.01",
                    'kind = "file"',
                    "count = [2, 2, 2]",
                    "= 3",
                    "[air",
                    "x = [1, 2",
                    '"',
                    "\\u00ff",
                    "[launch]",
                    "speed = 1e309",
                    "number = -1",
                ]
            ),
            max_size=8,
        ).map(lambda lines: "\n".join(lines).encode("utf-8")),
    )
)
@example(b"\xff\xfe[air]")
@example(b"[air]\nrho = 1.2\nrho = 1.3\n")  # a duplicate key
@example(b"[air]\n[air]\n")  # a duplicate table
def test_fuzzed_scene_files_load_or_are_refused(content):
    # raw files: binary, non-UTF-8, broken TOML, duplicate keys and tables; refused naming the file
    import tempfile
    from pathlib import Path

    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / "fuzz.toml"
        path.write_bytes(content)
        try:
            load_scene(path)
        except ConfigError as exc:
            assert "\n" not in str(exc) and str(exc).startswith(str(path)), str(exc)
