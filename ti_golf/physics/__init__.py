"""Taichi physics: types, per-ball force laws, integrators, contacts and the kernels that use them.

Importing it starts no Taichi runtime: the float-dependent types are made, and the kernels
compiled, on first use (see :mod:`ti_golf.physics.types`).
"""
