"""A faster host side of a kernel call: the same compiled kernel, its arguments set with less Python.

A call of a Taichi 1.7 kernel from Python costs the host far more than the launch itself: Taichi
works out the call's template key by walking every argument, every member of every argument
pack included, checking each array's type against its annotation (``extract_arg``,
``check_matched``), then walks them all again to set them (``recursive_set_args``). The collision
solver's kernels take argument packs of some thirty arrays, so a call cost the host about 145 µs
on the CI machine class, and a step of the contacts layout makes some sixty calls.

:class:`FastCall` keeps, for each kernel, what does not change from call to call:

* the **template key** of an argument pack: Taichi's, which checks every member against its
  annotation, is worked out again only when the pack or one of its members is another object
  than at an earlier call (the solver reuses its packs, :class:`ti_golf.physics.packs.Packs`);
  the other arguments' keys are worked out as Taichi does;
* the **order in which the arguments are set**: each argument's kind (an array, a pack, a scalar,
  a struct) follows from the kernel's annotations, so each call only hands the values over.

A call whose key Taichi has not compiled yet, or with an argument of another kind, goes through
Taichi's own call, which compiles, checks and raises as usual; so does every call in Taichi's
debug mode, with autodiff, or with ``TI_GOLF_PLAIN_LAUNCH=1`` (to compare). The kernels, their
arguments and their results are the same either way; a pack's members are checked by Taichi when
they are set (``ArgPack.__setitem__``) and at the first call.
"""

from __future__ import annotations

import inspect
from collections.abc import Callable
from typing import Any

import numpy as np

from ti_golf.errors import env_switch

PLAIN_ENV = "TI_GOLF_PLAIN_LAUNCH"
"""Set to 1 to call every kernel through Taichi's own call (see the module's docstring)."""

_VERSIONS = ((1, 7),)
"""The Taichi (major, minor) versions whose kernel call :class:`FastCall` follows."""

_TEMPLATE, _ARRAY, _PACK, _FLOAT, _INT, _UINT, _STRUCT, _MATRIX = range(8)
"""The kinds of a kernel's parameters that a fast call sets (any other goes through Taichi's call)."""


MADE: list[FastCall] = []
"""Every :class:`FastCall` of the process (one a kernel), for the tests and benchmarks."""

_SEEN_MAX = 64
"""Identities of packs and their members kept a parameter (see :meth:`FastCall._pack_key`)."""

_ANY_ELEMENT = -1
"""A pack member's element dimensions when its annotation leaves the element type open."""

_MISSING = object()
"""A parameter without a default that a call did not pass."""


def enabled() -> bool:
    """Whether kernels are called through :class:`FastCall` (a known Taichi version, not turned off)."""
    if env_switch(PLAIN_ENV):
        return False
    try:
        import taichi as ti
    except ImportError:  # pragma: no cover (taichi is a dependency)
        return False
    return tuple(ti.__version__[:2]) in _VERSIONS


class FastCall:
    """Calls of one kernel (``wrapped``: what ``ti.kernel`` returned) with positional arguments,
    through the plan of its parameters (see the module's docstring); any other call goes to
    ``wrapped``."""

    def __init__(self, wrapped: Callable[..., Any]) -> None:
        from taichi.lang import impl, kernel_impl
        from taichi.lang.exception import handle_exception_from_cpp

        self._wrapped = wrapped
        self._kernel = wrapped._primal  # type: ignore[attr-defined]
        self._impl = impl
        self._extract_arg = kernel_impl.TaichiCallableTemplateMapper.extract_arg
        self._handle = handle_exception_from_cpp
        self._plan = [self._kind(a.annotation) for a in self._kernel.arguments]
        self._names = [a.name for a in self._kernel.arguments]
        self._index = {name: i for i, name in enumerate(self._names)}
        empty = inspect.Parameter.empty
        self._defaults = [_MISSING if a.default is empty else a.default for a in self._kernel.arguments]
        self._packs: dict[int, list[tuple[str, int]]] = {}  # parameter -> its array members
        self._seen: dict[int, dict[tuple[int, ...], Any]] = {}  # parameter -> template keys by identities
        for i, kind in enumerate(self._plan):
            if kind == _PACK:
                members = self._pack_arrays(self._kernel.arguments[i].annotation)
                if members is None:
                    self._plan[i] = None
                else:
                    self._packs[i], self._seen[i] = members, {}
        self._usable = None not in self._plan and self._kernel.autodiff_mode == kernel_impl.AutodiffMode.NONE
        self._returns = self._kernel.return_type
        self.fast_calls = 0
        """Calls made here."""
        self.taichi_calls = 0
        """Calls handed to Taichi's own call."""
        MADE.append(self)

    @staticmethod
    def _kind(annotation: Any) -> int | None:
        from taichi.lang import kernel_impl
        from taichi.lang.matrix import MatrixType
        from taichi.lang.struct import StructType
        from taichi.types import ndarray_type, primitive_types

        if isinstance(annotation, kernel_impl.template):
            return _TEMPLATE
        if isinstance(annotation, kernel_impl.ArgPackType):
            return _PACK
        if isinstance(annotation, ndarray_type.NdarrayType):
            return _ARRAY if annotation.ndim is not None else None  # (its key Taichi's: the type any)
        if id(annotation) in primitive_types.real_type_ids:
            return _FLOAT
        if id(annotation) in primitive_types.integer_type_ids:
            return _INT if kernel_impl.is_signed(kernel_impl.cook_dtype(annotation)) else _UINT
        if isinstance(annotation, StructType):
            return _STRUCT
        if isinstance(annotation, MatrixType) and annotation.ndim == 1:
            if annotation.dtype in primitive_types.real_types:
                return _MATRIX
            if annotation.dtype in primitive_types.integer_types:
                return _MATRIX
        return None

    @staticmethod
    def _pack_arrays(annotation: Any) -> list[tuple[str, int]] | None:
        """The names of a pack's members, all arrays of a fixed dimension, in order, each with its
        element's dimensions (0 for scalars, 1 for vectors; ``_ANY_ELEMENT`` for an array whose
        element type the annotation leaves open, such as the sweep's table, f32 or the float type
        by solver); ``None`` when a member is anything else (then Taichi's call takes the kernel)."""
        from taichi.lang.matrix import MatrixType
        from taichi.types import ndarray_type

        members = []
        for name, member in annotation.members.items():
            if not isinstance(member, ndarray_type.NdarrayType) or member.ndim is None:
                return None
            if member.layout != ndarray_type.Layout.AOS:
                return None
            if member.dtype is None:
                members.append((name, _ANY_ELEMENT))
            else:
                members.append((name, member.dtype.ndim if isinstance(member.dtype, MatrixType) else 0))
        return members

    def __call__(self, *args: Any, **kwargs: Any) -> Any:
        """Call the kernel: here when its arguments allow, else through Taichi's own call."""
        ctx = self._launch_context(args, kwargs)
        if ctx is None:
            self.taichi_calls += 1
            return self._wrapped(*args, **kwargs)
        ctx, t_kernel = ctx
        runtime = self._impl.get_runtime()
        prog = runtime.prog
        self.fast_calls += 1
        try:
            prog.launch_kernel(prog.compile_kernel(prog.config(), prog.get_device_caps(), t_kernel), ctx)
        except Exception as e:
            raise self._handle(e) from None
        if self._returns is None:
            if self._kernel.has_print:
                runtime.sync()
            return None
        runtime.sync()
        values = [self._kernel.construct_kernel_ret(ctx, t, (i,)) for i, t in enumerate(self._returns)]
        return values[0] if len(values) == 1 else values

    def _launch_context(self, args: tuple[Any, ...], kwargs: dict[str, Any]) -> tuple[Any, Any] | None:
        """(a launch context with the call's arguments set, the compiled kernel), or ``None`` when
        Taichi's own call is to take this one (see the module's docstring)."""
        if kwargs:
            placed = self._positional(args, kwargs)
            if placed is None:
                return None
            args = placed
        if not self._usable or len(args) != len(self._plan):
            return None
        runtime = self._impl.get_runtime()
        if runtime.fwd_mode_manager or runtime.target_tape or self._impl.current_cfg().debug:
            return None
        t_kernel = self._compiled(args)
        if t_kernel is None:
            return None
        ctx = t_kernel.make_launch_context()
        return (ctx, t_kernel) if self._set(ctx, args) else None

    def _positional(self, args: tuple[Any, ...], kwargs: dict[str, Any]) -> tuple[Any, ...] | None:
        """The call's arguments in the parameters' order (those passed by name put in place, the
        defaults of those not passed), or ``None`` when that is not all of them."""
        if len(args) > len(self._names):
            return None
        values = list(args) + [self._defaults[i] for i in range(len(args), len(self._names))]
        for name, value in kwargs.items():
            i = self._index.get(name)
            if i is None or i < len(args):
                return None
            values[i] = value
        return None if any(v is _MISSING for v in values) else tuple(values)

    def _compiled(self, args: tuple[Any, ...]) -> Any:
        """The compiled kernel of this call's template key, or ``None`` if Taichi has not made it
        (then Taichi's own call makes it)."""
        key = []
        for i, (kind, arg) in enumerate(zip(self._plan, args, strict=True)):
            if kind == _PACK:
                pack_key = self._pack_key(i, arg)
                if pack_key is None:
                    return None
                key.append(pack_key)
            else:
                key.append(self._extract_arg(arg, self._kernel.arguments[i].annotation, self._names[i]))
        instance = self._kernel.mapper.mapping.get(tuple(key))
        if instance is None:
            return None
        return self._kernel.compiled_kernels.get((self._kernel.func, instance, self._kernel.autodiff_mode))

    def _pack_key(self, i: int, pack: Any) -> Any:
        """The template key of the pack ``pack`` passed as parameter ``i``: Taichi's, which checks
        each member against its annotation, worked out again only when the pack or one of its
        members is another object than at an earlier call; ``None`` if ``pack`` is not a pack."""
        entries = getattr(pack, "_ArgPack__entries", None)
        if entries is None:
            return None
        seen = self._seen[i]
        ids = (id(pack), *map(id, entries.values()))
        key = seen.get(ids)
        if key is None:
            key = self._extract_arg(pack, self._kernel.arguments[i].annotation, self._names[i])
            if len(seen) >= _SEEN_MAX:
                seen.clear()
            seen[ids] = key
        return key

    @staticmethod
    def _pack_members(pack: Any, members: list[tuple[str, int]], later: list[Any]) -> bool:
        """Append the arrays of ``pack`` (``members``: names and element dimensions) to ``later``:
        a Taichi array's handle, or a NumPy array's (address, bytes, shape); False if a member is
        neither (or has a gradient, or is not contiguous)."""
        for name, element_dims in members:
            member = pack[name]
            if isinstance(member, np.ndarray):
                if not member.flags.c_contiguous or element_dims == _ANY_ELEMENT:  # (NumPy's: Taichi's call)
                    return False
                later.append((int(member.ctypes.data), member.nbytes, member.shape[: member.ndim - element_dims]))
            elif getattr(member, "grad", None) is not None or not hasattr(member, "arr"):
                return False
            else:
                later.append(member.arr)
        return True

    @staticmethod
    def _set_vector(ctx: Any, at: tuple[int], annotation: Any, value: Any) -> bool:
        """Set a vector argument as Taichi does (each element made a float or an int of the
        annotation's type); False if ``value`` is not a vector of numbers of its length."""
        from taichi.types import primitive_types

        real = annotation.dtype in primitive_types.real_types
        kinds = (int, float, np.integer, np.floating) if real else (int, np.integer)
        try:
            elements = [value[k] for k in range(annotation.n)]
        except (TypeError, IndexError, KeyError):
            return False
        if len(value) != annotation.n or not all(isinstance(e, kinds) for e in elements):
            return False
        cast = float if real else int
        annotation.set_kernel_struct_args(annotation(*[cast(e) for e in elements]), ctx, at)
        return True

    def _set(self, ctx: Any, args: tuple[Any, ...]) -> bool:
        """Set the call's arguments in the launch context ``ctx`` as Taichi does: the arguments in
        order (templates left out), then the packs' arrays after them. False if an argument is not
        of its parameter's kind (then Taichi's own call reports it)."""
        later: list[Any] = []
        index = 0
        for i, (kind, arg) in enumerate(zip(self._plan, args, strict=True)):
            if kind == _TEMPLATE:
                continue
            at = (index,)
            index += 1
            if kind == _ARRAY:
                if getattr(arg, "grad", None) is not None or not hasattr(arg, "arr"):
                    return False
                ctx.set_arg_ndarray(at, arg.arr)
            elif kind == _PACK:
                if not self._pack_members(arg, self._packs[i], later):
                    return False
                ctx.set_arg_argpack(at, arg._ArgPack__argpack)
            elif kind == _FLOAT:
                if not isinstance(arg, (int, float, np.integer, np.floating)):
                    return False
                ctx.set_arg_float(at, float(arg))
            elif kind in (_INT, _UINT):
                if not isinstance(arg, (int, np.integer)):
                    return False
                (ctx.set_arg_int if kind == _INT else ctx.set_arg_uint)(at, int(arg))
            elif kind == _MATRIX:
                if not self._set_vector(ctx, at, self._kernel.arguments[i].annotation, arg):
                    return False
            else:  # a struct
                annotation = self._kernel.arguments[i].annotation
                if not isinstance(arg, annotation):
                    return False
                annotation.set_kernel_struct_args(arg, ctx, at)
        for j, arr in enumerate(later):
            if isinstance(arr, tuple):
                ctx.set_arg_external_array_with_shape((index + j,), arr[0], arr[1], arr[2], 0)
            else:
                ctx.set_arg_ndarray((index + j,), arr)
        return True
