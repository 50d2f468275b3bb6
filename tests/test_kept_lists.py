"""Builds that keep the lists of the balls that did not move (``grid.list_kept``, Gauss–Seidel).

A ball keeps its old list at a build while the skin it owes (its distance from where its list was
made, ``stale.skin_owed``) and 2h·|v| stay below half the skin; the others are listed anew. What
must hold after every such build, at the positions of the build:

- every pair whose gap is below the skin less what its two balls owe (their ``drift``) is listed:
  the bound the stale test relies on (a pair of two balls that kept their lists and is not listed
  had a gap of at least the skin less what they owed);
- every pair with a ball listed anew (``drift`` 0) within the skin is listed;
- every listed pair is within the build's reach (the skin, or h·|v_a − v_b|), and listed once.
"""

import numpy as np
from conftest import SERIAL_OR_PARALLEL
from scipy.spatial import cKDTree

import ti_golf as tg
from ti_golf.bench.pit import pit_scene
from ti_golf.solvers import CollisionSolver
from ti_golf.solvers.gauss_seidel import GaussSeidelSolver

BALLS = 2000
"""Balls of the pour: a pit as deep as the bundled one, in a narrower bin."""


def _check_build(solver: GaussSeidelSolver, sim: tg.Simulation) -> tuple[int, int]:
    """Check the lists just built against the positions of the build (see the module's docstring);
    returns (balls that kept their lists, balls in all)."""
    x, v = sim.state.x.to_numpy(), sim.state.v.to_numpy()  # (storage order, as the lists)
    radius = float(sim.model.radius_np.max())
    drift = solver.drift.to_numpy().astype(float)
    assert np.all(drift >= 0.0)
    skin, h = solver.skin, sim.dt
    upper, count = solver.upper.to_numpy(), np.diff(solver.first.to_numpy())
    owner = np.repeat(np.arange(len(count)), count)
    other = upper[owner, np.arange(int(count.sum())) - np.repeat(solver.first.to_numpy()[:-1], count)]
    listed = np.sort(np.stack([owner, other], axis=1), axis=1)
    keys = listed[:, 0].astype(np.int64) * len(x) + listed[:, 1]
    assert len(np.unique(keys)) == len(keys), "a pair listed twice"
    gap = np.linalg.norm(x[listed[:, 0]] - x[listed[:, 1]], axis=1) - 2 * radius
    reach = np.maximum(skin, h * np.linalg.norm(v[listed[:, 0]] - v[listed[:, 1]], axis=1))
    assert np.all(gap < reach * (1 + 1e-9)), "a pair listed out of the build's reach"
    near = np.array(sorted(cKDTree(x).query_pairs(2 * radius + skin)), dtype=np.int64).reshape(-1, 2)
    gap_near = np.linalg.norm(x[near[:, 0]] - x[near[:, 1]], axis=1) - 2 * radius
    owed = drift[near[:, 0]] + drift[near[:, 1]]
    must = near[gap_near < skin - owed]
    missing = ~np.isin(must[:, 0].astype(np.int64) * len(x) + must[:, 1], keys)
    assert not np.any(missing), f"pairs within the skin less what they owe, not listed: {must[missing][:5].tolist()}"
    return int(np.count_nonzero(drift > 0.0)), len(x)


@SERIAL_OR_PARALLEL
def test_a_build_keeps_the_lists_of_the_balls_that_did_not_move_and_every_pair_it_must(serial):
    scene, _side = pit_scene(BALLS)
    sim = tg.Simulation(scene)
    sim.solver = solver = CollisionSolver(sim.model, serial=serial, reorder=None if serial else True)
    assert isinstance(solver, GaussSeidelSolver)
    kept, builds = [], []
    real = solver.build

    def build(state):
        amend = solver.amendable
        real(state)
        builds.append(amend)
        if amend and len(builds) % 7 == 0:  # (every seventh: each check takes a tree of the balls)
            kept.append(_check_build(solver, sim))

    solver.build = build
    sim.run(t=0.9)  # the pour lands: the lists are rebuilt at nearly every step
    assert kept, "no build kept a list"
    shares = [k / n for k, n in kept]
    assert max(shares) > 0.5, f"the balls that kept their lists at each build: {shares}"


def test_a_build_after_an_edit_lists_every_ball_anew():
    # moving balls between steps (or retuning the model) may change what the skin bounds: the
    # next build lists every ball anew, and no ball owes anything
    scene, _side = pit_scene(BALLS)
    sim = tg.Simulation(scene)
    sim.run(t=0.6)
    solver = sim.solver
    assert solver.amendable
    sim.set_ball(0, x=sim.x[0] + [0.0, 0.5, 0.0])
    assert not solver.amendable
    sim.run(steps=1)
    assert solver.amendable
    np.testing.assert_array_equal(solver.drift.to_numpy(), 0.0)


def test_every_pair_that_can_touch_in_a_step_is_listed_when_it_starts():
    # the stale test counts what a ball owes from before the last build (its drift): at the start
    # of every step of the landing, each pair whose gap is below h·|v_a − v_b|, what it closes in
    # the step at the velocities it starts with, is listed (the build lists those; the stale test
    # keeps twice that margin), checked every third step in a pour whose builds keep most lists
    scene, _side = pit_scene(BALLS)
    sim = tg.Simulation(scene)
    sim.solver = solver = CollisionSolver(sim.model, serial=False, reorder=True)
    sim.run(t=0.5)
    real, checked, owing = solver._sweep, [], []

    def sweep(iterations, arguments):
        if len(checked) % 3 == 0:
            x, v = sim.state.x.to_numpy(), sim.state.v.to_numpy()
            r, h = float(sim.model.radius_np.max()), sim.dt
            listed = {tuple(p) for p in solver.pairs().tolist()}
            ids = sim.state.order if sim.state.order is not None else np.arange(len(x))
            speed = float(np.linalg.norm(v, axis=1).max())
            near = np.array(sorted(cKDTree(x).query_pairs(2 * r + 2 * h * speed)), dtype=np.int64).reshape(-1, 2)
            gap = np.linalg.norm(x[near[:, 0]] - x[near[:, 1]], axis=1) - 2 * r
            close = near[gap < h * np.linalg.norm(v[near[:, 0]] - v[near[:, 1]], axis=1)]
            missing = [p for p in np.sort(ids[close], axis=1).tolist() if tuple(p) not in listed]
            assert not missing, f"t = {sim.t:.4f} s: pairs that can touch in the step, not listed: {missing[:5]}"
            owing.append(int(np.count_nonzero(solver.drift.to_numpy() > 0.0)))
        checked.append(1)
        return real(iterations, arguments)

    solver._sweep = sweep
    sim.run(t=0.9)
    assert max(owing) > BALLS // 2, "few balls kept their lists"


def test_two_balls_that_kept_their_lists_meet_listed():
    # two balls 1.05 skins apart close in slowly (too slowly to bounce), each using a fifth of the
    # skin before a build
    # that keeps both lists (neither owes half the skin): each then owes that fifth, and the
    # stale test must count it, so that the pair is listed before they touch (counted from the
    # build alone, each would use half the skin only after they had run into each other)
    r = 0.02
    scene = tg.load_scene("lab_vacuum", ["air.rho=0", "world.gravity=[0,0,0]", "contact.solver=gauss_seidel"])
    sim = tg.Simulation(scene, x=[[0.0, 1.0, 0.0], [1.0, 1.0, 0.0]], radius=[r, r])
    sim.solver = solver = CollisionSolver(sim.model, serial=False)
    skin, h = solver.skin, sim.dt
    speed = 0.01 * skin / h  # a hundredth of the skin a step each
    sim.set_ball([0, 1], x=[[0.0, 1.0, 0.0], [2 * r + 1.05 * skin, 1.0, 0.0]], v=[[speed, 0, 0], [-speed, 0, 0]])
    sim.run(steps=20)
    solver.build(sim.state)  # (as a rebuild that another ball forced)
    np.testing.assert_allclose(solver.drift.to_numpy(), 0.2 * skin, rtol=0.05)
    deepest = 0.0
    for _ in range(60):
        sim.run(steps=1)
        deepest = max(deepest, 2 * r - float(np.linalg.norm(sim.x[1] - sim.x[0])))
    assert np.abs(sim.v[:, 0]).max() < 0.5 * speed, f"the balls did not stop each other: {sim.v[:, 0]}"
    assert deepest < 0.01 * skin, f"they overlapped by {deepest / skin:.2f} skins"
