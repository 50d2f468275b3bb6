"""The kernel profiler's records summed by kernel (ti_golf.bench.kernel_times), on stand-in records."""

from __future__ import annotations

from types import SimpleNamespace

import pytest
import taichi as ti

from ti_golf.bench.kernel_times import KernelTimes, kernel_of


def test_a_loops_name_gives_its_kernel_and_compiled_instance():
    assert kernel_of("gauss_seidel_sweep_c104_0_kernel_5_range_for") == (
        "gauss_seidel_sweep",
        "gauss_seidel_sweep_c104_0",
    )
    assert kernel_of("link_and_carry_c94_1_kernel_10_range_for") == ("link_and_carry", "link_and_carry_c94_1")
    assert kernel_of("storage_order_c86_0_kernel_6_serial") == ("storage_order", "storage_order_c86_0")
    assert kernel_of("jit_evaluator_1") == ("jit_evaluator_1", "jit_evaluator_1")  # not Taichi's form: itself


class _StandIn:
    """Taichi's profiler, holding the records a test gives it."""

    def __init__(self) -> None:
        self.pending: list[SimpleNamespace] = []
        self._traced_records: list[SimpleNamespace] = []

    def launch(self, name: str, ms: float) -> None:
        self.pending.append(SimpleNamespace(name=name, kernel_time=ms))

    def _update_records(self) -> None:
        self._traced_records = list(self.pending)

    def clear(self) -> None:
        self.pending.clear()
        self._traced_records = []


@pytest.fixture
def profiler(monkeypatch):
    stand_in = _StandIn()
    monkeypatch.setattr(ti.profiler.kernel_profiler, "get_default_kernel_profiler", lambda: stand_in)
    monkeypatch.setattr(ti.profiler, "clear_kernel_profiler_info", stand_in.clear)
    return stand_in


def test_seconds_sum_every_loop_and_launches_count_each_instance_once(profiler):
    times = KernelTimes()
    for _ in range(3):  # three launches of one instance of a kernel of two loops
        profiler.launch("sweep_c1_0_kernel_1_range_for", 2.0)
        profiler.launch("sweep_c1_0_kernel_3_range_for", 1.0)
    profiler.launch("sweep_c1_1_kernel_1_range_for", 4.0)  # and one of another instance
    profiler.launch("build_c2_0_kernel_0_serial", 0.5)
    times.fold()
    assert times.seconds["sweep"] == pytest.approx(13e-3) and times.launches["sweep"] == 4
    assert times.seconds["build"] == pytest.approx(0.5e-3) and times.launches["build"] == 1
    profiler.launch("sweep_c1_0_kernel_1_range_for", 2.0)  # records left since the last fold ...
    times.drop()  # ... dropped unsummed
    profiler.launch("build_c2_0_kernel_0_serial", 1.5)
    times.fold()  # a fold adds what came since the last
    assert times.launches == {"sweep": 4, "build": 2}
    assert times.total_s() == pytest.approx(15e-3)
    assert list(times.as_dict()) == ["sweep", "build"]  # the dearest first
    assert times.as_dict()["build"] == {"s": pytest.approx(2e-3), "launches": 2}
