"""``ti-golf schema``: the JSON Schema of scene files, for editors that check TOML as it is typed."""

from __future__ import annotations

import argparse
import json

from ti_golf.cli._common import check_writable
from ti_golf.files import write_text
from ti_golf.scene.jsonschema import json_schema
from ti_golf.study.spec import study_json_schema


def add_parser(sub: argparse._SubParsersAction) -> None:
    """Add ``schema`` to ``ti-golf``'s subcommands."""
    p = sub.add_parser(
        "schema",
        help="write the JSON Schema of scene files (for Taplo / Even Better TOML)",
        description="Write the JSON Schema (draft 2020-12) of scene files. An editor with Taplo (Even Better "
        "TOML) checks and completes a scene file against it when the file's first line is "
        "'#:schema ./scene.schema.json', or for every scene when a .taplo.toml [[rule]] with include = "
        '["scenes/*.toml"] sets schema.path = "scene.schema.json".',
    )
    p.add_argument("--out", help="write the schema to this file (default: standard output)")
    p.add_argument("--study", action="store_true", help="the schema of study files (ti-golf study) instead")


def cmd_schema(args: argparse.Namespace) -> int:
    """Print or write (atomically) the scene files' JSON Schema."""
    check_writable(args.out, "--out", (".json",))
    schema = study_json_schema() if args.study else json_schema()
    text = json.dumps(schema, indent=2, ensure_ascii=False) + "\n"
    if args.out is None:
        print(text, end="")
        return 0
    write_text(args.out, text)
    print(f"wrote {args.out}")
    return 0
