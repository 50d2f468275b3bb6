"""Kernels in one thread (ti_golf.one_thread): a kernel launched inside ``in_one_thread`` runs its
loops in order in the calling thread, and the lists a build makes that way are the lists the
thread pool makes, bit for bit."""

import numpy as np
import pytest
import taichi as ti
from conftest import ON_CPU

import ti_golf as tg
from ti_golf import one_thread
from ti_golf.bench.pit import pit_scene
from ti_golf.physics.types import kernel

pytestmark = [
    pytest.mark.skipif(not ON_CPU, reason="the thread pool is the CPU backend's"),
    pytest.mark.skipif(not one_thread.install(), reason="this Taichi's front end is not one_thread's"),
]


@kernel
def _arrival_order(order: ti.types.ndarray(dtype=ti.i32, ndim=1), count: ti.types.ndarray(dtype=ti.i32, ndim=1)):
    count[0] = 0
    for i in range(order.shape[0]):  # a top-level loop: the thread pool's, unless serialised
        x = ti.cast(i, ti.f64)
        for _ in range(2000):  # (work enough for every thread of the pool to take part)
            x = ti.sqrt(x * x + 1.0)
        if x > 0.0:
            order[ti.atomic_add(count[0], 1)] = i


def test_a_kernel_in_one_thread_takes_its_loop_in_order():
    n = 20_000
    order, count = ti.ndarray(ti.i32, n), ti.ndarray(ti.i32, 1)
    with one_thread.in_one_thread():
        _arrival_order(order, count)
        assert one_thread.active()
    assert not one_thread.active()
    np.testing.assert_array_equal(order.to_numpy(), np.arange(n))
    with one_thread.in_one_thread(False):  # (off: nothing changes)
        assert not one_thread.active()
    _arrival_order(order, count)  # the kernel itself, on the pool: every index once, in any order
    np.testing.assert_array_equal(np.sort(order.to_numpy()), np.arange(n))


@pytest.mark.parametrize("solver", ["jacobi", "gauss_seidel"])
def test_a_build_in_one_thread_lists_what_the_pool_lists(solver):
    scene, _ = pit_scene(600, (f"contact.solver={solver}",))
    sim = tg.Simulation(scene)
    sim.run(t=0.6)  # balls landing on a pile in a bin: pairs, planes and walls in reach
    lists = sim.solver
    built = {}
    for alone in (False, True):
        with one_thread.in_one_thread(alone):
            lists.build(sim.state)
        built[alone] = {
            name: getattr(lists, name).to_numpy()
            for name in ("first", "upper", "lower", "lower_first", "x_at_build", "lam", "surface_start")
        }
    assert built[False]["first"][-1] > 0, "the range's balls list no pair: the check is empty"
    for name, array in built[False].items():
        np.testing.assert_array_equal(built[True][name], array, err_msg=name)
