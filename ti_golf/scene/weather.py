"""Air density ρ and dynamic viscosity μ from the weather.

Plain Python (no Taichi, no numpy): the loader calls :func:`air_from_weather` when a scene gives
any of ``air.temperature``, ``air.pressure``, ``air.altitude``, ``air.humidity``.

* Pressure at an altitude: the International Standard Atmosphere's troposphere (ISO 2533:1975,
  U.S. Standard Atmosphere 1976), p(h) = p₀ (1 − L h/T₀)^(g₀M/(R*L)), T(h) = T₀ − L h, with
  p₀ = 101325 Pa, T₀ = 288.15 K, L = 0.0065 K/m, h the geopotential altitude r₀z/(r₀ + z) of
  the height z above sea level (r₀ = 6356766 m).
* Saturation vapour pressure over water: Buck (1981), "New equations for computing vapor pressure
  and enhancement factor", J. Appl. Meteorol. 20, 1527–1532, eq. (8):
  e_s = 6.1121 hPa · exp(17.502 t / (240.97 °C + t)), t in °C (within 0.2 % for −40 to 50 °C).
* Density: dry air and water vapour as ideal gases sharing the temperature, with partial
  pressures p_d = p − e and e = φ e_s (φ the relative humidity):
  ρ = p_d/(R_d T) + e/(R_v T), R_d = R*/M_d, R_v = R*/M_v.
* Viscosity: Sutherland's law as the standard atmosphere states it, μ = β T^(3/2)/(T + S),
  β = 1.458e-6 kg/(m·s·K^½), S = 110.4 K (dry air; water vapour changes μ by under 1 % in any
  weather a golfer meets).
"""

from __future__ import annotations

import math

R_UNIVERSAL = 8.31432
"""Universal gas constant R* [J/(mol·K)] of the 1976 standard atmosphere."""
M_DRY = 0.0289644
"""Molar mass of dry air [kg/mol]."""
M_VAPOUR = 0.01801528
"""Molar mass of water [kg/mol]."""
R_DRY = R_UNIVERSAL / M_DRY
"""Specific gas constant of dry air R_d ≈ 287.053 J/(kg·K)."""
R_VAPOUR = R_UNIVERSAL / M_VAPOUR
"""Specific gas constant of water vapour R_v ≈ 461.52 J/(kg·K)."""

P0 = 101325.0
"""Standard sea-level pressure [Pa]."""
T0_C = 15.0
"""Standard sea-level temperature [°C]."""
KELVIN = 273.15
"""0 °C in kelvin."""
LAPSE = 0.0065
"""Temperature lapse rate of the standard troposphere L [K/m]."""
G0 = 9.80665
"""Standard gravity g₀ [m/s²]."""
BAROMETRIC_EXPONENT = G0 * M_DRY / (R_UNIVERSAL * LAPSE)
"""g₀M/(R*L) ≈ 5.2559 of the barometric formula."""

EARTH_RADIUS = 6356766.0
"""The Earth's radius r₀ of the standard atmosphere's geopotential altitude [m]."""

SUTHERLAND_BETA = 1.458e-6
"""β of Sutherland's law [kg/(m·s·K^½)]."""
SUTHERLAND_S = 110.4
"""Sutherland's temperature S [K]."""

WEATHER_KEYS = ("temperature", "pressure", "altitude", "humidity")
"""The ``[air]`` keys from which ρ and μ are computed."""


def geopotential(altitude: float) -> float:
    """Geopotential altitude H = r₀z/(r₀ + z) [m] of the height z = ``altitude`` [m] above sea level."""
    return EARTH_RADIUS * altitude / (EARTH_RADIUS + altitude)


def isa_temperature(altitude: float) -> float:
    """Temperature [°C] of the standard atmosphere at ``altitude`` [m] above sea level."""
    return T0_C - LAPSE * geopotential(altitude)


def isa_pressure(altitude: float) -> float:
    """Pressure [Pa] of the standard atmosphere at ``altitude`` [m] above sea level (barometric
    formula of the troposphere)."""
    return P0 * (1.0 - LAPSE * geopotential(altitude) / (T0_C + KELVIN)) ** BAROMETRIC_EXPONENT


def saturation_vapour_pressure(temperature: float) -> float:
    """Saturation vapour pressure of water e_s [Pa] at ``temperature`` [°C] (Buck 1981, eq. 8)."""
    return 611.21 * math.exp(17.502 * temperature / (240.97 + temperature))


def air_density(temperature: float, pressure: float, humidity: float = 0.0) -> float:
    """Density ρ [kg/m³] of moist air at ``temperature`` [°C], ``pressure`` [Pa] and relative
    ``humidity`` φ ∈ [0, 1]: the ideal-gas mixture p_d/(R_d T) + e/(R_v T), e = φ e_s(T)."""
    T = temperature + KELVIN
    e = humidity * saturation_vapour_pressure(temperature)
    return (pressure - e) / (R_DRY * T) + e / (R_VAPOUR * T)


def sutherland_viscosity(temperature: float) -> float:
    """Dynamic viscosity μ [Pa·s] of air at ``temperature`` [°C] (Sutherland's law)."""
    T = temperature + KELVIN
    return SUTHERLAND_BETA * T**1.5 / (T + SUTHERLAND_S)


def air_from_weather(
    temperature: float | None = None,
    pressure: float | None = None,
    altitude: float | None = None,
    humidity: float | None = None,
) -> tuple[float, float]:
    """(ρ [kg/m³], μ [Pa·s]) of the air in a weather; what is not given is the standard atmosphere's.

    Args:
        temperature: air temperature [°C] (default: the standard atmosphere's at the altitude,
            15 °C − 6.5 °C per km of geopotential altitude).
        pressure: station pressure [Pa], as measured on site, not reduced to sea level (default:
            the standard atmosphere's at the altitude).
        altitude: height above sea level [m] (default 0); it sets the pressure and the default
            temperature, so it is not given together with ``pressure`` (see the loader).
        humidity: relative humidity φ ∈ [0, 1] (default 0: dry air).
    """
    h = 0.0 if altitude is None else altitude
    t = isa_temperature(h) if temperature is None else temperature
    p = isa_pressure(h) if pressure is None else pressure
    return air_density(t, p, 0.0 if humidity is None else humidity), sutherland_viscosity(t)
