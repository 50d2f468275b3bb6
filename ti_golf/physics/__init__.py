"""Taichi physics: types, per-ball force laws, integrators, contacts and the kernels that use them.

Importing this package initialises Taichi (through :func:`ti_golf.runtime.ensure_init`, the only
caller of ``ti.init``) because Taichi fixes the meaning of ``float`` in a type when the type is
created: types made before ``ti.init(default_fp=ti.f64)`` would silently be f32. The public API
(:mod:`ti_golf.sim.simulation`, :mod:`ti_golf.sweep`) imports it lazily, after the CLI has chosen the backend.
"""

from ti_golf.runtime import ensure_init as _ensure_init

_ensure_init()
