"""The Python API: a Simulation you can step, inspect, modify and continue; sweeps as arrays."""

from __future__ import annotations

import os
import re

import background
import numpy as np
import pytest
from conftest import ROOT, SCENES, cli

import ti_golf as tg
from ti_golf.cli.main import main
from ti_golf.sim.simulation import UNTIL_CHECK_S


def test_step_inspect_modify_continue():
    # like the report's WoP object: simulate, read the state, change it, simulate again
    sim = tg.Simulation.from_scene("lab_turbulent", ["world.ground=false"])
    assert sim.n == 1 and sim.t == 0.0
    sim.step(50)
    assert sim.t == pytest.approx(0.5)
    x_mid, v_mid = sim.x, sim.v
    assert x_mid[0, 0] > 10 and v_mid[0, 0] > 0
    sim.v = -v_mid  # turn the ball around ...
    sim.run(t=0.5)  # ... and, in vacuum, it would retrace its path; with drag it falls short
    assert abs(sim.x[0, 0]) < x_mid[0, 0]
    assert sim.t == pytest.approx(1.0)


def test_continuing_equals_one_long_run():
    a = tg.Simulation.from_scene("lab_spin_decay")
    b = tg.Simulation.from_scene("lab_spin_decay")
    a.run(t=3.0)
    for _ in range(6):
        b.run(t=0.5)
    np.testing.assert_array_equal(a.x, b.x)
    np.testing.assert_array_equal(a.w, b.w)


@pytest.mark.slow
def test_many_balls_of_different_size_and_mass():
    # a heavier ball of the same size loses less speed to drag (k_D/m): it carries farther (three
    # shots from one point: they never meet, and balls at one point that collide are refused)
    scene = tg.load_scene("lab_turbulent", ["world.ground=false", "world.collisions=false"])
    v = np.tile([60.0, 40.0, 0.0], (3, 1))
    sim = tg.Simulation(scene, x=np.zeros((3, 3)), v=v, radius=[0.02, 0.02, 0.03], mass=[0.045, 0.09, 0.045])
    sim.run(t=12.0, until="landed")
    carry = sim.flight().carry
    assert carry[1] > carry[0] > carry[2]


def test_a_tracked_ball_moved_or_struck_again_starts_a_new_flight_record(tmp_path):
    # moved 100 m downrange at t0, its carry was measured from the old launch point (312 m); struck
    # again after it landed, it stayed "landed" with the old shot's carry, and a run until it
    # landed stopped at once. Now each is a new launch from where and when it is: the same shot's
    # carry (to the last bit when struck from the same point: RK4's steps do not depend on the
    # time) and its hang time to the rounding of the absolute times it is taken from
    base = tg.Simulation("lab_turbulent")
    x0, v0 = base.x[0].copy(), base.v[0].copy()
    base.run(until="landed")
    shot = base.flight()
    sim = tg.Simulation("lab_turbulent")
    sim.x = [x0 + [100.0, 0.0, 0.0]]
    sim.run(until="landed")
    moved = sim.flight()
    assert moved.carry[0] == pytest.approx(shot.carry[0], rel=1e-12)  # (the positions' rounding 100 m on)
    assert moved.landing_x[0] == pytest.approx(shot.landing_x[0] + 100.0, rel=1e-12)
    struck_at = sim.t
    sim.set_ball(0, x=x0, v=v0)
    assert sim.unfinished("landed").tolist() == [0] and np.isnan(sim.flight().carry[0])
    sim.run(t=30.0, until="landed")
    again = sim.flight()
    assert again.carry[0] == shot.carry[0] and again.apex[0] == shot.apex[0]
    assert again.flight_time[0] == pytest.approx(shot.flight_time[0], abs=1e-9 * struck_at)
    # a saved run keeps the launch time: continued, the record reads the same
    sim.save(tmp_path / "again.npz")
    assert tg.Simulation.load(tmp_path / "again.npz").flight().flight_time[0] == again.flight_time[0]


def test_sweep_returns_arrays_in_grid_order():
    res = tg.sweep("lab_magnus", angles_deg=[8, 10, 12], speeds=[60, 80], spins=[0, 10])
    assert res.angle_deg.shape == res.carry.shape == (12,)
    np.testing.assert_array_equal(res.angle_deg[:3], [8, 10, 12])  # angle varies fastest
    assert set(res.speed_mps) == {60.0, 80.0} and set(res.spin_radps) == {0.0, 10.0}
    cols = res.columns()
    assert {"carry_m", "apex_height_m", "landing_angle_deg"} <= set(cols)
    # more backspin (Magnus lift) carries farther at these low angles
    i0 = np.flatnonzero((res.speed_mps == 80) & (res.spin_radps == 0) & (res.angle_deg == 10))[0]
    i1 = np.flatnonzero((res.speed_mps == 80) & (res.spin_radps == 10) & (res.angle_deg == 10))[0]
    assert res.carry[i1] > res.carry[i0]


def test_sweep_and_simulation_agree():
    # the fused sweep kernel and the step-by-step Simulation integrate the same equations
    res = tg.sweep("lab_spin_decay", angles_deg=[30.0])
    sim = tg.Simulation.from_scene("lab_spin_decay", ["launch.angle_deg=30", "world.ground=false"])
    sim.run(t=8.0, until="landed")
    f = sim.flight()
    assert f.carry[0] == pytest.approx(res.carry[0], rel=1e-9)
    assert f.apex[0] == pytest.approx(res.flight.apex[0], rel=1e-9)
    assert f.flight_time[0] == pytest.approx(res.flight.flight_time[0], rel=1e-9)


def test_sweep_is_deterministic_and_independent_of_grouping():
    # balls are grouped in SIMD lanes after sorting; results must not depend on the grouping
    angles = np.linspace(5, 60, 37)
    a = tg.sweep("lab_magnus", angles_deg=angles)
    b = tg.sweep("lab_magnus", angles_deg=angles[::-1])
    np.testing.assert_array_equal(a.carry, b.carry[::-1])


def test_nonfinite_simulation_names_the_ball():
    # a Magnus law 4,000 times the report's turns the ball faster than a step, and the explicit
    # step's turns grow its speed more each step, until it overflows (a drag that fast is refused)
    sim = tg.Simulation.from_scene("lab_magnus", ["world.ground=false", "air.C_M=100"])
    with pytest.raises(tg.SimulationError, match="ball 0") as err:
        sim.run(t=5.0)
    assert err.value.balls == [0]


@pytest.mark.slow
def test_status_counts():
    sim = tg.Simulation(tg.load_scene("lab_vacuum"), x=[[0, 0.02, 0], [1, 2.0, 0]], v=[[0, 0, 0], [0, 0, 0]])
    sim.step(1)
    c = sim.counts()
    assert c["flying"] == 1 and c["rolling"] == 1
    sim.run(t=3.0)
    assert sim.counts()["at_rest"] == 2


MANY_BALLS = {"avalanche", "ball_pit", "break_shot", "driving_range", "heap", "terrain_3d"}
"""Bundled scenes of many balls: filling them and their solvers' kernels take seconds (slow tier)."""


@pytest.mark.parametrize(
    "path",
    [pytest.param(p, marks=pytest.mark.slow) if p.stem in MANY_BALLS else p for p in sorted(SCENES.glob("*.toml"))],
    ids=lambda p: p.stem,
)
def test_every_scene_loads_and_runs(path):
    scene = tg.load_scene(path)
    assert scene.description
    sim = tg.Simulation(scene)
    x0 = sim.x
    sim.run(steps=20)
    assert np.all(np.isfinite(sim.x)) and sim.t == pytest.approx(20 * scene.world.dt)
    assert np.any(sim.x != x0)  # something moves in every scene
    if scene.launch is not None:
        res = tg.sweep(scene)
        assert np.all(res.flight.landed)


background.declare("sweep-f32", lambda _: (cli("sweep", "lab_turbulent", "--angles", "36.6", "--precision", "f32"), {}))


@pytest.mark.background("sweep-f32")
def test_f32_precision_meets_a_looser_accuracy(background_runs):
    # precision is chosen per process: run the CLI in f32 (another process, its own ti.init)
    out = background_runs.result("sweep-f32")[0]
    assert out.returncode == 0, out.stderr
    carry = float(out.stdout.split("carry ")[1].split(" m")[0])
    assert carry == pytest.approx(212.243, abs=0.01)  # report Appendix A, f32 round-off ~1e-5


def test_plain_compile_restores_the_compiler_setting():
    # the sweep kernel compiles without Taichi's advanced passes (minutes less on first use); the
    # setting must come back for every other kernel, also when the launch inside fails
    import taichi as ti

    from ti_golf.runtime import ensure_init, plain_compile

    ensure_init()
    cfg = ti.lang.impl.current_cfg()
    before = cfg.advanced_optimization
    with pytest.raises(RuntimeError), plain_compile():
        assert cfg.advanced_optimization is False
        raise RuntimeError("a failed launch")
    assert cfg.advanced_optimization == before


@pytest.mark.slow
def test_dropped_vector_arrays_give_their_memory_back():
    # Taichi 1.7.4 frees only scalar ndarrays when Python drops them (taichi issue 8763);
    # runtime.free_every_ndarray frees vector ones too: 24 arrays of 24 MB, each widened a little
    # as the solver's pair tables are, leave the process no bigger than a few of them would
    # (collected as the solver collects them: a first fill leaves an array in a reference cycle)
    import gc

    import taichi as ti

    from ti_golf.bench.common import _rss_bytes
    from ti_golf.runtime import ensure_init, release_freed_memory

    ensure_init()
    table = ti.types.vector(5, ti.f64)
    before = _rss_bytes()
    for width in range(24):
        a = ti.ndarray(table, (100_000 + 1000 * width, 6))  # 24 MB, a little more each time
        a.fill(1.0)  # touch every page
        del a
        gc.collect()
    release_freed_memory()
    assert _rss_bytes() - before < 3 * 24e6


def test_dropped_arrays_are_collected_only_when_a_cycle_keeps_one(monkeypatch):
    # the solver frees its old tables before it allocates larger ones (runtime.free_dropped_arrays);
    # a full collection costs tens of milliseconds in a process that has built many kernels, and
    # a pour's pair tables grow a hundred times, so it runs only when a dropped array outlived its
    # last reference (kept by a reference cycle, as Taichi's compile context keeps the arrays a
    # kernel was compiled with)
    import gc

    import taichi as ti

    from ti_golf import runtime

    runtime.ensure_init()
    real, collections = gc.collect, []
    monkeypatch.setattr(gc, "collect", lambda *a: collections.append(a) or real(*a))
    gc.disable()  # (no automatic collection between the lines below)
    try:
        alone = ti.ndarray(ti.f64, 10)
        dropped = runtime.watch(alone, None)
        del alone
        runtime.free_dropped_arrays(dropped)
        assert collections == [] and dropped[0]() is None  # freed with its last reference
        cycled = ti.ndarray(ti.f64, 10)
        holder: list = [cycled]
        holder.append(holder)
        dropped = runtime.watch(cycled)
        del cycled, holder
        assert dropped[0]() is not None  # kept by the cycle
        runtime.free_dropped_arrays(dropped)
        assert len(collections) == 1 and dropped[0]() is None
        runtime.free_dropped_arrays()  # nothing watched: always a collection
        assert len(collections) == 2
    finally:
        gc.enable()


def test_a_putt_is_not_a_flight_but_a_lob_is():
    # carry, apex and landing describe a ball that leaves the ground: a putt (launch angle 0) rolls
    # over the green and must not report a landing at t = 0 with zero carry; a lob from the same
    # spot (45°, 6 m/s) flies: its carry is the range v0²/g in vacuo (3.67 m), shortened by less
    # than 5 % by the drag at these speeds
    putt = tg.Simulation.from_scene("putting_green")
    putt.run(t=1.0)
    assert not putt.flight().landed[0] and np.isnan(putt.flight().carry[0])
    lob = tg.Simulation.from_scene("putting_green", ["launch.angle_deg=45", "launch.speed=6"])
    lob.run(t=2.0)
    f = lob.flight()
    assert f.landed[0] and 0.95 * 6.0**2 / 9.81 < f.carry[0] < 6.0**2 / 9.81


def test_init_refuses_to_change_a_started_runtime():
    # Taichi cannot switch backend, precision or debug checks in a running process: a second
    # init that asks for another must say so, not return the running one as if it had obeyed
    # (importing ti_golf.solvers.solver starts the runtime with the defaults; the tests start it first)
    info = tg.init()
    assert tg.init() is info
    with pytest.raises(RuntimeError, match="debug off"):
        tg.init(debug=True)
    with pytest.raises(RuntimeError, match="start a new process"):
        tg.init(precision="f32" if info.precision == "f64" else "f64")


def test_cuda_runs_with_matrices_scalarised_and_the_cpu_as_it_always_has():
    # Taichi 1.7.4's CUDA code for the flight's lane matrices stopped the first flight kernel with
    # CUDA_ERROR_MISALIGNED_ADDRESS on an H200; scalarised, it ran and gave the CPU's carries
    # (docs/solvers.md, "Few balls and backends"). No GPU here: the options are what the runtime asks for.
    from ti_golf.runtime import init_options

    assert init_options("cuda", "f64")["force_scalarize_matrix"]
    assert init_options("gpu", "f32")["force_scalarize_matrix"]
    assert not init_options("cpu", "f64")["force_scalarize_matrix"]
    assert init_options("cpu", "f64", debug=True)["debug"]


def test_outputs_are_written_whole_or_not_at_all(tmp_path, monkeypatch):
    # a run's NPZ and a sweep's CSV go to a temporary file renamed into place: a failure while
    # writing leaves the previous file as it was and no partial or temporary file behind
    sim = tg.Simulation.from_scene("lab_vacuum")
    sim.run(steps=10)
    sim.save(tmp_path / "run")  # .npz is added, as np.savez names its files
    with np.load(tmp_path / "run.npz") as d:
        np.testing.assert_array_equal(d["x"], sim.x)
    sim.run(steps=10)

    def broken(*args, **kwargs):
        raise OSError("disk full")

    monkeypatch.setattr(np, "savez", broken)
    with pytest.raises(OSError, match="disk full"):
        sim.save(tmp_path / "run.npz")
    monkeypatch.undo()
    with np.load(tmp_path / "run.npz") as d:
        assert d["t"] == pytest.approx(10 * sim.dt)  # the first save, intact
    res = tg.sweep("lab_vacuum", angles_deg=[30.0, 45.0])
    res.to_csv(tmp_path / "s.csv")
    text = (tmp_path / "s.csv").read_text()
    monkeypatch.setattr("ti_golf.golf.sweep.csv.writer", broken)
    with pytest.raises(OSError):
        res.to_csv(tmp_path / "s.csv")
    assert (tmp_path / "s.csv").read_text() == text
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.npz", "s.csv"]
    mask = os.umask(0o022)
    os.umask(mask)
    assert (tmp_path / "s.csv").stat().st_mode & 0o777 == 0o666 & ~mask  # as any file written


def test_a_scene_too_big_for_the_memory_is_refused_before_any_ball_is_made(tmp_path, monkeypatch):
    # 27 million balls at 2 KiB each need 51.5 GiB: refused naming the file, the block, the bytes
    # needed and the bytes available, before numpy or Taichi allocate anything
    from ti_golf.sim import given, simulation

    path = tmp_path / "big.toml"
    path.write_text("[[blocks]]\ncount = [300, 300, 300]\n[world]\ncollisions = true\n", encoding="utf-8")
    scene = tg.load_scene(path)
    monkeypatch.setattr(given, "available_memory", lambda: 24 * 2**30)
    monkeypatch.setattr(simulation, "build_balls", lambda s: pytest.fail("balls made"))
    with pytest.raises(tg.ConfigError) as err:
        tg.Simulation(scene)
    text = str(err.value)
    assert text.startswith(str(path)) and "blocks[0]" in text, text
    assert "27,000,000 balls" in text and "51.5 GiB" in text and "24.0 GiB available" in text, text


def test_a_sweep_grid_too_big_for_the_memory_is_refused_before_it_is_made(monkeypatch):
    # 901 angles × 7,901 speeds: 7.1 million launches at 1 KiB need 6.8 GiB; numpy's MemoryError
    # of the grid was all a user saw of a grid far greater than the memory
    from ti_golf.golf import sweep as sweep_module

    monkeypatch.setattr(sweep_module, "available_memory", lambda: 2 * 2**30)
    monkeypatch.setattr(sweep_module.np, "meshgrid", lambda *a, **k: pytest.fail("grid made"))
    with pytest.raises(tg.ConfigError, match=r"7,118,801 launches.*6.8 GiB.*2.0 GiB available") as err:
        tg.sweep("lab_turbulent", angles_deg="0:90:0.1", speeds="1:80:0.01")
    assert err.value.source == "angles_deg"


def test_arguments_of_the_wrong_kind_are_refused_naming_the_argument():
    # each of these, tried as a new user would, raised Python's or numpy's own error from inside
    # the package ("'int' object is not iterable"), or ran on something else than was meant
    # (to_rest="no" rolled the balls out, angles_deg=[True] flew at 1°, an unknown `until` meant
    # "landed", ball(-1) and ball(5) raised different errors)
    sim = tg.Simulation("break_shot")
    cases = [
        (lambda: tg.load_scene("lab_vacuum", 3), TypeError, "overrides must be"),
        (lambda: tg.load_scene(b"lab_vacuum"), TypeError, "path must be"),
        (lambda: tg.Simulation(""), tg.ConfigError, "no scene given"),
        (lambda: sim.set(None), TypeError, "changes must be"),
        (lambda: sim.set(5, 1), TypeError, r"set\(key, value\) takes a key"),
        (lambda: sim.set_ball(0, v="fast"), ValueError, r"v of balls \[0\] must be real numbers"),
        (lambda: sim.unfinished("xyz"), ValueError, "until must be 'rest' or 'landed'"),
        (lambda: sim.ball(-1), IndexError, "ids 0 … 15"),
        (lambda: sim.ball(16), IndexError, "ids 0 … 15"),
        (lambda: tg.sweep("lab_turbulent", angles_deg=[30], to_rest="no"), TypeError, "to_rest must be"),
        (lambda: tg.sweep("lab_turbulent", angles_deg=[True]), tg.ConfigError, "flat list of numbers"),
        (lambda: tg.sweep("lab_turbulent", angles_deg=[[30, 40]]), tg.ConfigError, "flat list of numbers"),
    ]
    for call, error, match in cases:
        with pytest.raises(error, match=match):
            call()
    sim.set_ball([0, 1], v=[1.0, 0.0, 0.0])  # one vector for every ball given
    np.testing.assert_array_equal(sim.v[:2], [[1.0, 0.0, 0.0]] * 2)


def test_balls_given_where_no_contact_can_sort_them_out_are_refused():
    # tried as a new user would: a ball 5 m under the ground came to rest inside it, one 2,000 km
    # away (past the scene files' 1,000 km, where the grid's cell coordinates overflow) was taken,
    # and two balls at one point stayed there, wholly overlapping
    bin_scene = tg.load_scene("break_shot", ["world.ground=false"])  # (no planes either: open space)
    cases = [
        ("lab_vacuum", {"x": [[0, -5, 0]]}, r"x of ball 0 \(\[0.0, -5.0, 0.0\]\) lies 5 m inside the ground"),
        ("lab_vacuum", {"x": [[0, -0.03, 0]], "radius": 0.02}, r"lies 0.03 m inside the ground, the whole ball"),
        ("lab_vacuum", {"x": [[0, 2e6, 0]]}, r"x must be within ±1e\+06 m"),
        ("break_shot", {"x": [[0, 1, 0], [1, 1, 0], [0, 1, 0]]}, r"x of balls 0 and 2 is one point, \[0.0, 1.0, 0.0\]"),
    ]
    for scene, given, match in cases:
        with pytest.raises(ValueError, match=match):
            tg.Simulation(scene, **given)
    tg.Simulation("lab_vacuum", x=[[0, -0.01, 0]], radius=0.02)  # partly in the ground: pushed out (B.18)
    tg.Simulation(bin_scene, x=[[0, -5, 0], [1, -5, 0]])  # nothing solid: anywhere
    tg.Simulation(tg.load_scene("break_shot", ["world.collisions=false"]), x=[[0, 1, 0]] * 2)  # shots: never meeting
    sim = tg.Simulation("lab_vacuum", x=[[0, 1, 0]], v=[[2000.0, 0, 0]])  # (a ball falls that fast in vacuum)
    with pytest.raises(ValueError, match=r"v must be within ±2.99792e\+08 m/s on each axis, the speed of light"):
        sim.v = [[1e300, 2.0, 3.0]]  # (its drag's step check said "world.dt must be at most 0 s")
    with pytest.raises(ValueError, match=r"x must be within ±1e\+06 m"):
        sim.x = [[3e6, 0.0, 0.0]]
    with pytest.raises(ValueError, match=r"x of balls \[0\] must be within ±1e\+06 m"):
        sim.set_ball(0, x=[0, 0, -2e6])


def test_a_scene_changed_in_python_is_checked_as_a_scene_file_is():
    # dataclasses.replace(scene, world=replace(scene.world, dt=-0.01)) ran backwards in time, and
    # C_D = NaN failed later as a SimulationError about world.dt: each value set and read is checked
    # as the loader checks it, naming the argument and the key
    from dataclasses import replace

    s = tg.load_scene("lab_vacuum")
    for bad, match in (
        (replace(s, world=replace(s.world, dt=-0.01)), r"^scene: key 'world.dt' must be in \(0, "),
        (replace(s, air=replace(s.air, C_D=float("nan"))), r"^scene: key 'air.C_D' must be a finite number"),
        (replace(s, contact=replace(s.contact, e=1.5)), r"^scene: key 'contact.e' must be in \[0, 1\]"),
    ):
        with pytest.raises(tg.ConfigError, match=match):
            tg.Simulation(bad)
        with pytest.raises(tg.ConfigError, match=match):
            tg.sweep(bad, angles_deg=[30.0])
    tg.Simulation(replace(s, world=replace(s.world, dt=5e-4)))  # a change within range is taken


def test_every_public_name_is_in_the_api_reference():
    # the docs' API page (docs/api.md) renders each name of ti_golf.__all__ from its docstring
    # (`::: ti_golf.NAME`, mkdocstrings) or, for the status constants, lists it in a table; every
    # class and function among them has a docstring to render
    text = (ROOT / "docs" / "api.md").read_text(encoding="utf-8")
    for name in tg.__all__:
        assert f"::: ti_golf.{name}\n" in text or f"| `ti_golf.{name}` |" in text, name
        obj = getattr(tg, name)
        if callable(obj):
            assert (obj.__doc__ or "").strip(), name


@pytest.mark.parametrize(
    "call, error, message",
    [
        (lambda s: s.run(steps=2, record_every=-1), ValueError, "record_every must be a whole number >= 0 (got -1)"),
        (lambda s: s.run(steps=2, record_every=0.5), ValueError, "record_every must be a whole number >= 0 (got 0.5)"),
        (lambda s: s.run(steps=2, every=-1, on_every=print), ValueError, "every must be a whole number >= 0"),
        (lambda s: s.run(steps=2, on_every=print), ValueError, "every and on_every go together"),
        (lambda s: s.run(t=0.1, steps=3), ValueError, "give t or steps, not both"),
        (lambda s: s.run(t=-1), ValueError, "t must be a number of seconds >= 0 (got -1)"),
        (lambda s: s.run(t=1e300), ValueError, "t must be at most 1e+09 s (got 1e+300)"),  # (it ran on for ever)
        (lambda s: s.run(steps=10**14), ValueError, "steps must be at most 1e+11, 1e+09 s of steps"),
        (lambda s: s.run(steps=2.5), ValueError, "steps must be a whole number >= 0 (got 2.5)"),
        (lambda s: s.step(-3), ValueError, "n must be a whole number >= 0 (got -3)"),
        (lambda s: s.step(1.5), ValueError, "n must be a whole number >= 0 (got 1.5)"),
        (lambda s: s.step("2"), ValueError, "n must be a whole number >= 0 (got '2')"),
    ],
)
def test_a_count_or_time_a_run_cannot_take_is_refused_and_changes_nothing(call, error, message):
    # negative or fractional counts hung the run (a chunk of 0 steps) or moved the clock without a step
    sim = tg.Simulation("lab_magnus")
    sim.step(2)
    with pytest.raises(error, match=re.escape(message)):
        call(sim)
    assert (sim.step_count, sim.t) == (2, pytest.approx(2 * sim.dt))


def test_balls_and_their_arrays_are_checked_against_each_other(tmp_path):
    scene = tg.load_scene("lab_magnus")
    with pytest.raises(ValueError, match="v given without x: the scene's balls come with their own"):
        tg.Simulation(scene, v=np.zeros((1, 3)))
    with pytest.raises(ValueError, match=re.escape("radius must be one number or one per ball, shape (2,)")):
        tg.Simulation(scene, x=np.zeros((2, 3)), radius=[0.02, 0.03, 0.04])
    with pytest.raises(ValueError, match=re.escape("x must have shape (N, 3) (got (0, 3))")):
        tg.Simulation(scene, x=np.zeros((0, 3)))
    with pytest.raises(TypeError, match="scene must be a Scene, a scene file's path or a bundled scene's name"):
        tg.Simulation(None)
    assert tg.Simulation("lab_magnus").scene == scene  # a name loads the scene
    sim = tg.Simulation(scene)
    with pytest.raises(ValueError, match="it is a folder"):
        sim.save(tmp_path)
    with pytest.raises(FileNotFoundError, match="does not exist"):
        sim.save(tmp_path / "no" / "run.npz")
    sim.save(tmp_path / "run")  # (.npz added, as numpy does) ...
    assert tg.Simulation.load(tmp_path / "run").t == sim.t  # ... and found again by the same name


def test_python_callers_get_the_checks_the_command_line_has(tmp_path):
    from ti_golf.golf.shots import shots
    from ti_golf.scene.launch_monitor import MonitorLaunch
    from ti_golf.study import run_study

    tour = tg.load_scene("tour_shot")
    with pytest.raises(ValueError, match=re.escape("launch speed must be in [0, 150] m/s (got -50)")):
        shots(tour, MonitorLaunch(-50.0, 16.1, 0.0, 700.0, 0.0))
    with pytest.raises(ValueError, match=re.escape("flight_dt must be in [1e-05, 0.05] s (got 0)")):
        shots(tour, MonitorLaunch(50.0, 16.1, 0.0, 700.0, 0.0), flight_dt=0)  # (it hung)
    res = tg.sweep("lab_turbulent", angles_deg=[30, 40], overrides={"world.t_max": 0.5})
    with pytest.raises(ValueError, match="no ball of the sweep landed"):
        res.best()  # (it was 0, a ball that never landed)
    assert tg.load_scene("lab_magnus", "air.C_D=0.3").air.C_D == 0.3  # one text, not its characters
    assert tg.load_scene("lab_magnus", {"air.wind": np.array([1.0, 0.0, 0.0])}).air.wind == (1.0, 0.0, 0.0)
    with pytest.raises(tg.ConfigError, match=re.escape("workers: must be a whole number in [1, ")):
        run_study("bag_weather", out=tmp_path / "out", workers=0)
    assert not (tmp_path / "out").exists()  # refused before its folder was made


def test_python_errors_name_the_arguments_and_the_command_line_its_options(capsys):
    # a Python caller gave overrides=, arch=, workers=: the errors name those, not --set, --arch
    # or --workers, which `ti-golf` names for the same mistakes
    with pytest.raises(tg.ConfigError) as info:
        tg.Simulation.from_scene("lab_magnus", overrides={"air.C_DD": 0.3})
    assert str(info.value).startswith("overrides: key 'air.C_DD' is not a scene key (did you mean 'air.C_D'?)")
    with pytest.raises(tg.ConfigError, match=r"did you mean 'air.C_D'\?"):  # (difflib's closest was C_M)
        tg.load_scene("lab_magnus", ["air.C_d=0.3"])
    with pytest.raises(tg.ConfigError, match="^arch: unknown backend 'tpu'"):
        tg.init(arch="tpu")
    assert main(["run", "lab_magnus", "--steps", "1", "--set", "air.C_DD=0.3"]) == 2
    assert "ti-golf: error: --set: key 'air.C_DD' is not a scene key" in capsys.readouterr().err
    assert main(["study", "bag_weather", "--workers", "0"]) == 2
    assert "ti-golf: error: --workers: must be a whole number in [1, " in capsys.readouterr().err


def test_a_run_until_rest_stops_at_the_same_step_whatever_it_records():
    # the checks of `until` fall every UNTIL_CHECK_S of simulated time: a run that records every 7
    # or 13 steps, or calls on_every, ends at the step and in the state of one that records nothing
    # (it stopped at the end of its recording chunk, so the saved state changed with --record-every),
    # at the same time to the last bit, and with the same landing time (each launch summed n·dt,
    # 19.35000000000014 s against 19.350000000000563 s)
    runs = []
    for record_every, every in ((0, 0), (7, 0), (13, 5)):
        sim = tg.Simulation.from_scene("lab_spin_decay")
        hook = {"every": every, "on_every": lambda s: None} if every else {}
        rec = sim.run(until="rest", record_every=record_every, **hook)
        assert len(rec.t) == (sim.step_count // record_every + 1 if record_every else 0)
        runs.append((sim.step_count, sim.t, sim.flight().flight_time, sim.x, sim.w, sim.status))
    assert runs[0][0] % round(UNTIL_CHECK_S / sim.dt) == 0 and (runs[0][5] == tg.AT_REST).all()
    for other in runs[1:]:
        assert other[0] == runs[0][0]
        for a, b in zip(other[1:], runs[0][1:]):
            np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize(
    "given, message",
    [
        ({"track": [True] * 5}, "track must be true or false, or one of them per ball, shape (2,)"),
        ({"track": np.ones((2, 2))}, "track must be true or false"),
        ({"track": "yes"}, "track must be true or false"),  # (was taken as true)
        ({"radius": "big"}, "radius must be one real number or one per ball, shape (2,) (got 'big')"),
        ({"x": [[0.0, 1.0, 0.0], [1.0, 1.0]]}, "x must be real numbers, shape (N, 3)"),
        ({"x": np.array([[0.0, 0.1, 0.0], [1.0, 0.1, 0.0]]) + 1j}, "x must be real numbers"),  # (parts dropped)
    ],
)
def test_balls_given_wrongly_are_one_error_naming_the_argument(given, message):
    # each ended in numpy's words (broadcast shapes, an element set with a sequence), or was taken
    # (a text as true, complex positions with their imaginary parts dropped and a warning)
    args = {"x": np.array([[0.0, 0.1, 0.0], [1.0, 0.1, 0.0]]), **given}
    with pytest.raises(ValueError) as info:
        tg.Simulation(tg.load_scene("break_shot"), **args)
    assert message in str(info.value) and "\n" not in str(info.value), str(info.value)


def test_the_golf_calls_take_what_the_command_line_takes_and_name_what_they_refuse():
    # sweep(angles_deg="30:42:0.5") ended in numpy's "could not convert string to float", shots()
    # of a scene's name in "'str' object has no attribute 'launch'", dispersion(n=2.5) flew 2 shots
    # and sim.ball(0.7) read ball 0
    from ti_golf.golf.dispersion import dispersion
    from ti_golf.golf.shots import shots
    from ti_golf.scene.launch_monitor import MonitorLaunch

    by_text = tg.sweep("lab_turbulent", angles_deg="36:37:0.5")
    np.testing.assert_array_equal(by_text.angle_deg, [36.0, 36.5, 37.0])
    np.testing.assert_array_equal(by_text.carry, tg.sweep("lab_turbulent", angles_deg=[36, 36.5, 37]).carry)
    with pytest.raises(
        tg.ConfigError, match=re.escape("angles_deg: must be a flat list of numbers or START:STOP:STEP")
    ):
        tg.sweep("lab_turbulent", angles_deg=[30, "a"])
    with pytest.raises(ValueError, match=re.escape("trajectories must be a whole number >= 0 (got 2.5)")):
        tg.sweep("lab_turbulent", trajectories=2.5)
    seven = MonitorLaunch(50.0, 16.1, 0.0, 700.0, 0.0)
    assert shots("tour_shot", seven).carry == shots(tg.load_scene("tour_shot"), seven).carry
    spread = MonitorLaunch(1.0, 1.0, 1.0, 10.0, 1.0)
    for given, message in (({"n": 2.5}, "n must be a whole number >= 0 (got 2.5)"), ({"seed": -1}, "seed must be")):
        with pytest.raises(ValueError, match=re.escape(message)):
            dispersion("tour_shot", seven, spread, **{"n": 20, **given})
    sim = tg.Simulation("break_shot")
    with pytest.raises(ValueError, match=re.escape("ball must be a whole number >= 0 (got 0.7)")):
        sim.ball(0.7)
    np.testing.assert_array_equal(sim.ball(np.int64(1))[0], sim.x[1])


def test_a_run_whose_process_ignores_ctrl_c_takes_every_step():
    # A process that ignores SIGINT (nohup, `trap '' INT`, a script's background job) must not
    # stop its steps on one: the steps held the signal, stopped early, and raised it again under
    # SIG_IGN, so nothing happened and the run counted steps it never took (t = 3.845 s of a
    # --t 4 run, saved as whole). SIGINTs sent every 5 ms through 300 parallel collision steps
    import signal
    import threading

    from ti_golf.solvers import CollisionSolver

    sim = tg.Simulation.from_scene("break_shot")
    sim.solver = CollisionSolver(sim.model, serial=False)  # (one launch a step: a held signal stops between steps)
    sim.run(steps=2)  # (compiled)
    done = threading.Event()

    def pester() -> None:
        while not done.wait(0.005):
            os.kill(os.getpid(), signal.SIGINT)

    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    sender = threading.Thread(target=pester)
    try:
        sender.start()
        sim.run(steps=300)
    finally:
        done.set()
        sender.join()
        signal.signal(signal.SIGINT, previous)
    assert round(sim.t / sim.dt) == 302


def test_a_run_too_many_steps_long_is_refused_and_a_tiny_step_runs_in_bounded_calls(monkeypatch):
    # world.dt = 1e-300 made `run --t 1` pass 1e300 steps to a kernel (a Taichi TypeError) and
    # world.dt = 1e-11 a launch of 5e9 steps that Ctrl-C waited minutes for
    from ti_golf.sim import simulation

    with pytest.raises(tg.ConfigError, match=r"'world.dt' = 1e-300 s makes a run of 1 s 1e\+300 steps; at most 1e\+12"):
        tg.Simulation.from_scene("lab_vacuum", ["world.dt=1e-300"]).run(t=1.0)
    with pytest.raises(ValueError, match=r"steps must be at most 1e\+12"):
        tg.Simulation.from_scene("lab_vacuum", ["world.dt=1e-20"]).run(steps=2 * 10**12)
    calls = []
    sim = tg.Simulation.from_scene("lab_vacuum", ["world.dt=1e-9"])
    real = simulation.kernels.advance
    monkeypatch.setattr(simulation.kernels, "advance", lambda *a: calls.append(a[3]) or real(*a))
    sim.run(t=5e-4)
    assert calls == [simulation.STEPS_PER_CALL] * 5 and round(sim.t / sim.dt) == 500_000


def test_a_run_saved_under_another_suffix_or_no_name_is_refused(tmp_path):
    # save("x.txt") wrote x.txt.npz, which load("x.txt") then did not find; save("") called the
    # empty name a folder
    sim = tg.Simulation.from_scene("lab_vacuum")
    with pytest.raises(ValueError, match=r"'.*x.txt': a saved run is an .npz file; end its name in .npz"):
        sim.save(tmp_path / "x.txt")
    with pytest.raises(ValueError, match="it needs a file name"):
        sim.save("")
    assert list(tmp_path.iterdir()) == []
