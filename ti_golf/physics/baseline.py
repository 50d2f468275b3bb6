"""Yardstick kernels for the benchmarks: what the memory system allows, measured in the same run."""

import taichi as ti

from .grid import int_table
from .types import vec3, vec3_array


@ti.kernel
def bare_gather(x: vec3_array, nbr: int_table, out: vec3_array):
    """out[i] = Σ_k (x[i] − x[nbr[i, k]]): a contact gather with no physics (memory traffic only)."""
    for i in range(x.shape[0]):
        acc = vec3(0.0)
        for k in range(nbr.shape[1]):
            acc += x[i] - x[nbr[i, k]]
        out[i] = acc
