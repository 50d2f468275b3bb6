"""The scene's ``[air]`` table: density, drag, Magnus lift, spin decay, the wind and the weather,
for the report's laws (``air.model = "lab"``) and the real-shot models of the spin ratio and the
Reynolds number. Plain Python, no Taichi (see :mod:`ti_golf.scene.schema`)."""

from __future__ import annotations

from dataclasses import dataclass

from ti_golf.scene.checks import NON_NEGATIVE, POSITIVE, UNIT_INTERVAL, VELOCITY, Interval, OneOf
from ti_golf.scene.keys import key

Vec3 = tuple[float, float, float]

COEFFICIENT = Interval(0.0, 100.0)
"""An aerodynamic coefficient (C_D, C_M, C_ω): a golf ball's are below 1; far larger ones overflow
the forces."""

AIR_MODELS = ("lab", "spin_ratio", "spin_reynolds")
"""Aerodynamic models (``air.model``): the report's laws, coefficients of the spin ratio, or of the
spin ratio and the Reynolds number."""
WIND_PROFILES = ("constant", "log")
"""How the wind varies with height (``air.wind_profile``): not at all, or logarithmically."""
SPIN_RATIOS = (0.02, 0.75)
"""The range of spin ratios S = Rω/|v_rel| of the C_D(S), C_L(S) fits of the spin-ratio models; the
coefficients are held at its ends."""
SPIN_RATIO_C_D = (0.1304, 0.9287, -0.8259)
"""C_D(S) = C_D0 + C_D1·S + C_D2·S² of ``air.model = "spin_ratio"`` (Ferguson, McNally & McPhee 2022;
the kernels' ``physics.aero.spin_ratio_coefficients``)."""
SPIN_REYNOLDS_C_D = (0.1304, 0.6683, -0.8259)
"""Default ``air.C_D_S`` [C_D0, C_D1, C_D2] of ``air.model = "spin_reynolds"`` (``ti-golf fit-aero``)."""
SPIN_REYNOLDS_C_L = (0.0504, 1.2031, -1.3073)
"""Default ``air.C_L_S`` [C_L0, C_L1, C_L2] (``ti-golf fit-aero``)."""
SPIN_REYNOLDS_CRISIS = (0.4668, 66500.0)
"""Default ``air.C_D_crisis`` and ``air.Re_crisis`` (``ti-golf fit-aero``)."""
SPIN_DECAY_RHO = 1.225
"""The air density [kg/m³] at which ``air.spin_decay``'s λ holds (Smits & Smith's sea-level air,
and the ``tour_shot`` air the other coefficients were fitted in): the spin-down torque is an air
force, so in air of density ρ the decay is dω/dt = −(ρ/SPIN_DECAY_RHO)·λ|v_rel|ω/R."""


@dataclass(frozen=True)
class Air:
    """Air properties (report L.1–L.23)."""

    rho: float = key(
        "float",
        1.3,
        "kg/m^3",
        "air density ρ (set from the weather instead when a weather key is given: air.temperature, "
        "air.pressure, air.altitude, air.humidity)",
        Interval(0.0, 1000.0),
    )
    gamma: int = key(
        "int", 2, "-", "flow type γ: 1 laminar (drag ∝ v), 2 turbulent (drag ∝ v²)", OneOf((1, 2)), "1 or 2"
    )
    C_D: float = key(
        "float",
        0.3,
        "-",
        "drag coefficient; k_D = ½ρA·C_D (L.22)",
        COEFFICIENT,
        read_when=("model", ("lab",)),
    )
    C_M: float = key(
        "float",
        0.0,
        "-",
        "Magnus coefficient; k_M = ½ρA·C_M/ω_M (L.2, L.21)",
        COEFFICIENT,
        read_when=("model", ("lab",)),
    )
    omega_M: float = key(
        "float",
        1.0,
        "1/s",
        "reference angular velocity ω_M of the Magnus law (L.2)",
        Interval(1.0e-3),
        read_when=("model", ("lab",)),
    )
    C_omega: float = key(
        "float",
        0.0,
        "-",
        "spin-decay coefficient; k_ω = ½ρA·C_ω/m (L.17, L.23)",
        COEFFICIENT,
        read_when=("model", ("lab", "spin_ratio")),
    )
    wind: Vec3 = key(
        "vec3",
        (0.0, 0.0, 0.0),
        "m/s",
        "the wind (with wind_profile = log: at the height wind_height); forces use v_rel = v − wind (L.21–L.23)",
        VELOCITY,
    )
    wind_profile: str = key(
        "str",
        "constant",
        "-",
        "constant: the same wind at every height; log: the wind grows with the height z above "
        "world.ground_height as u(z) = wind·ln(z/wind_z0)/ln(wind_height/wind_z0), none below wind_z0",
        OneOf(WIND_PROFILES),
    )
    wind_height: float = key(
        "float",
        10.0,
        "m",
        "reference height of the log profile: the height above the ground at which the wind is air.wind",
        POSITIVE,
        read_when=("wind_profile", ("log",)),
    )
    wind_z0: float = key(
        "float",
        0.03,
        "m",
        "roughness length z₀ of the log profile (0.03 m: open grass; 0.0002 m: water; 0.1 m: rough with bushes); "
        "below wind_height",
        POSITIVE,
        read_when=("wind_profile", ("log",)),
    )
    model: str = key(
        "str",
        "lab",
        "-",
        "drag and lift: lab = the report's constant C_D and Magnus law (L.21, L.22); spin_ratio = "
        "C_D(S) and C_L(S) of the spin ratio S = R|ω|/|v_rel| fitted to launch-monitor shots "
        "(Ferguson, McNally & McPhee 2022; C_D, C_M and omega_M unused; needs gamma = 2); "
        "spin_reynolds = C_D(S, Re) with a drag crisis and C_L(S), fitted to the PGA Tour averages, "
        "and spin decay dω/dt = −(ρ/1.225)·λ|v_rel|ω/R (needs gamma = 2; see docs/real_shots.md)",
        OneOf(AIR_MODELS),
    )
    viscosity: float = key(
        "float",
        1.81e-5,
        "Pa s",
        "dynamic viscosity μ of the air, for the Reynolds number Re = ρ|v_rel|·2R/μ of air.model = spin_reynolds "
        "(set from the weather instead when a weather key is given)",
        POSITIVE,
        read_when=("model", ("spin_reynolds",)),
    )
    temperature: float | None = key(
        "float",
        None,
        "°C",
        "air temperature (a weather key: ρ and μ then come from the weather; default: the standard "
        "atmosphere's at the altitude, 15 °C at sea level)",
        Interval(-40.0, 50.0),
    )
    pressure: float | None = key(
        "float",
        None,
        "Pa",
        "station pressure, as measured on site (1013.25 hPa = 101325 Pa); a weather key (default: the "
        "standard atmosphere's at air.altitude; not given with it)",
        Interval(50_000.0, 110_000.0, unit_word="Pa (hPa × 100)"),
    )
    altitude: float | None = key(
        "float",
        None,
        "m",
        "height above sea level (a weather key; default 0): sets the pressure (standard atmosphere, "
        "barometric formula) and the default temperature",
        Interval(-500.0, 5000.0),
    )
    humidity: float | None = key(
        "float", None, "-", "relative humidity φ (a weather key; default 0: dry air)", UNIT_INTERVAL
    )
    C_D_S: Vec3 = key(
        "vec3",
        SPIN_REYNOLDS_C_D,
        "-",
        "[C_D0, C_D1, C_D2]: drag coefficient C_D0 + C_D1·S + C_D2·S² above the drag crisis (S held within "
        "0.02–0.75, where it must stay in [0, 100])",
        read_when=("model", ("spin_reynolds",)),
    )
    C_L_S: Vec3 = key(
        "vec3",
        SPIN_REYNOLDS_C_L,
        "-",
        "[C_L0, C_L1, C_L2]: lift coefficient C_L0 + C_L1·S + C_L2·S² (S held within 0.02–0.75, where it "
        "must stay in [-100, 100]; in proportion to S below 0.02)",
        read_when=("model", ("spin_reynolds",)),
    )
    C_D_crisis: float = key(
        "float",
        SPIN_REYNOLDS_CRISIS[0],
        "-",
        "drag crisis: C_D rises by C_D_crisis/(1 + (Re/Re_crisis)⁴) as the ball slows",
        COEFFICIENT,
        read_when=("model", ("spin_reynolds",)),
    )
    Re_crisis: float = key(
        "float",
        SPIN_REYNOLDS_CRISIS[1],
        "-",
        "Reynolds number at the middle of the drag crisis",
        POSITIVE,
        read_when=("model", ("spin_reynolds",)),
    )
    spin_decay: float = key(
        "float",
        2.0e-5,
        "-",
        "spin-decay constant λ of dω/dt = −(ρ/1.225)·λ|v_rel|ω/R, λ at sea-level density (Smits & Smith "
        "1994: about 2e-5)",
        NON_NEGATIVE,
        read_when=("model", ("spin_reynolds",)),
    )


def quadratic_range(c: Vec3, lo: float, hi: float) -> tuple[float, float]:
    """The least and greatest of c0 + c1·S + c2·S² over lo ≤ S ≤ hi (at an end or at the vertex)."""
    at = [lo, hi]
    if c[2] != 0.0 and lo < -c[1] / (2.0 * c[2]) < hi:
        at.append(-c[1] / (2.0 * c[2]))
    values = [c[0] + c[1] * s + c[2] * s * s for s in at]
    return min(values), max(values)
