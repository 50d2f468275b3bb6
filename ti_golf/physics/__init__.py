"""Taichi physics: the balls on the device (the scene's :mod:`.model`, the balls' :mod:`.state`,
the kernels' argument :mod:`.packs`), types, per-ball force laws, integrators, the contact laws
and the kernels that move balls that do not collide. The collisions are the contact solvers'
(:mod:`ti_golf.solvers`).

Importing it starts no Taichi runtime: the float-dependent types are made, and the kernels
compiled, on first use (see :mod:`ti_golf.physics.types`).
"""
