"""A new user's first commands compile ti_golf's kernels without a word from Taichi's compiler.

Taichi prints a ``TaichiWarning`` while it compiles a kernel that, say, stores an f64 value in an
f32 array ("Assign may lose precision"); once a kernel is in the offline cache it is loaded and the
warning is never printed again, so only a process with an empty cache sees it.
"""

from __future__ import annotations

import pytest
from conftest import run_cli

FIRST_COMMANDS = {
    "parallel_gauss_seidel": ("run", "ball_pit", "--steps", "3"),  # grid, colours, sweeps, stale test
    "parallel_jacobi": ("run", "ball_pit", "--steps", "3", "--set", 'contact.solver="jacobi"'),
    "f32": ("run", "ball_pit", "--steps", "3", "--precision", "f32"),
    "blocks_and_terrain": ("run", "avalanche", "--steps", "3"),  # serial steps by blocks
    "serial_relisting": ("run", "break_shot", "--steps", "3"),
    "sweep": ("sweep", "lab_turbulent", "--angles", "36"),
    "bench_pit": ("bench", "pit", "--n", "5000", "--t", "0.05"),  # the bench's probes as well
}
"""Commands that compile each family of kernels, each in a process with an empty kernel cache."""


@pytest.mark.slow
@pytest.mark.parametrize("args", FIRST_COMMANDS.values(), ids=FIRST_COMMANDS.keys())
def test_a_first_run_compiles_without_a_compiler_warning(tmp_path, args):
    proc = run_cli(*args, env={"TI_OFFLINE_CACHE_FILE_PATH": str(tmp_path / "ticache")})
    assert proc.returncode == 0, proc.stderr
    assert "first run on this machine" in proc.stderr  # (the cache was empty: every kernel compiled)
    lines = proc.stderr.splitlines()
    warned = [" / ".join(lines[k : k + 3]) for k, line in enumerate(lines) if "TaichiWarning" in line]
    assert not warned, warned
