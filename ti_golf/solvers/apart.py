"""Balls set apart: the few much faster or bigger than the rest, listed by every ball instead of
widening every cell for them (see :mod:`ti_golf.solvers.grid`)."""

import math

import numpy as np
import taichi as ti

from ti_golf.physics.types import (
    float_array,
    i64_array,
    int_array,
    kernel,
    of_ball,
    vec3,
    vec3_array,
)
from ti_golf.solvers.sort import FOLD, fold_threads

APART_MAX = 32
"""Most balls set *apart* (see :func:`apart_balls`: much faster or bigger than the rest), which
own none of their pairs with the others (see :func:`.grid.owns`) and whose pairs are listed ball by
ball; with more, the cells are sized for the fastest pair and the largest ball instead
(:func:`.grid.cell_size`): a thousand balls hit at once are spread out, and big cells cost them
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
def apart_balls(
    v: vec3_array,
    radius: float_array,
    v_cut: float,
    r_cut: float,
    apart_ids: int_array,
    speeds: i64_array,
    folded: ti.template(),
) -> vec3:
    """(the greatest speed [m/s], the greatest speed of the balls not set apart, how many are set
    apart): the balls faster than ``v_cut`` or bigger than ``r_cut`` (see
    :func:`is_apart`). The indices of the first ``apart_ids.shape[0] − 1`` of them go to
    ``apart_ids`` in no particular order, their count to its last entry (integer atomics). The
    squared speeds' maxima are float atomics on the kernel's own variables (the same on every
    thread order), or with ``folded`` (``sort.fold_in_array``) meet in ``speeds`` (2,) as in
    ``grid.cell_bounds``: each thread folds ``sort.FOLD`` balls, then takes an integer atomic
    maximum of the f64 value's bits, which order as the non-negative values do (exact; a NaN is
    left out)."""
    last = apart_ids.shape[0] - 1
    apart_ids[last] = 0
    s2, rest2 = 0.0, 0.0
    if ti.static(not folded):
        for i in range(v.shape[0]):
            q = v[i].norm_sqr()
            ti.atomic_max(s2, q)
            if not set_apart(q, v_cut, radius, i, r_cut, apart_ids):
                ti.atomic_max(rest2, q)
    else:
        speeds[0], speeds[1] = 0, 0
        threads = fold_threads(v.shape[0])
        for t in range(threads):
            top, rest = ti.i64(0), ti.i64(0)  # (the bits of the squared speeds, folded as integers)
            for f in range(FOLD):
                i = t + f * threads
                if i < v.shape[0]:
                    q = v[i].norm_sqr()
                    bits = ti.bit_cast(ti.cast(q, ti.f64), ti.i64)
                    if q == q:  # (not NaN)
                        top = ti.max(top, bits)
                    apart = set_apart(q, v_cut, radius, i, r_cut, apart_ids)
                    if not apart and q == q:
                        rest = ti.max(rest, bits)
            ti.atomic_max(speeds[0], top)
            ti.atomic_max(speeds[1], rest)
        s2, rest2 = ti.cast(ti.bit_cast(speeds[0], ti.f64), float), ti.cast(ti.bit_cast(speeds[1], ti.f64), float)
    return ti.Vector([ti.sqrt(s2), ti.sqrt(rest2), ti.cast(apart_ids[last], float)])


@ti.func
def set_apart(q, v_cut, radius: ti.template(), i, r_cut, apart_ids: ti.template()):
    """Whether ball i, of squared speed ``q`` [m²/s²], is set apart (as :func:`is_apart` tests it);
    if so, its index goes to ``apart_ids`` (see :func:`apart_balls`)."""
    apart = q > v_cut * v_cut or of_ball(radius, i) > r_cut
    if apart:
        last = apart_ids.shape[0] - 1
        k = ti.atomic_add(apart_ids[last], 1)
        if k < last:
            apart_ids[k] = i
    return apart


@ti.func
def is_apart(v: ti.template(), radius: ti.template(), i, v_cut, r_cut, n_apart):
    """Whether ball i is one of the ``n_apart`` balls set apart (faster than ``v_cut`` or bigger
    than ``r_cut``, see :func:`apart_balls`); its velocity and radius are read only when there
    are any."""
    apart = False
    if n_apart > 0:
        apart = v[i].norm_sqr() > v_cut * v_cut or of_ball(radius, i) > r_cut
    return apart
