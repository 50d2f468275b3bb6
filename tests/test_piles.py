"""Dense piles with the Gauss–Seidel contact sweeps (``contact.solver = "gauss_seidel"``).

The pile checks are the ones a user sees in the bundled ball pit, in a bin narrowed to 0.3 m so
that the pour is as deep as the full one (34 layers, about 1.45 m) with 2,250 balls instead of
100,000 (``bench.pit.pit_scene``). Settled means what the pit benchmark prints: no pair overlapping
by more than 1 % of a radius, 99 % of the balls slower than 5 mm/s, every ball in the bin, and,
from a second after the last ball has landed, no more kinetic energy, on average over time, than if
every ball moved at 5 mm/s;
and, once the last ball has landed, contacts that never raise the total mechanical energy (a
resting contact never gains energy: restitution acts only on approaches faster than
v_bounce + 2|g|h, see ``contact.pair_step``).
"""

from collections.abc import Callable
from pathlib import Path

import background
import numpy as np
import pytest
import taichi as ti
from conftest import ON_CPU, SCENES
from pile_pours import LANDED, NARROW_PIT, SAMPLE, STEP, load_variant, pour, total_mass

import ti_golf as tg
from ti_golf.bench.pit import pile_quality, pit_scene
from ti_golf.runtime import ensure_init
from ti_golf.scene.schema import AT_REST
from ti_golf.solvers import CollisionSolver
from ti_golf.solvers.colour import phase_of_sweep, step_phases

SNAPSHOT = 0.9
"""Time [s] at which the pour is landing, every kind of contact at once (the determinism check)."""


@pytest.fixture(scope="module")
def settled_pit():
    scene, side = pit_scene(NARROW_PIT)
    sim, quality, energy, taken = pour(scene, side, snapshot=SNAPSHOT)
    return sim, quality, energy, side, taken


def _pour_on_its_own(variant: str) -> Callable[[Path], background.Command]:
    """The background run of the pour ``variant`` (tests/pile_pours.py), beside the other tests on
    the second core: at 2,250 balls a pour is bound by kernel launches and keeps one core busy."""
    return lambda workdir: (
        background.python(str(Path(__file__).with_name("pile_pours.py")), variant, str(workdir / "pour.npz")),
        {},
    )


for _variant in ("sleeping_off", "lively", "no_projection_once_landed", "contacts", "contacts_lively"):
    background.declare(f"pour-{_variant}", _pour_on_its_own(_variant))


def _poured(background_runs, variant: str) -> tuple[dict, np.ndarray, float]:
    """(pile figures, energy samples, total mass) of the background pour ``variant``."""
    done, workdir = background_runs.result(f"pour-{variant}")
    assert done.returncode == 0, done.stderr[-3000:]
    return load_variant(workdir / "pour.npz")


def test_bundled_pit_needs_no_solver_calming_keys():
    pit = tg.load_scene("ball_pit")
    assert pit.contact.solver == "gauss_seidel" and pit.contact.e >= 0.5
    assert "solver" not in (SCENES / "ball_pit.toml").read_text()  # the default's, as a user's own scene gets
    defaults = tg.load_scene(None, data={"description": "defaults"}).contact
    for key in ("iterations", "v_bounce", "k_p", "skin"):  # left at their defaults, the same in every scene
        assert getattr(pit.contact, key) == getattr(defaults, key), key


def _assert_settled(quality: dict, energy: np.ndarray, total_mass: float) -> None:
    assert quality["deepest_overlap"] <= 0.01, quality
    assert quality["p99_speed_mps"] <= 0.005, quality
    assert quality["outside_bin"] == 0, quality
    # from a second after the last ball landed the pile holds, on average over time, no more
    # kinetic energy than if every ball moved at the settled speed, 5 mm/s: a pile that boils
    # stays above that; a settled one has only small local collapses (a ball wedged above the
    # floor slipping down at up to 0.4 m/s for some 50 ms, waking the balls around it), physical
    # events whose peaks a single sample may catch
    kinetic = energy[round(1.0 / SAMPLE) :, 0]  # every 0.05 s from t = 2.5 s
    assert np.mean(kinetic) <= 0.5 * total_mass * 0.005**2, kinetic


@pytest.mark.slow  # the settled pit's pour: a minute or more, once per process
def test_pit_with_restitution_settles(settled_pit):
    sim, quality, energy, _, _ = settled_pit
    _assert_settled(quality, energy, total_mass(sim))
    r = float(np.max(sim.model.radius_np))
    assert 1.3 < np.percentile(sim.x[:, 1], 99) < 1.6  # 34 layers, no ball left bouncing above them
    assert sim.x[:, 1].min() > r * 0.99


@pytest.mark.background("pour-no_projection_once_landed")
def test_once_landed_the_contacts_only_take_energy_out_of_the_pit(background_runs):
    # after the last ball has landed, the contacts' impulses (restitution below 1 above the
    # inelastic speed, resting contacts that never bounce, Coulomb friction, the resistance to
    # pivoting) and sleeping only take energy out: the total mechanical energy never rises over
    # 0.05 s (a collapse turns potential energy into kinetic, so the kinetic energy alone may). The
    # position projection (B.18) is turned off once the pour has landed: it moves balls without an
    # impulse, and lifting one out of an overlap adds potential energy that no contact took from the
    # pile (docs' solver page, the Gauss–Seidel sweeps' limits).
    # Step by step, the sweeps stop short of convergence: a warm-started impulse not yet taken back
    # can leave a ball rising a little, so the energy may rise within a step by noise below what
    # the scene counts as at rest, one ball's ½·m·v_rest² (the last sweep's shock propagation, the
    # lower ball standing firm, added up to 0.01 J of kinetic energy in one sweep before it fell
    # back to both balls' masses where it would add energy, contact.kinetic_change). Over 0.05 s
    # the energy of a pile still settling falls by far more than that noise (0.05-0.9 J a window
    # in this pour); once it has settled (a pour of other round-off settled before t = 1.5 s and
    # then fell by 0.2-1.3 mJ a window), a window's change is that noise alone, 1e-8 J either way
    _, energy, mass = _poured(background_runs, "no_projection_once_landed")
    mechanical = energy.sum(axis=1)
    assert len(mechanical) == round((4.0 - LANDED) / STEP) + 1
    scene, _ = pit_scene(NARROW_PIT)
    at_rest = 0.5 * (mass / NARROW_PIT) * scene.world.v_rest**2
    windows = np.diff(mechanical[:: round(SAMPLE / STEP)])
    assert np.all(windows < at_rest), windows
    assert np.max(np.diff(mechanical)) < at_rest, np.max(np.diff(mechanical))


@pytest.mark.background("pour-sleeping_off")
def test_pit_settles_with_sleeping_off(background_runs):
    # sleeping (world.v_rest, t_rest) is an optimisation, not what holds the pile: with no ball
    # ever put to rest the same pour settles the same way
    quality, energy, mass = _poured(background_runs, "sleeping_off")
    assert quality["asleep_fraction"] == 0.0
    _assert_settled(quality, energy, mass)


@pytest.mark.background("pour-lively")
def test_pit_of_lively_balls_settles(background_runs):
    # real golf balls bounce (e ≈ 0.8, golf_data.md): the pour still settles
    _assert_settled(*_poured(background_runs, "lively"))


@pytest.mark.background("pour-contacts")
def test_pit_settles_with_contact_colours(background_runs):
    # the same sweeps laid out by contact colours (contact.layout = contacts, a thread per pair):
    # the same equations in another order settle the same pour to the same figures
    _assert_settled(*_poured(background_runs, "contacts"))


@pytest.mark.background("pour-contacts_lively")
def test_pit_of_lively_balls_settles_with_contact_colours(background_runs):
    _assert_settled(*_poured(background_runs, "contacts_lively"))


@pytest.mark.slow  # the settled pit's pour: a minute or more, once per process
def test_pour_is_deterministic(settled_pit):
    # Gauss–Seidel in parallel: each block of columns in one thread, the colours in turn, so
    # the run does not depend on thread scheduling (nor on what ran before it in the process);
    # and the serial steps (the settled pit's: few balls on the CPU) are the parallel ones taken
    # in one thread, bit for bit
    sim, *_, taken = settled_pit
    assert sim.solver.serial == ON_CPU
    scene, _ = pit_scene(NARROW_PIT)
    sim = tg.Simulation(scene)
    sim.solver = CollisionSolver(sim.model, serial=False)
    sim.run(t=SNAPSHOT)
    for a, b in zip((sim.x, sim.v, sim.w), taken):
        np.testing.assert_array_equal(a, b)


def _column_scene(layout: str = "auto"):
    # (no contact.solver: the default must hold it)
    return tg.load_scene(
        "lab_vacuum", ["world.integrator=semi_implicit", "world.dt=0.001", "contact.e=0.5", f"contact.layout={layout}"]
    )


@pytest.mark.parametrize("layout", ["auto", pytest.param("contacts", marks=pytest.mark.slow)])
def test_heavy_ball_on_a_column_is_held(layout):
    # a ball 100 times heavier than a golf ball on top of a column of 20: the column stands and
    # shortens by less than 2 % of a radius in 5 s (each contact's λ carries the weight above it
    # from step to step, so the sweeps need not rebuild a 2,000-fold load ratio every step); with
    # the contact colours, the column's pairs take rising colours, so a sweep climbs it as well
    sc = _column_scene(layout)
    r, m = sc.ball.radius, sc.ball.mass
    x = np.array([[0.0, r + 2.0 * r * i, 0.0] for i in range(21)])
    mass = np.full(21, m)
    mass[-1] = 100.0 * m
    sim = tg.Simulation(sc, x=x, mass=mass)
    sim.run(t=5.0)
    assert x[-1, 1] - sim.x[-1, 1] < 0.02 * r
    np.testing.assert_allclose(sim.x[:, [0, 2]], 0.0, atol=1e-9)  # still a column
    assert np.all(np.diff(sim.x[:, 1]) > 2.0 * r * (1.0 - 0.01))  # no pair overlapping by 1 % of a radius


@pytest.mark.slow  # the settled pit's pour: a minute or more, once per process
def test_heavy_ball_dropped_on_the_pit_stays_near_the_top(settled_pit):
    # the same heavy ball dropped from 0.5 m onto the settled pit ends in the top quarter of it
    pit, _, _, side, _ = settled_pit
    r, m = float(np.max(pit.model.radius_np)), float(np.max(pit.model.mass_np))
    top = float(np.percentile(pit.x[:, 1], 99))
    x = np.vstack([pit.x, [[side / 2, top + 0.5, side / 2]]])
    v, w = np.vstack([pit.v, np.zeros((1, 3))]), np.vstack([pit.w, np.zeros((1, 3))])
    mass = np.append(np.full(pit.n, m), 100.0 * m)
    sim = tg.Simulation(pit.scene, x=x, v=v, w=w, radius=r, mass=mass)
    sim.run(t=2.0)
    y = sim.x[-1, 1]
    assert y > 0.75 * top, (y, top)
    quality = pile_quality(sim, side)
    assert quality["outside_bin"] == 0 and quality["deepest_overlap"] < 0.02, quality


@pytest.mark.slow  # the settled pit's pour: a minute or more, once per process
def test_the_settled_pit_sleeps_by_regions_and_a_landing_ball_wakes_its_own(settled_pit, tmp_path):
    # with the Gauss–Seidel sweeps a ball sleeps once every ball within colour.REGION_HOPS contacts
    # of it is calm: the pit, one island, never slept as a whole (0 % asleep at 4 s), but its
    # regions do
    pit, quality, _, side, _ = settled_pit
    assert quality["asleep_fraction"] > 0.3, quality
    pit.save(tmp_path / "pit.npz")  # (the fixture's run stays as it is for the other tests)
    sim = tg.Simulation.load(tmp_path / "pit.npz")
    r = float(np.max(sim.model.radius_np))
    x, asleep = sim.x, sim.status == AT_REST
    # a ball of the top is lifted 0.3 m above the pile's middle and dropped onto it at 2 m/s
    top = int(np.argmax(x[:, 1]))
    drop = np.array([side / 2, x[:, 1].max() + 0.3, side / 2])
    below = np.linalg.norm(x[:, [0, 2]] - drop[[0, 2]], axis=1) < 2 * r  # the balls in its path
    below[top] = False
    sim.set_ball(top, x=drop, v=[0.0, -2.0, 0.0])
    landed = np.zeros(sim.n, dtype=bool)
    while not landed.any() and sim.t < 4.2:  # it lands after 0.11 s
        sim.run(t=0.01)
        landed = np.linalg.norm(sim.x - sim.x[top], axis=1) < 2.05 * r  # the balls it touches
        landed[top] = False
    assert landed.any()
    sim.run(t=0.02)  # (it may glance off them and skid over the pile's top)
    assert not np.any(sim.status[landed] == AT_REST), sim.status[landed]
    assert np.any(asleep[landed | below])  # ... some of which were asleep: it woke them
    sim.run(t=4.2 - sim.t)
    # far from it (the bottom half, away from the drop's column) the pile sleeps on
    far = (x[:, 1] < 0.5 * x[:, 1].max()) & (np.linalg.norm(x[:, [0, 2]] - drop[[0, 2]], axis=1) > 0.1)
    assert np.mean(sim.status[far & asleep] == AT_REST) > 0.9
    assert pile_quality(sim, side)["deepest_overlap"] <= 0.01


def _heap_angle(mu: float) -> tuple[float, float]:
    """Slope [deg] of a heap of 1,500 balls poured onto an open floor, with friction ``mu`` between
    the balls and on the floor: atan of the heap's height over the radius of the disc that holds
    half of the balls, once it has come to rest (the balls' 99th-percentile speed below 1 cm/s,
    looked at every 0.2 s from t = 2.2 s: the last avalanches of a pour end at different times,
    2.2 s to 3 s over the seeds of the pour); and that speed [m/s], at t = 3.2 s at the latest.
    The floor is rough (μ_roll = 1: a ball on it stops rolling within a few centimetres) so that
    the heap's foot holds, as on a carpet, rather than the balls rolling off for metres as on a
    hard floor."""
    data = {
        "description": "a heap on an open floor",
        "world": {"dt": 0.001},
        "contact": {"solver": "gauss_seidel", "e": 0.5, "mu": mu, "mu_roll": 1.0},
        "planes": [{"point": [0, 0, 0], "normal": [0, 1, 0]}],
        "blocks": [
            {
                "kind": "random",
                "number": 1500,
                "box_min": [-0.13, 0.05, -0.13],
                "box_max": [0.13, 1.85, 0.13],
                "velocity": [0.0, -0.5, 0.0],
                "seed": 3,
            }
        ],
    }
    sim = tg.Simulation(tg.load_scene(None, data=data))
    sim.run(t=2.2)
    while _p99_speed(sim) >= 0.01 and sim.t < 3.1:
        sim.run(t=0.2)
    x = sim.x
    spread = np.percentile(np.hypot(x[:, 0], x[:, 2]), 50)
    height = np.percentile(x[:, 1], 99.5)
    return float(np.degrees(np.arctan2(height, spread))), _p99_speed(sim)


def _p99_speed(sim: tg.Simulation) -> float:
    """The balls' 99th-percentile speed [m/s]."""
    return float(np.percentile(np.linalg.norm(sim.v, axis=1), 99))


@pytest.mark.slow
def test_friction_steepens_the_heap():
    (loose, loose_speed), (rough, rough_speed) = _heap_angle(0.1), _heap_angle(0.5)
    assert max(loose_speed, rough_speed) < 0.01, (loose_speed, rough_speed)  # both heaps have come to rest
    assert rough > loose + 4.0, (loose, rough)  # measured: 16.6° and 27.0°


@pytest.mark.slow
@pytest.mark.parametrize("reorder", [False, True], ids=["stored_as_given", "stored_in_grid_order"])
def test_boulder_pushed_into_a_pile_takes_its_far_pairs_in_turn(reorder):
    # a ball five times the size of the rest is set apart (physics.apart): the balls beside it
    # touch it two or three grid columns from its centre, so the colours leave those pairs to a
    # serial pass (colour.far_pairs); a boulder rolled into a three-layer pile at 1 m/s. Stored in
    # the grid's order (as piles of 8,192 balls and more are), the boulder is found again at its
    # new index after each reorder, else its pairs beyond the next cell went unlisted
    sc = _column_scene()
    r, m = sc.ball.radius, sc.ball.mass
    side = 12
    grid = np.array([[i, k, j] for k in range(3) for i in range(side) for j in range(side)], dtype=float)
    x = np.vstack([grid * 2.0 * r + [r, r, r], [[-7.0 * r, 5.0 * r, side * r]]])
    v = np.zeros_like(x)
    v[-1] = [1.0, 0.0, 0.0]
    radius = np.append(np.full(len(grid), r), 5.0 * r)
    mass = np.append(np.full(len(grid), m), 125.0 * m)
    walls = [{"point": [-15 * r, 0, 0], "normal": [1, 0, 0]}, {"point": [2 * side * r, 0, 0], "normal": [-1, 0, 0]}]
    walls += [{"point": [0, 0, 0], "normal": [0, 0, 1]}, {"point": [0, 0, 2 * side * r], "normal": [0, 0, -1]}]
    data = {"description": "a boulder rolled into a pile", "world": {"dt": 0.001}, "planes": walls}
    data["contact"] = {"solver": "gauss_seidel", "e": 0.5}
    scene = tg.load_scene(None, data=data)
    runs = []
    for _ in range(2):
        sim = tg.Simulation(scene, x=x, v=v, radius=radius, mass=mass)
        sim.solver = CollisionSolver(sim.model, serial=False, reorder=reorder)  # (433 balls: serial by default)
        far = 0
        for _ in range(10):
            sim.run(t=0.05)
            far = max(far, sim.solver.far_owners)
        assert far > 0
        runs.append(sim.x)
    np.testing.assert_array_equal(*runs)  # the serial pass keeps the run deterministic
    assert np.abs(sim.x[:-1] - x[:-1]).max() > 0.001  # it met the pile and moved balls of it
    deepest = sim.deepest_overlap()
    assert deepest is None or deepest.fraction < 0.02, deepest


@pytest.mark.parametrize("iterations", [1, 2, 3, 4, 8])
def test_the_serial_kernels_take_the_phases_the_parallel_launches_take(iterations):
    # the serial kernels' phase of each sweep (a value at run time, so that each inlines the ball's
    # sweep once) is the list by which the parallel step launches its sweeps
    ensure_init()

    @ti.kernel
    def phases(sweeps: ti.template(), out: ti.types.ndarray(dtype=ti.i32, ndim=1)):
        for k in range(sweeps + 1):
            out[k] = phase_of_sweep(k, sweeps)

    out = np.full(iterations + 1, -9, dtype=np.int32)
    phases(iterations, out)
    assert out.tolist() == step_phases(iterations)
