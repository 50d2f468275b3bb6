"""The scene key reference for people, as Markdown tables made from the key declarations
(:mod:`ti_golf.scene.schema`): :func:`describe_keys` is what ``ti-golf keys`` prints,
:func:`keys_markdown` the docs' key reference, which :func:`with_keys` writes into a page."""

from __future__ import annotations

from collections.abc import Iterator

from ti_golf.scene.keys import Key, help_text
from ti_golf.scene.schema import ARRAY_SCHEMA, SCHEMA, TOP_LEVEL

TYPE_NAMES = {
    "float": "number",
    "int": "integer",
    "bool": "boolean",
    "str": "string",
    "text": "string",
    "vec3": "[x, y, z]",
    "vec2": "[a, b]",
    "list2": "[min, max]",
    "range": "START:STOP:STEP or [a, b, …]",
}
"""How the reference names each kind of key (see :class:`~ti_golf.scene.keys.Key`)."""


def _tables() -> Iterator[tuple[str, str, dict[str, Key]]]:
    """(section as written in a scene file, prefix of dotted names, keys) of every table."""
    yield "(top level)", "", TOP_LEVEL
    for name, keys in SCHEMA.items():
        yield f"[{name}]", f"{name}.", keys
    for name, keys in ARRAY_SCHEMA.items():
        yield f"[[{name}]]", f"[[{name}]].", keys


def keys_markdown() -> str:
    """Every scene key as a Markdown table: section, key, type, unit, default, allowed values, help."""
    rows = ["| section | key | type | unit | default | allowed | help |", "|---|---|---|---|---|---|---|"]
    for section, _, keys in _tables():
        for k in keys.values():
            allowed = "; ".join(filter(None, ("required" if k.required else "", k.allowed)))
            rows.append(
                f"| `{section}` | `{k.name}` | {_cell(TYPE_NAMES[k.kind])} | {k.unit} | `{_default_text(k, 'help')}` | "
                f"{_cell(allowed)} | {_cell(help_text(k))} |"
            )
    return "\n".join(rows)


KEYS_BEGIN = "<!-- keys: generated from the key declarations (ti_golf.scene.schema); `make docs-keys` rewrites it -->"
KEYS_END = "<!-- keys: end -->"
"""The lines around the key reference in a docs page (docs/scenes.md)."""


def with_keys(page: str) -> str:
    """The Markdown ``page`` with the key reference between :data:`KEYS_BEGIN` and
    :data:`KEYS_END` made anew (:func:`keys_markdown`): the page as it should be in the repository,
    where it is read too, and on the site."""
    start = page.index(KEYS_BEGIN) + len(KEYS_BEGIN)
    end = page.index(KEYS_END, start)
    return f"{page[:start]}\n\n{keys_markdown()}\n\n{page[end:]}"


def describe_keys() -> str:
    """Every scene key by its dotted name with unit, default, allowed values and meaning, as a
    Markdown table (``ti-golf keys``)."""
    rows = ["| key | unit | default | allowed | meaning |", "|---|---|---|---|---|"]
    for _, prefix, keys in _tables():
        for k in keys.values():
            rows.append(
                f"| `{prefix}{k.name}` | {k.unit} | `{_default_text(k)}` | {_cell(k.allowed or k.kind)} | "
                f"{_cell(help_text(k))} |"
            )
    return "\n".join(rows)


def _default_text(k: Key, see: str = "meaning") -> str:
    """A key's default as a scene file writes it; ``(see <column>)`` when the default is not a value."""
    d = k.default
    if k.kind == "text" or d == "":
        return '""'
    if isinstance(d, tuple):
        return "[" + ", ".join(f"{c:g}" for c in d) + "]"
    if isinstance(d, bool):
        return str(d).lower()
    if d is None:
        return f"(see {see})"
    return str(d)


def _cell(text: str) -> str:
    """Escape '|' so a Markdown table cell stays one cell."""
    return text.replace("|", "\\|")
