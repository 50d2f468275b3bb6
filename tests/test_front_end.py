"""The faster Taichi front end (ti_golf.front_end) builds the very kernels Taichi's own builds."""

import math
import os
import subprocess
import sys

import numpy as np
import pytest

from ti_golf import front_end


def test_the_faster_front_end_is_installed_on_the_taichi_that_ti_golf_requires():
    import taichi as ti

    assert tuple(ti.__version__[:2]) in front_end._VERSIONS  # pyproject pins the versions it knows
    assert front_end.install()  # (runtime.init installed it already in this process: still True)


def test_source_positions_are_taichis_first_line_and_on_an_error_its_whole_message():
    import ast
    import inspect
    import textwrap
    import types

    from taichi.lang.ast.ast_transformer_utils import ASTTransformerContext

    from ti_golf.physics import aero, integrate

    ours = ASTTransformerContext.get_pos_info
    plain = ours.__wrapped__
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
        for node in ast.walk(ast.parse(textwrap.dedent("\n".join(src)))):
            if isinstance(node, (ast.stmt, ast.expr)):
                whole = plain(ctx, node)
                assert "^" in whole and ours(ctx, node) == whole.split("\n", 1)[0] + "\n"  # building: the IR's line
                try:
                    raise ValueError("(the front end reports an error)")
                except ValueError:
                    assert ours(ctx, node) == whole
                nodes += 1
    assert nodes > 500


def test_an_error_in_a_kernels_source_is_shown_under_its_line():
    import taichi as ti

    from ti_golf.runtime import ensure_init

    ensure_init()

    @ti.func
    def add_unknown(a):
        return a + not_defined  # noqa: F821

    @ti.kernel
    def with_error(x: ti.types.ndarray()):
        for i in x:
            x[i] = add_unknown(x[i])

    with pytest.raises(ti.TaichiNameError) as error:
        with_error(ti.ndarray(ti.f64, 2))
    message = str(error.value)
    assert "        return a + not_defined  # noqa: F821\n" + " " * 19 + "^" * 11 + "\n" in message
    assert "in add_unknown:" in message and "x[i] = add_unknown(x[i])" in message


def test_vector_reductions_are_the_sums_taichi_makes_in_the_same_order():
    # v.dot(u), v.norm(), v.norm_sqr(), v.sum() and v.cross(u) inside a kernel: the same
    # operations in the same order as Taichi's ti.func bodies, so the same bits (checked against
    # that order worked out in Python floats, which are f64 as the kernel's are)
    import taichi as ti

    from ti_golf.physics.types import kernel

    @kernel
    def reduce(a: ti.types.ndarray(dtype=ti.f64, ndim=2), out: ti.types.ndarray(dtype=ti.f64, ndim=2)):
        for i in range(a.shape[0]):
            u = ti.Vector([a[i, 0], a[i, 1], a[i, 2]])
            v = ti.Vector([a[i, 3], a[i, 4], a[i, 5]])
            c = u.cross(v)
            out[i, 0], out[i, 1], out[i, 2], out[i, 3] = u.dot(v), u.norm(), u.norm_sqr(), u.sum()
            out[i, 4], out[i, 5], out[i, 6] = c[0], c[1], c[2]

    assert front_end.install()
    a = np.random.default_rng(3).normal(size=(200, 6)) * 10.0 ** np.random.default_rng(4).integers(-8, 8, (200, 6))
    out = np.zeros((200, 7))
    reduce(a, out)
    for row, (u0, u1, u2, v0, v1, v2) in zip(out, a.tolist(), strict=True):
        squares = u0 * u0 + u1 * u1 + u2 * u2
        want = [u0 * v0 + u1 * v1 + u2 * v2, math.sqrt(squares), squares, u0 + u1 + u2]
        want += [u1 * v2 - u2 * v1, u2 * v0 - u0 * v2, u0 * v1 - u1 * v0]
        assert row.tolist() == want


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
def test_runs_built_by_taichis_own_front_end_equal_those_of_the_faster_one(tmp_path):
    # the faster front end builds the same arithmetic: the Jacobi and the Gauss-Seidel steps, the
    # flights and the planes, run bit for bit as when Taichi's own front end builds them (in a
    # cache of its own: the vector reductions' IR, and so their cache keys, differ)
    plain_env = {**os.environ, "TI_OFFLINE_CACHE_FILE_PATH": str(tmp_path / "cache"), front_end.PLAIN_ENV: "1"}
    for solver in ("jacobi", "gauss_seidel"):
        runs = []
        for name, env in (("plain", plain_env), ("faster", dict(os.environ))):
            out = tmp_path / f"{solver}_{name}.npz"
            args = ["run", "break_shot", "--set", f'contact.solver="{solver}"', "--t", "0.3", "--out", str(out)]
            done = subprocess.run(
                [sys.executable, "-m", "ti_golf", *args], env=env, capture_output=True, text=True, timeout=600
            )
            assert done.returncode == 0, done.stderr
            with np.load(out) as saved:
                runs.append({key: saved[key] for key in ("x", "v", "w")})
        for key in ("x", "v", "w"):
            np.testing.assert_array_equal(runs[0][key], runs[1][key], err_msg=f"{solver} {key}")
        assert np.abs(runs[0]["v"]).max() > 0.1  # the break: balls moved and collided


def test_expanded_functions_are_taichis_own_funcs_with_its_plain_front_end(monkeypatch):
    # the small functions Python builds at each call site (front_end.expanded) are plain ti.funcs
    # when Taichi's own front end is asked for; the runs above compare the two builds
    from taichi.lang.kernel_impl import Func

    def twice(x):
        return 2 * x

    assert not isinstance(front_end.expanded(twice).func, Func)
    monkeypatch.setenv(front_end.PLAIN_ENV, "1")
    assert isinstance(front_end.expanded(twice).func, Func)


def test_the_frame_line_taichis_import_reads_is_the_one_inspect_gives():
    import functools
    import inspect

    frame = sys._getframe()
    quick = functools.partial(front_end._frame_line, plain=inspect.getframeinfo)
    for context in (1, 3):
        assert tuple(quick(frame, context)) == tuple(inspect.getframeinfo(frame, context))
    # in a fresh process, `import ti_golf` before Taichi: Taichi imports with it, then all is as before
    code = (
        "import inspect, sys, ti_golf, taichi; from taichi.lang import kernel_impl; "
        "print(inspect.getframeinfo.__module__, any(type(f).__name__ == '_TaichiImport' for f in sys.meta_path))"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert done.stdout.split()[-2:] == ["inspect", "False"]


def test_a_ctrl_c_while_taichi_is_imported_waits_for_the_import_and_then_stops():
    # Ctrl-C while Taichi's compiled extension initialised failed the import: Taichi printed an
    # install hint and a traceback, exit 1. It is held while Taichi is imported, and raised once
    # the import is whole. (Here the signal comes as Taichi imports its compiled library.)
    script = """
import os, signal, sys
import ti_golf

class SignalAtTheLibrary:
    def find_spec(self, name, path=None, target=None):
        if name == "taichi._lib":
            os.kill(os.getpid(), signal.SIGINT)
        return None

sys.meta_path.insert(0, SignalAtTheLibrary())
try:
    import taichi
except KeyboardInterrupt:
    print("interrupted;", "taichi._lib.core" in sys.modules, signal.getsignal(signal.SIGINT) is signal.default_int_handler)
"""
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "interrupted; True True", (done.stdout, done.stderr)  # (the import ran through)
