"""The sweep's table of the pairs (``types.pair_table_type``): f32 with the Gauss–Seidel sweeps,
12 bytes a pair, and the float type with the Jacobi sweeps.

In it the Gauss–Seidel sweeps keep each pair's inverse distance, refined where it is read to
the float type's precision (``pairs.kept_normal``), and its gap to the last bit, across two
columns (``pairs.put_gap``); a rebuild keeps each pair's neighbour id as its 32 bits, any id an
i32 holds (``links.put_stashed``)."""

import numpy as np
import taichi as ti

from ti_golf.physics.types import (
    LAM,
    float_array,
    int_array,
    kernel,
    pair_columns,
    pair_table,
    pair_table_type,
    vec3_array,
)
from ti_golf.solvers.links import put_stashed
from ti_golf.solvers.pairs import kept_gap, kept_normal, pair_geometry, put_gap
from ti_golf.solvers.stash import stashed_id_bits


@kernel
def _stash_and_read(table: pair_table, ids: int_array, bits: int_array, out: int_array, with_friction: ti.template()):
    for p in range(ids.shape[0]):
        put_stashed(table, p, ti.cast(0.5 * p, ti.f32), ids[p], bits[p], with_friction)  # (λ is kept in f32)
    for p in range(ids.shape[0]):
        out[2 * p], out[2 * p + 1] = stashed_id_bits(table, p, with_friction)


def test_a_rebuild_keeps_any_ball_id_and_the_friction_bits_in_either_table():
    # the ids as 32 bits in an f32 table: past 2^24, where an f32 value no longer holds every
    # integer, up to the largest i32, and the list's end (−1); the friction bits beside them
    ids = np.array([0, 1, 2**24 + 1, 2**31 - 1, -1, 123_456_789], dtype=np.int32)
    bits = np.array([0, -1, 2**31 - 1, -(2**31), 0x0001_FFFF, 12345], dtype=np.int32)
    for gauss_seidel in (True, False):
        table = ti.ndarray(pair_table_type(gauss_seidel), (ids.size, pair_columns(gauss_seidel)))
        out = ti.ndarray(ti.i32, 2 * ids.size)
        i, b = ti.ndarray(ti.i32, ids.size), ti.ndarray(ti.i32, ids.size)
        i.from_numpy(ids)
        b.from_numpy(bits)
        _stash_and_read(table, i, b, out, gauss_seidel)
        got = out.to_numpy().reshape(-1, 2)
        np.testing.assert_array_equal(got[:, 0], ids)
        np.testing.assert_array_equal(got[:, 1], bits if gauss_seidel else 0)
        lam = table.to_numpy()[:, LAM]
        np.testing.assert_array_equal(lam, 0.5 * np.arange(ids.size))
        assert table.to_numpy().dtype == (np.float32 if gauss_seidel else np.float64)


@kernel
def _gaps(table: pair_table, gaps: float_array, out: float_array):
    for p in range(gaps.shape[0]):
        put_gap(table, p, gaps[p])
    for p in range(gaps.shape[0]):
        out[p] = kept_gap(table, p)


def test_the_gauss_seidel_table_keeps_every_bit_of_a_gap():
    # the sweeps close a pair's gap within the step from the gap the warm start kept: rounded to
    # f32, the balls of a settled pile woke one another for seconds (the 20,000-ball pour, 14 balls
    # still awake at t = 4 s, against none from t = 2.5 s); the table keeps the f64 gap's 64 bits
    # in two of its f32 columns, whatever they are as floats (NaN and subnormal halves included)
    rng = np.random.default_rng(3)
    special = [0.0, -0.0, 1e-300, -1e-300, 5e-324, 1e300, -0.01, 0.02134, np.nextafter(0.01, 1.0)]
    gaps = np.concatenate(
        [special, rng.normal(0.0, 1e-3, 2_000), rng.uniform(-1, 1, 2_000) * 10.0 ** rng.integers(-300, 300, 2_000)]
    )
    bits = rng.integers(-(2**63), 2**63 - 1, 2_000, dtype=np.int64)
    gaps = np.concatenate([gaps, bits.view(np.float64)[np.isfinite(bits.view(np.float64))]])
    table = ti.ndarray(pair_table_type(True), (gaps.size, pair_columns(True)))
    g, out = ti.ndarray(ti.f64, gaps.size), ti.ndarray(ti.f64, gaps.size)
    g.from_numpy(gaps)
    _gaps(table, g, out)
    np.testing.assert_array_equal(out.to_numpy().view(np.int64), gaps.view(np.int64))


@kernel
def _normals(x: vec3_array, kept: vec3_array, exact: vec3_array):
    for p in range(x.shape[0] // 2):
        a, b = 2 * p, 2 * p + 1
        inv, _ = pair_geometry(x, x, a, b)  # (the radii do not matter here)
        kept[p] = kept_normal(x[a], x[b], ti.cast(inv, ti.f32))
        exact[p] = (x[a] - x[b]) * (1.0 / (x[a] - x[b]).norm())


def test_the_kept_normal_is_the_f64_normal_to_a_few_ulps():
    # a Newton step from the f32 inverse distance (relative error up to 2^-24) leaves 3/2 of its
    # square, 2^-47, and the rounding of a few operations: a unit normal within 1e-14, not the
    # 6e-8 of the f32 value itself; over distances from touching golf balls to a metre, and in
    # a pile 100 m from the origin
    rng = np.random.default_rng(7)
    m = 20_000
    centre = rng.uniform(-100.0, 100.0, (m, 3))
    d = rng.normal(size=(m, 3))
    d *= (rng.uniform(0.02, 1.0, m) / np.linalg.norm(d, axis=1))[:, None]
    x_np = np.empty((2 * m, 3))
    x_np[0::2], x_np[1::2] = centre + d, centre
    x, kept, exact = (ti.Vector.ndarray(3, ti.f64, n) for n in (2 * m, m, m))
    x.from_numpy(x_np)
    _normals(x, kept, exact)
    k, e = kept.to_numpy(), exact.to_numpy()
    err = np.linalg.norm(k - e, axis=1)
    assert err.max() < 1e-14, err.max()
    f32_err = np.abs(
        np.linalg.norm(x_np[0::2] - x_np[1::2], axis=1) * (1.0 / np.linalg.norm(d, axis=1)).astype(np.float32) - 1
    )
    assert f32_err.max() > 1e-9  # (the f32 value alone is much further off: the refinement is what holds)
