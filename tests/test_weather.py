"""Weather and wind as golfers meet them: air density and viscosity from the weather against the
standard atmosphere and steam tables, the keys' precedence, the logarithmic wind profile seen by
every kernel, head-, tail- and cross-wind flights against an independent scipy integration, and
the carry gained at altitude against what the density ratio predicts.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import run_cli

import ti_golf as tg
from ti_golf import ConfigError
from ti_golf.bench.reference import landing_scipy
from ti_golf.golf.sweep import launch_grid
from ti_golf.scene import weather

# The PGA Tour driver of golf_data.md (TrackMan 2023): 171 mph, 10.4°, 2545 rpm.
DRIVER = {"angles_deg": [10.4], "speeds": [171 * 0.44704], "spins": [2545 * 2 * math.pi / 60]}


# ---------------------------------------------------------------------------------------------
# Density and viscosity from the weather (pure Python)
# ---------------------------------------------------------------------------------------------
# U.S. Standard Atmosphere 1976 (= ISA below 32 km), by geometric altitude: altitude [m],
# temperature [K], pressure [Pa], density [kg/m³], dynamic viscosity [Pa·s], as tabulated to five
# significant figures.
ISA_TABLE = [
    (0.0, 288.15, 101325.0, 1.2250, 1.7894e-5),
    (1000.0, 281.65, 89876.0, 1.1117, 1.7579e-5),
    (1500.0, 278.40, 84559.0, 1.0581, 1.7420e-5),
    (2000.0, 275.15, 79501.0, 1.0066, 1.7260e-5),
    (3000.0, 268.66, 70121.0, 0.90925, 1.6938e-5),
    (5000.0, 255.68, 54048.0, 0.73643, 1.6282e-5),
]


@pytest.mark.parametrize("altitude, T, p, rho, mu", ISA_TABLE)
def test_dry_air_at_altitude_is_the_standard_atmosphere(altitude, T, p, rho, mu):
    # barometric formula, ideal gas and Sutherland's law reproduce the table to its last figure
    assert weather.isa_temperature(altitude) + weather.KELVIN == pytest.approx(T, abs=0.01)
    assert weather.isa_pressure(altitude) == pytest.approx(p, rel=1e-5)
    got_rho, got_mu = weather.air_from_weather(altitude=altitude)
    assert got_rho == pytest.approx(rho, rel=1e-4)
    assert got_mu == pytest.approx(mu, rel=1e-4)


def test_sea_level_at_15_degrees_is_1_225():
    rho, mu = weather.air_from_weather(temperature=15.0, pressure=101325.0, humidity=0.0)
    assert rho == pytest.approx(1.2250, abs=5e-5)
    assert mu == pytest.approx(1.789e-5, rel=5e-4)  # Sutherland at 288.15 K
    # the standard atmosphere's tropopause, 216.65 K: 1.4216e-5 Pa·s in the 1976 table
    assert weather.sutherland_viscosity(216.65 - weather.KELVIN) == pytest.approx(1.4216e-5, rel=1e-4)


# Saturation vapour pressure of water [Pa] (IAPWS-95, Wagner & Pruß 2002, as tabulated in the
# CRC Handbook); Buck (1981) states his eq. (8) within 0.2 % over −40 to 50 °C.
STEAM_TABLE = [(0.01, 611.66), (10.0, 1228.2), (20.0, 2339.3), (30.0, 4247.0), (40.0, 7384.9), (50.0, 12352.0)]


@pytest.mark.parametrize("t, e_s", STEAM_TABLE)
def test_buck_saturation_pressure_matches_the_steam_table(t, e_s):
    assert weather.saturation_vapour_pressure(t) == pytest.approx(e_s, rel=2e-3)


@pytest.mark.parametrize("t, phi", [(15.0, 1.0), (30.0, 0.6), (35.0, 1.0)])
def test_humid_air_is_lighter_by_the_vapour_it_holds(t, phi):
    # Water (18.015 g/mol) replacing dry air (28.964 g/mol) at the same T and p: the virtual
    # temperature of meteorology, ρ = p/(R_d T_v), T_v = T/(1 − (e/p)(1 − ε)), ε = M_v/M_d = 0.622.
    p = 101325.0
    dry, _ = weather.air_from_weather(temperature=t, pressure=p, humidity=0.0)
    humid, _ = weather.air_from_weather(temperature=t, pressure=p, humidity=phi)
    e = phi * weather.saturation_vapour_pressure(t)
    T_v = (t + 273.15) / (1.0 - (e / p) * (1.0 - 18.01528 / 28.9644))
    assert humid == pytest.approx(p / (287.053 * T_v), rel=1e-5)
    assert humid < dry
    assert (dry - humid) / dry == pytest.approx(0.378 * e / p, rel=2e-3)


# ---------------------------------------------------------------------------------------------
# The keys: the weather sets ρ and μ, and what would have no effect is refused
# ---------------------------------------------------------------------------------------------
def _air(table: dict, overrides: list[str] | None = None) -> tg.Scene:
    return tg.load_scene("s.toml", overrides, data={"description": "t", "air": table})


def test_weather_keys_set_density_and_viscosity():
    scene = _air({"altitude": 1000.0})
    assert (scene.air.rho, scene.air.viscosity) == weather.air_from_weather(altitude=1000.0)
    assert scene.air.rho == pytest.approx(1.1117, rel=1e-4)
    hot = _air({"temperature": 35.0, "pressure": 95000.0, "humidity": 0.8})
    assert hot.air.rho == weather.air_density(35.0, 95000.0, 0.8)
    assert hot.air.viscosity == weather.sutherland_viscosity(35.0)
    plain = _air({})  # no weather: the keys as given (their defaults here)
    assert (plain.air.rho, plain.air.viscosity) == (1.3, 1.81e-5)


REFUSED = {
    # (air table in the file, --set overrides, the key named, fragment of the message)
    "rho_beside_weather": ({"rho": 1.2, "temperature": 20.0}, [], "air.rho", "air.temperature"),
    "viscosity_beside_weather": (
        {"model": "spin_reynolds", "gamma": 2, "viscosity": 1.8e-5, "humidity": 0.5},
        [],
        "air.viscosity",
        "sets μ",
    ),
    "viscosity_of_the_lab_air": ({"viscosity": 1.8e-5}, [], "air.viscosity", 'air.model = "spin_reynolds"'),
    "altitude_beside_pressure_and_temperature": (
        {"pressure": 90000.0, "altitude": 1000.0, "temperature": 20.0},
        [],
        "air.altitude",
        "air.pressure and air.temperature",
    ),
    "both_on_the_command_line": ({}, ["air.rho=1.2", "air.altitude=100"], "air.rho", "give one or the other"),
    "z0_above_reference": ({"wind_profile": "log", "wind_z0": 20.0}, [], "air.wind_z0", "below air.wind_height"),
    "reference_below_z0": ({"wind_profile": "log", "wind_height": 0.01}, [], "air.wind_height", "exceed"),
    "height_of_a_constant_wind": ({"wind_height": 2.0}, [], "air.wind_height", 'wind_profile = "log"'),
    "z0_of_a_constant_wind": ({"wind_z0": 0.1}, [], "air.wind_z0", 'wind_profile = "log"'),
    "pressure_in_hPa": ({"pressure": 1013.0}, [], "air.pressure", "hPa × 100"),
    # ln(z/z₀)/ln(z_ref/z₀) grows without bound as z₀ nears z_ref: 1e8 times the wind at 1,000 km
    "z0_just_below_reference": (
        {"wind_profile": "log", "wind_z0": 9.999999, "wind": [-1.0, 0.0, 0.0]},
        [],
        "air.wind_z0",
        "makes the log profile's wind 1.15e+08 m/s at 1e+06 m above the ground",
    ),
    "log_wind_named_where_given": (
        {"wind_profile": "log"},
        ["air.wind=[-400,0,0]"],  # (× ln(1e6/0.03)/ln(10/0.03) = 2.97 at 1,000 km)
        "air.wind",
        "past the wind's limit of 1000 m/s",
    ),
}


@pytest.mark.parametrize("case", list(REFUSED), ids=list(REFUSED))
def test_keys_without_effect_are_refused(case):
    table, overrides, key, fragment = REFUSED[case]
    with pytest.raises(ConfigError) as info:
        _air(table, overrides)
    assert info.value.key == key and fragment in str(info.value), str(info.value)


def test_the_command_line_wins_over_the_file():
    # tour_shot gives rho = 1.225: a --set weather key replaces it (and the default viscosity)
    scene = tg.load_scene("tour_shot", ["air.altitude=1600"])
    assert (scene.air.rho, scene.air.viscosity) == weather.air_from_weather(altitude=1600.0)
    # a file's weather, and --set rho: ρ as set, μ still from the weather's temperature
    scene = _air({"temperature": 30.0}, ["air.rho=1.1"])
    assert (scene.air.rho, scene.air.viscosity) == (1.1, weather.sutherland_viscosity(30.0))
    # --set pressure replaces the file's altitude (and its standard temperature: 15 °C)
    scene = _air({"altitude": 2000.0}, ["air.pressure=80000"])
    assert scene.air.rho == weather.air_density(15.0, 80000.0)
    # beside the pressure alone the altitude still sets the temperature: it is not refused
    scene = _air({"altitude": 1000.0, "pressure": 90000.0})
    assert scene.air.rho == weather.air_density(weather.isa_temperature(1000.0), 90000.0)


def test_cli_refuses_altitude_with_pressure_and_temperature_in_one_line():
    proc = run_cli(
        "sweep",
        "tour_shot",
        "--angles",
        "10",
        "--set",
        "air.altitude=1000",
        "--set",
        "air.pressure=90000",
        "--set",
        "air.temperature=20",
    )
    assert proc.returncode == 2, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "air.altitude" in lines[0] and "air.pressure" in lines[0], proc.stderr


# ---------------------------------------------------------------------------------------------
# The log profile in the kernels
# ---------------------------------------------------------------------------------------------
GROUND, Z0, Z_REF, U_REF = 1.5, 0.03, 10.0, 6.0
HEIGHTS = [0.01, Z0, 0.5, 2.0, Z_REF, 40.0]  # above the ground y = GROUND


def _profile(z: float) -> float:
    """u(z) = u_ref ln(z/z₀)/ln(z_ref/z₀) above z₀, 0 below."""
    return U_REF * math.log(z / Z0) / math.log(Z_REF / Z0) if z > Z0 else 0.0


@pytest.mark.parametrize(
    "collisions", [False, pytest.param(True, marks=pytest.mark.slow)], ids=["one_thread_per_ball", "collision_solver"]
)
def test_a_ball_moving_with_the_log_wind_feels_no_force(collisions):
    # Without gravity a ball flying level at the wind's speed at its height has v_rel = 0: no drag,
    # so it keeps its speed exactly. A kernel reading the wind at any other height, or from
    # another ground, would slow or push it (checked below with the constant profile).
    wind = f"air.wind=[{U_REF},0,0]"
    common = ["air.C_D=0.3", "world.gravity=[0,0,0]", "world.ground=false", f"world.ground_height={GROUND}", wind]
    common += [f"world.collisions={'true' if collisions else 'false'}", "world.integrator=rk4", "world.dt=0.01"]
    x = [[0.0, GROUND + z, 3.0 * i] for i, z in enumerate(HEIGHTS)]
    v = [[_profile(z), 0.0, 0.0] for z in HEIGHTS]
    log = tg.load_scene(
        "lab_turbulent", [*common, "air.wind_profile=log", f"air.wind_z0={Z0}", f"air.wind_height={Z_REF}"]
    )
    sim = tg.Simulation(log, x=x, v=v)
    sim.run(t=2.0)
    assert np.allclose(sim.v, v, rtol=0.0, atol=1e-12), sim.v[:, 0] - np.asarray(v)[:, 0]
    # the same balls in the constant wind (6 m/s everywhere) are all pushed but the one at 10 m
    sim = tg.Simulation(tg.load_scene("lab_turbulent", common), x=x, v=v)
    sim.run(t=2.0)
    pushed = np.abs(sim.v[:, 0] - np.asarray(v)[:, 0]) > 1e-3
    assert pushed.tolist() == [z != Z_REF for z in HEIGHTS]


WINDS = {"headwind": "[-5,0,0]", "tailwind": "[5,0,0]", "crosswind": "[0,0,5]"}


@pytest.fixture(scope="module")
def still_air_drive():
    return tg.sweep("tour_shot", **DRIVER).flight


@pytest.mark.parametrize("name", list(WINDS), ids=list(WINDS))
def test_the_drive_in_a_log_wind_lands_where_scipy_says(name, still_air_drive):
    # 5 m/s at 10 m over open grass (z₀ = 0.03 m), the driver flown by the sweep kernel (lanes,
    # RK4, h = 1 ms) against DOP853 on the numpy equations (ti_golf.bench.reference). RK4 is
    # fourth order where the wind is smooth; the steps across z = z₀ (at launch and at landing),
    # where the profile's slope jumps, leave errors of order h² there (4e-6 m measured at 1 ms,
    # 1e-5 m at 2 ms): the landing point must agree to 0.1 mm.
    scene = tg.load_scene("tour_shot", [f"air.wind={WINDS[name]}", "air.wind_profile=log"])
    res = tg.sweep(scene, **DRIVER).flight
    _, _, _, x0, v0, w0 = launch_grid(scene, **DRIVER)
    ref = landing_scipy(scene, x0, v0, w0, rtol=1e-10, atol=1e-10)[0]
    assert res.landing_x[0] == pytest.approx(ref[0], abs=1e-4)
    assert res.landing_z[0] == pytest.approx(ref[2], abs=1e-4)
    still = still_air_drive.carry[0]
    if name == "headwind":
        assert res.carry[0] < still - 10.0  # a headwind shortens the drive (by 18 m here)
    elif name == "tailwind":
        assert res.carry[0] > still + 10.0  # a tailwind lengthens it (by 12 m)
    else:  # the ball drifts downwind (+z), by 17 m, about as far along as in still air
        assert res.landing_z[0] > 10.0 and still_air_drive.landing_z[0] == 0.0
        assert res.carry[0] == pytest.approx(still, rel=0.01)


# ---------------------------------------------------------------------------------------------
# Altitude
# ---------------------------------------------------------------------------------------------
def test_the_drive_carries_farther_at_altitude_by_what_the_density_ratio_gives():
    # Drag and lift both scale with ρ, so the carry C is a function of ρ along the weather's path.
    # By the mean value theorem ln C(ρ₁₆₀₀) − ln C(ρ₀) = e(ξ)·ln(ρ₁₆₀₀/ρ₀) for the elasticity
    # e = d ln C/d ln ρ at some ρ between; e falls in size with ρ (less air, less to lose), so the
    # gain lies between e(ρ₀)·Δ and e(ρ₁₆₀₀)·Δ, Δ = ln(ρ₁₆₀₀/ρ₀) = −0.156: a 14.5 % thinner air.
    # And the gain lies in a sane band of 2–12 % (tour_shot's spin_reynolds air gives 3.0 %: thinner
    # air also lowers the Reynolds number toward the drag crisis, which takes back part of the gain).
    def carry(altitude: float) -> float:
        return float(tg.sweep("tour_shot", overrides=[f"air.altitude={altitude}"], **DRIVER).carry[0])

    def rho(altitude: float) -> float:
        return weather.air_from_weather(altitude=altitude)[0]

    def elasticity(altitude: float, d: float = 50.0) -> float:
        return math.log(carry(altitude + d) / carry(altitude - d)) / math.log(rho(altitude + d) / rho(altitude - d))

    delta = math.log(rho(1600.0) / rho(0.0))
    gain = math.log(carry(1600.0) / carry(0.0))
    e0, e1 = elasticity(0.0), elasticity(1600.0)
    assert e0 < e1 < 0.0  # less air, shorter flights lose less of their length to it
    assert e1 * delta < gain < e0 * delta
    assert 0.02 < math.expm1(gain) < 0.12
