"""A faster Taichi front end: the same kernels, with less repeated work per ``ti.func`` call site.

Taichi's front end turns every kernel's Python source into its IR in every new process, even when
the compiled kernel then comes from the offline cache, and it inlines a ``ti.func`` by
transforming its source again at every call site. Two parts of that work repeat exactly:

* **source positions**: for every AST node Taichi formats a message of the file, the line and a
  ``^^^`` marker under the node (``ASTTransformerContext.get_pos_info``, for error messages and
  the IR's debug information), wrapping each line with :class:`textwrap.TextWrapper`. A
  ``ti.func`` inlined at twenty call sites formats the same messages twenty times. Here each
  message is made once per source position and reused: the same text, so the kernels' IR and
  Taichi's cache keys are unchanged.
* **source lookup**: Taichi reads every function's source with :func:`inspect.getsourcelines`
  (which tokenises the file's lines) and expands the tabs of each line with :func:`textwrap.fill`
  at every call site. Here each function's source is read, and each line expanded, once.

* **wrapped lines**: each message wraps the node's source line at 80 columns, so a line with
  twenty nodes is wrapped twenty times; here each text is wrapped once (the same lines).
* **the method test**: ``ti.func`` and ``ti.kernel`` ask whether they decorate a method by
  reading their caller's source line through :func:`inspect.getframeinfo`, which looks the frame's
  module up among every loaded module, at each of the package's 300 decorators; here the line is
  read from :mod:`linecache` (the same line). This part is installed when
  :mod:`ti_golf.physics.types` is imported, before the kernel modules' decorators run.

Together they take about half of the front end's time off (``ti-golf bench startup --kernels
SCENE`` shows each kernel's front end). They are installed by :func:`install` (called by
:func:`ti_golf.runtime.init`) only on the Taichi versions whose internals they were written
against, and not at all with ``TI_GOLF_PLAIN_FRONT_END=1`` (to compare).
"""

from __future__ import annotations

import ast
import functools
import linecache
import os
import sys
import textwrap
import types
from collections.abc import Callable
from typing import Any

PLAIN_ENV = "TI_GOLF_PLAIN_FRONT_END"
"""Set to 1 to run Taichi's front end as it comes (no memoised source positions or lookups)."""

_VERSIONS = ((1, 7),)
"""The Taichi (major, minor) versions whose front end :func:`install` knows."""

_installed = False


def install() -> bool:
    """Memoise Taichi's source positions and source lookups (see the module's docstring); once
    per process. Returns whether the front end is now the faster one."""
    global _installed
    if _installed:
        return True
    if os.environ.get(PLAIN_ENV, "") not in ("", "0"):
        return False
    try:
        import taichi as ti
        from taichi.lang import kernel_impl
        from taichi.lang.ast import ast_transformer_utils
    except ImportError:
        return False
    context = getattr(ast_transformer_utils, "ASTTransformerContext", None)
    if tuple(ti.__version__[:2]) not in _VERSIONS or context is None:
        return False
    needed = (
        (context, "get_pos_info"),
        (kernel_impl, "getsourcelines"),
        (kernel_impl, "textwrap"),
        (kernel_impl, "_inside_class"),
        (kernel_impl, "_KERNEL_CLASS_STACKFRAME_STMT_RES"),
        (ast_transformer_utils, "TextWrapper"),
    )
    if not all(hasattr(m, a) for m, a in needed):
        return False
    context.get_pos_info = _memoised_positions(context.get_pos_info)
    ast_transformer_utils.TextWrapper = _MemoisedWrapper
    inside_class = _statement_test(kernel_impl._KERNEL_CLASS_STACKFRAME_STMT_RES)
    inside_class.__wrapped__ = kernel_impl._inside_class  # type: ignore[attr-defined]
    kernel_impl._inside_class = inside_class
    kernel_impl.getsourcelines = functools.lru_cache(maxsize=None)(kernel_impl.getsourcelines)
    # the module's one use of textwrap.fill expands each source line's tabs, at every call site
    kernel_impl.textwrap = types.SimpleNamespace(
        fill=functools.lru_cache(maxsize=None)(textwrap.fill), dedent=textwrap.dedent
    )
    _installed = True
    return True


class _MemoisedWrapper(textwrap.TextWrapper):
    """Taichi's ``TextWrapper(width=80)`` of the source-position messages, each text wrapped once:
    a message wraps its source line again for every node on the line."""

    _wrapped: dict[tuple[int, str], list[str]] = {}

    def wrap(self, text: str) -> list[str]:
        """The lines of ``text`` wrapped, as :meth:`textwrap.TextWrapper.wrap` makes them."""
        key = (self.width, text)
        lines = self._wrapped.get(key)
        if lines is None:
            lines = self._wrapped[key] = super().wrap(text)
        return list(lines)


def _statement_test(patterns: list[Any]) -> Callable[[int], bool]:
    """Taichi's test of whether ``ti.kernel`` or ``ti.func`` decorates a method (its caller's
    caller's statement, ``level`` frames up, begins a class or ``@data_oriented``), reading that
    line from :mod:`linecache` rather than through :func:`inspect.getframeinfo`, which looks up
    the frame's module among every module loaded at each decorator (about 0.1 s a process)."""

    def inside_class(level_of_class_stackframe: int) -> bool:
        try:
            frame = sys._getframe(level_of_class_stackframe)
            line = linecache.getline(frame.f_code.co_filename, frame.f_lineno, frame.f_globals).strip()
        except (ValueError, AttributeError):
            return False
        return any(pattern.match(line) for pattern in patterns)

    return inside_class


def _memoised_positions(get_pos_info: Callable[[Any, ast.AST], str]) -> Callable[[Any, ast.AST], str]:
    """``get_pos_info`` that makes each message once per source position: its text depends only
    on the function's file, source and first line, and on the node's kind and span (and, for a
    block, the first line of its body)."""
    messages: dict[tuple[Any, ...], str] = {}

    def pos_info(ctx: Any, node: ast.AST) -> str:
        body = getattr(node, "body", None)
        first_of_body = body[0].lineno if isinstance(body, list) and body else None
        key = (
            ctx.file,
            ctx.func.func,
            ctx.lineno_offset,
            ctx.indent,
            type(node),
            getattr(node, "lineno", None),
            getattr(node, "end_lineno", None),
            getattr(node, "col_offset", None),
            getattr(node, "end_col_offset", None),
            first_of_body,
        )
        message = messages.get(key)
        if message is None:
            message = messages[key] = get_pos_info(ctx, node)
        return message

    pos_info.__wrapped__ = get_pos_info  # type: ignore[attr-defined]
    return pos_info
