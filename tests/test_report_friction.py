"""The report's friction model for surface contacts (``contact.friction_model = "report"``):
friction from the tangential velocity of the ball's centre, clipped to stop it, spin untouched
(report Appendix B, c.3–c.4 and B.15).

References: a ball sliding on level ground decelerates at μ·g (the resting impulse is g·h a step,
its friction μ·g·h) until it stops; on an incline of angle θ it slides at g·(sin θ − μ·cos θ) when
tan θ > μ and stays put when tan θ ≤ μ; the spin never changes; on a bumpy valley (the scene of
Figures 3.2-6 and 3.2-7) friction takes energy and stops the ball on a slope no steeper than μ.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import ti_golf as tg
from ti_golf.errors import ConfigError

G = 9.81
R = 0.02

PATHS = pytest.mark.parametrize(
    "path",
    ["advance", "jacobi", "gauss_seidel"],
)
"""The three places a ball meets a surface: the one-ball kernel, and the collision step's sweeps."""


def level(path: str, mu: float, h: float = 0.001) -> tuple[tg.Scene, int]:
    """Level ground in vacuum with the report's friction and no rolling resistance, and the
    number of balls that sends ``path``'s way (two balls 5 m apart for the collision step)."""
    contact = {"mu": mu, "mu_roll": 0.0, "friction_model": "report"}
    world = {"integrator": "semi_implicit", "dt": h}
    if path != "advance":
        world["collisions"] = True
        contact["solver"] = path
    return tg.load_scene(data={"air": {"rho": 0.0}, "world": world, "contact": contact}), 1 if path == "advance" else 2


@PATHS
def test_a_sliding_ball_decelerates_at_mu_g_and_keeps_its_spin(path):
    # reference: resting contact on level ground, j_n = g·h a step, friction μ·g·h a step against
    # the centre's velocity: semi-implicit Euler gives v_N = v0 − μ·g·N·h exactly and
    # x_N = v0·t − μ·g·t·(t + h)/2 (t = N·h); the spin ω0, of any axis, is never touched.
    # The Gauss–Seidel sweeps keep the impulses in f32 between steps: 1e-7 of them.
    v0, mu, h = 3.0, 0.3, 0.001
    sc, n = level(path, mu, h)
    x0 = np.array([[0.0, R, 0.0], [0.0, R, 5.0]][:n])
    w0 = np.array([[1.0, 2.0, -40.0]] * n)
    sim = tg.Simulation(sc, x=x0, v=[[v0, 0.0, 0.0]] * n, w=w0, radius=R)
    assert (sim.solver is not None) == (path != "advance")
    rtol = 1e-7 if path == "gauss_seidel" else 1e-12
    for _ in range(3):
        sim.step(200)
        t = sim.t
        np.testing.assert_allclose(sim.v[:, 0], v0 - mu * G * t, rtol=rtol)
        np.testing.assert_allclose(sim.x[:, 0], v0 * t - 0.5 * mu * G * t * (t + h), rtol=rtol)
        np.testing.assert_array_equal(sim.w, w0)
        np.testing.assert_allclose(sim.x[:, 1], R, atol=1e-12)  # on the ground, not bouncing
    sim.run(t=2.0, until="rest")
    assert sim.counts()["at_rest"] == n
    # stopping distance v0²/(2μg), to O(v0·h) for the discrete steps
    np.testing.assert_allclose(sim.x[:, 0], v0**2 / (2 * mu * G), atol=2 * v0 * h)


INCLINE = math.radians(20.0)  # scenes/friction_incline.toml: tan θ = 0.364


@PATHS
@pytest.mark.parametrize("mu", [0.3, 0.4])
def test_on_an_incline_a_ball_slides_when_tan_theta_exceeds_mu_and_else_stays(path, mu):
    # reference: released at rest on a 20° incline, friction μ·N against the centre's velocity:
    # μ = 0.3 < tan θ: it slides down at a = g·(sin θ − μ·cos θ) (v_N = a·N·h exactly, the
    # distance ½·a·t·(t + h)) without spinning; μ = 0.4 > tan θ: friction holds it, at rest.
    overrides = ["contact.friction_model=report", f"contact.mu={mu}"]
    if path != "advance":
        overrides += ["world.collisions=true", f"contact.solver={path}"]
    sc = tg.load_scene("friction_incline", overrides)
    x0 = np.array(sc.balls[0].position)
    xs = [x0] if path == "advance" else [x0, x0 + [0.0, 0.0, 0.5]]
    sim = tg.Simulation(sc, x=xs)
    t = 1.0
    sim.run(t=t)
    down = np.array([math.cos(INCLINE), -math.sin(INCLINE), 0.0])
    np.testing.assert_array_equal(sim.w, 0.0)
    if mu == 0.3:
        a = G * (math.sin(INCLINE) - mu * math.cos(INCLINE))
        rtol = 1e-6 if path == "gauss_seidel" else 1e-9
        np.testing.assert_allclose(sim.v, np.tile(a * t * down, (len(xs), 1)), rtol=rtol, atol=1e-9)
        np.testing.assert_allclose((sim.x - xs) @ down, 0.5 * a * t * (t + sc.world.dt), rtol=1e-6)
    else:
        assert sim.counts()["at_rest"] == len(xs)
        np.testing.assert_allclose(sim.x, xs, atol=1e-9)


def test_the_friction_model_is_checked():
    with pytest.raises(ConfigError, match=r"contact\.friction_model.*'spin', 'report'"):
        tg.load_scene("friction_incline", ["contact.friction_model=coulomb"])
    assert tg.load_scene("friction_incline").contact.friction_model == "spin"  # the default


def bounce(mu: float) -> tuple[tg.Simulation, np.ndarray]:
    """The ball of Figures 3.2-6 (μ = 0) and 3.2-7 (μ = 0.4) run for 15 s; its v²/2 + g·y [J/kg]
    every 50 ms."""
    sim = tg.Simulation(tg.load_scene("lab_friction", [f"contact.mu={mu}"]))
    energy: list[float] = []
    sim.run(every=100, on_every=lambda s: energy.append(0.5 * float(s.v[0] @ s.v[0]) + G * float(s.x[0, 1])))
    return sim, np.array(energy)


def test_friction_on_the_bumpy_valley_takes_energy_and_stops_the_ball_on_a_slope():
    # Figures 3.2-6 and 3.2-7: the same throw without and with friction. Without it the ball
    # loses energy only in its bounces (e = 0.7) and is still sliding to and fro after 15 s; with
    # μ = 0.4 it ends at rest, lower in energy, on a slope no steeper than μ (and not level:
    # "note how particle stops on an inclined part of the terrain"). The spin stays zero.
    free, e_free = bounce(0.0)
    held, e_held = bounce(0.4)
    assert free.counts()["rolling"] + free.counts()["flying"] == 1
    assert np.linalg.norm(free.v[0]) > 1.0
    assert held.counts()["at_rest"] == 1
    assert e_held[-1] < 0.5 * e_free[-1]
    # energy never grows by more than what the position projection of a step can add
    assert np.diff(e_free).max() < 0.01 and np.diff(e_held).max() < 0.01
    n = held.terrain.normal(held.x[0, 0], held.x[0, 2])
    slope = math.hypot(n[0], n[2]) / n[1]
    assert 0.05 < slope <= 0.4
    np.testing.assert_array_equal(free.w, 0.0)
    np.testing.assert_array_equal(held.w, 0.0)
