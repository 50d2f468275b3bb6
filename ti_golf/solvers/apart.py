"""Balls set apart: the few much faster or bigger than the rest, listed by every ball instead of
widening every cell for them (see :mod:`ti_golf.solvers.grid`)."""

import math

import numpy as np
import taichi as ti

from ti_golf.physics.types import (
    float_array,
    int_array,
    kernel,
    of_ball,
    vec3,
    vec3_array,
)

APART_MAX = 32
"""Most balls set *apart* (see :func:`apart_balls`: much faster or bigger than the rest), which
own none of their pairs with the others (see :func:`owns`) and whose pairs are listed ball by
ball; with more, the cells are sized for the fastest pair and the largest ball instead
(:func:`cell_size`): a thousand balls hit at once are spread out, and big cells cost them
little. Their pairs are listed ball by ball on CPU backends only (``CollisionSolver.build``): a
ball listed apart tests every ball in one thread, and Taichi's Vulkan backend stops the loops of
a thread after 65,535 iterations in all, nested or not, without a word (measured with Taichi 1.7.4 and
lavapipe: the ball shot into the 70,001-ball pile of the GPU test lost 7 of its pairs); on a GPU,
many threads make wide cells cheap anyway."""


def size_cut(radius: np.ndarray) -> tuple[float, float]:
    """(r_cut, r_ref) [m] for balls of ``radius`` (n,) [m]: a ball bigger than r_cut, twice the
    radius of the (``APART_MAX`` + 1)-th biggest ball, is set apart (at most ``APART_MAX`` of
    them), and r_ref, the largest radius of the other balls, sizes the cells and the skin. So a
    boulder dropped into a pit of golf balls does not make every cell as wide as the boulder (a
    0.5 m ball on a pile of 131,072 2-cm balls made a rebuild of the lists take 20 s, against
    0.1 s). Without such outliers, r_cut is infinite and r_ref the largest radius."""
    r = np.sort(np.asarray(radius, dtype=float))[::-1]
    if len(r) <= APART_MAX:
        return math.inf, float(r[0])
    r_cut = 2.0 * float(r[APART_MAX])
    if r[0] <= r_cut:
        return math.inf, float(r[0])
    return r_cut, float(r[r <= r_cut][0])


def fast_speed(r_ref: float, skin: float, h: float) -> float:
    """The speed [m/s] above which a ball is *fast*: 2h·|v| exceeds the larger of the skin and the
    largest diameter ``2·r_ref`` [m] of the balls not set apart for their size (see
    :func:`size_cut`), so a pair with it could close by more than that within a step (``h`` [s]).
    Below it, cells are at most 2·r_ref + max(skin, 2·r_ref) wide."""
    return max(skin, 2.0 * r_ref) / (2.0 * h)


@kernel
def apart_balls(v: vec3_array, radius: float_array, v_cut: float, r_cut: float, apart_ids: int_array) -> vec3:
    """(the greatest speed [m/s], the greatest speed of the balls not set apart, how many are set
    apart): the balls faster than ``v_cut`` or bigger than ``r_cut`` (see
    :func:`is_apart`). The indices of the first ``apart_ids.shape[0] − 1`` of them go to
    ``apart_ids`` in no particular order, their count to its last entry (integer atomics; float
    atomic maxima, the same on every thread order)."""
    s2, rest2 = 0.0, 0.0
    last = apart_ids.shape[0] - 1
    apart_ids[last] = 0
    for i in range(v.shape[0]):
        q = v[i].norm_sqr()
        ti.atomic_max(s2, q)
        if q > v_cut * v_cut or of_ball(radius, i) > r_cut:  # as :func:`is_apart` tests it
            k = ti.atomic_add(apart_ids[last], 1)
            if k < last:
                apart_ids[k] = i
        else:
            ti.atomic_max(rest2, q)
    return ti.Vector([ti.sqrt(s2), ti.sqrt(rest2), ti.cast(apart_ids[last], float)])


@ti.func
def is_apart(v: ti.template(), radius: ti.template(), i, v_cut, r_cut, n_apart):
    """Whether ball i is one of the ``n_apart`` balls set apart (faster than ``v_cut`` or bigger
    than ``r_cut``, see :func:`apart_balls`); its velocity and radius are read only when there
    are any."""
    apart = False
    if n_apart > 0:
        apart = v[i].norm_sqr() > v_cut * v_cut or of_ball(radius, i) > r_cut
    return apart
