"""Shared test set-up: one Taichi runtime per test process (CPU, f64), the test tiers, helpers to
run the CLI.

Tiers: a test marked ``slow`` (a pour, a process of its own that compiles its own kernels, a
render in a subprocess) is left out of ``make test-fast`` (``pytest -m "not slow"``); every test
that waits for a background run (tests/background.py) is slow. ``make test`` runs them all on two
pytest-xdist workers, a test file at a time (``-n 2 --dist loadfile --no-loadscope-reorder``: a
module's costly fixtures, such as the settled narrow pit, are made once), the files of slow tests
handed out first so that the short ones fill the gaps. (``--dist loadgroup`` would group tests
across files, but pytest-xdist 3.8 cannot rename pytest 9's node ids, so its groups have no effect.)
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
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
IN_CI = os.environ.get("CI", "").lower() in ("1", "true", "yes")
"""CI sets ``CI=true``: there a test skipped for want of Vulkan fails (see :func:`pytest_runtest_makereport`)."""
XDIST_WORKER = os.environ.get("PYTEST_XDIST_WORKER")
"""The pytest-xdist worker this process is (``gw0``, ``gw1``, ...), or ``None`` in a plain run."""
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
        "starts in the background when a plain (not xdist) session does; implies slow",
    )
    config.addinivalue_line("markers", "vulkan: the test uses Vulkan (GGUI or the backend); one such test at a time")


LONGEST_FILES = (
    "test_piles.py",
    "test_collisions.py",
    "test_cli.py",
    "test_contact_colour.py",
    "test_study.py",
    "test_api.py",
)
"""The test files of the most work, longest first (``make test --durations=0`` from an empty
cache on two cores: about 340, 230, 135, 80, 57 and 55 s of the suite's 1,070): pytest-xdist hands
out whole files (``--dist loadfile``) in the order they are collected, so these go first, the
longest work first leaving the least idle time at the end."""


def _file_rank(item) -> int:
    """Where ``item``'s file comes among :data:`LONGEST_FILES` (after them all when not listed)."""
    name = item.path.name
    return LONGEST_FILES.index(name) if name in LONGEST_FILES else len(LONGEST_FILES)


def pytest_collection_modifyitems(session, config, items):
    """Every test that waits for a background run is slow. In a plain run those tests go last, in
    their order: their runs then overlap every other test on the second core. Under pytest-xdist
    the longest files go first (:data:`LONGEST_FILES`), and in each file the slow tests (the
    longest work handed out first leaves the least idle time at the end); each test runs its
    subprocess when it comes to it, the two workers keeping both cores busy."""
    for item in items:
        if item.get_closest_marker("background") is not None:
            item.add_marker(pytest.mark.slow)
    if XDIST_WORKER is None:
        items.sort(key=lambda item: item.get_closest_marker("background") is not None)  # a stable sort
    else:
        items.sort(key=lambda item: (_file_rank(item), item.get_closest_marker("slow") is None))


ON_VULKAN = pytest.mark.vulkan
"""The mark of a test that draws with GGUI or computes on Vulkan, in this process or a child: no two
such tests run at once, whatever worker runs them (:func:`one_vulkan_user_at_a_time`). Under load,
with two processes on mesa's software driver at once, a GGUI picture has come out without its
meshes (the ground missing)."""

NO_VULKAN_BACKEND = "Taichi cannot start its Vulkan backend here (apt-get install mesa-vulkan-drivers)"
"""The skip reason of a test that computes on Taichi's Vulkan backend when it cannot start (it
names Vulkan, so the skip fails in CI: see :data:`VULKAN_SKIPS_FAIL_IN_CI`)."""

VULKAN_SKIPS_FAIL_IN_CI = "Vulkan"
"""A skip whose reason names this fails in CI: a broken Vulkan install must not silently stop every
picture check (the GGUI snapshots, the windows, the Vulkan backend)."""


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item, call):
    """In CI (``CI=true``), a test skipped for want of Vulkan is reported as failed."""
    outcome = yield
    report = outcome.get_result()
    if not (IN_CI and report.skipped) or hasattr(report, "wasxfail"):
        return
    reason = report.longrepr[2] if isinstance(report.longrepr, tuple) else str(report.longrepr)
    reason = reason.removeprefix("Skipped: ")
    if VULKAN_SKIPS_FAIL_IN_CI in reason:
        report.outcome = "failed"
        report.longrepr = (
            f"CI=true, and this picture check was skipped: {reason}. CI must render with GGUI "
            "(`make system-deps` installs mesa-vulkan-drivers and libvulkan1)."
        )


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


@pytest.fixture(autouse=True)
def one_vulkan_user_at_a_time(request, tmp_path_factory):
    """A test marked ``vulkan`` holds a lock shared by every pytest-xdist worker of the session (a
    file in their common temporary folder) while it runs, its subprocesses included."""
    if request.node.get_closest_marker("vulkan") is None:
        yield
        return
    import fcntl

    root = tmp_path_factory.getbasetemp()
    with open((root.parent if XDIST_WORKER else root) / "vulkan.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        yield


@pytest.fixture(scope="session", autouse=True)
def background_runs(request, tmp_path_factory):
    """The session's background runs (tests/background.py): in a plain session those the selected
    tests mark start with the session's first test, in the order the tests will run; under
    pytest-xdist none starts early, each test runs its own when it comes to it (the other worker
    keeps the second core busy). Each xdist worker's runs keep their kernels in a cache of their
    own, as a plain session's do."""
    import taichi as ti

    cache = os.environ.get("TI_OFFLINE_CACHE_FILE_PATH") or ti.lang.impl.default_cfg().offline_cache_file_path
    suffix = "-background" + (f"-{XDIST_WORKER}" if XDIST_WORKER else "")
    runs = BackgroundRuns(tmp_path_factory.mktemp("background"), str(cache).rstrip("/\\") + suffix)
    early = [] if XDIST_WORKER else request.session.items
    runs.start([mark.args[0] for item in early for mark in item.iter_markers("background")])
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


def read_saved_run(path) -> tuple[dict, dict]:
    """The arrays of a saved run (``Simulation.save``) by entry name and its ``run`` description."""
    import json

    with np.load(path) as d:
        data = {k: d[k] for k in d.files}
    return data, json.loads(str(data["run"]))


def write_saved_run(path, data: dict, meta: dict) -> None:
    """Write a saved run of the arrays ``data`` with the ``run`` description ``meta``."""
    import json

    np.savez(path, **{**data, "run": np.array(json.dumps(meta))})


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


PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"

MATPLOTLIB_BLUE = (0x1F / 255, 0x77 / 255, 0xB4 / 255)
"""matplotlib's first line colour (``C0``, ``tab:blue``)."""


def png_rgb(path) -> np.ndarray:
    """The PNG at ``path`` as RGB floats in [0, 1], shape (height, width, 3) (it must be a PNG)."""
    import matplotlib.image as mpimg

    with open(path, "rb") as fh:
        assert fh.read(8) == PNG_SIGNATURE, f"{path} is not a PNG"
    return np.asarray(mpimg.imread(path), dtype=float)[..., :3]


def colour_pixels(img, colour, tol: float = 0.06) -> np.ndarray:
    """The pixels of ``img`` within ``tol`` of ``colour`` in every channel (a plotted line's core,
    beside its anti-aliased edges), as a boolean mask."""
    return np.all(np.abs(img - np.asarray(colour, float)) <= tol, axis=-1)
