"""MkDocs hook: the pages' generated parts, made from the package when the site is built.

* the scene key reference of docs/scenes.md, between its ``<!-- keys: ... -->`` lines, from the
  key declarations (:func:`ti_golf.scene.reference.with_keys`). The page in the repository holds
  it too, to be read there: ``python docs/_hooks/generate.py`` (``make docs-keys``) rewrites it,
  and a test fails when it is stale;
* ``<!-- changelog -->``: the top-level ``CHANGELOG.md``.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from ti_golf.scene.reference import KEYS_BEGIN, with_keys

ROOT = Path(__file__).resolve().parents[2]


def on_page_markdown(markdown: str, **kwargs: Any) -> str:
    """Replace the markers of generated content in a page's Markdown."""
    if KEYS_BEGIN in markdown:
        markdown = with_keys(markdown)
    if "<!-- changelog -->" in markdown:
        changelog = (ROOT / "CHANGELOG.md").read_text(encoding="utf-8")
        markdown = markdown.replace("<!-- changelog -->", changelog.split("\n", 1)[1])  # without its title
    return markdown


if __name__ == "__main__":  # make docs-keys: the key reference of docs/scenes.md made anew
    page = ROOT / "docs" / "scenes.md"
    page.write_text(with_keys(page.read_text(encoding="utf-8")), encoding="utf-8")
