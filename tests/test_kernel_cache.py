"""Processes that share Taichi's kernel cache take turns at it (ti_golf.kernel_cache)."""

from __future__ import annotations

import os
import subprocess
import sys
import time

import pytest
from conftest import ROOT, cli, run_cli

from ti_golf import kernel_cache

fcntl = pytest.importorskip("fcntl")


def test_a_turn_is_waited_for_and_given_up_after_its_wait(tmp_path):
    with kernel_cache.taking_turns(tmp_path) as taken:
        assert taken and (tmp_path / kernel_cache.LOCK_NAME).exists()
        start = time.monotonic()
        with kernel_cache.taking_turns(tmp_path, wait_s=0.2) as second:  # (another open file: another lock)
            assert not second
        assert 0.2 <= time.monotonic() - start < 2.0
    with kernel_cache.taking_turns(tmp_path, wait_s=0.0) as again:  # free once the first turn ended
        assert again


def test_a_command_waits_while_another_process_writes_the_cache_and_then_loads_from_it(tmp_path):
    # Taichi's own lock (ticache.lock, tried for 0.2 s) is held by a process that writes the cache
    # as it ends; a command that starts meanwhile used to give up on it with a raw warning and
    # compile every kernel again. Here this test is that writing process, for 3 s: the command
    # waits for its turn, then loads every kernel from the cache, and says nothing of locks
    cache = tmp_path / "cache"
    env = {**os.environ, "TI_OFFLINE_CACHE_FILE_PATH": str(cache)}
    assert run_cli("run", "lab_vacuum", "--steps", "1", env=env).returncode == 0  # fills the cache
    with open(cache / kernel_cache.LOCK_NAME, "a") as turn:
        fcntl.flock(turn, fcntl.LOCK_EX)
        (cache / "ticache.lock").touch()  # (Taichi's lock file: taken while it exists)
        proc = subprocess.Popen(
            cli("run", "lab_vacuum", "--steps", "1"),
            env={**env, "TI_LOG_LEVEL": "debug"},
            cwd=ROOT,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        time.sleep(3.0)
        assert proc.poll() is None  # waiting for its turn
        (cache / "ticache.lock").unlink()
    _, err = proc.communicate(timeout=300)
    assert proc.returncode == 0, err
    assert "Lock" not in err, [line for line in err.splitlines() if "Lock" in line]
    assert "from cache" in err and "Cache kernel" not in err  # every kernel loaded, none compiled again


@pytest.mark.skipif(sys.platform == "win32", reason="flock: POSIX")
def test_the_runtime_ends_in_its_turn_at_the_cache(tmp_path, monkeypatch):
    # the end of the runtime (Taichi then writes the cache) waits for the turn, as the first kernel does
    from ti_golf import runtime

    calls = []
    monkeypatch.setattr(runtime, "_info", object())
    monkeypatch.setattr(runtime.ti, "reset", lambda: calls.append(_turn_held()))
    monkeypatch.setattr(kernel_cache, "cache_folder", lambda: tmp_path)
    runtime.reset_runtime()
    assert calls == [True] and runtime._info is None
    runtime.reset_runtime()  # (ended: nothing more to do)
    assert calls == [True]


def _turn_held() -> bool:
    """Whether another process or file would now wait for the turn at the cache."""
    with kernel_cache.taking_turns(wait_s=0.0) as taken:
        return not taken
