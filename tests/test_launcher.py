"""The faster host side of a kernel call (ti_golf.launcher): the same kernels, the same results.

Each check runs a scene twice from the same start in this process, once with every kernel called
through the fast call and once through Taichi's own call, and compares the states bit for bit;
and checks that once a scene's kernels are compiled, every call of its steps takes the fast one
(a kernel whose arguments it cannot set would silently fall back to the slower call)."""

import numpy as np
import pytest
import taichi as ti

import ti_golf as tg
from ti_golf import launcher
from ti_golf.physics.types import kernel

pytestmark = pytest.mark.skipif(not launcher.enabled(), reason="the fast call is off (TI_GOLF_PLAIN_LAUNCH=1)")

SCENES = [
    ("break_shot", ()),  # the report's Jacobi sweeps, which the lab's scenes name
    ("break_shot", ("contact.solver=gauss_seidel",)),  # Gauss–Seidel, the column layout
    ("break_shot", ("contact.solver=gauss_seidel", "contact.layout=contacts")),  # a thread per pair
    ("terrain_3d", ()),  # a ball on a height field
    ("lab_magnus", ()),  # one ball in flight
]


def _taichi_calls() -> int:
    return sum(f.taichi_calls for f in launcher.MADE)


def _fast_calls() -> int:
    return sum(f.fast_calls for f in launcher.MADE)


STEPS = 20


def _run(name: str, overrides: tuple[str, ...]) -> np.ndarray:
    sim = tg.Simulation(tg.load_scene(name, list(overrides)))
    sim.step(STEPS)
    return np.concatenate([sim.x, sim.v, sim.w])


@pytest.mark.parametrize(("name", "overrides"), SCENES, ids=[n + "".join(f"-{o}" for o in over) for n, over in SCENES])
def test_a_fast_call_runs_the_kernels_as_taichis_own_call(name, overrides, monkeypatch):
    first = _run(name, overrides)  # compiles what the steps use
    taichi_before, fast_before = _taichi_calls(), _fast_calls()
    fast = _run(name, overrides)  # the same steps again
    assert _taichi_calls() == taichi_before, "a kernel of the steps went through Taichi's own call"
    assert _fast_calls() > fast_before
    monkeypatch.setattr(launcher.FastCall, "__call__", lambda self, *a, **k: self._wrapped(*a, **k))
    fast_before = _fast_calls()
    plain = _run(name, overrides)
    assert _fast_calls() == fast_before  # (the patch took: every call went through Taichi's)
    np.testing.assert_array_equal(fast, plain)
    np.testing.assert_array_equal(first, plain)


@kernel
def _scaled(a: ti.types.ndarray(dtype=ti.f64, ndim=1), factor: ti.f64):
    for i in range(a.shape[0]):
        a[i] *= factor


def test_an_argument_of_the_wrong_type_gets_taichis_error_not_a_crash():
    a = ti.ndarray(ti.f64, 4)
    a.from_numpy(np.arange(4.0))
    _scaled(a, 2.0)
    _scaled(a, factor=0.5)  # by name too
    _scaled(a, np.float64(3.0))
    np.testing.assert_array_equal(a.to_numpy(), np.arange(4.0) * 3.0)
    with pytest.raises(TypeError, match="Expect element type f64"):
        _scaled(ti.ndarray(ti.i32, 4), 2.0)
    with pytest.raises(ti.TaichiRuntimeTypeError):
        _scaled(a, "two")
