"""The scene keys' one declaration, and the JSON Schema made from it (``ti-golf schema``)."""

import dataclasses
import json
import math
import sys
from pathlib import Path

import pytest

from ti_golf.cli import main
from ti_golf.scene import schema as S
from ti_golf.scene.jsonschema import json_schema
from ti_golf.scene.loader import load_scene, scenes_dir

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
