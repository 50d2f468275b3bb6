"""Shared test set-up: one Taichi runtime per test session (CPU, f64), helpers to run the CLI."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
SCENES = ROOT / "scenes"


@pytest.fixture(scope="session", autouse=True)
def taichi_runtime():
    """The only ti.init of the test session goes through ti_golf.runtime (tests needing another
    backend or precision start a subprocess)."""
    import ti_golf

    return ti_golf.init("cpu", "f64")


def run_cli(*args: str, env: dict[str, str] | None = None, timeout: float = 600) -> subprocess.CompletedProcess:
    """Run ``python -m ti_golf ARGS`` in a fresh process; returns the completed process (text mode)."""
    full_env = {**os.environ, **(env or {})}
    return subprocess.run([sys.executable, "-m", "ti_golf", *args], capture_output=True, text=True,
                          env=full_env, timeout=timeout, cwd=ROOT)
