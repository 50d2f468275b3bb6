"""``ti-golf scenes`` and ``ti-golf keys``: the bundled scenes, and every scene key documented."""

from __future__ import annotations

import argparse

from ti_golf.errors import ConfigError
from ti_golf.scene.loader import load_scene, scenes_dir
from ti_golf.scene.reference import describe_keys


def add_parser(sub: argparse._SubParsersAction) -> None:
    """Add ``scenes`` and ``keys`` to ``ti-golf``'s subcommands."""
    sub.add_parser("scenes", help="list the bundled scenes with a one-line description")
    sub.add_parser("keys", help="print every scene key with unit, default and allowed values")


def cmd_scenes(args: argparse.Namespace) -> int:
    """Print each bundled scene's name and one-line description; 0."""
    folder = scenes_dir()
    files = sorted(folder.glob("*.toml"))
    if not files:
        print(f"no scenes in {folder}")
        return 0
    width = max(len(f.stem) for f in files)
    for f in files:
        try:
            desc = load_scene(f).description
        except ConfigError as exc:
            desc = f"(invalid: {f'key {exc.key!r} ' if exc.key else ''}{exc.reason})"
        print(f"{f.stem:<{width}}  {desc}")
    return 0


def cmd_keys(args: argparse.Namespace) -> int:
    """Print every scene key with its unit, default and allowed values; 0."""
    print(describe_keys())
    return 0
