"""The scene keys' one declaration, and the JSON Schema made from it (``ti-golf schema``)."""

import dataclasses
import json
import math
import re
import sys
from pathlib import Path

import pytest

from ti_golf.cli import main
from ti_golf.errors import ConfigError
from ti_golf.scene import schema as S
from ti_golf.scene.checks import Interval
from ti_golf.scene.jsonschema import json_schema
from ti_golf.scene.loader import load_scene, scenes_dir
from ti_golf.scene.reference import KEYS_BEGIN, KEYS_END, keys_markdown, with_keys

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

TABLE_CLASSES = {
    "air": S.Air,
    "ball": S.Ball,
    "launch": S.Launch,
    "world": S.World,
    "contact": S.Contact,
    "sweep": S.SweepDefaults,
    "terrain": S.TerrainConfig,
    "hole": S.HoleConfig,
    "game": S.GameConfig,
}
ARRAY_CLASSES = {"balls": S.BallSpec, "blocks": S.Block, "surfaces": S.Surface, "planes": S.Plane}


def validate(value, schema, where="scene"):
    """The subset of JSON Schema that ``json_schema`` emits: a list of problems (empty: valid)."""
    problems = []
    if "anyOf" in schema:
        if all(validate(value, s, where) for s in schema["anyOf"]):
            problems.append(f"{where}: matches none of anyOf")
        return problems
    kind = schema.get("type")
    checks = {
        "object": lambda v: isinstance(v, dict),
        "array": lambda v: isinstance(v, list),
        "string": lambda v: isinstance(v, str),
        "boolean": lambda v: isinstance(v, bool),
        "integer": lambda v: isinstance(v, int) and not isinstance(v, bool),
        "number": lambda v: isinstance(v, (int, float)) and not isinstance(v, bool),
    }
    if kind and not checks[kind](value):
        return [f"{where}: not of type {kind}"]
    if kind == "object":
        for name, v in value.items():
            if name not in schema["properties"]:
                if schema.get("additionalProperties") is False:
                    problems.append(f"{where}.{name}: not allowed")
                continue
            problems += validate(v, schema["properties"][name], f"{where}.{name}")
        problems += [f"{where}.{r}: required" for r in schema.get("required", []) if r not in value]
    if kind == "array":
        if not schema.get("minItems", 0) <= len(value) <= schema.get("maxItems", math.inf):
            problems.append(f"{where}: {len(value)} items")
        problems += [p for i, v in enumerate(value) for p in validate(v, schema.get("items", {}), f"{where}[{i}]")]
    if kind in ("number", "integer"):
        lo, hi = schema.get("minimum", -math.inf), schema.get("maximum", math.inf)
        xlo, xhi = schema.get("exclusiveMinimum", -math.inf), schema.get("exclusiveMaximum", math.inf)
        if not (lo <= value <= hi and xlo < value < xhi):
            problems.append(f"{where}: {value} out of range")
    if "enum" in schema and value not in schema["enum"]:
        problems.append(f"{where}: {value!r} not in {schema['enum']}")
    return problems


def test_each_key_is_declared_once_as_a_field_of_its_tables_dataclass():
    # the schema tables are the dataclasses' declared fields, one for one, with the same defaults
    for table, cls in {**TABLE_CLASSES, **ARRAY_CLASSES}.items():
        keys = (S.SCHEMA | S.ARRAY_SCHEMA)[table]
        declared = {f.name: f for f in dataclasses.fields(cls) if "key" in f.metadata}
        assert list(keys) == list(declared), table
        for name, k in keys.items():
            f = declared[name]
            if k.required:
                assert f.default is dataclasses.MISSING, (table, name)
            else:
                assert f.default == k.default, (table, name)
            assert k.doc and k.unit, (table, name)


def test_the_keys_an_application_leaves_unread_are_scene_keys_or_tables():
    # a misspelt entry would refuse nothing, and the key it meant would pass without effect
    from ti_golf.scene.readers import APPLICATIONS, TIMED_RUN_NOT_READ

    for unread in (*APPLICATIONS.values(), TIMED_RUN_NOT_READ):
        for entry, reason in unread.items():
            table, _, name = entry.partition(".")
            known = name in S.SCHEMA[table] if name else (table in S.SCHEMA or table in S.TOP_LEVEL)
            assert known and reason, entry


def test_the_json_schema_lists_every_key_with_its_bounds():
    schema = json_schema()
    json.dumps(schema)  # serialisable
    props = schema["properties"]
    for table, keys in S.SCHEMA.items():
        assert set(props[table]["properties"]) == set(keys), table
        assert props[table]["additionalProperties"] is False
    for table, keys in S.ARRAY_SCHEMA.items():
        assert set(props[table]["items"]["properties"]) == set(keys), table
    relax = props["contact"]["properties"]["relax"]  # declared as (0, 1]
    assert (relax["exclusiveMinimum"], relax["maximum"], relax["default"]) == (0.0, 1.0, 0.5)
    assert props["world"]["properties"]["integrator"]["enum"] == list(S.INTEGRATORS)
    assert props["hole"]["required"] == ["position"]
    assert validate({"contact": {"relax": 0.0}}, schema) == ["scene.contact.relax: 0.0 out of range"]
    assert validate({"air": {"colour": 1}}, schema) == ["scene.air.colour: not allowed"]


@pytest.mark.parametrize("path", sorted(scenes_dir().glob("*.toml")), ids=lambda p: p.stem)
def test_every_bundled_scene_is_valid_under_the_json_schema(path: Path):
    doc = tomllib.loads(path.read_text())
    assert validate(doc, json_schema()) == []
    load_scene(path)  # and the loader agrees


def test_ti_golf_schema_writes_the_schema(tmp_path, capsys):
    out = tmp_path / "scene.schema.json"
    assert main(["schema", "--out", str(out)]) == 0
    assert json.loads(out.read_text()) == json.loads(json.dumps(json_schema()))
    assert [p.name for p in tmp_path.iterdir()] == ["scene.schema.json"]  # no temporary file left
    capsys.readouterr()
    assert main(["schema"]) == 0
    assert json.loads(capsys.readouterr().out) == json.loads(out.read_text())


def test_the_json_schema_bounds_the_numbers_of_lists():
    props = json_schema()["properties"]
    assert props["terrain"]["properties"]["size"]["items"] == {"type": "number", "exclusiveMinimum": 0.0}
    assert props["terrain"]["properties"]["resolution"]["items"] == {"type": "integer", "minimum": 2}
    assert props["blocks"]["items"]["properties"]["angle_deg"]["items"] == {
        "type": "number",
        "minimum": -90.0,
        "maximum": 90.0,
    }
    assert validate({"terrain": {"size": [10, 0]}}, json_schema()) == ["scene.terrain.size[1]: 0 out of range"]


def _bounded_keys():
    """(table, key name, Interval) of every table key whose allowed values are an interval."""
    for table, keys in S.SCHEMA.items():
        for name, k in keys.items():
            if isinstance(k.check, Interval) and k.kind in ("float", "int"):
                yield table, name, k.check


@pytest.mark.parametrize("table,name,interval", [pytest.param(*b, id=f"{b[0]}.{b[1]}") for b in _bounded_keys()])
def test_the_loader_and_the_json_schema_reject_the_same_numbers(table, name, interval):
    # the loader's check and the schema's minimum/maximum both come from the key's one declaration
    schema = json_schema()
    outside = [interval.lo if interval.lo_open else interval.lo - 1]
    if interval.hi is not None:
        outside.append(interval.hi if interval.hi_open else interval.hi + 1)
    for value in outside:
        doc = {table: {name: value}}
        if table == "hole":
            doc["hole"]["position"] = [0.0, 0.0]
        assert validate(doc, schema), (table, name, value)
        with pytest.raises(ConfigError) as err:
            load_scene(data=doc)
        assert err.value.key == f"{table}.{name}" and interval.text in err.value.reason


def test_allowed_values_are_stated_once_by_the_check():
    # a key's 'allowed' text is its check's, unless the declaration words it itself (air.gamma)
    assert S.SCHEMA["contact"]["relax"].allowed == "(0, 1]"
    assert S.SCHEMA["world"]["integrator"].allowed == "semi_implicit | rk4"
    assert S.SCHEMA["air"]["gamma"].allowed == "1 or 2"
    assert S.ARRAY_SCHEMA["blocks"]["count"].allowed == "3 whole numbers >= 1"
    for keys in (*S.SCHEMA.values(), *S.ARRAY_SCHEMA.values()):
        for name, k in keys.items():
            assert (k.check is None) == (k.allowed == ""), name


def test_the_key_reference_of_the_docs_page_is_up_to_date():
    # docs/scenes.md holds the key table, to be read in the repository as on the site: a key
    # declared, changed or dropped without `make docs-keys` leaves the page stale
    page = (Path(__file__).resolve().parent.parent / "docs" / "scenes.md").read_text(encoding="utf-8")
    block = page[page.index(KEYS_BEGIN) + len(KEYS_BEGIN) : page.index(KEYS_END)]
    assert block.strip() == keys_markdown(), "docs/scenes.md's key table is out of date: run `make docs-keys`"
    assert with_keys(page) == page


def test_keys_markdown_lists_every_key_with_section_type_unit_default_allowed_and_help():
    lines = keys_markdown().splitlines()
    assert lines[0] == "| section | key | type | unit | default | allowed | help |"
    rows = {}
    for line in lines[2:]:
        cells = [c.strip() for c in re.split(r"(?<!\\)\|", line.strip().strip("|"))]
        assert len(cells) == 7, line
        rows[(cells[0].strip("`"), cells[1].strip("`"))] = cells
    expected = {("(top level)", name) for name in S.TOP_LEVEL}
    expected |= {(f"[{t}]", name) for t, keys in S.SCHEMA.items() for name in keys}
    expected |= {(f"[[{t}]]", name) for t, keys in S.ARRAY_SCHEMA.items() for name in keys}
    assert set(rows) == expected
    assert rows[("[contact]", "relax")][2:6] == ["number", "-", "`0.5`", "(0, 1]"]
    assert rows[("[air]", "wind")][2:5] == ["[x, y, z]", "m/s", "`[0, 0, 0]`"]
    assert rows[("[hole]", "position")][5] == "required; [[-1000000, 1000000], [-1000000, 1000000]]"
    assert rows[("[[balls]]", "position")][5] == "required; each in [-1000000, 1000000]"
