"""Kernels in one thread: the project's kernels launched with every loop run in the calling
thread, for arrays so small that Taichi's thread pool costs more than the loops' work.

On a CPU backend Taichi hands each top-level loop of a kernel to its thread pool: the calling
thread wakes the workers and sleeps until the last one is done. On the CI class that costs about
50 µs a loop, whatever its length and however many threads there are (a loop of one iteration
as much as one of a thousand), against about 15 µs for the whole call of a kernel without a loop.
A build of the neighbour lists between the serial launches of a pile of a thousand balls runs
some forty such loops: most of its time (the performance page, "Design measurements").

Inside :func:`in_one_thread`, each kernel made by :func:`ti_golf.physics.types.kernel` launches
its *one-thread variant*: the same function compiled again with every loop serialised, as
``ti.loop_config(serialize=True)`` before each would make it (:func:`install` adds that one call
to Taichi's front end for ``for`` statements while a variant compiles). The project's kernels
give the same result on every order of a loop's iterations (they gather rather than scatter float
atomics, and sort what integer atomics put in thread order), so a variant's result is the
kernel's, bit for bit. To Taichi it is another kernel, compiled and cached apart. On a Taichi
version whose front end this module does not know, the variant is the kernel itself."""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Iterator
from typing import Any

_VERSIONS = ((1, 7),)
"""The Taichi (major, minor) versions whose front end :func:`install` knows."""

_active = False  # inside in_one_thread(True): kernels launch their one-thread variants
_serialising = False  # a variant is being called (and so, at its first call, compiled)
_installed: bool | None = None  # None: not tried yet


def active() -> bool:
    """Whether kernels now launch their one-thread variants (:func:`in_one_thread`)."""
    return _active


@contextlib.contextmanager
def in_one_thread(on: bool = True) -> Iterator[None]:
    """While inside, with ``on``, the project's kernels launch their one-thread variants (see the
    module's docstring); with ``on`` false, nothing changes."""
    global _active
    before = _active
    _active = before or bool(on)
    try:
        yield
    finally:
        _active = before


def variant(compiled: Callable[..., Any]) -> Callable[..., Any]:
    """The one-thread variant of a kernel: a call of ``compiled``, a second ``ti.kernel`` of the
    kernel's function, that serialises its loops while it compiles (at its first call with each
    set of template arguments). Without the front end's hook (:func:`install`), ``compiled`` as
    it is."""
    if not install():
        return compiled

    def call(*args: Any, **kwargs: Any) -> Any:
        global _serialising
        _serialising = True
        try:
            return compiled(*args, **kwargs)
        finally:
            _serialising = False

    return call


def install() -> bool:
    """Make Taichi's front end serialise every loop over a ``range`` or ``ti.ndrange`` of the
    kernels it transforms while a one-thread variant is called (a top-level loop then runs in the
    calling thread; a nested loop already does). A loop over an array's elements (``for i in a``)
    cannot be serialised: Taichi ignores the request with a warning, so the project's kernels loop
    over ``range(a.shape[0])`` instead. Once per process; returns whether the hook is in place."""
    global _installed
    if _installed is not None:
        return _installed
    _installed = False
    try:
        import taichi as ti
        from taichi.lang import impl
        from taichi.lang.ast import ast_transformer
    except ImportError:
        return False
    transformer = getattr(ast_transformer, "ASTTransformer", None)
    loops = ("build_range_for", "build_ndrange_for", "build_grouped_ndrange_for")
    if tuple(ti.__version__[:2]) not in _VERSIONS or not all(hasattr(transformer, b) for b in loops):
        return False

    def serialised(build: Callable[[Any, Any], Any]) -> Callable[[Any, Any], Any]:
        def build_loop(ctx: Any, node: Any) -> Any:
            if _serialising:
                impl.get_runtime().compiling_callable.ast_builder().strictly_serialize()
            return build(ctx, node)

        return staticmethod(build_loop)

    for name in loops:
        setattr(transformer, name, serialised(getattr(transformer, name)))
    _installed = True
    return True
