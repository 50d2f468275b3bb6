"""The lab application's logic (report §2.2 and §2.4), driven headless: start, stop, change,
continue, reset, refused values, save; its parameter list and its orbit camera. The window and
the command: tests/test_lab_window.py."""

from __future__ import annotations

import json

import numpy as np
import pytest
from conftest import assert_same_state, png_rgb

import ti_golf as tg
from ti_golf.lab import app
from ti_golf.lab.app import Lab, bundled_scenes
from ti_golf.lab.params import panel_text, parameters, slider_span, slider_value
from ti_golf.render import orbit_view
from ti_golf.scene.balls import launch_position
from ti_golf.scene.keys import help_text
from ti_golf.scene.schema import SCHEMA

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


# ----------------------------------------------------------------------------------------------
# the logic, headless
# ----------------------------------------------------------------------------------------------
def test_stop_change_C_D_continue_then_reset_t0_is_the_initial_state_bit_for_bit():
    lab = Lab("lab_magnus")
    assert lab.set("launch.angle_deg", 20.0) is None  # a key that sets up the ball: at t0
    lab.start()
    assert lab.advance(max_steps=50) == 50
    lab.stop()
    assert lab.set("air.C_D", 0.25) is None
    lab.resume()
    assert lab.advance(max_steps=50) == 50
    # the same run, unbroken, in a Simulation: the lab's frames of steps change nothing, and the
    # second half flew with the new drag coefficient (the first-order drag change is far above
    # the last bits, so a run that ignored it could not pass)
    same = tg.Simulation.from_scene("lab_magnus", {"launch.angle_deg": 20.0})
    same.step(50)
    same.set("air.C_D", 0.25)
    same.step(50)
    for name in ("x", "v", "w"):
        np.testing.assert_array_equal(getattr(lab.sim, name), getattr(same, name), err_msg=name)
    unchanged = tg.Simulation.from_scene("lab_magnus", {"launch.angle_deg": 20.0})
    unchanged.step(100)
    assert np.linalg.norm(unchanged.v - lab.sim.v) > 1e-3
    lab.reset()
    assert lab.scene.air.C_D == 0.25 and lab.scene.launch.angle_deg == 20.0  # the changes stay
    assert_same_state(lab.sim, tg.Simulation.from_scene("lab_magnus", {"launch.angle_deg": 20.0, "air.C_D": 0.25}))
    assert not lab.running and lab.trails() is None


@pytest.mark.parametrize(
    "key, value, needle",
    [
        ("contact.e", 1.5, "contact.e: must be in [0, 1] (got 1.5)"),
        ("air.C_D", -0.1, "air.C_D: must be in [0, 100] (got -0.1)"),
        ("world.dt", 0.0, "world.dt: must be in (0, 1] s (got 0.0)"),
        ("launch.angle_deg", 120.0, "launch.angle_deg: must be in [-90, 90] degrees (got 120.0)"),
        ("air.gamma", 3, "air.gamma: must be one of 1, 2 (got 3)"),
        ("air.wind", [1.0, 2.0], "air.wind: must be a list of 3 numbers in m/s"),
        ("world.integrator", "euler", "world.integrator: must be one of 'semi_implicit', 'rk4'"),
        ("world.t_max", 10.0, "world.t_max: has no effect on a simulation"),
    ],
)
def test_a_bad_value_is_refused_with_the_allowed_range_and_changes_nothing(key, value, needle):
    lab = Lab("lab_magnus")
    before = lab.scene
    message = lab.set(key, value)
    assert message is not None and needle in message, message
    assert lab.refused and lab.message == message
    assert lab.scene == before


def test_keys_that_set_up_the_balls_wait_for_t0_and_unread_keys_are_refused():
    lab = Lab("lab_magnus")
    lab.step(3)
    message = lab.set("launch.speed", 50.0)
    assert "launch.speed sets up the balls or the ground at t0" in message and "Reset t0" in message
    assert lab.scene.launch.speed == 80.0 and lab.sim.step_count == 3
    assert lab.set("air.model", "spin_ratio") is None  # live: the next step uses it
    message = lab.set("air.C_D", 0.2)
    assert message == 'air.C_D: is only read when air.model = "lab"'
    assert next(p for p in lab.parameters() if p.key == "air.C_D").read is False


def test_a_run_stops_at_t_end_continues_for_t_end_more_and_paces_to_real_time():
    lab = Lab("lab_magnus", speed=1.0)  # h = 0.01 s
    lab.set("world.t_end", 0.1)
    lab.start()
    # real time: 0.05 s of wall-clock time, 5 steps (with a frame budget no machine runs out of:
    # the default budget, 30 ms of real time, holds fewer on a slow or busy machine)
    assert lab.advance(wall_dt=0.05, budget_s=60.0) == 5
    assert lab.advance(max_steps=1000) == 5  # never past t_end
    assert not lab.running and lab.finished and "Continue runs on" in lab.message
    lab.resume()
    assert lab.running and lab.t_stop == pytest.approx(0.2)
    lab.speed = None  # as fast as the frame's budget allows, at least one step
    assert lab.advance(budget_s=0.0) == 1
    samples = lab.recording.arrays()
    assert samples["traj_x"].shape == (12, 1, 3) and samples["traj_v"].shape == (12, 1, 3)  # t0 and every step
    np.testing.assert_allclose(np.diff(samples["traj_t"]), 0.01, rtol=1e-9)


def test_a_ball_that_goes_non_finite_stops_the_run_and_reset_recovers():
    lab = Lab("lab_magnus")
    # allowed, but a Magnus law 4,000 times the report's turns the ball faster than a step of 0.01 s,
    # and the explicit step's turns grow its speed more each step (a drag that fast is refused)
    assert lab.set("air.C_M", 100.0) is None
    lab.start()
    lab.advance(max_steps=10)
    assert not lab.running and lab.refused
    assert lab.message.startswith("stopped: ball 0 went non-finite at t = ")
    lab.set("air.C_M", Lab("lab_magnus").scene.air.C_M)
    lab.reset()
    lab.step(2)
    assert np.isfinite(lab.sim.x).all()


def test_the_selected_ball_is_edited_and_read_out_in_the_break_shot():
    lab = Lab("break_shot")
    assert lab.sim.n == 16
    lab.start()
    lab.advance(max_steps=100)
    lab.stop()
    lab.select(99)
    assert lab.selected == 15  # clamped to the last ball
    lab.select(0)
    assert "holds NaN" in lab.set_ball(v=[np.nan, 0.0, 0.0])
    # a value that is not three numbers is refused before anything changes (a position given
    # with it stays as it was; [[1, 2, 3]] ended in a TypeError after the ball had changed)
    x_before = lab.sim.x[0].copy()
    for bad in ([1.0, 2.0], "fast"):
        assert "takes three numbers [x, y, z]" in lab.set_ball(x=[0.5, 0.5, 0.5], v=bad) and lab.refused
        np.testing.assert_array_equal(lab.sim.x[0], x_before)
    assert lab.set_ball(v=[[0.0, 0.0, 2.0]], w=[0.0, 0.0, 0.0]) is None
    r = lab.readout()
    assert r.speed == 2.0 and r.spin == 0.0 and r.height == pytest.approx(0.02, abs=1e-3)
    assert sum(r.counts.values()) == 16
    lab.resume()
    lab.advance(max_steps=20)
    assert lab.sim.v[0, 2] > 1.0  # it rolls on sideways
    assert lab.trails().shape[1:] == (16, 3)
    assert any("16 balls" in line for line in r.lines())


def test_save_writes_the_run_its_plots_and_the_screenshot(tmp_path, monkeypatch):
    lab = Lab("lab_magnus")
    lab.start()
    lab.advance(max_steps=30)
    lab.stop()
    shots = []

    def screenshot(path):
        shots.append(path)
        path.write_bytes(PNG_SIGNATURE)

    written = lab.save(tmp_path, screenshot=screenshot)
    names = [p.name for p in written]
    assert names == [
        "lab_magnus_001.npz",
        "lab_magnus_001_trajectory.png",
        "lab_magnus_001_speed.png",
        "lab_magnus_001_spin.png",
        "lab_magnus_001_screen.png",
    ]
    assert written[-1].read_bytes() == PNG_SIGNATURE  # the screenshot is the window's (here a stand-in)
    # the plots show the ball's 30 steps: climbing (the Magnus shot at 11.5°), slowing in the air,
    # and spinning at its launch spin (no spin decay in lab_magnus: a level line)
    slopes = {}
    for p in written[1:4]:
        img = png_rgb(p)
        line = (img[..., 2] - img[..., 0]) > 0.15  # the one ball's line, matplotlib's blue, and its edges
        rows, cols = np.nonzero(line)
        assert line.sum() > 100, p.name
        first, last = cols <= np.percentile(cols, 10), cols >= np.percentile(cols, 90)
        slopes[p.name.split("_")[-1]] = rows[first].mean() - rows[last].mean()  # > 0: rising to the right
    assert slopes["trajectory.png"] > 20 and slopes["speed.png"] < -20 and abs(slopes["spin.png"]) < 3, slopes
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(names)  # no temporary files left
    with np.load(tmp_path / "lab_magnus_001.npz") as npz:
        assert npz["traj_v"].shape == (31, 1, 3) and bool(npz["partial"])
        assert json.loads(str(npz["run"]))["steps"] == 30
    resumed = tg.Simulation.load(tmp_path / "lab_magnus_001.npz")  # the saved run goes on
    assert_same_state(resumed, lab.sim)
    assert lab.save(tmp_path)[0].name == "lab_magnus_002.npz"  # a second save beside the first
    (tmp_path / "file").write_text("")
    assert lab.save(tmp_path / "file") == [] and lab.refused and "cannot save into" in lab.message
    # a plot that cannot be written (a full disk) leaves the files before it, and the message says so
    # (its docstring promised none, and the message named none)
    monkeypatch.setattr(app, "plot_speed", lambda *a: (_ for _ in ()).throw(OSError(28, "No space left on device")))
    kept = lab.save(tmp_path)
    assert [p.name for p in kept] == ["lab_magnus_003.npz", "lab_magnus_003_trajectory.png"] and lab.refused
    assert lab.message.endswith(
        "No space left on device (saved lab_magnus_003.npz, lab_magnus_003_trajectory.png before it)"
    ), lab.message


def test_load_offers_every_bundled_scene_and_refuses_a_bad_one(tmp_path):
    lab = Lab("lab_magnus")
    assert "lab_magnus" in lab.scenes and "break_shot" in lab.scenes and lab.scenes == bundled_scenes()
    bad = tmp_path / "bad.toml"
    bad.write_text("[air]\nC_D = -1\n")
    message = lab.load(bad)
    assert "bad.toml: key 'air.C_D' must be in [0, 100]" in message
    assert lab.scene.name == "lab_magnus"  # kept
    good = tmp_path / "mine.toml"
    good.write_text("[launch]\nspeed = 30.0\n")
    assert lab.load(good) is None and lab.scene.launch.speed == 30.0
    assert str(good) in lab.scenes


# ----------------------------------------------------------------------------------------------
# the parameters
# ----------------------------------------------------------------------------------------------
def test_every_key_a_run_reads_is_listed_with_its_unit_help_and_value():
    scene = tg.load_scene("terrain_2d")  # a launched ball and generated terrain: every table
    listed = {p.key: p for p in parameters(scene)}
    for table in ("air", "ball", "launch", "world", "contact", "terrain"):
        for name, k in SCHEMA[table].items():
            key = f"{table}.{name}"
            if key == "world.t_max":  # no simulation reads it
                assert key not in listed
                continue
            p = listed[key]
            assert (p.unit, p.help, p.allowed) == (k.unit, help_text(k), k.allowed)
    assert listed["launch.position"].value == launch_position(scene)  # the launch point stands in for "unset"
    assert listed["terrain.kill_height"].value == scene.terrain.kill
    # unset weather keys stand for the standard atmosphere at sea level, dry (the air's ρ is the file's)
    weather = [listed[f"air.{k}"].value for k in ("temperature", "pressure", "altitude", "humidity")]
    assert weather == [pytest.approx(15.0), pytest.approx(101325.0), 0.0, 0.0]
    numeric = ("float", "int", "vec3", "vec2")  # (a "range", terrain.surface_levels, may be unset: no slider)
    assert not [p.key for p in listed.values() if p.kind in numeric and p.value is None]  # every slider has a value
    assert listed["air.wind"].kind == "vec3" and listed["air.wind"].at_t0 is False
    assert listed["terrain.seed"].at_t0 and listed["ball.mass"].at_t0
    assert not listed["terrain.file"].editable  # a generated terrain: the file is not read
    assert not any(k.startswith(("hole.", "game.", "sweep.")) for k in listed)
    no_launch = {p.key for p in parameters(tg.load_scene("break_shot"))}
    assert not any(k.startswith(("launch.", "terrain.")) for k in no_launch)


def test_sliders_span_the_allowed_interval_and_reach_the_value():
    from ti_golf.scene.schema import SCHEMA as S

    assert slider_span("contact.e", S["contact"]["e"], 0.5) == (0.0, 1.0)
    assert slider_span("air.C_D", S["air"]["C_D"], 0.3) == (0.0, 1.0)
    assert slider_span("air.C_D", S["air"]["C_D"], 4.0) == (0.0, 4.0)  # a typed value beyond the span
    assert slider_span("contact.iterations", S["contact"]["iterations"], 4) == (1.0, 100.0)
    assert slider_span("world.ground_height", S["world"]["ground_height"], -7.0) == (-7.0, 5.0)
    assert slider_value(np.float32(0.3), "float") == 0.3  # the widget's 32 bits, as the decimal typed
    assert slider_value(2.0, "int") == 2


def test_the_panel_writes_the_help_in_its_font_s_characters():
    assert panel_text("k_ω = ½ρA·C_ω/m, −10 m, drag ∝ v²") == "k_omega = ½ rho A·C_omega/m, -10 m, drag ~ v²"
    assert panel_text("☃") == "?"


def test_the_orbit_camera_turns_around_the_scene_and_zooms():
    sim = tg.Simulation.from_scene("break_shot")
    v = orbit_view(sim, 0.0, 0.0, 1.0, (400, 300))
    d = np.subtract(v.position, v.lookat)
    assert d[0] > 0 and abs(d[1]) < 1e-9 * np.linalg.norm(d) and abs(d[2]) < 1e-9 * np.linalg.norm(d)  # from +x
    top = orbit_view(sim, 30.0, 89.0, 1.0, (400, 300))
    assert np.subtract(top.position, top.lookat)[1] > 0.99 * np.linalg.norm(np.subtract(top.position, top.lookat))
    near = orbit_view(sim, 0.0, 0.0, 0.5, (400, 300))
    np.testing.assert_allclose(np.subtract(near.position, near.lookat), 0.5 * d, rtol=1e-12)
    ball = orbit_view(sim, 90.0, 0.0, 1.0, (400, 300), target=sim.x[3])
    np.testing.assert_allclose(ball.lookat, sim.x[3])
    np.testing.assert_allclose(np.subtract(ball.position, ball.lookat), [0.0, 0.0, 60 * 0.02], atol=1e-12)
