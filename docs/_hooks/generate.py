"""MkDocs hook: the pages' generated parts, made from the package when the site is built.

* ``<!-- keys ... -->`` in a page: the scene key reference, from the key declarations
  (:func:`ti_golf.scene.reference.keys_markdown`);
* ``<!-- changelog -->``: the top-level ``CHANGELOG.md``.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

from ti_golf.scene.reference import keys_markdown

ROOT = Path(__file__).resolve().parents[2]


def on_page_markdown(markdown: str, **kwargs: Any) -> str:
    """Replace the markers of generated content in a page's Markdown."""
    markdown = re.sub(r"<!-- keys[^>]*-->", lambda _: keys_markdown(), markdown)
    if "<!-- changelog -->" in markdown:
        changelog = (ROOT / "CHANGELOG.md").read_text(encoding="utf-8")
        markdown = markdown.replace("<!-- changelog -->", changelog.split("\n", 1)[1])  # without its title
    return markdown
