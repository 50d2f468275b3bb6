"""Shared test set-up: one Taichi runtime per test session (CPU, f64), helpers to run the CLI."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest
from background import BackgroundRuns

ROOT = Path(__file__).resolve().parent.parent
SCENES = ROOT / "scenes"

TEST_ARCH = os.environ.get("TI_GOLF_TEST_ARCH", "cpu")
"""The backend of the whole session: CPU unless ``TI_GOLF_TEST_ARCH`` names another, to run the
suite on a GPU (``TI_GOLF_TEST_ARCH=cuda make test``). Also the default of the processes the tests
start, and of any kernel a test module launches while it is collected."""
os.environ["TI_GOLF_ARCH"] = TEST_ARCH

ON_CPU = TEST_ARCH == "cpu"
SERIAL_OR_PARALLEL = pytest.mark.parametrize(
    "serial",
    [pytest.param(True, marks=pytest.mark.skipif(not ON_CPU, reason="serial stepping runs on the CPU only")), False],
    ids=["serial", "parallel"],
)
"""Run a test with the collision step forced serial (``CollisionSolver(serial=True)``) and parallel."""


_exit_status: list[int] = []


def pytest_configure(config):
    config.addinivalue_line(
        "markers",
        "background(key): the test uses the run `key` of tests/background.py, which "
        "starts in the background when the session does",
    )


def pytest_collection_modifyitems(session, config, items):
    """The tests that wait for a background run (tests/background.py) go last, in their order:
    their runs then overlap every other test, not only those before them in the files."""
    items.sort(key=lambda item: item.get_closest_marker("background") is not None)  # a stable sort


def pytest_sessionfinish(session, exitstatus):
    _exit_status.append(int(exitstatus))


@pytest.hookimpl(trylast=True)
def pytest_unconfigure(config):
    """The test process ends as ``ti-golf`` does (``runtime.exit_process``): once pytest has
    reported, without the C++ static destructors of Taichi's runtime that can crash a normal exit
    and turn a passing run into a failing exit status."""
    if _exit_status:
        from ti_golf import runtime

        runtime.exit_process(_exit_status[0])


@pytest.fixture(scope="session", autouse=True)
def taichi_runtime():
    """The only ti.init of the test session goes through ti_golf.runtime (tests needing another
    backend or precision start a subprocess)."""
    import ti_golf

    return ti_golf.init(TEST_ARCH, "f64")


@pytest.fixture(scope="session", autouse=True)
def background_runs(request, tmp_path_factory):
    """The session's background runs (tests/background.py): those the selected tests mark start
    with the session's first test, in the order the tests will run."""
    import taichi as ti

    cache = os.environ.get("TI_OFFLINE_CACHE_FILE_PATH") or ti.lang.impl.default_cfg().offline_cache_file_path
    runs = BackgroundRuns(tmp_path_factory.mktemp("background"), str(cache).rstrip("/\\") + "-background")
    runs.start([mark.args[0] for item in request.session.items for mark in item.iter_markers("background")])
    yield runs
    runs.stop()


def cli(*args: str) -> list[str]:
    """The command line of ``python -m ti_golf ARGS``."""
    return [sys.executable, "-m", "ti_golf", *args]


def run_cli(*args: str, env: dict[str, str] | None = None, timeout: float = 600) -> subprocess.CompletedProcess:
    """Run ``python -m ti_golf ARGS`` in a fresh process; returns the completed process (text mode)."""
    full_env = {**os.environ, **(env or {})}
    return subprocess.run(cli(*args), capture_output=True, text=True, env=full_env, timeout=timeout, cwd=ROOT)


def sim_state(sim) -> dict:
    """Everything a step reads of a simulation's balls, by ball id, with t and the step count."""
    from ti_golf.physics.state import State

    out = {name: sim.state.read(name) for name in State.PER_BALL}
    out.update(t=sim.t, steps=sim.step_count)
    return out


def assert_same_state(a, b) -> None:
    """Two simulations' states equal bit for bit (NaN, in the records of balls not tracked, equal NaN)."""
    import numpy as np

    sa, sb = sim_state(a), sim_state(b)
    for name in sa:
        np.testing.assert_array_equal(sa[name], sb[name], err_msg=name)


@pytest.fixture
def ctrl_c():
    """Ctrl-C (SIGINT) raises ``KeyboardInterrupt`` in this test, as in a terminal, even where the
    tests were started with SIGINT ignored (a shell's background job)."""
    import signal

    before = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, before)


def sigint_as_in_a_terminal() -> None:
    """For ``subprocess.Popen(preexec_fn=...)``: the child starts with SIGINT's default action, so
    that Python turns it into ``KeyboardInterrupt`` (see :func:`ctrl_c`)."""
    import signal

    signal.signal(signal.SIGINT, signal.SIG_DFL)
