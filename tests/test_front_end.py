"""The faster Taichi front end (ti_golf.front_end) builds the very kernels Taichi's own builds."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

from ti_golf import front_end


def test_the_faster_front_end_is_installed_on_the_taichi_that_ti_golf_requires():
    import taichi as ti

    assert tuple(ti.__version__[:2]) in front_end._VERSIONS  # pyproject pins the versions it knows
    assert front_end.install()  # (runtime.init installed it already in this process: still True)


def test_source_positions_made_once_are_the_messages_taichi_makes_each_time():
    import ast
    import inspect
    import textwrap
    import types

    from taichi.lang.ast.ast_transformer_utils import ASTTransformerContext

    from ti_golf.physics import aero, integrate

    memoised = ASTTransformerContext.get_pos_info
    plain = memoised.__wrapped__
    nodes = 0
    for func in (aero.rates, integrate.step_free, integrate.track_flight):  # ti.funcs with blocks, long lines
        original = func.func.func  # the Python function under ti.func
        lines, first = inspect.getsourcelines(original)
        src = [textwrap.fill(line, tabsize=4, width=9999) for line in lines]
        ctx = types.SimpleNamespace(
            file=inspect.getsourcefile(original),
            func=types.SimpleNamespace(func=original),
            lineno_offset=first - 1,
            indent=0,
            src=src,
        )
        for _ in range(2):  # the second pass meets every position again: the messages come from the memo
            for node in ast.walk(ast.parse(textwrap.dedent("\n".join(src)))):
                if isinstance(node, (ast.stmt, ast.expr)):
                    assert memoised(ctx, node) == plain(ctx, node)
                    nodes += 1
    assert nodes > 1000


def test_wrapped_lines_made_once_are_the_lines_taichis_wrapper_makes():
    import textwrap

    from taichi.lang.ast import ast_transformer_utils

    lines = ["", "x = 1", "    y = a + b  # " + "long " * 30, "\tz = f(x)", " " * 12 + "^" * 70, "^" * 200]
    for _ in range(2):  # the second pass comes from the memo
        for line in lines:
            wrapped = ast_transformer_utils.TextWrapper(width=80).wrap(line)
            assert wrapped == textwrap.TextWrapper(width=80).wrap(line), line
            wrapped.append("changed by a caller")  # a caller's list is its own
    assert ast_transformer_utils.TextWrapper(width=40).wrap(lines[2]) == textwrap.wrap(lines[2], width=40)


def _both(level: int) -> tuple[bool, bool]:
    """The faster and Taichi's own test of whether the frame ``level`` up is a class body."""
    from taichi.lang import kernel_impl

    return kernel_impl._inside_class(level), kernel_impl._inside_class.__wrapped__(level)


def test_the_method_test_reads_the_callers_line_as_taichis_does():
    assert front_end.install()

    # on one line: the class body's frame is then on its `class` line, as a decorator's is
    class Methods: both = _both(2)  # noqa: E701  # fmt: skip

    assert Methods.both == (True, True)
    assert _both(2) == (False, False)  # a test function
    assert _both(10_000) == (False, False)  # no frame so far up


@pytest.mark.slow
def test_kernels_built_by_taichis_own_front_end_load_from_the_cache_under_the_faster_one(tmp_path):
    # the offline cache's key of a kernel is made from its IR: a kernel compiled in a process with
    # Taichi's own front end is found, not compiled again, in one with the faster front end
    env = {**os.environ, "TI_OFFLINE_CACHE_FILE_PATH": str(tmp_path / "cache"), "TI_GOLF_ARCH": "cpu"}
    cli = [sys.executable, "-m", "ti_golf"]
    plain = subprocess.run(
        [*cli, "run", "break_shot", "--steps", "1"],
        env={**env, front_end.PLAIN_ENV: "1"},
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert plain.returncode == 0, plain.stderr
    faster = subprocess.run(
        [*cli, "bench", "startup", "--kernels", "break_shot", "--cache", "warm", "--json"],
        env=env,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert faster.returncode == 0, faster.stderr
    report = json.loads(faster.stdout.strip().splitlines()[-1])
    kernels = {k["kernel"]: k for k in report["kernels"]}
    assert "ti_golf.solvers.collide.collision_step" in kernels
    assert {name: k["compiled"] for name, k in kernels.items() if k["compiled"]} == {}
