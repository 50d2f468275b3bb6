"""The fit of ``air.model = "spin_reynolds"`` to the PGA Tour averages (``ti-golf fit-aero``).

Six coefficients are fitted, each bounded by the range that the published laws span
(:data:`FIT_PARAMETERS`); C_D0 and C_L0 (the zero-spin ends of Ferguson, McNally & McPhee's fit),
the spin decay λ and the air stay as the scene has them. The residuals are each PGA row's carry,
apex and land-angle errors divided by their tolerances (3 %, 2 yd, 2°: :mod:`ti_golf.golf.tour`),
so the fit minimises Σ (error/tolerance)² over the 12 rows with the engine's own flights. The
LPGA rows are never flown here. The fit starts from :data:`START` whatever the scene holds, so it
finds the same coefficients every time.

scipy (``scipy.optimize.least_squares``, trust-region reflective) is imported only when a fit runs.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from ti_golf.errors import TiGolfError
from ti_golf.golf.tour import TourFlight, fly_tour
from ti_golf.golf.trackman import PGA_TOUR
from ti_golf.scene.air import SPIN_REYNOLDS_C_D, SPIN_REYNOLDS_C_L, SPIN_REYNOLDS_CRISIS
from ti_golf.scene.launch_monitor import MPH, RPM
from ti_golf.scene.schema import Air, Scene


@dataclass(frozen=True)
class FitParameter:
    """One fitted coefficient: its name, the range the published laws span [lo, hi] and where that
    range comes from, the scale the optimiser sees it in, and how to read and set it on an ``Air``."""

    name: str
    lo: float
    hi: float
    source: str
    scale: float
    get: Callable[[Air], float]
    put: Callable[[Air, float], Air]


def _component(field: str, i: int) -> tuple[Callable[[Air], float], Callable[[Air, float], Air]]:
    def get(air: Air) -> float:
        return float(getattr(air, field)[i])

    def put(air: Air, value: float) -> Air:
        v = list(getattr(air, field))
        v[i] = value
        changes: dict[str, Any] = {field: tuple(v)}
        return dataclasses.replace(air, **changes)

    return get, put


def _scalar(field: str) -> tuple[Callable[[Air], float], Callable[[Air, float], Air]]:
    return (lambda air: float(getattr(air, field))), (lambda air, value: dataclasses.replace(air, **{field: value}))


C_D_MAX_BELOW_CRISIS = 0.7
"""The largest golf-ball drag coefficient measured below the crisis (Jenkins et al. 2018: 0.24 to
0.7 for 3e4 < Re < 1.08e5): C_D0 + C_D_crisis stays below it."""

FIT_PARAMETERS = (
    FitParameter("C_D1", 0.18, 0.9287, "Smits & Smith 0.18 to Ferguson 0.9287", 1.0, *_component("C_D_S", 1)),
    FitParameter("C_D2", -0.8259, 0.0, "Ferguson -0.8259 to Smits & Smith 0", 1.0, *_component("C_D_S", 2)),
    FitParameter("C_L1", 1.2031, 1.99, "Ferguson 1.2031 to Lyu 1.99", 1.0, *_component("C_L_S", 1)),
    FitParameter("C_L2", -3.25, -1.149, "Lyu -3.25 to Ferguson -1.149", 1.0, *_component("C_L_S", 2)),
    FitParameter(
        "C_D_crisis", 0.0, C_D_MAX_BELOW_CRISIS, "C_D0 + C_D_crisis <= 0.7 (Jenkins 2018)", 1.0, *_scalar("C_D_crisis")
    ),
    FitParameter("Re_crisis", 3.0e4, 1.08e5, "Jenkins 2018: 3e4 to 1.08e5", 1.0e4, *_scalar("Re_crisis")),
)
"""The fitted coefficients, in the order of the fit's vector."""

START = (0.9287, -0.8259, 1.2031, -1.149, 0.3, 6.0e4)
"""Where the fit starts: Ferguson, McNally & McPhee's C_D(S) and C_L(S), and a drag crisis of
0.3 at Re = 6e4 (within Jenkins et al.'s range)."""


@dataclass(frozen=True)
class FitResult:
    """A finished fit: the coefficients found (in :data:`FIT_PARAMETERS` order), the fitted scene,
    its PGA flights, the cost ½Σr², the number of flights of the 12 rows it took, and whether the
    optimiser reported convergence."""

    values: tuple[float, ...]
    scene: Scene
    pga: TourFlight
    cost: float
    evaluations: int
    converged: bool
    message: str

    def at_bound(self) -> list[str]:
        """The coefficients that ended on (or beyond) an end of their published range."""
        out = []
        for p, v in zip(FIT_PARAMETERS, self.values):
            lo, hi = bounds(p, self.scene.air)
            if min(v - lo, hi - v) <= 1e-6 * max(1.0, abs(v)):  # (negative: outside)
                out.append(p.name)
        return out


def bounds(p: FitParameter, air: Air) -> tuple[float, float]:
    """The published range of one coefficient for the scene's air (C_D_crisis's upper end depends
    on the scene's C_D0)."""
    if p.name == "C_D_crisis":
        return p.lo, C_D_MAX_BELOW_CRISIS - air.C_D_S[0]
    return p.lo, p.hi


def with_values(scene: Scene, values: tuple[float, ...] | np.ndarray) -> Scene:
    """The scene with the fitted coefficients set to ``values`` (and ``air.model = "spin_reynolds"``)."""
    air = dataclasses.replace(scene.air, model="spin_reynolds")
    for p, v in zip(FIT_PARAMETERS, values):
        air = p.put(air, float(v))
    return dataclasses.replace(scene, air=air)


def fit(scene: Scene, bounded: bool = True) -> FitResult:
    """Fit :data:`FIT_PARAMETERS` to the 12 PGA Tour rows in the scene's air and ball, each within
    its published range, or (``bounded=False``) free but for C_D_crisis ≥ 0 and Re_crisis ≥ 1e3.

    Raises :class:`~ti_golf.errors.TiGolfError` if scipy is not installed.
    """
    try:
        from scipy.optimize import least_squares
    except ImportError:
        raise TiGolfError(
            "fitting needs scipy, which ti_golf does not need otherwise: pip install 'ti-golf[fit]' (or scipy)"
        ) from None
    scale = np.array([p.scale for p in FIT_PARAMETERS])
    lo, hi = (np.array(b) for b in zip(*(bounds(p, scene.air) for p in FIT_PARAMETERS)))
    if not bounded:
        lo = np.array(
            [0.0 if p.name == "C_D_crisis" else 1e3 if p.name == "Re_crisis" else -np.inf for p in FIT_PARAMETERS]
        )
        hi = np.full(len(FIT_PARAMETERS), np.inf)
    x0 = np.clip(np.asarray(START, float), lo, hi)
    evaluations = 0

    def residuals(x: np.ndarray) -> np.ndarray:
        nonlocal evaluations
        evaluations += 1
        r = fly_tour(with_values(scene, x * scale), PGA_TOUR).residuals()
        return np.nan_to_num(r, nan=1e3)  # a ball that did not land is far off

    sol = least_squares(residuals, x0 / scale, bounds=(lo / scale, hi / scale), diff_step=1e-4, method="trf")
    values = tuple(float(v) for v in sol.x * scale)
    fitted = with_values(scene, values)
    return FitResult(
        values, fitted, fly_tour(fitted, PGA_TOUR), float(sol.cost), evaluations, sol.status > 0, str(sol.message)
    )


def fitted_spin_ratios(radius: float) -> tuple[float, float]:
    """The least and greatest spin ratio S = R·ω/v at launch among the PGA rows the fit flies, for
    balls of radius ``radius`` [m]: the launches whose drag and lift the default coefficients of
    ``spin_reynolds`` were fitted to."""
    ratios = [radius * row.spin_rpm * RPM / (row.ball_mph * MPH) for row in PGA_TOUR]
    return min(ratios), max(ratios)


EXTRAPOLATED = 1.1
"""How far past the fitted rows' greatest launch spin ratio (:func:`fitted_spin_ratios`) a launch
may go before :func:`beyond_the_fit` says so."""


def beyond_the_fit(scene: Scene, speeds: Any, spins: Any) -> str | None:
    """A note when a launch of ``speeds`` [m/s] and ``spins`` [rad/s] has a spin ratio well past
    the PGA rows that ``spin_reynolds``'s default coefficients were fitted to: there its drag and
    lift are extrapolated, and the fit (whose drag falls past S ≈ 0.4, as the wedges' flights
    ask) lets more spin carry farther, where real shots balloon and fall short. ``None`` for other
    air, or for coefficients of the scene's own."""
    air = scene.air
    if air.model != "spin_reynolds" or (air.C_D_S, air.C_L_S, (air.C_D_crisis, air.Re_crisis)) != (
        SPIN_REYNOLDS_C_D,
        SPIN_REYNOLDS_C_L,
        SPIN_REYNOLDS_CRISIS,
    ):
        return None
    speeds, spins = np.broadcast_arrays(np.asarray(speeds, float), np.asarray(spins, float))
    moving = speeds > 0
    if not np.any(moving):
        return None
    ratio = float(np.max(scene.ball.radius * np.abs(spins[moving]) / speeds[moving]))
    highest = fitted_spin_ratios(scene.ball.radius)[1]
    if ratio <= EXTRAPOLATED * highest:
        return None
    return (
        f"note: a spin ratio of {ratio:.2f} at launch lies past the PGA rows the spin_reynolds air was fitted to "
        f"(up to {highest:.2f}): its drag and lift there are extrapolated, and more spin may carry farther than "
        "real shots do"
    )
