"""The report's lab workflow (section 2.2): simulate, change parameters or the state, continue;
go back to t0; save a run and continue it later, bit for bit as if it had never stopped."""

from __future__ import annotations

import json
import os
import signal

import numpy as np
import pytest
from conftest import ON_CPU, SERIAL_OR_PARALLEL, assert_same_state, sim_state

import ti_golf as tg
from ti_golf.bench.pit import pit_scene
from ti_golf.cli import main
from ti_golf.physics import kernels
from ti_golf.scene.document import scene_document, with_changes
from ti_golf.solvers import CollisionSolver, collide
from ti_golf.solvers.stepping import RELIST_MAX_BALLS


def _continued(make, t1: float, t2: float, path):
    """(a run of t1 + t2 unbroken, a run of t1 saved to ``path`` and loaded into a new simulation
    that runs t2 more)."""
    whole = make()
    whole.run(t=t1 + t2)
    first = make()
    first.run(t=t1)
    first.save(path)
    second = tg.Simulation.load(path)
    second.run(t=t2)
    return whole, second


# ----------------------------------------------------------------------------------------------
# save and load
# ----------------------------------------------------------------------------------------------
def test_a_flight_saved_mid_air_lands_as_if_it_never_stopped(tmp_path):
    # saved at 2 s, before the apex; continued through the landing, the bounces and the roll: the
    # state and the flight record (carry, apex, landing) are those of the unbroken run, bit for bit
    whole, resumed = _continued(lambda: tg.Simulation.from_scene("lab_spin_decay"), 2.0, 4.0, tmp_path / "a.npz")
    assert whole.flight().landed.all()  # the landing happened after the save
    assert_same_state(whole, resumed)
    for name in ("carry", "apex", "flight_time", "landing_angle", "landing_speed"):
        np.testing.assert_array_equal(getattr(whole.flight(), name), getattr(resumed.flight(), name), err_msg=name)


def test_the_break_shot_saved_during_the_break_goes_on_bit_for_bit(tmp_path):
    # Jacobi sweeps with resting impulses carried from step to step (contact.solver = "jacobi"),
    # saved 40 ms into the break, while the rack's balls are in contact
    whole, resumed = _continued(lambda: tg.Simulation.from_scene("break_shot"), 0.2, 0.1, tmp_path / "b.npz")
    assert np.linalg.norm(whole.v[1:], axis=1).max() > 0.5  # the rack has broken
    assert resumed.solver.rebuilds == whole.solver.rebuilds
    assert_same_state(whole, resumed)


def _columns_scene() -> tg.Scene:
    """27 balls in 3 × 3 columns of 3 on the ground (Gauss–Seidel sweeps, quickly asleep) and a
    ball rolling into them at 1 m/s, which arrives after 0.06 s; no air."""
    r = 0.02
    balls = [{"position": [2 * r * i, r + 2 * r * k, 2 * r * j]} for i in range(3) for j in range(3) for k in range(3)]
    balls.append({"position": [-0.1, r, 2 * r], "velocity": [1.0, 0.0, 0.0]})
    data = {
        "air": {"rho": 0.0},
        "world": {"dt": 0.001, "t_rest": 0.03},
        "contact": {"solver": "gauss_seidel", "e": 0.5, "mu": 0.4},
        "balls": balls,
    }
    return tg.load_scene(None, data=data)


@pytest.mark.slow
@SERIAL_OR_PARALLEL
def test_a_pile_saved_asleep_wakes_as_if_it_never_stopped(serial, tmp_path):
    # Gauss-Seidel sweeps with each pair's friction impulse carried, balls put to sleep, the
    # storage order of a reordered pile (parallel): saved while the columns sleep, continued
    # through the rolling ball's impact
    scene = _columns_scene()

    def make():
        sim = tg.Simulation(scene)
        sim.solver = CollisionSolver(sim.model, serial=serial, reorder=not serial)
        return sim

    saved = tmp_path / "p.npz"
    whole, resumed = _continued(make, 0.07, 0.03, saved)  # (woken just after 0.07 s; in parallel asleep by 0.11 s)
    with np.load(saved) as d:
        assert np.count_nonzero(d["status"] == tg.AT_REST) == 27  # the columns sleep at the save
        assert ("order" in d.files) == (not serial)
    assert np.count_nonzero(whole.status == tg.AT_REST) < 27  # and are woken after it
    assert (resumed.solver.serial, resumed.solver.reorder) == (serial, not serial)
    assert_same_state(whole, resumed)


@pytest.mark.skipif(not ON_CPU, reason="serial stepping runs on the CPU only")
def test_a_pour_saved_serially_goes_on_in_parallel_bit_for_bit(tmp_path, monkeypatch):
    # a pile of more than RELIST_MAX_BALLS balls steps serially on the CPU with the parallel
    # step's lists, tables and sweep order (solver.relists false): a run saved so while the pour
    # lands goes on where only the parallel step runs (a GPU, here the CPU taken for one when the
    # run is read) as the serial steps would have, without a rebuild of its lists at the load
    from ti_golf.sim import saved_run

    scene, _ = pit_scene(RELIST_MAX_BALLS + 100)
    first = tg.Simulation(scene)
    first.run(t=0.25)
    while first.solver.rebuild_due:  # (saved where the lists still hold: a rebuild at the load would show)
        first.run(steps=1)
    first.save(tmp_path / "pour.npz")
    assert first.solver.serial and not first.solver.relists
    monkeypatch.setattr(saved_run, "on_cpu", lambda: False)
    resumed = tg.Simulation.load(tmp_path / "pour.npz")
    assert not resumed.solver.serial
    rebuilds = resumed.solver.rebuilds
    resumed.run(steps=1)
    assert resumed.solver.rebuilds == rebuilds
    resumed.run(steps=99)
    whole = tg.Simulation(scene)
    whole.run(steps=resumed.state.steps)
    assert_same_state(whole, resumed)


def _pairs_in_rows(path) -> None:
    """Rewrite the solver's arrays of the saved run at ``path`` as solvers saved them until
    2026-11-26: the pair tables with a row per ball as wide as the longest list, each list's
    length in ``n_upper`` (now the pairs lie ball after ball, from ``first``), the sweep's table
    a 5-vector per pair in f64 (now a row of 5 columns in the float type, or, Gauss–Seidel, 3 in f32), one table of friction impulses, and a row
    of surface impulses for every ball (now only for the balls near a surface, from
    ``surface_start``); and, until 2026-11-27, the lower lists in a table stored by column, as
    wide as the longest, each list's length in ``n_lower`` (now the links lie ball after ball,
    from ``lower_first``), the two tables' widths in ``capacity``."""
    with np.load(path) as d:
        data = dict(d)
    meta = json.loads(str(data["run"]))
    solver = meta["solver"]
    first = data.pop("solver.first")
    n_upper = np.diff(first).astype(np.int32)
    width = data["solver.upper"].shape[1]
    listed = np.arange(width)[None, :] < n_upper[:, None]

    def rows(flat):
        out = np.zeros((len(n_upper), width, *flat.shape[1:]), flat.dtype)
        out[listed] = flat[: first[-1]]
        return out

    data["solver.n_upper"], data["solver.lam"], data["solver.friction"] = (
        n_upper,
        rows(data["solver.lam"]),
        rows(data["solver.friction"]),  # (Gauss–Seidel: one per pair)
    )
    solver["elements"]["n_upper"] = solver["elements"].pop("first")
    del solver["values"]["pair_capacity"], solver["scratch"]["stash_first"], solver["scratch"]["pair_chunk"]
    solver["scratch"]["impulse"] = [[len(n_upper), width], [5], "float64"]  # a 5-vector per pair, in f64 either way
    solver["scratch"].pop("friction_back", None)
    solver["values"].pop("friction_back", None)
    start, impulse = data.pop("solver.surface_start"), data.pop("solver.surface_impulse")
    has = np.diff(start) > 0
    every = np.zeros((len(has), *impulse.shape[1:]), impulse.dtype)
    every[has] = impulse[start[:-1][has]]
    data["solver.lam_plane"] = every[..., 0]
    friction = every[..., 1:]
    data["solver.friction_plane"] = friction if friction.any() else np.zeros((1, 1, 3), np.float32)  # (Jacobi)
    for name in ("surface_start", "surface_impulse"):
        del solver["elements"][name]
    solver["elements"].update(lam_plane=[], friction_plane=[3])
    solver["scratch"].pop("surface_impulse_back", None)
    solver["values"].pop("surface_impulse_back", None)
    lower_first, links = data.pop("solver.lower_first"), data.pop("solver.lower")
    n_lower = np.diff(lower_first).astype(np.int32)
    table = np.zeros((max(1, int(n_lower.max())), len(n_lower)), np.int32)
    table[
        np.arange(lower_first[-1]) - np.repeat(lower_first[:-1], n_lower), np.repeat(np.arange(len(n_lower)), n_lower)
    ] = links[: lower_first[-1]]
    data["solver.lower"], data["solver.n_lower"] = table, n_lower
    solver["elements"]["n_lower"] = solver["elements"].pop("lower_first")
    solver["values"]["capacity"] = [width, table.shape[0]]
    data["run"] = np.array(json.dumps(meta))
    np.savez(path, **data)


@pytest.mark.slow
@SERIAL_OR_PARALLEL
def test_a_run_saved_with_the_pair_tables_in_rows_still_continues_bit_for_bit(serial, tmp_path):
    # a solver saved before its pair tables were laid out ball after ball (see _pairs_in_rows) is
    # given its pairs and their impulses in the new layout, and steps on as the unbroken run does
    def make():
        sim = tg.Simulation(_columns_scene())
        sim.solver = CollisionSolver(sim.model, serial=serial, reorder=not serial)
        return sim

    whole = make()
    whole.run(t=0.17)
    first = make()
    first.run(t=0.07)
    first.save(tmp_path / "p.npz")
    _pairs_in_rows(tmp_path / "p.npz")
    resumed = tg.Simulation.load(tmp_path / "p.npz")
    assert hasattr(resumed.solver, "n_upper") is False and resumed.solver.pair_capacity >= 27
    resumed.run(t=0.1)
    assert_same_state(whole, resumed)


def test_a_loaded_run_keeps_its_changed_parameters_and_resets_to_its_t0(tmp_path):
    sim = tg.Simulation.from_scene("break_shot")
    sim.run(t=0.05)
    sim.set({"contact.e": 0.6, "contact.mu": 0.3})
    sim.save(tmp_path / "r")  # .npz added
    loaded = tg.Simulation.load(tmp_path / "r.npz")
    assert loaded.scene == sim.scene and loaded.scene.contact.e == 0.6
    loaded.reset()
    fresh = tg.Simulation(sim.scene)
    assert_same_state(loaded, fresh)


def test_balls_given_as_arrays_are_saved_for_reset(tmp_path):
    scene = tg.load_scene("lab_vacuum", ["world.collisions=false"])
    x = np.array([[0.0, 1.0, 0.0], [5.0, 2.0, 0.0]])
    v = np.array([[10.0, 10.0, 0.0], [0.0, 5.0, 1.0]])
    sim = tg.Simulation(scene, x=x, v=v, radius=[0.02, 0.03], track=[True, False])
    x[:] = 0.0  # the simulation keeps its own copy
    sim.run(t=0.5)
    sim.save(tmp_path / "g.npz")
    loaded = tg.Simulation.load(tmp_path / "g.npz")
    assert_same_state(loaded, sim)
    loaded.reset()
    assert_same_state(
        loaded,
        tg.Simulation(scene, x=[[0.0, 1.0, 0.0], [5.0, 2.0, 0.0]], v=v, radius=[0.02, 0.03], track=[True, False]),
    )
    unkept = tg.Simulation(scene, x=x, keep_initial=False)  # a big pile that is never reset
    assert unkept.initial is None
    unkept.save(tmp_path / "u.npz")
    for sim in (unkept, tg.Simulation.load(tmp_path / "u.npz")):
        with pytest.raises(ValueError, match="keep_initial=False"):
            sim.reset()


def test_a_file_that_cannot_be_continued_is_refused_in_one_line(tmp_path):
    old = tmp_path / "old.npz"  # as save() wrote it before runs could be continued
    np.savez(old, x=np.zeros((1, 3)), v=np.zeros((1, 3)), w=np.zeros((1, 3)), t=np.float64(1.0))
    with pytest.raises(tg.ConfigError, match="final state only"):
        tg.Simulation.load(old)
    with pytest.raises(tg.ConfigError, match="file not found"):
        tg.Simulation.load(tmp_path / "missing.npz")
    (tmp_path / "text.npz").write_text("not a zip")
    with pytest.raises(tg.ConfigError, match="is not a run saved by ti-golf"):
        tg.Simulation.load(tmp_path / "text.npz")
    sim = tg.Simulation.from_scene("lab_vacuum")
    sim.save(tmp_path / "f32.npz")
    with np.load(tmp_path / "f32.npz") as d:
        data = {k: d[k] for k in d.files}
    meta = json.loads(str(data["run"]))
    meta["precision"] = "f32"
    data["run"] = np.array(json.dumps(meta))
    np.savez(tmp_path / "f32.npz", **data)
    with pytest.raises(tg.ConfigError, match=r"saved in f32 precision .* \(--precision f32\)"):
        tg.Simulation.load(tmp_path / "f32.npz")


def test_every_bundled_scene_is_written_back_as_it_loads():
    # a saved run carries its scene as a document; loaded again it is the same scene
    from ti_golf.bench.pit import pit_scene
    from ti_golf.scene.loader import scenes_dir

    scenes = [tg.load_scene(p) for p in sorted(scenes_dir().glob("*.toml"))] + [pit_scene(500)[0]]
    tilted = tg.load_scene(None, data={"planes": [{"normal": [0.3, 1.0, 0.2]}, {"normal": [-1.0, 2.0, 7.0]}]})
    for scene in scenes + [tilted]:
        assert with_changes(scene, {}) == scene, scene.name
        assert json.loads(json.dumps(scene_document(scene))) == scene_document(scene)


# ----------------------------------------------------------------------------------------------
# change parameters and continue
# ----------------------------------------------------------------------------------------------
def test_drag_turned_off_mid_flight_leaves_the_vacuum_parabola():
    # from the state at 1 s, with C_D = 0 (no Magnus, no spin decay in this scene) the ball
    # falls freely: x(T) = x0 + v0·T + g·T²/2, which RK4 integrates exactly (a quadratic), here
    # with half the time step
    sim = tg.Simulation.from_scene("lab_turbulent", ["world.ground=false"])
    sim.run(t=1.0)
    x0, v0 = sim.x[0], sim.v[0]
    sim.set({"air.C_D": 0.0, "world.dt": 5e-4})
    assert sim.dt == 5e-4 and sim.scene.air.C_D == 0.0
    sim.run(t=2.0)
    assert sim.step_count == 100 + 4000
    g = np.array(sim.scene.world.gravity)
    np.testing.assert_allclose(sim.x[0], x0 + 2.0 * v0 + 0.5 * g * 2.0**2, rtol=0, atol=1e-9)
    np.testing.assert_allclose(sim.v[0], v0 + 2.0 * g, rtol=0, atol=1e-11)


def test_continuing_with_changed_parameters_equals_a_new_run_of_the_changed_scene():
    # one ball: nothing is carried but x, v, ω, so going on after set() is a new simulation of
    # the changed scene started from the same state, bit for bit
    sim = tg.Simulation.from_scene("lab_magnus")
    sim.run(t=1.5)
    changes = {"air.wind": [-5.0, 0.0, 2.0], "air.C_D": 0.2, "world.integrator": "semi_implicit"}
    fresh = tg.Simulation(with_changes(sim.scene, changes), x=sim.x, v=sim.v, w=sim.w)
    sim.set(changes)
    sim.run(t=1.0)
    fresh.run(t=1.0)
    for name in ("x", "v", "w"):
        np.testing.assert_array_equal(getattr(sim, name), getattr(fresh, name))


def test_set_checks_values_as_the_scene_loader_does():
    sim = tg.Simulation.from_scene("lab_turbulent")
    before = sim.scene
    for changes in ({"air.C_D": -1.0}, {"air.CD": 0.2}, {"world.dt": "fast"}, {"contact.e": 1.5}):
        with pytest.raises(tg.ConfigError) as got:
            sim.set(changes)
        with pytest.raises(tg.ConfigError) as loader:
            tg.load_scene("lab_turbulent", changes)
        assert str(got.value) == str(loader.value)
    with pytest.raises(tg.ConfigError) as got:  # a key the scene's settings leave unread
        tg.Simulation.from_scene("tour_shot").set("air.C_D", 0.2)
    assert 'air.model = "lab"' in str(got.value)
    for key, value in (("sweep.angles", [10, 20]), ("world.t_max", 9.0), ("description", "a shot")):
        with pytest.raises(tg.ConfigError, match="has no effect on a simulation"):
            sim.set(key, value)
    assert sim.scene == before  # nothing changed


def test_a_change_that_leaves_a_key_unread_drops_it():
    # lab_magnus gives C_D and C_M: the spin-ratio model reads neither, so they go
    sim = tg.Simulation.from_scene("lab_magnus")
    sim.set("air.model=spin_ratio")
    assert sim.scene.air.model == "spin_ratio" and sim.scene.air.C_M == tg.load_scene(None, data={}).air.C_M


def test_weather_and_a_density_over_it_survive_later_changes():
    # the weather gives ρ and μ (the loader refuses ρ beside it): the scene keeps one source of each
    scene = with_changes(tg.load_scene("tour_shot"), {"air.altitude": 1600.0})
    weather = scene.air.rho, scene.air.viscosity
    assert weather[0] < 1.1  # thinner air at 1,600 m (tests/test_weather.py has the figures)
    again = with_changes(scene, {"air.spin_decay": 2.5e-5})
    assert (again.air.rho, again.air.viscosity, again.air.altitude) == (*weather, 1600.0)
    dense = with_changes(scene, {"air.rho": 1.3})  # a --set ρ over the weather wins, and stays
    later = with_changes(dense, {"air.spin_decay": 2.5e-5})
    assert (later.air.rho, later.air.viscosity) == (1.3, weather[1])


def test_keys_that_set_up_the_balls_apply_at_t0_only():
    sim = tg.Simulation.from_scene("lab_vacuum")
    sim.set({"launch.speed": 30.0, "launch.angle_deg": 20.0})  # at t0: set up again
    assert_same_state(sim, tg.Simulation.from_scene("lab_vacuum", {"launch.speed": 30.0, "launch.angle_deg": 20.0}))
    sim.run(t=0.1)
    with pytest.raises(tg.ConfigError, match="sets up the balls or the ground at t0"):
        sim.set("launch.speed", 10.0)
    sim.reset({"launch.speed": 10.0})  # with reset they apply
    assert sim.t == 0.0 and np.linalg.norm(sim.v[0]) == pytest.approx(10.0)
    given = tg.Simulation(sim.scene, x=[[0.0, 1.0, 0.0]])
    with pytest.raises(tg.ConfigError, match="given as arrays"):
        given.set("launch.speed", 5.0)
    # radii given alone (the scene's balls): a new ball.radius had no effect and was taken quietly,
    # while the launch's keys still set the scene's ball up
    sized = tg.Simulation(sim.scene, radius=0.03)
    with pytest.raises(tg.ConfigError, match="'ball.radius' has no effect: this simulation's balls were given"):
        sized.set("ball.radius", 0.01)
    sized.set("launch.speed", 5.0)
    assert np.linalg.norm(sized.v[0]) == pytest.approx(5.0) and sized.model.radius_np.tolist() == [0.03]


def test_reset_goes_back_to_t0_bit_for_bit_with_the_changed_parameters():
    sim = tg.Simulation.from_scene("break_shot")
    start = sim_state(sim)
    sim.run(t=0.2)
    sim.set({"contact.e": 0.5, "contact.solver": "gauss_seidel"})
    sim.reset()
    assert sim.scene.contact.e == 0.5 and sim.scene.contact.solver == "gauss_seidel"
    for name, value in start.items():
        np.testing.assert_array_equal(sim_state(sim)[name], value, err_msg=name)
    assert sim.solver.gauss_seidel and sim.solver.rebuilds == 0
    fresh = tg.Simulation(sim.scene)  # no carried impulse, no list survives the reset
    sim.run(t=0.2)
    fresh.run(t=0.2)
    assert_same_state(sim, fresh)


def test_collisions_and_the_solver_can_change_mid_run():
    sim = tg.Simulation.from_scene("break_shot")
    sim.run(t=0.17)
    sim.set("world.collisions", False)
    assert sim.solver is None
    sim.run(t=0.01)
    sim.set({"world.collisions": True, "contact.solver": "gauss_seidel", "contact.skin": 0.2})
    assert sim.solver.gauss_seidel and sim.solver.skin == pytest.approx(0.2 * 0.02)
    sim.run(t=0.05)
    again = tg.Simulation.from_scene("break_shot")
    again.run(t=0.17)
    again.set("world.collisions", False)
    again.run(t=0.01)
    again.set({"world.collisions": True, "contact.solver": "gauss_seidel", "contact.skin": 0.2})
    again.run(t=0.05)
    assert_same_state(sim, again)  # deterministic
    deepest = sim.deepest_overlap()
    assert deepest is None or deepest.fraction < 0.05


def test_set_ball_edits_one_ball_and_wakes_it():
    sim = tg.Simulation(_columns_scene())
    sim.run(t=0.05)
    assert np.all(sim.status[:27] == tg.AT_REST)
    x, v = sim.x, sim.v
    sim.set_ball(2, v=[0.0, 2.0, 0.0])  # the top ball of the first column, thrown up
    assert sim.status[2] == tg.FLYING and np.all(np.delete(sim.status, [2, 27])[:26] == tg.AT_REST)
    np.testing.assert_array_equal(np.delete(sim.v, 2, axis=0), np.delete(v, 2, axis=0))
    sim.run(t=0.1)  # up at 2 m/s, no air: n semi-implicit Euler steps of h rise n·h·v0 − h²·g·n(n + 1)/2
    n, h, g = 100, 0.001, 9.81
    assert sim.x[2, 1] - x[2, 1] == pytest.approx(n * h * 2.0 - h * h * g * n * (n + 1) / 2, abs=1e-12)
    sim.set_ball([0, 1], x=[[1.0, 0.02, 1.0], [1.1, 0.02, 1.0]])
    np.testing.assert_array_equal(sim.x[[0, 1]], [[1.0, 0.02, 1.0], [1.1, 0.02, 1.0]])
    for bad, match in (
        ({"i": 28, "v": [0, 0, 0]}, "ball ids"),
        ({"i": 0, "v": [0, 0]}, "shape"),
        ({"i": 0, "w": [np.nan, 0, 0]}, "NaN"),
    ):
        with pytest.raises(ValueError, match=match):
            sim.set_ball(**bad)


def test_a_change_that_can_move_balls_at_rest_wakes_them_and_one_that_cannot_does_not():
    # a ball at rest on the ground stayed put, "at rest", when gravity turned upward, the ground
    # went away or it was moved 5 m up by assigning x: a change of the scene or of x must be felt
    def resting() -> tg.Simulation:
        sim = tg.Simulation("lab_vacuum", x=[[0.0, 0.02, 0.0]])
        sim.run(t=0.5)
        assert sim.status[0] == tg.AT_REST
        return sim

    sim = resting()
    for key, value in (("contact.e", 0.3), ("world.dt", 5e-4), ("world.t_rest", 0.2)):
        sim.set(key, value)  # (ti_golf.sim.changes.STILL_AT_REST: they cannot move it)
        assert sim.status[0] == tg.AT_REST, key
    sim.run(t=0.1)
    assert sim.status[0] == tg.AT_REST and sim.x[0, 1] == pytest.approx(0.02, abs=1e-12)
    sim.set("world.gravity", [0.0, 9.81, 0.0])  # falls up: ½·g·t² in vacuum, to first order in h
    x0, t = sim.x[0, 1], 0.2
    sim.run(t=t)
    assert sim.status[0] == tg.FLYING and sim.x[0, 1] - x0 == pytest.approx(0.5 * 9.81 * t**2, rel=0.01)
    sim = resting()
    sim.set("world.ground", False)
    sim.run(t=0.2)
    assert sim.x[0, 1] < 0.02 - 0.19
    sim = resting()
    sim.x = [[0.0, 5.0, 0.0]]
    sim.run(t=0.2)
    assert sim.x[0, 1] < 5.0 - 0.19
    sim = resting()
    sim.x = sim.x  # (no ball moved: none woken)
    assert sim.status[0] == tg.AT_REST


# ----------------------------------------------------------------------------------------------
# the command line
# ----------------------------------------------------------------------------------------------
def test_run_resume_ends_where_one_unbroken_run_ends(tmp_path, capsys):
    first, resumed, again, whole = (str(tmp_path / f"{n}.npz") for n in ("first", "resumed", "again", "whole"))
    assert main(["run", "break_shot", "--t", "0.1", "--out", first]) == 0
    assert main(["run", "--resume", first, "--t", "0.1", "--out", resumed]) == 0
    assert "resumed at t = 0.1 s" in capsys.readouterr().out
    assert main(["run", "--resume", resumed, "--steps", "200", "--out", again]) == 0  # a resumed run resumes too
    assert main(["run", "break_shot", "--t", "0.3", "--out", whole]) == 0
    with np.load(again) as a, np.load(whole) as b:
        for name in ("x", "v", "w", "t", "status", "rest_time"):
            np.testing.assert_array_equal(a[name], b[name], err_msg=name)


def test_run_resume_with_set_changes_the_continuation(tmp_path, capsys):
    first, out = str(tmp_path / "first.npz"), str(tmp_path / "out.npz")
    assert main(["run", "lab_turbulent", "--t", "1", "--out", first]) == 0
    assert main(["run", "--resume", first, "--t", "1", "--set", "air.C_D=0", "--out", out]) == 0
    sim = tg.Simulation.load(out)
    assert sim.scene.air.C_D == 0.0 and sim.t == pytest.approx(2.0)
    capsys.readouterr()
    cases = (
        (["--set", "launch.speed=5"], "key 'launch.speed' sets up the balls or the ground at t0"),
        (["--set", "air.C_D=-1"], "key 'air.C_D' must be in [0, 100]"),
        (["lab_turbulent"], "--resume: takes the scene from"),
    )
    for extra, message in cases:
        assert main(["run", "--resume", first, "--t", "1", *extra]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and message in err[0], err
    assert main(["run", "--resume", str(tmp_path / "none.npz")]) == 2
    assert "file not found" in capsys.readouterr().err
    assert main(["run"]) == 2
    assert "needs a SCENE" in capsys.readouterr().err


def test_an_interrupted_run_saves_whole_steps_that_can_be_continued(tmp_path, monkeypatch, capsys, ctrl_c):
    # Ctrl-C arrives while the third chunk of steps runs in the kernel: those steps end first
    # (t, step count), so the partial file holds the state of a run of that many steps, bit for bit
    real, calls = collide.collision_step, []

    def interrupted(*args):
        calls.append(1)
        if len(calls) == 3:
            os.kill(os.getpid(), signal.SIGINT)
        return real(*args)

    monkeypatch.setattr(collide, "collision_step", interrupted)
    out = tmp_path / "partial.npz"
    assert main(["run", "break_shot", "--t", "10", "--out", str(out)]) == 130
    assert "marked partial" in capsys.readouterr().err
    monkeypatch.undo()
    partial = tg.Simulation.load(out)
    assert partial.step_count == 3 * 100  # three chunks of 0.05 s
    whole = tg.Simulation.from_scene("break_shot")
    whole.run(steps=partial.step_count)
    assert_same_state(partial, whole)


def test_a_signal_during_steps_waits_for_them_to_end(monkeypatch, ctrl_c):
    sim = tg.Simulation.from_scene("lab_vacuum")
    real = kernels.advance

    def interrupted(*args):
        os.kill(os.getpid(), signal.SIGINT)  # arrives while the kernel runs
        return real(*args)

    monkeypatch.setattr(kernels, "advance", interrupted)
    before = signal.getsignal(signal.SIGINT)
    with pytest.raises(KeyboardInterrupt):
        sim.step(10)
    assert sim.step_count == 10 and sim.t == pytest.approx(10 * sim.dt)
    assert signal.getsignal(signal.SIGINT) == before
