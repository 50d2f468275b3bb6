"""Physics verification: every claim against a closed form, a conservation law, an independent
high-accuracy integration (scipy DOP853) or the report's own tables.

Tolerances are tied to the integrator: RK4 has global error O(h⁴), the semi-implicit Euler O(h).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import ti_golf as tg
from ti_golf.bench.reference import derivatives as reference_derivatives
from ti_golf.golf.tour import fly_tour
from ti_golf.golf.trackman import PGA_TOUR, TOUR
from ti_golf.scene.schema import backspin_axis, launch_velocity

G = 9.81
MPH, YD, RPM = 0.44704, 0.9144, 2.0 * math.pi / 60.0  # golf_data.md's conversions, to SI

# The TrackMan tour averages (2023 dataset), copied from the reference notes (golf_data.md) rather
# than imported: the tests' reference must not come from the code under test, whose own copy
# (ti_golf.golf.trackman) is checked against this one.
#                    ball mph, launch °, spin rpm, max height yd, land angle °, carry yd
TRACKMAN = {
    "PGA Driver": (171, 10.4, 2545, 35, 39, 282),
    "PGA 3-wood": (162, 9.3, 3663, 32, 44, 249),
    "PGA 5-wood": (156, 9.7, 4322, 33, 48, 236),
    "PGA Hybrid": (149, 10.2, 4587, 31, 49, 231),
    "PGA 3-iron": (145, 10.3, 4404, 30, 48, 218),
    "PGA 4-iron": (140, 10.8, 4782, 31, 49, 209),
    "PGA 5-iron": (135, 11.9, 5280, 33, 50, 199),
    "PGA 6-iron": (130, 14.0, 6204, 32, 50, 188),
    "PGA 7-iron": (123, 16.1, 7124, 34, 51, 176),
    "PGA 8-iron": (118, 17.8, 8078, 33, 51, 164),
    "PGA 9-iron": (112, 20.0, 8793, 32, 52, 152),
    "PGA PW": (104, 23.7, 9316, 32, 52, 142),
    "LPGA Driver": (143, 12.6, 2506, 26, 36, 223),
    "LPGA 3-wood": (135, 11.6, 2595, 25, 38, 200),
    "LPGA 5-wood": (130, 12.3, 4320, 25, 43, 189),
    "LPGA Hybrid": (125, 13.9, 4504, 25, 45, 178),
    "LPGA 4-iron": (118, 13.9, 4608, 25, 43, 175),
    "LPGA 5-iron": (114, 14.6, 4966, 25, 45, 166),
    "LPGA 6-iron": (111, 16.7, 5904, 25, 46, 155),
    "LPGA 7-iron": (106, 18.5, 6630, 26, 47, 143),
    "LPGA 8-iron": (102, 20.8, 7413, 27, 47, 133),
    "LPGA 9-iron": (95, 23.5, 7605, 27, 48, 123),
    "LPGA PW": (88, 25.2, 8465, 27, 48, 111),
}
PGA = [name for name in TRACKMAN if name.startswith("PGA")]

CARRY_TARGET, APEX_TARGET, LAND_TARGET = 3.0, 2.0, 2.0
"""The targets each row of the table is held to: carry within 3 % [%], apex within 2 yd [yd],
land angle within 2° [deg] of the table's (the tests' own, not the code's tolerances)."""


def lab(name: str, *overrides: str) -> tg.Scene:
    return tg.load_scene(name, list(overrides))


# ---------------------------------------------------------------------------------------------
# Ballistics and the report's tables
# ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize("angle", [10.0, 30.0, 45.0, 62.5])
def test_vacuum_range_is_closed_form(angle):
    # R = v0² sin 2θ / g. RK4 integrates a quadratic trajectory exactly and the cubic Hermite
    # landing interpolates it exactly, so only round-off remains.
    res = tg.sweep(lab("lab_vacuum"), angles_deg=[angle])
    expected = 80.0**2 * math.sin(math.radians(2 * angle)) / G
    assert res.carry[0] == pytest.approx(expected, rel=1e-10)
    # apex v0² sin²θ / 2g above the launch point, flight time 2 v0 sinθ / g
    vy = 80.0 * math.sin(math.radians(angle))
    assert res.flight.apex[0] - 0.02 == pytest.approx(vy**2 / (2 * G), rel=1e-10)
    assert res.flight.flight_time[0] == pytest.approx(2 * vy / G, rel=1e-10)
    assert res.flight.landing_angle[0] == pytest.approx(angle, abs=1e-8)


def test_semi_implicit_euler_is_first_order():
    # The report's integrator: halving h halves the carry error (global error O(h)).
    exact = 80.0**2 / G
    errors = []
    for dt in (0.004, 0.002, 0.001):
        res = tg.sweep(lab("lab_vacuum", "world.integrator=semi_implicit", f"world.dt={dt}"), angles_deg=[45.0])
        errors.append(abs(res.carry[0] - exact))
    ratios = [errors[0] / errors[1], errors[1] / errors[2]]
    assert all(1.8 < r < 2.2 for r in ratios), (errors, ratios)


# report Appendix A (RK4, h = 0.01, Mathematica): carry [m] at launch angle [deg], v0 = 80 m/s
APPENDIX_A = {
    "lab_laminar": {40.0: 618.821, 42.0: 623.979, 44.4: 626.179, 46.0: 625.228, 50.0: 614.458},
    "lab_turbulent": {32.0: 210.29, 34.0: 211.616, 36.6: 212.243, 38.0: 212.085, 42.0: 209.799},
    "lab_vacuum": {40.0: 642.484, 45.0: 652.396, 50.0: 642.484},
}


@pytest.mark.parametrize("scene", sorted(APPENDIX_A))
def test_appendix_a_table(scene):
    # The appendix prints 6 significant digits: agreement to half a unit in the last digit.
    table = APPENDIX_A[scene]
    res = tg.sweep(lab(scene), angles_deg=list(table))
    for angle, carry in zip(res.angle_deg, res.carry):
        assert carry == pytest.approx(table[angle], abs=0.0006 if carry < 1000 else 0.006), angle


@pytest.mark.parametrize(
    "scene, angles, best_carry, tol",
    [
        ("lab_turbulent", np.arange(36.0, 37.4001, 0.02), 212.243, 0.05),  # Appendix A maximum
        ("lab_laminar", np.arange(43.4, 45.4001, 0.02), 626.179, 0.1),
        ("lab_vacuum", np.arange(44.0, 46.0001, 0.02), 652.396, 0.1),
    ],
)
def test_best_carry_of_fine_sweep(scene, angles, best_carry, tol):
    res = tg.sweep(lab(scene), angles_deg=angles)
    assert res.carry[res.best()] == pytest.approx(best_carry, abs=tol)


def test_table_3_1_1_magnus_row():
    # report Table 3.1-1: turbulent drag + Magnus (ω0 = 10 rad/s, ω_M = 1/s): 244 m at 11.5°,
    # read off trajectories 0.5° apart.
    res = tg.sweep(lab("lab_magnus"), angles_deg=np.arange(7.0, 17.001, 0.05))
    b = res.best()
    assert res.carry[b] == pytest.approx(244.0, abs=1.0)
    assert res.angle_deg[b] == pytest.approx(11.5, abs=0.5)
    # and the lift makes it carry farther than the same shot without Magnus (report: +20 %)
    plain = tg.sweep(lab("lab_turbulent"), angles_deg=np.arange(30.0, 40.0, 0.1)).carry.max()
    assert 1.10 < res.carry[b] / plain < 1.25


# ---------------------------------------------------------------------------------------------
# Conservation laws
# ---------------------------------------------------------------------------------------------
def _free_flight(scene: tg.Scene, angle: float = 45.0, speed: float = 80.0) -> tg.Simulation:
    return tg.Simulation(scene, x=[[0.0, 0.0, 0.0]], v=[launch_velocity(speed, angle, 0.0)])


def test_energy_is_conserved_in_vacuum_by_rk4():
    sim = _free_flight(lab("lab_vacuum", "world.ground=false"))
    e0 = 0.5 * np.sum(sim.v**2) + G * sim.x[0, 1]
    for _ in range(20):  # 10 s in 0.5 s chunks: RK4 is exact for constant gravity, round-off remains
        sim.run(t=0.5)
        e = 0.5 * np.sum(sim.v**2) + G * sim.x[0, 1]
        assert abs(e - e0) / e0 < 1e-12


def test_semi_implicit_energy_drift_is_exact():
    # Symplectic Euler under constant gravity: E(n+1) − E(n) = −½h²g² per unit mass exactly,
    # so after t seconds the energy has changed by −½ h g² t (a closed form, not a tolerance).
    h, t = 0.001, 5.0
    sim = _free_flight(lab("lab_vacuum", "world.ground=false", "world.integrator=semi_implicit", f"world.dt={h}"))
    e0 = 0.5 * np.sum(sim.v**2) + G * sim.x[0, 1]
    sim.run(t=t)
    e1 = 0.5 * np.sum(sim.v**2) + G * sim.x[0, 1]
    assert e1 - e0 == pytest.approx(-0.5 * h * G**2 * t, rel=1e-6)


# ---------------------------------------------------------------------------------------------
# Magnus force, spin decay and wind against an independent integration
# ---------------------------------------------------------------------------------------------
def _scipy_trajectory(scene: tg.Scene, x0, v0, w0, times):
    def rhs(_t, y):
        dv, dw = reference_derivatives(scene, y[3:6][None], y[6:9][None])
        return np.concatenate([y[3:6], dv[0], dw[0]])

    sol = solve_ivp(
        rhs, (0, times[-1]), np.concatenate([x0, v0, w0]), method="DOP853", rtol=1e-12, atol=1e-12, t_eval=times
    )
    return sol.y[0:3].T, sol.y[6:9].T


@pytest.mark.parametrize(
    "overrides, spin",
    [
        # Magnus only (lab row 4), spin decay with gamma = 2 and 1, and all of it in a crosswind
        (("air.C_M=0.025",), 10.0),
        (("air.C_M=0.025", "air.omega_M=100", "air.C_omega=1.0"), 300.0),
        (("air.gamma=1", "air.C_M=0.025", "air.omega_M=100", "air.C_omega=0.5"), 300.0),
        (("air.C_M=0.025", "air.omega_M=100", "air.C_omega=1.0", "air.wind=[-4, 0.5, 3]"), 300.0),
    ],
)
def test_magnus_and_spin_decay_match_scipy(overrides, spin):
    x0, v0 = np.zeros(3), np.array(launch_velocity(45.0, 25.0, 10.0))
    w0 = spin * (np.array(backspin_axis(10.0)) + np.array([0.0, 0.15, 0.0]))  # backspin and some side spin
    errors = []
    for dt in (0.2, 0.1, 0.005):
        scene = lab("lab_turbulent", "world.ground=false", f"world.dt={dt}", *overrides)
        sim = tg.Simulation(scene, x=[x0], v=[v0], w=[w0])
        rec = sim.run(t=4.0, record_every=int(round(0.2 / dt)))
        ref_x, ref_w = _scipy_trajectory(scene, x0, v0, w0, np.asarray(rec.t))
        errors.append(
            (
                np.max(np.abs(np.asarray(rec.x)[:, 0] - ref_x)),
                np.max(np.abs(np.asarray(rec.w)[:, 0] - ref_w)) / np.linalg.norm(w0),
            )
        )
    (ex1, _), (ex2, _), (ex3, ew3) = errors
    # RK4 converges to the independent solution at 4th order: halving h divides the error by ~16
    assert 10.0 < ex1 / ex2 < 22.0, errors
    assert ex3 < 1e-6 and ew3 < 1e-8, errors
    # and the physics moved things: the spin-free drag-only flight ends elsewhere
    plain = tg.Simulation(lab("lab_turbulent", "world.ground=false"), x=[x0], v=[v0])
    plain.run(t=4.0)
    assert np.linalg.norm(plain.x[0] - ref_x[-1]) > 1.0


def test_spin_decay_closed_form_laminar():
    # γ = 1: dω/dt = −k_ω ω with k_ω = ½ρA·C_ω/m (L.17, L.18), so |ω(t)| = ω0·exp(−k_ω t)
    scene = lab("lab_laminar", "world.ground=false", "air.C_omega=2.0", "world.dt=0.01")
    sim = tg.Simulation(scene, x=[[0, 0, 0]], v=[[30.0, 10.0, 0]], w=[[0, 0, 500.0]])
    sim.run(t=3.0)
    k_w = 0.5 * 1.3 * math.pi * 0.02**2 * 2.0 / 0.045
    assert np.linalg.norm(sim.w[0]) == pytest.approx(500.0 * math.exp(-k_w * 3.0), rel=1e-9)


def test_wind_enters_through_relative_velocity():
    # Galilean invariance of L.21–L.23: a shot at v0 in a wind W flies like a shot at v0 − W in
    # still air, carried along by W: x_W(t) = x_0(t) + W t.
    W = np.array([-5.0, 0.0, 2.0])
    base = lab("lab_magnus", "world.ground=false", "air.C_omega=1.0")
    windy = lab("lab_magnus", "world.ground=false", "air.C_omega=1.0", "air.wind=[-5, 0, 2]")
    v0, w0 = np.array(launch_velocity(80.0, 12.0, 0.0)), np.array([0.0, 0.0, 10.0])
    a = tg.Simulation(windy, x=[[0, 0, 0]], v=[v0], w=[w0])
    b = tg.Simulation(base, x=[[0, 0, 0]], v=[v0 - W], w=[w0])
    a.run(t=5.0)
    b.run(t=5.0)
    np.testing.assert_allclose(a.x[0], b.x[0] + W * a.t, atol=1e-9)
    np.testing.assert_allclose(a.v[0], b.v[0] + W, atol=1e-9)
    # a ball released with the wind's velocity: v_rel is vertical, so it drifts with the wind
    # exactly while drag slows its fall below the vacuum value ½gt²
    c = tg.Simulation(windy, x=[[0, 100.0, 0]], v=[W])
    c.run(t=2.0)
    np.testing.assert_allclose(c.x[0, [0, 2]], W[[0, 2]] * 2.0, atol=1e-12)
    assert 0.9 * 0.5 * G * 4.0 < 100.0 - c.x[0, 1] < 0.5 * G * 4.0


def test_headwind_shortens_the_shot():
    # report Figure 3.2-4 vs 3.2-5: the same shots carry less into a 5 m/s headwind
    calm = tg.sweep(lab("lab_magnus"), angles_deg=np.arange(7, 17.01, 0.5))
    head = tg.sweep(lab("lab_headwind"), angles_deg=np.arange(7, 17.01, 0.5))
    assert np.all(head.carry < calm.carry)


# ---------------------------------------------------------------------------------------------
# Drag and lift of the spin ratio (air.model = "spin_ratio", golf_data.md)
# ---------------------------------------------------------------------------------------------
SPIN_RATIO_AIR = ('air.model="spin_ratio"', "air.C_omega=0.03")
"""tour_shot's air before it took the spin_reynolds model: C_D(S), C_L(S) of Ferguson et al. and
the report's spin decay with C_ω = 0.03."""


@pytest.mark.parametrize(
    "speed, angle, spin, wind",
    [
        (76.4, 10.4, 266.5, "[3, 0, -2]"),  # a tour driver with side spin in a crosswind: S from 0.07 up
        (15.0, 40.0, 800.0, "[0, 0, 0]"),  # a slow, spinning lob: S > 0.75, the fit held at its end
        (60.0, 25.0, 20.0, "[0, 0, 0]"),  # almost no spin: S < 0.02, lift in proportion to S
    ],
)
def test_spin_ratio_aerodynamics_match_scipy(speed, angle, spin, wind):
    # dv/dt = g − (½ρA/m)|v_rel|·(C_D(S) v_rel − C_L(S) (ω × v_rel)/|ω|), S = R|ω|/|v_rel|, with the
    # report's spin decay (L.20): the kernels against DOP853 on the numpy law (reference.py), RK4
    # converging at 4th order (the fit's ends are kinks, which these flights do not cross)
    x0, v0 = np.zeros(3), np.array(launch_velocity(speed, angle, 5.0))
    w0 = spin * (np.array(backspin_axis(5.0)) + np.array([0.0, 0.2, 0.0])) / math.hypot(1.0, 0.2)
    errors = []
    for dt in (0.2, 0.1, 0.005):
        scene = lab("tour_shot", *SPIN_RATIO_AIR, "world.ground=false", f"world.dt={dt}", f"air.wind={wind}")
        sim = tg.Simulation(scene, x=[x0], v=[v0], w=[w0])
        rec = sim.run(t=3.0, record_every=round(0.2 / dt))
        ref_x, ref_w = _scipy_trajectory(scene, x0, v0, w0, np.asarray(rec.t))
        errors.append(
            (np.max(np.abs(np.asarray(rec.x)[:, 0] - ref_x)), np.max(np.abs(np.asarray(rec.w)[:, 0] - ref_w)) / spin)
        )
    (ex1, _), (ex2, _), (ex3, ew3) = errors
    assert 10.0 < ex1 / ex2 < 22.0, errors
    assert ex3 < 1e-6 and ew3 < 1e-8, errors
    # and the model is not the lab's law: the same ball with the report's C_D = 0.3 and Magnus
    # coefficient ends metres away
    lab_law = tg.Simulation(
        lab(
            "tour_shot",
            "world.ground=false",
            'air.model="lab"',
            "air.C_D=0.3",
            "air.C_M=0.025",
            "air.omega_M=100",
            f"air.wind={wind}",
        ),
        x=[x0],
        v=[v0],
        w=[w0],
    )
    lab_law.run(t=3.0)
    assert np.linalg.norm(lab_law.x[0] - ref_x[-1]) > 1.0


def test_spin_ratio_aerodynamics_carry_the_tour_averages():
    # golf_data.md: "simple point-mass models with one shared C_D/C_L set typically reach carry
    # within about 5 %, max height within about 4 yd, and land 2–5° shallower than the table".
    # tour_shot's former air (sea-level, a Rules-of-Golf ball, C_D(S) and C_L(S)) flies every club of the
    # table from its launch numbers: carry within 5 %, apex within 4 yd (RK4 at h = 1 ms: its error
    # is far below both). Every club lands shallower than the table, by 1.9° (driver) to 7.5°
    # (4-iron), a little more than the 5° quoted.
    scene = lab("tour_shot", *SPIN_RATIO_AIR)
    for name in PGA:
        mph, launch, rpm, apex_yd, land_deg, carry_yd = TRACKMAN[name]
        res = tg.sweep(scene, angles_deg=[launch], speeds=[mph * MPH], spins=[rpm * RPM])
        got_carry, got_apex = res.carry[0] / YD, (res.flight.apex[0] - scene.ball.radius) / YD
        assert got_carry == pytest.approx(carry_yd, rel=0.05), name
        assert got_apex == pytest.approx(apex_yd, abs=4.0), name
        assert 0.0 < land_deg - res.flight.landing_angle[0] <= 8.0, name
    # the lab's law with one Magnus constant (golf_hole's before this model) cannot fit both ends
    # of the bag: a driver launched as on tour carries 40 % short
    old = lab(
        "tour_shot",
        'air.model="lab"',
        "air.rho=1.2",
        "air.C_D=0.25",
        "air.C_M=0.025",
        "air.omega_M=100",
        "air.C_omega=1",
    )
    mph, launch, rpm, *_, carry_yd = TRACKMAN["PGA Driver"]
    res = tg.sweep(old, angles_deg=[launch], speeds=[mph * MPH], spins=[rpm * RPM])
    assert res.carry[0] / YD < 0.7 * carry_yd


# ---------------------------------------------------------------------------------------------
# Drag and lift of the spin ratio and the Reynolds number (air.model = "spin_reynolds")
# ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "speed, angle, spin, wind",
    [
        (76.4, 10.4, 266.5, "[3, 0, -2]"),  # a tour driver in a crosswind: Re 2.1e5 down to 1.0e5
        (30.0, 35.0, 500.0, "[0, 0, 0]"),  # a slow pitch: Re 8.6e4 down to 4.2e4, through the crisis (6.65e4)
    ],
)
def test_spin_reynolds_aerodynamics_match_scipy(speed, angle, spin, wind):
    # dv/dt = g − (½ρA/m)|v_rel|·(C_D(S, Re) v_rel − C_L(S) (ω × v_rel)/|ω|), Re = ρ|v_rel|2R/μ,
    # dω/dt = −λ|v_rel|ω/R (Smits & Smith): the kernels against DOP853 on the numpy law
    # (reference.py), RK4 converging at 4th order (the S range's ends are kinks these flights do not
    # reach)
    x0, v0 = np.zeros(3), np.array(launch_velocity(speed, angle, 5.0))
    w0 = spin * (np.array(backspin_axis(5.0)) + np.array([0.0, 0.2, 0.0])) / math.hypot(1.0, 0.2)
    errors = []
    for dt in (0.2, 0.1, 0.005):
        scene = lab("tour_shot", "world.ground=false", f"world.dt={dt}", f"air.wind={wind}")
        sim = tg.Simulation(scene, x=[x0], v=[v0], w=[w0])
        rec = sim.run(t=3.0, record_every=round(0.2 / dt))
        ref_x, ref_w = _scipy_trajectory(scene, x0, v0, w0, np.asarray(rec.t))
        errors.append(
            (np.max(np.abs(np.asarray(rec.x)[:, 0] - ref_x)), np.max(np.abs(np.asarray(rec.w)[:, 0] - ref_w)) / spin)
        )
    (ex1, _), (ex2, _), (ex3, ew3) = errors
    assert 10.0 < ex1 / ex2 < 22.0, errors
    assert ex3 < 1e-6 and ew3 < 1e-8, errors
    # the Reynolds number matters: without the drag crisis the same ball ends elsewhere
    plain = tg.Simulation(
        lab("tour_shot", "world.ground=false", "air.C_D_crisis=0", f"air.wind={wind}"), x=[x0], v=[v0], w=[w0]
    )
    plain.run(t=3.0)
    assert np.linalg.norm(plain.x[0] - ref_x[-1]) > 0.5


@pytest.mark.parametrize("rho", [1.225, 0.909])
def test_spin_reynolds_spin_decays_with_the_distance_flown(rho):
    # Smits & Smith: dω/dt = −λ|v|ω/R at sea level (ρ = 1.225 kg/m³), so ω = ω0·exp(−λ d/R) after
    # a distance d, whatever the drag. The spin-down torque is an air force: in thinner air (ρ =
    # 0.909, some 3,000 m up) the spin lasts longer, exp(−(ρ/1.225)·λd/R) (the decay ignored ρ:
    # the same spin per metre at every altitude). Without gravity and with ω along v (no lift: ω ×
    # v = 0) the ball flies straight; λ = 2e-4 (ten times golf's) takes about half the spin in 3 s.
    # RK4 at h = 1 ms: both sides to ~1e-12.
    lam, R = 2e-4, 0.021335
    scene = lab("tour_shot", "world.ground=false", "world.gravity=[0, 0, 0]", f"air.spin_decay={lam}", f"air.rho={rho}")
    v0 = np.array([40.0, 20.0, 5.0])
    w0 = 800.0 * v0 / np.linalg.norm(v0)
    sim = tg.Simulation(scene, x=[[0.0, 1.0, 0.0]], v=[v0], w=[w0])
    sim.run(t=3.0)
    d = np.linalg.norm(sim.x[0] - [0.0, 1.0, 0.0])
    assert np.linalg.norm(np.cross(sim.x[0] - [0.0, 1.0, 0.0], v0)) < 1e-9 * d  # straight
    assert np.linalg.norm(sim.w[0]) == pytest.approx(800.0 * math.exp(-rho / 1.225 * lam * d / R), rel=1e-9)
    assert 0.3 < np.linalg.norm(sim.w[0]) / 800.0 < 0.8


@pytest.mark.parametrize("viscosity", [1.81e-5, 3.62e-5])
def test_spin_reynolds_drag_crisis_as_a_quadrature(viscosity):
    # A ball without spin or gravity slows along a line: dv/dt = −k·C_D(Re)·v², k = ½ρA/m, so the
    # distance flown while slowing from v0 to v is x = ∫_v^v0 du / (k·C_D(Re(u))·u) (C_D: the
    # coefficients at S = 0.02, where the S range is held, plus the crisis
    # C_D_crisis/(1 + (Re/Re_crisis)⁴), Re = ρu·2R/μ). RK4 at h = 1 ms against scipy's quad.
    from scipy.integrate import quad

    scene = lab("tour_shot", "world.ground=false", "world.gravity=[0, 0, 0]", f"air.viscosity={viscosity}")
    a, R = scene.air, scene.ball.radius
    k = 0.5 * a.rho * math.pi * R**2 / scene.ball.mass

    def C_D(u: float, crisis: float = a.C_D_crisis) -> float:
        c = 0.02
        re = a.rho * u * 2.0 * R / a.viscosity
        return a.C_D_S[0] + a.C_D_S[1] * c + a.C_D_S[2] * c * c + crisis / (1.0 + (re / a.Re_crisis) ** 4)

    sim = tg.Simulation(scene, x=[[0.0, 1.0, 0.0]], v=[[40.0, 0.0, 0.0]])
    sim.run(t=4.0)
    v, x = sim.v[0, 0], sim.x[0, 0]
    expected, _ = quad(lambda u: 1.0 / (k * C_D(u) * u), v, 40.0, epsabs=1e-12, epsrel=1e-12)
    assert x == pytest.approx(expected, rel=1e-9)
    # the crisis matters: without it the ball would have slowed to v over a fifth more distance
    without, _ = quad(lambda u: 1.0 / (k * C_D(u, 0.0) * u), v, 40.0)
    assert without > 1.2 * x


def test_the_code_flies_the_published_trackman_table():
    # the launch numbers ti_golf flies, and the measurements it compares with, are golf_data.md's
    assert [row.name for row in TOUR] == list(TRACKMAN)
    for row in TOUR:
        published = TRACKMAN[row.name]
        kept = (row.ball_mph, row.launch_deg, row.spin_rpm, row.apex_yd, row.land_deg, row.carry_yd)
        assert kept == published, row.name
        assert (row.speed_si, row.spin_si) == pytest.approx((published[0] * MPH, published[2] * RPM), rel=1e-12)


def _errors(f, names: list[str]) -> np.ndarray:
    """The model's carry [%], apex [yd] and land angle [deg] errors against the published table,
    shape (3, len(names)), computed here from the model's flights (not by the code's TourFlight)."""
    table = np.array([TRACKMAN[name] for name in names], dtype=float)
    return np.array([100.0 * (f.carry / table[:, 5] - 1.0), f.apex - table[:, 3], f.land - table[:, 4]])


@pytest.fixture(scope="module")
def tour_flight():
    """All 23 rows of the TrackMan table flown at once in tour_shot's air, and their errors."""
    f = fly_tour(lab("tour_shot"))
    assert [row.name for row in f.rows] == list(TRACKMAN)
    return f, _errors(f, list(TRACKMAN))


TOUR_MISSES = {
    "PGA Driver": "lands 2.6° steep",
    "PGA 3-wood": "carries 3.6 % long",
    "PGA 5-wood": "apex 2.2 yd high",
    "PGA Hybrid": "apex 2.4 yd high",
    "PGA 4-iron": "lands 2.2° shallow",
    "PGA 5-iron": "apex 2.1 yd low",
    "LPGA 3-wood": "apex 4.9 yd low, lands 5.1° shallow: lower and slower than the LPGA driver yet lands steeper",
    "LPGA 4-iron": "carries 5.2 % short",
    "LPGA 5-iron": "carries 5.3 % short, apex 2.3 yd low",
    "LPGA 6-iron": "carries 3.1 % short",
    "LPGA 9-iron": "apex 2.2 yd low",
    "LPGA PW": "apex 5.2 yd low",
}
"""The rows outside the issue's targets with the fitted coefficients (docs/real_shots.md)."""


@pytest.mark.parametrize("i", range(len(TRACKMAN)), ids=[name.replace(" ", "-") for name in TRACKMAN])
def test_tour_shot_flies_the_trackman_table(tour_flight, i, request):
    # the targets for each of the 23 rows (the fit saw the 12 PGA rows only): carry within
    # 3 %, apex within 2 yd, land angle within 2° of the table, all at the launch height as the
    # table's (RK4 at h = 1 ms: its error is far below these). The rows the model misses are
    # expected failures, strict: a row that starts to pass must leave the list.
    name = list(TRACKMAN)[i]
    if name in TOUR_MISSES:
        request.applymarker(pytest.mark.xfail(strict=True, reason=TOUR_MISSES[name]))
    f, (carry, apex, land) = tour_flight
    got = f"carry {f.carry[i]:.1f} yd ({carry[i]:+.1f} %), apex {f.apex[i]:.1f} yd ({apex[i]:+.1f}), land {f.land[i]:.1f}° ({land[i]:+.1f})"
    assert abs(carry[i]) <= CARRY_TARGET, f"{name}: {got}"
    assert abs(apex[i]) <= APEX_TARGET, f"{name}: {got}"
    assert abs(land[i]) <= LAND_TARGET, f"{name}: {got}"


def test_tour_shot_misses_are_bounded_and_land_angles_follow_the_table(tour_flight):
    # every row, the misses included, within 5.5 %, 5.5 yd and 5.5°; and the drag crisis fixes the
    # spin-ratio model's shallow landings (golf_data.md: 2–5° shallow): the PGA rows' mean land
    # angle error is within 1° with spin_reynolds and more than 3° shallow with spin_ratio
    f, (carry, apex, land) = tour_flight
    assert np.max(np.abs(carry)) < 5.5 and np.max(np.abs(apex)) < 5.5, f.table()
    assert np.max(np.abs(land)) < 5.5, f.table()
    pga = np.array([name in PGA for name in TRACKMAN])
    assert abs(np.mean(land[pga])) < 1.0, f.table()
    old = fly_tour(lab("tour_shot", *SPIN_RATIO_AIR), PGA_TOUR)
    assert np.mean(_errors(old, PGA)[2]) < -3.0, old.table()
    # the code's own verdict (ti-golf tour marks the rows it misses) agrees with these targets
    within = (np.abs(carry) <= CARRY_TARGET) & (np.abs(apex) <= APEX_TARGET) & (np.abs(land) <= LAND_TARGET)
    np.testing.assert_array_equal(f.within(), within)
    assert sorted(name for name in TRACKMAN if name not in TOUR_MISSES) == sorted(np.array(list(TRACKMAN))[within])


# ---------------------------------------------------------------------------------------------
# Ground plane contact (report Appendix B)
# ---------------------------------------------------------------------------------------------
def _penner_bounce(u, v_n, spin, R, mu):
    """Penner (2002; golf_data.md) for a ball landing at forward speed u and descent speed v_n
    [m/s] with backspin ``spin`` [rad/s] on level turf: the impact is solved in a frame tilted by
    θ_c = 15.4°·(v/18.6 m/s)·(φ/44.4°) toward the ball, with e = 0.510 − 0.0375 v_n' + 0.000903 v_n'²
    (0.120 above 20 m/s); the ball rolls out if μ ≥ μ_c = 2(u' + Rω)/(7(1+e)v_n'), u'' = (5/7)u' −
    (2/7)Rω and ω'' = −u''/R, else slides, u'' = u' − μ(1+e)v_n', ω'' = ω − 5μ(1+e)v_n'/(2R).
    Returns the velocity (x forward, y up) and backspin after the bounce, and whether it rolled."""
    phi = math.degrees(math.atan2(v_n, u))
    theta = math.radians(min(15.4 * (math.hypot(u, v_n) / 18.6) * (phi / 44.4), 90.0 - phi))
    n, t = np.array([-math.sin(theta), math.cos(theta)]), np.array([math.cos(theta), math.sin(theta)])
    v_in = np.array([u, -v_n])
    vn, ut = -v_in @ n, v_in @ t
    e = 0.510 - 0.0375 * vn + 0.000903 * vn**2 if vn <= 20.0 else 0.120
    rolls = mu >= 2 * (ut + R * spin) / (7 * (1 + e) * vn)
    if rolls:
        ut2 = 5 / 7 * ut - 2 / 7 * R * spin
        spin2 = -ut2 / R
    else:
        ut2 = ut - mu * (1 + e) * vn
        spin2 = spin - 5 * mu * (1 + e) * vn / (2 * R)
    return e * vn * n + ut2 * t, spin2, rolls


TURF = (
    "world.gravity=[0,0,0]",
    "world.integrator=semi_implicit",
    "world.dt=0.0001",
    "contact.turf=true",
    "contact.mu=0.4",
    "ball.radius=0.021335",
    "ball.mass=0.04593",
)


@pytest.mark.parametrize(
    "u, v_n, spin, rolls",
    [
        (16.7, 17.7, 600.0, True),  # a tour 7-iron landing (24 m/s at 47°): it rolls out, slowly forward
        (25.0, 6.0, 0.0, False),  # a low, fast, spinless skid: it slides
        (9.0, 14.0, 1000.0, True),  # a steep wedge with much backspin: it checks and spins back
    ],
)
@pytest.mark.parametrize("where", ["plane", "colliding", "terrain"])
def test_a_turf_bounce_is_penners(u, v_n, spin, rolls, where):
    # gravity off, so one step holds the whole impact and the closed form applies to round-off;
    # "plane": one ball (the flight kernel's plane contact), "colliding": two balls far apart (the
    # collision step's planes), "terrain": a flat height field whose one surface type has turf
    R = 0.021335
    want_v, want_spin, want_rolls = _penner_bounce(u, v_n, spin, R, 0.4)
    assert want_rolls == rolls
    overrides = list(TURF)
    if where == "terrain":
        overrides += [
            "contact.turf=false",
            'terrain.kind="generated"',
            "terrain.amplitude=0.0",
            "terrain.origin=[-50,0,-50]",
            "terrain.size=[100,100]",
            "terrain.resolution=[5,5]",
        ]
    if where == "colliding":
        overrides.append("contact.solver=jacobi")  # (the report's sweeps: one step holds the impact)
    scene = lab("lab_vacuum", *overrides)
    if where == "terrain":
        import dataclasses

        from ti_golf.scene.schema import Surface

        scene = dataclasses.replace(scene, surfaces=(Surface(name="fairway", turf=True),))
    x = [[0.0, R + 1e-3, 0.0]] + ([[0.0, R + 1e-3, 30.0]] if where == "colliding" else [])
    v = [[u, -v_n, 0.0]] * len(x)
    w = [[0.0, 0.0, spin]] * len(x)
    sim = tg.Simulation(scene, x=x, v=v, w=w)
    assert (sim.solver is not None) == (where == "colliding")
    sim.run(t=0.01)
    np.testing.assert_allclose(sim.v[:, :2], [want_v] * len(x), rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(sim.w[:, 2], want_spin, rtol=1e-9)
    assert want_v[1] > 0  # it left the ground
    if spin == 1000.0:
        assert want_v[0] < 0 < want_spin  # it checks: back it comes, rolling backward


def test_dropped_ball_comes_to_rest_without_sinking_or_jitter():
    scene = lab("lab_vacuum", "world.integrator=semi_implicit", "world.dt=0.001")
    sim = tg.Simulation(scene, x=[[0, 0.5, 0]])
    ys = []
    for _ in range(300):
        sim.step(10)
        ys.append(sim.x[0, 1])
    assert sim.counts()["at_rest"] == 1
    assert min(ys) >= 0.02 - 1e-12  # never below the surface
    x_rest = sim.x.copy()
    sim.run(t=2.0)
    np.testing.assert_array_equal(sim.x, x_rest)  # at rest means at rest
    assert sim.x[0, 1] == pytest.approx(0.02, abs=1e-9)


STEPS = [None, "jacobi", "gauss_seidel", "jacobi/parallel", "gauss_seidel/parallel"]
"""How a ball is stepped: alone (``advance``), or beside a ball far away by a collision solver,
serially as few balls are on the CPU or in parallel launches as many are."""


def solver_keys(solver: str | None) -> list[str]:
    """The scene key choosing the contact solver of a :data:`STEPS` entry."""
    return [f"contact.solver={solver.split('/')[0]}"] if solver else []


def stepped_by(solver: str | None, sim: tg.Simulation) -> tg.Simulation:
    """``sim`` stepped as the :data:`STEPS` entry says (its collision solver made parallel)."""
    from ti_golf.solvers import CollisionSolver

    assert (sim.solver is None) == (solver is None)
    if solver and solver.endswith("/parallel"):
        sim.solver = CollisionSolver(sim.model, serial=False)
    return sim


def bounce_peaks(integrator: str, solver: str | None, H: float, e: float, h: float) -> tuple[float, float]:
    """The first two heights [m] to which a ball dropped from H bounces on the ground (no air, no
    friction), sampled at every step of h, stepped as :data:`STEPS` entry ``solver`` says."""
    over = (f"contact.e={e}", f"world.integrator={integrator}", f"world.dt={h}", "contact.mu=0")
    x = [[0.0, 0.02 + H, 0.0], [10.0, 0.02, 0.0]][: 1 if solver is None else 2]
    sim = stepped_by(solver, tg.Simulation(lab("lab_vacuum", *over, *solver_keys(solver)), x=x))
    rec = sim.run(t=1.0 + 2.0 * e * math.sqrt(2.0 * H / G), record_every=1)
    y = np.asarray(rec.x)[:, 0, 1] - 0.02
    peaks = [y[i] for i in range(1, len(y) - 1) if y[i - 1] < y[i] >= y[i + 1] and y[i] > 0.01]
    return peaks[0], peaks[1]


def rebound_apexes(solver: str | None, H: float, e: float, h: float) -> list[float]:
    """The heights [m] above the ground to which a ball dropped from H (no air, no friction) rises
    after each of its first two bounces under RK4 with steps of h, stepped as :data:`STEPS` entry
    ``solver`` says: from its state at the end of the step of each bounce, y + v_y²/2g, exact for a
    flight in vacuum (RK4 flies its parabola exactly)."""
    over = (f"contact.e={e}", "world.integrator=rk4", f"world.dt={h}", "contact.mu=0", "world.v_rest=0")
    x = [[0.0, 0.02 + H, 0.0], [10.0, 0.02, 0.0]][: 1 if solver is None else 2]
    sim = stepped_by(solver, tg.Simulation(lab("lab_vacuum", *over, *solver_keys(solver)), x=x))
    apexes: list[float] = []
    falling = True
    while len(apexes) < 2 and sim.t < 1.0 + 4.0 * math.sqrt(2.0 * H / G):
        sim.step()
        (_, y, _), (_, v_y, _) = sim.x[0], sim.v[0]
        if falling and v_y > 0.0:
            apexes.append(y - 0.02 + v_y**2 / (2.0 * G))
        falling = v_y < 0.0
    return apexes


@pytest.mark.parametrize("solver", STEPS, ids=lambda s: s or "advance")
@pytest.mark.parametrize("e", [0.9, 0.6])
def test_a_bounce_split_at_the_time_of_impact_adds_no_error_of_its_own(e, solver):
    # A ball dropped from H rebounds to e²H, then e⁴H. The step that meets the ground is split at
    # the time of impact, its velocity too: the ball leaves the ground at e times the speed it
    # reached it with, and gravity acts on the rest of the step after the bounce. (The rebound was
    # e times the step's end velocity, which holds a whole step of gravity: +0.45 % of e²H at e =
    # 0.9, h = 1 ms, under either integrator.) RK4 flies a parabola exactly, and the time of impact
    # is the root of the parabola through the step's gaps, so its rebounds are exact to rounding
    # (the straight line between the gaps missed by up to 3e-6 of e²H). At H2 the impact falls
    # 0.5 µs into a step: the contact test's straight line x + h·v runs ½·g·h² below RK4's curve and
    # fires while the free flight still ends 4 µm above the ground (the rebound was then (1 + e)·v·h,
    # 1.2 %, too high). Semi-implicit Euler's first height (sampled at each step) is e²H less its
    # own flight's first-order error, (e² + e)·v0·h/2 (a fall from rest loses v·h/2 of height and
    # the rise another), to second order in h.
    h = 1e-3
    for H in (1.0, 0.5 * G * (0.452 + 0.5e-6) ** 2):
        first, second = rebound_apexes(solver, H, e, h)
        assert first == pytest.approx(e**2 * H, rel=1e-12) and second == pytest.approx(e**4 * H, rel=1e-12), H
    H = 1.0
    first, _ = bounce_peaks("semi_implicit", solver, H, e, h)
    v0 = math.sqrt(2.0 * G * H)
    assert first == pytest.approx(e**2 * H - (e**2 + e) * v0 * h / 2.0, abs=3.0 * G * h**2)


@pytest.mark.parametrize("solver", STEPS, ids=lambda s: s or "advance")
def test_a_ball_rolling_with_topspin_under_the_reports_magnus_law_rolls_without_hopping(solver):
    # The lab's Magnus law (L.2), linear in ω, presses a ball rolling at 9 m/s with ω = v/R of
    # topspin into the ground at some 2 g: each 10 ms step's approach (0.28 m/s) passed
    # v_bounce + 2|g|h (0.25 m/s), so it bounced at e = 0.5 every other step, hopping up to 9 mm
    # and flickering between flying and rolling. It rolls on the ground, in contact at every step,
    # and the rolling resistance slows it by at least μ_roll·g (the downforce adds to it). With a
    # second ball far away the collision solvers step it (they let it hop and gain speed: Magnus
    # does no work, yet 20 m/s became 20.21 m/s in 0.5 s).
    scene = lab("lab_magnus", *solver_keys(solver))
    R, mu_r = scene.ball.radius, scene.contact.mu_roll
    x = [[0.0, R, 0.0], [0.0, R, 2.0]][: 1 if solver is None else 2]
    v, w = [[9.0, 0.0, 0.0], [0.0, 0.0, 0.0]][: len(x)], [[0.0, 0.0, -9.0 / R], [0.0, 0.0, 0.0]][: len(x)]
    sim = stepped_by(solver, tg.Simulation(scene, x=x, v=v, w=w))
    ys, statuses, speeds = [], [], []
    for _ in range(200):
        sim.step()
        x, v, _ = sim.ball(0)
        ys.append(x[1])
        statuses.append(int(sim.status[0]))
        speeds.append(v[0])
    assert max(ys) - R < 1e-6 and min(ys) - R > -1e-6  # on the ground, neither above nor in it
    assert set(statuses) == {tg.ROLLING}
    assert speeds[-1] <= 9.0 - mu_r * G * 200 * scene.world.dt + 1e-9


IMPACT = ("world.gravity=[0,0,0]", "air.C_D=0", "contact.e=0.5", "world.v_rest=0")
"""An impact alone: no gravity, no air, restitution 0.5."""
F32_CARRIED = 1e-7
"""Relative tolerance where the Gauss–Seidel sweeps carry a contact's impulses in f32 (2^-24 of
each, a few times over)."""


@pytest.mark.parametrize("solver", STEPS, ids=lambda s: s or "advance")
def test_a_ball_striking_the_ground_takes_coulomb_friction_of_the_whole_impact(solver):
    # B.15 for a solid sphere striking a plane at (u, −v_n) without spin: the normal impulse per
    # unit mass is (1 + e)·v_n; friction stops the slip, (2/7)·u, or gives out at μ·(1 + e)·v_n;
    # ω = (5/2)·J_t/R. Rolling resistance brakes a resting contact only, not an impact's jolt, in
    # every solver (the Gauss–Seidel sweeps took μ_roll·(1 + e)·v_n = 0.3 m/s more from u with
    # μ_roll = 0.2). With a ball far away (the collision solvers), the Gauss–Seidel sweeps bounded
    # the friction by the compression alone, less the gap closed in the step.
    u, v_n, R, e = 5.0, 3.0, 0.02, 0.5
    for mu in (0.1, 0.4):
        over = (*IMPACT, f"contact.mu={mu}", "contact.mu_roll=0.2", *solver_keys(solver))
        x = [[0.0, R + 1e-3, 0.0], [10.0, 1.0, 0.0]][: 1 if solver is None else 2]
        v = [[u, -v_n, 0.0], [0.0, 0.0, 0.0]][: len(x)]
        sim = stepped_by(solver, tg.Simulation(lab("lab_vacuum", *over), x=x, v=v, radius=R))
        sim.step(3)
        J_t = min(2 / 7 * u, mu * (1 + e) * v_n)
        tol = F32_CARRIED if solver and solver.startswith("gauss_seidel") else 1e-12
        np.testing.assert_allclose(sim.v[0], [u - J_t, e * v_n, 0.0], rtol=tol, atol=1e-12)
        np.testing.assert_allclose(sim.w[0], [0.0, 0.0, -2.5 * J_t / R], rtol=tol, atol=1e-9)


@pytest.mark.parametrize("solver", STEPS, ids=lambda s: s or "advance")
def test_a_plastic_impact_ends_its_step_on_the_ground_not_in_it(solver):
    # a ball 3 mm above the ground falls at 10 m/s (no gravity, e = 0): it reaches the ground 30 %
    # into the 1 ms step. The Gauss–Seidel sweeps close the gap exactly within the step (v_n =
    # −3 m/s); the position's split at the time of impact, made for a ball turned back, put it
    # (1 − 0.3)·3 mm into the ground, (1 − k_p) of that left after the projection (B.18). Every
    # solver ends it on the ground (to rounding), and none above it by more than the gap it had.
    R, gap0, speed = 0.02, 3e-3, 10.0
    over = (*IMPACT, "contact.e=0", "contact.mu=0", *solver_keys(solver))
    x = [[0.0, R + gap0, 0.0], [10.0, 1.0, 0.0]][: 1 if solver is None else 2]
    v = [[0.0, -speed, 0.0], [0.0, 0.0, 0.0]][: len(x)]
    sim = stepped_by(solver, tg.Simulation(lab("lab_vacuum", *over), x=x, v=v, radius=R))
    sim.step(1)
    gap = sim.x[0, 1] - R
    assert -1e-12 <= gap <= gap0 + 1e-12, gap
    sim.step(1)  # and touching it at rest from then on
    assert abs(sim.x[0, 1] - R) < 1e-12 and abs(sim.v[0, 1]) < 1e-12


@pytest.mark.parametrize("solver", STEPS, ids=lambda s: s or "advance")
def test_a_ball_settling_onto_the_ground_under_rk4_lands_on_it_and_rests(solver):
    # 0.3 mm above the ground at rest, g = 9.81, RK4 at h = 10 ms (lab_vacuum): the free flight
    # crosses the ground and the contact only slows the ball (an approach of g·h, below the
    # inelastic speed). Ending the step on the free flight's path plus h·(v − v_free) left it
    # ½·g·h² = 0.49 mm above the ground for ever, flying, under the Gauss–Seidel sweeps
    R = 0.02
    x = [[0.0, R + 3e-4, 0.0], [10.0, R, 0.0]][: 1 if solver is None else 2]
    sim = stepped_by(solver, tg.Simulation(lab("lab_vacuum", *solver_keys(solver)), x=x, radius=R))
    assert sim.scene.world.integrator == "rk4"
    sim.step(1)
    assert abs(sim.x[0, 1] - R) < 1e-12
    sim.run(t=1.0)
    assert sim.status[0] == tg.AT_REST and abs(sim.x[0, 1] - R) < 1e-12


@pytest.mark.parametrize("solver", STEPS[1:])
@pytest.mark.parametrize("phi, mu", [(30.0, 0.4), (60.0, 0.1)], ids=["stops_the_slip", "gives_out"])
def test_an_oblique_impact_of_two_balls_takes_coulomb_friction_of_the_whole_impact(solver, phi, mu):
    # equal solid spheres, ball a at 3 m/s striking ball b at rest whose centre lies φ off its
    # path: J_n = (1 + e)·(m/2)·v cos φ; the friction stops the slip at the contact, v sin φ,
    # with J_t = (m/7)·v sin φ, or gives out at μ·J_n; each ball spins at (5/2)·J_t/(m R). The
    # Jacobi sweeps scaled an impact's friction by contact.relax (half the slip left), the
    # Gauss–Seidel sweeps bounded it by μ times the compression alone (1/(1 + e) of it).
    speed, R, m, e = 3.0, 0.02, 0.045, 0.5
    p, d = np.radians(phi), 2 * R + 1e-9
    x = [[0.0, 0.0, 0.0], [d * np.cos(p), d * np.sin(p), 0.0]]
    over = (*IMPACT, "world.ground=false", f"contact.mu={mu}", *solver_keys(solver))
    v = [[speed, 0.0, 0.0], [0.0, 0.0, 0.0]]
    sim = stepped_by(solver, tg.Simulation(lab("lab_vacuum", *over), x=x, v=v, radius=R, mass=m))
    sim.step(1)
    J_n = (1 + e) * m / 2 * speed * np.cos(p)
    J_t = min(m / 7 * speed * np.sin(p), mu * J_n)
    np.testing.assert_allclose(
        sim.w[:, 2], 2.5 * J_t / (m * R), rtol=F32_CARRIED if solver.startswith("gauss_seidel") else 1e-12
    )
    np.testing.assert_allclose(m * sim.v.sum(axis=0), [m * speed, 0.0, 0.0], rtol=1e-12, atol=1e-15)


def test_rolling_ball_stops_where_closed_form_says():
    # A ball pushed along the ground at u0 with no spin (no air): it slides, friction μ slows it
    # and spins it up until the contact point sticks, then it rolls and rolling resistance μ_roll
    # stops it. Rolling resistance slows the centre by μ_r·g without changing the contact-point
    # slip, so the slip decays at (7/2)μg (solid sphere) and the centre at (μ+μ_r)g while sliding;
    # then the ball rolls at du/dt = −μ_r g.
    u0, mu, mu_r = 3.0, 0.3, 0.05
    scene = lab(
        "lab_vacuum", "world.integrator=semi_implicit", "world.dt=0.0005", f"contact.mu={mu}", f"contact.mu_roll={mu_r}"
    )
    sim = tg.Simulation(scene, x=[[0, 0.02, 0]], v=[[u0, 0, 0]])
    sim.run(t=15.0, until="rest")
    t1 = u0 / (3.5 * mu * G)
    u1 = u0 - (mu + mu_r) * G * t1
    distance = u0 * t1 - 0.5 * (mu + mu_r) * G * t1**2 + u1**2 / (2 * mu_r * G)
    assert sim.counts()["at_rest"] == 1
    assert sim.x[0, 0] == pytest.approx(distance, abs=0.01)


@pytest.mark.parametrize("velocity", [[0.0, -500.0, 0.0], [353.6, -353.6, 0.0]])
def test_no_tunnelling_at_500_mps(velocity):
    # h·|v| = 0.5 m is 25 radii per step: the half-space test (L.3, L.4) still catches the contact.
    scene = lab("lab_vacuum", "world.integrator=semi_implicit", "world.dt=0.001", "contact.e=0.8")
    sim = tg.Simulation(scene, x=[[0, 1.0, 0]], v=[velocity])
    lowest = np.inf
    for _ in range(400):
        sim.step(1)
        lowest = min(lowest, sim.x[0, 1])
    assert lowest >= 0.02 - 1e-9
    assert sim.v[0, 1] != 0 or sim.x[0, 1] > 0.02  # it bounced back up


@pytest.mark.parametrize("n_balls", [1, 2], ids=["advance", "collision_step"])
def test_spin_about_the_normal_decays_at_five_halves_mu_roll_g_over_r(n_balls):
    # reference: a ball spinning on the spot on level ground feels the torque μ_roll·N·R, so
    # dω_y/dt = −(5/2)·μ_roll·g/R until it stops. The resting impulse is g·h every step, so the
    # semi-implicit steps follow the line exactly (round-off only); the ball does not move.
    mu_r, w0, h = 0.05, 30.0, 0.001
    sc = tg.load_scene(
        data={
            "air": {"rho": 0.0},
            "world": {"integrator": "semi_implicit", "dt": h},
            "contact": {"mu": 0.4, "mu_roll": mu_r, "solver": "jacobi"},  # (the report's sweeps)
        }
    )
    x0 = np.array([[0.0, 0.02, 0.0], [5.0, 0.02, 0.0]][:n_balls])
    sim = tg.Simulation(sc, x=x0, w=[[0.0, w0, 0.0]] * n_balls, radius=0.02)
    assert (sim.solver is not None) == (n_balls == 2)
    rate = 2.5 * mu_r * G / 0.02
    sim.step(1)  # the first step meets the ground (its resting impulse starts then)
    for _ in range(3):
        sim.step(100)
        np.testing.assert_allclose(sim.w[:, 1], w0 - rate * sim.t, rtol=1e-12)
    np.testing.assert_array_equal(sim.x, x0)
    sim.run(t=w0 / rate)
    np.testing.assert_array_equal(sim.w, 0.0)
    assert sim.counts()["at_rest"] == n_balls


def test_friction_spins_up_a_sliding_ball():
    # sliding without spin, friction builds spin until the ball rolls: ω_z = −v_x / R
    scene = lab("lab_vacuum", "world.integrator=semi_implicit", "world.dt=0.0005", "contact.mu_roll=0")
    sim = tg.Simulation(scene, x=[[0, 0.02, 0]], v=[[2.0, 0, 0]])
    sim.run(t=1.0)
    assert sim.w[0, 2] == pytest.approx(-sim.v[0, 0] / 0.02, rel=1e-6)
    assert sim.v[0, 0] == pytest.approx(5 / 7 * 2.0, rel=1e-3)  # angular momentum about the contact point


@pytest.mark.parametrize("integrator", ["semi_implicit", "rk4"])
def test_the_longest_step_a_ball_s_drag_allows_is_the_explicit_step_s_limit(integrator):
    # a 10 m ball of a milligram reaches its terminal speed v_t = √(g/(k/m)) (0.4 mm/s) in about
    # v_t/g = 41 µs: a step of 1 ms threw it to the ground in one step, with exit code 0. The
    # explicit step's map v' = v + h(g − (k/m)v²) has v_t as its fixed point, stable while
    # h ≤ 1/((k/m)v_t) = v_t/g: below that limit the ball settles at v_t exactly, above it is refused
    from ti_golf.errors import ConfigError

    def dropped(dt: float) -> tg.Scene:
        return tg.load_scene(
            data={
                "world": {"dt": dt, "integrator": integrator, "ground": False},
                "launch": {"position": [0, 20, 0], "speed": 0.0},
                "ball": {"radius": 10.0, "mass": 1e-6},
                "air": {"rho": 1.2, "C_D": 0.3, "gamma": 2},
            }
        )

    k = 0.5 * 1.2 * math.pi * 10.0**2 * 0.3 / 1e-6
    v_t = math.sqrt(9.81 / k)
    h_max = v_t / 9.81
    with pytest.raises(ConfigError, match=rf"world.dt' = 0.001 s is too long a step.*at most {h_max:.3g} s"):
        tg.Simulation(dropped(1e-3))
    with pytest.raises(ConfigError, match="too long a step"):
        tg.Simulation(dropped(1.01 * h_max))
    sim = tg.Simulation(dropped(0.9 * h_max))
    sim.step(120)  # 108 v_t/g: the distance to v_t shrinks by |1 − 2·0.9| = 0.8 a step (or faster)
    assert sim.v[0, 1] == pytest.approx(-v_t, rel=1e-6) and sim.x[0, 1] > 20.0 - 2.0 * v_t * sim.t
    with pytest.raises(ConfigError, match="too long a step"):  # (a change is checked too, and not made)
        sim.set("air.rho", 2.0)  # (h_max shrinks as 1/√ρ: 0.9 × √(2/1.2) = 1.16 of it)
    assert sim.scene.air.rho == 1.2


def test_a_step_that_sinks_a_resting_ball_through_half_its_radius_is_refused_where_balls_collide():
    # the contacts are solved from each step's start, and a step lets gravity carry a ball at rest
    # g·h² into what holds it: the bundled heap's 10,000 balls ended 102 % of a radius deep in each
    # other at world.dt = 0.05 s (g·h² = 1.2 R), with exit code 0. Refused past g·h² = R/2; a column
    # of balls just inside that limit still stands, each ball's overlap a fraction of g·h²
    from ti_golf.errors import ConfigError

    R, g = 0.02, 9.81
    h_max = math.sqrt(0.5 * R / g)

    def column(dt: float, collisions: bool = True) -> tg.Scene:
        return tg.load_scene(data={"world": {"dt": dt, "collisions": collisions}, "air": {"rho": 0.0}})

    x = [[0.0, R + 2 * R * k, 0.0] for k in range(4)]
    with pytest.raises(
        ConfigError, match=rf"world.dt' = .* too long a step for balls that collide.*at most {h_max:.3g} s"
    ):
        tg.Simulation(column(1.01 * h_max), x=x)
    tg.Simulation(column(1.01 * h_max), x=x[:1])  # (one ball: nothing collides)
    tg.Simulation(column(1.01 * h_max, collisions=False), x=x)
    sim = tg.Simulation(column(0.99 * h_max), x=x)
    sim.run(t=1.0)
    deepest = sim.deepest_overlap()
    assert deepest is None or deepest.depth < 0.5 * g * sim.dt**2, deepest
    assert np.all(np.abs(sim.x[:, 0]) < 1e-9) and sim.x[-1, 1] > 6.5 * R  # (standing, not scattered)
    with pytest.raises(ConfigError, match="too long a step for balls that collide"):
        sim.set("world.dt", 1.01 * h_max)  # (a change is checked too, and not made)
    assert sim.dt == pytest.approx(0.99 * h_max)


@pytest.mark.parametrize("integrator", ["semi_implicit", "rk4"])
def test_the_longest_step_a_ball_s_spin_decay_allows_keeps_the_spin_s_sense(integrator):
    # laminar spin decay dω/dt = −k_ω·ω at a fixed rate k_ω = ½ρπR²·C_ω/m: a step maps ω to
    # ω·P(h·k_ω), P(z) = 1 − z (semi-implicit Euler) or the RK4 polynomial 1 − z + z²/2 − z³/6 + z⁴/24,
    # so after n steps ω = ω0·P(z)^n exactly (no drag on a ball at rest, no Magnus). Past z = 1 an
    # Euler step turns the spin around (z = 1.5: −0.5 ω0) and past 2 it grows: refused up front
    from ti_golf.errors import OVERRIDES, ConfigError

    R, m, rho, C_omega = 0.02, 1e-4, 1.2, 100.0  # a 0.1 g ball of the lab's radius: k_ω = 754/s
    k_omega = 0.5 * rho * math.pi * R**2 * C_omega / m
    w0 = np.array([[0.0, 0.0, 300.0]])

    def spun(dt: float) -> tg.Scene:
        return lab(
            "lab_laminar",
            "world.ground=false",
            "world.gravity=[0, 0, 0]",
            "air.C_M=0",
            f"air.C_omega={C_omega}",
            f"ball.mass={m}",
            f"ball.radius={R}",
            f"air.rho={rho}",
            f'world.integrator="{integrator}"',
            f"world.dt={dt}",
        )

    h = 0.99 / k_omega
    sim = tg.Simulation(spun(h), x=[[0.0, 1.0, 0.0]], v=[[0.0, 0.0, 0.0]], w=w0)
    sim.step(5)
    z = h * k_omega
    P = 1 - z if integrator == "semi_implicit" else 1 - z + z**2 / 2 - z**3 / 6 + z**4 / 24
    np.testing.assert_allclose(sim.w[0], w0[0] * P**5, rtol=1e-9, atol=1e-12)
    assert sim.w[0, 2] > 0.0  # the spin kept its sense
    with pytest.raises(
        ConfigError,
        match=r"'world.dt' is too long a step for the spin decay: .* and air.C_omega = 100, the spin of ball 0",
    ) as got:
        tg.Simulation(spun(1.01 / k_omega), x=[[0.0, 1.0, 0.0]], w=w0)
    assert got.value.source == OVERRIDES  # (--set gave both; the first overridden of world.dt, C_omega)
    assert f"at most {1 / k_omega:.3g} s" in str(got.value)
    # the same in the spin_reynolds air, λ|v_rel|/R: ten times its limit at the tour's 7-iron speed
    with pytest.raises(ConfigError, match=r"'air.spin_decay' makes the spin decay too fast: .*the spin of ball 0"):
        tg.Simulation(lab("tour_shot", "air.spin_decay=300"))
