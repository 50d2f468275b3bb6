"""Shots as golfers read them: launch-monitor launches, fade and draw, roll-out to rest, dispersion.

References: the launch-monitor conventions of golf_data.md (HLA + right, spin axis + tilts the
lift right), an independent scipy DOP853 integration of the same equations (bench.reference), the
step-by-step Simulation for the roll-out, and the linearisation Cov(y) ≈ J Σ Jᵀ for dispersion.
"""

from __future__ import annotations

import contextlib
import io
import json
import math
from dataclasses import fields, replace

import numpy as np
import pytest
from conftest import ROOT
from scipy.integrate import solve_ivp

from ti_golf.bench.reference import derivatives
from ti_golf.cli import main
from ti_golf.golf.dispersion import chi2_radius, dispersion, ellipse
from ti_golf.golf.shots import shots
from ti_golf.golf.sweep import sweep
from ti_golf.scene.balls import launch_position
from ti_golf.scene.launch_monitor import (
    MPH,
    RPM,
    UNITS,
    YARD,
    MonitorLaunch,
    launch_monitor,
    launch_vectors,
    right_of,
    scene_launch,
)
from ti_golf.scene.loader import load_scene
from ti_golf.scene.schema import backspin_axis
from ti_golf.sim.simulation import Simulation

SEVEN_IRON = MonitorLaunch(123 * MPH, 16.1, 0.0, 7124 * RPM, 0.0)
"""The PGA Tour 7-iron of golf_data.md as a launch monitor gives it."""
NAMES = [f.name for f in fields(MonitorLaunch)]


@pytest.fixture(scope="module")
def tour():
    return load_scene("tour_shot")


# ----------------------------------------------------------------------------------------------
# launch-monitor launch -> engine vectors (numpy only)
# ----------------------------------------------------------------------------------------------
def test_launch_vectors_give_the_launch_monitor_numbers_back():
    rng = np.random.default_rng(7)
    n = 200
    launch = [rng.uniform(20, 80, n), rng.uniform(-5, 45, n), rng.uniform(-20, 20, n), rng.uniform(0, 1000, n)]
    axis = rng.uniform(-60, 60, n)
    for direction in (0.0, 30.0, -135.0):
        v, w = launch_vectors(*launch, axis, direction)
        np.testing.assert_allclose(np.linalg.norm(v, axis=1), launch[0], rtol=1e-12)
        np.testing.assert_allclose(np.degrees(np.arcsin(v[:, 1] / launch[0])), launch[1], atol=1e-9)
        np.testing.assert_allclose(np.linalg.norm(w, axis=1), launch[3], rtol=1e-12)
        np.testing.assert_allclose(np.einsum("ij,ij->i", v, w), 0.0, atol=1e-9)  # no rifle spin
        back = launch_monitor(v, w, direction)
        for got, want in zip((back[k] for k in ("speed", "vla_deg", "hla_deg", "spin", "axis_deg")), launch + [axis]):
            np.testing.assert_allclose(got, want, atol=1e-9)


def test_axis_zero_is_pure_backspin_and_the_axis_tilts_the_lift_right():
    # axis 0: ω along the scene's backspin axis d × ŷ of the shot's azimuth
    v, w = launch_vectors(50.0, 12.0, 7.0, 600.0, 0.0, direction_deg=10.0)
    np.testing.assert_allclose(w[0], 600.0 * np.asarray(backspin_axis(17.0)), atol=1e-12)
    # the Magnus lift ∝ ω × v turns by the axis angle α about v from straight up toward the right:
    # its component to the right of the target line is |ω||v| sin α (HLA 0, so v ⊥ r̂)
    for alpha in (-20.0, -3.0, 3.0, 20.0):
        v, w = launch_vectors(50.0, 12.0, 0.0, 600.0, alpha, direction_deg=10.0)
        lift = np.cross(w[0], v[0])
        right = lift @ right_of(10.0)
        assert math.copysign(1.0, right) == math.copysign(1.0, alpha)
        assert right == pytest.approx(600.0 * 50.0 * math.sin(math.radians(alpha)), rel=1e-12)


def test_the_scene_launch_reads_back_as_the_seven_iron(tour):
    got = scene_launch(tour)
    for k in NAMES:
        assert getattr(got, k) == pytest.approx(getattr(SEVEN_IRON, k), rel=2e-4, abs=1e-12)


# ----------------------------------------------------------------------------------------------
# fade, draw and the numbers golfers read, against scipy
# ----------------------------------------------------------------------------------------------
def scipy_shot(scene, x0, v0, w0):
    """Landing point [m], hang time [s], |ω| at landing [rad/s] and apex height [m] by DOP853
    (rtol = atol = 1e-12) of bench.reference's equations, with exact landing and apex events."""
    level = x0[1]

    def rhs(_t, y):
        dv, dw = derivatives(scene, y[3:6][None, :], y[6:9][None, :])
        return np.concatenate([y[3:6], dv[0], dw[0]])

    def landing(_t, y):
        return y[1] - level

    def top(_t, y):
        return y[4]

    landing.terminal, landing.direction, top.direction = True, -1, -1
    sol = solve_ivp(rhs, (0, 30), np.concatenate([x0, v0, w0]), "DOP853", rtol=1e-12, atol=1e-12, events=(landing, top))
    y = sol.y_events[0][0]
    return y[:3], sol.t_events[0][0], np.linalg.norm(y[6:9]), sol.y_events[1][0][1] - level


def test_a_fade_curves_right_and_a_draw_left_by_the_amount_scipy_integrates(tour):
    launches = MonitorLaunch(*(np.array([getattr(SEVEN_IRON, k)] * 3, float) for k in NAMES))
    launches = replace(launches, axis_deg=np.array([5.0, -5.0, 0.0]))
    res = shots(tour, launches, to_rest=False)
    fade, draw, straight = res.offline
    assert fade > 5.0 and draw < -5.0  # metres: a 5° axis curves a 7-iron several metres
    assert straight == 0.0
    assert draw == pytest.approx(-fade, rel=1e-12)  # mirror images
    v0, w0 = launches.vectors()
    x0 = np.array([0.0, tour.ball.radius, 0.0])
    for i in range(3):
        p, t, spin, apex = scipy_shot(tour, x0, v0[i], w0[i])
        # RK4 (h = 1 ms) with Hermite landing: global error O(h⁴), far below 1e-6 m over a 6 s flight
        assert res.offline[i] == pytest.approx(p[2], abs=1e-6)
        assert res.carry[i] == pytest.approx(math.hypot(p[0], p[2]), abs=1e-6)
        assert res.hang_time[i] == pytest.approx(t, abs=1e-8)
        assert res.apex[i] == pytest.approx(apex, abs=1e-6)
        # ω at landing: linear inside the landing step, error O(h²·d²ω/dt²) ≈ 1e-6·|ω|·(decay rate)²
        assert res.land_spin[i] == pytest.approx(spin, rel=1e-7)


def test_hla_turns_the_whole_flight_about_the_vertical(tour):
    # no wind, axis 0: the flight of HLA h is the straight flight turned by h about ŷ
    launches = MonitorLaunch(*(np.array([getattr(SEVEN_IRON, k)] * 2, float) for k in NAMES))
    res = shots(tour, replace(launches, hla_deg=np.array([0.0, 4.0])), to_rest=False)
    assert res.carry[1] == pytest.approx(res.carry[0], rel=1e-9)
    assert res.offline[1] == pytest.approx(res.carry[0] * math.sin(math.radians(4.0)), rel=1e-9)
    assert res.along[1] == pytest.approx(res.carry[0] * math.cos(math.radians(4.0)), rel=1e-9)


def test_two_phase_roll_out_agrees_with_one_simulation(tour):
    # flight in lanes, then bounce and roll from the landing state, against one Simulation from the
    # tee to rest: the same flight (carry to 1e-9 m), but the first turf contact falls up to a step
    # apart (the Simulation meets the turf at the end of the step that crosses it), and each of the
    # few bounces that follow adds as much: the points of rest agree to a few steps' travel at
    # landing, 4·v_land·h ≈ 10 cm of a 3 m roll (the benchmark measures 2–5 cm over 8 shots)
    launch = replace(SEVEN_IRON, axis_deg=8.0)
    res = shots(tour, launch)
    assert res.at_rest[0] and res.total[0] > res.carry[0]
    assert res.roll[0] == pytest.approx(res.total[0] - res.carry[0])
    v, w = launch.vectors()
    sim = Simulation(tour, x=np.array([[0.0, tour.ball.radius, 0.0]]), v=v, w=w)
    sim.run(t=30.0, until="rest")
    assert sim.flight().carry[0] == pytest.approx(res.carry[0], abs=1e-9)
    h = tour.world.dt
    rest = np.array([res.rest_along[0], res.rest_offline[0]])
    assert np.hypot(*(rest - sim.x[0, [0, 2]])) < 4 * res.land_speed[0] * h


def test_sweep_columns_hold_the_same_numbers(tour):
    res = sweep(tour, angles_deg=[14.0, 18.0], to_rest=True)
    cols = res.columns()
    one = shots(tour, replace(scene_launch(tour), vla_deg=np.array([14.0, 18.0])))
    for col, want in (
        ("total_m", one.total),
        ("roll_m", one.roll),
        ("offline_m", one.offline),
        ("apex_height_m", one.apex),
        ("landing_spin_radps", one.land_spin),
    ):
        np.testing.assert_allclose(cols[col], want, rtol=1e-9, atol=1e-9, err_msg=col)


def test_a_ball_that_lands_behind_the_tee_carries_a_negative_distance_and_is_never_the_best():
    # the report's Magnus law at 40 rad/s of backspin loops a 60° launch back over the tee: its carry
    # was the distance alone, positive, so a sweep could call a backward shot its best
    lab = load_scene("lab_magnus")
    res = sweep(lab, angles_deg=[10.0, 60.0], spins=[40.0])
    f, s = res.flight, res.shots
    assert f.landed.all() and s.along[1] < 0 < s.along[0]  # (along the target line, +x)
    np.testing.assert_allclose(np.abs(res.carry), np.hypot(f.landing_x, f.landing_z), rtol=1e-12)
    assert res.carry[1] == -f.carry[1] < 0 < res.carry[0] == f.carry[0]
    assert res.best() == 0 and res.columns()["carry_m"][1] == res.carry[1]
    assert f.carry[1] > f.carry[0]  # (the case that was wrong: farther from the tee, but backward)


def test_a_ball_that_never_rises_has_no_landing_to_describe_and_all_its_travel_is_roll(tour):
    # launched 10° down, the ball is below its launch height at once: the landing angle, speed and
    # spin were the launch's (10°, 123 mph), read as a landing; launched level with a 7-iron's
    # backspin it climbs on its lift and flies (a landing of its own, steeper than level)
    base = scene_launch(tour)
    down, level = (shots(tour, replace(base, vla_deg=vla)) for vla in (-10.0, 0.0))
    assert down.carry[0] == 0.0 and down.apex[0] == 0.0 and down.hang_time[0] == 0.0
    assert np.isnan([down.land_angle[0], down.land_speed[0], down.land_spin[0]]).all()
    assert down.total[0] > 0 and down.roll[0] == down.total[0]
    assert level.apex[0] > 1.0 and level.carry[0] > 100.0 and level.hang_time[0] > 1.0
    assert 0.0 < level.land_angle[0] < 90.0 and np.isfinite([level.land_speed[0], level.land_spin[0]]).all()


# ----------------------------------------------------------------------------------------------
# dispersion
# ----------------------------------------------------------------------------------------------
def test_ellipses_of_a_known_normal_distribution():
    # points of a known 2-D normal: semi-axes k·√λ of its covariance, k² = −2 ln(1 − p), and the
    # ellipse holds a fraction p of the points (to binomial sampling error)
    rng = np.random.default_rng(11)
    n, a = 200_000, math.radians(25.0)
    rot = np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])
    pts = rng.standard_normal((n, 2)) * [1.0, 4.0] @ rot.T + [2.0, 150.0]  # major axis 25° off "along"
    assert chi2_radius(0.95) == pytest.approx(math.sqrt(5.991465), rel=1e-6)
    for p in (0.68, 0.95):
        e = ellipse(pts, p)
        k = chi2_radius(p)
        assert e.semi_major == pytest.approx(4.0 * k, rel=0.01) and e.semi_minor == pytest.approx(k, rel=0.01)
        assert e.angle_deg == pytest.approx(-25.0, abs=0.5)  # the major axis turned from "along" toward the left
        assert abs(e.inside - p) < 4 * math.sqrt(p * (1 - p) / n)
        np.testing.assert_allclose(e.center, [2.0, 150.0], atol=0.05)
        out = e.outline()  # the outline is at Mahalanobis radius k
        d = out - e.center
        cov = np.cov(pts, rowvar=False)
        np.testing.assert_allclose(np.einsum("ij,jk,ik->i", d, np.linalg.inv(cov), d), k * k, rtol=1e-9)


def test_a_flight_that_diverges_while_finite_is_stopped_naming_the_step():
    # a 5 m ball of a milligram: its drag acts in far less than a step of 10 ms, the explicit step
    # overshoots, and the flight grew to an apex of 5e47 m, reported as "did not land" with exit 0
    from ti_golf.errors import SimulationError

    with pytest.raises(SimulationError, match=r"rose past what their launch can lift them.*try a smaller world.dt"):
        sweep("lab_magnus", angles_deg=[45.0], overrides=["ball.radius=5", "ball.mass=1e-6"])
    # (the bound: 10 × (|v0| + |wind|)²/2g; the report's own Magnus shots rise well within it)
    res = sweep("lab_magnus", angles_deg=[10.0, 45.0, 80.0], spins=[0.0, 40.0])
    rise = res.flight.apex - launch_position(res.scene)[1]
    assert np.all(rise < (res.speed_mps**2 / (2 * 9.81)) + 1e-9)


def test_a_roll_out_without_a_ground_names_who_took_the_ground_away():
    # an override that took the ground away is named as such, not the bundled scene's file
    from ti_golf.errors import OVERRIDES, ConfigError
    from ti_golf.golf.rollout import roll_out

    scene = load_scene("tour_shot", ["world.ground=false"])
    with pytest.raises(ConfigError, match="needs a ground") as got:
        roll_out(scene, np.zeros((1, 3)), np.zeros((1, 3)), np.zeros((1, 3)))
    assert (got.value.source, got.value.key) == (OVERRIDES, "world.ground")


def test_a_flight_that_diverges_at_a_chosen_flight_step_names_that_step():
    # `dispersion --flight-dt 0.05` of a 10 mg ball diverged and said "try a smaller world.dt",
    # the step the user had not chosen (world.dt steps only the roll-out)
    from ti_golf.errors import SimulationError

    scene = load_scene("tour_shot", ["ball.mass=1e-5"])
    with pytest.raises(SimulationError, match=r"diverged at flight_dt = 0.05 s: try a smaller flight_dt") as got:
        dispersion(scene, SEVEN_IRON, MonitorLaunch(0.0, 0.0, 1.0, 0.0, 0.0), n=4, flight_dt=0.05, to_rest=False)
    assert "world.dt" not in str(got.value)


@pytest.mark.parametrize(
    "scene, overrides, spins",
    [
        ("lab_turbulent", ["ball.mass=1e-6"], None),  # drag 45,000 times a golf ball's on its mass
        ("lab_turbulent", ["air.rho=1000", 'world.integrator="semi_implicit"'], None),
        ("lab_magnus", [], [1e5]),  # a spin whose lift turns the ball faster than a step
        ("tour_shot", ["air.spin_decay=1e9"], None),
    ],
)
def test_a_flight_whose_first_step_overshoots_is_stopped_not_landed_at_its_tee(scene, overrides, spins):
    # the step threw the ball below its launch height at once, and the landing was put at the
    # launch: carry 0, landing upward at the launch speed, exit code 0
    from ti_golf.errors import SimulationError

    with pytest.raises(SimulationError, match=r"fell below their launch height in one step while rising.*smaller"):
        sweep(scene, angles_deg=[30.0], spins=spins, overrides=overrides)


@pytest.mark.parametrize("integrator", ["semi_implicit", "rk4"])
def test_a_ball_launched_upward_slower_than_a_step_of_gravity_lands_at_its_tee(integrator):
    # a ball launched up at less than g·h (here 0.05 m/s against 0.098 m/s at h = 10 ms) comes
    # back below its launch height within its first step: it barely rises, and lands at the tee. It
    # was taken for a diverged integration, and stopped a whole sweep of small speeds (exit 3)
    scene = load_scene("lab_magnus", [f'world.integrator="{integrator}"'])
    g, h = -scene.world.gravity[1], scene.world.dt
    speeds = [0.05 / math.sin(math.radians(30.0)), 0.5 * g * h / math.sin(math.radians(30.0)), 2.0]
    res = sweep(scene, angles_deg=[30.0], speeds=speeds)
    assert res.flight.landed.all()
    assert res.carry[:2] == pytest.approx([0.0, 0.0], abs=2.0 * h * speeds[1])  # (at most a step's flight)
    assert res.carry[2] > 0.1


def test_a_ball_that_gravity_does_not_pull_down_does_not_land_and_is_no_divergence():
    # gravity upward or sideways: the rise bound of a ball pulled down said the flight diverged
    for gravity in ("[0, 9.81, 0]", "[9.81, 0, 0]"):
        res = sweep("lab_vacuum", angles_deg=[45.0], overrides=[f"world.gravity={gravity}", "world.t_max=5"])
        assert not res.flight.landed.any()


def test_a_launch_spun_far_past_the_fitted_rows_gets_a_note():
    # the default spin_reynolds coefficients were fitted to the PGA rows (spin ratios 0.07 to 0.45
    # at launch); past S ≈ 0.40 their drag falls, and more spin carries farther
    from ti_golf.golf.aero_fit import EXTRAPOLATED, beyond_the_fit, fitted_spin_ratios

    tour = load_scene("tour_shot")
    lo, hi = fitted_spin_ratios(tour.ball.radius)
    assert 0.07 < lo < 0.08 and 0.44 < hi < 0.46
    speed = 54.99
    spin_at = [hi * speed / tour.ball.radius * k for k in (1.0, EXTRAPOLATED * 1.01)]
    assert beyond_the_fit(tour, speed, spin_at[0]) is None
    assert "lies past the PGA rows" in beyond_the_fit(tour, [speed, speed], spin_at)
    assert beyond_the_fit(load_scene("lab_magnus"), speed, spin_at[1]) is None  # (other air)
    own = load_scene("tour_shot", ["air.C_D_S=[0.13, 0.9, -0.8]"])
    assert beyond_the_fit(own, speed, spin_at[1]) is None  # (coefficients of the scene's own)
    r = sweep(tour, angles_deg=[16.1], speeds=[speed], spins=[7124 * RPM, 13369 * RPM])
    assert r.carry[1] > r.carry[0]  # (the extrapolation the note warns of)


def test_draws_held_at_a_launch_limit_are_counted():
    # a VLA of 16.1 ± 100° draws beyond ±90° a share Φ((-90 - 16.1)/100) + 1 - Φ((90 - 16.1)/100)
    # of the time, held there (the summary said VLA 100° and the "68 %" ellipse held 78 %)
    from ti_golf.golf.dispersion import draw_launches, held_at_limits

    mean = MonitorLaunch(55.0, 16.1, 0.0, 700.0, 0.0)
    sd = MonitorLaunch(0.0, 100.0, 1.5, 0.0, 3.0)
    n = 200_000
    held = held_at_limits(draw_launches(mean, sd, n, seed=5), sd)
    phi = [0.5 * (1 + math.erf(z / math.sqrt(2))) for z in ((-90 - 16.1) / 100, (90 - 16.1) / 100)]
    want = phi[0] + 1 - phi[1]
    assert set(held) == {"vla_deg"}  # (no spread, or within the limits: not listed)
    assert held["vla_deg"] == pytest.approx(want, abs=4 * math.sqrt(want * (1 - want) / n))


def test_dispersion_is_deterministic_for_a_seed(tour):
    sd = MonitorLaunch(1.5 * MPH, 1.0, 1.5, 300 * RPM, 3.0)
    a, b = (dispersion(tour, SEVEN_IRON, sd, n=48, seed=3) for _ in range(2))
    c = dispersion(tour, SEVEN_IRON, sd, n=48, seed=4, to_rest=False)
    for name in ("carry", "total", "offline", "rest_offline", "land_spin"):
        np.testing.assert_array_equal(getattr(a.shots, name), getattr(b.shots, name), err_msg=name)
    assert a.shots.at_rest.all()
    assert not np.array_equal(a.shots.carry, c.shots.carry)


def linearised_mismatch(scene, scale):
    """Relative mismatch of the sample covariance of (carry, offline) from its linearisation:
    against J Σ̂ Jᵀ with the draws' own covariance Σ̂, and against J Σ Jᵀ with the player's Σ;
    J by central differences of single shots, step σ."""
    sd = MonitorLaunch(*(scale * v for v in (1.5 * MPH, 1.0, 1.5, 300 * RPM, 3.0)))
    n = 2000
    d = dispersion(scene, SEVEN_IRON, sd, n=n, seed=5, to_rest=False, flight_dt=0.01)
    plus_minus = [
        replace(SEVEN_IRON, **{k: getattr(SEVEN_IRON, k) + s * getattr(sd, k)}) for k in NAMES for s in (1, -1)
    ]
    batch = MonitorLaunch(*(np.array([getattr(p, k) for p in plus_minus]) for k in NAMES))
    one = shots(scene, batch, to_rest=False, flight_dt=0.01)
    y = np.stack([one.carry, one.offline], axis=1)
    J = np.stack([(y[2 * i] - y[2 * i + 1]) / (2 * getattr(sd, k)) for i, k in enumerate(NAMES)], axis=1)  # (2, 5)
    X = np.stack([getattr(d.launches, k) for k in NAMES], axis=1)
    Y = np.stack([d.shots.carry, d.shots.offline], axis=1)
    cov_y = np.cov(Y, rowvar=False)
    norm = np.sqrt(np.outer(np.diag(cov_y), np.diag(cov_y)))
    sample = np.abs(cov_y - J @ np.cov(X, rowvar=False) @ J.T) / norm
    player = np.abs(cov_y - J @ np.diag([getattr(sd, k) ** 2 for k in NAMES]) @ J.T) / norm
    return sample.max(), player.max(), n


def test_dispersion_spread_matches_the_linearised_spread(tour):
    # y(x) = y0 + J Δx + O(Δx²): the sample covariance of y equals J Σ̂ Jᵀ up to the cross moments
    # of the linear and quadratic parts, relative O(σ) (σ a tenth of a player's spread here); and
    # J Σ Jᵀ up to the sampling error of a covariance, about √(2/N) relative
    sample, player, n = linearised_mismatch(tour, 0.1)
    assert sample < 2e-3
    assert player < 4 * math.sqrt(2 / n)
    half, _, _ = linearised_mismatch(tour, 0.05)
    assert half < sample / 1.5  # the mismatch shrinks with σ: it is the nonlinearity, nothing else


# ----------------------------------------------------------------------------------------------
# the command line (in-process)
# ----------------------------------------------------------------------------------------------
def cli(*args):
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            code = main(list(args))
        except SystemExit as exc:
            code = exc.code
    return code, out.getvalue(), err.getvalue()


def test_a_dispersion_in_which_no_shot_lands_says_so():
    # it printed the table's header with no rows under it, and no word why
    code, out, err = cli("dispersion", "lab_turbulent", "--n", "2", "--no-roll", "--set", "world.t_max=0.5")
    assert code == 0 and out.splitlines()[-1] == "no shot landed within world.t_max = 0.5 s", out + err
    assert "mean" not in out.split("spread (sd):")[1]


def test_a_dispersion_says_how_many_shots_never_flew():
    # shots launched below the horizontal go down through their launch height at once: they were
    # counted as landed (carry 0, a landing ellipse of 0 x 0 yd) with no word that none had flown
    code, out, err = cli("dispersion", "tour_shot", "--n", "40", "--vla", "0", "--no-roll", "--json")
    summary = json.loads(out.strip().splitlines()[-1])
    note = next(line for line in out.splitlines() if line.startswith("note:") and "never rose" in line)
    assert code == 0 and 0 < summary["unflown"] < 40 and f"note: {summary['unflown']} of the shots" in note, out + err
    code, out, _ = cli("dispersion", "tour_shot", "--n", "40", "--vla", "5", "--no-roll", "--json")
    assert code == 0 and json.loads(out.strip().splitlines()[-1])["unflown"] == 0 and "never rose" not in out


def test_a_speed_ratio_below_one_is_said_as_slower():
    from ti_golf.bench.common import faster

    assert (faster(2.54), faster(0.625), faster(1.0, 2)) == ("2.5x faster", "1.6x slower", "1.00x faster")


def test_shot_prints_the_numbers_golfers_read_in_either_units():
    code, out, _ = cli("shot", "tour_shot", "--axis", "5")
    assert code == 0
    for word in ("carry", "total", "roll", "offline", "apex", "hang time", "land angle", "land speed", "land spin"):
        assert word in out, word
    code, imp, _ = cli("shot", "tour_shot", "--axis", "5", "--hla", "-2", "--json")
    code2, met, _ = cli(
        "shot", "tour_shot", "--units", "metric", "--axis", "5", "--hla", "-2", "--speed", "54.99",
        "--spin", "746", "--json",
    )  # fmt: skip
    imp, met = json.loads(imp), json.loads(met)
    assert code == code2 == 0 and imp["at_rest"] and imp["units"] == "imperial"
    assert imp["offline_yd"] > 0  # a fade from 2° left ends right of where it started
    for name in ("carry", "total", "roll", "offline", "apex"):
        assert imp[f"{name}_yd"] * YARD == pytest.approx(met[f"{name}_m"], rel=1e-5, abs=1e-5)
    assert imp["land_speed_mph"] * MPH == pytest.approx(met["land_speed_mps"], rel=1e-5)
    assert imp["land_spin_rpm"] * RPM == pytest.approx(met["land_spin_radps"], rel=1e-5)
    assert imp["hang_time_s"] == pytest.approx(met["hang_time_s"], rel=1e-5)


@pytest.mark.parametrize(
    "args, option",
    [
        (["shot", "tour_shot", "--speed", "0"], "--speed"),
        (["shot", "tour_shot", "--vla", "95"], "--vla"),
        (["shot", "tour_shot", "--spin", "-10"], "--spin"),
        (["shot", "tour_shot", "--axis", "nan"], "--axis"),
        (["shot", "tour_shot", "--units", "furlongs"], "--units"),
        (["shot", "driving_range", "--speed", "150"], "--vla"),  # no [launch] to take VLA and spin from
        # a scene's launch out of a shot's range names its key, not an option that was not given
        (["shot", "lab_magnus", "--set", "launch.spin=[0, 0, 100000]"], "launch.spin of scene 'lab_magnus'"),
        (["shot", "lab_magnus", "--set", "launch.speed=0"], "launch.speed of scene 'lab_magnus'"),
        (["dispersion", "tour_shot", "--n", "1"], "--n"),
        (["dispersion", "tour_shot", "--n", "1000001"], "--n"),
        (["dispersion", "tour_shot", "--sd-vla", "-1"], "--sd-vla"),
        (["dispersion", "tour_shot", "--out", "shots.txt"], "--out"),
        (["dispersion", "tour_shot", "--flight-dt", "0.5"], "--flight-dt"),
    ],
)
def test_bad_launch_input_is_one_line_and_exit_code_2(args, option):
    code, out, err = cli(*args)
    assert code == 2, (out, err)
    assert option in err and "Traceback" not in err
    assert err.strip().splitlines()[-1].startswith("ti-golf: error:")


@pytest.mark.parametrize("command", ["sweep", "shot", "dispersion", "tour"])
@pytest.mark.parametrize("table", ["balls", "blocks"])
def test_flights_refuse_a_scene_whose_other_balls_they_would_not_fly(tmp_path, command, table):
    # each launch flies alone: a scene's [[balls]] or [[blocks]] were silently left out of the
    # flights (a ball set in the launch's path changed nothing), where `run` simulates them
    extra = {
        "balls": "position = [5.0, 1.0, 0.0]\n",
        "blocks": 'kind = "lattice"\ncount = [2, 1, 1]\norigin = [5.0, 1.0, 0.0]\nspacing = 0.05\n',
    }
    scene = tmp_path / "shot_and_wall.toml"
    scene.write_text((ROOT / "scenes" / "tour_shot.toml").read_text() + f"\n[[{table}]]\n{extra[table]}")
    code, out, err = cli(command, str(scene))
    assert code == 2, (out, err)
    assert f"shot_and_wall.toml: key '{table}[0]' has no effect on a sweep, a shot" in err and "Traceback" not in err
    assert cli("run", str(scene), "--steps", "1")[0] == 0  # (the scene itself is good)


def test_dispersion_command_writes_its_shots_and_plot(tmp_path):
    csv_path, npz_path, png = tmp_path / "shots.csv", tmp_path / "shots.npz", tmp_path / "d.png"
    code, out, _ = cli(
        "dispersion", "tour_shot", "--n", "300", "--seed", "2", "--out", str(csv_path), "--plot", str(png), "--json"
    )
    assert code == 0
    summary = json.loads(out.strip().splitlines()[-1])
    assert summary["n"] == 300 and summary["at_rest"] == 300
    assert [e["p"] for e in summary["ellipses"]] == [0.68, 0.95]
    assert summary["total_mean"] > summary["carry_mean"]
    header = csv_path.read_text().splitlines()[0].split(",")
    assert {"speed_mph", "axis_deg", "carry_yd", "total_yd", "offline_yd", "land_spin_rpm"} <= set(header)
    table = np.loadtxt(csv_path, delimiter=",", skiprows=1)
    assert table.shape == (300, len(header))
    assert np.std(table[:, header.index("carry_yd")], ddof=1) == pytest.approx(summary["carry_sd"], rel=1e-6)
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    code, _, _ = cli("dispersion", "tour_shot", "--n", "300", "--seed", "2", "--no-roll", "--out", str(npz_path))
    assert code == 0
    with np.load(npz_path) as z:
        np.testing.assert_allclose(z["carry_yd"], table[:, header.index("carry_yd")], rtol=1e-8)
        assert int(z["seed"]) == 2 and str(z["units"]) == "imperial"
        # without a roll-out, total, roll and the rest points would be NaN throughout: left out
        assert not {"total_yd", "roll_yd", "rest_along_yd", "rest_offline_yd"} & set(z.files)
    assert UNITS["imperial"].distance == YARD


def test_bench_dispersion_of_fewer_shots_than_its_default_rest_rolls_them_all_out():
    # --rest's default (10,000) was refused for any --n below it, naming --rest, not given
    code, out, err = cli("bench", "dispersion", "--n", "100", "--json")
    assert code == 0, err
    assert json.loads(out.strip().splitlines()[-1])["rest"]["n"] == 100


def test_bench_dispersion_rolls_out_the_landings_at_the_scenes_step(monkeypatch):
    # the loop over (world.dt, flight_dt) kept only the last flight's landings, so the roll-out
    # started from the coarse step's while its rate and its log said world.dt's
    from ti_golf.bench import dispersion as bench

    n, rest = 64, 32  # (apart from the 16 shots that compile, and the one compared with a Simulation)
    landed: dict[float, np.ndarray] = {}
    rolled: list[np.ndarray] = []
    fly, roll_out = bench.fly, bench.roll_out

    def flown(scene, x0, v0, w0, **kwargs):
        out = fly(scene, x0, v0, w0, **kwargs)
        if len(x0) == n:
            landed[scene.world.dt] = out["land_x"].copy()
        return out

    def rolled_out(scene, x, v, w, *args, **kwargs):
        if len(x) == rest:
            rolled.append(x.copy())
        return roll_out(scene, x, v, w, *args, **kwargs)

    monkeypatch.setattr(bench, "fly", flown)
    monkeypatch.setattr(bench, "roll_out", rolled_out)
    r = bench.bench_dispersion(
        n=n, rest=rest, flight_dt=0.01, n_reference=2, n_single=1, n_numpy=4, n_scipy=1, n_compare=1, log=lambda _: None
    )
    dt = load_scene(bench.SCENE).world.dt
    assert set(landed) == {dt, 0.01} and r["rest"]["n"] == rest and len(rolled) == 1
    assert not np.array_equal(landed[dt][:rest], landed[0.01][:rest])  # (the two steps land apart)
    np.testing.assert_array_equal(rolled[0], landed[dt][:rest].astype(np.float64))


def test_bench_dispersion_refuses_a_flight_step_not_coarser_than_the_scenes():
    from ti_golf.bench.dispersion import SCENE, bench_dispersion

    dt = load_scene(SCENE).world.dt
    for flight_dt in (dt, dt / 2, math.nan):
        with pytest.raises(ValueError, match="coarser than"):
            bench_dispersion(n=4, rest=0, flight_dt=flight_dt)


def test_bench_dispersion_reports_rates_baselines_and_accuracy():
    from ti_golf.bench.dispersion import bench_dispersion

    lines: list[str] = []
    r = bench_dispersion(n=64, rest=16, n_reference=3, n_single=2, n_numpy=16, n_scipy=2, n_compare=1, log=lines.append)
    fine, coarse = r["landing"]["dt_0.001"], r["landing"]["dt_0.01"]
    assert fine["landed_fraction"] == coarse["landed_fraction"] == 1.0
    # RK4's global error is O(h⁴): tiny at 1 ms, 10⁴ times that at 10 ms, still below a millimetre
    assert fine["max_carry_error_m"] < 1e-6 and coarse["max_carry_error_m"] < 1e-3
    assert r["rest"]["at_rest_fraction"] == 1.0 and r["rest"]["max_rest_gap_vs_one_simulation_m"] < 0.1
    assert set(r["baselines"]) == set(r["speedup"]) == set(r["baseline_sizes"])
    # each speed-up is the lanes' rate at h = 1 ms over the baseline's, each rate shots over seconds
    assert fine["shots_per_s"] == pytest.approx(64 / fine["seconds"], rel=1e-9)
    for name, rate in r["baselines"].items():
        assert r["speedup"][name] == pytest.approx(fine["shots_per_s"] / rate, rel=1e-9), name
    # the coarse step flies the same shots in about a tenth of the steps
    assert coarse["seconds"] < fine["seconds"]
    assert any("shots/s" in line for line in lines)


def test_a_shot_beyond_a_golf_shots_speed_or_spin_says_which_commands_take_more(capsys):
    # shot and dispersion bound speed and spin at 150 m/s and 2000 rad/s, sweep and the scenes at
    # 1000 m/s and 1e5 rad/s: the error gave the bound alone, which sweep took without a word
    from ti_golf.cli import main

    for option, value, bound in (("--speed", "200", "(0, 150] m/s"), ("--spin", "3000", "[0, 2000] rad/s")):
        assert main(["shot", "lab_vacuum", "--units", "metric", option, value]) == 2
        said = capsys.readouterr().err
        assert f"{option}: must be in {bound} (got {value}): the range of golf shots; a scene's [launch] and" in said
