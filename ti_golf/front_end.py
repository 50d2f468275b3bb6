"""A faster Taichi front end: kernels of the same arithmetic, with less repeated work per
``ti.func`` call site.

Taichi's front end turns every kernel's Python source into its IR in every new process, even when
the compiled kernel then comes from the offline cache, and it inlines a ``ti.func`` by
transforming its source again at every call site. Much of that work repeats:

* **source positions**: for every AST node Taichi formats a message of the file, the line and a
  ``^^^`` marker under the node, wrapped at 80 columns (``ASTTransformerContext.get_pos_info``),
  and the IR keeps it as the node's debug information. Here the IR keeps the message's first line
  (file, line and function), and the whole message is made only when the front end reports an
  error in a kernel's source. A run-time error of Taichi's debug mode then names the line
  without quoting it; the IR differs from Taichi's own in that text, so the cache keys differ too.
* **source lookup**: Taichi reads every function's source with :func:`inspect.getsourcelines`
  (which tokenises the file's lines) and expands the tabs of each line with :func:`textwrap.fill`
  at every call site. Here each function's source is read, and each line expanded, once.
* **vector reductions**: ``v.dot(u)``, ``v.norm()``, ``v.norm_sqr()``, ``v.sum()`` and
  ``v.cross(u)`` are Taichi ``ti.func`` bodies nested up to three deep, transformed at each of
  some 260 call sites of the collision step; here they are built by Python as the same sums and
  products in the same order: the kernels' arithmetic, and so every run, is the same bit for bit;
  their IR is simpler, so the cache holds them under other keys than Taichi's own front end's.
* **the method test**: ``ti.func`` and ``ti.kernel`` ask whether they decorate a method by
  reading their caller's source line through :func:`inspect.getframeinfo`, which looks the frame's
  module up among every loaded module, at each of the package's 300 decorators; here the line is
  read from :mod:`linecache` (the same line). This part is installed when
  :mod:`ti_golf.physics.types` is imported, before the kernel modules' decorators run; for
  Taichi's own 120 decorators, which run while Taichi is imported, ``import ti_golf`` has
  :func:`inspect.getframeinfo` read the line so during that import (:func:`quicken_taichi_import`).

* **small functions**: a ``ti.func`` call, however small the function, costs Taichi a parse of its
  source, a scope and a copy of every argument (a whole matrix for a row of it); the package's
  smallest, most called functions of one expression (a per-ball entry, a struct member of the
  scalar array, a row of a lane matrix) are :func:`expanded` instead: Python runs their body at
  each call site on Taichi's expressions, as for the vector reductions.

Together they take about two thirds of the front end's time off (``ti-golf bench startup --kernels
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

from ti_golf.errors import env_switch
from ti_golf.signals import ctrl_c_held

PLAIN_ENV = "TI_GOLF_PLAIN_FRONT_END"
"""Set to 1 to run Taichi's front end as it comes (whole source positions, no memoised lookups)."""

_VERSIONS = ((1, 7),)
"""The Taichi (major, minor) versions whose front end :func:`install` knows."""

_installed = False


def install() -> bool:
    """Memoise Taichi's source positions and source lookups (see the module's docstring); once
    per process. Returns whether the front end is now the faster one."""
    global _installed
    if _installed:
        return True
    if env_switch(PLAIN_ENV):
        return False
    try:
        import taichi as ti
        from taichi.lang import impl, kernel_impl, matrix_ops
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
        *((matrix_ops, name) for name in ("sum", "dot", "norm_sqr", "norm", "cross")),
        (impl, "subscript"),
    )
    if not all(hasattr(m, a) for m, a in needed):
        return False
    context.get_pos_info = _position_lines(context.get_pos_info)
    _inline_reductions()
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


def quicken_taichi_import() -> None:
    """Have the first ``import taichi`` of the process (by whichever module) run with an
    :func:`inspect.getframeinfo` that reads the frame's one line from :mod:`linecache`, the line
    it would return, rather than looking the frame's module up among every module loaded, at each
    of Taichi's own decorators (about 0.03 s of every command). Nothing once Taichi is imported,
    or with ``TI_GOLF_PLAIN_FRONT_END=1``."""
    plain = os.environ.get(PLAIN_ENV, "") == "1"  # (not env_switch: a mistyped value is the CLI's to report)
    if "taichi" not in sys.modules and not plain:
        sys.meta_path.insert(0, _TaichiImport())


class _TaichiImport:
    """A finder of no module of its own (:data:`sys.meta_path`): the first import of ``taichi``
    takes the spec the other finders give, its loader running with the quicker frame lines."""

    def find_spec(self, name: str, path: Any = None, target: Any = None) -> Any:
        if name != "taichi":
            return None
        sys.meta_path.remove(self)
        import importlib.util

        spec = importlib.util.find_spec(name)
        if spec is not None and spec.loader is not None and hasattr(spec.loader, "exec_module"):
            run = spec.loader.exec_module

            def exec_module(module: types.ModuleType) -> None:
                import inspect

                plain = inspect.getframeinfo
                inspect.getframeinfo = functools.partial(_frame_line, plain=plain)
                try:
                    with ctrl_c_held():  # (an interrupted extension fails for good: Taichi's install hint)
                        run(module)
                finally:
                    inspect.getframeinfo = plain

            spec.loader.exec_module = exec_module  # type: ignore[method-assign] # (this spec's own loader)
        return spec


def _frame_line(frame: types.FrameType, context: int = 1, *, plain: Callable[..., Any]) -> Any:
    """``plain`` (:func:`inspect.getframeinfo`) of ``frame``; for ``context`` 1, with its line read
    from :mod:`linecache`."""
    import inspect

    if context != 1 or not isinstance(frame, types.FrameType):
        return plain(frame, context)
    filename, line = frame.f_code.co_filename, frame.f_lineno
    return inspect.Traceback(filename, line, frame.f_code.co_name, [linecache.getline(filename, line)], 0)


def knows_taichi() -> bool:
    """Whether the Taichi at hand is one whose internals this module was written against, and the
    faster front end is wanted (not ``TI_GOLF_PLAIN_FRONT_END=1``)."""
    import taichi as ti

    return tuple(ti.__version__[:2]) in _VERSIONS and not env_switch(PLAIN_ENV)


def expanded(fn: Callable[..., Any]) -> Any:
    """``ti.func`` for a small function of one expression, built by Python at each call site
    instead: Taichi calls it as it calls its own functions inside a kernel, with the caller's
    expressions, so its front end neither parses the function's source nor copies its arguments.
    The body must read arrays and matrices through :func:`element` and make vectors with
    :func:`float_vector` (what Taichi's front end calls for ``a[i]`` and ``ti.Vector``), take
    compile-time values as plain Python values, and use each argument once (an argument is an
    expression, not a copy, so each use evaluates it). A plain ``ti.func`` where the Taichi is
    not one this module knows, or with ``TI_GOLF_PLAIN_FRONT_END=1``."""
    if not knows_taichi():
        import taichi as ti

        return ti.func(fn)
    return _called_as_taichis_own(fn)


def _called_as_taichis_own(fn: Callable[..., Any]) -> Any:
    """``fn`` marked as Taichi marks its functions, so that its front end calls it inside a kernel
    without the warning it gives a Python function (which it could not tell from a mistake)."""

    @functools.wraps(fn)
    def at_call_site(*args: Any, **kwargs: Any) -> Any:
        return fn(*args, **kwargs)

    at_call_site._is_taichi_function = True  # type: ignore[attr-defined]
    at_call_site.func = types.SimpleNamespace(has_print=False)  # type: ignore[attr-defined] # (read after the call)
    return at_call_site


def _element(array: Any, *indices: Any) -> Any:
    """``array[indices]`` inside a kernel (an ndarray, or a vector or matrix): what Taichi's front
    end builds for the subscript, for the bodies of :func:`expanded` functions."""
    from taichi.lang import impl

    return impl.subscript(None, array, *indices)


def _float_vector(*values: Any) -> Any:
    """The vector of ``values`` in the chosen float type inside a kernel: what Taichi's front end
    builds for ``ti.Vector([...], dt=float)``, for the bodies of :func:`expanded` functions."""
    from taichi.lang import matrix

    return matrix.make_matrix(list(values), dt=float)


element = _called_as_taichis_own(_element)
float_vector = _called_as_taichis_own(_float_vector)


def _inline_reductions() -> None:
    """Taichi's ``sum``, ``dot``, ``norm_sqr`` and ``norm`` of a vector, built inside kernels as
    the same sums in the same order (x₀ + x₁ + x₂, left to right), and the cross product of two
    3-vectors as the same differences of products, by Python at the call site
    rather than as ``ti.func`` bodies that the front end transforms at every call (``dot`` calls
    ``sum``, which calls ``_reduce``: three transforms a call, some 260 in the collision step).
    Outside kernels, and for anything but a vector, Taichi's own run."""
    from taichi.lang import impl, matrix_ops
    from taichi.lang import ops as ops_mod
    from taichi.lang.matrix import Vector

    own = {name: getattr(matrix_ops, name) for name in ("sum", "dot", "norm_sqr", "norm", "cross")}

    def vector_length(*values: Any) -> int | None:
        shapes = {tuple(v.get_shape()) if hasattr(v, "get_shape") else None for v in values}
        shape = shapes.pop() if len(shapes) == 1 else None
        return shape[0] if shape is not None and len(shape) == 1 and impl.inside_kernel() else None

    def total(vector: Any, n: int) -> Any:
        result = impl.subscript(None, vector, 0)
        for i in range(1, n):
            result = ops_mod.add(result, impl.subscript(None, vector, i))
        return result

    def vector_sum(mat: Any) -> Any:
        n = vector_length(mat)
        return own["sum"](mat) if n is None else total(mat, n)

    def dot(vec_x: Any, vec_y: Any) -> Any:
        n = vector_length(vec_x, vec_y)
        return own["dot"](vec_x, vec_y) if n is None else total(ops_mod.mul(vec_x, vec_y), n)

    def norm_sqr(mat: Any) -> Any:
        n = vector_length(mat)
        return own["norm_sqr"](mat) if n is None else total(ops_mod.mul(mat, mat), n)

    def norm(mat: Any, eps: Any = 0.0) -> Any:
        n = vector_length(mat)
        return own["norm"](mat, eps) if n is None else ops_mod.sqrt(total(ops_mod.mul(mat, mat), n) + eps)

    def cross(vec_x: Any, vec_y: Any) -> Any:
        if vector_length(vec_x, vec_y) != 3:
            return own["cross"](vec_x, vec_y)
        x, y = ([impl.subscript(None, v, i) for i in range(3)] for v in (vec_x, vec_y))
        return Vector(
            [
                ops_mod.sub(ops_mod.mul(x[1], y[2]), ops_mod.mul(x[2], y[1])),
                ops_mod.sub(ops_mod.mul(x[2], y[0]), ops_mod.mul(x[0], y[2])),
                ops_mod.sub(ops_mod.mul(x[0], y[1]), ops_mod.mul(x[1], y[0])),
            ]
        )

    matrix_ops.sum, matrix_ops.dot, matrix_ops.norm_sqr, matrix_ops.norm = vector_sum, dot, norm_sqr, norm
    matrix_ops.cross = cross


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


def _position_lines(get_pos_info: Callable[[Any, ast.AST], str]) -> Callable[[Any, ast.AST], str]:
    """``get_pos_info`` that, while Taichi builds a kernel, gives only the first line of its
    message (``File "...", line N, in FUNC:``), which the IR keeps as the node's debug information;
    and, while an exception is being handled (the front end reporting an error in a kernel's
    source), Taichi's whole message, with the source line and ``^^^`` under the node."""

    def pos_info(ctx: Any, node: Any) -> str:  # (node: an ast.stmt or ast.expr)
        if sys.exc_info()[1] is not None:
            return get_pos_info(ctx, node)
        return f'File "{ctx.file}", line {node.lineno + ctx.lineno_offset}, in {ctx.func.func.__name__}:\n'

    pos_info.__wrapped__ = get_pos_info  # type: ignore[attr-defined]
    return pos_info
