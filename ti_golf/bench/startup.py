"""Start-up: the wall time of ``ti-golf`` commands in fresh processes, with Taichi's kernel cache
warm and cold, against the project's targets; and where one run's start goes, kernel by kernel.

Each command runs as a new user runs it, ``python -m ti_golf ...`` in a process of its own (the
``ti-golf`` script is the same entry point), timed from the start of the process to its end:
``ti-golf run SCENE --steps 1`` for every bundled scene, ``ti-golf scenes`` and ``ti-golf keys``.
*Warm*: Taichi's offline kernel cache already holds the command's kernels (each command is run
once first, untimed, to make sure). *Cold*: the cache is an empty temporary folder
(``TI_OFFLINE_CACHE_FILE_PATH``, which ``ti.init`` reads), so every kernel is compiled. Each
figure is a wall time, beside the process's CPU time (user and system): on a machine busy with
other work the wall time grows, the CPU time much less. The targets are for wall time on an
otherwise idle machine.

:func:`start_profile` runs one scene's ``--steps 1`` in a fresh process with
:class:`ti_golf.kernel_log.KernelLog` installed and reports the import, ``ti.init``, set-up and
first-step seconds and, per kernel, its instances and the seconds of Taichi's front end and of
its compilation (or load from the cache).
"""

from __future__ import annotations

import json
import math
import os
import resource
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from ti_golf.errors import ConfigError
from ti_golf.kernel_log import cache_hits, cache_keys, cached_module_lines
from ti_golf.runtime import ON_THE_CPU
from ti_golf.scene.balls import ball_count
from ti_golf.scene.loader import load_scene, scenes_dir

WARM_RUN_S = 2.0
"""Target [s]: ``ti-golf run SCENE --steps 1`` of any bundled scene, warm cache, on the CPU."""
WARM_ONE_BALL_S = 1.2
"""Target [s]: the same for a one-ball scene."""
WARM_LISTING_S = 0.5
"""Target [s]: ``ti-golf scenes`` and ``ti-golf keys``."""
COLD_COLLISIONS_CPU_S = 15.0
"""Target [s]: a collision scene's run from an empty cache on the CPU."""
COLD_POUR_CUDA_S = 30.0
"""Target [s]: the pour's (ball_pit) run from an empty cache on CUDA."""

POUR = "ball_pit"


def startup_commands(scenes: Sequence[str] | None = None) -> list[dict[str, Any]]:
    """The commands timed (each a dict: ``name``, ``args``, ``balls``, ``collisions``): a run of
    each of ``scenes`` (default: every bundled scene), then ``scenes`` and ``keys``."""
    names = list(scenes) if scenes else scene_names()
    out = []
    for name in names:
        scene = load_scene(name)
        n = ball_count(scene)
        out.append(
            {
                "name": f"run {name}",
                "args": ["run", name, "--steps", "1"],
                "balls": n,
                "collisions": bool(scene.world.collisions and n > 1),
            }
        )
    out += [{"name": "scenes", "args": ["scenes"]}, {"name": "keys", "args": ["keys"]}]
    return out


def targets(command: dict[str, Any], arch: str) -> tuple[float | None, float | None]:
    """(warm, cold) targets [s] of a command on a backend, ``None`` where the project sets none."""
    run = command["args"][0] == "run"
    warm = cold = None
    if arch == "cpu":
        warm = (WARM_ONE_BALL_S if command["balls"] == 1 else WARM_RUN_S) if run else WARM_LISTING_S
        cold = COLD_COLLISIONS_CPU_S if run and command["collisions"] else None
    elif arch in ("cuda", "gpu") and command["args"][1:2] == [POUR]:
        cold = COLD_POUR_CUDA_S
    return warm, cold


def _child_cpu_s() -> float:
    """CPU seconds (user and system) of this process's waited-for children so far."""
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def _time_command(args: Sequence[str], env: dict[str, str], timeout: float) -> tuple[float, float, str | None]:
    """Wall time and CPU time [s] of ``python -m ti_golf ARGS`` in a fresh process, and why it
    failed (or None). The CPU time (user and system, all threads) is what other processes on a
    busy machine do not inflate, where the wall time grows with the load."""
    start, cpu = time.perf_counter(), _child_cpu_s()
    try:
        proc = subprocess.run(
            [sys.executable, "-m", "ti_golf", *args],
            capture_output=True,
            text=True,
            env=env,
            timeout=timeout,
        )
    except subprocess.TimeoutExpired:
        return time.perf_counter() - start, math.nan, f"took more than {timeout:g} s"
    seconds, cpu = time.perf_counter() - start, _child_cpu_s() - cpu
    fallback = next((line for line in proc.stderr.splitlines() if line.endswith(ON_THE_CPU)), None)
    if fallback is not None:  # (its times would be the CPU's, labelled with the backend asked for)
        raise ConfigError("--arch", None, f"{fallback.removeprefix('ti-golf: ')}: nothing to time on it")
    if proc.returncode != 0:
        last = (proc.stderr.strip().splitlines() or ["(no message)"])[-1]
        return seconds, cpu, f"exit code {proc.returncode}: {last}"
    return seconds, cpu, None


def _env(arch: str, precision: str, cache: str | None = None) -> dict[str, str]:
    env = {**os.environ, "TI_GOLF_ARCH": arch, "TI_GOLF_PRECISION": precision}
    if cache is not None:
        env["TI_OFFLINE_CACHE_FILE_PATH"] = cache
    return env


def bench_startup(
    scenes: Sequence[str] | None = None,
    caches: Sequence[str] = ("warm", "cold"),
    repeats: int = 1,
    arch: str = "cpu",
    precision: str = "f64",
    timeout: float = 600.0,
    say: Callable[[str], None] | None = None,
) -> dict[str, Any]:
    """Time :func:`startup_commands` in fresh processes, warm (best of ``repeats``, after an
    untimed run) and cold (each in an empty cache of its own), against :func:`targets`; ``say``
    gets a line per command as it is timed."""
    rows = []
    for command in startup_commands(scenes):
        warm_target, cold_target = targets(command, arch)
        row: dict[str, Any] = {
            "command": f"ti-golf {' '.join(command['args'])}",
            "balls": command.get("balls"),
            "warm_target_s": warm_target,
            "cold_target_s": cold_target,
        }
        if "warm" in caches:
            _time_command(command["args"], _env(arch, precision), timeout)  # fills the cache
            times = [_time_command(command["args"], _env(arch, precision), timeout) for _ in range(repeats)]
            row["warm_s"], row["warm_cpu_s"], _ = min(times, key=lambda t: t[0])
            row["warm_error"] = next((e for _, _, e in times if e), None)
        if "cold" in caches:
            with tempfile.TemporaryDirectory(prefix="ti-golf-cold-cache-") as cache:
                row["cold_s"], row["cold_cpu_s"], row["cold_error"] = _time_command(
                    command["args"], _env(arch, precision, cache), timeout
                )
        for which in ("warm", "cold"):
            target = row[f"{which}_target_s"]
            if f"{which}_s" in row:
                ok = row[f"{which}_error"] is None and (target is None or row[f"{which}_s"] <= target)
                row[f"{which}_pass"] = ok if target is not None or row[f"{which}_error"] else None
        rows.append(row)
        if say is not None:
            say(startup_line(row))
    judged = [r[k] for r in rows for k in ("warm_pass", "cold_pass") if r.get(k) is not None]
    return {
        "benchmark": "startup",
        "arch": arch,
        "precision": precision,
        "cpu_count": os.cpu_count(),
        "load_average": _load(),
        "bytecode_stale": stale_bytecode(),
        "repeats": repeats,
        "commands": rows,
        "passed": sum(judged),
        "failed": len(judged) - sum(judged),
    }


def stale_bytecode(package: Path | None = None) -> list[str]:
    """The modules of ``package`` (default: ti_golf's folder) whose compiled bytecode is missing or
    older than their source. Python compiles such a module at every import (about 0.15 s for the
    package's modules in all on a slow host) unless it may write the bytecode next to it, which
    ``PYTHONDONTWRITEBYTECODE`` or a read-only folder forbids: a warm start is then not as warm
    as a user's. ``make setup`` compiles them (``python -m compileall``), as pip does for a wheel."""
    from importlib.util import cache_from_source

    root = package or Path(__file__).resolve().parents[1]
    stale = []
    for source in sorted(root.rglob("*.py")):
        compiled = Path(cache_from_source(str(source)))
        if not compiled.exists() or compiled.stat().st_mtime < source.stat().st_mtime:
            stale.append(str(source.relative_to(root.parent)))
    return stale


def _load() -> float | None:
    """The system's load average over the last minute (other processes slow every figure), or None."""
    try:
        return os.getloadavg()[0]
    except (AttributeError, OSError):  # pragma: no cover - not Unix
        return None


def startup_line(row: dict[str, Any]) -> str:
    """One command's figures for people: warm and cold seconds, each beside its target."""
    cells = []
    for which in ("warm", "cold"):
        if f"{which}_s" not in row:
            continue
        target, verdict = row[f"{which}_target_s"], row.get(f"{which}_pass")
        mark = "" if verdict is None else (" pass" if verdict else " FAIL")
        goal = f" (target {target:g} s{mark})" if target is not None else mark
        error = f" [{row[f'{which}_error']}]" if row[f"{which}_error"] else ""
        cells.append(f"{which} {row[f'{which}_s']:6.2f} s, cpu {row[f'{which}_cpu_s']:6.2f} s{goal}{error}")
    return f"{row['command']:<40} " + "; ".join(cells)


PROFILE_SCRIPT = """
import json, sys, time
start = time.perf_counter()
from ti_golf.bench.startup import profile_in_process
print(json.dumps(profile_in_process(sys.argv[1], start)))
"""


def profile_in_process(scene: str, start: float) -> dict[str, Any]:
    """The stages and kernels of one run's start in this (fresh) process: imports (since
    ``start``, the script's first line), ``ti.init``, the simulation's set-up and its first step,
    with every kernel's front end and compilation timed (:class:`~ti_golf.kernel_log.KernelLog`)."""
    from taichi.lang import impl

    from ti_golf import runtime
    from ti_golf.kernel_log import KernelLog
    from ti_golf.sim.simulation import Simulation

    stages = {"import_s": time.perf_counter() - start}
    t = time.perf_counter()
    info = runtime.init()
    stages["init_s"] = time.perf_counter() - t
    log = KernelLog()
    with log.installed():
        t = time.perf_counter()
        sim = Simulation.from_scene(scene)
        stages["setup_s"] = time.perf_counter() - t
        t = time.perf_counter()
        sim.run(steps=1)
        stages["first_step_s"] = time.perf_counter() - t
    stages["total_s"] = time.perf_counter() - start
    load = _load()
    instances, front_end, compile_s, first_launch = log.totals()
    return {
        "benchmark": "startup_kernels",
        "scene": scene,
        "arch": info.arch,
        "precision": info.precision,
        "cache_path": impl.current_cfg().offline_cache_file_path,
        "stages": stages,
        "load_average": load,
        "instances": instances,
        "front_end_s": front_end,
        "compile_s": compile_s,
        "first_launch_s": first_launch,
        "kernels": [
            {
                "kernel": k.name,
                "instances": k.instances,
                "front_end_s": k.front_end_s,
                "compile_s": k.compile_s,
                "first_launch_s": k.first_launch_s,
                "instance_names": k.instance_names,
            }
            for k in log.table()
        ],
    }


def start_profile(
    scene: str, cold: bool = False, arch: str = "cpu", precision: str = "f64", timeout: float = 600.0
) -> dict[str, Any]:
    """:func:`profile_in_process` in a fresh process, with the kernel cache as it is or, with
    ``cold``, empty (a temporary folder); each kernel's ``compiled`` instances are those its debug
    log does not say it loaded from the cache (:func:`~ti_golf.kernel_log.cache_hits`), and its
    ``module_lines`` the lines of its instances' compiled modules in the cache
    (:func:`~ti_golf.kernel_log.cached_module_lines`; ``None`` where one is not found there)."""
    with tempfile.TemporaryDirectory(prefix="ti-golf-cold-cache-") as cache:
        env = {**_env(arch, precision, cache if cold else None), "TI_LOG_LEVEL": "debug"}
        proc = subprocess.run(
            [sys.executable, "-c", PROFILE_SCRIPT, scene], capture_output=True, text=True, env=env, timeout=timeout
        )
        if proc.returncode != 0:
            last = (proc.stderr.strip().splitlines() or ["(no message)"])[-1]
            raise RuntimeError(f"the profiled run of {scene} failed (exit code {proc.returncode}): {last}")
        result = json.loads(proc.stdout.strip().splitlines()[-1])
        result["cache"] = "cold" if cold else "warm"
        hits, keys, folder = cache_hits(proc.stderr), cache_keys(proc.stderr), Path(result.pop("cache_path"))
        for k in result["kernels"]:
            names = k.pop("instance_names")
            k["compiled"] = sum(name not in hits for name in names)
            lines = [cached_module_lines(folder / f"{keys[name]}.tic") if name in keys else None for name in names]
            k["module_lines"] = _total(lines)
    result["compiled"] = sum(k["compiled"] for k in result["kernels"])
    result["module_lines"] = _total([k["module_lines"] for k in result["kernels"]])
    return result


def _total(counts: Sequence[int | None]) -> int | None:
    """The sum of ``counts``, or ``None`` when one of them is not known."""
    return None if None in counts else sum(n for n in counts if n is not None)


def profile_lines(result: dict[str, Any], top: int | None = None) -> list[str]:
    """The profile for people: the stages, then a row per kernel (the longest front end first)."""
    s = result["stages"]
    lines = [
        f"{result['scene']} ({result['arch']}, {result['precision']}, {result['cache']} cache): "
        f"{s['total_s']:.2f} s to the end of the first step: imports {s['import_s']:.2f} s, ti.init "
        f"{s['init_s']:.2f} s, set-up {s['setup_s']:.2f} s, first step {s['first_step_s']:.2f} s"
        + (f" (load average {result['load_average']:.1f})" if result.get("load_average") is not None else ""),
        f"kernels: {result['instances']} instances prepared, {result['compiled']} compiled and "
        f"{result['instances'] - result['compiled']} loaded from the cache; Taichi's front end "
        f"{result['front_end_s']:.2f} s, compile or load {result['compile_s']:.2f} s, first launches "
        f"{result['first_launch_s']:.2f} s (the machine code made from the compiled modules, which the cache "
        f"does not keep, and the kernels' first runs); the modules {_lines(result['module_lines'])} lines",
        f"{'front end [s]':>13}  {'compile [s]':>11}  {'first launch [s]':>16}  {'module lines':>12}  "
        f"{'instances':>9}  {'compiled':>8}  kernel",
    ]
    for k in result["kernels"][:top]:
        lines.append(
            f"{k['front_end_s']:13.3f}  {k['compile_s']:11.3f}  {k['first_launch_s']:16.3f}  "
            f"{_lines(k['module_lines']):>12}  {k['instances']:9d}  {k['compiled']:8d}  {k['kernel']}"
        )
    return lines


def _lines(count: int | None) -> str:
    """A count of lines for people, ``?`` when it is not known."""
    return "?" if count is None else f"{count:,}"


def scene_names() -> list[str]:
    """The bundled scenes' names."""
    return sorted(p.stem for p in scenes_dir().glob("*.toml"))
