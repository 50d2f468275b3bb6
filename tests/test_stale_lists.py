"""When the Gauss–Seidel steps rebuild the neighbour lists (``solvers.stale``): only when a pair
the lists miss may touch in the next step, or a ball has used more than a search can cover (the
skin when every ball is tested, about a radius more through the grid), or may touch a surface the
build found out of its reach.

A pair out of the lists may touch in the next step when its surface gap is below 2h·|v_a − v_b|,
as the build lists pairs. The Jacobi steps rebuild as soon as any ball has used half the skin
(its distance from the build plus 2h·|v|), which bounds every pair; the Gauss–Seidel steps look
for such pairs around each ball past half the skin."""

import numpy as np
import pytest
import taichi as ti
from conftest import SERIAL_OR_PARALLEL

import ti_golf as tg
from ti_golf.physics.types import (
    GridParams,
    GridScratch,
    NeighbourLists,
    float_array,
    int_array,
    kernel,
    vec3,
    vec3_array,
)
from ti_golf.runtime import on_cpu
from ti_golf.solvers import CollisionSolver, stale


@kernel
def _stale_both_ways(
    g: GridParams,
    grid: GridScratch,
    apart_ids: int_array,
    stored_sorted: ti.template(),
    radius: float_array,
    lists: NeighbourLists,
    x1: vec3_array,
    v: vec3_array,
    out: int_array,
):
    """For every ball: 1 when the grid finds a pair the lists miss within its reach
    (``stale.stale_near``), plus 2 when testing every ball does (``stale.stale_by_every_ball``)."""
    for i in range(x1.shape[0]):
        near = stale.stale_near(i, g, grid.start, grid.sorted_ids, apart_ids, stored_sorted, radius, lists, x1, v)
        every = stale.stale_by_every_ball(i, g.h, radius, lists, x1, v)
        out[i] = ti.cast(near, ti.i32) + 2 * ti.cast(every, ti.i32)


@pytest.mark.skipif(not on_cpu(), reason="the balls listed apart are looked for apart on the CPU only")
@pytest.mark.parametrize("reorder", [False, True], ids=["stored_as_given", "stored_in_grid_order"])
@pytest.mark.parametrize("boulder", [False, True], ids=["equal_balls", "a_boulder_listed_apart"])
def test_the_grid_finds_the_same_missing_pairs_as_testing_every_ball(reorder, boulder):
    # the grid's search (125 cells around the ball's cell at the build, and the balls listed apart)
    # must find exactly the pairs that testing every ball finds, for every ball, whenever no ball
    # has used more than its searched reach (stale.searched_reach: about a radius more than the
    # skin): a heap of balls, each then moved by up to 0.6 of its allowance with up to 0.4 of it
    # in 2h·|v|, the allowance the skin for most balls and the whole reach for one in five, so
    # that many balls come within reach of a ball the lists miss and many do not
    rng = np.random.default_rng(5)
    r = 0.02
    x = rng.uniform(0.0, 1.0, (800, 3)) * [0.5, 0.3, 0.5]  # a quarter of the volume in balls
    radius, mass = np.full(len(x), r), None
    if boulder:  # five times the others' size, listed apart (apart.size_cut), in the middle of them
        centre = np.array([0.25, 0.15, 0.25])
        x = np.vstack([centre, x[np.linalg.norm(x - centre, axis=1) > 0.1 + r + 1e-3]])
        radius = np.full(len(x), r)
        radius[0] = 0.1
        mass = 0.046 * (radius / r) ** 3
    n = len(x)
    sc = tg.load_scene("lab_vacuum", ["air.rho=0", "world.gravity=[0,0,0]", "contact.solver=gauss_seidel"])
    sim = tg.Simulation(sc, x=x, radius=radius, mass=mass)
    sim.solver = s = CollisionSolver(sim.model, serial=False, reorder=reorder)
    s.build(sim.state)
    if boulder:
        assert s.n_apart == 1
    x_build = s.x_at_build.to_numpy().astype(float)
    h, skin = sim.dt, s.skin
    reach = np.maximum(skin, stale.SEARCHED * s.cell - radius)  # (stale.searched_reach)
    assert np.sum(reach > 10.0 * skin) > n // 2  # (the cells are 2·r + skin wide: a radius and more)
    allowance = np.where(rng.uniform(size=n) < 0.2, reach, skin)
    direction = rng.normal(size=(n, 3))
    direction /= np.linalg.norm(direction, axis=1)[:, None]
    moved = x_build + direction * (rng.uniform(0.0, 0.6, n) * allowance)[:, None]
    v = rng.normal(size=(n, 3))
    v *= (rng.uniform(0.0, 0.4, n) * allowance / (2.0 * h * np.linalg.norm(v, axis=1)))[:, None]
    x1, v1, out = ti.ndarray(vec3.get(), n), ti.ndarray(vec3.get(), n), ti.ndarray(ti.i32, n)
    x1.from_numpy(moved)
    v1.from_numpy(v)
    g, grid, apart_ids, stored_sorted = s.last_grid()
    _stale_both_ways(g, grid, apart_ids, stored_sorted, s._model.radius, s._packs.lists(s), x1, v1, out)
    found = out.to_numpy()
    assert np.all((found == 0) | (found == 3))  # each ball: found both ways or neither
    assert 20 < np.sum(found == 3) < n - 20  # both kinds, many of each


def _rebuild_steps(speed: float, h: float, allowance: float, steps: int) -> list[int]:
    """The steps (from 1) that begin with a rebuild of the lists, for a ball at a constant
    ``speed`` [m/s] with time step ``h`` [s], when the lists are rebuilt once it has used more than
    ``allowance`` [m]: its distance from the build plus 2h·|v| (a model of the rule, stepped)."""
    rebuilt, moved, stale = [1], 0.0, False
    for k in range(1, steps + 1):
        if stale and k > 1:
            rebuilt.append(k)
            moved = 0.0
        moved += speed * h
        stale = moved + 2.0 * h * speed > allowance
    return rebuilt


def _steps_that_rebuild(sim: tg.Simulation, steps: int) -> list[int]:
    """The steps (from 1) of ``steps`` one-step launches of ``sim`` that began with a rebuild."""
    rebuilt = []
    for k in range(1, steps + 1):
        before = sim.solver.rebuilds
        sim.step(1)
        if sim.solver.rebuilds > before:
            rebuilt.append(k)
    return rebuilt


@pytest.mark.slow
@SERIAL_OR_PARALLEL
@pytest.mark.parametrize("solver", ["jacobi", "gauss_seidel"])
def test_a_lone_ball_uses_its_searched_reach_under_gauss_seidel_and_half_the_skin_under_jacobi(solver, serial):
    # a ball gliding at 0.13 m/s (0.13 mm a 1 ms step) with no other ball near: under Gauss–Seidel
    # no pair can be missing from its lists, so they are rebuilt only once it has used as much as
    # a search covers: through the grid, 0.99 of the cell (2·r + skin, 42 mm) less its radius,
    # 21.6 mm, every 164 steps; testing every ball (the serial steps that relist two balls
    # themselves), the whole skin (2 mm), every 14 steps. The Jacobi steps rebuild once it has used
    # half the skin, every 6 steps
    sc = tg.load_scene(
        "lab_vacuum", ["air.rho=0", "world.gravity=[0,0,0]", "world.dt=0.001", f"contact.solver={solver}"]
    )
    sim = tg.Simulation(sc, x=[[0.1, 0.5, 0.1], [1.1, 0.5, 0.1]], v=[[0.13, 0.0, 0.0], [0.0, 0.0, 0.0]])
    sim.solver = s = CollisionSolver(sim.model, serial=serial)
    rebuilt = _steps_that_rebuild(sim, 400)
    r = sc.ball.radius
    allowance = 0.5 * s.skin
    if solver == "gauss_seidel":
        allowance = s.skin if serial else stale.SEARCHED * s.cell - r
    assert rebuilt == _rebuild_steps(0.13, sim.dt, allowance, 400)
    every = np.diff(rebuilt)
    assert np.all(every == {0.5 * s.skin: 6, s.skin: 14}.get(allowance, 164))  # 0.13 mm a step, less 0.26


@SERIAL_OR_PARALLEL
def test_two_balls_closing_in_are_listed_before_they_touch(serial):
    # two balls 2.5 mm apart (beyond the 2 mm skin: not listed) close in at 0.13 m/s each. Each
    # has used more than half the skin after 6 steps, yet their pair can touch only once its gap,
    # 0.26 mm less each step, is below 2h·|v_a − v_b| (0.52 mm), after step 8: the lists are
    # rebuilt at step 9 (head-on, the model of the rule above, with half the gap for the allowance
    # of each ball), the pair listed, and the balls then meet as B.9 has it: with e = 1 and equal
    # masses they exchange velocities
    sc = tg.load_scene(
        "lab_vacuum",
        ["air.rho=0", "world.gravity=[0,0,0]", "world.dt=0.001", "contact.e=1", "contact.solver=gauss_seidel"],
    )
    r = sc.ball.radius
    x = [[0.1, 0.5, 0.1], [0.1 + 2.0 * r + 0.0025, 0.5, 0.1]]
    sim = tg.Simulation(sc, x=x, v=[[0.13, 0.0, 0.0], [-0.13, 0.0, 0.0]])
    sim.solver = CollisionSolver(sim.model, serial=serial)
    rebuilt = _steps_that_rebuild(sim, 30)
    assert rebuilt[:2] == _rebuild_steps(0.13, sim.dt, 0.5 * 0.0025, 30)[:2] == [1, 9]
    np.testing.assert_allclose(sim.v, [[-0.13, 0.0, 0.0], [0.13, 0.0, 0.0]], atol=1e-12)


@pytest.mark.slow
@SERIAL_OR_PARALLEL
def test_balls_moving_together_rebuild_only_as_a_lone_ball_does(serial):
    # two balls 2.5 mm apart (beyond the 2 mm skin: not listed) glide side by side at 0.13 m/s,
    # a third rests a metre away. The pair keeps its gap and closes at no speed, so it is never
    # listed, and the lists are rebuilt as for a lone ball (every 164 steps through the grid,
    # every 14 testing every ball). A test of each ball's move since the build, blind to the
    # motion the two share, rebuilt them every 8 steps (each ball past half the gap)
    sc = tg.load_scene(
        "lab_vacuum", ["air.rho=0", "world.gravity=[0,0,0]", "world.dt=0.001", "contact.solver=gauss_seidel"]
    )
    r = sc.ball.radius
    x = [[0.1, 0.5, 0.1], [0.1, 0.5, 0.1 + 2.0 * r + 0.0025], [1.1, 0.5, 0.1]]
    sim = tg.Simulation(sc, x=x, v=[[0.13, 0.0, 0.0], [0.13, 0.0, 0.0], [0.0, 0.0, 0.0]])
    sim.solver = s = CollisionSolver(sim.model, serial=serial)
    rebuilt = _steps_that_rebuild(sim, 400)
    allowance = s.skin if serial else stale.SEARCHED * s.cell - r
    assert rebuilt == _rebuild_steps(0.13, sim.dt, allowance, 400)
    assert np.all(np.diff(rebuilt) == (14 if serial else 164))
    assert len(s.pairs()) == 0


def test_a_ball_without_a_surface_row_rebuilds_before_it_can_reach_a_plane():
    # a ball 10.5 mm above the ground (beyond the 2 mm skin: the build gives it no row of surface
    # impulses) falls at 1 m/s, 1 mm a step, with no other ball near: it uses more than the skin
    # at once, yet no pair can be missing; the lists are rebuilt once the ground is within 2h·|v|
    # (2 mm) of where it is, after step 9 (straight down, the model above with the 10.5 mm gap for
    # the allowance), so that it meets the ground with its row, and bounces as B.9 has it (e = 1)
    sc = tg.load_scene(
        "lab_vacuum",
        ["air.rho=0", "world.gravity=[0,0,0]", "world.dt=0.001", "contact.e=1", "contact.solver=gauss_seidel"],
    )
    r, gap = sc.ball.radius, 0.0105
    sim = tg.Simulation(sc, x=[[0.1, r + gap, 0.1], [1.1, 0.5, 0.1]], v=[[0.0, -1.0, 0.0], [0.0, 0.0, 0.0]])
    sim.solver = s = CollisionSolver(sim.model, serial=False)
    rebuilt = _steps_that_rebuild(sim, 10)
    assert s.surface_start.to_numpy()[:2].tolist() == [0, 1]  # the falling ball has its row
    assert rebuilt[:2] == _rebuild_steps(1.0, sim.dt, gap, 10)[:2] == [1, 10]
    sim.step(10)
    np.testing.assert_allclose(sim.v[0], [0.0, 1.0, 0.0], atol=1e-9)
